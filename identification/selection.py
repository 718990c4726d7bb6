"""Reduced-term selection: orthogonal forward regression with the error-reduction ratio (FROLS).

Billings' forward regression orthogonal least squares: at each step every remaining candidate
column is orthogonalised against the terms already chosen (modified Gram-Schmidt), and the one
with the largest error-reduction ratio ``ERR_i = (w_i^T y)^2 / ((w_i^T w_i)(y^T y))`` is added.
Selection stops at ``n_terms`` terms or when ``1 - sum(ERR) < err_tol``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numba as nb
import numpy as np

from .budget import check_allocation, product
from .errors import IdentificationError

__all__ = ["ForwardSelection", "forward_regression"]


@dataclass(frozen=True)
class ForwardSelection:
    """Result of :func:`forward_regression`.

    Attributes
    ----------
    selected : ndarray of int
        Indices of the chosen columns, in the order they were chosen.
    err : ndarray of float
        Error-reduction ratio of each chosen column (fraction of ``y^T y`` it explains).
    """

    selected: np.ndarray
    err: np.ndarray


@nb.njit(cache=True, nogil=True)
def _frols(W, y, n_max, err_tol):  # pragma: no cover - compiled
    N, M = W.shape
    sigma = 0.0
    for i in range(N):
        sigma += y[i] * y[i]
    d = np.empty(M)  # squared norm of each candidate, orthogonalised against the chosen ones
    g = np.empty(M)  # its projection on y
    for j in range(M):
        dj = 0.0
        gj = 0.0
        for i in range(N):
            dj += W[i, j] * W[i, j]
            gj += W[i, j] * y[i]
        d[j] = dj
        g[j] = gj
    floor = 1e-24 * d  # below this a candidate is numerically dependent on the chosen terms
    chosen = np.zeros(M, dtype=np.bool_)
    selected = np.empty(n_max, dtype=np.int64)
    errs = np.empty(n_max)
    total = 0.0
    count = 0
    while count < n_max:
        best = -1
        best_err = -1.0
        for j in range(M):
            if chosen[j] or d[j] <= floor[j] or d[j] == 0.0:
                continue
            e = g[j] * g[j] / (d[j] * sigma)
            if e > best_err:
                best_err = e
                best = j
        if best < 0:
            break
        chosen[best] = True
        selected[count] = best
        errs[count] = best_err
        count += 1
        total += best_err
        if 1.0 - total < err_tol or count == n_max:
            break
        dw = d[best]
        # modified Gram-Schmidt step; the new norms and projections are accumulated in the same
        # pass that updates each column
        for j in range(M):
            if chosen[j]:
                continue
            a = 0.0
            for i in range(N):
                a += W[i, best] * W[i, j]
            a /= dw
            dj = 0.0
            gj = 0.0
            for i in range(N):
                v = W[i, j] - a * W[i, best]
                W[i, j] = v
                dj += v * v
                gj += v * y[i]
            d[j] = dj
            g[j] = gj
    return selected[:count], errs[:count]


def forward_regression(X, y, *, n_terms: int | None = None, err_tol: float | None = None):
    """Select columns of ``X`` explaining ``y`` by orthogonal forward regression (FROLS).

    Parameters
    ----------
    X : ndarray (N, M)
        Candidate regression matrix.
    y : ndarray (N,)
        Target (one output channel).
    n_terms : int, optional
        Maximum number of terms to select (default: all M).
    err_tol : float, optional
        Stop when the unexplained fraction ``1 - sum(ERR)`` falls below this (default 0: no
        early stop).

    Returns
    -------
    ForwardSelection
    """
    X = np.asarray(X, dtype=np.float64)
    y = np.asarray(y, dtype=np.float64)
    if X.ndim != 2 or y.ndim != 1 or y.shape[0] != X.shape[0]:
        raise IdentificationError(
            f"forward_regression needs X (N, M) and y (N,); got {X.shape} and {y.shape}"
        )
    M = X.shape[1]
    if n_terms is None:
        n_terms = M
    if not isinstance(n_terms, (int, np.integer)) or not 1 <= n_terms:
        raise IdentificationError(f"n_terms must be a positive integer, got {n_terms!r}")
    n_terms = min(int(n_terms), M)
    if err_tol is None:
        err_tol = 0.0
    if not 0.0 <= err_tol < 1.0:
        raise IdentificationError(f"err_tol must be in [0, 1), got {err_tol!r}")
    if not np.any(y):
        raise IdentificationError("forward_regression: the output is identically zero")
    check_allocation(
        product(X.shape[0], M, 8),
        f"forward regression's working copy of X ({X.shape[0]:,} rows x {M:,} candidate terms "
        "x 8 bytes)",
        "offer fewer candidate terms (lower order or degree) or use a shorter record",
    )
    selected, errs = _frols(np.array(X, order="F"), np.ascontiguousarray(y), n_terms, err_tol)
    return ForwardSelection(selected=selected, err=errs)
