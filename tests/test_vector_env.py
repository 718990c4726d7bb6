"""The batched vector env (vrig.envs.DriveIterationVectorEnv) against gymnasium's own vector envs.

Independent truth: gymnasium's SyncVectorEnv and AsyncVectorEnv over ``gymnasium.make`` of the
same id (each sub-env plays its own rig runs, one after another or in its own process). The
batched env must give the same observations, rewards, terminations, truncations and infos bit
for bit, through autoresets and TimeLimit truncations.
"""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import vrig  # noqa: F401  (registers the environments)
from vrig.envs import ENV_IDS, DriveIterationEnv, DriveIterationVectorEnv

ID = next(i for i, kw in ENV_IDS.items() if kw.get("rig") == "shock-absorber")
# short fast episodes; a tolerance out of reach so that TimeLimit truncates (budget 3)
KW = {"fast": True, "seconds": 2.0, "tolerance": 1e-6, "max_episode_steps": 3}


def _play(mode, n=3, steps=8, seed=11, mask_at=None):
    kw = {} if mode is None else {"vectorization_mode": mode}
    env = gym.make_vec(ID, num_envs=n, **kw, **KW)
    try:
        kind = type(env).__name__
        obs, info = env.reset(seed=seed)
        trace = [(obs, info)]
        rng = np.random.default_rng(0)
        for k in range(steps):
            if k == mask_at:
                mask = np.zeros(n, bool)
                mask[1] = True
                trace.append(env.reset(options={"reset_mask": mask}))
            action = rng.uniform(0.3, 1.3, size=env.action_space.shape)
            trace.append(env.step(action))
    finally:
        env.close()
    return kind, trace


def _assert_same(a, b):
    assert len(a) == len(b)
    for x, y in zip(a, b, strict=True):
        if isinstance(x, dict):
            assert sorted(x) == sorted(y)
            for key in x:
                _assert_same_leaf(x[key], y[key], key)
        elif isinstance(x, tuple):
            _assert_same(x, y)
        else:
            _assert_same_leaf(x, y, "")


def _assert_same_leaf(x, y, key):
    if isinstance(x, dict):
        _assert_same([x], [y])
        return
    x, y = np.asarray(x), np.asarray(y)
    assert x.shape == y.shape, key
    if x.dtype.kind in "fc":
        np.testing.assert_array_equal(x, y, err_msg=key)
    else:
        assert x.tolist() == y.tolist(), key


def test_make_vec_builds_the_batched_env_sharing_one_rig():
    env = gym.make_vec(ID, num_envs=2, **KW)
    try:
        assert isinstance(env.unwrapped, DriveIterationVectorEnv)
        physics = [e.unwrapped.physics for e in env.unwrapped.envs]
        assert physics[0] is physics[1]
    finally:
        env.close()


def test_batched_equals_sync_and_async_through_autoresets_and_truncations():
    kind, batched = _play(None)
    assert kind == "DriveIterationVectorEnv"
    _, sync = _play("sync")
    _, asyn = _play("async")
    # the run went through TimeLimit truncations and autoresets (budget 3, 8 steps)
    truncs = np.array([step[3] for step in batched[1:]])
    assert truncs.any(axis=0).all()
    _assert_same(batched, sync)
    _assert_same(batched, asyn)


def test_partial_reset_mask_equals_sync():
    _, batched = _play(None, n=2, steps=4, mask_at=2)
    _, sync = _play("sync", n=2, steps=4, mask_at=2)
    _assert_same(batched, sync)


def test_a_bad_action_raises_and_ends_every_episode():
    env = DriveIterationVectorEnv(2, "shock-absorber", fast=True, seconds=2.0, max_episode_steps=3)
    try:
        env.reset(seed=0)
        bad = np.ones((2, env.single_action_space.shape[0]))
        bad[1, 0] = np.nan
        with pytest.raises(ValueError, match="finite"):
            env.step(bad)
        with pytest.raises(RuntimeError, match="reset"):
            env.step(np.ones((2, env.single_action_space.shape[0])))
        env.reset(seed=1)  # and a reset starts over
        env.step(np.ones((2, env.single_action_space.shape[0])))
    finally:
        env.close()


def test_shared_physics_refuses_its_own_options():
    env = DriveIterationEnv("shock-absorber", fast=True, seconds=2.0)
    with pytest.raises(ValueError, match="fidelity"):
        DriveIterationEnv(env.physics, fidelity="full")
    with pytest.raises(ValueError, match="model_seed"):
        DriveIterationEnv(env.physics, model_seed=3)
    shared = DriveIterationEnv(env.physics, n_bands=2)
    assert shared.physics is env.physics
    assert shared.action_space.shape == (2,)
