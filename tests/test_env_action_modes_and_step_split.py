"""Environment v1 (issue 16): TimeLimit alone owns truncation, the phase-aware ("complex") action
mode against analytic phase-shifted sinusoids, and the step/reset split for batched rig runs."""

from __future__ import annotations

import warnings

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils import seeding
from gymnasium.utils.env_checker import check_env
from helpers import records_equal

import vrig
from identification.errors import SimulationDivergedError
from vrig.envs import ActionLayout, DriveIterationEnv
from vrig.envs.task import ITERATION_MAX
from vrig.policies import BandRatioPolicy, FixedGain, run_episode
from vrig.processing import band_gains


def make_short(env_id="vrig/ShockAbsorber-v2", **kw):
    """2 s targets on the fast rig: quick."""
    return gym.make(env_id, fast=True, seconds=2.0, **kw)


def burst(t, f0, centre, sigma, phase=0.0):
    """A Gaussian-enveloped sinusoid: its spectrum is a Gaussian of width 1 / (2 pi sigma) Hz
    around f0, so a band well around f0 holds all of it (to round-off)."""
    return np.exp(-0.5 * ((t - centre) / sigma) ** 2) * np.cos(2 * np.pi * f0 * (t - centre) + phase)




# ---------------------------------------------------------------- complex band gains
def test_complex_band_gains_rotate_a_sinusoid_in_its_band_and_leave_the_others():
    """A 5 Hz burst in band [2, 8) Hz with gain 0.7 exp(0.6j) becomes 0.7 x the burst advanced by
    0.6 rad; a 20 Hz burst in [8, 50) Hz with a real gain is only scaled; on the second channel
    a negative phase delays the 20 Hz carrier by phi / omega."""
    fs, n = 100.0, 4000
    t = np.arange(n) / fs
    a, b = burst(t, 5.0, 15.0, 1.0), burst(t, 20.0, 25.0, 1.0)
    x = np.c_[a + b, a + b]
    edges = [0.0, 2.0, 8.0, 50.0]
    gains = np.array(
        [
            [0.3 * np.exp(1.0j), 0.7 * np.exp(0.6j), 1.3],
            [1.0, 1.0, 0.5 * np.exp(-0.9j)],
        ]
    )
    y = band_gains(x, fs, gains, edges)
    assert y.dtype == float and y.shape == x.shape
    truth0 = 0.7 * burst(t, 5.0, 15.0, 1.0, 0.6) + 1.3 * b
    delay = 0.9 / (2 * np.pi * 20.0)  # s: a phase lag of 0.9 rad at 20 Hz
    envelope = np.exp(-0.5 * (t - 25.0) ** 2)
    truth1 = a + 0.5 * envelope * np.cos(2 * np.pi * 20.0 * (t - 25.0 - delay))  # carrier delayed
    np.testing.assert_allclose(y[:, 0], truth0, rtol=0, atol=1e-12)
    np.testing.assert_allclose(y[:, 1], truth1, rtol=0, atol=1e-12)


def test_complex_band_gains_half_turn_negates_and_zero_phase_is_the_real_gain_bit_for_bit():
    fs, n = 100.0, 3000
    t = np.arange(n) / fs
    x = np.c_[burst(t, 5.0, 10.0, 1.0) + burst(t, 20.0, 20.0, 1.0)]
    edges = [0.0, 2.0, 8.0, 50.0]
    y = band_gains(x, fs, np.full((1, 3), 0.8 * np.exp(1j * np.pi)), edges)
    np.testing.assert_allclose(y, -0.8 * x, rtol=0, atol=1e-12)
    real = np.array([[0.4, 0.9, 1.3]])
    np.testing.assert_array_equal(
        band_gains(x, fs, real.astype(complex), edges), band_gains(x, fs, real, edges)
    )
    # equal complex gains with a phase are a rotation, not the "equal gains: scale" shortcut
    z = band_gains(x, fs, np.full((1, 3), np.exp(0.5j)), edges)
    assert z.dtype == float and not np.allclose(z, x)


# ---------------------------------------------------------------- action layout
def test_complex_layout_is_magnitudes_then_phases_channel_major_then_the_flag():
    lay = ActionLayout("complex", 2, 3, True, 0.0, 2.0, 1.0)
    assert (lay.n_gains, lay.n_phases, lay.size) == (6, 6, 13)
    g = np.arange(6.0).reshape(2, 3) / 10
    p = -np.arange(6.0).reshape(2, 3) / 10
    np.testing.assert_array_equal(lay.action(g, p, reidentify=True), np.r_[g.ravel(), p.ravel(), 1])
    np.testing.assert_array_equal(lay.action([0.5, 0.7]), np.r_[[0.5] * 3, [0.7] * 3, [0] * 7])
    low, high = lay.bounds()
    np.testing.assert_array_equal(low, np.r_[[0.0] * 6, [-1.0] * 6, 0.0])
    np.testing.assert_array_equal(high, np.r_[[2.0] * 6, [1.0] * 6, 1.0])
    with pytest.raises(TypeError, match="keyword"):
        lay.action(0.8, True)
    with pytest.raises(ValueError, match="complex"):
        ActionLayout("bands", 1, 4, False, 0.0, 2.0).action(0.8, 0.1)


def test_invalid_phase_max_and_removed_max_iterations_raise():
    with pytest.raises(ValueError, match="phase_max"):
        make_short(action_mode="complex", phase_max=4.0)
    with pytest.raises(ValueError, match="phase_max"):
        make_short(action_mode="complex", phase_max=0.0)
    with pytest.raises(TypeError, match="max_episode_steps"):
        DriveIterationEnv("shock-absorber", fast=True, seconds=2.0, max_iterations=10)


# ---------------------------------------------------------------- complex steps
def test_phase_zero_complex_steps_equal_bands_steps_bit_for_bit():
    gains = [[0.5, 0.8, 1.0, 1.2]]  # unequal: the spectral path of band_gains
    traces = []
    for mode in ("bands", "complex"):
        e = make_short(action_mode=mode)
        lay = e.unwrapped.layout
        trace = [e.reset(seed=3)]
        for _ in range(3):
            trace.append(e.step(lay.action(gains)))
            trace.append(e.unwrapped.drive.copy())
        traces.append(trace)
        e.close()
    assert records_equal(traces[0], traces[1])


def test_a_complex_step_rotates_the_correction_of_its_band_by_the_phase():
    """The correction is replaced by a 60 Hz burst (all its content in the last band, 10 Hz to
    Nyquist, and none in the tapered ends): the prepared drive is the previous one plus the
    magnitude times the burst advanced by the phase, whatever the other bands' gains."""
    e = make_short(action_mode="complex")
    u = e.unwrapped
    e.reset(seed=2)
    t = np.arange(u.engine.n) / u.physics.fs
    corr = 0.01 * burst(t, 60.0, 1.0, 0.1)[:, None]
    u.engine.correction = lambda response: corr
    before = u.drive.copy()
    drive, n = u.prepare_step(u.layout.action([[0.3, 1.5, 0.2, 0.7]], [[1.2, -0.4, 0.9, 0.6]]))
    assert n == 1
    truth = 0.7 * 0.01 * burst(t, 60.0, 1.0, 0.1, 0.6)
    np.testing.assert_allclose(drive[:, 0] - before[:, 0], truth, rtol=0, atol=1e-14)
    _o, _r, _term, trunc, info = u.finish_step(u.engine.play(drive, n))
    assert info["iteration"] == 1 and not trunc and not info["action_clipped"]


def test_phases_beyond_phase_max_are_clipped_and_reported():
    a, b = make_short(action_mode="complex", phase_max=0.5), make_short(action_mode="complex", phase_max=0.5)
    a.reset(seed=4)
    b.reset(seed=4)
    lay = a.unwrapped.layout
    _o, _r, _t, _tr, info_a = a.step(lay.action(0.8, [[3.0, -3.0, 0.1, 0.0]]))
    _o, _r, _t, _tr, info_b = b.step(lay.action(0.8, [[0.5, -0.5, 0.1, 0.0]]))
    assert info_a["action_clipped"] and not info_b["action_clipped"]
    np.testing.assert_array_equal(a.unwrapped.drive, b.unwrapped.drive)


@pytest.mark.parametrize("mode,reidentify", [("complex", False), ("complex", True), ("channels", True)])
def test_check_env_passes_for_each_action_mode(mode, reidentify):
    e = make_short(action_mode=mode, reidentify_action=reidentify)
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message=".*symmetric and normalized.*")
        check_env(e.unwrapped)
    e.close()


# ---------------------------------------------------------------- truncation
def test_the_env_never_truncates_time_limit_does():
    e = DriveIterationEnv("shock-absorber", fast=True, seconds=2.0, tolerance=1e-9)
    e.reset(seed=1)
    for _ in range(12):  # beyond the v0 budget of 10
        _o, _r, term, trunc, info = e.step(e.layout.action(0.3))
        assert not trunc and not term and info["reason"] == ""
    assert info["iteration"] == 12
    w = gym.wrappers.TimeLimit(e, 3)
    w.reset(seed=1)
    flags = [w.step(e.layout.action(0.3))[3] for _ in range(3)]
    assert flags == [False, False, True]
    res = run_episode(w, FixedGain(w, 0.3), seed=1)
    assert res.iterations == 3 and res.reason == "budget" and not res.success


def test_the_iteration_observation_is_bounded_by_the_record_names():
    e = make_short()
    u = e.unwrapped
    e.reset(seed=0)
    obs = u.task.observe(
        log_band_error=u.log_band_error, previous_log_band_error=None, eta0=u.scores[0],
        rms_error=u.scores[1], drive=u.drive, full_scale=u.physics.drive_full_scale,
        iteration=150,
    )  # fmt: skip
    assert ITERATION_MAX == 99 == obs["iteration"][0] and obs in e.observation_space


# ---------------------------------------------------------------- the split
def test_prepare_play_finish_is_step_bit_for_bit():
    a, b = make_short(action_mode="complex"), make_short(action_mode="complex")
    lay = a.unwrapped.layout
    actions = [lay.action(0.8, 0.2), lay.action([[0.5, 1.0, 1.2, 0.9]], -0.3), lay.action(1.0)]
    ta = [a.reset(seed=6)] + [a.step(x) for x in actions]
    u = b.unwrapped
    drive, n = u.prepare_reset(seed=6)
    tb = [u.finish_reset(u.engine.play(drive, n))]
    for x in actions:
        drive, n = u.prepare_step(x)
        tb.append(u.finish_step(u.engine.play(drive, n)))
    assert records_equal(ta, tb)
    np.testing.assert_array_equal(a.unwrapped.drive, u.drive)


def test_the_split_contract_failures_and_misuse():
    e = make_short()
    u = e.unwrapped
    with pytest.raises(RuntimeError, match="reset"):
        u.prepare_step(u.layout.action(0.8))
    e.reset(seed=1)
    drive, n = u.prepare_step(u.layout.action(0.8))
    with pytest.raises(RuntimeError, match="not finished"):
        u.prepare_step(u.layout.action(0.8))
    trip = vrig.RigLimitError("force", "actuator", 1.0, 2.5e4, 2.4e4, "N")
    _o, reward, term, trunc, info = u.finish_step(trip)  # a batched play that tripped
    assert term and not trunc and reward == -u.task.trip_penalty and info["reason"] == "limit"
    with pytest.raises(RuntimeError, match="finish_step"):
        u.finish_step(None)
    # a diverging free run in the update itself: nothing to play, recorded for the finish
    e.reset(seed=1)

    def diverge(*a, **k):
        raise SimulationDivergedError(0, "x", 10, np.inf, 1.0)

    u.engine.next_drive = diverge
    drive, n = u.prepare_step(u.layout.action(0.8))
    assert drive is None and n == 1 and u.pending == (None, 1)
    _o, reward, term, _tr, info = u.finish_step(None)
    assert term and info["reason"] == "unstable" and reward == -u.task.trip_penalty
    # any other exception from the play is raised by the finish and ends the episode
    e.reset(seed=1)
    u.prepare_step(u.layout.action(0.8))
    with pytest.raises(KeyError):
        u.finish_step(KeyError("boom"))
    with pytest.raises(RuntimeError, match="reset"):
        e.step(u.layout.action(0.8))


def test_finish_reset_redraws_a_drawn_target_that_tripped_at_it00():
    e = make_short()
    u = e.unwrapped
    drive, n = u.prepare_reset(seed=5)
    first = u.field_seed
    trip = vrig.RigLimitError("force", "actuator", 1.0, 2.5e4, 2.4e4, "N")
    assert u.finish_reset(trip) is None
    rng, _ = seeding.np_random(5)  # the env's documented randomness: two draws, then a redraw
    drawn = rng.integers(0, 2**31 - 1, size=2)
    redraw = int(rng.integers(0, 2**31 - 1))
    assert first == drawn[0] and u.field_seed == redraw
    drive, n = u.pending
    obs, info = u.finish_reset(u.engine.play(drive, n))
    assert info["field_seed"] == redraw and info["run_seed"] == drawn[1] and n == 0
    ref = make_short()
    ref_obs, ref_info = ref.reset(seed=0, options={"field_seed": redraw, "run_seed": int(drawn[1])})
    assert records_equal(obs, ref_obs) and ref_info["eta0"].tolist() == info["eta0"].tolist()
    # an explicit target is not redrawn: the trip is raised
    u.prepare_reset(seed=5, options={"field_seed": 3})
    with pytest.raises(vrig.RigLimitError):
        u.finish_reset(trip)


# ---------------------------------------------------------------- policies
def test_policies_in_complex_mode():
    e = make_short(action_mode="complex")
    lay = e.unwrapped.layout
    obs, _ = e.reset(seed=0)
    a = FixedGain(e, 0.8)(obs)
    np.testing.assert_array_equal(a, np.r_[[0.8] * 4, [0.0] * 4])
    assert BandRatioPolicy.n_params(e) == 2 * lay.n_bands + 3
    p = BandRatioPolicy.initial(e, 0.8)
    p[-4:] = [0.1, -0.2, 3.0, 0.0]  # phases per band; 3 rad is clipped to phase_max
    act = BandRatioPolicy(e, p)(obs)
    np.testing.assert_allclose(act[:4], 0.8)
    np.testing.assert_allclose(act[4:], [0.1, -0.2, np.pi / 2, 0.0])


@pytest.mark.parametrize("rig,n_in,n_out", [("radiator", 1, 2), ("light-truck-front", 6, 10)])
def test_the_spaces_are_the_documented_sizes(rig, n_in, n_out):
    """The table of DriveIterationEnv's docstring: flat observation 4 n_out n_bands + 2 n_out +
    2 n_in + 1 (v2: band_error, band_error_change, change_ratio, change_phase per output and
    band); actions n_in n_bands, n_in, 1, 2 n_in n_bands (+1 with the flag)."""
    from gymnasium.spaces.utils import flatdim

    sizes = {"bands": 4 * n_in, "channels": n_in, "scalar": 1, "complex": 8 * n_in}
    for mode, size in sizes.items():
        e = DriveIterationEnv(rig, fast=True, seconds=2.0, action_mode=mode, reidentify_action=True)
        assert e.action_space.shape == (size + 1,), mode
    assert e.observation_space["band_error"].shape == (n_out, 4)
    for key in ("band_error_change", "change_ratio", "change_phase"):
        assert e.observation_space[key].shape == (n_out, 4)
    assert flatdim(e.observation_space) == 4 * 4 * n_out + 2 * n_out + 2 * n_in + 1
