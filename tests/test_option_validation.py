"""Validated reconstruction options and gym-environment settings (issue #11, item 7).

Bad options raise a ``ValueError`` naming the option and what is allowed before any rig run;
a constant desired response is refused instead of scoring η0 ~ 1e14 %; the environment's
penalties are finite, and after a ``reset`` that raised, ``step`` raises until the next
successful ``reset``.
"""

from __future__ import annotations

import math

import gymnasium as gym
import numpy as np
import pytest

import vrig
from vrig.envs import IterationTask, band_edges
from vrig.reconstruction import DriveIteration, reconstruct
from vrig.reconstruction.methods import InverseArx, InverseFrf, SplitSpectra


@pytest.fixture(scope="module")
def shaker():
    return vrig.load_rig("shaker")  # fs 500 Hz: Nyquist 250 Hz


def _desired(rig, seconds=2.0, seed=0):
    rng = np.random.default_rng(seed)
    n = int(seconds * rig.fs)
    return vrig.TimeHistory(rng.standard_normal(n), rig.fs, [rig.outputs[0].name], ["m/s^2"])


@pytest.mark.parametrize(
    ("band", "message"),
    [
        ((10.0, 300.0), "0 <= low < high <= fs/2 = 250 Hz"),  # beyond Nyquist: accepted today
        ((300.0, 400.0), "fs/2 = 250 Hz"),
        ((20.0, 20.0), "0 <= low < high"),  # empty
        ((math.nan, 60.0), "0 <= low < high"),
    ],
)
def test_a_bandwidth_beyond_nyquist_or_empty_is_refused(shaker, band, message):
    with pytest.raises(ValueError, match="bandwidth must satisfy") as err:
        DriveIteration(shaker, _desired(shaker), bandwidth=band)
    assert message in str(err.value)


@pytest.mark.parametrize(
    ("options", "name"),
    [
        ({"divergence": math.nan}, "divergence"),
        ({"divergence": -1.0}, "divergence"),
        ({"min_increase": math.nan}, "min_increase"),
        ({"id_rms": math.nan}, "id_rms"),
        ({"id_rms": -0.1}, "id_rms"),
        ({"id_rms": 50.0}, "id_rms"),  # beyond the 10 V full scale
        ({"id_duration": math.inf}, "id_duration"),
        ({"seed": -1}, "seed must be a non-negative integer"),
        ({"iterations": 100}, "iterations must be an integer in 0..99"),
        ({"method": "frf", "rcond": math.nan}, "rcond"),
        ({"method": "frf", "rcond": -1e-3}, "rcond"),
        ({"method": "frf", "tikhonov": math.inf}, "tikhonov"),
    ],
)
def test_bad_reconstruction_options_raise_before_any_run(shaker, options, name):
    with pytest.raises(ValueError, match=name):
        reconstruct(
            shaker, _desired(shaker), bandwidth=(10.0, 60.0), **{"iterations": 0, **options}
        )


def test_method_objects_validate_their_options():
    with pytest.raises(ValueError, match="rcond"):
        InverseFrf(rcond=math.nan)
    with pytest.raises(ValueError, match="max_lead"):
        InverseArx(4, max_lead=-1)
    with pytest.raises(ValueError, match="split_hz"):
        SplitSpectra(math.inf)


@pytest.mark.parametrize("level", [0.0, 3.7])
def test_a_constant_desired_response_is_refused(shaker, level):
    desired = vrig.TimeHistory(np.full(1000, level), shaker.fs, [shaker.outputs[0].name])
    with pytest.raises(ValueError, match="'shaft_acc' has no content in the simulation band"):
        reconstruct(shaker, desired, bandwidth=(10.0, 60.0), iterations=0)  # before identifying


@pytest.mark.parametrize("name", ["trip_penalty", "energy_penalty", "step_penalty"])
@pytest.mark.parametrize("value", [math.nan, math.inf, -1.0])
def test_penalties_must_be_finite_and_non_negative(name, value):
    with pytest.raises(ValueError, match=f"{name} must be a finite number >= 0"):
        IterationTask(edges=band_edges((0.0, 10.0), 4), **{name: value})
    with pytest.raises(ValueError, match=name):
        gym.make("vrig/Shaker-v2", fast=True, seconds=2.0, **{name: value})


def test_step_after_a_reset_that_raised_raises_until_the_next_good_reset():
    env = gym.make("vrig/ShockAbsorber-v2", fast=True, seconds=2.0).unwrapped
    env.reset(seed=0)
    action = np.full(env.action_space.shape, 0.8)
    env.step(action)  # an episode in progress
    n = int(2.0 * env.physics.fs)
    constant = vrig.TimeHistory(np.full(n, 100.0), env.physics.fs, ["damper_load"], ["N"])
    with pytest.raises(ValueError, match="no content"):
        env.reset(seed=1, options={"desired": constant})
    with pytest.raises(RuntimeError, match="reset"):
        env.step(action)  # today: steps the old episode against the new, failed reset
    with pytest.raises(ValueError, match="reset option"):
        env.reset(options={"desird": constant})
    with pytest.raises(RuntimeError, match="reset"):
        env.step(action)
    _, info = env.reset(seed=0)
    _, reward, *_ = env.step(action)
    assert np.isfinite(reward) and info["iteration"] == 0
    env.close()
