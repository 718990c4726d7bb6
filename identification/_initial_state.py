"""Least-squares estimate of a free run's initial state (internal; see
:meth:`identification.Narx.estimate_initial_state`).

The initial state of a NARX free run that starts at sample 0 is the ``p = max_lag`` past outputs
``y(-p) .. y(-1)`` (the past inputs are taken as zero, as :meth:`~identification.Narx.simulate`
does for a zero past). It is chosen to make the free run over the first ``n`` samples fit the
measured outputs in weighted least squares,

    x* = argmin_x  sum_{t < n} sum_k  w_k^2 (y_k(t) - yhat_k(t; x))^2,   w_k = 1 / std(y_k[:n]).

When every term holds at most one past-output factor, untransformed (ARX, ``kind=
"input-polynomial"``, and ``y*u`` products too), the free run is *affine* in ``x``:
``yhat(x) = yhat(0) + S x`` exactly, so the columns of ``S`` are free-run differences and ``x*``
is one linear least-squares solution (when ``S`` is rank deficient, the minimum-norm one in
column-equilibrated units: a past output no term reaches, e.g. ``y(-3)`` when the output lags stop
at 2 but an input lag reaches 3, is returned as 0).
Otherwise ``x*`` is found by :func:`scipy.optimize.least_squares` (trust-region reflective,
finite-difference Jacobian) started from zero and from the affine estimate at zero (the linear
estimate), and the better of the two is kept.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from scipy import linalg, optimize

from .errors import IdentificationError

_DIVERGED = 1e6  # residual of a trial state whose free run diverged (the weighted ones are O(1))


def estimate_state(
    run: Callable[[np.ndarray], np.ndarray | None],
    y: np.ndarray,
    p: int,
    *,
    affine: bool,
) -> np.ndarray:
    """The (p, ny) initial state whose free run ``run`` best fits ``y`` (n, ny).

    Parameters
    ----------
    run : callable
        ``run(x)`` -> the free run (n, ny) from the state ``x`` (p, ny), None when it diverged.
    y : ndarray (n, ny)
        The measured outputs the free run is fitted to, n >= p.
    p : int
        Number of past samples in the state (the model's largest lag).
    affine : bool
        True when the free run is affine in the state (one linear least-squares solve).
    """
    n, ny = y.shape
    if p == 0:
        return np.zeros((0, ny))
    std = y.std(axis=0)
    w = 1.0 / np.where(std > 0, std, 1.0)
    amp = np.max(np.abs(y), axis=0)
    scale = np.tile(np.where(amp > 0, amp, 1.0), p)  # the state's natural size, row-major (p, ny)
    base = run(np.zeros((p, ny)))
    x_lin = None
    if base is not None:
        x_lin = _affine_estimate(run, y, base, w, scale)
    if affine:
        if x_lin is None:
            raise IdentificationError(
                "the free run from a zero initial state is not finite over the fitted samples: "
                "no initial state can be estimated (check the model's stability)"
            )
        return x_lin.reshape(p, ny)

    def residual(x):
        sim = run(x.reshape(p, ny))
        if sim is None:
            return np.full(n * ny, _DIVERGED)
        return ((y - sim) * w).ravel()

    best = None
    for x0 in (np.zeros(p * ny), x_lin):
        if x0 is None or not np.all(np.isfinite(x0)):
            continue
        sol = optimize.least_squares(
            residual, x0, x_scale=scale, method="trf", xtol=1e-14, ftol=1e-14, gtol=1e-14
        )
        if best is None or sol.cost < best.cost:
            best = sol
    return best.x.reshape(p, ny)


def _affine_estimate(run, y, base, w, scale) -> np.ndarray | None:
    """Linear least squares on the free-run differences ``S[:, i] = run(s_i e_i) - run(0)``
    (exact for a free run affine in the state; the linearisation's secant otherwise)."""
    n, ny = y.shape
    S = np.empty((n * ny, scale.size))
    for i, s in enumerate(scale):
        x = np.zeros(scale.size)
        x[i] = s
        sim = run(x.reshape(-1, ny))
        if sim is None:
            return None
        S[:, i] = ((sim - base) * w).ravel() / s
    target = ((y - base) * w).ravel()
    col = np.linalg.norm(S, axis=0)
    col = np.where(col > 0, col, 1.0)  # equilibrate the columns: min norm in balanced units
    sol, *_ = linalg.lstsq(S / col, target, cond=max(S.shape) * np.finfo(float).eps)
    return sol / col
