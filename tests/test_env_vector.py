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

import vrig
from vrig.envs import ENV_IDS, DriveIterationEnv, DriveIterationVectorEnv, IterationPhysics
from vrig.reconstruction.defaults import default_band

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
        if isinstance(y, Exception):
            assert type(x) is type(y) and str(x) == str(y)
        elif isinstance(x, dict):
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


def test_partial_reset_mask_equals_sync(monkeypatch):
    import vrig.envs.vector as vector

    ahead, real = [], vector._Ahead  # the episodes now end apart: a step resets one sub-env
    monkeypatch.setattr(vector, "_Ahead", lambda *a: ahead.append(1) or real(*a))
    _, batched = _play(None, n=2, steps=4, mask_at=2)
    assert ahead  # ... and plays the other's drive beside the new target's runs
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


# ------------------------------------------------------------------ batched target records
# Independent truth: the serial functions (``vrig.pseudo_field``, ``field_record``) and
# gymnasium's SyncVectorEnv, whose sub-envs make their targets one after another. The pseudo-field
# level is raised (vrig.desired.pseudo_field._FIELD_FRACTION) so that targets trip while they are made and are
# made again at a lower level; and on the elastomeric damper, so that drawn targets trip at IT00
# and are redrawn (the env's FIELD_REDRAWS rule).


def _outcome(fn):
    try:
        return fn()
    except Exception as exc:  # the error is part of the result to compare
        return exc


def _same_outcome(got, truth):
    if isinstance(truth, Exception):
        assert type(got) is type(truth) and str(got) == str(truth)
        return
    for g, t in zip(got, truth, strict=True):
        assert g.names == t.names and g.units == t.units and g.fs == t.fs
        np.testing.assert_array_equal(g.data, t.data)


def test_pseudo_fields_equal_pseudo_field_seed_by_seed_through_tripped_levels(monkeypatch):
    import vrig.desired.pseudo_field as field

    monkeypatch.setattr(field, "_FIELD_FRACTION", 0.4)  # 40 %: too large for some seeds
    monkeypatch.setattr(field, "_FIELD_ATTEMPTS", 2)  # ... and then 20 %, the last level
    rig = vrig.load_rig("shock-absorber", fidelity="fast")
    twin = vrig.load_rig("shock-absorber", fidelity="fast")  # the serial truth's own rig
    band, seeds = default_band(rig), list(range(6))
    tried = []
    real = field._field_drive
    monkeypatch.setattr(field, "_field_drive", lambda *a: tried.append(a[3]) or real(*a))
    truth = [_outcome(lambda s=s: vrig.pseudo_field(twin, band, 2.0, seed=s)) for s in seeds]
    assert any(isinstance(t, vrig.RigLimitError) for t in truth)  # a seed trips at both levels
    assert any(not isinstance(t, Exception) for t in truth)  # another is made at 20 %
    assert tried.count(0.4) == len(seeds) and 0 < tried.count(0.2) <= len(seeds)
    for threads in (1, 2):
        got = field.pseudo_fields(rig, band, 2.0, seeds, threads=threads)
        for g, t in zip(got, truth, strict=True):
            _same_outcome(g, t)
    with pytest.raises(ValueError, match="seed"):
        field.pseudo_fields(rig, band, 2.0, [1, -1])


def test_a_lone_record_plays_its_check_ahead_and_equals_pseudo_field(monkeypatch):
    """One seed on two threads: each level's 1.5x check is played beside its run (the thread
    would idle); whatever the level's outcome, the record (or error) is pseudo_field's."""
    import vrig.desired.pseudo_field as field

    monkeypatch.setattr(field, "_FIELD_FRACTION", 0.4)  # as above: some seeds trip at 40 %
    monkeypatch.setattr(field, "_FIELD_ATTEMPTS", 2)
    rig = vrig.load_rig("shock-absorber", fidelity="fast")
    twin = vrig.load_rig("shock-absorber", fidelity="fast")
    band = default_band(rig)
    batches = []
    real = field._runs
    monkeypatch.setattr(field, "_runs", lambda r, d, *a: batches.append(len(d)) or real(r, d, *a))
    kinds = set()
    for seed in range(4):
        truth = _outcome(lambda s=seed: vrig.pseudo_field(twin, band, 2.0, seed=s))
        kinds.add(isinstance(truth, Exception))
        batches.clear()
        (got,) = field.pseudo_fields(rig, band, 2.0, [seed], threads=2)
        _same_outcome(got, truth)
        assert batches[0] == 2 and all(b == 0 for b in batches[1::2])  # never a late check
    assert kinds == {True, False}  # seeds that trip at both levels, and one made at 20 %
    assert field._spare_threads(rig, 1, 1) == 0 and field._spare_threads(rig, 3, 2) == 1
    assert field._spare_threads(rig, 8, 2) == 0 and field._spare_threads(rig, 1, 4) == 1


def test_field_records_equal_field_record_with_one_twin():
    from vrig.service import field_record, field_records

    rig = vrig.load_rig("shock-absorber", fidelity="fast")
    seeds = [0, 7, 7]
    got = field_records(rig, "rough-road", 3.0, seeds, threads=2, with_road=True)
    for seed, g in zip(seeds, got, strict=True):
        _same_outcome(g, field_record(rig, "rough-road", 3.0, seed=seed, with_road=True))
    with pytest.raises(ValueError, match="seed"):
        field_records(rig, "rough-road", 3.0, [True])


def _vector_play(mode, rig_id, n, seed, steps, **kw):
    """Reset with ``seed`` and step ``steps`` times with random gains: the trace, up to the
    first error (in its place)."""
    extra = {} if mode is None else {"vectorization_mode": mode}
    env = gym.make_vec(rig_id, num_envs=n, **extra, **kw)
    try:
        trace = [_outcome(lambda: env.reset(seed=seed))]
        if isinstance(trace[0], Exception):
            return trace
        rng = np.random.default_rng(1)
        for _ in range(steps):
            action = rng.uniform(0.5, 1.0, size=env.action_space.shape)
            trace.append(_outcome(lambda a=action: env.step(a)))
            if isinstance(trace[-1], Exception):  # a redrawn target tripped again: as serial
                break
    finally:
        env.close()
    return trace


def test_batched_target_records_equal_serial_resets_when_targets_trip(monkeypatch):
    """Elastomeric damper, pseudo-field level 20 %: sub-env 0's first drawn target trips at IT00
    and is redrawn, the others start on theirs; then autoresets (budget 2) make new targets in
    one batch. Every observation, reward and info equals the serial resets' bit for bit."""
    import vrig.desired.pseudo_field as field
    import vrig.envs.drive_iteration as di

    monkeypatch.setattr(field, "_FIELD_FRACTION", 0.2)
    damper = next(i for i, kw in ENV_IDS.items() if kw.get("rig") == "elastomeric-damper")
    kw = {"fast": True, "seconds": 2.0, "tolerance": 1e-6, "max_episode_steps": 2}
    redraws = []
    real = di.DriveIterationEnv._finish_reset

    def spy(self, pending, outcome):
        done = real(self, pending, outcome)
        redraws.append(done is None)
        return done

    monkeypatch.setattr(di.DriveIterationEnv, "_finish_reset", spy)
    sync = _vector_play("sync", damper, 3, 0, 4, **kw)
    assert any(redraws)  # the serial resets redrew a tripped target
    batches = []
    records = IterationPhysics.target_records

    def logged(self, seeds, **options):
        batches.append(len(seeds))
        return records(self, seeds, **options)

    monkeypatch.setattr(IterationPhysics, "target_records", logged)
    batched = _vector_play(None, damper, 3, 0, 4, **kw)
    assert batches and max(batches) == 3  # the three sub-envs' targets in one batch
    _assert_same(batched, sync)


def test_a_target_that_cannot_be_made_fails_the_batched_reset_as_the_serial_one(monkeypatch):
    import vrig.desired.pseudo_field as field

    monkeypatch.setattr(field, "_FIELD_FRACTION", 0.4)
    monkeypatch.setattr(field, "_FIELD_ATTEMPTS", 2)
    kw = {"fast": True, "seconds": 2.0, "tolerance": 1e-6, "max_episode_steps": 2}
    sync = _vector_play("sync", ID, 3, 2, 0, **kw)  # sub-envs 0 and 2 make their targets,
    assert isinstance(sync[0], vrig.RigLimitError)  # sub-env 1's trips at both levels
    batched = _vector_play(None, ID, 3, 2, 0, **kw)
    assert type(batched[0]) is type(sync[0]) and str(batched[0]) == str(sync[0])
    monkeypatch.setattr(field, "_FIELD_ATTEMPTS", 5)  # and then the envs reset as usual
    _assert_same(_vector_play(None, ID, 3, 0, 2, **kw), _vector_play("sync", ID, 3, 0, 2, **kw))
