"""Drive iteration on the virtual rigs: convergence, divergence guard, limits."""

from __future__ import annotations

import numpy as np
import pytest

import vrig
from vrig.reconstruction import InverseArx, pseudo_damage, reconstruct
from vrig.signals import flat_psd, random_drive, triangular_psd

# the shaker's accelerometer is deaf below ~10 Hz (suspension at 32 Hz, a ~ w^2 below it; §3.1.1):
# the simulation band starts where the transducer sees the response
BAND = (10.0, 60.0)


@pytest.fixture(scope="module")
def shaker_case():
    rig = vrig.load_rig("shaker", seed=0)
    d = random_drive(
        flat_psd((0.0, 50.0)),
        int(16 * rig.fs),
        rig.fs,
        rms=0.5,
        seed=7,
        names=[c.name for c in rig.inputs],
        unit="V",
    )
    return rig, rig.run(d, seed=99)  # a pseudo-field desired response, 0-50 Hz


@pytest.mark.parametrize("method,options", [("arx", {"order": 4}), ("frf", {})])
def test_shaker_iteration_reaches_five_percent_within_five_iterations(shaker_case, method, options):
    rig, desired = shaker_case
    res = reconstruct(
        rig, desired, method=method, iterations=5, gain=0.8, bandwidth=BAND, **options
    )
    assert res.errors.shape[1] == 1
    assert res.errors.min() < 5.0
    assert res.errors[res.best_iteration].mean() == res.errors.mean(axis=1).min()
    assert res.final_drive is res.drives[res.best_iteration]
    assert len(res.drives) == len(res.responses) == res.errors.shape[0]
    assert 0.5 < res.damage_ratio[res.best_iteration, 0] < 2.0


def test_iteration_is_reproducible(shaker_case):
    rig, desired = shaker_case
    a = reconstruct(rig, desired, method="arx", iterations=1, bandwidth=BAND, seed=3)
    b = reconstruct(rig, desired, method="arx", iterations=1, bandwidth=BAND, seed=3)
    np.testing.assert_array_equal(a.errors, b.errors)
    np.testing.assert_array_equal(a.final_drive.data, b.final_drive.data)


def test_a_diverging_iteration_stops_and_keeps_the_best_drive(shaker_case):
    rig, desired = shaker_case

    class SignFlipped(InverseArx):
        """A wrong inverse for the corrections: the update pushes the error up."""

        def drive(self, response):
            return -super().drive(response)

    small = desired.with_data(0.2 * desired.data)  # room below the transducer range to grow
    res = reconstruct(rig, small, method=SignFlipped(4), iterations=6, gain=0.3, bandwidth=BAND)
    assert "diverging" in res.stopped
    assert res.errors.shape[0] < 7
    assert res.best_iteration == int(np.argmin(res.errors.mean(axis=1)))
    assert res.errors[-1].mean() > 1.5 * res.errors.min()


def test_a_drive_beyond_limits_is_never_sent(shaker_case, tmp_path):
    """IT00DRV beyond the full scale: nothing is played, but the identification records, the
    model and the refused drive come back in the error and are saved and plotted."""
    from vrig.plots import save_reconstruction_plots

    rig, desired = shaker_case
    played = []
    huge = desired.with_data(desired.data * 50)
    with pytest.raises(vrig.ReconstructionError, match="IT00DRV") as err:
        reconstruct(_Recording(rig, played), huge, method="arx", iterations=2, bandwidth=BAND)
    assert len(played) == 1  # only the identification drive went out
    exc = err.value
    assert exc.stage == "IT00" and isinstance(exc.cause, vrig.RigLimitError)
    assert exc.__cause__ is exc.cause
    res = exc.result
    assert res.drives == [] and res.errors.shape == (0, 1) and res.best_iteration == -1
    np.testing.assert_array_equal(res.id_drive.data, played[0])
    assert res.id_response is not None and hasattr(res.method, "inverse")  # the fitted model
    full = rig.inputs[0].full_scale
    assert res.rejected_name == "REFUSED00" and np.abs(res.rejected_drive.data).max() > full
    assert "IT00" in res.stopped and "not sent" in res.stopped
    with pytest.raises(ValueError, match="no iteration was played"):
        _ = res.final_drive

    folder = vrig.TestFolder(tmp_path / "failed")
    folder.save(exc.result, field=huge, rig=rig, fmt="npz")
    assert list(folder.files()) == ["IDDRV", "IDRES", "FIELD01", "DESRES01", "REFUSED00"]
    np.testing.assert_array_equal(folder.read("REFUSED00").data, res.rejected_drive.data)
    np.testing.assert_array_equal(folder.read("IDDRV").data, played[0])
    summary = folder.summary()
    assert summary["iterations_run"] == -1 and summary["best_iteration"] is None
    assert summary["rejected"] == "REFUSED00" and "IT00DRV was not sent" in summary["stop_reason"]
    ((model, lead),) = folder.load_models().values()
    assert lead == res.method.inverse.lead_
    x = np.random.default_rng(0).standard_normal((200, 1))
    np.testing.assert_allclose(model.simulate(x), res.method.inverse.model.simulate(x))
    pngs = save_reconstruction_plots(exc.result, tmp_path / "failed", rig=rig)
    assert [p.name for p in pngs] == ["refused_drive_vs_limits.png"]


class _Recording:
    """A rig proxy that records every drive it is asked to play and raises ``fail[k]`` (an
    exception) on the k-th run (0: the identification drive, 1: IT00DRV, ...)."""

    def __init__(self, rig, played, fail=None):
        self.rig, self.played, self.fail = rig, played, dict(fail or {})
        for name in ("inputs", "outputs", "fs", "name", "bandwidth"):
            setattr(self, name, getattr(rig, name))

    def run(self, drive, seed=None):
        k = len(self.played)
        self.played.append(np.array(drive.data))
        if k in self.fail:
            raise self.fail[k]
        return self.rig.run(drive, seed=seed)


def _trip(kind="following error"):
    return vrig.RigLimitError(kind, "amplifier_voltage", 1.25, 3.0, 2.0, "V")


@pytest.mark.parametrize(
    "failure,stopped,rejected",
    [
        (lambda: _trip(), "IT01: interlock: following error", "TRIPPED01"),
        (
            lambda: vrig.SimulationInstabilityError("mjWARN_BADQACC at t = 1.2 s"),
            "IT01: SimulationInstabilityError: mjWARN_BADQACC",
            "TRIPPED01",
        ),
    ],
)
def test_a_rig_failure_after_it00_keeps_every_iteration_played(
    shaker_case, failure, stopped, rejected
):
    rig, desired = shaker_case
    played = []
    res = reconstruct(
        _Recording(rig, played, {3: failure()}), desired, iterations=4, bandwidth=BAND
    )
    assert len(played) == 4  # IDDRV, IT00DRV, IT01DRV, IT02DRV (tripped)
    assert len(res.drives) == len(res.responses) == res.errors.shape[0] == 2
    for drv, sent in zip(res.drives, played[1:3], strict=True):
        np.testing.assert_array_equal(drv.data, sent)
    assert res.stopped.startswith(stopped.replace("IT01", "IT02"))
    assert res.rejected_name == rejected.replace("01", "02")
    np.testing.assert_array_equal(res.rejected_drive.data, played[3])
    assert res.best_iteration == int(np.argmin(res.errors.mean(axis=1)))
    assert res.final_drive is res.drives[res.best_iteration]
    assert type(res.error) is type(failure())


class _DivergesOnCorrections(InverseArx):
    """An inverse whose free run diverges (or returns NaN) on the n-th ``drive`` call: call 0 is
    inverse(DESRES), call 1 the correction from IT00RES, ..."""

    def __init__(self, order, at, how):
        super().__init__(order)
        self.at, self.how, self.calls = at, how, 0

    def drive(self, response):
        self.calls += 1
        out = super().drive(response)
        if self.calls - 1 == self.at:
            if self.how == "raise":
                from identification import SimulationDivergedError

                raise SimulationDivergedError(0, "amplifier_voltage", 17, 1e9, 1e6)
            out = out.copy()
            out[17, 0] = np.nan
        return out


@pytest.mark.parametrize("how", ["raise", "nan"])
def test_a_diverged_inverse_after_it00_keeps_every_iteration_played(shaker_case, how):
    rig, desired = shaker_case
    played = []
    method = _DivergesOnCorrections(4, at=2, how=how)  # the correction from IT01RES
    res = reconstruct(_Recording(rig, played), desired, method=method, iterations=4, bandwidth=BAND)
    assert len(played) == 3 and len(res.drives) == 2 == res.errors.shape[0]
    assert res.stopped.startswith("IT02DRV")
    assert "SimulationDivergedError" in res.stopped
    assert ("not finite" in res.stopped) == (how == "nan")
    assert res.rejected_drive is None and res.final_drive is res.drives[res.best_iteration]


@pytest.mark.parametrize("how", ["raise", "nan"])
def test_a_diverged_inverse_at_it00_still_returns_the_identification(shaker_case, how):
    rig, desired = shaker_case
    played = []
    method = _DivergesOnCorrections(4, at=0, how=how)  # inverse(DESRES) itself
    with pytest.raises(vrig.ReconstructionError) as err:
        reconstruct(_Recording(rig, played), desired, method=method, bandwidth=BAND)
    assert len(played) == 1 and err.value.stage == "model"
    res = err.value.result
    np.testing.assert_array_equal(res.id_drive.data, played[0])
    assert res.id_response is not None and res.method is method and res.drives == []


def test_an_identification_drive_that_always_trips_is_kept(shaker_case):
    rig, desired = shaker_case
    played = []
    trips = {k: _trip() for k in range(11)}  # full, 1/2, ..., 1/1024 of the RMS
    with pytest.raises(vrig.ReconstructionError, match="identification") as err:
        reconstruct(_Recording(rig, played, trips), desired, bandwidth=BAND)
    res = err.value.result
    assert len(played) == 11 and err.value.stage == "identification"
    assert res.id_drive is None and res.id_response is None
    assert res.rejected_name == "TRIPPEDID"
    np.testing.assert_array_equal(res.rejected_drive.data, played[-1])
    np.testing.assert_allclose(played[-1], played[0] / 1024)


def test_the_identification_level_halves_past_an_eighth_until_the_rig_runs(shaker_case):
    """A rig that takes only 1/32 of the default identification level (a user's rig whose
    response ranges do not match its drives' full scales: models/README.md's example) is
    identified at 1/32; the rule used to give up at 1/8."""
    rig, desired = shaker_case
    played = []
    trips = {k: _trip() for k in range(5)}  # full, 1/2, 1/4, 1/8, 1/16 trip; 1/32 runs
    res = reconstruct(_Recording(rig, played, trips), desired, iterations=0, bandwidth=BAND)
    np.testing.assert_allclose(res.id_drive.data, played[0] / 32)
    assert res.identification["reason"].endswith(
        f"halved 5x after interlock trips ({trips[4]})"
    )


def test_pseudo_damage_scales_with_the_slope():
    x = np.sin(np.linspace(0, 20 * np.pi, 2001))  # 10 cycles of range 2
    assert pseudo_damage(x, slope=5) == pytest.approx(10 * 2.0**5, rel=0.06)
    assert pseudo_damage(2 * x, slope=5) == pytest.approx(2**5 * pseudo_damage(x, slope=5))


def test_bad_arguments(shaker_case):
    rig, desired = shaker_case
    with pytest.raises(ValueError, match="unknown method"):
        reconstruct(rig, desired, method="magic")
    with pytest.raises(ValueError, match="gain"):
        reconstruct(rig, desired, gain=0.0)
    with pytest.raises(ValueError, match="sampled at"):
        reconstruct(rig, vrig.TimeHistory(desired.data, fs=100.0))


def test_offline_iteration_with_a_file_backed_rig(tmp_path, shaker_case):
    """Drives go out as RPC III files and responses come back as files (an external lab)."""
    from vrig import io
    from vrig.rigs import FileRig

    lab, desired = shaker_case
    played = []

    def respond(drive_path):
        drive = io.read(drive_path)
        played.append(drive_path.name)
        out = tmp_path / drive_path.with_suffix(".rsp").name
        io.write_rpc3(out, lab.run(drive.data, seed=len(played)), data_type="FLOATING_POINT")
        return out

    rig = FileRig(
        tmp_path / "test", lab.inputs, lab.outputs, lab.fs, respond, bandwidth=lab.bandwidth
    )
    res = reconstruct(rig, desired, method="arx", order=4, iterations=3, bandwidth=BAND)
    assert played[:2] == ["RUN000.drv", "RUN001.drv"]  # identification drive, then IT00DRV
    assert len(played) == 1 + res.errors.shape[0]
    assert res.errors.min() < 5.0


def test_shock_absorber_arx_iteration_lowers_the_error_by_a_third():
    """Free play on (rubber bushes): the thesis got 27 % at IT00 and 17 % at IT05 (Table 6.16)."""
    rig = vrig.load_rig("shock-absorber", seed=0)
    drive = random_drive(
        triangular_psd((0.0, 10.0)),
        int(30 * rig.fs),
        rig.fs,
        rms=0.003,
        seed=11,
        names=["actuator_disp"],
        unit="m",
    )
    desired = rig.run(drive, seed=99)  # pseudo-field response (§6.5)
    res = reconstruct(
        rig, desired, method="arx", order=4, iterations=5, bandwidth=(0.2, 10.0), id_rms=0.003
    )
    assert res.errors.shape[0] == 6
    assert res.errors[5, 0] <= 0.7 * res.errors[0, 0]


# --- per-band gains (the drive update of the gym environments)


def test_band_gains_scale_each_band_of_a_two_tone_record():
    from vrig.reconstruction import band_gains

    fs, n = 512.0, 4096
    t = np.arange(n) / fs
    lo, hi = np.sin(2 * np.pi * 8.0 * t), np.sin(2 * np.pi * 40.0 * t)  # integer periods
    x = np.column_stack([lo + hi, lo + hi])
    g = np.array([[0.5, 1.5], [1.0, 0.0]])
    y = band_gains(x, fs, g, [0.0, 20.0, fs / 2])
    mid = slice(n // 8, -n // 8)  # away from the record's ends (zero-padded spectrum)
    np.testing.assert_allclose(y[mid, 0], (0.5 * lo + 1.5 * hi)[mid], atol=2e-2)
    np.testing.assert_allclose(y[mid, 1], lo[mid], atol=2e-2)


def test_band_gains_equal_across_bands_are_a_plain_gain():
    from vrig.reconstruction import band_gains

    x = np.random.default_rng(0).normal(size=(1000, 2))
    g = np.array([[0.8, 0.8, 0.8], [0.3, 0.3, 0.3]])
    np.testing.assert_array_equal(band_gains(x, 100.0, g, [0, 5, 20, 50]), x * [0.8, 0.3])
    with pytest.raises(ValueError, match="n_bands"):
        band_gains(x, 100.0, g[:, :2], [0, 5, 20, 50])


# --- a linear two-transducer test rig (scipy filters: fast, known dynamics)


class _TwoTransducerRig:
    """One drive; response "a" a low-pass copy of the drive, "b" a delayed, scaled copy."""

    name = "two-transducer"
    fs = 200.0
    bandwidth = (0.0, 20.0)

    def __init__(self):
        from vrig.rigs import ChannelSpec

        self.inputs = (ChannelSpec("u", "m", 1.0, "direct"),)
        self.outputs = (
            ChannelSpec("a", "N", 100.0, "load_cell"),
            ChannelSpec("b", "N", 100.0, "load_cell"),
        )
        self.played = []

    def run(self, drive, *, seed=None):
        from scipy import signal

        u = np.asarray(getattr(drive, "data", drive), float)
        self.played.append(u.copy())
        a = signal.lfilter([0.2], [1.0, -0.8], u[:, 0])
        b = 2.0 * np.concatenate([[0.0], u[:-1, 0]])
        return vrig.TimeHistory(np.column_stack([a, b]), self.fs, ["a", "b"], ["N", "N"])


def _two_transducer_desired(rig, seconds=20.0, seed=3):
    d = random_drive(
        triangular_psd((0.0, 15.0)), int(seconds * rig.fs), rig.fs, rms=0.05, seed=seed, names=["u"]
    )
    return rig.run(d)


def test_every_drive_is_band_limited_and_starts_and_ends_at_rest():
    from vrig.reconstruction import DriveIteration

    rig = _TwoTransducerRig()
    desired = _two_transducer_desired(rig)
    engine = DriveIteration(rig, desired, method="arx", order=2, taper=0.5, seed=0)
    engine.identify()
    drive = engine.first_drive()[:, 0]
    m = int(0.5 * rig.fs)
    assert drive[0] == 0.0 and drive[-1] == 0.0
    ramp = 0.5 - 0.5 * np.cos(np.pi * np.arange(m) / m)  # raised-cosine taper: a ramp, no step
    assert np.all(np.abs(drive[:m]) <= ramp * np.abs(drive).max() + 1e-15)
    assert np.all(np.abs(drive[::-1][:m]) <= ramp * np.abs(drive).max() + 1e-15)
    # nothing above the identification band's edge (24 Hz; zero-phase 8th-order skirt)
    spectrum = np.abs(np.fft.rfft(drive[m:-m]))
    f = np.fft.rfftfreq(drive.size - 2 * m, 1 / rig.fs)
    assert spectrum[f > 40].max() < 1e-3 * spectrum.max()


def test_inverse_on_a_subset_of_responses_scores_every_response():
    from vrig.reconstruction import InverseArx

    rig = _TwoTransducerRig()
    desired = _two_transducer_desired(rig)
    res = reconstruct(rig, desired, method=InverseArx(2, responses=["b"]), iterations=2, seed=0)
    assert res.errors.shape == (3, 2)  # both responses scored
    assert res.method.inverse.model.n_inputs_ == 1  # the inverse sees response b only
    # b = 2 u(t-1) is exactly invertible: both responses are reproduced
    assert res.errors[-1].max() < 2.0
    with pytest.raises(vrig.ReconstructionError, match="no channel 'c'") as err:
        reconstruct(rig, desired, method=InverseArx(2, responses=["c"]), iterations=0)
    assert isinstance(err.value.cause, KeyError) and err.value.result.id_response is not None


def test_multiple_transducer_split_spectra_uses_each_bands_own_response():
    from vrig.reconstruction import InverseArx, SplitSpectra

    rig = _TwoTransducerRig()
    desired = _two_transducer_desired(rig)
    method = SplitSpectra(
        5.0, InverseArx(2), InverseArx(2), low_responses=["a"], high_responses=["b"]
    )
    res = reconstruct(rig, desired, method=method, iterations=2, seed=0)
    assert method.low.inverse.model.n_inputs_ == 1 and method.high.inverse.model.n_inputs_ == 1
    assert res.errors[-1].max() < 5.0


def test_output_subset_rig_plays_the_whole_rig_and_returns_the_chosen_responses():
    from vrig.rigs import OutputSubset

    rig = _TwoTransducerRig()
    sub = OutputSubset(rig, ["b"])
    assert [c.name for c in sub.outputs] == ["b"] and sub.inputs == rig.inputs
    assert sub.fs == rig.fs and sub.bandwidth == rig.bandwidth
    u = np.zeros((50, 1))
    u[10, 0] = 1.0
    out = sub.run(u)
    assert out.names == ("b",) and out.data[11, 0] == 2.0
    with pytest.raises(ValueError, match="cannot select"):
        OutputSubset(rig, ["c"])


def test_the_identification_drive_follows_the_given_psd():
    from scipy import signal

    rig = _TwoTransducerRig()
    desired = _two_transducer_desired(rig)
    flat = flat_psd((5.0, 10.0))
    res = reconstruct(rig, desired, method="arx", order=2, iterations=0, id_psd=flat, seed=0)
    f, p = signal.welch(res.id_drive.data[:, 0], fs=rig.fs, nperseg=256)
    inside = (f > 6) & (f < 9)
    outside = (f < 3) | (f > 12)  # a Welch line's Hann leakage reaches ~2 Hz
    assert p[outside].max() < 1e-2 * p[inside].mean()


# --- the reference text's comparisons that hold on the virtual rigs (Tables 3.4 and 3.7)


def test_fuel_tank_split_spectra_beats_the_full_spectrum_model():
    """Table 3.4: the tank's bounce/pitch modes (11.3/13.2 Hz on the settled buffers) inside the
    band spoil one full-spectrum inverse; two band models split at 12 Hz do better (text: 20 vs
    46 %).

    On the datasheet-typical set (``variant="mild"``: progressive buffers and snubbers), whose
    modes straddle the 12 Hz split. On the calibrated default (``thesis``, issue 23: no snubbers)
    the split row is a prediction the twin meets only in its ordering (README "Variants"),
    reported by benchmarks/thesis_tables.py, not asserted here."""
    from vrig.reconstruction import InverseArx, SplitSpectra

    rig = vrig.load_rig("fuel-tank-2ch", seed=0, variant="mild")
    band = (1.0, 40.0)
    _drive, desired = vrig.pseudo_field(rig, band, 20.0, seed=0)
    common = dict(iterations=0, bandwidth=band, id_duration=30.0, seed=0)
    full = reconstruct(rig, desired, method=InverseArx(4), **common)
    split = reconstruct(
        rig, desired, method=SplitSpectra(12.0, InverseArx(4), InverseArx(4)), **common
    )
    assert np.all(split.errors[0] <= 0.8 * full.errors[0])


@pytest.mark.slow
def test_rig_specific_psds_model_the_seven_channel_rig_better():
    """Table 3.7 / Algorithm 3.1, in the form the text states it: the rig-specific drive PSD
    "proved effective for the vertical channels" (Sec. 3.3.1), i.e. a lower inverse modelling
    error over the four vertical channels (mean of channels 1-4) than the triangular PSD.

    The former claim (lower error on at least 5 of 7 channels) was never robust: it hangs on
    the inverses' automatic lead. Both at 12 samples: 3 of 7 (vertical 45/57/47/43 % vs
    47/52/52/55 %; lateral and longitudinal 83/100/57 % vs 66/66/56 %); both at 13: 6 of 7; the
    5 of 7 before the chunked-run commit was triangular at 13, rig-specific at 12, and a new
    noise realisation alone moved the triangular lead to 12. The noise itself moves every
    error by ~0.1 %-points. The vertical mean is lower at either lead (48.0 vs 51.5 % at 12,
    47.4 vs 51.5 % at 13)."""
    from benchmarks.thesis_tables import table_3_7

    _names, out = table_3_7(seconds=30.0, log=lambda *a: None)
    tri, spec = np.array(out["triangular"]), np.array(out["rig-specific (Alg. 3.1)"])
    assert spec[:4].mean() < tri[:4].mean(), (spec.round(1), tri.round(1))


def test_a_time_domain_inverse_drives_a_cut_out_desired_response_without_a_start_kick():
    """A desired response is a cut-out of a longer record (not at rest at sample 0): the
    method's free run starts from a faded-in history, so a degree-2 inverse of a linear system
    gives the cut-out's own drive from the first samples on, as the linear inverse does."""
    from scipy import signal

    from identification import band_limited_noise
    from vrig.reconstruction import InverseNarx

    def plant(d):  # linear actuator lag + stiffness: exact inverse d(t) = d(t-1)/3 + ...
        x = signal.lfilter([0.2], [1.0, -0.8], d)
        return 1000.0 * (1.5 * x - 0.5 * np.concatenate([[0.0], x[:-1]]))

    fs = 250.0
    d_id = 1e-3 * band_limited_noise(6000, 1, cutoff=0.2, seed=1)[:, 0]
    y_id = plant(d_id) * (1 + 0.002 * np.random.default_rng(0).standard_normal(6000))
    d_long = 2e-3 * band_limited_noise(4000, 1, cutoff=0.1, seed=2)[:, 0]
    d_des, y_des = d_long[1000:], plant(d_long)[1000:]

    def th(x, name, unit):
        return vrig.TimeHistory(x[:, None], fs, [name], [unit])

    rms = np.sqrt(np.mean(d_des**2))
    for method in (InverseArx(4, lead=0), InverseNarx(4, 2, focus="simulation", lead=0)):
        method.identify(th(d_id, "drive", "m"), th(y_id, "load", "N"))
        drive = method.drive(th(y_des, "load", "N"))[:, 0]
        assert np.sqrt(np.mean((drive - d_des) ** 2)) < 0.03 * rms, method.describe()


def test_a_narx_inverse_is_kept_bounded_at_the_desired_responses_level():
    """The inverse runs on the desired response, ~2x the identification response at the default
    identification level. A drive that obeys d(t) = r(t) + 0.5 d(t-1) + 0.25 d(t-1)^2 (the
    exact inverse of r(t) = d(t) - 0.5 d(t-1) - 0.25 d(t-1)^2) has no bounded solution once
    r stays above 0.25: identified at r ~ 0.11, the exact model is bounded at 1.5x (Narx's own
    default margin) but not at 2x. The method's margin (3x) must give a model whose drive for
    a 2x response is bounded; an explicit 1.5x margin keeps the exact, escaping structure."""
    from identification import SimulationDivergedError, band_limited_noise
    from vrig.reconstruction import InverseNarx

    d = 0.25 + 0.05 * band_limited_noise(3000, 1, cutoff=0.1, seed=3)[:, 0]
    prev = np.concatenate([[0.0], d[:-1]])
    r = d - 0.5 * prev - 0.25 * prev**2
    r_noisy = r + 0.002 * r.std() * np.random.default_rng(0).standard_normal(r.size)

    def th(x, name):
        return vrig.TimeHistory(x[:, None], 100.0, [name], ["m"])

    method = InverseNarx(1, 2, kind="full", focus="simulation", lead=0)
    method.identify(th(d, "drive"), th(r_noisy, "response"))
    assert method.inverse.model.stability_margin == 3.0
    drive = method.drive(th(2.0 * r, "response"))
    assert np.all(np.isfinite(drive)) and np.abs(drive).max() < 10 * np.abs(d).max()
    exact = InverseNarx(1, 2, kind="full", focus="simulation", lead=0, stability_margin=1.5)
    exact.identify(th(d, "drive"), th(r_noisy, "response"))
    coef = dict(zip(exact.inverse.model.term_names()[0], exact.inverse.model.coef_[0], strict=True))
    assert abs(coef["drive(t-1)*drive(t-1)"] - 0.25) < 0.02  # the generating structure
    with pytest.raises(SimulationDivergedError):
        exact.drive(th(2.0 * r, "response"))  # reported as a divergence, not a huge drive


def test_a_searched_narx_method_reports_its_search():
    """InverseNarx(search=True): the inverse's structure found by NarxSearch within its budget;
    the plant's exact inverse is linear (order 1 with a lead of 1 sample), so the search's
    drive for a fresh response matches the true drive, and the search's table is reported."""
    from identification import band_limited_noise
    from vrig.reconstruction import InverseNarx

    def plant(d):
        return np.concatenate([[0.0], 0.5 * d[:-1]]) + 0.3 * np.concatenate(
            [[0.0, 0.0], d[:-2]]
        )

    fs = 200.0
    d_id = band_limited_noise(5000, 1, cutoff=0.3, seed=1)[:, 0]
    d_new = band_limited_noise(2000, 1, cutoff=0.2, seed=2)[:, 0]

    def th(x, name):
        return vrig.TimeHistory(x[:, None], fs, [name], ["m"])

    method = InverseNarx(2, 2, search=True, budget=5.0)
    assert method.options()["search"] is True
    method.identify(th(d_id, "drive"), th(plant(d_id), "load"))
    report = method.search_report()
    assert report.startswith("NarxSearch:") and "searched:" in method.describe()
    drive = method.drive(th(plant(d_new), "load"))[:, 0]
    err = np.sqrt(np.mean((drive[200:-5] - d_new[200:-5]) ** 2)) / d_new.std()
    assert err < 1e-3, (err, method.describe())
    # the searched inverse has the fitted inverse's model class: no constant term, even on a
    # response with a mean (NarxSearch's own default has one)
    offset = InverseNarx(2, 2, search=True, budget=5.0)
    offset.identify(th(d_id, "drive"), th(plant(d_id) + 0.2, "load"))
    assert "1" not in offset.inverse.model.term_names()[0]
    with pytest.raises(ValueError, match="search must be True or False"):
        InverseNarx(2, 2, search="yes")


# ---------------------------------------------------------------------------------------------
# issue 25 item 7: a user's own rig (a side-car without a "reconstruction" block)
# ---------------------------------------------------------------------------------------------
USER_RIG = __import__("pathlib").Path(__file__).parent / "data" / "servo_mass.rig.json"


def test_split_on_a_users_rig_splits_at_the_bands_rule_not_a_type_error():
    """``vrig.reconstruct(rig, desired, method="split")`` on a rig loaded from its path whose
    side-car has no "reconstruction" block raised ``TypeError: SplitSpectra.__init__() missing
    ... 'split_hz'``. The rule (vrig.reconstruction.defaults.default_split_hz, the one the CLI and the envs use):
    the side-car's split, else the band's geometric mean, or a quarter of its upper edge for a
    band from 0 Hz."""
    from vrig.reconstruction import DriveIteration
    from vrig.reconstruction.defaults import default_split_hz

    rig = vrig.load_rig(USER_RIG)
    assert rig.defaults.method("split").split_hz is None and rig.bandwidth == (0.0, 250.0)
    desired = vrig.TimeHistory(np.zeros((4000, 2)), rig.fs, [c.name for c in rig.outputs])
    assert DriveIteration(rig, desired, method="split").method.split_hz == 250.0 / 4
    band = DriveIteration(rig, desired, method="split", bandwidth=(4.0, 100.0)).method
    assert band.split_hz == pytest.approx(20.0)  # sqrt(4 * 100)
    given = DriveIteration(rig, desired, method="split", split_hz=30.0).method
    assert given.split_hz == 30.0
    assert default_split_hz((0.0, 40.0)) == 10.0 and default_split_hz((1.0, 100.0)) == 10.0
    # a shipped rig whose side-car names its split keeps it (the shaker: 40 Hz in 10-60 Hz)
    shaker = vrig.load_rig("shaker", fidelity="fast")
    assert default_split_hz((10.0, 60.0), shaker) == 40.0
    # the method by name without its required option: a ValueError naming it
    with pytest.raises(ValueError, match="split_hz"):
        vrig.reconstruction.make_method("split")


def test_reconstruct_split_runs_on_a_users_rig():
    rig = vrig.load_rig(USER_RIG, fidelity="fast")
    names = [c.name for c in rig.inputs]
    drive = random_drive(triangular_psd((0.0, 40.0)), 4000, rig.fs, rms=0.002, seed=1, names=names)
    desired = rig.run(drive, seed=2)
    result = reconstruct(rig, desired, method="split", iterations=1, bandwidth=(0.0, 40.0))
    assert result.method.split_hz == 10.0
    assert result.errors.shape == (2, 2) and np.all(np.isfinite(result.errors))


def test_the_shortest_identification_record_is_what_the_identification_needs():
    """DriveIteration.check_length's rule (issue 25 item 6): ARX(4) at the default lead search
    needs max_lead + DELAY_SAMPLES = 128 model-rate samples - exactly the delay estimate's own
    need (identification.estimate_delay refuses 127 and takes 128); the H1 inverse 32."""
    from identification import IdentificationError, estimate_delay
    from vrig.reconstruction import DriveIteration
    from vrig.reconstruction.methods import DELAY_SAMPLES, FRF_MIN_SAMPLES, InverseArx

    assert InverseArx(4).min_samples(1, 1) == 32 + DELAY_SAMPLES == 128
    rng = np.random.default_rng(0)
    u = rng.standard_normal(128)
    y = np.convolve(u, [0.0, 0.0, 1.0, 0.5])[:128]
    assert estimate_delay(u, y, max_lag=32) == 2
    with pytest.raises(IdentificationError, match="need more than 127 samples"):
        estimate_delay(u[:127], y[:127], max_lag=32)
    rig = vrig.load_rig(USER_RIG, fidelity="fast")
    names = [c.name for c in rig.outputs]
    # fs 1000 Hz, band 0-250 Hz: no decimation; 127 samples refused before anything is played
    short = vrig.TimeHistory(rng.standard_normal((127, 2)), rig.fs, names)
    with pytest.raises(ValueError, match=r"127 samples at the model rate 1000 Hz.*needs at least 128"):
        DriveIteration(rig, short, method="arx").check_length()
    DriveIteration(rig, short.with_data(rng.standard_normal((128, 2)))).check_length()
    assert DriveIteration(rig, short, method="frf").method.min_samples(1, 2) == FRF_MIN_SAMPLES
    # a longer identification drive (id_duration) makes a short desired record usable
    DriveIteration(rig, short, method="arx", id_duration=0.2).check_length()


def test_a_polynomial_inverse_identified_below_the_targets_peak_is_flagged():
    """Issue 25 item 7: on a user's rig at the global defaults (identification at 5 % of full
    scale) the NARX inverse is used beyond the amplitude range it was fitted on; its polynomial
    extrapolates and IT01DRV overshot the full scale (arx, frf: linear, ran). The identification
    report says so, and the CLI's advice after such a stop is --id-match, not a lower gain."""
    from vrig.cli import _advice
    from vrig.reconstruction import DriveIteration

    rig = vrig.load_rig(USER_RIG, fidelity="fast")
    names = [c.name for c in rig.inputs]
    drive = random_drive(triangular_psd((0.0, 40.0)), 4000, rig.fs, rms=0.002, seed=1, names=names)
    desired = rig.run(drive, seed=2)
    low = (0.0005,)  # identification at a quarter of the target's drive level [m rms]
    narx = DriveIteration(rig, desired, method="narx", order=2, id_rms=low, bandwidth=(0, 40))
    narx.identify()
    assert max(narx.id_report["peak_ratio"]) < 1  # the target peaks beyond the identification
    assert "extrapolates" in narx.id_report["extrapolation"]
    assert "--id-match" in _advice("refused", "after IT00", 0.8, narx.id_report)
    arx = DriveIteration(rig, desired, method="arx", id_rms=low, bandwidth=(0, 40))
    arx.identify()  # a linear inverse extrapolates linearly: no note
    assert "extrapolation" not in arx.id_report
    assert "--gain" in _advice("refused", "after IT00", 0.8, arx.id_report)
