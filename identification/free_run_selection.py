"""Term selection by free-run (simulation) error, and model size by an information criterion.

FROLS (:mod:`identification.selection`) ranks candidate terms by how much of the output they
explain *one step ahead*; a term that predicts well can still simulate badly (and a model built
from such terms diverge). The simulation-error minimisation with pruning (SEMP) of Piroddi and
Spinelli (2003, "An identification algorithm for polynomial NARX models based on simulation
error minimization", Int. J. Control 76(17)) instead adds, at each step, the candidate whose
least-squares model has the smallest *free-run* error, then prunes every earlier term whose
removal does not make that error worse. Here it runs per output channel: the channel is
simulated with its own past outputs fed back and the other outputs (MIMO cross terms) taken as
measured, each candidate model fitted by least squares and free-run; a diverging candidate
scores ``inf``.

Scoring. By default (``screen="auto"``) the compiled scorer of :mod:`identification._semp`
scores the candidates: least squares of each subset from the Gram matrix (bordered Cholesky
solves of every candidate of a step at once, ``lstsq`` where a pivot is too small), a compiled
free run read from the term table, runs abandoned once their squared error exceeds the best
finished one of the step, candidates run in threads. It takes the same decisions as scoring
every subset exhaustively (up to rounding). ``screen=None`` is that exhaustive reference
(``lstsq``, :func:`~identification.simulation.compile_plan`,
:func:`~identification.simulation.simulate_plan` per subset).

Size. Before starting, the work of the path is estimated (:func:`selection_estimate`: samples x
candidates x steps x terms per subset, at a nominal rate, an upper bound). Past the budget
(:data:`SELECTION_BUDGET_S` estimated single-core seconds for the whole model, shared by its
output channels) each forward step scores by free run only a *shortlist*: the candidates of
largest one-step error-reduction ratio orthogonalised against the selected terms (FROLS's
ratio), as many as fit the budget (``SelectionPath.screened`` says how many); if even
:data:`MIN_SHORTLIST` candidates per step do not fit, :class:`IdentificationError` names the
estimate and what to change. Pruning always scores every selected term by its full free run.

The model size along the path is chosen by an information criterion on the free-run residuals
(:func:`identification.validation.criterion_value`: AIC, AICc, BIC, FPE) or by PRESS (the
leave-one-out one-step error of the least-squares fit, :func:`identification.validation.press`).
:func:`criterion_path` gives the same choice on a FROLS ordering.
"""

from __future__ import annotations

import contextlib
import contextvars
import dataclasses
import time
from dataclasses import dataclass

import numpy as np

from ._semp import CompiledScorer, estimate_seconds, path_work, scaled_lstsq
from .errors import IdentificationError, SimulationDivergedError
from .simulation import compile_plan, simulate_plan
from .structure import ChannelStructure
from .validation import criterion_value, press

__all__ = [
    "CRITERIA",
    "MIN_SHORTLIST",
    "SELECTION_BUDGET_S",
    "SelectionPath",
    "criterion_path",
    "screening",
    "selection_estimate",
    "simulation_selection",
]

CRITERIA = ("aic", "aicc", "bic", "fpe", "press")

SELECTION_BUDGET_S = 60.0
"""Estimated single-core seconds a free-run selection may take for a whole model (its output
channels share it) before its forward steps are screened to a shortlist; assign a new value to
change it (as :data:`identification.budget.MEMORY_BUDGET_BYTES`)."""
#: longest path when ``n_terms`` is not given (the criterion sizes it along the path)
DEFAULT_PATH = 40

MIN_SHORTLIST = 10
"""Fewest candidates a screened forward step scores by free run; a problem that does not fit
the budget even so is refused."""

_SCREEN: contextvars.ContextVar = contextvars.ContextVar("semp_screen", default="auto")


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
    screened : int or None
        Candidates scored by free run per forward step when the steps were screened to a
        shortlist (None: every candidate was scored).
    """

    steps: list
    mse: np.ndarray
    criterion: np.ndarray
    chosen: int
    screened: int | None = None

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


@contextlib.contextmanager
def screening(screen):
    """Within the block, :func:`simulation_selection` (hence ``Narx(selection="simulation")``)
    scores with ``screen`` unless given one: ``"auto"``, an int or None (the exhaustive
    reference scorer, e.g. to time or check the compiled one against it).

    >>> with screening(None):                                        # doctest: +SKIP
    ...     reference = Narx(2, 2, selection="simulation").fit(u, y)

    Parameters
    ----------
    screen : {"auto", None} or int
        As :func:`simulation_selection`'s ``screen``.
    """
    _check_screen(screen)
    token = _SCREEN.set(screen)
    try:
        yield
    finally:
        _SCREEN.reset(token)


def _check_screen(screen) -> None:
    if screen is None or (isinstance(screen, str) and screen == "auto"):
        return
    if isinstance(screen, bool) or not isinstance(screen, (int, np.integer)) or screen < 1:
        raise IdentificationError(
            f"screen must be 'auto', None or a number of candidates >= 1, got {screen!r}"
        )


def selection_estimate(
    n_samples: int, n_candidates: int, n_steps: int, cost: float = 1.5, shortlist=None
) -> float:
    """Estimated single-core seconds of a free-run selection path of one channel.

    An upper bound of the compiled scorer's work: every forward step k = 1 .. ``n_steps``
    scores each candidate left (or ``shortlist`` of them) by a free run of ``n_samples``
    samples with k terms, and each pruning k - 1 runs of k - 1 terms; a term costs ``cost``
    operations per sample, at :data:`identification._semp.TERM_RATE` operations per second;
    the least squares ``n_steps + 2`` passes over the regression matrix (``n_samples x
    n_candidates`` multiply-adds each, at :data:`identification._semp.GRAM_RATE`).

    Parameters
    ----------
    n_samples : int
        Samples of each free run (the record less the largest lag).
    n_candidates : int
        Candidate terms of the channel.
    n_steps : int
        Longest path (``n_terms``, default min(candidates, 40)).
    cost : float
        Mean operations per term and sample: 1 plus the mean number of output factors.
    shortlist : int, optional
        Candidates scored per forward step (default: every one left).
    """
    return estimate_seconds(n_samples, n_candidates, n_steps, cost, shortlist)


def _shortlist(screen, scorer, k: int, n_max: int, budget, ny: int) -> int | None:
    """Candidates per forward step (None: all), from ``screen`` and the size estimate."""
    _check_screen(screen)
    budget = SELECTION_BUDGET_S if budget is None else float(budget)
    if not budget > 0:
        raise IdentificationError(f"budget must be > 0 seconds, got {budget!r}")
    share = budget / ny
    n, M, cost = scorer.n, scorer.M, scorer.cost

    def est(m):
        return estimate_seconds(n, M, n_max, cost, m)

    if screen == "auto":
        if est(None) <= share:
            return None
        lo, hi = MIN_SHORTLIST, M  # largest m in [lo, hi] with est(m) <= share
        while lo < hi:
            mid = (lo + hi + 1) // 2
            lo, hi = (mid, hi) if est(mid) <= share else (lo, mid - 1)
        m = lo
    else:
        m = int(screen)
    if est(m) > share:
        ops = n * cost * path_work(M, n_max) + (n_max + 2) * n * M  # runs + least squares
        raise IdentificationError(
            f"free-run selection of output channel {k}: about {est(None):,.3g} s of "
            f"single-core work estimated ({n:,} samples x {M:,} candidate terms x up to {n_max} "
            f"steps: ~{ops:.2g} operations), {est(m):,.3g} s with {m} candidates per step, "
            f"beyond the budget of {share:.3g} s per channel ({budget:g} s for {ny} "
            "channel(s)): use fewer samples (a shorter or decimated record), a smaller "
            "n_terms, a lower order or degree, or selection='frols'; or raise "
            "identification.free_run_selection.SELECTION_BUDGET_S"
        )
    return m if m < M else None


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


class _ReferenceScorer:
    """The reference (exhaustive) scorer: for every subset, ``numpy.linalg.lstsq`` on its
    columns of ``X`` scaled to unit norm (as :mod:`identification.solvers` do),
    :func:`~identification.simulation.compile_plan` and
    :func:`~identification.simulation.simulate_plan` (``screen=None``)."""

    def __init__(self, siso: ChannelStructure, X, inputs, yk, start, bound):
        self.siso, self.X, self.inputs = siso, X, inputs
        self.yk = np.ascontiguousarray(yk[:, None])
        self.target = yk[start:]
        self.start, self.bound = start, np.array([bound])

    def fit(self, cols):
        return scaled_lstsq(self.X[:, cols], self.target)

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

    def forward(self, selected, cap):
        """Every candidate scored; ``(j, mse)`` of the best (``cap`` unused)."""
        best, best_j = np.inf, -1
        for j in range(self.X.shape[1]):
            if j in selected:
                continue
            v, _ = self.score([*selected, j])
            if v < best:
                best, best_j = v, j
        return best_j, best

    def prune(self, selected: list, current: float):
        """Drop, in order, each earlier term whose removal does not raise the free-run MSE."""
        for i in list(selected[:-1]):
            rest = [c for c in selected if c != i]
            v, _ = self.score(rest)
            if v <= current:
                selected, current = rest, v
        return selected, current

    def residual(self, cols) -> np.ndarray:
        """Free-run residual of the least-squares model on ``cols``."""
        return self.score(cols)[1]

    def close(self) -> None:
        """Nothing to release."""


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
    screen="default",
    budget: float | None = None,
    workers: int | None = None,
    deadline: float | None = None,
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
    screen : {"auto", None} or int, optional
        ``"auto"``: the compiled scorer (:mod:`identification._semp`) scores every candidate
        while the size estimate is within ``budget``, else a shortlist sized to fit it (see the
        module docstring); an int m: it scores the m candidates of largest one-step
        error-reduction ratio per forward step; None: the reference scorer (``lstsq``,
        ``compile_plan``, ``simulate_plan`` per subset; no estimate). Default: the value set by
        :func:`screening` (``"auto"``).
    budget : float, optional
        Estimated single-core seconds allowed for the whole model (``y``'s ``ny`` channels
        share it; default :data:`SELECTION_BUDGET_S`).
    workers : int, optional
        Threads scoring candidates (default: the CPU count).
    deadline : float, optional
        A ``time.perf_counter()`` value after which no further forward step starts (the
        estimate behind ``budget`` is nominal: on a loaded machine the path can run slower);
        the size is then chosen among the steps made. Default: none.

    Raises
    ------
    IdentificationError
        When even the smallest shortlist exceeds the budget (naming the estimate and what to
        change), or when no candidate gives a bounded free run.
    """
    check_criterion(criterion)
    if workers is not None and (
        isinstance(workers, bool) or not isinstance(workers, (int, np.integer)) or workers < 1
    ):
        raise IdentificationError(f"workers must be None or a number >= 1, got {workers!r}")
    M = X.shape[1]
    n_max = min(M, DEFAULT_PATH if n_terms is None else int(n_terms))
    target = y[start:, k]
    siso, inputs = _siso_view(ch, k, y.shape[1], u, y)
    screen = _SCREEN.get() if isinstance(screen, str) and screen == "default" else screen
    if screen is None:
        scorer = _ReferenceScorer(siso, X, inputs, y[:, k], start, bound)
        screened = None
    else:
        scorer = CompiledScorer(siso, X, inputs, y[:, k], start, bound, workers=workers)
        screened = scorer.shortlist = _shortlist(screen, scorer, k, n_max, budget, y.shape[1])
    try:
        steps, mses, crits = _semp_path(scorer, n_max, tol, criterion, X, target, deadline)
    finally:
        scorer.close()
    if not steps:
        raise IdentificationError(
            f"output channel {k}: no candidate term gives a bounded free run; lower the "
            "degree or the order, or check the record"
        )
    crit = np.array(crits)
    chosen = len(steps) - 1 if criterion is None else int(np.nanargmin(crit))
    return SelectionPath(steps, np.array(mses), crit, chosen, screened)


def _semp_path(scorer, n_max: int, tol: float, criterion, X, target, deadline=None):
    """The SEMP path: forward steps by free-run MSE, each followed by pruning; no step starts
    after ``deadline`` once one was made."""
    selected: list[int] = []
    steps, mses, crits = [], [], []
    current = np.inf
    while len(selected) < n_max:
        if steps and deadline is not None and time.perf_counter() > deadline:
            break
        cap = current * (1.0 - tol) if np.isfinite(current) else np.inf
        best_j, best = scorer.forward(selected, cap)
        if best_j < 0 or not np.isfinite(best):
            break
        if np.isfinite(current) and best > current * (1.0 - tol):
            break
        selected.append(best_j)
        selected, current = scorer.prune(selected, best)
        steps.append(np.array(selected, dtype=np.int64))
        mses.append(current)
        resid = scorer.residual(selected) if criterion not in (None, "press") else None
        crits.append(_size_score(criterion, resid, selected, X, target))
    return steps, mses, crits


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
