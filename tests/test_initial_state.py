"""Initial conditions of a free run (issue 24, deliverable 3): the estimated initial state,
``Narx.estimate_initial_state`` and ``simulate(u, initial_state=...)``.

Truth: known ARX/NARX systems written out as recursions in this file, started from a known
non-zero past (outputs before sample 0; inputs before sample 0 are zero, the documented
convention), with noise-free records so that the fitted models hold the true coefficients to
rounding.
"""

from __future__ import annotations

import numpy as np
import pytest

from identification import Arx, IdentificationError, Narx, SimulationDivergedError

PAST = np.array([0.8, -0.5])  # y(-2), y(-1): the known initial state (oldest first)


def _arx(u, past):
    """y(t) = 1.5 y(t-1) - 0.7 y(t-2) + 0.5 u(t) + 0.3 u(t-1) + 0.2 u(t-2) (the text's order-2
    structure), from the outputs ``past`` = (y(-2), y(-1)) and a zero past input."""
    y = np.concatenate([past, np.zeros(u.size)])
    U = np.concatenate([np.zeros(2), u])
    for t in range(2, y.size):
        y[t] = 1.5 * y[t - 1] - 0.7 * y[t - 2] + 0.5 * U[t] + 0.3 * U[t - 1] + 0.2 * U[t - 2]
    return y[2:]


def _narx(u, past):
    """y(t) = 0.5 y(t-1) - 0.2 y(t-2) + 0.1 y(t-1)^2 + u(t-1) + 0.3 u(t-2) - 0.05 u(t-1) y(t-1)
    (input lags from 1: SysIdentPy's ylag = xlag = 2), from ``past`` and a zero past input."""
    y = np.concatenate([past, np.zeros(u.size)])
    U = np.concatenate([np.zeros(2), u])
    for t in range(2, y.size):
        y1, y2, u1, u2 = y[t - 1], y[t - 2], U[t - 1], U[t - 2]
        y[t] = 0.5 * y1 - 0.2 * y2 + 0.1 * y1**2 + u1 + 0.3 * u2 - 0.05 * u1 * y1
    return y[2:]


def _white(n, seed, scale=0.5):
    return scale * np.random.default_rng(seed).standard_normal(n)


@pytest.fixture(scope="module")
def arx_model():
    u = _white(1500, 0)
    return Arx(order=2).fit(u, _arx(u, np.zeros(2)))


@pytest.fixture(scope="module")
def narx_model():
    u = _white(1500, 1)
    return Narx(order=2, degree=2, lags="sysidentpy").fit(u, _narx(u, np.zeros(2)))


def test_the_arx_initial_state_is_recovered_and_the_free_run_then_matches(arx_model):
    """Identifiable: with max_lag_ = na = 2, y(0) = -0.7 y(-2) + 1.5 y(-1) + ... and
    y(1) = -0.7 y(-1) + 1.5 y(0) + ...: the first two outputs are a triangular map of the state
    with a_2 = -0.7 on its diagonal, invertible. The free run is affine in the state: one linear
    least-squares solve."""
    u = _white(300, 2)
    y = _arx(u, PAST)
    state = arx_model.estimate_initial_state(u, y)
    assert state.shape == (2, 1)
    np.testing.assert_allclose(state[:, 0], PAST, rtol=0, atol=1e-6)
    sim = arx_model.simulate(u, initial_state=state)
    np.testing.assert_allclose(sim[:, 0], y, rtol=0, atol=1e-6 * np.abs(y).max())
    assert np.abs(arx_model.simulate(u)[:, 0] - y).max() > 0.1  # the zero past does not


def test_the_narx_initial_state_is_recovered_by_nonlinear_least_squares(narx_model):
    """Non-linear in the state (y(t-1)^2). Identifiable globally: y(-2) enters y(0) only through
    -0.2 y(-2), so y(-1) and y(0) give y(-2); likewise y(0) and y(1) give y(-1): the state maps
    one to one onto the first two outputs."""
    u = _white(300, 3)
    y = _narx(u, PAST)
    state = narx_model.estimate_initial_state(u, y, n_fit=40)
    np.testing.assert_allclose(state[:, 0], PAST, rtol=0, atol=1e-6)
    sim = narx_model.simulate(u, initial_state=state)
    np.testing.assert_allclose(sim[:, 0], y, rtol=0, atol=1e-6 * np.abs(y).max())


def test_a_mimo_arx_state_is_recovered():
    """y1(t) = 0.6 y1(t-1) + 0.2 y2(t-1) + u1(t), y2(t) = -0.3 y1(t-1) + 0.5 y2(t-1) + u2(t):
    y(0) = A y(-1) + u(0) with A non-singular (det 0.36), so y(-1) is identifiable."""
    A = np.array([[0.6, 0.2], [-0.3, 0.5]])

    def system(u, past):
        y = np.zeros_like(u)
        prev = past
        for t in range(u.shape[0]):
            y[t] = A @ prev + u[t]
            prev = y[t]
        return y

    rng = np.random.default_rng(4)
    u = rng.standard_normal((800, 2))
    model = Arx(order=1).fit(u, system(u, np.zeros(2)))
    ut = rng.standard_normal((100, 2))
    past = np.array([1.2, -0.7])
    y = system(ut, past)
    state = model.estimate_initial_state(ut, y, n_fit=10)
    np.testing.assert_allclose(state, past[None, :], rtol=0, atol=1e-6)
    np.testing.assert_allclose(model.simulate(ut, initial_state=state), y, rtol=0, atol=1e-6)


def test_a_zero_initial_state_is_the_zero_past_run_bit_for_bit(narx_model):
    u = _white(200, 5)
    np.testing.assert_array_equal(
        narx_model.simulate(u), narx_model.simulate(u, initial_state=np.zeros(2))
    )


def test_divergence_from_an_initial_state_counts_samples_from_sample_0(narx_model):
    u = _white(200, 6)
    with pytest.raises(SimulationDivergedError) as info:  # y^2 feedback escapes from y = 50
        narx_model.simulate(u, initial_state=[50.0, 50.0])
    assert 0 <= info.value.sample < 10


def test_bad_initial_state_arguments_are_refused(narx_model):
    u = _white(100, 7)
    y = _narx(u, PAST)
    with pytest.raises(IdentificationError, match="not both"):
        narx_model.simulate(u, y0=y[:2], initial_state=PAST)
    with pytest.raises(IdentificationError, match=r"initial_state must have shape \(max_lag_"):
        narx_model.simulate(u, initial_state=np.zeros(3))
    with pytest.raises(IdentificationError, match="NaN"):
        narx_model.simulate(u, initial_state=[0.0, np.nan])
    for n_fit in (1, 101, 2.5, True):
        with pytest.raises(IdentificationError, match="n_fit must be"):
            narx_model.estimate_initial_state(u, y, n_fit=n_fit)
    with pytest.raises(IdentificationError, match="same length"):
        narx_model.estimate_initial_state(u, y[:-1])
