"""One NARX call a user can trust: structure and options searched, judged by free run.

:class:`NarxSearch` fits a grid of :class:`~identification.models.Narx` candidates — orders,
degrees, term kinds, non-polynomial functions, and the fitting options ``focus``
(least squares or simulation error) and ``selection`` (all terms, FROLS, SEMP) — and keeps the one
whose **free run** best reproduces data it was not fitted on. No single option is best on every
data set (measured on six real data sets: simulation focus won on three, free-run selection on
one, plain least squares on another), and a least-squares model that passes its own stability
check can still diverge on other inputs; the search makes both choices from the data.

Validation (documented protocol)
    k-fold in time (``folds``; ``"auto"``: 4 folds for a record shorter than 3,000 samples, 2
    below 8,000, else 1): k held-out windows, each ``holdout`` of the record, spread evenly
    from its start to its end (one fold: the last window; two: the first and the last), each
    model fitted on the longer contiguous part outside its window. A window that follows its
    fit part is scored on a free run started from the measured first ``init_window`` outputs
    of the *fit part* and run through it (nonlinear_benchmarks' convention for a test record:
    one long free run, so a model that drifts is seen drifting, as a test record will show
    it); a window before its fit part is scored on a free run started from its own first
    ``init_window`` measured outputs. Each window is cut into ``n_blocks`` blocks. The score
    of an output is its root relative squared error over all blocks,
    ``sqrt(sum e^2 / sum (y - mean y)^2)`` (the mean per block); a candidate's score is the
    mean over its outputs, its **spread** the standard deviation of its block scores.

Rejection (a candidate is never returned when)
    its fit fails or its stability contract refuses it; its free run leaves the model's bound
    (``bound_``, 1000 x the record's peak by default) or becomes non-finite on **any** fold's
    validation run; or on the identification input scaled by 0.5 and by 2 (from rest: a zero
    past and the input faded in over its first ``min(200, N / 10)`` samples); or on a white
    Gaussian input of the same mean, RMS and band as the identification input (band: the
    frequencies holding 99 % of its power, estimated by Welch's method; the noise drawn from
    ``seed``). The shortlist (the choice, in rank order) also needs a bounded free run on an
    input 4 times longer than the training part (at most 200,000 samples) of its spectrum and
    level (Gaussian noise shaped by its Welch spectrum): a model that is bounded only over the
    record's length is rejected there. Every candidate's row in :attr:`NarxSearch.results_`
    says why it was rejected.

Baselines (``baselines=True``, the default)
    Whatever the grid, the field holds ARX (least squares) and linear output-error
    (simulation focus) models of every searched order and FROLS terms sized by ``criterion``
    (SysIdentPy's default method) for every structure; with ``lags="text"`` also SysIdentPy's
    own candidates, input lags from 1 (ARX and FROLS of degree 1, FROLS of degree 2, and their
    linear output-error fit, for every searched order): on a record taken in closed loop the
    current input holds the controller's instantaneous reaction to the output, which a free
    run cannot use. The search's validation score is never worse than theirs, by
    construction. Their rows say ``(baseline)``.

Search order and time budget
    Stage 1 fits every structure (order x degree x kind x functions) by least squares, with all
    terms and, when ``"frols"`` is in ``selection``, with FROLS terms sized by ``criterion`` and
    at each size of ``n_terms`` — cheapest first (by term count). A sized FROLS path is its own
    entry in stage 2 (refined there at that size). The structures are then ranked — the best by validation
    score and the best by one-step held-out error, alternately (simulation focus can make a
    structure whose least-squares fit diverges the best one; its one-step error says how much
    it can explain) — and stage 2 spends the rest of the budget on the expensive options
    (``focus="simulation"``, ``selection="simulation"``), best-ranked structure first (each
    option class first on the smallest structure, which calibrates its fit-time rate cheaply),
    in rounds: every ranked entry gets its cheapest remaining option (as predicted then) before
    any gets its next, so a promising structure is not starved by a higher-ranked one's
    expensive options.
    Stage 1 may spend half the budget; the stage-1 candidates it leaves are tried after stage 2,
    while time is left.
    Before each candidate its fit time is predicted (``rate x work``, work = rows x (k (k + 30) +
    30 M) for M candidate terms of which k are fitted, plus a SEMP path's free runs, rows x
    ``path_work``; the median rate of its option class measured on the candidates already
    fitted, extrapolated conservatively to larger candidates) and it is skipped when the
    prediction exceeds the time left less a reserve for the final refit; a candidate that runs
    longer than predicted is held to the budget by its fit's deadline (``Narx.fit(deadline=...)``:
    the refinement stops iterating, free-run selection plans for the time left), set 5 % of the
    budget before that reserve (a fit cut short still finishes its step and is validated). The budget
    bounds the wall time of :meth:`NarxSearch.fit` after the compiled kernels' one-time load
    (``warm_up_time_``: about half a minute with a cold numba cache, once per environment, which
    would otherwise eat a short budget whole); ``budget=None`` tries every candidate to
    the end. With ``budget=None`` everything is deterministic under ``seed``; with a budget, the
    candidates tried (and a fit cut short) depend on the machine's speed.

Widening
    With a budget and time left once the grid is done, the search widens around the three
    best validated candidates, ring after ring: orders one lag either side, unequal output
    and input lags, selections of half, 1.5 and twice the size (orders within the measured
    initial window). Their rows say ``(widening)``; :meth:`NarxSearch.report` gives the time
    used of the budget.

Choice and refit
    The best candidate is the lowest score; scores within 1 % of it are ties, broken by the
    spread (the steadiest), then by fewer terms, then by the simpler fit (least squares before
    simulation focus, all terms before FROLS before SEMP). A candidate the widening found is
    chosen only if it beats the best of the others by more than that one's spread (the
    widening looks where the validation scored well: a guard against choosing validation
    noise). The choice is refitted on the whole record,
    and the refit is **checked** as the candidate was: its free run over the whole record (from
    its first ``init_window`` measured outputs) must stay bounded and be no worse than the
    validated model's over the same record beyond the validation's spread (its standard error,
    at least 1 %), and it must be bounded on the stress inputs and the longer input of the
    whole record. Otherwise (or when the refit would overrun the budget) the model fitted on
    fold 1's training part (the one validated) is returned. ``refit_`` says which and why,
    ``refit_check_`` holds both whole-record errors. The refit gets the search's deadline too
    (a refinement past it keeps the best iterate reached).
"""

from __future__ import annotations

import dataclasses
import itertools
import math
import time
import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np
from scipy import signal

from ._semp import path_work
from ._validation import as_signal, check_same_length
from .errors import (
    IdentificationError,
    InsufficientDataError,
    RankDeficiencyWarning,
    SimulationDivergedError,
    StabilityWarning,
    UnstableModelError,
)
from .free_run_selection import DEFAULT_PATH
from .models import Narx
from .structure import TERM_KINDS

__all__ = ["CandidateResult", "NarxSearch", "SearchCandidate"]

SELECTIONS = ("all", "frols", "simulation")
FOCUSES = ("prediction", "simulation")
#: fit-time rate of an option class not yet measured, as a multiple of least squares' rate
#: (engineering estimates: refinement and free-run selection run many free runs per fit)
_PRIOR_RATE = {
    ("prediction", "all"): 1.0,
    ("prediction", "frols"): 3.0,
    ("prediction", "simulation"): 2.0,  # per unit of its larger work (its path's free runs)
    ("simulation", "all"): 40.0,
    ("simulation", "frols"): 40.0,
    ("simulation", "simulation"): 4.0,
}
#: fraction of the budget stage 1 may spend before stage 2 starts: the least-squares fits rank
#: the structures, but the gains are often in stage 2 (on the Silverbox record a simulation-focus
#: fit validates 20x better than every least-squares one); the stage-1 candidates left over are
#: tried after stage 2 while time is left
_STAGE1_SHARE = 0.5
#: relative score difference treated as a tie: below the validation's resolution on records of a
#: few thousand samples; ties go to fewer terms, then least squares before simulation focus and
#: FROLS before SEMP (the simpler fit), then the lower score
_TIE = 1e-2
#: fraction of the budget a candidate's fit deadline keeps beyond the refit reserve: a fit cut
#: short by its deadline still finishes the step it is in (a SEMP forward step, an LM iteration),
#: its stability contract and its validation runs; without it the refit of the best candidate no
#: longer fits in the budget (measured on F-16: a cut-short SEMP ended 2 s past its deadline)
_FIT_SLACK = 0.05
_COST_RANK = {"prediction": 0, "simulation": 1, "all": 0, "frols": 1}
#: fraction of the budget the reserve keeps for the choice's own free runs (the shortlist's
#: longer input, the refit's whole-record and stress runs) besides the refit: without it a
#: search that used its budget to the end kept the training-part model for lack of 0.2 s
_CHOICE_SHARE = 0.03
#: the shortlist's stability margin: a free run on an input this many times longer than the
#: training part (its spectrum and level), at most :data:`_LONG_MAX` samples
_LONG_FACTOR = 4
_LONG_MAX = 200_000
#: ``folds="auto"``: records shorter than the first number get 4 folds, shorter than the second 2,
#: longer ones 1 (a long record's one held-out quarter already holds thousands of samples; a
#: short record's quarter is a few hundred, too few to predict a test record's error)
_AUTO_FOLDS = (3000, 8000)


@dataclass(frozen=True)
class SearchCandidate:
    """One point of the search grid: a structure and the fitting options.

    Parameters
    ----------
    order : int or (int, int)
        Model order n (output lags 1..n, input lags up to n) or a pair ``(na, nb)``: output lags
        1..na, input lags up to nb.
    degree : int
        Polynomial degree (1: ARX).
    kind : str
        Term set (:data:`identification.structure.TERM_KINDS`).
    functions : tuple or None
        Non-polynomial regressor functions (as :class:`~identification.models.Narx` takes them).
    focus : {"prediction", "simulation"}
        What the coefficients minimise.
    selection : {"all", "frols", "simulation"}
        All terms, FROLS terms, or SEMP terms (sized by the search's ``criterion``).
    lags : {"text", "sysidentpy"}
        Input lag convention: from 0 (the reference text's full-order structure, eq. 5-3: input
        lags 0..n) or from 1 (SysIdentPy's ``xlag=n``: input lags 1..n).
    n_terms : int, optional
        Terms per output channel of a FROLS or SEMP selection (None: sized by the criterion;
        ignored with all terms).
    """

    order: int | tuple
    degree: int
    kind: str
    functions: tuple | None
    focus: str
    selection: str
    lags: str = "text"
    n_terms: int | None = None

    @property
    def lag_orders(self) -> tuple:
        """(largest output lag, largest input lag or one per input)."""
        return _pair(self.order)

    @property
    def structure(self) -> tuple:
        """The structure part (order, degree, kind, functions)."""
        return (self.order, self.degree, self.kind, self.functions)

    @property
    def entry(self) -> tuple:
        """What stage 2 ranks and refines: the structure, the selection size (``None``: all
        terms, or sized by the criterion) and the lag convention."""
        return (*self.structure, self.n_terms, self.lags)

    @property
    def options(self) -> tuple[str, str]:
        """The option class (focus, selection)."""
        return (self.focus, self.selection)

    def label(self) -> str:
        """Short human-readable description, e.g. ``"order 4, degree 2 full, LS all terms"``."""
        kind = "" if self.degree == 1 else f" {self.kind}"
        funs = ""
        if self.functions:
            funs = " + " + ", ".join(
                f if isinstance(f, str) else f"{f[0]}({f[1]})" for f in self.functions
            )
        how = {"all": "all terms", "frols": "FROLS", "simulation": "SEMP"}[self.selection]
        if self.selection != "all" and self.n_terms is not None:
            how += f" {self.n_terms} terms"
        fit = "LS" if self.focus == "prediction" else "sim. focus"
        na, nb = self.lag_orders
        first = 0 if self.lags == "text" else 1
        ulags = "/".join(f"{first}..{b}" for b in (nb if isinstance(nb, tuple) else (nb,)))
        order = (
            f"order {na}"
            if isinstance(self.order, int) and first == 0
            else f"y lags 1..{na}, u lags {ulags}"
        )
        return f"{order}, degree {self.degree}{kind}{funs}, {fit}, {how}"

    def narx(self, criterion: str, options: dict) -> Narx:
        """The unfitted model of this candidate.

        Parameters
        ----------
        criterion : str
            Size criterion of a FROLS or SEMP path (``Narx(criterion=...)``).
        options : dict
            Further ``Narx`` arguments (not the searched ones).
        """
        kw = dict(options)
        if self.selection != "all":
            kw.update(selection=("frols" if self.selection == "frols" else "simulation"))
            if self.n_terms is None:
                kw.update(criterion=criterion)
            else:
                kw.update(n_terms=self.n_terms)
        na, nb = self.lag_orders
        text = self.lags == "text"
        nb = [b + text for b in nb] if isinstance(nb, tuple) else nb + text
        kw.update(na=na, nb=nb, nk=0 if text else 1)
        return Narx(
            degree=self.degree,
            kind=self.kind,
            functions=list(self.functions) if self.functions else None,
            focus=self.focus,
            **kw,
        )


@dataclass
class CandidateResult:
    """What the search found for one candidate (a row of :meth:`NarxSearch.report`).

    Attributes
    ----------
    candidate : SearchCandidate
        The structure and options.
    status : {"ok", "rejected", "failed", "skipped"}
        ``ok``: validated; ``rejected``: fitted but a free run diverged (see ``reason``);
        ``failed``: the fit raised; ``skipped``: not tried (budget, size).
    reason : str
        Why it was rejected, failed or skipped; for an ok row "" or a note (its fit was cut
        short by the budget: ``Narx.fit(deadline=...)``).
    score : float
        Mean over the outputs of the validation free-run error (RRSE; ``inf`` unless ok).
    scores : ndarray (ny,)
        Validation free-run RRSE per output (``inf`` unless ok).
    one_step : float
        Mean one-step-ahead RRSE on the validation blocks (``inf`` when not computed).
    n_terms : int
        Terms over all output channels (0 when not fitted).
    fit_time : float
        Seconds spent fitting and validating it.
    predicted_time : float
        The fit time predicted before it was tried (seconds; ``nan`` with no budget).
    block_scores : ndarray (n_folds * n_blocks,)
        Free-run RRSE of each validation block (mean over the outputs), fold by fold.
    spread : float
        Standard deviation of ``block_scores`` (``inf`` unless ok; 0 with one block): how much
        the score would move on another stretch of record.
    origin : str
        Why it is in the field: ``"grid"``, ``"baseline"`` (the linear and FROLS candidates the
        search always tries, ``baselines=True``) or ``"widening"`` (tried with time left).
    """

    candidate: SearchCandidate
    status: str
    reason: str = ""
    score: float = math.inf
    scores: np.ndarray = field(default_factory=lambda: np.array([]))
    one_step: float = math.inf
    n_terms: int = 0
    fit_time: float = 0.0
    predicted_time: float = math.nan
    block_scores: np.ndarray = field(default_factory=lambda: np.array([]))
    spread: float = math.inf
    origin: str = "grid"


@dataclass(frozen=True, eq=False)
class _Fold:
    """One validation fold: the training part ``u``, ``y``; the held-out ``window`` (a, b);
    ``start``, where its validation free run starts (from the measured outputs there); the
    scored ``blocks`` (absolute sample ranges inside the window); the ``stress`` inputs."""

    u: np.ndarray
    y: np.ndarray
    window: tuple[int, int]
    start: int
    blocks: tuple[slice, ...]
    stress: list


def _positive(x: np.ndarray) -> np.ndarray:
    return np.where(x > 0, x, 1.0)


def _tuple(values, name: str) -> tuple:
    if isinstance(values, (str, bytes)) or not isinstance(values, Sequence):
        values = (values,)
    values = tuple(values)
    if not values:
        raise IdentificationError(f"{name} is empty: give at least one value to search")
    return values


def _order_grid(values) -> tuple:
    """Orders: ints n >= 0 or pairs (na, nb) of them, nb an int or one int per input; sorted by
    largest lag, duplicates removed."""
    out = []
    for v in _tuple(values, "orders"):
        if isinstance(v, Sequence) and not isinstance(v, str):
            pair = tuple(v)
            if len(pair) != 2:
                raise IdentificationError(f"an order pair must be (na, nb), got {v!r}")
            na = _int_grid(pair[0], "orders", 0)[0]
            nb = pair[1]
            if isinstance(nb, Sequence) and not isinstance(nb, str):
                if not nb:
                    raise IdentificationError(f"per-input lags nb are empty in {v!r}")
                nb = tuple(_int_grid(x, "orders", 0)[0] for x in nb)
            else:
                nb = _int_grid(nb, "orders", 0)[0]
            out.append((na, nb))
        else:
            out.append(_int_grid(v, "orders", 0)[0])

    def key(o):
        na, nb = _pair(o)
        return (_largest_lag(o), na, nb if isinstance(nb, tuple) else (nb,))

    return tuple(sorted(dict.fromkeys(out), key=key))


def _pair(order) -> tuple:
    return (order, order) if isinstance(order, int) else order


def _largest_lag(order) -> int:
    """The largest lag of an order (an int, or (na, nb) with nb an int or one per input)."""
    na, nb = _pair(order)
    return max(na, *(nb if isinstance(nb, tuple) else (nb,)))


def _size_grid(values) -> tuple:
    """Selection sizes: None (the criterion) or ints >= 1; duplicates removed, None first."""
    values = (None,) if values is None else _tuple(values, "n_terms")
    sizes = [v for v in values if v is not None]
    out = (None,) if len(sizes) < len(values) else ()
    return out + (_int_grid(sizes, "n_terms", 1) if sizes else ())


def _int_grid(values, name: str, minimum: int) -> tuple[int, ...]:
    values = _tuple(values, name)
    for v in values:
        if not isinstance(v, (int, np.integer)) or isinstance(v, bool) or v < minimum:
            raise IdentificationError(f"{name} must be integers >= {minimum}, got {v!r}")
    return tuple(sorted({int(v) for v in values}))


def _choice_grid(values, name: str, allowed: tuple) -> tuple[str, ...]:
    values = _tuple(values, name)
    bad = [v for v in values if v not in allowed]
    if bad:
        raise IdentificationError(f"{name} values must be among {allowed}, got {bad[0]!r}")
    return tuple(dict.fromkeys(values))


def _function_grid(values) -> tuple:
    if values is None:
        return (None,)
    out = []
    for f in _tuple(values, "functions"):
        if f is None or (isinstance(f, Sequence) and not isinstance(f, str) and len(f) == 0):
            out.append(None)
        elif isinstance(f, str) or (isinstance(f, tuple) and len(f) == 2 and isinstance(f[0], str)):
            out.append((f,))  # one function spec: a set of one
        else:
            out.append(tuple(tuple(s) if isinstance(s, list) else s for s in f))
    for f in out:
        if f is not None:
            Narx(order=1, functions=list(f))  # validates the specs now, not mid-search
    return tuple(dict.fromkeys(out))


def _check_budget(budget) -> float | None:
    if budget is None:
        return None
    if isinstance(budget, bool) or not isinstance(budget, (int, float, np.number)):
        raise IdentificationError(f"budget must be a number of seconds > 0 or None, got {budget!r}")
    if not (budget > 0 and math.isfinite(budget)):
        raise IdentificationError(f"budget must be a finite number of seconds > 0, got {budget!r}")
    return float(budget)


class NarxSearch:
    """Search NARX structures and fitting options by free-run validation (see the module doc).

    Parameters
    ----------
    budget : float or None
        Wall-clock budget of :meth:`fit`, seconds (default 60); None: try every candidate.
    orders : sequence of int or (int, int)
        Model orders to try (samples): n (output lags 1..n, input lags up to n) or a pair
        ``(na, nb)`` (output lags 1..na, input lags up to nb; nb may be a tuple, one largest lag
        per input, e.g. ``(3, (2, 7))``).
    lags : {"text", "sysidentpy"}
        Input lags from 0 (default: the reference text's full-order structure, eq. 5-3) or from
        1 (SysIdentPy's ``xlag``), so that comparisons with SysIdentPy are like for like.
    degrees : sequence of int
        Polynomial degrees to try (1: ARX).
    kinds : sequence of str
        Term sets for degrees above 1 (:class:`~identification.models.Narx` ``kind``).
    functions : sequence, optional
        Non-polynomial function sets to try: each item is None (none), one spec (e.g.
        ``("saturation", "auto")``) or a list of specs, as ``Narx(functions=...)`` takes them.
    focus : sequence of {"prediction", "simulation"}
        Coefficient fits to try (least squares; simulation error).
    selection : sequence of {"all", "frols", "simulation"}
        Term choices to try (all terms; FROLS; SEMP free-run selection), sized by ``criterion``.
        Least squares on all terms is always tried (stage 1: it ranks the structures); where a
        structure has too many terms for that (``max_terms``), least squares on FROLS terms ranks
        it instead.
    criterion : {"aic", "aicc", "bic", "fpe", "press"}
        Size criterion of the FROLS and SEMP paths.
    n_terms : sequence of int or None, optional
        Sizes of the FROLS and SEMP selections to try, terms per output channel; ``None`` in the
        sequence (or ``n_terms=None``, the default) sizes them by ``criterion``. Each size is its
        own candidate (validated by free run like every other): on long records an information
        criterion can keep hundreds of terms whose free run is worse than a shorter path's.
    holdout : float
        Fraction of the record each validation window holds, in (0, 0.5].
    folds : int or "auto"
        Validation windows (k-fold in time): 1, the last ``holdout`` of the record; k >= 2,
        k windows of that length spread evenly from the record's start to its end (2: the
        first and the last), each model fitted on the longer contiguous part outside its
        window. ``"auto"`` (default): 4 folds for a record shorter than 3,000 samples, 2 below
        8,000, else 1.
    n_blocks : int
        Blocks each validation window is cut into: the score's spread is the standard
        deviation of the block scores.
    baselines : bool
        Always put the baselines in the field (default True): ARX (least squares) and linear
        output-error (simulation focus) models of every searched order and FROLS terms sized by
        ``criterion`` of every structure, whatever ``degrees``, ``focus`` and ``selection`` say,
        and (``lags="text"``) SysIdentPy's candidates with input lags from 1 (see the module
        doc); so the search's validation score is never worse than the best linear model's or
        FROLS's (SysIdentPy's default method). False: exactly the grid given.
    init_window : int, optional
        Measured samples that start each validation free run (default: the largest order; at
        least every candidate's largest lag).
    max_terms : int
        Largest all-terms model (terms per output channel); larger structures get only FROLS
        and SEMP fits. An all-terms fit also needs at least 5 training samples per term.
    max_candidates : int
        Largest candidate term set of a FROLS or SEMP fit (per output channel); larger
        structures are skipped. A selection needs as many training samples as candidates.
    options : dict, optional
        Further ``Narx`` arguments given to every candidate (e.g. ``max_radius=0.995``,
        ``stability_margin=3.0``, ``max_iter=30``). The constant term is a candidate term by
        default (``constant=True``, unlike a bare ``Narx``): measured records carry offsets
        (transducer zeros, mean loads; a time-domain model's advantage over frequency-domain
        ones is that it can reproduce them), FROLS and SEMP drop it where it does not help, and
        an all-terms fit pays one parameter. ``options={"constant": False}`` leaves it out.
    seed : int
        Seed of the white stress input.
    callback : callable, optional
        Called with each :class:`CandidateResult` as it is decided (e.g. to print progress).

    Attributes
    ----------
    best_ : Narx
        The chosen model (refitted on the whole record unless ``refit_`` says otherwise).
    best_result_ : CandidateResult
        Its row in ``results_``.
    results_ : list of CandidateResult
        One row per candidate, in the order they were decided.
    refit_ : str
        ``"whole record"`` or why the training-part model was kept.
    refit_check_ : dict
        The refit's check (when it ran): ``refit`` and ``validated``, the free-run RRSE over
        the whole record of the refit and of the validated model, and ``tolerance``, the
        validation's spread the refit may exceed it by.
    n_folds_ : int
        Validation folds used (``folds``, or what ``"auto"`` chose for the record).
    search_time_ : float
        Wall time of the search, seconds: the budget used (after the compiled kernels' one-time
        load, ``warm_up_time_``, which the budget does not count: with a cold numba cache it
        is about half a minute, once per environment).
    warm_up_time_ : float
        Seconds spent loading (or compiling) the kernels before the search's clock started.

    Examples
    --------
    >>> search = NarxSearch(budget=30, orders=(2, 4), degrees=(1, 2)).fit(u, y)  # doctest: +SKIP
    >>> print(search.report())                                                 # doctest: +SKIP
    >>> y_sim = search.best_.simulate(u_new, y0=y_new[:50])                    # doctest: +SKIP
    """

    def __init__(
        self,
        budget: float | None = 60.0,
        *,
        orders=(1, 2, 3, 4, 6, 8),
        lags: str = "text",
        degrees=(1, 2, 3),
        kinds=("full", "input-polynomial"),
        functions=None,
        focus=FOCUSES,
        selection=SELECTIONS,
        criterion: str = "bic",
        n_terms=None,
        holdout: float = 0.25,
        folds: int | str = "auto",
        n_blocks: int = 2,
        baselines: bool = True,
        init_window: int | None = None,
        max_terms: int = 600,
        max_candidates: int = 2000,
        options: dict | None = None,
        seed: int = 0,
        callback: Callable | None = None,
    ):
        self.budget = _check_budget(budget)
        self.orders = _order_grid(orders)
        if lags not in ("text", "sysidentpy"):
            raise IdentificationError(f"lags must be 'text' or 'sysidentpy', got {lags!r}")
        self.lags = lags
        self.degrees = _int_grid(degrees, "degrees", 1)
        self.kinds = _choice_grid(kinds, "kinds", TERM_KINDS)
        self.functions = _function_grid(functions)
        self.focus = _choice_grid(focus, "focus", FOCUSES)
        self.selection = _choice_grid(selection, "selection", SELECTIONS)
        Narx(order=1, criterion=criterion)  # validates the criterion
        self.criterion = criterion
        self.n_terms = _size_grid(n_terms)
        if not (isinstance(holdout, (int, float)) and 0 < holdout <= 0.5):
            raise IdentificationError(f"holdout must be a fraction in (0, 0.5], got {holdout!r}")
        self.holdout = float(holdout)
        if folds != "auto":
            folds = _int_grid(folds, "folds", 1)[0] if not isinstance(folds, str) else folds
        if not (folds == "auto" or isinstance(folds, int)):
            raise IdentificationError(f"folds must be an integer >= 1 or 'auto', got {folds!r}")
        self.folds = folds
        if not isinstance(baselines, (bool, np.bool_)):
            raise IdentificationError(f"baselines must be True or False, got {baselines!r}")
        self.baselines = bool(baselines)
        self.n_blocks = _int_grid(n_blocks, "n_blocks", 1)[0]
        self.init_window = (
            None if init_window is None else _int_grid(init_window, "init_window", 1)[0]
        )
        if self.init_window is not None and self.init_window < self._max_lag():
            raise IdentificationError(
                f"init_window ({self.init_window}) must cover the largest lag "
                f"({self._max_lag()}): every free run starts from that many measured outputs"
            )
        self.max_terms = _int_grid(max_terms, "max_terms", 1)[0]
        self.max_candidates = _int_grid(max_candidates, "max_candidates", 1)[0]
        self.options = {"constant": True, **(options or {})}
        reserved_options = ("order", "na", "nb", "nk", "degree", "kind", "functions", "focus")
        for reserved in (*reserved_options, "n_terms", "selection"):
            if reserved in self.options:
                raise IdentificationError(
                    f"options may not set {reserved!r}: it is searched (give the grid instead)"
                )
        Narx(order=1, **self.options)  # validates the options now
        self.seed = int(seed)
        self.callback = callback

    # ------------------------------------------------------------------ grid
    def _max_lag(self) -> int:
        return max(_largest_lag(o) for o in self.orders)

    def structures(self) -> list[tuple]:
        """Every structure (order, degree, kind, functions) of the grid, without duplicates."""
        out = [(n, 1, "full", None) for n in self.orders] if self.baselines else []
        for n, d, kind, funs in itertools.product(
            self.orders, self.degrees, self.kinds, self.functions
        ):
            out.append((n, d, "full" if d == 1 else kind, funs))
        return list(dict.fromkeys(out))

    def _other_lag_baselines(self) -> list[SearchCandidate]:
        """With ``lags="text"`` and ``baselines``: SysIdentPy's own candidates, input lags from
        1 (no current input), for every searched order: ARX and FROLS of degree 1, FROLS of
        degree 2 (its default basis). On a record taken in closed loop the current input holds
        the controller's instantaneous reaction to the output (measured on the closed-loop ball
        and beam: FROLS without it tested up to 6x better than the searched models with it)."""
        if not self.baselines or self.lags != "text":
            return []
        out = []
        for n in self.orders:
            out.append(SearchCandidate(n, 1, "full", None, "prediction", "all", "sysidentpy"))
            for d in (1, 2):
                out.append(SearchCandidate(n, d, "full", None, "prediction", "frols", "sysidentpy"))
        return out

    def _is_baseline(self, c: SearchCandidate) -> bool:
        """Whether ``c`` is in the field only because of ``baselines``."""
        if not self.baselines:
            return False
        if c.lags != self.lags:
            return True
        linear = c.degree == 1 and c.functions is None and c.n_terms is None
        in_grid = (
            (c.degree in self.degrees and (c.functions in self.functions))
            and c.focus in self.focus
            and (c.selection in self.selection or c.options == ("prediction", "all"))
        )
        return not in_grid and (linear or c.options == ("prediction", "frols"))

    def _stage2_options(self) -> list[tuple[str, str]]:
        cheap = {("prediction", "all"), ("prediction", "frols")}
        opts = itertools.product(self.focus, self.selection)
        return [o for o in opts if o not in cheap]

    # ------------------------------------------------------------------ fit
    def fit(self, u, y, *, input_names=None, output_names=None):
        """Search on input ``u`` (N, nu) and output ``y`` (N, ny); returns self.

        Parameters
        ----------
        u : array_like, shape (N, nu) or (N,)
            Identification input record (time on axis 0).
        y : array_like, shape (N, ny) or (N,)
            Identification output record, same N.
        input_names, output_names : sequence of str, optional
            Channel names kept in the chosen model.

        Raises
        ------
        InsufficientDataError
            when the record is too short for the validation blocks.
        IdentificationError
            when no candidate gives a model whose free runs stay bounded (``results_`` says why
            each was rejected).
        """
        u = as_signal(u, "u")
        y = as_signal(y, "y")
        check_same_length(u, y, "u", "y")
        for o in self.orders:
            nb = _pair(o)[1]
            if isinstance(nb, tuple) and len(nb) != u.shape[1]:
                raise IdentificationError(
                    f"order {o!r} gives {len(nb)} per-input lags, but u has {u.shape[1]} inputs"
                )
        self._names = (input_names, output_names)
        for stale in (
            "best_",
            "best_result_",
            "refit_",
            "refit_check_",
        ):  # a refit that fails keeps no old model
            self.__dict__.pop(stale, None)
        self._prepare(u, y)
        loading = time.perf_counter()
        _warm_up(u, y)  # before the clock starts: a cold cache compiles for half a minute
        t0 = time.perf_counter()
        self.warm_up_time_ = t0 - loading
        self._t0 = t0
        self._deadline = None if self.budget is None else t0 + self.budget
        self.results_ = []
        self._rates: dict[tuple, list[tuple[float, float]]] = {}
        self._kept: dict[tuple, int] = {}
        self._models: dict[SearchCandidate, Narx] = {}
        with warnings.catch_warnings():
            for w in (StabilityWarning, RankDeficiencyWarning, RuntimeWarning):
                warnings.simplefilter("ignore", w)
            try:
                self._stage1()
                self._stage2()
                for c in self._deferred:
                    self._try(c)
                self._widen()
                self._choose(u, y)
            finally:  # report() works after a failed search too (it says why each failed)
                self.search_time_ = time.perf_counter() - t0
        return self

    def _n_folds(self, n_samples: int) -> int:
        if self.folds != "auto":
            return self.folds
        short, medium = _AUTO_FOLDS
        return 4 if n_samples < short else 2 if n_samples < medium else 1

    def _prepare(self, u, y) -> None:
        """Folds, validation blocks and stress inputs; refuses a record too short for them."""
        N = u.shape[0]
        init = self.init_window or max(self._max_lag(), 1)
        k = self._n_folds(N)
        n_val = round(self.holdout * N)
        need = max(10, 2 * init)  # scored samples per block
        if (n_val - init) // self.n_blocks < need or N - n_val < need:
            raise InsufficientDataError(
                f"a record of {N} samples is too short for the validation: a held-out window "
                f"of {self.holdout:g} of it ({n_val} samples, of which a restarted free run "
                f"loses {init} measured initial samples) cut into {self.n_blocks} block(s) "
                f"needs at least {init + self.n_blocks * need} samples ({need} scored per "
                "block). Give a longer record, a larger holdout, fewer blocks or smaller orders"
            )
        self._init = init
        if k == 1:
            starts = [N - n_val]
        else:  # the last window first: fold 0's model is the one kept when the refit is not
            starts = sorted({int(a) for a in np.linspace(0, N - n_val, k).round()}, reverse=True)
        self._folds = []
        for a in starts:
            b = a + n_val
            fit = slice(0, a) if a >= N - b else slice(b, N)
            start = fit.start if fit.stop == a else a  # continue from the fit part, or restart
            edges = np.linspace(max(a, start + init), b, self.n_blocks + 1).round().astype(int)
            blocks = tuple(slice(int(s), int(e)) for s, e in itertools.pairwise(edges))
            stress = self._stress_inputs(u[fit])
            self._folds.append(_Fold(u[fit], y[fit], (a, b), start, blocks, stress))
        self._u, self._y = u, y
        lengths = [f.u.shape[0] for f in self._folds]
        self._rows = min(lengths)
        self._fit_rows = sum(lengths)
        self._refit_scale = N / self._fit_rows  # a refit's time per fold-fit time
        self.n_folds_ = len(self._folds)

    def _stress_inputs(self, u) -> list[tuple[str, np.ndarray]]:
        """0.5x and 2x the identification input, and white noise of its mean, RMS and band;
        each faded in from zero over its first ``min(200, N / 10)`` samples (raised cosine): the
        free runs start from rest, and a step from a zero past to a full-level input is not
        what these tests are about."""
        rng = np.random.default_rng(self.seed)
        n = u.shape[0]
        k = max(min(200, n // 10), 1)
        fade = np.ones(n)
        fade[:k] = signal.windows.hann(2 * k + 1)[:k]
        return [
            (what, fade[:, None] * x)
            for what, x in (
                ("0.5x the identification input", 0.5 * u),
                ("2x the identification input", 2.0 * u),
                ("a white input of the same RMS and band", _white_like(u, rng)),
            )
        ]

    # ------------------------------------------------------------------ stages
    def _stage1(self) -> None:
        size = {}
        asked = "frols" in self.selection and "prediction" in self.focus
        selects = self.selection != ("all",)
        for s in self.structures():
            base = SearchCandidate(*s, "prediction", "all", self.lags)
            size[base] = self._terms(base)
            # FROLS least squares: asked for, or the only fit that can rank a structure too big
            # for all terms (else stage 2 never sees it); sized by the criterion, a baseline
            if asked or (selects and self._too_big(base, size[base])):
                for k in self.n_terms:
                    c = SearchCandidate(*s, "prediction", "frols", self.lags, k)
                    size[c] = self._terms(c)
            if self.baselines:  # FROLS sized by the criterion: SysIdentPy's default method
                c = SearchCandidate(*s, "prediction", "frols", self.lags, None)
                size.setdefault(c, self._terms(c))
        for c in self._other_lag_baselines():
            size.setdefault(c, self._terms(c))
        cands = list(size)
        stop = None if self._deadline is None else self._t0 + _STAGE1_SHARE * self.budget
        self._deferred = []
        for c in sorted(cands, key=lambda c: (size[c], c.selection != "all", c.n_terms or 0)):
            if stop is not None and time.perf_counter() > stop and self.results_:
                self._deferred.append(c)  # tried after stage 2, if time is left
            else:
                self._try(c)

    def _stage2(self) -> None:
        """The expensive options on the ranked structures, in rounds (each entry, best first,
        its cheapest remaining option); each option class is first tried on the smallest
        structure, which calibrates its rate cheaply."""
        ranked = self._ranked_structures()
        if not ranked or not any(self._entry_candidates(e) for e in ranked):
            return
        size = {e: self._terms(SearchCandidate(*e[:4], "prediction", "all", e[5])) for e in ranked}
        # the linear output-error baselines first (cheap: a few parameters), best-ranked first
        first = [c for e in ranked for c in self._entry_candidates(e) if self._is_baseline(c)]
        smallest = min(ranked, key=lambda e: (size[e], ranked.index(e)))
        first += [c for c in self._entry_candidates(smallest) if c not in first]
        for c in first:
            self._try(c)
        queues = [[c for c in self._entry_candidates(e) if c not in first] for e in ranked]
        while any(queues):  # rounds: each entry in rank order gets its next option
            for q in queues:
                if not q:
                    continue
                if self.budget is not None:  # cheapest as predicted now (else: fixed order)
                    q.sort(key=lambda c: self._predicted(c, size[c.entry]))
                self._try(q.pop(0))

    def _entry_candidates(self, entry: tuple) -> list[SearchCandidate]:
        """Stage 2's candidates of a ranked entry: every expensive option of a structure (its
        selections sized by the criterion), or the selections of a sized entry at that size."""
        *s, k, lags = entry
        opts = self._stage2_options()
        linear = s[1] == 1 and s[3] is None and k is None
        if self.baselines and linear and ("simulation", "all") not in opts:
            opts = [("simulation", "all"), *opts]  # the linear output-error baseline
        if lags != self.lags:  # a baseline of the other lag convention: its linear OE only
            opts = [("simulation", "all")] if linear else []
        if k is not None:
            opts = [o for o in opts if o[1] != "all"]
            sizes = [k]
        else:
            sizes = [None]
        return [SearchCandidate(*s, *o, lags, n) for o in opts for n in sizes]

    def _ranked_structures(self) -> list[tuple]:
        """Structures in the order stage 2 refines them: the best by stage-1 validation score
        and the best by one-step held-out error, alternately (a structure whose least-squares
        fit diverges can still be the best after the simulation focus refines it; its one-step
        error says how much it can explain). Structures never fitted are left out."""
        best: dict[tuple, list[float]] = {}
        for r in self.results_:
            v = best.setdefault(r.candidate.entry, [math.inf, math.inf])
            v[0], v[1] = min(v[0], r.score), min(v[1], r.one_step)
        by_free_run = sorted((s for s, v in best.items() if math.isfinite(v[0])), key=best.get)
        by_one_step = sorted(
            (s for s, v in best.items() if math.isfinite(v[1])), key=lambda s: best[s][1]
        )
        merged = itertools.chain.from_iterable(itertools.zip_longest(by_free_run, by_one_step))
        return list(dict.fromkeys(s for s in merged if s is not None))

    def _widen(self) -> None:
        """With time left after the grid: the neighbours of the three best validated
        candidates (orders one lag either side, unequal output and input lags, selections of
        half, 1.5x and twice the size), ring after ring around the best so far, while a
        candidate's predicted fit time fits in what is left. Orders stay within the
        validation's measured initial window. Not with ``budget=None`` (the grid is then the
        whole search)."""
        if self._deadline is None:
            return
        seen = {r.candidate for r in self.results_}
        while self._deadline - time.perf_counter() - self._reserve() > 0:
            ok = sorted((r for r in self.results_ if r.status == "ok"), key=lambda r: r.score)
            ring = [c for r in ok[:3] for c in self._neighbours(r) if c not in seen]
            ring = list(dict.fromkeys(ring))
            if not ring:
                return
            for c in ring:
                seen.add(c)
                self._try(c, origin="widening")

    def _neighbours(self, r: CandidateResult) -> list[SearchCandidate]:
        """The widening's neighbours of a validated candidate (see :meth:`_widen`)."""
        c = r.candidate
        out = []
        na, nb = c.lag_orders
        if not isinstance(nb, tuple):
            pairs = [(na - 1, nb), (na + 1, nb), (na, nb - 1), (na, nb + 1)]
            if isinstance(c.order, int):
                pairs = [(na - 1, nb - 1), (na + 1, nb + 1), *pairs]
            for a, b in pairs:
                if min(a, b) >= 0 and max(a, b, 1) <= self._init and (a, b) != (0, 0):
                    out.append(dataclasses.replace(c, order=a if a == b else (a, b)))
        if c.selection != "all":
            k = max(1, r.n_terms // self._y.shape[1])
            for m in sorted({max(1, k // 2), round(1.5 * k), 2 * k} - {c.n_terms}):
                out.append(dataclasses.replace(c, n_terms=m))
        return out

    # ------------------------------------------------------------------ one candidate
    def _terms(self, c: SearchCandidate) -> int:
        """Terms per output channel of the candidate's full structure (before any selection)."""
        model = c.narx(self.criterion, self.options)
        ny, nu = self._y.shape[1], self._u.shape[1]
        scale = np.concatenate([self._y.std(axis=0), self._u.std(axis=0)])
        try:
            return max(ch.n_terms for ch in model._structure(ny, nu, scale, None))
        except IdentificationError:
            return 10**12

    def _work(self, c: SearchCandidate, terms: int) -> float:
        """Work units of one candidate, per fold: rows x k x (k + 30) for the fit of its k terms
        (a QR's rows x k^2; the refinement's Jacobian; the free runs' rows x k) plus rows x 30 x
        terms for building and screening its ``terms`` candidates. k is ``terms`` with all
        terms; with FROLS or SEMP the candidate's ``n_terms``, else the number FROLS kept for
        the structure in stage 1 (the selections size by the same criterion), else ``terms``.
        Free-run selection (SEMP) adds its path's free runs: ``path_work`` subset-terms per
        sample (:mod:`identification._semp`: every candidate scored at each of its steps, up to
        ``n_terms`` or 40 — it runs the whole path and sizes after), which grows with the
        candidates times the square of the path length, not with k alone."""
        if c.selection == "all":
            k = terms
        else:
            k = c.n_terms if c.n_terms is not None else self._kept.get(c.structure, terms)
        work = float(k) * (k + 30.0) + 30.0 * terms
        if c.selection == "simulation":
            steps = min(terms, DEFAULT_PATH if c.n_terms is None else c.n_terms)
            work += path_work(terms, steps)
        return self._fit_rows * work

    def _predicted(self, c: SearchCandidate, terms: int) -> float:
        """Predicted seconds: the median rate (seconds per work unit) of the candidates of the
        same option class fitted so far (least squares' times :data:`_PRIOR_RATE` before one),
        times the work, times ``sqrt(work / largest work seen)`` when extrapolating to a larger
        candidate (costs grow faster than the work units for the iterative options). A
        candidate slower than predicted is still held to the budget: its fit gets the search's
        deadline (``Narx.fit(deadline=...)``)."""
        work = self._work(c, terms)
        seen = self._rates.get(c.options)
        if seen:
            rate = float(np.median([r for _, r in seen]))
            largest = max(w for w, _ in seen)
        else:
            base = self._rates.get(("prediction", "all"), [(work, 1e-9)])
            rate = float(np.median([r for _, r in base])) * _PRIOR_RATE[c.options]
            largest = max(w for w, _ in base)
        return rate * work * math.sqrt(max(1.0, work / largest))

    def _try(self, c: SearchCandidate, origin: str = "grid") -> CandidateResult:
        terms = self._terms(c)
        origin = "baseline" if origin == "grid" and self._is_baseline(c) else origin
        result = CandidateResult(c, "skipped", origin=origin)
        too_big = self._too_big(c, terms)
        if too_big:
            result.reason = too_big
            return self._record(result)
        predicted = self._predicted(c, terms)
        result.predicted_time = predicted
        if self._deadline is not None:
            left = self._deadline - time.perf_counter() - self._reserve()
            if predicted > left:
                result.reason = f"predicted {predicted:.3g} s, {max(left, 0):.3g} s of budget left"
                return self._record(result)
        t = time.perf_counter()
        self._evaluate(c, result)
        result.fit_time = time.perf_counter() - t
        if result.status != "failed" or result.n_terms:
            work = self._work(c, terms)
            self._rates.setdefault(c.options, []).append((work, result.fit_time / work))
            if c.options == ("prediction", "frols") and c.n_terms is None and result.n_terms:
                self._kept[c.structure] = max(1, result.n_terms // self._y.shape[1])
        return self._record(result)

    def _too_big(self, c: SearchCandidate, terms: int) -> str:
        """Why the candidate is too large to fit ("" when it is not)."""
        if c.selection == "all":
            if terms > self.max_terms:
                return f"{terms} terms per channel: over max_terms ({self.max_terms})"
            if 5 * terms > self._rows:
                return (
                    f"{terms} terms per channel need {5 * terms} training samples, "
                    f"{self._rows} available"
                )
            return ""
        if c.n_terms is not None and c.n_terms >= terms:
            return f"n_terms {c.n_terms} >= its {terms} candidate terms: the all-terms fit"
        if terms > self.max_candidates:
            return f"{terms} candidate terms: over max_candidates ({self.max_candidates})"
        if terms > self._rows:
            return f"{terms} candidate terms, {self._rows} training samples"
        return ""

    def _reserve(self) -> float:
        """Time kept for the final refit: the best candidate so far's fit time, scaled from its
        training parts to the whole record (plus 20 %), and :data:`_CHOICE_SHARE` of the budget
        for the choice's checks, at most a quarter of the budget (a
        refit that does not fit in what is left is skipped: see ``refit_``)."""
        ok = [r for r in getattr(self, "results_", []) if r.status == "ok"]
        if not ok or self.budget is None:
            return 0.0
        best = min(ok, key=lambda r: r.score)
        refit = 1.2 * best.fit_time * self._refit_scale
        return min(refit + _CHOICE_SHARE * self.budget, 0.25 * self.budget)

    def _record(self, result: CandidateResult) -> CandidateResult:
        self.results_.append(result)
        if self.callback is not None:
            self.callback(result)
        return result

    def _evaluate(self, c: SearchCandidate, result: CandidateResult) -> None:
        """Fit on each fold's training part, validate; fills ``result`` in place."""
        sq_err, sq_dev, one_step = [], [], []
        for i, fold in enumerate(self._folds):
            model = c.narx(self.criterion, self.options)
            deadline = (
                None
                if self._deadline is None
                else self._deadline - self._reserve() - _FIT_SLACK * self.budget
            )
            try:
                model.fit(fold.u, fold.y, deadline=deadline)
            except (IdentificationError, np.linalg.LinAlgError, FloatingPointError) as exc:
                result.status, result.reason = "failed", _first_line(exc)
                if isinstance(exc, UnstableModelError) and hasattr(model, "coef_"):
                    result.one_step = self._one_step(model, fold.blocks)  # ranks it for stage 2
                return
            result.n_terms = int(np.sum(model.n_terms_))
            verdict = self._validate(model, i)
            if isinstance(verdict, str):
                result.status, result.reason = "rejected", verdict
                result.one_step = self._one_step(model, fold.blocks)
                return
            if model.timed_out_:
                result.reason = "cut short by the budget (the best iterate reached)"
            sq_err.append(verdict[0])
            sq_dev.append(verdict[1])
            one_step.append(self._one_step(model, fold.blocks))
            self._models.setdefault(c, model)
        err, dev = np.concatenate(sq_err), np.concatenate(sq_dev)  # (blocks, ny)
        scores = np.sqrt(err.sum(axis=0) / _positive(dev.sum(axis=0)))
        blocks = np.mean(np.sqrt(err / _positive(dev)), axis=1)
        result.status, result.scores = "ok", scores
        result.score, result.one_step = float(np.mean(scores)), float(np.mean(one_step))
        result.block_scores = blocks
        result.spread = float(np.std(blocks, ddof=1)) if blocks.size > 1 else 0.0

    def _validate(self, model: Narx, i: int):
        """Per block ``(sum e^2, sum (y - mean)^2)`` (arrays (n_blocks, ny)) of fold ``i``'s
        validation free run, or why the model is rejected. The run starts from the measured
        first ``init`` outputs of the fold's training part when its window follows that part
        (and runs through it: the window is scored after as long a free run as the record
        allows, as a test record will be), else at the window's own start."""
        u, y, init = self._u, self._y, self._init
        fold = self._folds[i]
        b = fold.window[1]
        try:
            sim = model.simulate(u[fold.start : b], y0=y[fold.start : fold.start + init])
        except SimulationDivergedError as exc:
            at = fold.start + exc.sample
            where = (
                f"before its validation window (from sample {fold.start})"
                if at < fold.blocks[0].start
                else "on validation block " + str(1 + sum(bl.start <= at for bl in fold.blocks[1:]))
            )
            fold_name = f" of fold {i + 1}" if len(self._folds) > 1 else ""
            return f"free run diverges {where}{fold_name} (sample {at})"
        e = np.empty((len(fold.blocks), y.shape[1]))
        d = np.empty_like(e)
        for j, bl in enumerate(fold.blocks):
            yb = y[bl]
            e[j] = np.sum((yb - sim[bl.start - fold.start : bl.stop - fold.start]) ** 2, axis=0)
            d[j] = np.sum((yb - yb.mean(axis=0)) ** 2, axis=0)
        for stress in fold.stress:
            why = _diverges(model, stress)
            if why is not None:
                return why
        return e, d

    def _one_step(self, model: Narx, blocks) -> float:
        u, y, init = self._u, self._y, self._init
        err, dev = 0.0, 0.0
        try:
            for b in blocks:
                p = model.predict(u[b], y[b])[init:]
                yb = y[b][init:]
                err = err + np.sum((yb - p) ** 2, axis=0)
                dev = dev + np.sum((yb - yb.mean(axis=0)) ** 2, axis=0)
        except IdentificationError:
            return math.inf
        v = float(np.mean(np.sqrt(err / np.where(dev > 0, dev, 1.0))))
        return v if math.isfinite(v) else math.inf

    # ------------------------------------------------------------------ choice
    def _choose(self, u, y) -> None:
        ok = [r for r in self.results_ if r.status == "ok"]
        if not ok:
            counts = {
                s: sum(r.status == s for r in self.results_)
                for s in ("rejected", "failed", "skipped")
            }
            raise IdentificationError(
                "no candidate gave a model whose free run stays bounded on the validation blocks "
                f"and the stress inputs ({counts['rejected']} rejected, {counts['failed']} failed, "
                f"{counts['skipped']} skipped; see results_ / report()). Try lower orders or "
                "degrees, kind='input-polynomial', a larger budget, or check the record"
            )
        fold = self._folds[0]
        long_input = self._long_input(fold.u)
        while True:  # the shortlist's stability margin: the best bounded on a longer input
            best = _pick(ok)
            why = _diverges(self._models[best.candidate], long_input)
            if why is None:
                break
            best.status, best.reason = "rejected", why
            ok.remove(best)
            if not ok:
                raise IdentificationError(
                    "every validated candidate's free run diverges on a longer input of the "
                    f"record's spectrum and level ({why}); see report(). Try lower orders or "
                    "degrees, kind='input-polynomial', or check the record"
                )
        self.best_result_ = best
        fold_model = self._models[best.candidate]
        predicted = best.fit_time * self._refit_scale
        if self._deadline is not None and time.perf_counter() + predicted > self._deadline:
            self.best_ = self._named(fold_model)
            self.refit_ = (
                f"training-part model kept: its refit on the whole record (about "
                f"{predicted:.2g} s) would overrun the budget"
            )
            return
        with warnings.catch_warnings():
            for w in (StabilityWarning, RankDeficiencyWarning):
                warnings.simplefilter("ignore", w)
            self.best_, self.refit_ = self._refit(best, fold_model, u, y)

    def _long_input(self, u: np.ndarray) -> tuple[str, np.ndarray]:
        """The shortlist's stability margin: Gaussian noise of ``u``'s spectrum (Welch), mean
        and RMS, :data:`_LONG_FACTOR` times longer (at most :data:`_LONG_MAX` samples), faded
        in from rest as the stress inputs are."""
        n = min(_LONG_FACTOR * u.shape[0], max(_LONG_MAX, u.shape[0]))
        rng = np.random.default_rng([self.seed, 1])
        x = _spectrum_like(u, n, rng)
        k = max(min(200, n // 10), 1)
        x[:k] *= signal.windows.hann(2 * k + 1)[:k, None]
        return (f"a {n / u.shape[0]:.3g}x longer input of the record's spectrum and level", x)

    def _record_error(self, model: Narx, u, y) -> tuple[float, str | None]:
        """Free-run RRSE over the whole record (mean over outputs; from its first ``init``
        measured outputs) and, when it diverges, where."""
        init = self._init
        try:
            sim = model.simulate(u, y0=y[:init])
        except SimulationDivergedError as exc:
            return math.inf, f"free run over the whole record diverges (sample {exc.sample})"
        e = y[init:] - sim[init:]
        dev = y[init:] - y[init:].mean(axis=0)
        rrse = np.sqrt(np.sum(e**2, axis=0) / _positive(np.sum(dev**2, axis=0)))
        return float(np.mean(rrse)), None

    def _refit(self, best: CandidateResult, fold_model: Narx, u, y):
        """The candidate refitted on the whole record, if it passes the checks its validated
        model passed and is not worse than it beyond the validation's spread; else
        ``fold_model``. Returns (model, what was done)."""
        input_names, output_names = self._names
        c = best.candidate
        kept = "training-part model kept"
        try:
            model = c.narx(self.criterion, self.options).fit(
                u, y, input_names=input_names, output_names=output_names, deadline=self._deadline
            )
        except IdentificationError as exc:
            return self._named(fold_model), f"{kept}: refit failed ({_first_line(exc)})"
        refit, where = self._record_error(model, u, y)
        validated, _ = self._record_error(fold_model, u, y)
        tolerance = max(best.spread / math.sqrt(max(best.block_scores.size, 1)), _TIE * validated)
        self.refit_check_ = {"refit": refit, "validated": validated, "tolerance": tolerance}
        if where is not None:
            return self._named(fold_model), f"{kept}: the refit's {where}"
        for what, us in [*self._stress_inputs(u), self._long_input(u)]:
            why = _diverges(model, (what, us))
            if why is not None:
                return self._named(fold_model), f"{kept}: the refit's {why}"
        if refit > validated + tolerance:
            return self._named(fold_model), (
                f"{kept}: the refit's free run over the whole record is worse (RRSE "
                f"{refit:.3g}) than the validated model's ({validated:.3g}) beyond the "
                f"validation's spread ({tolerance:.2g})"
            )
        return model, "whole record"

    def _named(self, model: Narx) -> Narx:
        input_names, output_names = self._names
        if input_names is not None:
            model.input_names_ = tuple(str(s) for s in input_names)
        if output_names is not None:
            model.output_names_ = tuple(str(s) for s in output_names)
        return model

    # ------------------------------------------------------------------ use
    def _check_fitted(self):
        if not hasattr(self, "best_"):
            raise IdentificationError("this NarxSearch is not fitted yet; call fit(u, y)")

    def report(self, *, limit: int | None = None) -> str:
        """The candidates as a text table: the chosen one first, then by validation score, then
        the rejected, failed and skipped ones with their reasons (also after a search that
        found no model).

        Parameters
        ----------
        limit : int, optional
            Show at most this many rows (default all).
        """
        if not hasattr(self, "results_"):
            self._check_fitted()
        best = getattr(self, "best_result_", None)
        check = getattr(self, "refit_check_", None)
        checked = (
            f"; whole-record free-run RRSE: refit {check['refit']:.3g}, validated "
            f"{check['validated']:.3g}"
            if check and self.refit_ == "whole record"
            else ""
        )
        chosen = (
            f"chosen: {best.candidate.label()} (refit: {self.refit_}{checked})"
            if hasattr(self, "best_")
            else "no model chosen (none validated)"
        )
        rank = {"ok": 0, "rejected": 1, "failed": 2, "skipped": 3}
        chosen_first = best if hasattr(self, "best_") else None
        rows = sorted(
            self.results_, key=lambda r: (r is not chosen_first, rank[r.status], r.score, r.n_terms)
        )
        shown = rows if limit is None else rows[:limit]
        widened = sum(r.origin == "widening" for r in self.results_)
        baselines = sum(r.origin == "baseline" for r in self.results_)
        used = (
            f"{self.search_time_:.1f} s (no budget)"
            if self.budget is None
            else f"{self.search_time_:.1f} s of the {self.budget:g} s budget"
        )
        if getattr(self, "warm_up_time_", 0.0) > 1.0:
            used += f" (after {self.warm_up_time_:.0f} s loading the compiled kernels)"
        folds = getattr(self, "n_folds_", None)
        head = (
            f"NarxSearch: {len(self.results_)} candidates ({baselines} baselines, {widened} from "
            f"widening) in {used}; {sum(r.status == 'ok' for r in rows)} validated"
            + (f" on {folds} fold(s) x {self.n_blocks} block(s)" if folds else "")
            + f"; {chosen}"
        )
        lines = [
            head,
            f"{'':2}{'candidate':<58} {'terms':>6} {'val RRSE':>9} {'spread':>7} {'1-step':>8} "
            f"{'s':>6}  status",
        ]
        for r in shown:
            mark = "*" if r is best and hasattr(self, "best_") else " "
            score = f"{r.score:.4g}" if math.isfinite(r.score) else "-"
            spread = f"{r.spread:.2g}" if math.isfinite(r.spread) else "-"
            one = f"{r.one_step:.3g}" if math.isfinite(r.one_step) else "-"
            status = r.status + (f": {r.reason}" if r.reason else "")
            if r.origin != "grid":
                status += f" ({r.origin})"
            lines.append(
                f"{mark} {r.candidate.label():<58} {r.n_terms:>6} {score:>9} {spread:>7} "
                f"{one:>8} {r.fit_time:>6.2f}  {status}"
            )
        if len(shown) < len(rows):
            lines.append(f"  ... {len(rows) - len(shown)} more")
        return "\n".join(lines)

    def lead_model(self) -> Narx:
        """A cheap stand-in for the search (an ARX of the middle order): what
        :class:`~identification.inverse.InverseModel` ranks the leads with before it runs the
        search once, at the lead chosen."""
        mid = _largest_lag(self.orders[len(self.orders) // 2])
        opts = {k: v for k, v in self.options.items() if k in ("max_radius", "stability_margin")}
        return Narx(order=max(mid, 1), degree=1, **opts)


def _warm_up(u, y) -> None:
    """Load the compiled kernels (free run, prediction, refinement, SEMP) on a tiny problem, so that
    the first candidate's fit time (which sets the rates the budget is planned with) is not the
    kernels' load time."""
    n = min(u.shape[0], 200)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for kw in ({"focus": "simulation", "max_iter": 1}, {"selection": "simulation"}):
            try:
                model = Narx(order=1, degree=2, **kw).fit(u[:n], y[:n])
                model.simulate(u[:n])
                model.predict(u[:n], y[:n])
            except (IdentificationError, np.linalg.LinAlgError, FloatingPointError):
                pass


def _simplicity(c: SearchCandidate) -> tuple[int, int]:
    """Tie-break order of the fitting options: least squares, then simulation focus; all terms,
    FROLS, then SEMP."""
    return (_COST_RANK[c.focus], _COST_RANK.get(c.selection, 2))


def _first_line(exc: BaseException) -> str:
    text = str(exc).strip().splitlines()
    return (text[0] if text else type(exc).__name__)[:200]


def _white_like(u: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """Gaussian noise with each channel's mean, RMS about the mean and band (99 % of its power,
    Welch PSD) — the band edges as fractions of Nyquist; a band reaching 0 is a low-pass."""
    N = u.shape[0]
    out = np.empty_like(u)
    for j, mean, std, f, p in _channel_spectra(u):
        if std == 0:
            out[:, j] = mean
            continue
        cum = np.cumsum(p) / np.sum(p)
        f = f / f[-1]
        lo = float(f[np.searchsorted(cum, 0.005)])
        hi = float(f[min(np.searchsorted(cum, 0.995) + 1, f.size - 1)])
        e = rng.standard_normal(N + 512)
        if hi < 0.999:
            if lo > 0.002:
                sos = signal.butter(4, [lo, hi], btype="bandpass", output="sos")
            else:
                sos = signal.butter(4, hi, output="sos")
            e = signal.sosfilt(sos, e)
        e = e[512:]
        out[:, j] = mean + std * (e - e.mean()) / e.std()
    return out


def _pick(ok: list[CandidateResult]) -> CandidateResult:
    """The choice among validated candidates (:func:`_best_of`), where a candidate the
    widening found must beat the best of the others by more than that one's spread: the
    widening looks where the validation scored well, and what it finds by looking there is
    chosen only when its advantage is more than the validation's block-to-block variation
    (measured on the Cascaded Tanks record, 1,024 samples: a widened candidate validating 28 %
    better tested 21 % worse)."""
    searched = [r for r in ok if r.origin != "widening"]
    widened = [r for r in ok if r.origin == "widening"]
    if not searched or not widened:
        return _best_of(searched or widened)
    best, found = _best_of(searched), _best_of(widened)
    return found if found.score < best.score - best.spread else best


def _best_of(ok: list[CandidateResult]) -> CandidateResult:
    """The lowest score; scores within :data:`_TIE` of it are ties, broken by the spread (the
    steadiest within 10 % or the tie resolution of the smallest spread), then by fewer terms,
    then by the simpler fit."""
    low = min(r.score for r in ok)
    tied = [r for r in ok if r.score <= low * (1 + _TIE)]
    calm = min(r.spread for r in tied)
    steady = [r for r in tied if r.spread <= 1.1 * calm + _TIE * low]
    return min(steady, key=lambda r: (r.n_terms, *_simplicity(r.candidate), r.score))


def _diverges(model: Narx, stress: tuple[str, np.ndarray]) -> str | None:
    """Why ``model``'s free run from rest on the stress input diverges (None: it is bounded)."""
    what, u = stress
    try:
        model.simulate(u)
    except SimulationDivergedError as exc:
        return f"free run diverges on {what} (sample {exc.sample})"
    return None


def _spectrum_like(u: np.ndarray, n: int, rng: np.random.Generator) -> np.ndarray:
    """``n`` samples of Gaussian noise per channel with ``u``'s mean, RMS about the mean and
    power spectrum shape (Welch, interpolated onto the longer record's frequency lines)."""
    out = np.empty((n, u.shape[1]))
    freqs = np.fft.rfftfreq(n)
    for j, mean, std, f, p in _channel_spectra(u):
        if std == 0:
            out[:, j] = mean
            continue
        shape = np.sqrt(np.interp(freqs, f, p))
        e = np.fft.irfft(np.fft.rfft(rng.standard_normal(n)) * shape, n)
        out[:, j] = mean + std * (e - e.mean()) / e.std()
    return out


def _channel_spectra(u: np.ndarray):
    """Per input channel ``(j, mean, std, f, p)``: its mean, RMS about the mean and Welch PSD
    (``f`` in cycles per sample; ``f, p`` None for a constant channel)."""
    for j in range(u.shape[1]):
        x = u[:, j]
        mean, std = float(x.mean()), float(x.std())
        if std == 0:
            yield j, mean, std, None, None
            continue
        f, p = signal.welch(x - mean, nperseg=min(1024, u.shape[0]))
        yield j, mean, std, f, p
