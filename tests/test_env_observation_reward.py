"""The v2 drive-iteration observation and reward (issue 26, deliverable 3): the realised /
predicted response-change ratio per output and band, and the success bonus.

Truth: analytic records built in the frequency domain (the realised change a known complex factor
times the predicted one per band), and a static-gain rig driven through an inverse model whose
gain is off by a known factor c (the realised change is then exactly c times the predicted one).
"""

from __future__ import annotations

import numpy as np
import pytest

import vrig
from vrig.envs import DriveIterationEnv, band_edges
from vrig.envs.task import IterationTask, response_change_ratios
from vrig.policies import SecantBandGain
from vrig.reconstruction import IterationSettings
from vrig.rigs.spec import ChannelSpec

FS = 200.0


def _band_limited(rng, n, n_ch, edges, factors=None):
    """Random records (n, n_ch) with no DC or Nyquist content, and the same records with band
    b's bins multiplied by ``factors[b]`` (complex; None: unchanged)."""
    spec = rng.standard_normal((n // 2 + 1, n_ch)) + 1j * rng.standard_normal((n // 2 + 1, n_ch))
    spec[0] = spec[-1] = 0.0  # the real-only bins: a complex factor there would be dropped
    f = np.fft.rfftfreq(n, 1.0 / FS)
    band = np.clip(np.searchsorted(edges, f, side="right") - 1, 0, len(edges) - 2)
    scaled = spec if factors is None else spec * np.asarray(factors)[band][:, None]
    return np.fft.irfft(spec, n, axis=0), np.fft.irfft(scaled, n, axis=0)


def test_the_ratio_is_the_known_factor_per_band():
    """R = c_b g_b (DESRES - ITn-1RES) in every band b gives rho_b = c_b (magnitude and phase),
    whatever the gains (real per channel, complex per band)."""
    rng = np.random.default_rng(0)
    edges = band_edges((0.0, FS / 2), 4)
    c = np.array([0.5, 2.0 * np.exp(0.3j), 1.0, 0.8 * np.exp(-1.0j)])
    g = np.array([0.7, 0.9 * np.exp(0.2j), 0.5, 1.2])  # one drive channel, complex per band
    error, change = _band_limited(rng, 1024, 2, edges, c * g)  # change_b = c_b g_b error_b
    previous = rng.standard_normal((1024, 2))
    desired = previous + error
    rho = response_change_ratios(desired, previous, previous + change, FS, edges, g[None, :])
    assert rho.shape == (2, 4)
    np.testing.assert_allclose(rho, np.tile(c, (2, 1)), rtol=1e-10)
    # real gains, one per drive channel (two channels of equal gain): the band's gain is theirs
    change = _band_limited(np.random.default_rng(0), 1024, 2, edges, 0.6 * c)[1]
    rho = response_change_ratios(desired, previous, previous + change, FS, edges, [0.6, 0.6])
    np.testing.assert_allclose(rho, np.tile(c, (2, 1)), rtol=1e-10)


def test_a_band_with_nothing_predicted_is_ratio_one():
    rng = np.random.default_rng(1)
    edges = band_edges((0.0, FS / 2), 4)
    error, _ = _band_limited(rng, 512, 1, edges)
    previous = rng.standard_normal((512, 1))
    gains = np.array([[0.8, 0.0, 0.8, 0.8]])  # band 1: a zero gain, nothing aimed at
    rho = response_change_ratios(
        previous + error, previous, previous + 0.4 * error, FS, edges, gains
    )
    np.testing.assert_allclose(rho[0, [0, 2, 3]], 0.5, rtol=1e-10)
    assert rho[0, 1] == 1.0
    # no error left at all: nothing predicted anywhere
    rho = response_change_ratios(previous, previous, previous + error, FS, edges, 0.8)
    np.testing.assert_array_equal(rho, np.ones((1, 4)))
    with pytest.raises(ValueError, match="one shape"):
        response_change_ratios(previous, previous[:-1], previous, FS, edges, 0.8)


# ----------------------------------------------------------------- a static-gain rig
class _StaticRig:
    """y = k u, one drive and one response, no noise: a linear gain rig."""

    name = "static-gain"
    fs = FS
    bandwidth = (0.0, FS / 2)

    def __init__(self, k):
        self.k = float(k)
        self.inputs = (ChannelSpec("u", "m", 1.0, "direct"),)
        self.outputs = (ChannelSpec("y", "N", 100.0, "load_cell"),)

    def run(self, drive, *, seed=None):
        u = np.asarray(getattr(drive, "data", drive), float)
        return vrig.TimeHistory(self.k * u, self.fs, ["y"], ["N"])


class _GainInverse:
    """An inverse model that believes the rig is y = k_model u (identification ignored)."""

    def __init__(self, k_model):
        self.k_model = float(k_model)

    def identify(self, iddrv, idres):
        pass

    def drive(self, response):
        return np.asarray(response.data, float) / self.k_model

    def describe(self):
        return f"static inverse 1/{self.k_model:g}"


def _static_env(k, k_model, **kw):
    rig = _StaticRig(k)
    rng = np.random.default_rng(5)
    n = int(4 * FS)
    u = np.convolve(rng.standard_normal(n), np.hanning(9) / 4, mode="same") * 0.05
    desired = rig.run(u[:, None])
    settings = IterationSettings(method=_GainInverse(k_model), bandwidth=(0.0, FS / 2), taper=0.0)
    env = DriveIterationEnv(rig, settings=settings, seconds=4.0, desired=[desired], **kw)
    return env


@pytest.fixture
def unshaped(monkeypatch):
    """Drives sent as the inverse makes them, less their mean: the engine's drive shaping
    low-passes at the identification band's edge, capped at 0.45 fs, which would scale the top
    band's change by the filter's response; without it the rig chain is exactly linear."""
    from vrig.reconstruction import DriveIteration

    monkeypatch.setattr(DriveIteration, "shape", lambda self, x: x - x.mean(axis=0))


@pytest.mark.parametrize("mode", ["bands", "complex"])
def test_a_model_off_by_c_observes_log10_c(mode, unshaped):
    """The model's gain is 1.25 x the rig's: a correction moves the response by c = 0.8 of what
    it aimed at, in every band and at every iteration (the response processing is linear: no
    band filter over (0, Nyquist), a linear detrend)."""
    env = _static_env(2.0, 2.5, action_mode=mode, tolerance=1e-9)
    obs, _ = env.reset(seed=0)
    assert np.all(obs["change_ratio"] == 0) and np.all(obs["change_phase"] == 0)  # IT00
    for gain in (0.6, 1.0, 0.3):
        obs, *_ = env.step(env.layout.action(gain))
        np.testing.assert_allclose(obs["change_ratio"], np.log10(0.8), atol=1e-6)
        np.testing.assert_allclose(obs["change_phase"], 0.0, atol=1e-6)
    assert obs in env.observation_space


def test_the_success_bonus_is_paid_exactly_on_the_step_that_meets_the_tolerance():
    """An exact model and gain 0.5 halve the error at each iteration; the tolerance lies between
    IT02's and IT03's η0: the bonus is in IT03's reward only, everything else is unchanged."""
    probe = _static_env(2.0, 2.0, tolerance=1e-9)
    _, info = probe.reset(seed=0)
    eta = [info["eta0"].max()]
    for _ in range(3):
        eta.append(probe.step(probe.layout.action(0.5))[4]["eta0"].max())
    assert np.all(np.diff(eta) < 0)
    tol = float(np.sqrt(eta[2] * eta[3]))  # between IT02 and IT03
    runs = {}
    for bonus in (0.0, 2.5):
        env = _static_env(2.0, 2.0, tolerance=tol, success_bonus=bonus)
        env.reset(seed=0)
        runs[bonus] = [env.step(env.layout.action(0.5)) for _ in range(3)]
    for n, (plain, paid) in enumerate(zip(runs[0.0], runs[2.5], strict=True), start=1):
        met = bool(np.all(plain[4]["eta0"] <= tol))
        assert met == (n == 3) == plain[2] == paid[2]  # terminated at IT03 only
        assert paid[1] - plain[1] == pytest.approx(2.5 if met else 0.0, abs=1e-12)
        np.testing.assert_array_equal(plain[4]["eta0"], paid[4]["eta0"])
    task = IterationTask(edges=band_edges((0.0, 10.0), 4), tolerance=1.0, success_bonus=3.0)
    assert task.reward([2.0], [1.0], 1.0, 1.0) == pytest.approx(np.log(2.0) + 3.0)
    assert task.reward([2.0], [1.01], 1.0, 1.0) == pytest.approx(np.log(2.0 / 1.01))


@pytest.mark.parametrize("value", [np.nan, np.inf, -1.0])
def test_the_success_bonus_must_be_finite_and_non_negative(value):
    with pytest.raises(ValueError, match="success_bonus must be a finite number >= 0"):
        IterationTask(edges=band_edges((0.0, 10.0), 4), success_bonus=value)


def test_the_secant_gain_of_the_observed_ratio_removes_the_error_in_one_step(unshaped):
    """Model off by c = 0.8: the first update (gain 0.8) leaves 1 - 0.64 = 36 % of the error and
    observes rho = 0.8; the secant gain 1 / 0.8 then removes the rest (a linear rig)."""
    env = _static_env(2.0, 2.5, tolerance=1e-3)  # IT01 at 36 % of IT00's error: not met
    obs, info = env.reset(seed=0)
    policy = SecantBandGain(env, start=0.8)
    policy.reset()
    np.testing.assert_allclose(policy(obs), 0.8)  # IT00: nothing observed yet
    desres = env.engine.desres.data
    e0 = desres - env.response.data
    obs, _r, term, _t, _info = env.step(policy(obs))
    assert not term
    e1 = desres - env.response.data
    np.testing.assert_allclose(e1, 0.36 * e0, atol=1e-9 * np.abs(e0).max())
    np.testing.assert_allclose(policy(obs), 1.25, rtol=1e-5)  # 1 / rho
    obs, _r, term, _t, info = env.step(policy(obs))
    # what is left: the gain's error, the float32 observation's rounding of log10(rho) (~1e-7)
    assert np.abs(desres - env.response.data).max() < 1e-6 * np.abs(e1).max()
    assert term and info["reason"] == "tolerance"
