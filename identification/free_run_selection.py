"""Term selection by free-run (simulation) error, and model size by an information criterion.

FROLS (:mod:`identification.selection`) ranks candidate terms by how much of the output they
explain *one step ahead*; a term that predicts well can still simulate badly (and a model built
from such terms diverge). The simulation-error minimisation with pruning (SEMP) of Piroddi and
Spinelli (2003, "An identification algorithm for polynomial NARX models based on simulation
error minimization", Int. J. Control 76(17)) instead adds, at each step, the candidate whose
least-squares model has the smallest *free-run* error, then prunes every earlier term whose
removal does not make that error worse. Here it runs per output channel: the channel is
simulated with its own past outputs fed back and the other outputs (MIMO cross terms) taken as
measured, each candidate model fitted by least squares and free-run by the compiled plan
(:mod:`identification.simulation`); a diverging candidate scores ``inf``.

The model size along the path is chosen by an information criterion on the free-run residuals
(:func:`identification.validation.criterion_value`: AIC, AICc, BIC, FPE) or by PRESS (the
leave-one-out one-step error of the least-squares fit, :func:`identification.validation.press`).
:func:`criterion_path` gives the same choice on a FROLS ordering.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from .errors import IdentificationError, SimulationDivergedError
from .simulation import compile_plan, simulate_plan
from .structure import ChannelStructure
from .validation import criterion_value, press

__all__ = ["CRITERIA", "SelectionPath", "criterion_path", "simulation_selection"]

CRITERIA = ("aic", "aicc", "bic", "fpe", "press")


@dataclass(frozen=True)
class SelectionPath:
    """The terms of one channel chosen step by step, with each step's score.

    Attributes
    ----------
    steps : list of ndarray of int
        The selected candidate indices after each step (pruning may shrink a step's set).
    mse : ndarray
        Free-run (or, for a FROLS path, one-step) mean squared error after each step.
    criterion : ndarray
        The criterion value after each step (``nan`` when no criterion was asked for).
    chosen : int
        Index of the step kept.
    """

    steps: list
    mse: np.ndarray
    criterion: np.ndarray
    chosen: int

    @property
    def selected(self) -> np.ndarray:
        """The candidate indices of the step kept (``steps[chosen]``)."""
        return self.steps[self.chosen]


def check_criterion(criterion) -> None:
    """Raise :class:`IdentificationError` unless ``criterion`` is None or one of :data:`CRITERIA`.

    Parameters
    ----------
    criterion : str or None
        A term-count criterion name (``"aic"``, ``"aicc"``, ``"bic"``, ``"fpe"``, ``"press"``).
    """
    if criterion is not None and criterion not in CRITERIA:
        raise IdentificationError(
            f"criterion must be one of {CRITERIA} or None, got {criterion!r}"
        )


def _siso_view(ch: ChannelStructure, k: int, ny: int, u, y):
    """Channel k as a single-output model (its own output fed back, other outputs as inputs):
    the remapped structure (functions and breakpoints kept) and its input record."""
    others = [j for j in range(ny) if j != k]
    src = ch.regressors[:, 0].copy()
    new = np.empty_like(src)
    new[src == k] = 0
    for pos, j in enumerate(others):
        new[src == j] = 1 + pos
    is_in = src >= ny
    new[is_in] = 1 + len(others) + (src[is_in] - ny)
    regs = np.column_stack([new, ch.regressors[:, 1]])
    inputs = np.column_stack([y[:, others], u]) if others else u
    return dataclasses.replace(ch, regressors=regs), np.ascontiguousarray(inputs)


class _FreeRunScorer:
    """Least squares + compiled free run of one channel's candidate term subsets."""

    def __init__(self, siso: ChannelStructure, X, inputs, yk, start, bound):
        self.siso, self.X, self.inputs = siso, X, inputs
        self.yk = np.ascontiguousarray(yk[:, None])
        self.target = yk[start:]
        self.start, self.bound = start, np.array([bound])

    def fit(self, cols):
        coef, *_ = np.linalg.lstsq(self.X[:, cols], self.target, rcond=None)
        return coef

    def score(self, cols) -> tuple[float, np.ndarray | None]:
        """Free-run MSE of the least-squares model on ``cols`` (inf when it diverges)."""
        cols = np.asarray(cols, dtype=np.int64)
        coef = self.fit(cols)
        sub = dataclasses.replace(self.siso, terms=self.siso.terms[cols])
        plan = compile_plan((sub,), (coef,), 1, self.inputs.shape[1])
        try:
            sim = simulate_plan(plan, self.inputs, self.yk[: self.start], self.bound, ("y",))
        except SimulationDivergedError:
            return np.inf, None
        resid = self.target - sim[self.start :, 0]
        return float(resid @ resid) / resid.size, resid


def _size_score(criterion, resid, cols, X, target) -> float:
    if criterion is None:
        return np.nan
    if criterion == "press":
        return float(press(X[:, cols], target).press)
    return criterion_value(criterion, resid, len(cols))


def simulation_selection(
    X: np.ndarray,
    ch: ChannelStructure,
    k: int,
    u: np.ndarray,
    y: np.ndarray,
    start: int,
    *,
    n_terms: int | None = None,
    criterion: str | None = "bic",
    tol: float = 1e-3,
    bound: float = np.inf,
) -> SelectionPath:
    """SEMP forward selection with pruning by free-run error for output channel ``k``.

    Parameters
    ----------
    X : ndarray (N - start, M)
        The channel's candidate regression matrix (one-step, measured outputs).
    ch : ChannelStructure
        The channel's candidate structure (``X``'s columns are its terms).
    k : int
        Output channel index.
    u : ndarray (N, nu)
        Identification input record.
    y : ndarray (N, ny)
        Identification output record (the measured past outputs of the free run's start).
    start : int
        First simulated sample (the largest lag); earlier outputs are the measured ones.
    n_terms : int, optional
        Longest path (default: min(M, 40)).
    criterion : {"aic", "aicc", "bic", "fpe", "press"} or None
        Size choice along the path; None keeps the last step.
    tol : float
        The path also ends when a step lowers the free-run MSE by less than this fraction.
    bound : float
        Free-run bound of the channel (a candidate leaving it scores inf).
    """
    check_criterion(criterion)
    M = X.shape[1]
    n_max = min(M, 40 if n_terms is None else int(n_terms))
    target = y[start:, k]
    siso, inputs = _siso_view(ch, k, y.shape[1], u, y)
    scorer = _FreeRunScorer(siso, X, inputs, y[:, k], start, bound)
    selected: list[int] = []
    steps, mses, crits = [], [], []
    current = np.inf
    while len(selected) < n_max:
        best, best_j, best_resid = np.inf, -1, None
        for j in range(M):
            if j in selected:
                continue
            v, resid = scorer.score([*selected, j])
            if v < best:
                best, best_j, best_resid = v, j, resid
        if best_j < 0 or not np.isfinite(best):
            break
        if np.isfinite(current) and best > current * (1.0 - tol):
            break
        selected.append(best_j)
        current, resid = best, best_resid
        for i in list(selected[:-1]):  # pruning: drop terms the new one made redundant
            rest = [c for c in selected if c != i]
            v, r = scorer.score(rest)
            if v <= current:
                selected, current, resid = rest, v, r
        steps.append(np.array(selected, dtype=np.int64))
        mses.append(current)
        crits.append(_size_score(criterion, resid, selected, X, target))
    if not steps:
        raise IdentificationError(
            f"output channel {k}: no candidate term gives a bounded free run; lower the "
            "degree or the order, or check the record"
        )
    crit = np.array(crits)
    chosen = len(steps) - 1 if criterion is None else int(np.nanargmin(crit))
    return SelectionPath(steps, np.array(mses), crit, chosen)


def criterion_path(X, target, selected, err, criterion) -> int:
    """Number of FROLS terms (a prefix of ``selected``) that minimises ``criterion``.

    The one-step residual energy after n terms is ``(1 - sum(err[:n])) * |target|^2`` (the
    error-reduction ratios add up); PRESS refits each prefix.

    Parameters
    ----------
    X : ndarray (N, M)
        The candidate regression matrix (one-step, measured outputs).
    target : ndarray (N,)
        The channel's measured output (the regression target).
    selected : sequence of int
        The candidate indices in the order FROLS chose them.
    err : ndarray
        Error-reduction ratio of each selected term, in the same order.
    criterion : {"aic", "aicc", "bic", "fpe", "press"}
        The criterion minimised over the prefixes.
    """
    check_criterion(criterion)
    energy = float(target @ target)
    n = target.size
    best, best_n = np.inf, len(selected)
    for m in range(1, len(selected) + 1):
        if criterion == "press":
            v = float(press(X[:, selected[:m]], target).press)
        else:
            sigma2 = max(1.0 - float(np.sum(err[:m])), 1e-300) * energy / n
            v = _criterion_from_variance(criterion, sigma2, n, m)
        if v < best:
            best, best_n = v, m
    return best_n


def _criterion_from_variance(name: str, sigma2: float, n: int, p: int) -> float:
    """The criteria of :func:`identification.validation.information_criteria` from sigma^2."""
    if n - p - 1 <= 0:
        return np.inf
    if name == "aic":
        return n * np.log(sigma2) + 2 * p
    if name == "aicc":
        return n * np.log(sigma2) + 2 * p + 2 * p * (p + 1) / (n - p - 1)
    if name == "bic":
        return n * np.log(sigma2) + p * np.log(n)
    return sigma2 * (n + p) / (n - p)  # fpe
