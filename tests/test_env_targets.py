"""The target of the drive-iteration envs (issue 22, deliverable 6): ``target="pseudo-field"``
(default, unchanged), ``"field:<scenario>"`` and ``"field"``, made by
:func:`vrig.desired.kinds.desired_response` with each reset's seed.

The routing is tested with a stand-in for ``desired_response``, the real service records with
``vrig.roads``.
"""

from __future__ import annotations

import warnings

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import vrig
from vrig.envs import DriveIterationEnv, DriveIterationVectorEnv, IterationPhysics
from vrig.timehistory import TimeHistory

KW = {"fast": True, "seconds": 2.0}


@pytest.fixture
def fake_field(monkeypatch):
    """``desired_responses`` of the physics replaced: a field target gives half the
    pseudo-field record of the same seed (reachable, and known); every seed is logged."""
    from vrig.desired import kinds
    from vrig.envs import physics

    real, calls = kinds.desired_response, []

    def fake(rig, target, seconds, *, seed=0, band=None):
        calls.append((rig, target, seconds, seed))
        field, source, extra = real(rig, "pseudo-field", seconds, seed=seed, band=band)
        if target == "pseudo-field":
            return field, source, extra
        half = TimeHistory(0.5 * field.data, field.fs, field.names, field.units)
        return half, f"stand-in for {target}", {}

    def fake_batch(rig, target, seconds, seeds, *, band=None, threads=None, twin=None):
        return [fake(rig, target, seconds, seed=s, band=band) for s in seeds]

    monkeypatch.setattr(physics, "desired_responses", fake_batch)
    return calls


def test_the_default_target_is_the_pseudo_field_record_of_the_drawn_seed_bit_for_bit():
    """The default env's desired response is ``vrig.pseudo_field`` of the drawn seed over the
    rig's band (what the envs drew before the target option), and its IT00 observation is that
    of the same record passed explicitly."""
    env = gym.make("vrig/ShockAbsorber-v2", **KW)
    named = gym.make("vrig/ShockAbsorber-v2", target="pseudo-field", **KW)
    obs, info = env.reset(seed=3)
    obs_named, info_named = named.reset(seed=3)
    ph = env.unwrapped.physics
    assert ph.target == "pseudo-field"
    _drive, truth = vrig.pseudo_field(ph.rig, ph.band, 2.0, seed=info["field_seed"])
    np.testing.assert_array_equal(env.unwrapped.desired.data, truth.data)
    explicit = gym.make("vrig/ShockAbsorber-v2", **KW)
    obs_explicit, _ = explicit.reset(seed=3, options={"desired": truth, "run_seed": info["run_seed"]})
    for key in obs:
        np.testing.assert_array_equal(obs[key], obs_explicit[key], err_msg=key)
        np.testing.assert_array_equal(obs[key], obs_named[key], err_msg=key)
    assert info_named["field_seed"] == info["field_seed"]
    np.testing.assert_array_equal(ph.pseudo_field(info["field_seed"]).data, truth.data)
    for e in (env, named, explicit):
        e.close()


def test_an_unknown_scenario_or_target_is_a_value_error_at_make_time():
    with pytest.raises(ValueError, match=r"no service scenario 'nope'.*rough-road"):
        gym.make("vrig/ShockAbsorber-v2", target="field:nope", **KW)
    with pytest.raises(ValueError, match="no service scenario"):
        DriveIterationEnv("shaker", target="field", **KW)  # the shaker has none
    with pytest.raises(ValueError, match="unknown target 'road'"):
        DriveIterationEnv("shock-absorber", target="road", **KW)
    with pytest.raises(TypeError, match="target must be a string"):
        IterationPhysics("shock-absorber", seconds=2.0, fidelity="fast", target=1)


def test_a_target_with_a_desired_set_or_next_to_a_shared_physics_is_refused():
    env = DriveIterationEnv("shock-absorber", **KW)
    with pytest.raises(ValueError, match="not both"):
        DriveIterationEnv("shock-absorber", target="field", desired=[env.physics.pseudo_field(0)])
    with pytest.raises(ValueError, match="target"):
        DriveIterationEnv(env.physics, target="field")


def test_a_field_target_draws_each_reset_through_desired_response_with_its_seed(fake_field):
    env = DriveIterationEnv("shock-absorber", target="field", **KW)
    ph = env.physics
    assert ph.target == "field:rough-road"  # "field" alone: the rig's first scenario
    seeds = []
    for seed in (0, 1):
        _obs, info = env.reset(seed=seed)
        seeds.append(info["field_seed"])
        assert fake_field[-1] == (ph.rig, "field:rough-road", 2.0, info["field_seed"])
        half = 0.5 * ph.pseudo_field(info["field_seed"]).data
        np.testing.assert_array_equal(env.desired.data, half)
        obs, _r, _term, trunc, _info = env.step(np.full(env.action_space.shape, 0.8))
        assert env.observation_space.contains(obs) and not trunc
    assert seeds[0] != seeds[1]  # a new record per reset
    n = len(fake_field)
    env.reset(seed=0)
    assert len(fake_field) == n  # the record of a seed is kept


def test_the_checker_passes_on_a_field_target(fake_field):
    env = gym.make("vrig/ShockAbsorber-v2", target="field:rough-road", **KW)
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message=".*symmetric and normalized.*")
        check_env(env.unwrapped)
    assert any(c[1] == "field:rough-road" for c in fake_field)
    env.close()


def test_the_vector_env_shares_one_field_target(fake_field):
    env = DriveIterationVectorEnv(2, "shock-absorber", target="field", max_episode_steps=2, **KW)
    try:
        subs = [s.unwrapped for s in env._staged]
        assert subs[0].physics is subs[1].physics
        assert subs[0].physics.target == "field:rough-road"
        _obs, info = env.reset(seed=4)
        for sub, seed in zip(subs, info["field_seed"], strict=True):
            half = 0.5 * sub.physics.pseudo_field(seed).data
            np.testing.assert_array_equal(sub.desired.data, half)
    finally:
        env.close()
    with pytest.raises(ValueError, match="nope"):
        gym.make_vec("vrig/ShockAbsorber-v2", num_envs=2, target="field:nope", **KW)


def test_a_field_target_env_resets_on_a_service_record_and_steps():
    """The real service record: the env's desired response is ``field_record`` of the drawn
    road seed (4 s: the road fades in and out over 1 s each), and the env steps on it (the
    radiator in its truck front end: its IT00 drive stays inside the rig's limits)."""
    from vrig.service import field_record

    env = gym.make("vrig/Radiator-v2", target="field:truck-front", fast=True, seconds=4.0)
    env = env.unwrapped
    obs, info = env.reset(seed=0)
    truth = field_record(env.physics.rig, "truck-front", 4.0, seed=info["field_seed"])
    np.testing.assert_array_equal(env.desired.data, truth.data)
    assert env.observation_space.contains(obs)
    obs, reward, _term, _trunc, info = env.step(np.full(env.action_space.shape, 0.5))
    assert env.observation_space.contains(obs) and np.isfinite(reward)
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message=".*symmetric and normalized.*")
        check_env(env)
