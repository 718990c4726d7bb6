"""The Rig interface: loading, channels, interlocks, bad drives, determinism, TimeHistory."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

import vrig
from identification import band_limited_noise

TEST_RIG = Path(__file__).parent / "data" / "servo_mass.xml"


@pytest.fixture(scope="module")
def rig():
    return vrig.load_rig(TEST_RIG)


def _drive(rig, seconds=1.0, rms=0.002, seed=0, cutoff_hz=20.0):
    n = int(seconds * rig.fs)
    return rms * band_limited_noise(n, len(rig.inputs), cutoff=cutoff_hz / (rig.fs / 2), seed=seed)


def test_user_rig_loads_from_its_mjcf_path(rig):
    assert rig.name == "servo_mass"
    assert [c.name for c in rig.inputs] == ["table_disp"]
    assert [(c.name, c.unit) for c in rig.outputs] == [("table_lvdt", "m"), ("mass_acc", "m/s^2")]
    assert rig.fs == 1000
    assert rig.inputs[0].limits["velocity"] == pytest.approx(6.3e-4 / 1.2e-3)
    text = rig.describe()
    assert "table_disp" in text and "interlocks" in text


def test_run_returns_a_time_history_with_units(rig):
    out = rig.run(_drive(rig), seed=1)
    assert isinstance(out, vrig.TimeHistory)
    assert out.fs == rig.fs and out.n_samples == rig.fs
    assert out.names == ("table_lvdt", "mass_acc") and out.units == ("m", "m/s^2")
    assert np.all(np.isfinite(out.data))


def test_same_seed_is_bit_identical_and_seeds_differ_only_by_noise(rig):
    d = _drive(rig, seconds=1.0)
    a = rig.run(d, seed=5).data
    b = rig.run(d, seed=5).data
    c = rig.run(d, seed=6).data
    assert np.array_equal(a, b)
    assert not np.array_equal(a, c)
    # the LVDT is noise-free in this rig and there is no valve noise: only the accelerometer's
    # transducer noise may differ, and by about its documented level (0.01 m/s^2 rms)
    assert np.array_equal(a[:, 0], c[:, 0])
    diff = a[:, 1] - c[:, 1]
    assert 0.5 * np.sqrt(2) * 0.01 < diff.std() < 2.0 * np.sqrt(2) * 0.01


def test_a_fresh_rig_with_the_same_seed_repeats_its_run_sequence():
    d = _drive(vrig.load_rig(TEST_RIG))
    r1 = vrig.load_rig(TEST_RIG, seed=3)
    r2 = vrig.load_rig(TEST_RIG, seed=3)
    assert np.array_equal(r1.run(d).data, r2.run(d).data)
    assert np.array_equal(r1.run(d).data, r2.run(d).data)


def test_drive_beyond_full_scale_is_never_sent(rig):
    d = _drive(rig)
    d[300, 0] = 0.08
    with pytest.raises(vrig.RigLimitError, match="before the drive was sent") as err:
        rig.run(d)
    assert err.value.kind == "drive" and err.value.channel == "table_disp"
    assert err.value.value == pytest.approx(0.08)


def test_stroke_interlock():
    r = vrig.load_rig(TEST_RIG, stroke=0.02)
    t = np.arange(2000) / r.fs
    with pytest.raises(vrig.RigLimitError, match="stroke limit on channel 'table_disp'") as err:
        r.run(0.03 * np.sin(2 * np.pi * 0.5 * t))
    assert err.value.kind == "stroke"
    assert abs(err.value.value) > 0.02
    # the trip time is where the commanded position first passes the stroke (within servo lag)
    assert err.value.time == pytest.approx(np.arcsin(0.02 / 0.03) / (2 * np.pi * 0.5), abs=0.02)


def test_force_interlock():
    r = vrig.load_rig(TEST_RIG, force_limit=500.0)
    t = np.arange(1000) / r.fs
    with pytest.raises(vrig.RigLimitError, match="force limit") as err:
        r.run(0.004 * np.sin(2 * np.pi * 15 * t))  # ~25 kg at 35 m/s^2: ~900 N
    assert err.value.kind == "force" and err.value.unit == "N"


def test_transducer_range_interlock(tmp_path):
    desc = json.loads(TEST_RIG.with_suffix(".rig.json").read_text())
    desc["outputs"][1]["full_scale"] = 5.0  # an accelerometer with a 5 m/s^2 range
    desc["mjcf"] = str(TEST_RIG)
    path = tmp_path / "small_range.rig.json"
    path.write_text(json.dumps(desc))
    r = vrig.load_rig(path)
    t = np.arange(1000) / r.fs
    with pytest.raises(vrig.RigLimitError, match="transducer range limit on channel 'mass_acc'"):
        r.run(0.004 * np.sin(2 * np.pi * 15 * t))


def test_bad_drives_are_rejected_with_actionable_messages(rig):
    with pytest.raises(ValueError, match=r"shape \(N, 1\)"):
        rig.run(np.zeros((100, 2)))
    with pytest.raises(ValueError, match="NaN"):
        rig.run(np.array([0.0, np.nan, 0.0]))
    with pytest.raises(ValueError, match=r"sampled at 500 Hz .* fs = 1000 Hz"):
        rig.run(vrig.TimeHistory(np.zeros(100), fs=500.0))
    with pytest.raises(ValueError, match="do not match the rig's drives"):
        rig.run(vrig.TimeHistory(np.zeros(100), fs=1000.0, names=["force"]))
    with pytest.raises(ValueError, match="at least 2 samples"):
        rig.run(np.zeros((1, 1)))


def test_time_history_drive_with_matching_names_is_accepted(rig):
    d = vrig.TimeHistory(_drive(rig, seconds=0.5), fs=rig.fs, names=["table_disp"], units=["m"])
    assert rig.run(d, seed=0).n_samples == d.n_samples


def test_unknown_parameters_and_rigs_are_rejected():
    with pytest.raises(ValueError, match="unknown parameter"):
        vrig.load_rig(TEST_RIG, stiffness=3)
    with pytest.raises(ValueError, match="unknown rig 'bogus'"):
        vrig.load_rig("bogus")
    with pytest.raises(vrig.RigModelError, match="side-car"):
        vrig.load_rig(Path(__file__).parent / "no_such_rig.xml")


def test_list_rigs_names_the_shipped_models():
    assert "shock-absorber" in vrig.list_rigs()


def test_time_history_basics(tmp_path):
    th = vrig.TimeHistory(
        np.arange(20.0).reshape(10, 2), fs=100.0, names=["x", "F"], units=["m", "N"]
    )
    assert th.duration == pytest.approx(0.1)
    assert th["F"].names == ("F",) and th["F"].units == ("N",)
    np.testing.assert_array_equal(th.channel("x"), np.arange(0, 20, 2.0))
    assert th.window(0.02, 0.05).n_samples == 3
    back = vrig.TimeHistory.load(th.save(tmp_path / "th"))
    assert np.array_equal(back.data, th.data) and back.names == th.names and back.fs == th.fs
    with pytest.raises(ValueError, match="NaN"):
        vrig.TimeHistory([1.0, np.nan], fs=10)
    with pytest.raises(ValueError, match="positive sample rate"):
        vrig.TimeHistory([1.0, 2.0], fs=0)
    with pytest.raises(KeyError, match="no channel 'y'"):
        th["y"]
    with pytest.raises(ValueError, match="unique"):
        vrig.TimeHistory(np.zeros((3, 2)), fs=1, names=["a", "a"])


def test_a_mujoco_instability_is_an_error_not_nan():
    # a 1e14 N/m spring at a 10 ms timestep: explicit-in-position integration blows up
    r = vrig.load_rig(Path(__file__).parent / "data" / "unstable.xml")
    with pytest.raises(vrig.SimulationInstabilityError, match="mjWARN_BADQACC"):
        r.run(0.001 * np.sin(np.arange(200) / 5))


def test_a_non_finite_drive_is_refused_before_it_is_sent():
    from vrig.rigs import ChannelSpec
    from vrig.rigs.limits import check_drive_limits

    chans = [ChannelSpec("u", "m", 1.0, "hydraulic")]
    drive = np.zeros((10, 1))
    check_drive_limits(chans, drive)  # within limits: no error
    drive[4, 0] = np.nan
    with pytest.raises(vrig.RigLimitError, match="not finite"):
        check_drive_limits(chans, drive, fs=100.0, what="IT00DRV")
