"""Regression matrices of (N)ARX models, built column-wise with index tables (Appendix B).

The linear regressors are lagged copies of the data columns (Algorithm B.2, no loop over samples);
the polynomial terms are products of those columns chosen by the term index table (Algorithm B.5,
generalised to any degree) and computed by a compiled kernel. A regressor with a static function
(:mod:`identification._transforms`) holds ``g(x)`` instead of ``x``.
"""

from __future__ import annotations

import numpy as np

from ._kernels import expand_terms
from ._transforms import apply_array
from .budget import check_allocation, product
from .structure import ChannelStructure

__all__ = ["lagged_regressors", "regression_matrix"]


def lagged_regressors(
    u: np.ndarray,
    y: np.ndarray,
    regressors: np.ndarray,
    start: int,
    functions: np.ndarray | None = None,
    breakpoints: np.ndarray | None = None,
) -> np.ndarray:
    """Return ``Z`` (N - start, R + 1), Fortran-ordered: a column of ones, then each regressor.

    Row ``i`` corresponds to time ``t = start + i``; regressor (source, lag) is
    ``y[t - lag, source]`` for outputs and ``u[t - lag, source - ny]`` for inputs, passed through
    ``g = functions[r]`` with breakpoint ``breakpoints[r]`` when given (code 0: identity).

    Parameters
    ----------
    u : ndarray (N, nu)
        Input record.
    y : ndarray (N, ny)
        Output record, same N.
    regressors : ndarray (R, 2) of int
        ``(source, lag)`` of each regressor: source < ny an output, else input ``source - ny``;
        lag in samples.
    start : int
        First row's time index (at least the largest lag).
    functions : ndarray (R,) of int, optional
        Static function code per regressor (0: identity; default all identity).
    breakpoints : ndarray (R,), optional
        Breakpoint per regressor, in its source's units (used by the dead-zone/saturation codes).
    """
    N = u.shape[0]
    ny = y.shape[1]
    rows = N - start
    check_allocation(
        product(rows, regressors.shape[0] + 1, 8),
        f"the lagged regressors ({rows:,} rows x {regressors.shape[0] + 1:,} columns x 8 bytes)",
        "use fewer lags or a shorter record",
    )
    Z = np.empty((rows, regressors.shape[0] + 1), order="F")
    Z[:, 0] = 1.0
    for r, (src, lag) in enumerate(regressors):
        data = y[:, src] if src < ny else u[:, src - ny]
        x = data[start - lag : N - lag]
        if functions is not None and functions[r] != 0:
            x = apply_array(int(functions[r]), float(breakpoints[r]), x)
        Z[:, r + 1] = x
    return Z


def regression_matrix(
    u: np.ndarray, y: np.ndarray, channel: ChannelStructure, start: int, *, extra_columns: int = 0
) -> np.ndarray:
    """Regression matrix ``X_k`` (eq. 5-12) of one output channel for times ``start .. N-1``.

    Parameters
    ----------
    u, y : ndarray (N, nu), (N, ny)
        Inputs and outputs, time on axis 0.
    channel : ChannelStructure
        Regressors and term table of the channel.
    start : int
        First time index used (>= the channel's largest lag).
    extra_columns : int
        Allocate this many trailing, uninitialised columns (e.g. for an augmented ``[X | Y]``
        factorisation without a copy).

    Returns
    -------
    ndarray (N - start, n_terms + extra_columns), Fortran-ordered.

    Raises
    ------
    IdentificationError
        When the matrix would exceed the memory budget (:mod:`identification.budget`).
    """
    rows, cols = u.shape[0] - start, channel.n_terms + extra_columns
    check_allocation(
        product(rows, cols, 8),
        f"the regression matrix ({rows:,} rows x {cols:,} terms x 8 bytes)",
        "use fewer terms (lower order or degree, or a smaller term set) or a shorter record",
    )
    Z = lagged_regressors(u, y, channel.regressors, start, channel.functions, channel.breakpoints)
    out = np.empty((Z.shape[0], channel.n_terms + extra_columns), order="F")
    expand_terms(Z, channel.terms, out)
    return out
