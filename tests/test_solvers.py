"""Least-squares estimators (Appendix C): accuracy, ill-conditioning, rank deficiency."""

from __future__ import annotations

import warnings

import mpmath
import numpy as np
import pytest

from identification import IdentificationError, IllConditionedWarning, RankDeficiencyWarning
from identification.solvers import SOLVERS, get_solver

ALL = sorted(SOLVERS)
STABLE = ["qr", "householder", "mgs", "cgs", "svd"]


def _with_singular_values(rng, N, s):
    U, _ = np.linalg.qr(rng.standard_normal((N, s.size)))
    V, _ = np.linalg.qr(rng.standard_normal((s.size, s.size)))
    return (U * s) @ V.T


@pytest.mark.parametrize("name", ALL)
def test_exact_on_well_conditioned_problem(name, rng):
    X = rng.standard_normal((200, 12))
    theta = rng.standard_normal((12, 3))
    coef = SOLVERS[name](X, X @ theta)
    np.testing.assert_allclose(coef, theta, rtol=0, atol=1e-10)


@pytest.mark.parametrize("name", ALL)
def test_least_squares_residual_is_orthogonal_to_columns(name, rng):
    X = rng.standard_normal((300, 6))
    y = rng.standard_normal(300)
    coef = SOLVERS[name](X, y)
    assert coef.shape == (6,)
    assert np.max(np.abs(X.T @ (y - X @ coef))) < 1e-10


@pytest.fixture(scope="module")
def ill_conditioned():
    rng = np.random.default_rng(7)
    s = np.logspace(0, -10, 8)  # cond(X) = 1e10
    X = _with_singular_values(rng, 60, s)
    y = X @ rng.standard_normal(8)
    assert np.linalg.cond(X) >= 1e10 * 0.99
    mpmath.mp.dps = 60
    Xm = mpmath.matrix(X.tolist())
    ym = mpmath.matrix(y.tolist())
    ref = mpmath.lu_solve(Xm.T * Xm, Xm.T * ym)  # exact normal equations in 60 digits
    return X, y, np.array([float(v) for v in ref])


def _rel_err(a, b):
    return np.linalg.norm(a - b) / np.linalg.norm(b)


def test_orthogonal_solvers_beat_normal_equations_when_ill_conditioned(ill_conditioned):
    X, y, ref = ill_conditioned
    errs = {}
    for name in ALL:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            errs[name] = _rel_err(SOLVERS[name](X, y), ref)
    # backward-stable solvers lose about cond * eps ~ 1e-6; the normal equations cond^2 * eps
    for name in STABLE:
        assert errs[name] < 1e-4, (name, errs)
        assert errs["normal"] > 100 * errs[name], (name, errs)


def test_normal_equations_warn_when_ill_conditioned(ill_conditioned):
    X, y, _ = ill_conditioned
    with pytest.warns((IllConditionedWarning, RankDeficiencyWarning)):
        SOLVERS["normal"](X, y)


@pytest.mark.filterwarnings("ignore::identification.errors.IllConditionedWarning")
@pytest.mark.parametrize("name", ALL)
def test_rank_deficiency_warns_with_rank_and_returns_minimum_norm(name, rng):
    A = rng.standard_normal((100, 4))
    X = np.column_stack([A, A[:, 0] + A[:, 1]])  # rank 4 of 5
    y = rng.standard_normal(100)
    with pytest.warns(RankDeficiencyWarning, match="effective rank 4 of 5"):
        coef = SOLVERS[name](X, y)
    np.testing.assert_allclose(coef, np.linalg.pinv(X) @ y, atol=1e-8)


def test_zero_column_is_rank_deficient(rng):
    X = np.column_stack([rng.standard_normal(50), np.zeros(50)])
    with pytest.warns(RankDeficiencyWarning, match="effective rank 1 of 2"):
        coef = SOLVERS["qr"](X, X[:, 0] * 3.0)
    np.testing.assert_allclose(coef, [3.0, 0.0], atol=1e-12)


def test_columns_far_apart_in_scale_are_solved_accurately(rng):
    X = rng.standard_normal((200, 4)) * np.array([1e-6, 1.0, 1e4, 1e8])
    theta = np.array([2e6, -1.0, 3e-4, 5e-9])
    for name in STABLE:
        np.testing.assert_allclose(SOLVERS[name](X, X @ theta), theta, rtol=1e-9)


@pytest.mark.parametrize("name", ALL)
@pytest.mark.parametrize("scale", [1e160, 1e-170])
def test_columns_whose_squares_overflow_or_underflow_are_solved(name, scale, rng):
    """Issue 25: column norms were sqrt(sum x^2): entries of 1e160 overflowed (inf norms, then
    SciPy's 'A has a NaN entry'), entries of 1e-170 underflowed (a live column taken for zero).
    Least squares is scale-invariant: scaling a column by s scales its coefficient by 1/s."""
    X = rng.standard_normal((200, 5))
    theta = rng.standard_normal(5)
    s = np.array([scale, 1.0, scale, 1.0, scale])
    coef = SOLVERS[name](X * s, X @ theta)
    np.testing.assert_allclose(coef * s, theta, rtol=1e-9)


@pytest.mark.parametrize("scale", [1e100, 1e-100])
def test_a_narx_fit_is_scale_invariant(scale):
    """``Narx(2, 2).fit(u * 1e100, y * 1e100)`` raised SciPy's 'A has a NaN entry' (issue 25).
    The records of y[t] = 0.6 y[t-1] + 0.5 u[t-1] + 0.3 u[t-1]^2 + e[t], scaled by s, are
    those of the same structure with the quadratic coefficient 0.3 / s: least squares on them
    is the scaled problem, so the one-step prediction (divided by s) is the unscaled fit's, and
    its residual is at most the innovation e (the generating model's own residual)."""
    from identification import Narx

    rng = np.random.default_rng(3)
    u, e = rng.standard_normal(600), 0.01 * rng.standard_normal(600)
    y = np.zeros(600)
    for t in range(1, 600):
        y[t] = 0.6 * y[t - 1] + 0.5 * u[t - 1] + 0.3 * u[t - 1] ** 2 + e[t]
    u, y = u[:, None], y[:, None]
    unscaled = Narx(2, 2).fit(u, y).predict(u, y)
    scaled = Narx(2, 2).fit(u * scale, y * scale).predict(u * scale, y * scale) / scale
    np.testing.assert_allclose(scaled[2:], unscaled[2:], rtol=1e-9, atol=1e-12)
    residual = np.sqrt(np.mean((y[2:] - scaled[2:]) ** 2))
    assert residual <= np.sqrt(np.mean(e[2:] ** 2))


def test_regression_terms_beyond_float64_are_a_clear_identification_error():
    """Records of magnitude 1e300: their squares overflow float64 - no rescaling inside the
    solver can help; the error says so and what to do (not 'X and Y must be finite')."""
    from identification import Narx

    u = np.random.default_rng(4).standard_normal((300, 1))
    y = np.convolve(u[:, 0], [0.0, 0.5, 0.2])[:300, None]
    with np.errstate(over="ignore"), pytest.raises(IdentificationError, match="overflows"):
        Narx(2, 2).fit(u * 1e300, y * 1e300)


def test_unknown_solver_is_rejected():
    with pytest.raises(IdentificationError, match="unknown solver 'lu'"):
        get_solver("lu")


def test_solver_input_validation(rng):
    X = rng.standard_normal((10, 3))
    with pytest.raises(IdentificationError, match="at least as many samples"):
        SOLVERS["qr"](X[:2], np.ones(2))
    with pytest.raises(IdentificationError, match="Y must have shape"):
        SOLVERS["qr"](X, np.ones(9))
    Xn = X.copy()
    Xn[3, 1] = np.nan
    with pytest.raises(IdentificationError, match="finite"):
        SOLVERS["qr"](Xn, np.ones(10))
    with pytest.raises(IdentificationError, match="rcond"):
        SOLVERS["qr"](X, np.ones(10), rcond=2.0)
