"""Output-error (simulation-error) refinement of NARX coefficients by Levenberg-Marquardt.

Least squares on the regression matrix minimises the *one-step-ahead* prediction error. When
the noise is on the measured output (a transducer's noise, the normal case on a rig) that
estimate is biased, and its free run can be poor or unstable. :func:`refine` starts from it and
minimises the *free-run* (simulation) error over the record,

    V(theta) = sum_t sum_k  w_k^2 (y_k(t) - yhat_k(t; theta))^2,   w_k = 1 / std(y_k),

with a Levenberg-Marquardt loop whose Jacobian comes from the compiled sensitivity recursion
(:mod:`identification._sensitivity`; exact, no finite differences). MIMO, non-square and
cross-coupled outputs are handled jointly (one parameter vector over all channels).

Long or marginally stable records use a **truncated horizon**: the record is cut into
segments of H samples, each restarted from the measured outputs (multiple shooting without the
continuity constraints). H = 1 is the least-squares cost and H >= N pure output error. A model
whose least-squares free run diverges is refined along a horizon *continuation* (short horizons
first, then 4x longer, up to the whole record), each stage started from the previous one: a
short horizon keeps the cost finite while the dynamics are pulled towards a stable free run.

Why a hand-written LM rather than ``scipy.optimize.least_squares``: a trial step whose free run
diverges has no finite residual and must simply be rejected (MINPACK's ``lm`` cannot, ``trf``
can); and the normal equations with Marquardt's diagonal scaling cost one BLAS ``J^T J`` per
accepted step, where ``trf``'s exact solver takes an SVD of J per iteration (5-10x slower at the
sizes here). The Jacobian itself is checked against finite differences in the tests.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy import linalg

from ._sensitivity import simulate_with_sensitivity
from .errors import IdentificationError

__all__ = ["FlatModel", "RefinementResult", "refine", "simulation_error"]

_J_BUDGET_BYTES = 2 * 2**30  # refuse a Jacobian beyond 2 GiB


@dataclass(frozen=True, eq=False)
class FlatModel:
    """All channels of a condensed model as flat arrays for the compiled kernel."""

    ny: int
    max_lag: int
    reg_src: np.ndarray
    reg_lag: np.ndarray
    reg_fn: np.ndarray
    reg_bp: np.ndarray
    reg_ptr: np.ndarray
    terms: np.ndarray  # (P, L_max), padded with 0 (the constant factor)
    term_ptr: np.ndarray

    @classmethod
    def from_channels(cls, channels, ny: int) -> FlatModel:
        L = max(ch.degree for ch in channels)
        src, lag, fn, bp, rptr = [], [], [], [], [0]
        rows, tptr = [], [0]
        for ch in channels:
            R = ch.n_regressors
            src.append(ch.regressors[:, 0])
            lag.append(ch.regressors[:, 1])
            fn.append(getattr(ch, "functions", None) if getattr(ch, "functions", None) is not None else np.zeros(R, np.int64))
            bp.append(getattr(ch, "breakpoints", None) if getattr(ch, "breakpoints", None) is not None else np.zeros(R))
            rptr.append(rptr[-1] + R)
            t = np.zeros((ch.n_terms, L), dtype=np.int64)
            t[:, L - ch.degree :] = ch.terms
            rows.append(t)
            tptr.append(tptr[-1] + ch.n_terms)
        i64 = np.int64
        return cls(
            ny=ny,
            max_lag=max(ch.max_lag for ch in channels),
            reg_src=np.ascontiguousarray(np.concatenate(src), dtype=i64),
            reg_lag=np.ascontiguousarray(np.concatenate(lag), dtype=i64),
            reg_fn=np.ascontiguousarray(np.concatenate(fn), dtype=i64),
            reg_bp=np.ascontiguousarray(np.concatenate(bp), dtype=np.float64),
            reg_ptr=np.array(rptr, dtype=i64),
            terms=np.ascontiguousarray(np.concatenate(rows), dtype=i64),
            term_ptr=np.array(tptr, dtype=i64),
        )

    @property
    def n_params(self) -> int:
        return int(self.term_ptr[-1])

    def split(self, theta: np.ndarray) -> tuple[np.ndarray, ...]:
        """Flat parameter vector -> one coefficient vector per channel."""
        return tuple(
            np.ascontiguousarray(theta[a:b])
            for a, b in zip(self.term_ptr[:-1], self.term_ptr[1:], strict=True)
        )


def simulation_error(
    flat: FlatModel,
    theta: np.ndarray,
    u: np.ndarray,
    y: np.ndarray,
    *,
    horizon: int | None = None,
    weight: np.ndarray | None = None,
    bound: np.ndarray | None = None,
    jacobian: bool = False,
):
    """Weighted free-run residuals (and their Jacobian) of the flat model on a record.

    Returns ``(e, J, yhat)``: ``e`` (rows,) with rows ``(t - max_lag) * ny + k``, ``J`` (rows, P)
    ``= d yhat / d theta`` weighted like ``e`` (None unless ``jacobian``), ``yhat`` (N, ny) with
    the first ``max_lag`` rows equal to ``y``. ``e`` is None when the free run left ``bound``.
    """
    N, ny = y.shape
    p = flat.max_lag
    h = N if horizon is None else int(horizon)
    w = np.ones(ny) if weight is None else np.asarray(weight, dtype=np.float64)
    b = np.full(ny, np.inf) if bound is None else np.asarray(bound, dtype=np.float64)
    rows = (N - p) * ny
    E = np.empty(rows)
    J = np.empty((rows, flat.n_params) if jacobian else (1, 1))
    Yhat = np.array(y, dtype=np.float64, order="C")
    k, _t = simulate_with_sensitivity(
        np.ascontiguousarray(u, dtype=np.float64),
        np.ascontiguousarray(y, dtype=np.float64),
        p,
        max(h, 1),
        flat.reg_src,
        flat.reg_lag,
        flat.reg_fn,
        flat.reg_bp,
        flat.reg_ptr,
        flat.terms,
        flat.term_ptr,
        np.ascontiguousarray(theta, dtype=np.float64),
        w,
        b,
        jacobian,
        Yhat,
        E,
        J,
    )
    if k >= 0:
        return None, None, Yhat
    return E, (J if jacobian else None), Yhat


@dataclass
class RefinementResult:
    """What :func:`refine` did.

    Attributes
    ----------
    theta : ndarray (P,)
        The refined coefficients (all channels, flat).
    cost : float
        Final weighted sum of squared free-run errors (whole record, ``horizon`` of the last stage).
    initial_cost : float
        The same cost at the starting coefficients (``inf`` when their free run diverged).
    iterations : int
        Levenberg-Marquardt iterations over all stages.
    horizons : list of int
        The horizon of each continuation stage (the last one is the record length for a full
        output-error fit).
    covariance : ndarray (P, P) or None
        Asymptotic covariance of the estimate, ``sigma^2 (J^T J)^-1`` at the optimum with
        ``sigma^2`` the residual variance (output-error noise model), in the original units.
    converged : bool
    history : list of float
        Cost after each accepted step.
    """

    theta: np.ndarray
    cost: float
    initial_cost: float
    iterations: int
    horizons: list[int]
    covariance: np.ndarray | None
    converged: bool
    history: list[float] = field(default_factory=list)


def _check_budget(rows: int, n_params: int) -> None:
    need = 8 * rows * n_params
    if need > _J_BUDGET_BYTES:
        raise IdentificationError(
            f"the output-error Jacobian would take {need / 2**30:.1f} GiB ({rows} residuals x "
            f"{n_params} parameters; budget {_J_BUDGET_BYTES / 2**30:.0f} GiB): shorten the "
            "record, select fewer terms (n_terms=...) or fit with focus='prediction'"
        )


def _lm_stage(flat, theta, u, y, horizon, w, bound, max_iter, tol):
    """Levenberg-Marquardt at one horizon (Marquardt scaling, Nielsen's damping update).

    Solves ``(J^T J + mu diag(J^T J)) delta = J^T e`` in the scaled variables
    ``x = sqrt(diag(J^T J)) * delta``; a trial whose free run leaves ``bound`` is rejected.
    Returns ``(theta, cost, iterations, converged, history)``.
    """
    e, J, _ = simulation_error(
        flat, theta, u, y, horizon=horizon, weight=w, bound=bound, jacobian=True
    )
    if e is None:
        return theta, np.inf, 0, False, []
    cost = float(e @ e)
    A, grad = J.T @ J, J.T @ e
    mu, nu = 1e-3, 2.0
    history: list[float] = []
    its = 0
    while its < max_iter:
        its += 1
        d = np.diag(A).copy()
        d = np.maximum(d, 1e-14 * max(float(d.max()), 1e-300))
        s = 1.0 / np.sqrt(d)
        As = A * s[:, None] * s[None, :]
        As[np.diag_indices_from(As)] += mu
        try:
            delta = s * linalg.cho_solve(
                linalg.cho_factor(As, check_finite=False), grad * s, check_finite=False
            )
        except linalg.LinAlgError:
            mu, nu = mu * nu, nu * 2.0
            continue
        if np.linalg.norm(delta) <= tol * (np.linalg.norm(theta) + tol):
            return theta, cost, its, True, history
        trial = theta + delta
        e_t, _, _ = simulation_error(flat, trial, u, y, horizon=horizon, weight=w, bound=bound)
        cost_t = float(e_t @ e_t) if e_t is not None else np.inf
        predicted = float(delta @ (mu * d * delta + grad))
        rho = (cost - cost_t) / predicted if predicted > 0 else -1.0
        if rho > 0 and np.isfinite(cost_t):
            rel = (cost - cost_t) / max(cost, 1e-300)
            theta, cost = trial, cost_t
            e, J, _ = simulation_error(
                flat, theta, u, y, horizon=horizon, weight=w, bound=bound, jacobian=True
            )
            A, grad = J.T @ J, J.T @ e
            mu *= max(1.0 / 3.0, 1.0 - (2.0 * rho - 1.0) ** 3)
            nu = 2.0
            history.append(cost)
            if rel < tol:
                return theta, cost, its, True, history
        else:
            mu, nu = mu * nu, nu * 2.0
            if mu > 1e12:  # no descent direction left at working precision
                return theta, cost, its, True, history
    return theta, cost, its, False, history


def _horizon_schedule(start: int, n: int, max_lag: int) -> list[int]:
    h, out = start, []
    while h < n:
        out.append(h)
        h *= 4
    return [*out, n]


def refine(
    flat: FlatModel,
    theta0: np.ndarray,
    u: np.ndarray,
    y: np.ndarray,
    *,
    horizon: int | None = None,
    max_iter: int = 50,
    tol: float = 1e-6,
    bound: np.ndarray | None = None,
) -> RefinementResult:
    """Minimise the free-run error of ``flat`` over the record ``u, y`` from ``theta0``.

    Parameters
    ----------
    flat : FlatModel
    theta0 : ndarray (P,)
        Starting coefficients (the least-squares estimate).
    u, y : ndarray (N, nu), (N, ny)
        Identification record; every segment starts from the measured outputs.
    horizon : int, optional
        Fixed truncated horizon in samples. Default: the whole record, reached by continuation
        from ``max(10, 2 * max_lag)`` samples (x4 per stage) when the free run of ``theta0``
        over the whole record diverges, directly otherwise.
    max_iter : int
        Levenberg-Marquardt iterations per stage.
    tol : float
        Stop a stage when an accepted step lowers the cost by less than this fraction, or the
        step is below this fraction of ``|theta|``.
    bound : ndarray (ny,), optional
        Free-run bound per channel; a trial leaving it is rejected (default: finite only).
    """
    N, ny = y.shape
    p = flat.max_lag
    _check_budget((N - p) * ny, flat.n_params)
    std = y[p:].std(axis=0)
    w = 1.0 / np.where(std > 0, std, 1.0)
    theta = np.array(theta0, dtype=np.float64)
    full = N if horizon is None else min(int(horizon), N)
    e0, _, _ = simulation_error(flat, theta, u, y, horizon=full, weight=w, bound=bound)
    initial = float(e0 @ e0) if e0 is not None else np.inf
    if horizon is not None or e0 is not None:
        stages = [full]
    else:
        stages = _horizon_schedule(max(10, 2 * p), N, p)
    total, history, converged, cost = 0, [], False, np.inf
    for h in stages:
        theta, cost, its, converged, hist = _lm_stage(
            flat, theta, u, y, h, w, bound, max_iter, tol
        )
        total += its
        history += hist
    cov = None
    if np.isfinite(cost):
        e, J, _ = simulation_error(
            flat, theta, u, y, horizon=stages[-1], weight=w, bound=bound, jacobian=True
        )
        cov = _covariance(e, J, flat, w, N - p)
    return RefinementResult(theta, cost, initial, total, stages, cov, converged, history)


def _covariance(e, J, flat: FlatModel, w, n_rows):
    """``sigma^2 (J^T J)^-1`` per channel's noise level, back in the original output units.

    With weights ``w_k`` the weighted residual variance is the same for every channel when the
    noise is proportional to each output's spread; the plain estimate is the mean square of the
    weighted residuals times ``n / (n - P)``.
    """
    P = flat.n_params
    dof = e.shape[0] - P
    if dof <= 0:
        return None
    sigma2 = float(e @ e) / dof
    try:
        return sigma2 * linalg.pinvh(J.T @ J)
    except (linalg.LinAlgError, ValueError):
        return None
