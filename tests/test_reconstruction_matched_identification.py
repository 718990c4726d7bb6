"""Identification matched to the target (IterationSettings(id_match=True), issue 22 deliverable 5).

Truth: the target's own statistics (RMS, peak, half-energy amplitude), the PSD of the drive that
made the target (a linear test rig whose dynamics are a known filter), the rig's limits.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from scipy import signal

import vrig
from vrig.reconstruction import DriveIteration, IterationSettings, reconstruct
from vrig.reconstruction.matching import PEAK_MARGIN, half_energy_amplitude
from vrig.signals import random_drive, triangular_psd
from vrig.spectra import psd_function

FS = 200.0


class _LinearRig:
    """One displacement drive (full scale 1 m), one load response: a resonant low-pass filter
    (8 Hz, gain 1000 N/m at DC); trips (as a force interlock) when the drive's magnitude exceeds
    ``trip`` m. Records every drive it plays."""

    name = "linear"
    fs = FS
    bandwidth = (0.0, 20.0)

    def __init__(self, trip: float = np.inf):
        from vrig.rigs import ChannelSpec

        self.inputs = (ChannelSpec("u", "m", 1.0, "direct"),)
        self.outputs = (ChannelSpec("y", "N", 1e5, "load_cell"),)
        self.sos = signal.butter(2, 8.0, fs=FS, output="sos")
        self.trip, self.played = trip, []

    def run(self, drive, *, seed=None):
        u = np.asarray(getattr(drive, "data", drive), float)
        self.played.append(u.copy())
        over = np.abs(u[:, 0]) > self.trip
        if over.any():
            i = int(np.argmax(over))
            raise vrig.RigLimitError("force", "u", i / FS, u[i, 0], self.trip, "m")
        y = 1000.0 * signal.sosfilt(self.sos, u[:, 0])
        return vrig.TimeHistory(y[:, None], FS, ["y"], ["N"])


def _drive_psd(f):
    """A drive PSD unlike the default triangle: a bump at 4 Hz on a low shelf, up to 15 Hz."""
    return (np.exp(-(((f - 4.0) / 2.0) ** 2)) + 0.1) * (f <= 15.0)


def _target(rig, rms: float, seconds: float = 20.0, seed: int = 21):
    """The rig's response to a drive of PSD :func:`_drive_psd` at ``rms`` m, and the drive."""
    f = np.linspace(0, FS / 2, 801)
    drive = random_drive(psd_function(f, _drive_psd(f)), round(seconds * FS), FS, rms=rms,
                         seed=seed, names=["u"], unit="m")  # fmt: skip
    return rig.run(drive), drive


def _ratios(report):
    return np.array([report[k][0] for k in ("rms_ratio", "peak_ratio", "half_energy_ratio")])


def test_the_matched_drive_reaches_the_targets_level_with_the_targets_spectrum():
    rig = _LinearRig()
    target, _ = _target(rig, rms=0.2)  # 20 % of full scale: four times the default level
    default = DriveIteration(rig, target, method="arx", order=4, seed=0)
    default.identify()
    assert np.all(_ratios(default.id_report) < 0.3)  # 5 % against 30 %: far below
    assert default.id_report["mode"] == "default" and default.id_matching is None
    matched = DriveIteration(rig, target, method="arx", order=4, seed=0, id_match=True)
    matched.identify()
    r = _ratios(matched.id_report)
    assert np.all((r >= 0.85) & (r <= 1.3)), r
    assert "reached" in matched.id_report["reason"]
    # the identification drive's spectrum is the target drive's (normalised; 2 Hz bins in 1-13 Hz,
    # clear of the target drive's 15 Hz edge, which Welch leakage and the smoothing round off)
    f, p = signal.welch(matched.id_drive.data[:, 0], fs=FS, nperseg=400)
    truth = _drive_psd(f)
    for lo in np.arange(1.0, 12.0, 2.0):
        s = (f >= lo) & (f < lo + 2)
        assert p[s].sum() / p.sum() == pytest.approx(truth[s].sum() / truth.sum(), rel=0.15)
    rec = matched.id_matching
    assert rec.probe_drive.n_samples == 5 * 800  # five 4 s Welch segments at 200 Hz
    probe_rms = np.sqrt(np.mean(rec.probe_drive.data**2))
    np.testing.assert_allclose(probe_rms, 0.05, rtol=1e-9)  # the default level, 5 % of 1 m
    assert len(rec.plays) == 1 and rec.kept == 0  # a linear rig: the FRF's level is the level


def test_a_matched_identification_is_reproducible_and_keyed():
    rig = _LinearRig()
    target, _ = _target(rig, rms=0.2)
    a = DriveIteration(rig, target, method="arx", order=4, seed=3, id_match=True)
    b = DriveIteration(rig, target, method="arx", order=4, seed=3, id_match=True)
    a.identify()
    b.identify()
    np.testing.assert_array_equal(a.id_drive.data, b.id_drive.data)
    np.testing.assert_array_equal(a.target, b.target)
    s = IterationSettings()
    assert s.identification_key() != s.replace(id_match=True).identification_key()


def test_a_level_that_trips_is_halved_and_never_exceeded_again():
    target, _ = _target(_LinearRig(), rms=0.15)  # needs drive peaks of ~0.6 m
    rig = _LinearRig(trip=0.4)  # ... on a rig that trips at 0.4 m
    engine = DriveIteration(rig, target, method="arx", order=4, seed=0, id_match=True)
    engine.identify()
    plays = engine.id_matching.plays
    tripped = [i for i, p in enumerate(plays) if "tripped" in p]
    assert tripped, plays
    first = tripped[0]
    after = [p["peak_percent"][0] for p in plays[first + 1 :]]
    assert after and max(after) <= plays[first]["peak_percent"][0] / 2 * (1 + 1e-9)
    assert np.abs(engine.id_drive.data).max() <= 0.4
    reason = engine.id_report["reason"]
    assert "halved after an interlock trip" in reason and "half the level that tripped" in reason


def test_a_target_beyond_full_scale_is_held_at_full_scale_and_said_so():
    rig = _LinearRig()
    big, _ = _target(rig, rms=0.3)
    target = big.with_data(3.0 * big.data)  # needs ~0.9 m RMS, peaks far beyond the 1 m
    rig.played.clear()  # the drives of the identification only
    engine = DriveIteration(rig, target, method="arx", order=4, seed=0, id_match=True)
    engine.identify()
    played = np.array([np.abs(u).max() for u in rig.played])
    assert played.max() <= PEAK_MARGIN * 1.0 * (1 + 1e-9)  # nothing beyond 95 % of full scale
    reason = engine.id_report["reason"]
    assert "held at the drives' full scale" in reason
    needed = float(reason.split("needs about ")[1].split(" %")[0])
    assert needed > 100  # the target's peak needs more than the full scale


def test_the_summary_records_the_identification(tmp_path):
    rig = _LinearRig()
    target, _ = _target(rig, rms=0.2)
    res = reconstruct(rig, target, method="arx", order=4, iterations=0, seed=0, id_match=True)
    assert res.identification["mode"] == "matched"
    vrig.TestFolder(tmp_path / "t").save(res, rig=rig)
    summary = json.loads((tmp_path / "t" / "summary.json").read_text())
    ident = summary["identification"]
    assert ident["mode"] == "matched" and ident["plays"] and ident["reason"]
    assert ident["probe"]["seconds"] == 20.0
    default = reconstruct(rig, target, method="arx", order=4, iterations=0, seed=0)
    assert default.identification["mode"] == "default"
    assert default.identification["rms_percent"] == [5.0]


def test_the_elastomeric_damper_is_identified_at_a_three_times_larger_targets_level():
    """A pseudo-field-like damper response (4 % of full scale, triangular drive) scaled x3."""
    rig = vrig.load_rig("elastomeric-damper", fidelity="fast")
    full = rig.inputs[0].full_scale
    d = random_drive(triangular_psd((0.0, 25.0)), round(20 * rig.fs), rig.fs, rms=0.04 * full,
                     seed=5, names=[rig.inputs[0].name], unit="m")  # fmt: skip
    raw = rig.run(d, seed=7)
    target = raw.with_data(3.0 * raw.data)
    default = DriveIteration(rig, target, method="arx", order=4, seed=0)
    default.identify()
    assert np.all(_ratios(default.id_report) < 0.5)
    matched = DriveIteration(rig, target, method="arx", order=4, seed=0, id_match=True)
    matched.identify()
    r = _ratios(matched.id_report)
    assert np.all((r >= 0.85) & (r <= 1.5)), r


def test_half_energy_amplitude_of_a_gaussian_record_and_of_events():
    x = np.random.default_rng(5).standard_normal((400_000, 1))
    # energy-weighted |x| of a Gaussian is chi-distributed with 3 degrees of freedom
    from scipy import stats

    assert half_energy_amplitude(x)[0] == pytest.approx(stats.chi(3).median(), rel=0.01)
    events = np.zeros((1000, 1))
    events[100:200] = 5.0  # all the energy in one event of amplitude 5
    events[500:] = 0.1
    assert half_energy_amplitude(events)[0] == 5.0


@pytest.mark.parametrize(
    "options,match",
    [
        ({"id_match": "yes"}, "id_match must be True or False"),
        ({"id_match": True, "id_psd": triangular_psd((0, 10))}, "not both"),
    ],
)
def test_bad_settings(options, match):
    with pytest.raises(ValueError, match=match):
        IterationSettings(**options)


def test_the_env_physics_identifies_a_matched_model_per_target():
    """Model caches key on the target when the identification is matched to it."""
    from vrig.envs.physics import IterationPhysics, clear_model_cache

    clear_model_cache()
    rig = _LinearRig()
    small, _ = _target(rig, rms=0.05, seed=1)
    large, _ = _target(rig, rms=0.2, seed=2)
    physics = IterationPhysics(rig, method="arx", order=4, id_match=True, seconds=20.0)
    a = physics.start(small, run_seed=0)
    b = physics.start(large, run_seed=0)
    again = physics.start(small, run_seed=1)
    level = [np.sqrt(np.mean(e.id_drive.data**2)) for e in (a, b)]
    assert level[1] > 2.5 * level[0]  # each target got its own identification level
    assert again.id_drive is a.id_drive  # the same target: the cached model
    clear_model_cache()


def test_the_cli_identifies_matched_to_the_target(tmp_path, capsys):
    from vrig.cli import main

    out = tmp_path / "r"
    code = main(["reconstruct", "--rig", "elastomeric-damper", "--iterations", "0",
                 "--seconds", "10", "--id-match", "--out", str(out)])  # fmt: skip
    assert code == 0
    assert "identification matched: " in capsys.readouterr().out
    summary = json.loads((out / "summary.json").read_text())
    assert summary["identification"]["mode"] == "matched"
    assert summary["identification"]["probe"]["seconds"] > 0
