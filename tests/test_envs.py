"""The vrig/ gymnasium environments: API conformance, determinism, reproduction of
vrig.reconstruct, observation/reward meaning and invalid actions (fast rigs, 4 s targets)."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
from helpers import records_equal

import vrig
from identification import metrics
from vrig.desired.pseudo_field import pseudo_field
from vrig.envs import ENV_IDS, band_edges, band_error_ratios
from vrig.io import write
from vrig.reconstruction import reconstruct


def make(env_id="vrig/ShockAbsorber-v2", **kw):
    return gym.make(env_id, fast=True, **kw)


def make_short(env_id="vrig/ShockAbsorber-v2", **kw):
    """API checks only: 2 s targets (the shortest allowed) keep them quick."""
    return make(env_id, seconds=2.0, **kw)


@pytest.fixture(scope="module")
def env():
    e = make()
    yield e
    e.close()


def _rollout(env, seed, actions):
    obs, info = env.reset(seed=seed)
    trace = [(obs, 0.0, False, False, info)]
    for a in actions:
        step = env.step(a)
        trace.append(step)
        if step[2] or step[3]:
            break
    return trace




def test_environments_are_registered_on_import_vrig():
    for env_id in ENV_IDS:
        spec = gym.spec(env_id)
        assert spec.max_episode_steps == 10
        assert spec.entry_point == "vrig.envs.checker:make_checked"
    assert gym.spec("vrig/ElastomericDamper-v2").kwargs["rig"] == "elastomeric-damper"
    assert gym.spec("vrig/LightTruckFront-v2").kwargs["rig"] == "light-truck-front"
    # every per-rig id has a measured tolerance (its side-car's), not the 2 % fallback
    for env_id, kwargs in ENV_IDS.items():
        if "rig" in kwargs:
            defaults = vrig.load_rig(kwargs["rig"]).defaults
            assert defaults.gym_id == env_id and defaults.tolerance is not None, env_id
    assert vrig.envs.DriveIterationEnv is not None


# check_env of every registered id: tests/test_env_ids.py (the seven-channel tank's is slow)


def test_the_same_seed_gives_identical_trajectories():
    a, b = make_short(), make_short()
    a.action_space.seed(5)
    actions = [a.action_space.sample() for _ in range(3)]
    ta, tb = _rollout(a, 7, actions), _rollout(b, 7, actions)
    assert records_equal(ta, tb)
    tc = _rollout(a, 8, actions)
    assert not np.array_equal(tc[0][0]["band_error"], ta[0][0]["band_error"])


@pytest.mark.parametrize("vector", [gym.vector.SyncVectorEnv, gym.vector.AsyncVectorEnv])
def test_vector_envs_run_two_episodes(vector):
    fns = [lambda: make_short(max_episode_steps=2, tolerance=1e-6)] * 2
    venv = vector(fns)
    try:
        venv.reset(seed=[1, 2])
        venv.action_space.seed(0)
        finished = np.zeros(2, int)
        for _ in range(8):
            obs, rew, term, trunc, _info = venv.step(np.full(venv.action_space.shape, 0.8))
            finished += term | trunc
            assert obs["band_error"].shape == (2, 1, 4) and np.all(np.isfinite(rew))
            if np.all(finished >= 2):
                break
        assert np.all(finished >= 2)
    finally:
        venv.close()


@pytest.mark.parametrize(
    "mode,strategy",
    [("bands", "fixed"), ("scalar", "fixed"), ("channels", "adaptive"), ("complex", "fixed")],
)
def test_fixed_gain_reproduces_reconstruct(mode, strategy):
    adaptive = strategy == "adaptive"  # re-identify flag set on every step
    e = make(
        action_mode=mode, reidentify_action=adaptive, model_seed=3, tolerance=1e-6, id_duration=6.0
    )
    ph = e.unwrapped.physics
    _drive, desired = pseudo_field(ph.rig, ph.band, 4.0, seed=11)
    truth = reconstruct(
        ph.rig,
        desired,
        iterations=3 if not adaptive else 2,
        gain=0.8,
        bandwidth=ph.band,
        seed=3,
        id_duration=6.0,
        strategy=strategy,
    )
    _obs, info = e.reset(seed=0, options={"desired": desired, "run_seed": 3})
    errors = [info["eta0"]]
    for _ in range(truth.errors.shape[0] - 1):
        _obs, _r, _term, _trunc, info = e.step(e.unwrapped.layout.action(0.8, reidentify=adaptive))
        errors.append(info["eta0"])
    np.testing.assert_allclose(np.array(errors), truth.errors, rtol=0, atol=1e-9)
    np.testing.assert_array_equal(e.unwrapped.drive, truth.drives[-1].data)


def test_observation_reward_and_info_mean_what_the_docs_say(env):
    u = env.unwrapped
    obs, info = env.reset(seed=3)
    assert obs in env.observation_space
    desres, res = u.engine.desres.data, u.response.data
    eta0 = metrics.qantim_fit_dc(desres, res)
    np.testing.assert_allclose(info["eta0"], eta0, rtol=1e-12)
    np.testing.assert_allclose(obs["eta0"], eta0, rtol=1e-6)
    full = np.array([c.full_scale for c in u.physics.rig.inputs])
    np.testing.assert_allclose(obs["drive_peak"], np.abs(u.drive).max(axis=0) / full, rtol=1e-6)
    np.testing.assert_allclose(
        obs["drive_rms"], np.sqrt(np.mean(u.drive**2, axis=0)) / full, rtol=1e-6
    )
    assert obs["iteration"][0] == 0 and np.all(obs["band_error_change"] == 0)
    before, energy = info["eta0"], np.mean(u.drive**2) / full[0] ** 2
    old_band = obs["band_error"]
    obs, reward, _term, _trunc, info = env.step(u.layout.action(0.7))
    energy_after = np.mean(u.drive**2) / full[0] ** 2
    expected = np.log(before.mean()) - np.log(info["eta0"].mean())
    expected -= 0.1 * max(0.0, np.log(energy_after / energy))
    assert reward == pytest.approx(expected, rel=1e-9)
    np.testing.assert_allclose(obs["band_error_change"], obs["band_error"] - old_band, atol=1e-5)
    assert obs["iteration"][0] == 1 and info["iteration"] == 1
    assert info["mean_eta0"] < before.mean()  # one correction at gain 0.7 reduces the error


def test_tolerance_terminates_and_the_budget_truncates():
    e = make(tolerance=1e3)
    e.reset(seed=1)
    _obs, _r, term, trunc, info = e.step(e.unwrapped.layout.action(0.5))
    assert term and not trunc and info["success"] and info["reason"] == "tolerance"
    e = make(tolerance=1e-6, max_episode_steps=2)
    e.reset(seed=1)
    e.step(e.unwrapped.layout.action(0.5))
    _obs, _r, term, trunc, info = e.step(e.unwrapped.layout.action(0.5))
    # the TimeLimit wrapper truncates (v1): the env itself names no reason
    assert trunc and not term and info["reason"] == "" and not info["success"]


def test_a_drive_beyond_limits_is_never_sent_and_ends_the_episode(env):
    u = env.unwrapped
    env.reset(seed=2)
    rig = u.physics.rig
    full = rig.inputs[0].full_scale
    sent = []
    run = rig.run
    engine = u.engine
    engine.next_drive = lambda drive, *a, **k: drive + 2 * full  # beyond the full scale
    rig.run = lambda *a, **k: sent.append(a) or run(*a, **k)
    try:
        _obs, reward, term, trunc, info = env.step(u.layout.action(0.8))
    finally:
        rig.run = run
    assert sent == []
    assert term and not trunc and reward == -5.0
    assert info["reason"] == "limit" and "not sent" in info["trip"] and not info["success"]
    with pytest.raises(RuntimeError, match="reset"):
        env.step(u.layout.action(0.8))


def test_invalid_actions_raise_and_out_of_bounds_gains_are_clipped():
    a, b = make(), make()
    a.reset(seed=4)
    b.reset(seed=4)
    n = a.action_space.shape[0]
    with pytest.raises(ValueError, match="shape"):
        a.step(np.full(n + 1, 0.5))
    with pytest.raises(ValueError, match="finite"):
        a.step(np.r_[np.nan, np.full(n - 1, 0.5)])
    _o, _r, _t, _tr, info_a = a.step(np.full(n, 7.0))  # clipped to 2
    _o, _r, _t, _tr, info_b = b.step(np.full(n, 2.0))
    assert info_a["action_clipped"] and not info_b["action_clipped"]
    np.testing.assert_array_equal(info_a["eta0"], info_b["eta0"])


def test_reset_options_and_desired_sets(tmp_path):
    e = make()
    u = e.unwrapped
    with pytest.raises(ValueError, match="unknown reset option"):
        e.reset(options={"bogus": 1})
    _o, info = e.reset(seed=0, options={"field_seed": 42})
    _drive, truth = pseudo_field(u.physics.rig, u.physics.band, 4.0, seed=42)
    np.testing.assert_array_equal(u.desired.data, truth.data)
    assert info["field_seed"] == 42
    path = tmp_path / "desres.npz"
    write(path, truth.with_data(0.5 * truth.data))
    f = make(desired=[path])
    f.reset(seed=9)
    np.testing.assert_allclose(f.unwrapped.desired.data, 0.5 * truth.data)
    with pytest.raises(ValueError, match="channel"):
        make(desired=[vrig.TimeHistory(np.c_[truth.data, truth.data], truth.fs, ["a", "b"])])


def _beyond_the_rig(e):
    """A desired response 1000 x a reachable one: its IT00 drive exceeds the drive's full
    scale (a RigLimitError before anything is sent)."""
    d = e.unwrapped.physics.target_record(3)
    return d.with_data(1000.0 * d.data)


def test_a_failed_first_reset_leaves_the_env_as_new_with_gymnasiums_checker():
    """Issue 25 item 5: with gymnasium.make's default wrappers (the env checker on), a first
    reset that raises (the target trips) broke the env for good: every step after a later,
    successful reset raised a TypeError inside gymnasium's checker. Now the failed reset leaves
    no trace: the next reset and step equal a fresh env's, bit for bit."""
    e, fresh = make_short(), make_short()
    assert "EnvChecker" in str(e)  # the default gymnasium.make stack, checker included
    with pytest.raises(vrig.RigLimitError):
        e.reset(seed=0, options={"desired": _beyond_the_rig(e)})
    assert e.unwrapped.engine is None and e.unwrapped.pending is None
    with pytest.raises(RuntimeError, match="reset"):  # no episode: refused, not half-run
        e.step(e.unwrapped.layout.action(0.8))
    action = e.unwrapped.layout.action(0.8)
    got = [e.reset(seed=0), e.step(action), e.step(action)]
    want = [fresh.reset(seed=0), fresh.step(action), fresh.step(action)]
    assert records_equal(got, want)
    # a failure later on (not the checker's first reset) recovers the same way
    with pytest.raises(vrig.RigLimitError):
        e.reset(options={"desired": _beyond_the_rig(e)})
    assert records_equal([e.reset(seed=0), e.step(action)], want[:2])


def test_complex_actions_and_fractional_seeds_are_refused_not_truncated():
    """Issue 25 item 5: a complex action lost its imaginary part (numpy's cast), a field seed
    1.5 became 1. Both are refused before anything changes."""
    e = make_short()
    e.reset(seed=1)
    lay = e.unwrapped.layout
    drive = e.unwrapped.drive.copy()
    with pytest.raises(TypeError, match="complex"):
        e.step(lay.action(0.8).astype(complex) + 0.3j)
    with pytest.raises(TypeError, match="complex"):
        e.step(lay.action(0.8).astype(complex))  # a zero imaginary part is still complex
    np.testing.assert_array_equal(e.unwrapped.drive, drive)  # nothing changed
    _o, _r, _t, _tr, info = e.step(lay.action(0.8))  # the episode goes on
    assert info["iteration"] == 1
    for key in ("field_seed", "run_seed"):
        for bad in (1.5, -1, True, "3"):
            with pytest.raises(ValueError, match=key):
                e.reset(options={key: bad})
    _o, info = e.reset(seed=2, options={"field_seed": np.int64(7), "run_seed": 3})
    assert info["field_seed"] == 7 and info["run_seed"] == 3
    with pytest.raises(ValueError, match="real"):
        vrig.IterationSettings(gain=np.complex128(0.8 + 0.3j))


def test_band_edges_are_log_spaced_over_the_band():
    np.testing.assert_allclose(band_edges((0.0, 10.0), 4), [0, 1.25, 2.5, 5, 10])
    edges = band_edges((10.0, 60.0), 3)
    np.testing.assert_allclose(edges[[0, -1]], [10, 60])
    np.testing.assert_allclose(np.diff(np.log(edges)), np.log(6) / 3)
    with pytest.raises(ValueError):
        band_edges((5.0, 1.0), 4)


def test_band_error_ratios_against_a_known_spectrum():
    fs, n = 100.0, 1000
    t = np.arange(n) / fs
    low, high = np.sin(2 * np.pi * 2 * t), 3 * np.sin(2 * np.pi * 20 * t)
    desired = (low + high)[:, None]
    response = (low + 0.9 * high)[:, None]  # 10 % error in the upper band, none in the lower
    r = band_error_ratios(desired, response, fs, [0.0, 10.0, 50.0])
    np.testing.assert_allclose(r, [[0.0, 0.1]], atol=1e-12)


def test_invalid_constructor_arguments_raise():
    with pytest.raises(ValueError, match="action_mode"):
        make(action_mode="per-sample")
    with pytest.raises(ValueError, match="gain_range"):
        make(gain_range=(1.0, 0.5))


def _trip_on(monkeypatch, bad_seeds):
    """IT00 of the targets whose field seed is in ``bad_seeds`` trips the force interlock."""
    from vrig.reconstruction.iteration import DriveIteration

    play, seen = DriveIteration.play, []

    def tripping(self, drive, iteration, *a, **kw):
        seed = seen[-1] if seen else None
        if iteration == 0 and seed in bad_seeds:
            raise vrig.RigLimitError("force", "actuator_disp", 1.0, 2.5e4, 2.4e4, "N")
        return play(self, drive, iteration, *a, **kw)

    return tripping, seen


def test_a_drawn_target_whose_it00_trips_is_redrawn_an_explicit_one_raises(monkeypatch):
    """A hardening rig (the calibrated damper) can trip on the linear inverse's IT00 drive of a
    drawn pseudo-field target: reset draws another target (deterministically); a target the
    caller named raises the trip."""
    from vrig.envs.drive_iteration import FIELD_REDRAWS
    from vrig.reconstruction.iteration import DriveIteration

    e = make_short()
    u = e.unwrapped
    _o, info = e.reset(seed=5)
    first = info["field_seed"]
    tripping, seen = _trip_on(monkeypatch, {first})
    monkeypatch.setattr(DriveIteration, "play", tripping)
    record = u.physics.target_record  # each reset's target (pseudo-field by default)
    monkeypatch.setattr(u.physics, "target_record", lambda s: (seen.append(s), record(s))[1])
    _o, info = e.reset(seed=5)
    assert seen[0] == first and info["field_seed"] == seen[-1] != first
    assert info["iteration"] == 0 and np.all(np.isfinite(info["eta0"]))
    _o, again = e.reset(seed=5)  # the redraw is deterministic
    assert again["field_seed"] == info["field_seed"]
    with pytest.raises(vrig.RigLimitError, match="force"):
        e.reset(seed=5, options={"field_seed": first})
    # every draw trips: the last trip is raised after FIELD_REDRAWS redraws
    def always(self, drive, iteration, *a, **kw):
        raise vrig.RigLimitError("force", "actuator_disp", 1.0, 2.5e4, 2.4e4, "N")

    monkeypatch.setattr(DriveIteration, "play", always)
    seen.clear()
    with pytest.raises(vrig.RigLimitError, match="force"):
        e.reset(seed=6)
    assert len(seen) == FIELD_REDRAWS + 1 and len(set(seen)) == len(seen)
    e.close()


@pytest.mark.slow
@pytest.mark.parametrize(
    "env_id,seed", [("vrig/LightTruckFront-v2", 0), ("vrig/ShockAbsorber-v2", 1)]
)
def test_the_default_tolerance_is_reached_at_gain_08_but_not_at_it00(env_id, seed):
    """The tolerance rule (vrig.envs) on the default (full-fidelity, 20 s) env: the slowest of the
    measured targets (reset seeds 0-2) meets the tolerance within the 10-step budget at the
    fixed gain 0.8, and not at IT00 (it takes several iterations)."""
    e = gym.make(env_id)
    u = e.unwrapped
    _obs, info = e.reset(seed=seed)
    assert not info["success"]
    for _ in range(10):
        _obs, _r, term, trunc, info = e.step(u.layout.action(0.8))
        assert info["reason"] not in ("limit", "unstable"), info["trip"]
        if term or trunc:
            break
    assert info["success"] and info["reason"] == "tolerance", info["eta0"]
    assert info["iteration"] >= 3
    e.close()
