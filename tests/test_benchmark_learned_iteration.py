"""benchmarks/learned_iteration.py's model-updating rows (issue 26): the ``update`` hook and the
runner that plays an update method as :func:`vrig.reconstruct` on the env's own episode.

Truth: the env's fixed-gain episode (a different code path: ``reset``/``step``) for the runner
without an update; a fake reconstruction for the settings it is given and the stop it reports.
"""

from __future__ import annotations

from types import SimpleNamespace

import gymnasium as gym
import numpy as np
import pytest

import vrig  # registers the environments
from benchmarks import learned_iteration as li
from vrig.errors import ReconstructionError
from vrig.policies import FixedGain, run_episode
from vrig.reconstruction import IterationSettings


@pytest.fixture(scope="module")
def env():
    e = gym.make(
        "vrig/ShockAbsorber-v2",
        fast=True,
        seconds=2.0,
        id_duration=4.0,
        max_episode_steps=li.BUDGET,
    )
    yield e
    e.close()


def test_without_an_update_the_runner_plays_the_envs_fixed_gain_episode(env):
    """Same model, target, run seed, tolerance and budget: the reconstruction's errors are the
    env's, iteration for iteration, and it stops where the env terminates."""
    plain = [None, "none"]  # "none": today's loop, bit for bit
    for seed, update in ((3, plain[-1]), (4, None)):
        mine = li.play_update(env, update, field_seed=seed, run_seed=seed, gain=0.8)
        theirs = run_episode(
            env, FixedGain(env, 0.8), options={"field_seed": seed, "run_seed": seed}
        )
        assert (mine.iterations, mine.success, mine.reason) == (
            theirs.iterations,
            theirs.success,
            theirs.reason,
        )
        np.testing.assert_allclose(mine.mean_eta0, theirs.mean_eta0, rtol=1e-9)
        np.testing.assert_allclose(mine.final_eta0, theirs.final_eta0, rtol=1e-9)
    assert theirs.success or theirs.reason == "budget"


def _fake(errors, stop_kind, seen):
    def reconstruct(rig, desired, settings):
        seen.append(settings)
        return SimpleNamespace(errors=np.asarray(errors, float), stop_kind=stop_kind)

    return reconstruct


@pytest.mark.parametrize(
    "stop_kind,reason,played",
    [("converged", "tolerance", 2), ("completed", "budget", 2), ("interlock", "limit", 3),
     ("refused", "limit", 3), ("diverged", "unstable", 3), ("unstable", "unstable", 3)],
)  # fmt: skip
def test_the_runner_gives_the_reconstructions_stop_as_the_envs_reason(
    env, stop_kind, reason, played
):
    seen = []
    fake = _fake([[9.0], [5.0], [1.0]], stop_kind, seen)
    r = li.play_update(env, None, field_seed=1, run_seed=7, reconstruct=fake)
    # a failed step counts as played (as run_episode counts it); only success counts iterations
    assert (r.reason, r.iterations, r.success) == (reason, played, reason == "tolerance")
    assert r.iterations_to_tolerance(li.BUDGET) == (2 if r.success else li.BUDGET + 1)
    assert r.mean_eta0 == [9.0, 5.0, 1.0] and r.final_eta0.tolist() == [1.0]
    (s,) = seen
    u = env.unwrapped
    assert (s.run_seed, s.iterations, s.tolerance) == (7, li.BUDGET, u.task.tolerance)
    assert s.divergence == np.inf and s.strategy == "fixed"
    assert s.gain == li.rule_gain(u.physics.rig) == 0.8  # the shock absorber's rule gain
    assert s.identification_key() == u.physics.settings.identification_key()  # same model


def test_an_it00_failure_is_a_trip_with_nothing_iterated(env):
    def reconstruct(rig, desired, settings):
        result = SimpleNamespace(errors=np.empty((0, 1)), stop_kind="interlock")
        raise ReconstructionError("no iteration played", result=result, cause=None, stage="IT00")

    r = li.play_update(env, None, field_seed=1, run_seed=1, reconstruct=reconstruct)
    assert r.reason == "limit" and not r.success and r.final_eta0 is None


def test_update_rows_exist_exactly_when_the_settings_have_the_field(monkeypatch):
    args = SimpleNamespace(quick=True, rl_dir="no-such-folder")
    specs, note = li._specs("shock-absorber", [0.0] * 7, args)
    names = (*IterationSettings.field_names(), "update")
    monkeypatch.setattr(IterationSettings, "field_names", classmethod(lambda cls: names))
    assert li.update_methods() == li.UPDATE_METHODS == ("frf", "secant", "reidentify", "ilc")
    specs, note = li._specs("shock-absorber", [0.0] * 7, args)
    assert [k for k in specs if k.startswith("update")] == [
        f"update {u}" for u in li.UPDATE_METHODS
    ]
    assert specs["update ilc"] == ("update", "ilc") and "update" not in (note or "")


def test_the_runner_passes_the_update_method_to_the_reconstruction(env):
    seen = []
    for update in li.UPDATE_METHODS:
        li.play_update(
            env, update, field_seed=2, run_seed=2, reconstruct=_fake([[3.0]], "converged", seen)
        )
    assert [s.update for s in seen] == list(li.UPDATE_METHODS)
    from vrig.reconstruction import UPDATES

    assert set(li.UPDATE_METHODS) == set(UPDATES) - {"none"}  # every method, each once


def test_the_rule_gain_follows_the_side_car():
    assert li.rule_gain(vrig.load_rig("fuel-tank-2ch", fidelity="fast")) == 0.3  # gym.gain
    assert li.rule_gain(vrig.load_rig("fuel-tank-7ch", fidelity="fast")) == 0.5  # frf's gain
    assert li.rule_gain(vrig.load_rig("elastomeric-damper", fidelity="fast")) == 0.5  # rig's
    assert li.rule_gain(SimpleNamespace()) == 0.8


def test_episode_times_stop_at_an_episode_that_ends_early(monkeypatch, capsys):
    """``--timing``: an episode that ends before 10 iterations (a trip, a diverging drive) is
    timed as far as it went, its iterations counted; stepping on would raise (the env's own
    contract: no step after the end)."""

    class _EndsAtTwo:
        action_space = gym.spaces.Box(0.0, 2.0, shape=(1,))

        def reset(self, seed=None):
            self.n = 0
            return {}, {}

        def step(self, action):
            if self.n >= 2:
                raise RuntimeError("no episode in progress")
            self.n += 1
            return {}, 0.0, self.n == 2, False, {}

        def close(self):
            pass

    monkeypatch.setattr(li.gym, "make", lambda *a, **k: _EndsAtTwo())
    out = li.episode_times(rigs=("any",), repeats=2)
    assert out["any fast"]["iterations"] == [2, 2]
    assert out["any default"]["iterations"] == [2, 2]
    assert "iterations played: 2, 2" in capsys.readouterr().out
