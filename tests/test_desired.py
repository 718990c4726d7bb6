"""vrig.desired.reachability and vrig.desired.belgian_block: F2D, the transducer-range check, reachability (§2.3.2), the
scaling rule, the CLI's check-target and reconstruct's summary entry, the Belgian-block record.

Truths used: the multiple coherence of a linear system with independent output noise is
S / (S + N); a rig with as many independent drives as responses reaches any target; a rig with
one drive and two responses reaches a target only along its FRF ratio, and the projection of a
target with independent channels leaves a share computable from the two PSDs; a response that
no drive moves is unreachable; the drive that made a target is the drive it needs.
"""

from __future__ import annotations

import contextlib
import io
import json
import warnings

import numpy as np
import pytest
from scipy import signal

import vrig
from vrig.cli import main
from vrig.desired.f2d import f2d
from vrig.desired.pseudo_field import pseudo_field
from vrig.desired.range_report import range_report
from vrig.desired.reachability import check_target, multiple_coherence, scale_to_limits
from vrig.processing import gprepro
from vrig.reconstruction.defaults import default_band
from vrig.signals import flat_psd, random_drive

FS = 250.0
FIR = np.array(  # responses x drives x taps: a well-conditioned 2 x 2 system
    [[[1.0, 0.5, 0.2], [0.3, -0.4, 0.1]], [[0.2, 0.1, 0.0], [1.0, -0.6, 0.3]]]
)


class LinearRig:
    """A rig that is a known linear system: ``y_j = sum_k fir[j, k] * x_k + noise_j``.

    Responses listed in ``dead`` are independent white noise of RMS 0.3 (no drive moves them).
    Drives: displacement [m], full scale 1, stroke 0.8, velocity limit 50 [m/s] (all times
    ``drive_scale``); responses [N], range 1000.
    """

    def __init__(self, fir, noise=0.002, dead=(), band=(0.0, 40.0), drive_scale=1.0):
        self.fir = np.asarray(fir, float)
        n, m, _ = self.fir.shape
        self.noise, self.dead = noise, tuple(dead)
        self.fs, self.bandwidth, self.name, self.defaults = FS, band, "linear", None
        limits = {"stroke": 0.8 * drive_scale, "velocity": 50.0 * drive_scale}
        self.inputs = tuple(
            vrig.ChannelSpec(f"x{k}", "m", drive_scale, "hydraulic", limits=limits)
            for k in range(m)
        )
        self.outputs = tuple(vrig.ChannelSpec(f"y{j}", "N", 1e3, "load_cell") for j in range(n))

    def response(self, x: np.ndarray) -> np.ndarray:
        """The noise-free response to drive samples ``x``."""
        n, m, _ = self.fir.shape
        return np.stack(
            [sum(signal.lfilter(self.fir[j, k], 1.0, x[:, k]) for k in range(m)) for j in range(n)],
            axis=1,
        )

    def run(self, drive, seed=None):
        x = drive.data if isinstance(drive, vrig.TimeHistory) else np.asarray(drive, float)
        rng = np.random.default_rng(seed)
        y = self.response(x) + self.noise * rng.standard_normal((x.shape[0], len(self.outputs)))
        for j in self.dead:
            y[:, j] = 0.3 * rng.standard_normal(x.shape[0])
        return vrig.TimeHistory(
            y, FS, [c.name for c in self.outputs], [c.unit for c in self.outputs]
        )


def _drive(rig, seconds=20.0, rms=0.1, seed=5):
    return random_drive(
        flat_psd((0.0, 40.0)), round(seconds * FS), FS, channels=len(rig.inputs), rms=rms, seed=seed
    )


def _independent(th, channel: int, seed: int = 3):
    """``th`` with one channel replaced by a copy of itself with random phases: the same PSD
    and RMS, independent of every drive."""
    y = np.array(th.data)
    spectrum = np.fft.rfft(y[:, channel])
    phase = np.exp(2j * np.pi * np.random.default_rng(seed).random(spectrum.size))
    y[:, channel] = np.fft.irfft(spectrum * phase, y.shape[0])
    return th.with_data(y)


# ------------------------------------------------------------------------ multiple coherence
def _blocks(v: np.ndarray) -> np.ndarray:
    """Means of lines 1-120 in blocks of 8."""
    return v[1:121].reshape(15, 8).mean(axis=1)


def test_multiple_coherence_of_a_linear_system_with_output_noise_is_s_over_s_plus_n():
    rng = np.random.default_rng(0)
    n, sx, sn = 2**18, np.array([1.0, 0.7]), np.array([1.0, 0.8])
    x = rng.standard_normal((n, 2)) * sx
    y = LinearRig(FIR, noise=0.0).response(x) + rng.standard_normal((n, 2)) * sn
    f, gamma2 = multiple_coherence(x, y, FS, nperseg=256)
    for j in range(2):  # white inputs and noise: S_j(f) = sum_k |H_jk|^2 sx_k^2 (same scaling)
        s = sum(
            np.abs(signal.freqz(FIR[j, k], 1.0, worN=f, fs=FS)[1]) ** 2 * sx[k] ** 2
            for k in range(2)
        )
        truth = s / (s + sn[j] ** 2)
        assert truth.min() < 0.5 < truth.max()  # the test spans low and high coherence
        # 2047 averages: a line's estimate scatters by up to 0.013 (std), its bias is 0.0003;
        # blocks of 8 neighbouring lines (the truth is smooth) scatter by < 0.007
        np.testing.assert_allclose(_blocks(gamma2[:, j]), _blocks(truth), atol=0.03)


def test_multiple_coherence_of_one_drive_is_the_ordinary_coherence():
    rng = np.random.default_rng(1)
    x = rng.standard_normal(5000)
    y = signal.lfilter([1.0, 0.5], [1.0, -0.3], x) + rng.standard_normal(5000)
    f, gamma2 = multiple_coherence(x, y, FS, nperseg=255)
    f_ref, ref = signal.coherence(x, y, fs=FS, nperseg=255)
    np.testing.assert_allclose(f, f_ref)
    np.testing.assert_allclose(gamma2[:, 0], ref, atol=1e-12)
    with pytest.raises(ValueError, match="nperseg must be"):
        multiple_coherence(x, y, FS, nperseg=10_000)


# --------------------------------------------------------------------- reachability (known rig)
def test_a_square_rig_reaches_any_target_also_one_with_independent_channels():
    rig = LinearRig(FIR)
    target = rig.run(_drive(rig), seed=9)
    assert np.all(check_target(rig, target).unreachable < 0.02)
    assert np.all(check_target(rig, _independent(target, 1)).unreachable < 0.02)


def test_one_drive_two_responses_leaves_the_inconsistent_share_of_a_target():
    rig = LinearRig(FIR[:, :1])
    target = rig.run(_drive(rig), seed=9)
    consistent = check_target(rig, target)
    assert np.all(consistent.unreachable < 0.02)
    check = check_target(rig, _independent(target, 1))
    # analytic: in channels normalised by their RMS, the rig reaches the direction u ∝ (h1, h2)
    # with |u_j|^2 = P_j / (P1 + P2) (P_j: normalised PSD of channel j, white drive); the
    # residual of two independent channels is 2 P1 P2^2 / (P1 + P2)^2 on channel 1 and
    # 2 P1^2 P2 / (P1 + P2)^2 on channel 2
    f = np.fft.rfftfreq(256, 1 / FS)
    f = f[(f > 0) & (f <= 40.0)]
    p = np.array([np.abs(signal.freqz(FIR[j, 0], 1.0, worN=f, fs=FS)[1]) ** 2 for j in range(2)])
    p /= p.sum(axis=1, keepdims=True)
    share = 2 * p[0] * p[1] / (p[0] + p[1]) ** 2
    expected = [np.sum(share * p[1]), np.sum(share * p[0])]
    np.testing.assert_allclose(check.unreachable, expected, atol=0.06)
    assert check.unreachable.sum() > 0.5  # and far from the consistent target's


def test_a_response_no_drive_moves_is_unreachable():
    rig = LinearRig(FIR, dead=(1,))
    check = check_target(rig, rig.run(_drive(rig), seed=9))
    assert check.unreachable[1] > 0.9 and check.unreachable[0] < 0.02
    assert check.channels[1].incoherent > 0.9 and check.channels[0].incoherent < 0.02


def test_the_needed_drive_is_the_drive_that_made_the_target():
    rig = LinearRig(FIR)
    drive = _drive(rig)
    check = check_target(rig, rig.run(drive, seed=9))
    made = gprepro(drive, default_band(rig)).data
    spectrum = np.fft.rfft(made, axis=0)
    omega = 2 * np.pi * np.fft.rfftfreq(made.shape[0], 1 / FS)
    velocity = np.fft.irfft(1j * omega[:, None] * spectrum, made.shape[0], axis=0)
    for k, need in enumerate(check.drives):
        assert need.needed_peak == pytest.approx(np.abs(made[:, k]).max(), rel=0.1)
        assert need.needed_peak_velocity == pytest.approx(np.abs(velocity[:, k]).max(), rel=0.15)
        assert need.limit == 0.8 and need.limit_kind == "stroke"  # the stroke is below full scale
        assert need.fraction_of_limit == pytest.approx(need.needed_peak / 0.8)
        assert need.fraction_of_velocity_limit == pytest.approx(need.needed_peak_velocity / 50)


def test_scale_to_limits_halves_the_binding_limit_and_never_scales_up():
    rig = LinearRig(FIR)
    drive = _drive(rig, rms=0.4)  # peaks beyond half the 0.8 stroke
    target = rig.run(drive, seed=9)
    check = check_target(rig, target)
    made = gprepro(drive, default_band(rig)).data
    spectrum = np.fft.rfft(made, axis=0)
    omega = 2 * np.pi * np.fft.rfftfreq(made.shape[0], 1 / FS)
    velocity = np.fft.irfft(1j * omega[:, None] * spectrum, made.shape[0], axis=0)
    stroke, speed = 0.5 * 0.8 / np.abs(made).max(), 0.5 * 50.0 / np.abs(velocity).max()
    assert stroke < 1 and speed < 1
    scale = scale_to_limits(rig, target, check)
    assert scale.factor == pytest.approx(min(stroke, speed), rel=0.15)
    assert scale.binding.startswith("stroke of x" if stroke < speed else "velocity limit of x")
    small = target.with_data(target.data * 1e-3)  # far within every limit: kept as it is
    assert scale_to_limits(rig, small, check_target(rig, small)).factor == 1.0
    wide = LinearRig(FIR, drive_scale=1e6)  # drives that never bind: the range does
    ranged = target.with_data(target.data * 1500 / np.abs(target.data).max())
    scale = scale_to_limits(wide, ranged, check_target(wide, ranged))
    worst = np.argmax(np.abs(ranged.data).max(axis=0))
    assert scale.factor == pytest.approx(0.5 * 1000 / 1500)
    assert scale.binding == f"transducer range of y{worst}"
    with pytest.raises(ValueError, match="drive_fraction"):
        scale_to_limits(rig, target, check, drive_fraction=0)


def test_check_target_refuses_targets_it_cannot_judge():
    rig = LinearRig(FIR)
    target = rig.run(_drive(rig), seed=9)
    with pytest.raises(ValueError, match="has 1 channels"):
        check_target(rig, target[["y0"]])
    with pytest.raises(ValueError, match="sampled at 500 Hz"):
        check_target(rig, vrig.TimeHistory(target.data, 500.0, target.names, target.units))
    with pytest.raises(ValueError, match="too short for the spectral estimate"):
        check_target(rig, target.window(0.0, 1.0))
    with pytest.raises(ValueError, match="both id_drive and id_response"):
        check_target(rig, target, id_drive=_drive(rig))
    with pytest.raises(ValueError, match="band must satisfy"):
        check_target(rig, target, band=(10.0, 500.0))


def test_the_check_reads_as_a_table_and_as_json():
    rig = LinearRig(FIR)
    target = rig.run(_drive(rig), seed=9)
    check = check_target(rig, target)
    in_band = gprepro(target, default_band(rig)).data.std(axis=0)  # Parseval: the same power
    np.testing.assert_allclose([c.target_rms for c in check.channels], in_band, rtol=0.05)
    text = str(check)
    assert "unreachable" in text and "needed peak" in text and "y1" in text and "x0" in text
    data = json.loads(json.dumps(check.to_dict()))
    assert [c["name"] for c in data["channels"]] == ["y0", "y1"]
    assert data["drives"][0]["limit_kind"] == "stroke" and data["band_hz"] == [0.0, 40.0]


# ---------------------------------------------------------------------------------------- F2D
def _field(rig, amplitude=(3.0, 5.0), unit="N", names=None, high=2.0):
    """20 s at 256 Hz: 10 Hz tones (in band), a 100 Hz tone of amplitude ``high`` (out of
    band), an offset and a trend."""
    fs, seconds = 256.0, 20.0
    t = np.arange(round(seconds * fs)) / fs
    x = np.stack(
        [
            a * np.sin(2 * np.pi * 10 * t) + high * np.sin(2 * np.pi * 100 * t) + 7 + 0.3 * t
            for a in amplitude
        ],
        axis=1,
    )
    names = names or [c.name for c in rig.outputs]
    return vrig.TimeHistory(x, fs, names, [unit] * len(names))


def _tone_amplitude(x: np.ndarray, fs: float, hz: float) -> np.ndarray:
    t = np.arange(x.shape[0]) / fs
    mid = slice(x.shape[0] // 4, 3 * x.shape[0] // 4)
    basis = np.stack([np.sin(2 * np.pi * hz * t), np.cos(2 * np.pi * hz * t)], axis=1)[mid]
    coef = np.linalg.lstsq(basis, x[mid], rcond=None)[0]
    return np.hypot(*coef)


def test_f2d_resamples_band_limits_and_removes_the_offset():
    rig = LinearRig(FIR)
    desired = f2d(_field(rig), rig)
    assert desired.fs == FS and desired.names == ("y0", "y1") and desired.units == ("N", "N")
    assert desired.n_samples == 5000  # 20 s at 256 Hz, resampled by 125/128
    np.testing.assert_allclose(_tone_amplitude(desired.data, FS, 10.0), [3.0, 5.0], rtol=0.02)
    assert np.all(_tone_amplitude(desired.data, FS, 100.0) < 0.01)  # outside the 0-40 Hz band
    assert np.all(np.abs(desired.data.mean(axis=0)) < 1e-9)


def test_f2d_maps_channels_by_name_and_checks_units():
    rig = LinearRig(FIR)
    field = _field(rig, (0.3, 0.5), unit="kN", names=["left", "right"], high=0.02)
    with pytest.raises(ValueError, match=r"no channel for the rig's response\(s\) \['y0', 'y1'\]"):
        f2d(field, rig)
    mapping = {"y0": "right", "y1": "left"}
    with pytest.raises(ValueError, match=r"in 'kN'.*'N'.*1 kN = 1000 N"):
        f2d(field, rig, channels=mapping)
    desired = f2d(field, rig, channels=mapping, scale={"y0": 1e3, "y1": 2e3})
    np.testing.assert_allclose(_tone_amplitude(desired.data, FS, 10.0), [500.0, 600.0], rtol=0.02)
    with pytest.raises(ValueError, match="not responses of the rig"):
        f2d(field, rig, channels={"z": "left"})


def test_range_report_counts_the_samples_beyond_the_range():
    rig = LinearRig(FIR)
    x = np.zeros((1000, 2))
    x[:100, 1] = 2000.0  # 10 % of the samples at twice the 1000 N range
    x[:, 0] = 500.0
    report = range_report(rig, vrig.TimeHistory(x, FS, ["y0", "y1"], ["N", "N"]))
    assert report.exceeding == ("y1",)
    assert report.rows[1].fraction_beyond == pytest.approx(0.1)
    assert report.rows[1].peak_fraction == pytest.approx(2.0)
    assert (
        report.rows[0].peak_fraction == pytest.approx(0.5) and report.rows[0].fraction_beyond == 0
    )
    assert "EXCEEDS" in report.table()


def test_f2d_warns_once_per_channel_beyond_the_range():
    rig = LinearRig(FIR)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        f2d(_field(rig, (3.0, 2500.0)), rig)
    lines = [str(w.message) for w in caught if issubclass(w.category, UserWarning)]
    assert len(lines) == 1 and lines[0].startswith("f2d: y1 peaks at") and "\n" not in lines[0]


# ------------------------------------------------------------------------------- MuJoCo rigs
@pytest.mark.parametrize("name", ["shock-absorber", "fuel-tank-2ch"])
def test_a_pseudo_field_target_is_reachable(name):
    rig = vrig.load_rig(name, fidelity="fast")
    _, target = pseudo_field(rig, default_band(rig), 10.0, seed=0)
    check = check_target(rig, target, seed=1)
    assert np.all(check.unreachable < 0.02), check.table()


class _DeadChannel:
    """A rig whose response ``channel`` is independent band-limited noise (a transducer on a
    part no actuator moves), of about its own RMS under the pseudo-field drive."""

    def __init__(self, rig, channel: int, rms: float):
        self.rig, self.channel, self.rms = rig, channel, rms

    def __getattr__(self, attr):
        return getattr(self.rig, attr)

    def run(self, drive, seed=None):
        out = np.array(self.rig.run(drive, seed=seed).data)
        noise = random_drive(
            flat_psd(default_band(self.rig)),
            out.shape[0],
            self.rig.fs,
            rms=self.rms,
            seed=(seed or 0) + 123,
        )
        out[:, self.channel] = noise.data[:, 0]
        return vrig.TimeHistory(
            out, self.rig.fs, [c.name for c in self.rig.outputs], [c.unit for c in self.rig.outputs]
        )


def test_a_response_channel_independent_of_the_drives_is_unreachable_on_a_rig():
    rig = vrig.load_rig("fuel-tank-2ch", fidelity="fast")
    dead = _DeadChannel(rig, 1, rms=10.0)
    _, target = pseudo_field(dead, default_band(rig), 10.0, seed=0)
    check = check_target(dead, target, seed=1)
    assert check.unreachable[1] > 0.9 and check.unreachable[0] < 0.02, check.table()


def test_the_needed_drive_of_a_pseudo_field_target_is_its_drive():
    rig = vrig.load_rig("shaker", fidelity="fast")  # the near-linear reference rig
    drive, target = pseudo_field(rig, default_band(rig), 10.0, seed=0)
    check = check_target(rig, target, seed=1)
    made = np.abs(gprepro(drive, default_band(rig)).data).max()
    assert check.drives[0].needed_peak == pytest.approx(made, rel=0.15)


def test_the_target_check_identifies_as_the_reconstruction_does(monkeypatch):
    """check_target's own identification run is the engine's (one identification drive): with
    the same band, level and seed it plays the same IDDRV and gets the same IDRES."""
    from vrig.desired import reachability
    from vrig.reconstruction import DriveIteration

    rig = vrig.load_rig("shock-absorber", fidelity="fast")
    desired = rig.run(_drive_for(rig), seed=2)
    engine = DriveIteration(rig, desired, id_seed=4)
    engine.identify()
    seen = {}
    real = reachability._lines

    def lines(drive, response, *a):
        seen["pair"] = (drive, response)
        return real(drive, response, *a)

    monkeypatch.setattr(reachability, "_lines", lines)
    check_target(rig, desired, seed=4)
    drive, response = seen["pair"]
    np.testing.assert_array_equal(drive, engine.id_drive.data)
    np.testing.assert_array_equal(response, engine.id_response.data)


def _drive_for(rig, seconds=10.0):
    return random_drive(
        flat_psd((0.5, 5.0)),
        round(seconds * rig.fs),
        rig.fs,
        rms=0.05 * rig.inputs[0].full_scale,
        seed=1,
        names=[rig.inputs[0].name],
    )


# ----------------------------------------------------------------------------------------- CLI
def _cli(argv):
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main(argv)
    return code, out.getvalue(), err.getvalue()


@pytest.fixture(scope="module")
def shock_target(tmp_path_factory):
    rig = vrig.load_rig("shock-absorber")
    _, target = pseudo_field(rig, default_band(rig), 10.0, seed=0)
    path = tmp_path_factory.mktemp("targets") / "target.npz"
    vrig.io.write(path, target)
    return path, target


def test_cli_check_target_prints_the_ranges_and_the_check(shock_target):
    path, _ = shock_target
    code, out, _ = _cli(["check-target", "--rig", "shock-absorber", "--desired", str(path)])
    assert code == 0
    assert "transducer range" in out and "unreachable" in out and "needed peak" in out
    line = next(
        ln
        for ln in out.splitlines()
        if ln.startswith("damper_load") and "%" in ln and "N" in ln and "±" not in ln
    )
    assert float(line.split()[-4]) < 2.0  # unreachable [%] of a pseudo-field target


def test_cli_check_target_rejects_bad_input(shock_target, tmp_path):
    path, target = shock_target
    code, _, err = _cli(["check-target", "--rig", "shock-absorber", "--desired", str(tmp_path)])
    assert code == 2 and "a folder, not a file" in err
    wrong_fs = tmp_path / "fs.npz"
    vrig.io.write(wrong_fs, vrig.TimeHistory(target.data, 400.0, target.names, target.units))
    code, _, err = _cli(["check-target", "--rig", "shock-absorber", "--desired", str(wrong_fs)])
    assert code == 2 and "resample it first" in err
    short = tmp_path / "short.npz"
    vrig.io.write(short, target.window(0.0, 2.0))
    code, _, err = _cli(["check-target", "--rig", "shock-absorber", "--desired", str(short)])
    assert code == 2 and "too short for the spectral estimate" in err
    code, _, err = _cli(
        ["check-target", "--rig", "shock-absorber", "--desired", str(path), "--seconds", "1"]
    )
    assert code == 2 and "--seconds must be" in err


def _reconstruct(out):
    return _cli(
        [
            "reconstruct",
            "--rig",
            "shock-absorber",
            "--seconds",
            "10",
            "--iterations",
            "0",
            "--out",
            str(out),
        ]
    )


def test_reconstruct_records_the_target_check_in_the_summary(tmp_path):
    code, _, _ = _reconstruct(tmp_path / "rec")
    assert code == 0
    summary = json.loads((tmp_path / "rec" / "summary.json").read_text())
    check = summary["target_check"]
    assert check["rig"] == "shock-absorber" and check["band_hz"] == summary["bandwidth_hz"]
    assert check["channels"][0]["unreachable"] < 0.02
    assert check["id_seconds"] == pytest.approx(summary["duration_s"])  # its own IDRES


def test_a_failing_target_check_never_loses_the_run(tmp_path, monkeypatch):
    import vrig.desired.reachability

    def broken(*args, **kwargs):
        raise RuntimeError("no spectra today")

    monkeypatch.setattr(vrig.desired.reachability, "check_target", broken)
    code, _, _ = _reconstruct(tmp_path / "rec")
    assert code == 0
    summary = json.loads((tmp_path / "rec" / "summary.json").read_text())
    assert summary["target_check"] == {"error": "RuntimeError: no spectra today"}
    assert summary["iterations_run"] == 0


# ----------------------------------------------------------------------- the Belgian record
@pytest.fixture(scope="module")
def belgian_path():
    from vrig.desired.belgian_block import belgian_block_path

    try:
        return belgian_block_path()
    except FileNotFoundError as exc:
        pytest.skip(f"public data absent: {exc}")


def test_the_belgian_record_maps_to_the_four_vertical_responses(belgian_path):
    from vrig.desired.belgian_block import (
        belgian_block_desired,
        belgian_block_record,
        belgian_block_rig,
    )

    rig = vrig.load_rig("fuel-tank-7ch", fidelity="fast")
    desired = belgian_block_desired(rig, seconds=10.0, start=20.0, scale=0.25)
    names = ("LF_vertical_acc", "RF_vertical_acc", "LR_vertical_acc", "RR_vertical_acc")
    assert desired.names == names and desired.units == ("m/s^2",) * 4
    assert desired.fs == rig.fs and desired.n_samples == 2500
    assert [c.name for c in belgian_block_rig(rig).outputs] == list(names)
    # independent F2D of the record at its own rate: g -> m/s^2, x 0.25, 1-40 Hz band-pass
    raw = belgian_block_record(belgian_path)
    wheels = [
        "WFT1@LF_Z_Acceler.RN_1",
        "WFT1@RF_Z_Acceler.RN_1",
        "WFT2@LR_Z_Acceler.RN_1",
        "WFT2@RR_Z_Acceler.RN_1",
    ]
    x = raw[wheels].data[20 * 256 : 30 * 256] * 9.80665 * 0.25
    sos = signal.butter(4, [1.0, 40.0], btype="bandpass", fs=256.0, output="sos")
    ref = signal.sosfiltfilt(sos, signal.detrend(x, axis=0), axis=0)
    mid = slice(250, -250)  # away from the filters' edges
    np.testing.assert_allclose(desired.data[mid].std(axis=0), ref[64:-64].std(axis=0), rtol=0.03)


def test_the_belgian_record_says_where_it_is_missing(tmp_path):
    from vrig.desired.belgian_block import belgian_block_desired

    rig = vrig.load_rig("fuel-tank-7ch", fidelity="fast")
    with pytest.raises(FileNotFoundError, match=str(tmp_path)):
        belgian_block_desired(rig, tmp_path / "none.rsp", scale=1.0)
    with pytest.raises(ValueError, match="must lie in the record"):
        belgian_block_desired(rig, seconds=60.0, start=280.0, scale=1.0)
    with pytest.raises(ValueError, match="no response"):
        belgian_block_desired(vrig.load_rig("shock-absorber", fidelity="fast"), scale=1.0)


def test_the_belgian_record_is_scaled_to_the_actuator_velocity(belgian_path):
    from vrig.desired.belgian_block import belgian_block_desired, belgian_block_record

    rig = vrig.load_rig("fuel-tank-7ch", fidelity="fast")
    desired = belgian_block_desired(rig, seconds=20.0, start=20.0)
    physical = belgian_block_desired(rig, seconds=20.0, start=20.0, scale=1.0)
    factor = desired.data.std() / physical.data.std()
    # independent estimate: the vertical links follow the actuators 1:1 below ~30 Hz (the rig's
    # README), so the drive velocity is the wheel velocity, the record integrated over 1-40 Hz;
    # the rule allows half of the 0.525 m/s actuator velocity limit
    wheels = ["WFT1@LF_Z_Acceler.RN_1", "WFT1@RF_Z_Acceler.RN_1"]
    acc = belgian_block_record(belgian_path)[wheels].data[20 * 256 : 40 * 256] * 9.80665
    spectrum = np.fft.rfft(acc, axis=0)
    f = np.fft.rfftfreq(acc.shape[0], 1 / 256.0)
    keep = (f >= 1.0) & (f <= 40.0)
    velocity = np.fft.irfft(
        np.where(keep[:, None], spectrum / (2j * np.pi * np.where(keep, f, 1.0))[:, None], 0),
        acc.shape[0],
        axis=0,
    )
    estimate = 0.5 * 0.525 / np.abs(velocity).max()
    assert factor == pytest.approx(estimate, rel=0.35)
    np.testing.assert_allclose(desired.data, physical.data * factor, rtol=1e-9, atol=1e-12)
