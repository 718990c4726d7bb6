"""One frozen settings object for a drive iteration, shared by reconstruct, the engine, the
gymnasium environment and the benchmark runner; separate identification and run seeds (issue 14,
deliverable 2).

The seeds are checked on a noisy linear test rig that records the seed of every run it is asked
for: the identification run must use ``id_seed``, iteration ``n`` must use ``run_seed + 1 + n``
(the documented rule), whatever the other seed is.
"""

from __future__ import annotations

import dataclasses
import gc

import numpy as np
import pytest
from scipy import signal

import vrig
from vrig.reconstruction import DriveIteration, IterationSettings
from vrig.rigs import ChannelSpec
from vrig.signals import random_drive, triangular_psd


class _SeedRecordingRig:
    """One drive, one response: a first-order low-pass of the drive plus seeded white noise."""

    name = "seed-recorder"
    fs = 200.0
    bandwidth = (0.0, 20.0)

    def __init__(self):
        self.inputs = (ChannelSpec("u", "m", 1.0, "direct"),)
        self.outputs = (ChannelSpec("y", "N", 100.0, "load_cell"),)
        self.seeds: list = []

    def run(self, drive, *, seed=None):
        self.seeds.append(seed)
        u = np.asarray(getattr(drive, "data", drive), float)[:, 0]
        y = signal.lfilter([0.2], [1.0, -0.8], u)
        y = y + 1e-4 * np.random.default_rng(seed).standard_normal(y.size)
        return vrig.TimeHistory(y[:, None], self.fs, ["y"], ["N"])


def _desired(rig, seconds=10.0):
    d = random_drive(
        triangular_psd((0.0, 15.0)), int(seconds * rig.fs), rig.fs, rms=0.05, seed=11, names=["u"]
    )
    return _SeedRecordingRig().run(d, seed=99)


def test_settings_are_frozen_all_the_way_down():
    s = IterationSettings(method="arx", method_options={"order": 4}, gain=[0.5, 0.6])
    with pytest.raises(dataclasses.FrozenInstanceError):
        s.gain = 0.3
    with pytest.raises(TypeError):
        s.method_options["order"] = 6  # read-only mapping
    assert s.gain == (0.5, 0.6)  # a list is stored as a tuple
    assert hash(s.identification_key()) == hash(s.identification_key())


@pytest.mark.parametrize(
    ("field", "value", "match"),
    [
        ("iterations", 100, "iterations"),
        ("iterations", True, "iterations"),
        ("gain", 0.0, "gain"),
        ("gain", 2.5, "gain"),
        ("strategy", "clever", "strategy"),
        ("divergence", 0.5, "divergence"),
        ("min_increase", -1.0, "min_increase"),
        ("decimation", 0, "decimation"),
        ("taper", -0.1, "taper"),
        ("id_duration", 0.0, "id_duration"),
        ("id_seed", -1, "id_seed"),
        ("run_seed", 1.5, "run_seed"),
    ],
)
def test_bad_settings_are_refused_when_made_and_when_replaced(field, value, match):
    with pytest.raises(ValueError, match=match):
        IterationSettings(**{field: value})
    with pytest.raises(ValueError, match=match):
        IterationSettings().replace(**{field: value})


def test_build_maps_seed_to_both_seeds_and_other_names_to_method_options():
    base = IterationSettings(method="narx", method_options={"degree": 2})
    s = IterationSettings.build(base, seed=5, gain=0.5, order=4)
    assert (s.id_seed, s.run_seed, s.rig_run_seed) == (5, 5, 5)
    assert s.gain == 0.5 and s.method == "narx"
    assert dict(s.method_options) == {"degree": 2, "order": 4}
    assert IterationSettings(id_seed=3).rig_run_seed == 3  # run seed defaults to the id seed
    with pytest.raises(TypeError, match="IterationSettings"):
        IterationSettings.build({"gain": 0.5})


def test_identification_uses_id_seed_and_iteration_n_uses_run_seed_plus_1_plus_n():
    rig = _SeedRecordingRig()
    res = vrig.reconstruct(
        rig, _desired(rig), method="arx", order=2, iterations=2, id_seed=7, run_seed=40
    )
    assert len(res.errors) == 3
    assert rig.seeds == [7, 41, 42, 43]
    assert res.settings.id_seed == 7 and res.settings.run_seed == 40 and res.seed == 7


def test_the_identified_model_depends_on_the_id_seed_only():
    rig_a, rig_b = _SeedRecordingRig(), _SeedRecordingRig()
    desired = _desired(rig_a)
    a = vrig.reconstruct(rig_a, desired, method="arx", order=2, iterations=0, seed=7)
    b = vrig.reconstruct(
        rig_b, desired, method="arx", order=2, iterations=0, id_seed=7, run_seed=1000
    )
    np.testing.assert_array_equal(a.id_drive.data, b.id_drive.data)
    np.testing.assert_array_equal(a.drives[0].data, b.drives[0].data)  # same model, same IT00DRV
    assert not np.array_equal(a.raw_responses[0].data, b.raw_responses[0].data)  # other noise


def test_a_settings_object_and_keywords_give_the_same_reconstruction():
    s = IterationSettings(method="arx", method_options={"order": 2}, iterations=1, gain=0.6)
    rig1, rig2 = _SeedRecordingRig(), _SeedRecordingRig()
    desired = _desired(rig1)
    r1 = vrig.reconstruct(rig1, desired, s)
    r2 = vrig.reconstruct(rig2, desired, method="arx", order=2, iterations=1, gain=0.6)
    np.testing.assert_array_equal(r1.errors, r2.errors)
    # the result keeps the settings with every default resolved: the given ones as given
    assert r1.settings == r2.settings == s.replace(bandwidth=rig1.bandwidth, id_rms=r1.settings.id_rms)
    assert r1.settings.id_rms == tuple(0.05 * c.full_scale for c in rig1.inputs)  # the built-in
    r3 = vrig.reconstruct(_SeedRecordingRig(), desired, s, iterations=0)  # keyword over object
    assert len(r3.errors) == 1 and r3.settings.iterations == 0


def test_the_engine_takes_the_same_settings_object():
    rig = _SeedRecordingRig()
    s = IterationSettings(method="arx", method_options={"order": 2}, taper=1.0, id_seed=2)
    engine = DriveIteration(rig, _desired(rig), s)
    engine.identify()
    drive = engine.first_drive()[:, 0]
    m = int(1.0 * rig.fs)
    # the 1 s raised-cosine taper: the drive grows from rest no faster than the ramp allows
    ramp = 0.5 - 0.5 * np.cos(np.pi * np.arange(m) / m)
    assert np.all(np.abs(drive[:m]) <= ramp * np.abs(drive).max() + 1e-15)
    # the engine keeps the given settings with the defaults resolved (nothing given changed)
    assert engine.settings == vrig.reconstruction.defaults.resolve(rig, s).settings
    assert engine.settings.replace(gain=None, bandwidth=None, id_rms=None) == s
    assert rig.seeds == [2]


def test_env_takes_taper_and_id_psd_from_settings_and_keeps_its_run_seed():
    from vrig.envs import DriveIterationEnv, clear_model_cache
    from vrig.signals import flat_psd

    clear_model_cache()
    rig = _SeedRecordingRig()
    psd = flat_psd((0.0, 24.0))
    s = IterationSettings(method="arx", method_options={"order": 2}, taper=0.75, id_psd=psd)
    env = DriveIterationEnv(rig, settings=s, seconds=6.0, model_seed=3)
    _obs, info = env.reset(seed=0, options={"desired": _desired(rig, 6.0), "run_seed": 20})
    engine = env.engine
    assert engine.settings.taper == 0.75 and engine.settings.id_psd is psd
    assert (engine.settings.id_seed, engine.settings.run_seed) == (3, 20) == (3, info["run_seed"])
    # the identification drive is the one the settings' PSD makes (flat, not the default
    # triangular one): the same record as an engine given the same settings identifies with
    ref_rig = _SeedRecordingRig()
    ref = DriveIteration(ref_rig, _desired(rig, 6.0), env.physics.settings.replace(run_seed=20))
    ref.identify()
    np.testing.assert_array_equal(engine.id_drive.data, ref.id_drive.data)
    assert rig.seeds == [3, 21]  # identification with id_seed, IT00 with run_seed + 1
    env.step(env.action_space.sample() * 0 + 0.5)
    assert rig.seeds[-1] == 22


def test_model_cache_never_confuses_two_rig_objects():
    """The cache key of an object rig holds the object: a later rig cannot get its id (and with
    it the first rig's identified model)."""
    from vrig.envs import IterationPhysics

    first = _SeedRecordingRig()
    key = IterationPhysics(first, seconds=6.0)._key
    del first
    gc.collect()
    keys = {IterationPhysics(_SeedRecordingRig(), seconds=6.0)._key for _ in range(20)}
    assert key not in keys
