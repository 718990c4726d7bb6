"""Model-updating iteration (``IterationSettings.update``, issue 26 deliverable 1).

Truth: a linear time-invariant rig whose FRF is known in closed form (a second-order Butterworth
low-pass, ``scipy.signal.sosfreqz``) and whose gain is 3x the one the identification run saw (the
identified inverse is wrong by a factor 3): the correction factor of the plain loop at gain 1 is
``1 - 3 = -2`` (the error doubles), the secant ratio is 1/3 in every band, the rig's FRF after
IT00 is 3x the identification's, and the ILC error map is ``1 - G0 L`` per line.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from scipy import signal

import vrig
from vrig.reconstruction import DriveIteration, IterationSettings, reconstruct
from vrig.reconstruction.updates import DEFAULT_OPTIONS, IlcUpdate, make_update
from vrig.signals import random_drive, triangular_psd

FS = 200.0
FACTOR = 3.0  # the rig's gain after the identification run over the identified one


class _DriftRig:
    """One displacement drive (full scale 1 m), one load response: 1000 N/m times a 2nd-order
    Butterworth low-pass at 8 Hz; every run after the first (the identification) has ``factor``
    times that gain (the rig changed after it was identified). Optional white output noise."""

    name = "drift"
    fs = FS
    bandwidth = (0.0, 20.0)
    defaults = None

    def __init__(self, factor: float = FACTOR, noise: float = 0.0, runs: int = 0):
        from vrig.rigs import ChannelSpec

        self.inputs = (ChannelSpec("u", "m", 1.0, "direct"),)
        self.outputs = (ChannelSpec("y", "N", 1e5, "load_cell"),)
        self.sos = signal.butter(2, 8.0, fs=FS, output="sos")
        self.factor, self.noise, self.runs = factor, noise, runs

    def frf(self, f: np.ndarray) -> np.ndarray:
        """The FRF of the runs after the identification [N/m] at ``f`` [Hz]."""
        return 1000.0 * self.factor * signal.sosfreqz(self.sos, worN=f, fs=FS)[1]

    def run(self, drive, *, seed=None):
        u = np.asarray(getattr(drive, "data", drive), float)[:, 0]
        k = 1.0 if self.runs == 0 else self.factor
        self.runs += 1
        y = 1000.0 * k * signal.sosfilt(self.sos, u)
        y = y + self.noise * np.random.default_rng(seed).standard_normal(y.size)
        return vrig.TimeHistory(y[:, None], FS, ["y"], ["N"])


@pytest.fixture(scope="module")
def desired():
    """The changed rig's response to a 20 s random drive (0-15 Hz, 5 cm RMS): an exact drive
    exists."""
    drive = random_drive(triangular_psd((0.0, 15.0)), round(20 * FS), FS, rms=0.05, seed=7,
                         names=["u"], unit="m")  # fmt: skip
    return _DriftRig(runs=1).run(drive)


def _run(desired, update="none", iterations=4, **options):
    return reconstruct(_DriftRig(), desired, method="arx", gain=1.0, iterations=iterations,
                       seed=0, divergence=np.inf, update=update, **options)  # fmt: skip


def test_without_an_update_the_wrong_model_diverges_at_gain_1(desired):
    res = _run(desired, iterations=1)
    eta = res.errors[:, 0]
    # IT00: the response is 3x the desired one (error 2x); IT01: correction factor 1 - 3 = -2
    assert eta[0] == pytest.approx(200.0, rel=0.03)
    assert eta[1] == pytest.approx(400.0, rel=0.03)
    assert res.updates == []


def test_update_none_is_the_documented_loop_bit_for_bit(desired):
    """``update="none"`` plays ITn+1DRV = ITnDRV + gain (inverse(DESRES) - inverse(ITnRES)),
    made here from the engine's primitives (shape, up, the inverse), bit for bit."""
    gain = 0.6
    res = reconstruct(_DriftRig(factor=1.4, noise=1.0), desired, method="arx", gain=gain,
                      iterations=3, seed=2)  # fmt: skip
    engine = DriveIteration(_DriftRig(factor=1.4, noise=1.0), desired, method="arx", seed=2)
    assert engine.updater is None and engine.settings.update == "none"
    engine.identify()
    drive = engine.first_drive()
    for it in range(4):
        np.testing.assert_array_equal(res.drives[it].data, drive)
        _, _, response, _ = engine.play(drive, it)
        inv = engine.method.drive(engine.down(response))
        drive = drive + gain * engine.shape(engine.up(engine.target - inv))


def test_secant_update_is_exact_after_one_pair(desired):
    res = _run(desired, "secant")
    eta = res.errors[:, 0]
    assert res.updates[0]["event"] == "start"
    first = res.updates[1]  # after IT01: the pair (IT00, IT01)
    assert first["bands_skipped"] == [] and first["bands_clipped"] == []
    # every band's correction is divided by the realised/predicted ratio, 3
    np.testing.assert_allclose(first["scale"], 1 / FACTOR, rtol=0.03)
    assert eta[1] == pytest.approx(400.0, rel=0.03)  # IT01: the model's own (wrong) correction
    assert eta[2] < 3.0  # IT02: from 400 % to a few per cent in one secant step
    assert eta[-1] < 1.0


def test_frf_update_estimates_the_rigs_frf_from_one_iteration_record(desired):
    engine = DriveIteration(_DriftRig(), desired, method="arx", seed=0, update="frf",
                            update_options={"forgetting": 0.0})  # fmt: skip
    engine.identify()
    drive = engine.first_drive()
    rule = engine.updater
    f = rule.frf.f
    band = (f >= 1.0) & (f <= 12.0)  # where the desired response has its content
    truth = engine.rig.frf(f[band])
    np.testing.assert_allclose(rule.frf.H[band, 0, 0], truth / FACTOR, rtol=0.05)  # IDRES's
    engine.play(drive, 0)  # IT00 observed: with forgetting 0, IT00's record alone
    np.testing.assert_allclose(rule.frf.H[band, 0, 0], truth, rtol=0.03)
    assert rule.log[-1]["lines_updated"] >= band.sum()


def test_frf_update_converges_in_one_or_two_steps(desired):
    exact = _run(desired, "frf", iterations=2, update_options={"forgetting": 0.0}).errors[:, 0]
    assert exact[0] == pytest.approx(200.0, rel=0.03)
    assert exact[1] < 3.0  # one step: the FRF of IT00's record is the rig's
    default = _run(desired, "frf").errors[:, 0]  # forgetting 0.5: the IDRES estimate fades
    assert default[1] < 25.0 and default[2] < 3.0 and default[-1] < 1.0
    assert DEFAULT_OPTIONS["frf"]["forgetting"] == 0.5


def test_frf_update_keeps_lines_below_the_coherence_threshold(desired):
    engine = DriveIteration(_DriftRig(noise=50.0), desired, method="arx", seed=0, update="frf",
                            update_options={"coherence": 0.99, "forgetting": 0.0})  # fmt: skip
    engine.identify()
    drive = engine.first_drive()
    before = engine.updater.frf.H.copy()
    engine.play(drive, 0)
    spectra = engine.updater.spectra
    _, coh = spectra.h1()
    low = coh[:, 0] < 0.99
    assert low.any() and (~low).any()
    np.testing.assert_array_equal(engine.updater.frf.H[low], before[low])
    assert not np.allclose(engine.updater.frf.H[~low], before[~low])


def test_reidentify_converges_and_logs_each_refit(desired):
    res = _run(desired, "reidentify")
    eta = res.errors[:, 0]
    assert eta[1] < 0.5 * eta[0] and eta[-1] < 2.0
    refits = [e for e in res.updates if e["event"] == "refit"]
    assert [e["records"] for e in refits] == [2, 3, 4, 5]  # identification + each iteration


class _FailsOnRefit(vrig.reconstruction.InverseArx):
    """An inverse ARX whose every fit after the first raises (a copy carries the count)."""

    fits = 0

    def identify(self, iddrv, idres):
        self.fits += 1
        if self.fits > 1:
            raise np.linalg.LinAlgError("singular")
        super().identify(iddrv, idres)


def test_reidentify_keeps_the_previous_model_when_a_fit_fails(desired):
    method = _FailsOnRefit(4)
    res = reconstruct(_DriftRig(factor=1.5), desired, method=method, gain=1.0, iterations=3,
                      seed=0, update="reidentify")  # fmt: skip
    plain = reconstruct(_DriftRig(factor=1.5), desired, method=_FailsOnRefit(4), gain=1.0,
                        iterations=3, seed=0)  # fmt: skip
    kept = [e for e in res.updates if e["event"] == "kept previous model"]
    assert len(kept) == 3 and "LinAlgError" in kept[0]["reason"]
    assert res.stop_kind == "completed"
    for a, b in zip(res.drives, plain.drives, strict=True):  # the identified model throughout
        np.testing.assert_array_equal(a.data, b.data)


class _BudgetedArx(vrig.reconstruction.InverseArx):
    """An inverse ARX whose fit refuses a record longer than ``limit`` samples as the library's
    memory check does (MemoryBudgetError before allocating), and logs each record length."""

    def __init__(self, order, limit):
        super().__init__(order)
        self.limit, self.seen = limit, []

    def identify(self, iddrv, idres):
        from identification import MemoryBudgetError

        self.seen.append(iddrv.n_samples)
        if iddrv.n_samples > self.limit:
            raise MemoryBudgetError("the regression matrix would take too much")
        super().identify(iddrv, idres)


def test_reidentify_drops_the_oldest_records_when_the_memory_budget_refuses(desired):
    n = desired.n_samples
    method = _BudgetedArx(4, limit=10**9)  # sizes the identification record first
    engine = DriveIteration(_DriftRig(), desired, method=method, seed=0)
    engine.identify()
    n_id = method.seen[0]
    # room for the identification record and two iteration records (each as long as DESRES)
    res = reconstruct(_DriftRig(), desired, method=_BudgetedArx(4, limit=n_id + 2 * n),
                      gain=1.0, iterations=4, seed=0, update="reidentify")  # fmt: skip
    refits = [e for e in res.updates if e["event"] == "refit"]
    dropped = [e for e in res.updates if e["event"] == "dropped oldest record"]
    assert [e["records"] for e in refits] == [2, 3, 3, 3]  # identification + at most 2
    assert len(dropped) == 2 and all(e["reason"] == "memory budget" for e in dropped)
    assert not [e for e in res.updates if e["event"] == "kept previous model"]
    eta = res.errors[:, 0]
    assert eta[-1] < 0.5 * eta[0]  # still converging on the most recent records


def test_ilc_error_decreases_monotonically_under_its_condition(desired):
    engine = DriveIteration(_DriftRig(), desired, method="arx", seed=0, update="ilc",
                            update_options={"r": 1.0})  # fmt: skip
    engine.identify()
    engine.first_drive()
    rule = engine.updater
    band = (rule.f >= 0.5) & (rule.f <= 15.0)
    G0 = engine.rig.frf(rule.f)[:, None, None]  # the changed rig's true FRF
    rho = rule.contraction(G0)
    assert rho[band].max() < 1.0  # |1 - G0 L| < 1: the condition holds with the true G
    res = _run(desired, "ilc", iterations=6, update_options={"r": 1.0})
    eta = res.errors[:, 0]
    assert np.all(np.diff(eta) < 0), eta
    assert np.all(eta[1:] / eta[:-1] <= rho[band].max() + 0.02)  # Parseval: the line bound
    # SISO with G0 = 3 G: L G0 = 3 / (1 + r) on every line, the error map 1 - 3 / 2 = -0.5
    np.testing.assert_allclose(rho[band], 0.5, atol=0.05)
    np.testing.assert_allclose(eta[1:] / eta[:-1], 0.5, atol=0.03)


def test_ilc_with_a_weak_drive_weight_violates_the_condition_and_does_not_decrease(desired):
    engine = DriveIteration(_DriftRig(), desired, method="arx", seed=0, update="ilc",
                            update_options={"r": 1e-3})  # fmt: skip
    engine.identify()
    engine.first_drive()
    band = (engine.updater.f >= 1.0) & (engine.updater.f <= 12.0)
    G0 = engine.rig.frf(engine.updater.f)[:, None, None]
    assert engine.updater.contraction(G0)[band].min() > 1.0  # |1 - 3| ~ 2 on every line
    eta = _run(desired, "ilc", iterations=1, update_options={"r": 1e-3}).errors[:, 0]
    assert eta[1] > eta[0]


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"update": "bogus"}, "update must be one of"),
        ({"update": 3}, "update must be one of"),
        ({"update": "frf", "update_options": {"gain": 1}}, "takes no option 'gain'"),
        ({"update": "frf", "update_options": {"forgetting": 1.5}}, "forgetting must be"),
        ({"update": "frf", "update_options": {"coherence": 1.0}}, "coherence must be"),
        ({"update": "frf", "update_options": {"nperseg": 4}}, "nperseg must be"),
        ({"update": "secant", "update_options": {"clip": 1.0}}, "clip must be"),
        ({"update": "secant", "update_options": {"n_bands": 0}}, "n_bands must be"),
        ({"update": "secant", "update_options": {"min_change": -1}}, "min_change must be"),
        ({"update": "reidentify", "update_options": {"records": 0}}, "records must be"),
        ({"update": "ilc", "update_options": {"q": [1.0, -1.0]}}, "q must be"),
        ({"update": "ilc", "update_options": {"r": 0.0}}, "r must be"),
        ({"update": "none", "update_options": {"r": 1.0}}, "takes no option 'r'"),
        ({"update": "frf", "strategy": "adaptive"}, "choose one"),
        ({"update": "frf", "update_options": [("r", 1)]}, "update_options must be a mapping"),
    ],
)
def test_bad_update_names_and_options_raise(kwargs, match):
    with pytest.raises(ValueError, match=match):
        IterationSettings(**kwargs)


def test_update_settings_are_frozen_and_build_a_rule():
    s = IterationSettings(update="ilc", update_options={"q": [1.0, 2.0]})
    assert s.update_options["q"] == (1.0, 2.0)
    with pytest.raises(TypeError):
        s.update_options["r"] = 2.0
    assert isinstance(make_update(s.update, s.update_options), IlcUpdate)
    assert make_update("none") is None
    assert IterationSettings().update == "none"


def test_ilc_weights_per_response_must_match_the_rig(desired):
    engine = DriveIteration(_DriftRig(), desired, method="arx", seed=0, update="ilc",
                            update_options={"q": [1.0, 2.0]})  # fmt: skip
    engine.identify()
    with pytest.raises(ValueError, match="one per response"):
        engine.first_drive()


def test_the_update_log_reaches_summary_json(desired, tmp_path):
    res = _run(desired, "secant", iterations=2)
    written = vrig.TestFolder(tmp_path / "out").save(res)
    summary = json.loads(next(p for p in written if p.name == "summary.json").read_text())
    assert [e["event"] for e in summary["updates"]] == ["start", "update"]
    assert summary["updates"][1]["scale"] == pytest.approx(res.updates[1]["scale"])


# ------------------------------------------------------------------------- CLI and runner rows
def test_the_cli_takes_update_and_refuses_an_unknown_one(capsys):
    from vrig import cli

    parser = cli._parser()
    args = parser.parse_args(["reconstruct", "--rig", "shock-absorber", "--update", "secant"])
    assert args.update == "secant"
    assert parser.parse_args(["reconstruct", "--rig", "shock-absorber"]).update == "none"
    with pytest.raises(SystemExit):
        parser.parse_args(["reconstruct", "--rig", "shock-absorber", "--update", "bogus"])
    assert "invalid choice: 'bogus'" in capsys.readouterr().err


def _runner():
    import sys
    from pathlib import Path

    root = str(Path(__file__).resolve().parents[1])
    if root not in sys.path:  # benchmarks/ is a source-checkout package
        sys.path.insert(0, root)
    from benchmarks.runner import record, registry

    return record, registry


def test_the_runner_has_the_update_methods_as_rows_out_of_quick():
    record, registry = _runner()
    rows = {"arx-frf-update": "frf", "arx-secant": "secant", "arx-ilc": "ilc",
            "narx-reidentify": "reidentify"}  # fmt: skip
    for name, update in rows.items():
        plugin = registry.get_method(name)
        assert plugin.update == update and not plugin.quick
        assert name in registry.method_names() and name not in registry.method_names(quick=True)
    assert registry.get_method("arx").update == "none"
    settings = record.Settings(seconds=4.0, iterations=1).iteration(
        "arx", (0.5, 20.0), 3, update="secant"
    )
    assert settings.update == "secant" and settings.id_seed == settings.run_seed == 3
    with pytest.raises(ValueError, match="update of method"):
        registry.register_method("x-bad", lambda: None, update="bogus")


def test_a_runner_record_runs_with_its_rows_update():
    """The arx-secant row is the arx row up to IT01 (the secant rule needs a drive change) and
    differs after it: the record ran with its update."""
    record, _ = _runner()
    settings = record.Settings(seconds=4.0, iterations=2, fidelity="fast")
    recs = [record.compute_record(record.RecordKey("shock-absorber", m, 0, 0), settings)
            for m in ("arx", "arx-secant")]  # fmt: skip
    assert all(r["status"] == "ok" for r in recs), [r["error"] for r in recs]
    plain, secant = (np.asarray(r["eta0_per_iteration"]) for r in recs)
    np.testing.assert_array_equal(plain[:2], secant[:2])
    assert plain[2] != secant[2]


# ------------------------------------------------------------------------------------- MIMO
FIR = np.array(  # responses x drives x taps: a well-conditioned 2 x 2 system
    [[[1.0, 0.5, 0.2], [0.3, -0.4, 0.1]], [[0.2, 0.1, 0.0], [1.0, -0.6, 0.3]]]
)


class _DriftRig2x2:
    """Two drives, two responses: ``y_j = k sum_i fir[j, i] * u_i`` (FIR filters), ``k = 1`` in
    the first run (the identification) and ``factor`` after it."""

    name = "drift-2x2"
    fs = FS
    bandwidth = (0.0, 40.0)
    defaults = None

    def __init__(self, factor: float = FACTOR, runs: int = 0):
        from vrig.rigs import ChannelSpec

        self.inputs = tuple(ChannelSpec(f"u{i}", "m", 1.0, "direct") for i in range(2))
        self.outputs = tuple(ChannelSpec(f"y{j}", "N", 1e3, "load_cell") for j in range(2))
        self.factor, self.runs = factor, runs

    def frf(self, f: np.ndarray) -> np.ndarray:
        """(F, 2, 2) FRF of the runs after the identification at ``f`` [Hz]."""
        z = np.exp(-2j * np.pi * np.asarray(f)[:, None] / FS) ** np.arange(FIR.shape[2])
        return self.factor * np.einsum("jit,ft->fji", FIR, z)

    def run(self, drive, *, seed=None):
        u = np.asarray(getattr(drive, "data", drive), float)
        k = 1.0 if self.runs == 0 else self.factor
        self.runs += 1
        y = np.stack([sum(signal.lfilter(FIR[j, i], 1.0, u[:, i]) for i in range(2))
                      for j in range(2)], axis=1)  # fmt: skip
        return vrig.TimeHistory(k * y, FS, ["y0", "y1"], ["N", "N"])


@pytest.fixture(scope="module")
def desired_2x2():
    drive = random_drive(triangular_psd((0.0, 30.0)), round(20 * FS), FS, channels=2, rms=0.05,
                         seed=8, names=["u0", "u1"], unit="m")  # fmt: skip
    return _DriftRig2x2(runs=1).run(drive)


def _run_2x2(desired, update, iterations=4, **options):
    return reconstruct(_DriftRig2x2(), desired, method="arx", gain=1.0, iterations=iterations,
                       seed=0, divergence=np.inf, update=update, **options)  # fmt: skip


def test_mimo_frf_update_estimates_the_frf_matrix_and_converges(desired_2x2):
    engine = DriveIteration(_DriftRig2x2(), desired_2x2, method="arx", seed=0, update="frf",
                            update_options={"forgetting": 0.0})  # fmt: skip
    engine.identify()
    engine.play(engine.first_drive(), 0)
    rule = engine.updater
    band = (rule.frf.f >= 1.0) & (rule.frf.f <= 25.0)
    truth = engine.rig.frf(rule.frf.f[band])
    err = np.abs(rule.frf.H[band] - truth).max(axis=(1, 2)) / np.abs(truth).max(axis=(1, 2))
    assert err.max() < 0.03
    plain = _run_2x2(desired_2x2, "none", iterations=1).errors
    assert np.all(plain[1] > 1.8 * plain[0])  # 1 - 3 = -2 on every line
    eta = _run_2x2(desired_2x2, "frf", update_options={"forgetting": 0.0}).errors
    assert np.all(eta[1] < 3.0) and np.all(eta[-1] < eta[1])  # one step, then the floor


def test_mimo_secant_update_is_exact_after_one_pair(desired_2x2):
    res = _run_2x2(desired_2x2, "secant", iterations=4)
    first = res.updates[1]  # the pair (IT00, IT01): S_b = I / 3 in every band it updates
    assert len(first["bands_updated"]) >= 6
    np.testing.assert_allclose(np.array(first["scale"])[first["bands_updated"]], 1 / FACTOR,
                               rtol=0.03)  # fmt: skip
    eta = res.errors.max(axis=1)
    assert eta[1] > 1.8 * eta[0]  # IT01: the model's own correction, 1 - 3 = -2
    assert eta[2] < 3.0 and eta[-1] < 2.0


def test_secant_band_edges_are_octaves_up_to_seven_bands_and_finer_beyond():
    from vrig.spectra import band_edges  # the secant update's bands

    np.testing.assert_array_equal(band_edges((0.0, 40.0), 3), [0.0, 10.0, 20.0, 40.0])
    fine = band_edges((0.0, 40.0), 13)  # six octaves in 12 half-octave bands
    np.testing.assert_allclose(fine[1:], 40.0 / 2.0 ** np.arange(6, -0.5, -0.5), rtol=1e-15)
    np.testing.assert_allclose(band_edges((2.0, 32.0), 4), [2.0, 4.0, 8.0, 16.0, 32.0])
