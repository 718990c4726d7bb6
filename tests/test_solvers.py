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
