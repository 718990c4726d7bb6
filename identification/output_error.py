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

import time
from dataclasses import dataclass, field

import numpy as np
from scipy import linalg

from ._sensitivity import simulate_with_sensitivity
from .budget import check_allocation, product
from .errors import IdentificationError, SimulationDivergedError
from .simulation import compile_plan, simulate_plan

__all__ = ["FlatModel", "RefinementResult", "check_refinement_budget", "refine", "simulation_error"]


@dataclass(frozen=True, eq=False)
class FlatModel:
    """All channels of a condensed model as flat arrays for the compiled kernel.

    Parameters
    ----------
    ny : int
        Number of output channels.
    max_lag : int
        Largest lag of any regressor, in samples.
    reg_src, reg_lag, reg_fn, reg_bp : ndarray (R,)
        Every channel's regressors, concatenated: source index (outputs first, then inputs), lag
        in samples, function code (0: identity) and breakpoint (in the source's units).
    reg_ptr : ndarray (ny + 1,)
        Channel k's regressors are ``reg_ptr[k]:reg_ptr[k + 1]``.
    terms : ndarray (P, L_max)
        Every channel's terms as 1-based regressor indices, left-padded with 0 (the constant
        factor) to the largest degree.
    term_ptr : ndarray (ny + 1,)
        Channel k's terms (and coefficients) are ``term_ptr[k]:term_ptr[k + 1]``.
    channels : tuple of ChannelStructure
        The structure of each output channel (for the fast plan-based free run).
    nu : int
        Number of input channels.
    """

    ny: int
    max_lag: int
    reg_src: np.ndarray
    reg_lag: np.ndarray
    reg_fn: np.ndarray
    reg_bp: np.ndarray
    reg_ptr: np.ndarray
    terms: np.ndarray  # (P, L_max), padded with 0 (the constant factor)
    term_ptr: np.ndarray
    channels: tuple  # the ChannelStructure of each output (for the fast plan-based free run)
    nu: int

    @classmethod
    def from_channels(cls, channels, ny: int, nu: int) -> FlatModel:
        """Build the flat arrays from one :class:`ChannelStructure` per output channel.

        Parameters
        ----------
        channels : sequence of ChannelStructure
            The structure of each output channel.
        ny, nu : int
            Numbers of output and input channels.
        """
        L = max(ch.degree for ch in channels)
        src, lag, fn, bp, rptr = [], [], [], [], [0]
        rows, tptr = [], [0]
        for ch in channels:
            R = ch.n_regressors
            src.append(ch.regressors[:, 0])
            lag.append(ch.regressors[:, 1])
            fn.append(ch.functions)  # non-polynomial regressor functions (0 = identity)
            bp.append(ch.breakpoints)
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
            channels=tuple(channels),
            nu=int(nu),
        )

    @property
    def n_params(self) -> int:
        """Number of coefficients over all channels (P)."""
        return int(self.term_ptr[-1])

    def split(self, theta: np.ndarray) -> tuple[np.ndarray, ...]:
        """Flat parameter vector -> one coefficient vector per channel.

        Parameters
        ----------
        theta : ndarray (P,)
            Coefficients of all channels, flat.
        """
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

    Parameters
    ----------
    flat : FlatModel
        The condensed model structure.
    theta : ndarray (P,)
        Coefficients of all channels, flat.
    u : ndarray (N, nu)
        Input record.
    y : ndarray (N, ny)
        Measured output record (the start of every segment and the reference of ``e``).
    horizon : int, optional
        Truncated horizon in samples: segments restarted from the measured outputs (default
        the whole record).
    weight : ndarray (ny,), optional
        Weight of each output channel's residuals (default 1).
    bound : ndarray (ny,), optional
        Free-run magnitude bound per channel, in the output's units (default finite only).
    jacobian : bool, optional
        Also compute the sensitivity Jacobian ``J``.
    """
    N, ny = y.shape
    p = flat.max_lag
    h = N if horizon is None else int(horizon)
    w = np.ones(ny) if weight is None else np.asarray(weight, dtype=np.float64)
    b = np.full(ny, np.inf) if bound is None else np.asarray(bound, dtype=np.float64)
    rows = (N - p) * ny
    if jacobian:
        check_refinement_budget(rows, flat.n_params)
    if not jacobian and h >= N:  # one segment: the compiled plan-based free run is faster
        return _plan_error(flat, theta, u, y, w, b)
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


def _plan_error(flat: FlatModel, theta, u, y, w, b):
    p = flat.max_lag
    plan = compile_plan(flat.channels, flat.split(theta), flat.ny, flat.nu)
    try:
        yhat = simulate_plan(plan, u, y[:p], b, [str(k) for k in range(flat.ny)])
    except SimulationDivergedError:
        return None, None, None
    return ((y[p:] - yhat[p:]) * w).ravel(), None, yhat


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
        True when the last stage stopped on ``tol`` (not on ``max_iter`` or early stopping).
    history : list of float
        Cost after each accepted step.
    kept_step : int or None
        With early stopping: the accepted step of the last stage that was kept, the latest
        whose held-out free-run error is within 1 % of the best (0: the stage's starting
        coefficients, i.e. refinement made the held-out error worse; a short or
        unrepresentative held-out part can cause that: try ``holdout=0``). None without a
        holdout.
    timed_out : bool
        The ``deadline`` passed before the iterations ended (the result is the best iterate
        reached by then).
    """

    theta: np.ndarray
    cost: float
    initial_cost: float
    iterations: int
    horizons: list[int]
    covariance: np.ndarray | None
    converged: bool
    history: list[float] = field(default_factory=list)
    kept_step: int | None = None
    timed_out: bool = False


def check_refinement_budget(rows: int, n_params: int) -> None:
    """An :class:`~identification.errors.IdentificationError` when the output-error Jacobian
    (``rows`` residuals x ``n_params`` parameters, float64) would exceed the memory budget
    (:func:`~identification.budget.check_allocation`); :meth:`Narx.fit` calls it before the
    least-squares start, so that a refinement too large is refused at once.

    Parameters
    ----------
    rows : int
        Residuals: the record's samples after the largest lag, times the outputs.
    n_params : int
        The model's parameters (all channels).
    """
    check_allocation(
        product(rows, n_params, 8),
        f"the output-error Jacobian ({rows:,} residuals x {n_params:,} parameters x 8 bytes)",
        "shorten the record, select fewer terms (n_terms=...) or fit with focus='prediction'",
    )


class _Monitor:
    """Early stopping on a held-out record.

    Every accepted iterate's free-run error on the held-out part is recorded; the stage stops
    when it has not improved for ``patience`` steps, and :meth:`choice` keeps the *latest*
    iterate within ``flat`` (1 %) of the best held-out error: a flat held-out error is noise,
    not over-fitting, and the further-refined iterate is kept.
    """

    def __init__(self, flat, u, y, w, bound, patience: int = 5, flat_tol: float = 0.01):
        self.flat, self.u, self.y, self.w, self.bound = flat, u, y, w, bound
        self.patience, self.flat_tol = patience, flat_tol
        self.thetas: list[np.ndarray] = []
        self.scores: list[float] = []

    def score(self, theta) -> float:
        e, _, _ = simulation_error(
            self.flat, theta, self.u, self.y, weight=self.w, bound=self.bound
        )
        return float(e @ e) if e is not None else np.inf

    def update(self, theta) -> bool:
        """Record ``theta``; True when the held-out error has not improved for ``patience``."""
        self.thetas.append(theta.copy())
        self.scores.append(self.score(theta))
        best = int(np.argmin(self.scores))
        return len(self.scores) - 1 - best >= self.patience

    def choice(self) -> int | None:
        """Index of the iterate to keep (None when nothing was recorded or all diverged)."""
        if not self.scores or not np.isfinite(min(self.scores)):
            return None
        limit = min(self.scores) * (1.0 + self.flat_tol)
        return max(i for i, v in enumerate(self.scores) if v <= limit)


def _lm_step(A, grad, mu):
    """Solve ``(A + mu diag(A)) delta = grad`` with Marquardt's scaling; None if singular."""
    d = np.diag(A).copy()
    d = np.maximum(d, 1e-14 * max(float(d.max()), 1e-300))
    s = 1.0 / np.sqrt(d)
    As = A * s[:, None] * s[None, :]
    As[np.diag_indices_from(As)] += mu
    try:
        x = linalg.cho_solve(
            linalg.cho_factor(As, check_finite=False), grad * s, check_finite=False
        )
    except linalg.LinAlgError:
        return None, d
    return s * x, d


def _lm_stage(flat, theta, data, horizon, max_iter, tol, monitor=None):
    """Levenberg-Marquardt at one horizon (Marquardt scaling, Nielsen's damping update).

    Solves ``(J^T J + mu diag(J^T J)) delta = J^T e``; a trial whose free run leaves the bound,
    or that ``feasible`` (the last item of ``data``, None: no constraint) refuses, is rejected.
    With a ``monitor`` the stage also stops when the held-out error has not improved for its
    patience (early stopping). Returns ``(theta, cost, its, converged, hist)``.
    """
    u, y, w, bound, feasible, deadline = data

    def evaluate(th, jac):
        if not jac and feasible is not None and not feasible(th):
            return None, None, None
        return simulation_error(
            flat, th, u, y, horizon=horizon, weight=w, bound=bound, jacobian=jac
        )

    e, J, _ = evaluate(theta, True)
    if e is None:
        return theta, np.inf, 0, False, []
    if monitor is not None:
        monitor.update(theta)
    cost, A, grad = float(e @ e), J.T @ J, J.T @ e
    mu, nu, its, history = 1e-3, 2.0, 0, []
    while its < max_iter:
        if deadline is not None and time.perf_counter() > deadline:
            return theta, cost, its, False, history
        its += 1
        delta, d = _lm_step(A, grad, mu)
        if delta is None:
            mu, nu = mu * nu, nu * 2.0
            continue
        e_t, _, _ = evaluate(theta + delta, False)
        cost_t = float(e_t @ e_t) if e_t is not None else np.inf
        predicted = float(delta @ (mu * d * delta + grad))
        rho = (cost - cost_t) / predicted if predicted > 0 else -1.0
        if not (rho > 0 and np.isfinite(cost_t)):
            mu, nu = mu * nu, nu * 2.0
            if mu > 1e12:  # no descent direction left at working precision
                return theta, cost, its, True, history
            continue
        rel = (cost - cost_t) / max(cost, 1e-300)
        theta, cost = theta + delta, cost_t
        e, J, _ = evaluate(theta, True)
        A, grad = J.T @ J, J.T @ e
        mu *= max(1.0 / 3.0, 1.0 - (2.0 * rho - 1.0) ** 3)
        nu = 2.0
        history.append(cost)
        if monitor is not None and monitor.update(theta):
            return theta, cost, its, True, history
        if rel < tol:
            return theta, cost, its, True, history
    return theta, cost, its, False, history


def _horizon_schedule(start: int, n: int) -> list[int]:
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
    tol: float = 1e-5,
    bound: np.ndarray | None = None,
    holdout: float = 0.0,
    feasible=None,
    deadline: float | None = None,
) -> RefinementResult:
    """Minimise the free-run error of ``flat`` over the record ``u, y`` from ``theta0``.

    Parameters
    ----------
    flat : FlatModel
        The condensed model structure (all channels).
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
        Stop a stage when an accepted step lowers the cost by less than this fraction (a step
        criterion relative to ``|theta|`` is meaningless for ill-conditioned polynomial models,
        whose large coefficients cancel).
    bound : ndarray (ny,), optional
        Free-run bound per channel; a trial leaving it is rejected (default: finite only).
    holdout : float
        Fraction of the record (its end) held out for early stopping: the last stage stops when
        the free-run error on the held-out part has not improved for 5 accepted steps and keeps
        the latest iterate within 1 % of the best held-out error. 0: no early stopping, the
        whole record is fitted.
    feasible : callable, optional
        A constraint ``feasible(theta) -> bool`` (e.g. a bounded free run on other inputs):
        every trial step it refuses is rejected like a diverging one, so from a feasible
        ``theta0`` every accepted iterate, hence the result, is feasible (a descent method
        kept inside the feasible set; no projection). Default: no constraint.
    deadline : float, optional
        A ``time.perf_counter()`` value after which no further iteration starts; the result is
        then the best iterate reached (early stopping's choice still applies) and says
        ``timed_out``. Default: no deadline.
    """
    N, ny = y.shape
    p = flat.max_lag
    check_refinement_budget((N - p) * ny, flat.n_params)
    std = y[p:].std(axis=0)
    w = 1.0 / np.where(std > 0, std, 1.0)
    monitor = None
    if holdout > 0:
        cut = round(N * (1.0 - holdout))
        if cut - p < 2 * flat.n_params or N - cut < 4 * p + 10:
            raise IdentificationError(
                f"holdout={holdout} leaves too few samples to fit {flat.n_params} parameters "
                f"({cut - p}) or to validate ({N - cut}); lower it or use a longer record"
            )
        monitor = _Monitor(flat, u[cut - p :], y[cut - p :], w, bound)
        u, y, N = u[:cut], y[:cut], cut
    data = (u, y, w, bound, feasible, deadline)
    theta = np.array(theta0, dtype=np.float64)
    full = N if horizon is None else min(int(horizon), N)
    e0, _, _ = simulation_error(flat, theta, u, y, horizon=full, weight=w, bound=bound)
    initial = float(e0 @ e0) if e0 is not None else np.inf
    if horizon is not None or e0 is not None:
        stages = [full]
    else:  # continuation from the longest short horizon (<= 10, >= 2) with a finite cost
        h0 = max(10, 2 * p)
        while (
            h0 > 2
            and simulation_error(flat, theta, u, y, horizon=h0, weight=w, bound=bound)[0] is None
        ):
            h0 //= 2
        stages = _horizon_schedule(max(h0, 2), N)
    total, history, converged, cost = 0, [], False, np.inf
    for i, h in enumerate(stages):
        last = i == len(stages) - 1
        its_h = max_iter if last else max(5, max_iter // 5)  # continuation stages: a few
        theta, cost, its, converged, hist = _lm_stage(
            flat, theta, data, h, its_h, tol, monitor if last else None
        )
        total += its
        history += hist
    kept = None if monitor is None else monitor.choice()
    if kept is not None:
        theta = monitor.thetas[kept]
        e, _, _ = simulation_error(flat, theta, u, y, horizon=stages[-1], weight=w, bound=bound)
        cost = float(e @ e) if e is not None else np.inf
    cov = None
    if np.isfinite(cost):
        e, J, _ = simulation_error(
            flat, theta, u, y, horizon=stages[-1], weight=w, bound=bound, jacobian=True
        )
        cov = _covariance(e, J, flat)
    late = deadline is not None and time.perf_counter() > deadline
    return RefinementResult(
        theta, cost, initial, total, stages, cov, converged, history, kept, late and not converged
    )


def _covariance(e, J, flat: FlatModel):
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
