"""Condensed NARX model structure: lagged regressors and polynomial term index tables.

The thesis stores each output channel's model as ``Mpar_k`` (eq. 5-23): coefficients, order,
degree and the index tables Π2, Π3 of the quadratic and cubic combinations of the linear terms.
Here the same idea is generalised to any degree:

* ``regressors`` (R, 2): the linear regressors of the channel as (source, lag) pairs. Sources
  ``0 .. ny-1`` are the outputs y1..y_ny, sources ``ny .. ny+nu-1`` the inputs u1..u_nu.
* ``terms`` (M, L): one row per model term, the indices of its L factors into the vector
  ``z = [1, x_1, ..., x_R]``; index 0 is the constant factor 1, so a row ``(0, 0, 5)`` of a cubic
  model is the linear term x_5 and ``(0, 0, 0)`` is the constant. Rows are non-decreasing.

With full-order regressors (eq. 4-15 / 5-3) and all combinations, the term order is the thesis's:
linear terms first, then quadratic, cubic, ... each in lexicographic order of their factors
(Appendix E; Algorithm B.5's P1/P2 index vectors).
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass
from functools import cache

import numpy as np

from .errors import IdentificationError

__all__ = [
    "TERM_KINDS",
    "ChannelStructure",
    "explicit_regressors",
    "full_order_regressors",
    "polynomial_terms",
    "term_count",
    "term_count_combinatorial",
]

TERM_KINDS = ("full", "pure", "quasi-static", "input-polynomial")


@dataclass(frozen=True, eq=False)
class ChannelStructure:
    """Structure of one output channel: linear regressors and the polynomial term table.

    Parameters
    ----------
    regressors : ndarray of int, shape (R, 2)
        (source, lag) of each linear regressor; sources < ny are outputs, the rest inputs.
    terms : ndarray of int, shape (M, L)
        Factor indices of each term into ``[1, x_1 .. x_R]`` (0 = constant factor).
    order : int or None
        The full-order model order n_k when the regressors were built by eq. 5-3, else None.
    """

    regressors: np.ndarray
    terms: np.ndarray
    order: int | None = None

    def __post_init__(self):
        regs = np.ascontiguousarray(self.regressors, dtype=np.int64).reshape(-1, 2)
        terms = np.ascontiguousarray(self.terms, dtype=np.int64)
        if terms.ndim != 2 or terms.shape[1] < 1:
            raise IdentificationError("terms must be a 2-D index table (n_terms, degree)")
        if terms.size and (terms.min() < 0 or terms.max() > regs.shape[0]):
            raise IdentificationError("term factor index out of range of the regressors")
        if terms.shape[1] > 1 and np.any(np.diff(terms, axis=1) < 0):
            raise IdentificationError("term factor indices must be non-decreasing along each row")
        regs.setflags(write=False)
        terms.setflags(write=False)
        object.__setattr__(self, "regressors", regs)
        object.__setattr__(self, "terms", terms)

    @property
    def degree(self) -> int:
        """Polynomial degree L_k (number of factors per term)."""
        return int(self.terms.shape[1])

    @property
    def n_regressors(self) -> int:
        return int(self.regressors.shape[0])

    @property
    def n_terms(self) -> int:
        return int(self.terms.shape[0])

    @property
    def max_lag(self) -> int:
        return int(self.regressors[:, 1].max()) if self.regressors.size else 0

    def same_as(self, other: ChannelStructure) -> bool:
        """True when both channels have identical regressors and terms (one shared matrix)."""
        return np.array_equal(self.regressors, other.regressors) and np.array_equal(
            self.terms, other.terms
        )

    def regressor_names(self, output_names, input_names) -> list[str]:
        ny = len(output_names)
        names = []
        for src, lag in self.regressors:
            base = output_names[src] if src < ny else input_names[src - ny]
            names.append(f"{base}(t)" if lag == 0 else f"{base}(t-{lag})")
        return names

    def term_names(self, output_names, input_names) -> list[str]:
        """Human-readable term names, e.g. ``y1(t-1)*u2(t)``; the constant is ``1``."""
        regs = self.regressor_names(output_names, input_names)
        out = []
        for row in self.terms:
            factors = [regs[i - 1] for i in row if i > 0]
            out.append("*".join(factors) if factors else "1")
        return out


def full_order_regressors(ny: int, nu: int, order: int) -> np.ndarray:
    """Linear regressors of the full-order structure (eq. 4-15 / 5-3) for one output channel.

    ``y_1(t-1) .. y_1(t-n), ..., y_ny(t-1) .. y_ny(t-n), u_1(t) .. u_1(t-n), ..., u_nu(t-n)``:
    na = n for every output, nb = n + 1 terms for every input, nk = 0.
    """
    if order < 0:
        raise IdentificationError(f"order must be >= 0, got {order}")
    rows = [(s, lag) for s in range(ny) for lag in range(1, order + 1)]
    rows += [(ny + j, lag) for j in range(nu) for lag in range(0, order + 1)]
    return np.array(rows, dtype=np.int64).reshape(-1, 2)


def explicit_regressors(ny: int, nu: int, na, nb, nk) -> np.ndarray:
    """Linear regressors from explicit ARX orders for one output channel.

    ``na[i]`` output lags 1..na[i] of output i; ``nb[j]`` input terms of input j starting at delay
    ``nk[j]``: lags nk[j] .. nk[j] + nb[j] - 1 (MATLAB ``arx`` convention).
    """
    rows = [(s, lag) for s in range(ny) for lag in range(1, na[s] + 1)]
    rows += [(ny + j, lag) for j in range(nu) for lag in range(nk[j], nk[j] + nb[j])]
    return np.array(rows, dtype=np.int64).reshape(-1, 2)


def polynomial_terms(
    regressors: np.ndarray, degree: int, *, kind: str = "full", constant: bool = False, ny: int = 0
) -> np.ndarray:
    """Term index table for a channel with the given linear regressors.

    Parameters
    ----------
    regressors : ndarray (R, 2)
        The channel's (source, lag) table.
    degree : int
        Polynomial degree L >= 1.
    kind : {"full", "pure", "quasi-static"}
        ``"full"``: every monomial of degree 1..L of the regressors (eq. 5-8).
        ``"pure"``: linear terms plus pure powers x_i^2 .. x_i^L, no cross products
        (purely quadratic NARX, eq. 5-24, generalised to degree L).
        ``"quasi-static"``: linear terms plus pure powers of the static (lag-0) input regressors
        only (quasi-static NARX, eq. 5-25).
        ``"input-polynomial"``: linear terms plus every monomial of degree 2..L of the *input*
        regressors only: the outputs enter linearly, so the free run is stable exactly when its
        linear autoregressive part is (useful for inverse models).
    constant : bool
        Add the constant term (first row, all factors 0).
    ny : int
        Number of outputs (needed by ``"quasi-static"`` to tell inputs from outputs).
    """
    if degree < 1:
        raise IdentificationError(f"degree must be >= 1, got {degree}")
    if kind not in TERM_KINDS:
        raise IdentificationError(f"unknown term kind {kind!r}; choose one of {TERM_KINDS}")
    R = int(regressors.shape[0])
    L = int(degree)
    if kind == "full":
        combos = np.array(
            list(itertools.combinations_with_replacement(range(R + 1), L)), dtype=np.int64
        ).reshape(-1, L)
        # combinations_with_replacement over [0, 1..R] yields the constant, then the linear,
        # quadratic, ... terms, each in lexicographic order: the thesis's ordering.
        return combos if constant else combos[1:]
    rows = []
    if constant:
        rows.append([0] * L)
    rows += [[0] * (L - 1) + [i] for i in range(1, R + 1)]
    if kind == "input-polynomial":
        inputs = [i + 1 for i, (src, _lag) in enumerate(regressors) if src >= ny]
        for d in range(2, L + 1):
            rows += [
                [0] * (L - d) + list(c) for c in itertools.combinations_with_replacement(inputs, d)
            ]
        return np.array(rows, dtype=np.int64).reshape(-1, L)
    if kind == "pure":
        powered = range(1, R + 1)
    else:  # quasi-static: lag-0 input regressors
        powered = [i + 1 for i, (src, lag) in enumerate(regressors) if src >= ny and lag == 0]
    for d in range(2, L + 1):
        rows += [[0] * (L - d) + [i] * d for i in powered]
    return np.array(rows, dtype=np.int64).reshape(-1, L)


@cache
def _nested_sum(m: int, depth: int) -> int:
    # eq. 5-10: g(m, 1) = m;  g(m, d) = m + sum_{j=1}^{m} g(j, d-1)
    if depth == 1:
        return m
    return m + sum(_nested_sum(j, depth - 1) for j in range(1, m + 1))


def term_count(ny: int, nu: int, order: int, degree: int) -> int:
    """Maximum number of NARX terms of one output channel, eq. 5-10 of the reference text.

    ``M_k = R + sum_{R1=1}^{R} [R1 + sum_{R2=1}^{R1} [R2 + ... + sum_{RL=1}^{R(L-1)} RL]]`` with
    ``R = ny*n_k + nu*(n_k + 1)`` (full-order structure, no constant term).

    Examples
    --------
    >>> term_count(1, 2, 2, 2)   # Example 5.1 / Appendix E
    44
    """
    for name, v, lo in (("ny", ny, 0), ("nu", nu, 0), ("order", order, 0), ("degree", degree, 1)):
        if not isinstance(v, (int, np.integer)) or v < lo:
            raise IdentificationError(f"{name} must be an integer >= {lo}, got {v!r}")
    R = ny * order + nu * (order + 1)
    return int(_nested_sum(R, degree)) if R > 0 else 0


def term_count_combinatorial(ny: int, nu: int, order: int, degree: int) -> int:
    """Closed form of eq. 5-10: the number of monomials of degree 1..L in R variables,
    ``C(R + L, L) - 1``."""
    R = ny * order + nu * (order + 1)
    return math.comb(R + degree, degree) - 1
