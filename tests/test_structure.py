"""Model structure: term ordering (Appendix E), term counts (eq. 5-10), term kinds (§5.5)."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

from identification import IdentificationError, Narx, term_count, term_count_combinatorial
from identification.structure import full_order_regressors, polynomial_terms

# Appendix E, written out as the reference text lists it (2 inputs, 1 output, order 2, quadratic).
_LIN = ["y1(t-1)", "y1(t-2)", "u1(t)", "u1(t-1)", "u1(t-2)", "u2(t)", "u2(t-1)", "u2(t-2)"]
APPENDIX_E = [
    *_LIN,
    "y1(t-1)*y1(t-1)",
    "y1(t-1)*y1(t-2)",
    "y1(t-1)*u1(t)",
    "y1(t-1)*u1(t-1)",
    "y1(t-1)*u1(t-2)",
    "y1(t-1)*u2(t)",
    "y1(t-1)*u2(t-1)",
    "y1(t-1)*u2(t-2)",
    "y1(t-2)*y1(t-2)",
    "y1(t-2)*u1(t)",
    "y1(t-2)*u1(t-1)",
    "y1(t-2)*u1(t-2)",
    "y1(t-2)*u2(t)",
    "y1(t-2)*u2(t-1)",
    "y1(t-2)*u2(t-2)",
    "u1(t)*u1(t)",
    "u1(t)*u1(t-1)",
    "u1(t)*u1(t-2)",
    "u1(t)*u2(t)",
    "u1(t)*u2(t-1)",
    "u1(t)*u2(t-2)",
    "u1(t-1)*u1(t-1)",
    "u1(t-1)*u1(t-2)",
    "u1(t-1)*u2(t)",
    "u1(t-1)*u2(t-1)",
    "u1(t-1)*u2(t-2)",
    "u1(t-2)*u1(t-2)",
    "u1(t-2)*u2(t)",
    "u1(t-2)*u2(t-1)",
    "u1(t-2)*u2(t-2)",
    "u2(t)*u2(t)",
    "u2(t)*u2(t-1)",
    "u2(t)*u2(t-2)",
    "u2(t-1)*u2(t-1)",
    "u2(t-1)*u2(t-2)",
    "u2(t-2)*u2(t-2)",
]


def _fit_tiny(model, ny, nu, n=400, seed=0):
    rng = np.random.default_rng(seed)
    return model.fit(rng.standard_normal((n, nu)), rng.standard_normal((n, ny)))


def test_appendix_e_term_order_and_count():
    assert len(APPENDIX_E) == 44
    m = _fit_tiny(Narx(order=2, degree=2), ny=1, nu=2)
    assert m.n_terms_.tolist() == [44]
    assert m.term_names()[0] == APPENDIX_E


def _eq_5_10(ny, nu, n, L):
    """Eq. 5-10 written out literally as nested sums (independent of the library's recursion)."""
    R = ny * n + nu * (n + 1)

    def inner(upper, depth):
        if depth == L:
            return sum(range(1, upper + 1))
        return sum(r + inner(r, depth + 1) for r in range(1, upper + 1))

    return R if L == 1 else R + inner(R, 2)


@pytest.mark.parametrize(
    "ny,nu,n,L", list(itertools.product([1, 2, 3], [0, 1, 2], [0, 1, 2, 4], [1, 2, 3, 4]))
)
def test_term_count_matches_eq_5_10_and_combinatorics(ny, nu, n, L):
    R = ny * n + nu * (n + 1)
    expected = math.comb(R + L, L) - 1
    assert term_count(ny, nu, n, L) == expected
    assert term_count_combinatorial(ny, nu, n, L) == expected
    assert _eq_5_10(ny, nu, n, L) == expected


def test_term_count_examples_from_the_text():
    assert term_count(1, 2, 2, 2) == 44  # Example 5.1
    assert term_count(7, 7, 4, 2) == 2079  # 7x7 quadratic order 4


def test_term_count_rejects_bad_arguments():
    with pytest.raises(IdentificationError, match="degree"):
        term_count(1, 1, 2, 0)
    with pytest.raises(IdentificationError, match="order"):
        term_count(1, 1, -1, 2)


def test_full_order_regressors_eq_4_15():
    regs = full_order_regressors(ny=2, nu=1, order=3)
    # na = n for every output (lags 1..n); nb = n + 1 terms for every input (lags 0..n), nk = 0
    assert regs.tolist() == [
        [0, 1],
        [0, 2],
        [0, 3],
        [1, 1],
        [1, 2],
        [1, 3],
        [2, 0],
        [2, 1],
        [2, 2],
        [2, 3],
    ]


def test_any_degree_is_supported():
    m = _fit_tiny(Narx(order=1, degree=5), ny=1, nu=1, n=600)
    assert m.n_terms_[0] == math.comb(3 + 5, 5) - 1
    assert "y1(t-1)*y1(t-1)*u1(t)*u1(t)*u1(t-1)" in m.term_names()[0]


def test_purely_quadratic_terms_eq_5_24():
    # SISO order n: constant, n output lags, n + 1 input lags, and the square of each (2n + 1)
    m = _fit_tiny(Narx(order=2, degree=2, kind="pure", constant=True), ny=1, nu=1)
    names = m.term_names()[0]
    lin = ["y1(t-1)", "y1(t-2)", "u1(t)", "u1(t-1)", "u1(t-2)"]
    assert names == ["1", *lin, *[f"{x}*{x}" for x in lin]]


def test_quasi_static_terms_eq_5_25():
    m = _fit_tiny(Narx(order=2, degree=2, kind="quasi-static"), ny=1, nu=2)
    assert m.term_names()[0] == [*_LIN, "u1(t)*u1(t)", "u2(t)*u2(t)"]


def test_explicit_orders_follow_matlab_arx_convention():
    m = _fit_tiny(Narx(na=2, nb=3, nk=1, degree=1), ny=1, nu=1)
    assert m.term_names()[0] == ["y1(t-1)", "y1(t-2)", "u1(t-1)", "u1(t-2)", "u1(t-3)"]


def test_terms_rows_are_sorted_and_within_range():
    regs = full_order_regressors(2, 2, 2)
    t = polynomial_terms(regs, 3)
    assert np.all(np.diff(t, axis=1) >= 0)
    assert t.min() >= 0 and t.max() == regs.shape[0]
    assert len({tuple(r) for r in t}) == t.shape[0]


def test_input_polynomial_terms_keep_the_outputs_linear():
    m = _fit_tiny(Narx(order=1, degree=2, kind="input-polynomial"), ny=1, nu=1)
    assert m.term_names()[0] == [
        "y1(t-1)",
        "u1(t)",
        "u1(t-1)",
        "u1(t)*u1(t)",
        "u1(t)*u1(t-1)",
        "u1(t-1)*u1(t-1)",
    ]
