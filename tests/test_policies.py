"""Baseline and learned drive-iteration policies (vrig.policies) and the CEM trainer."""

from __future__ import annotations

from types import SimpleNamespace

import gymnasium as gym
import numpy as np
import pytest

import vrig  # noqa: F401  (registers the environments)
from vrig.envs import ActionLayout
from vrig.policies import (
    AdaptiveBandGain,
    BandRatioPolicy,
    DecreasingGain,
    FixedGain,
    cross_entropy_search,
    run_episode,
)


def fake_env(mode="bands", n_inputs=1, n_bands=4, reidentify=False):
    """Just what a policy reads: the action layout."""
    layout = ActionLayout(mode, n_inputs, n_bands, reidentify, 0.0, 2.0)
    return SimpleNamespace(unwrapped=SimpleNamespace(layout=layout))


def obs(iteration=0, error=None, change=None, n_out=1, n_bands=4):
    return {
        "band_error": np.full((n_out, n_bands), -1.0) if error is None else np.array(error),
        "band_error_change": np.zeros((n_out, n_bands)) if change is None else np.array(change),
        "iteration": np.array([iteration], np.float32),
    }


@pytest.mark.parametrize(
    "mode,n_inputs,shape", [("bands", 2, (8,)), ("channels", 2, (2,)), ("scalar", 2, (1,))]
)
def test_fixed_gain_gives_its_gain_in_every_action_mode(mode, n_inputs, shape):
    a = FixedGain(fake_env(mode, n_inputs), 0.8)(obs())
    assert a.shape == shape and a.dtype == np.float64
    assert np.all(a == 0.8)


def test_the_reidentify_flag_is_the_last_element():
    a = FixedGain(fake_env(reidentify=True), 1.5)(obs())
    np.testing.assert_array_equal(a, [1.5, 1.5, 1.5, 1.5, 0.0])


def test_gains_are_kept_in_the_action_range():
    assert np.all(FixedGain(fake_env(), 9.0)(obs()) == 2.0)


def test_decreasing_gain_schedule():
    p = DecreasingGain(fake_env("scalar"), start=1.0, decay=0.5, floor=0.2)
    got = [p(obs(n))[0] for n in range(4)]
    np.testing.assert_allclose(got, [1.0, 0.5, 0.25, 0.2])


def test_adaptive_rule_cuts_the_gain_of_a_band_whose_error_grew():
    p = AdaptiveBandGain(fake_env(n_inputs=1), start=0.8, shrink=0.5, grow=1.1, high=1.2)
    p.reset()
    np.testing.assert_allclose(p(obs(0)), 0.8)
    change = [[-0.3, 0.2, -0.1, -0.2]]  # band 2 grew
    np.testing.assert_allclose(p(obs(1, change=change)), [0.88, 0.4, 0.88, 0.88])
    np.testing.assert_allclose(p(obs(2, change=change)), [0.968, 0.2, 0.968, 0.968])
    p.reset()
    np.testing.assert_allclose(p(obs(0)), 0.8)


def test_band_ratio_policy_maps_errors_to_gains():
    env = fake_env()
    p = BandRatioPolicy(env, BandRatioPolicy.initial(env, gain=0.8))
    np.testing.assert_allclose(p(obs(3, change=[[0.5, -0.5, 1.0, 0.0]])), 0.8)  # alpha = beta = 0
    theta = np.log([0.5, 1.0, 1.0, 1.0])
    p = BandRatioPolicy(env, np.r_[theta, -1.0, 0.0, 0.0])  # gain x e^-1 per decade of growth
    got = p(obs(1, change=[[0.0, 1.0, 0.0, -0.5]]))
    np.testing.assert_allclose(got, [0.5, np.exp(-1.0), 1.0, min(2.0, np.exp(0.5))])
    p = BandRatioPolicy(env, np.r_[np.zeros(4), 0.0, 0.0, np.log(0.5)])  # halves per iteration
    np.testing.assert_allclose(p(obs(2)), 0.25)
    with pytest.raises(ValueError, match="params"):
        BandRatioPolicy(env, [1.0, 2.0])


def test_cross_entropy_search_finds_the_minimum_of_a_quadratic():
    target = np.array([1.5, -2.0, 0.25])
    best, score, history = cross_entropy_search(
        lambda p: float(np.sum((p - target) ** 2)),
        np.zeros(3),
        2.0,
        generations=25,
        population=30,
        elite=6,
        seed=1,
    )
    np.testing.assert_allclose(best, target, atol=0.05)
    assert score == pytest.approx(np.sum((best - target) ** 2))
    assert len(history) == 25 and history[-1][2] <= history[0][2]


def test_run_episode_follows_the_env():
    env = gym.make("vrig/ShockAbsorber-v2", fast=True, max_episode_steps=3)
    res = run_episode(env, FixedGain(env, 1.0), seed=5)
    assert 1 <= res.iterations <= 3 and len(res.mean_eta0) == res.iterations + 1
    assert res.reason in ("tolerance", "budget")
    assert res.success == bool(np.all(res.final_eta0 <= env.unwrapped.task.tolerance))
    assert res.mean_eta0[-1] < res.mean_eta0[0]
    assert res.iterations_to_tolerance(3) == (res.iterations if res.success else 4)
    # the same episode with the same seed
    again = run_episode(env, FixedGain(env, 1.0), seed=5)
    assert again.mean_eta0 == res.mean_eta0


# ---------------------------------------------------------------------------------------------
# issue 25: complex gains were cast to their real part (NumPy's ComplexWarning at most)
# ---------------------------------------------------------------------------------------------
COMPLEX = [0.5 + 0.2j, np.complex128(0.5 + 0.2j), np.array(0.5 + 0.2j)]


@pytest.mark.parametrize("value", COMPLEX, ids=["python", "numpy-scalar", "numpy-0d"])
@pytest.mark.parametrize(
    "make",
    [
        lambda env, v: FixedGain(env, v),
        lambda env, v: DecreasingGain(env, start=v),
        lambda env, v: DecreasingGain(env, decay=v),
        lambda env, v: DecreasingGain(env, floor=v),
        lambda env, v: AdaptiveBandGain(env, start=v),
        lambda env, v: AdaptiveBandGain(env, shrink=v),
        lambda env, v: AdaptiveBandGain(env, grow=v),
        lambda env, v: AdaptiveBandGain(env, low=v),
        lambda env, v: AdaptiveBandGain(env, high=v),
        lambda env, v: BandRatioPolicy(env, np.full(7, v)),
        lambda env, v: BandRatioPolicy.initial(env, v),
    ],
    ids=[
        "FixedGain", "Decreasing-start", "Decreasing-decay", "Decreasing-floor", "Adaptive-start",
        "Adaptive-shrink", "Adaptive-grow", "Adaptive-low", "Adaptive-high", "BandRatio-params",
        "BandRatio-initial",
    ],
)  # fmt: skip
def test_every_constructor_refuses_a_complex_gain(make, value):
    with pytest.raises(TypeError, match="complex value"):
        make(fake_env(), value)


def test_a_complex_gain_is_refused_in_the_complex_action_mode_too():
    """The complex mode takes a real gain and a real phase per band, not a complex gain."""
    with pytest.raises(TypeError, match="complex value"):
        FixedGain(fake_env("complex"), np.complex128(0.5 + 0.2j))


class _ComplexGains(FixedGain):
    def gains(self, obs):
        return np.full(4, 0.5 + 0.2j)


class _ComplexPhases(FixedGain):
    def phases(self, obs):
        return np.full(4, 0.1 + 0.1j)


def test_a_policy_whose_gains_or_phases_are_complex_is_refused_when_called():
    with pytest.raises(TypeError, match="gains must be real"):
        _ComplexGains(fake_env())(obs())
    with pytest.raises(TypeError, match="phases must be real"):
        _ComplexPhases(fake_env("complex"))(obs())


@pytest.mark.parametrize(
    ("value", "error", "match"),
    [
        ("0.8", TypeError, "real number"),
        (True, TypeError, "real number"),
        (np.nan, ValueError, "finite"),
        (np.inf, ValueError, "finite"),
        ([0.5, 0.6], TypeError, "one number"),
    ],
)
def test_a_gain_must_be_one_finite_real_number(value, error, match):
    with pytest.raises(error, match=match):
        FixedGain(fake_env(), value)


def test_real_gains_of_any_numeric_type_are_kept_exactly():
    for value in (1, np.float32(0.75), np.int64(1), np.array(0.5)):
        assert FixedGain(fake_env(), value).gain == float(value)
    with pytest.raises(ValueError, match="> 0"):
        BandRatioPolicy.initial(fake_env(), 0.0)


def test_cross_entropy_search_refuses_a_complex_start():
    with pytest.raises(TypeError, match="complex value"):
        cross_entropy_search(lambda p: float(p @ p), np.array([1 + 1j, 0.0]), 1.0)
