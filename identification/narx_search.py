"""One NARX call a user can trust: structure and options searched, judged by free run.

:class:`NarxSearch` fits a grid of :class:`~identification.models.Narx` candidates — orders,
degrees, term kinds, non-polynomial functions, and the fitting options ``focus``
(least squares or simulation error) and ``selection`` (all terms, FROLS, SEMP) — and keeps the one
whose **free run** best reproduces data it was not fitted on. No single option is best on every
data set (measured on six real data sets: simulation focus won on three, free-run selection on
one, plain least squares on another), and a least-squares model that passes its own stability
check can still diverge on other inputs; the search makes both choices from the data.

Validation (documented protocol)
    The last ``holdout`` fraction of the record is held out (``folds=2``: also the first
    ``holdout`` fraction, with the model then fitted on the last ``1 - holdout``; the score is the
    mean of the two folds). The held-out part is cut into ``n_blocks`` contiguous blocks; each
    block's free run starts from its own first ``init_window`` measured outputs
    (nonlinear_benchmarks' convention) and is scored on the rest. The score of an output is its
    root relative squared error over the blocks, ``sqrt(sum e^2 / sum (y - mean y)^2)`` (an NRMSE
    normalised by the held-out output's standard deviation); a candidate's score is the mean over
    its outputs.

Rejection (a candidate is never returned when)
    its fit fails or its stability contract refuses it; its free run leaves the model's bound
    (``bound_``, 1000 x the record's peak by default) or becomes non-finite on **any** validation
    block; or on the identification input scaled by 0.5 and by 2 (from rest: a zero past and
    the input faded in over its first ``min(200, N / 10)`` samples); or on a
    white Gaussian input of the same mean, RMS and band as the identification input (band: the
    frequencies holding 99 % of its power, estimated by Welch's method; the noise drawn from
    ``seed``). Every candidate's row in :attr:`NarxSearch.results_` says why it was rejected.

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
    bounds the wall time of :meth:`NarxSearch.fit`; ``budget=None`` tries every candidate to
    the end. With ``budget=None`` everything is deterministic under ``seed``; with a budget, the
    candidates tried (and a fit cut short) depend on the machine's speed.

Refit
    The best candidate (ties within 1 %: fewer terms, then the simpler fit — least squares before
    simulation focus, all terms before FROLS before SEMP) is refitted on the whole record and kept if
    its free run is bounded on every validation block, on the whole record and on the stress
    inputs; otherwise (or when the refit would overrun the budget) the model fitted on the training
    part (the one validated) is returned. ``refit_`` says which. The refit gets the search's
    deadline too (a refinement past it keeps the best iterate reached).
"""

from __future__ import annotations

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
        """What stage 2 ranks and refines: the structure and the selection size (``None``: all
        terms, or sized by the criterion)."""
        return (*self.structure, self.n_terms)

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
        Fraction of the record held out for validation, in (0, 0.5].
    folds : {1, 2}
        1: the last ``holdout`` is held out; 2: also the first (fitted on the last part).
    n_blocks : int
        Contiguous validation blocks the held-out part is cut into (each started from its own
        measured window).
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
    search_time_ : float
        Wall time of :meth:`fit`, seconds.

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
        folds: int = 1,
        n_blocks: int = 2,
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
        if folds not in (1, 2):
            raise IdentificationError(f"folds must be 1 or 2, got {folds!r}")
        self.folds = int(folds)
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
        out = []
        for n, d, kind, funs in itertools.product(
            self.orders, self.degrees, self.kinds, self.functions
        ):
            out.append((n, d, "full" if d == 1 else kind, funs))
        return list(dict.fromkeys(out))

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
        t0 = time.perf_counter()
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
        for stale in ("best_", "best_result_", "refit_"):  # a refit that fails keeps no old model
            self.__dict__.pop(stale, None)
        self._t0 = t0
        self._deadline = None if self.budget is None else t0 + self.budget
        self._prepare(u, y)
        _warm_up(u, y)
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
                self._choose(u, y)
            finally:  # report() works after a failed search too (it says why each failed)
                self.search_time_ = time.perf_counter() - t0
        return self

    def _prepare(self, u, y) -> None:
        """Folds, validation blocks and stress inputs; refuses a record too short for them."""
        N = u.shape[0]
        init = self.init_window or max(self._max_lag(), 1)
        n_val = round(self.holdout * N)
        block = n_val // self.n_blocks
        need = init + max(10, 2 * init)
        if block < need:
            raise InsufficientDataError(
                f"a record of {N} samples is too short for the validation: its held-out "
                f"{self.holdout:g} ({n_val} samples) in {self.n_blocks} block(s) gives "
                f"{block}-sample blocks, but each needs at least {need} ({init} measured "
                f"initial samples + {need - init} scored). Give a longer record, a larger "
                "holdout, fewer blocks or smaller orders"
            )
        self._init = init
        folds = [(slice(0, N - n_val), (N - n_val, N))]
        if self.folds == 2:
            folds.append((slice(n_val, N), (0, n_val)))
        self._folds = []
        for fit, (a, b) in folds:
            edges = np.linspace(a, b, self.n_blocks + 1).round().astype(int)
            blocks = [slice(int(s), int(e)) for s, e in itertools.pairwise(edges)]
            self._folds.append((u[fit], y[fit], blocks, self._stress_inputs(u[fit])))
        self._u, self._y = u, y
        self._rows = N - n_val

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
            # for all terms (else stage 2 never sees it)
            if asked or (selects and self._too_big(base, size[base])):
                for k in self.n_terms:
                    c = SearchCandidate(*s, "prediction", "frols", self.lags, k)
                    size[c] = self._terms(c)
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
        if not self._stage2_options() or not ranked:
            return
        lags = self.lags
        size = {e: self._terms(SearchCandidate(*e[:4], "prediction", "all", lags)) for e in ranked}
        smallest = min(ranked, key=lambda e: (size[e], ranked.index(e)))
        first = self._entry_candidates(smallest)
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
        *s, k = entry
        opts = self._stage2_options()
        if k is not None:
            opts = [o for o in opts if o[1] != "all"]
            sizes = [k]
        else:
            sizes = [None]
        return [SearchCandidate(*s, *o, self.lags, n) for o in opts for n in sizes]

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
        return self._rows * work * self.folds

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

    def _try(self, c: SearchCandidate) -> CandidateResult:
        terms = self._terms(c)
        result = CandidateResult(c, "skipped")
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
        training part to the whole record (plus 20 %), at most a quarter of the budget (a
        refit that does not fit in what is left is skipped: see ``refit_``)."""
        ok = [r for r in getattr(self, "results_", []) if r.status == "ok"]
        if not ok or self.budget is None:
            return 0.0
        best = min(ok, key=lambda r: r.score)
        return min(1.2 * best.fit_time / self.folds / (1.0 - self.holdout), 0.25 * self.budget)

    def _record(self, result: CandidateResult) -> CandidateResult:
        self.results_.append(result)
        if self.callback is not None:
            self.callback(result)
        return result

    def _evaluate(self, c: SearchCandidate, result: CandidateResult) -> None:
        """Fit on each fold's training part, validate; fills ``result`` in place."""
        sq_err, sq_dev, one_step = 0.0, 0.0, []
        for ufit, yfit, blocks, stress in self._folds:
            model = c.narx(self.criterion, self.options)
            deadline = (
                None
                if self._deadline is None
                else self._deadline - self._reserve() - _FIT_SLACK * self.budget
            )
            try:
                model.fit(ufit, yfit, deadline=deadline)
            except (IdentificationError, np.linalg.LinAlgError, FloatingPointError) as exc:
                result.status, result.reason = "failed", _first_line(exc)
                if isinstance(exc, UnstableModelError) and hasattr(model, "coef_"):
                    result.one_step = self._one_step(model, blocks)  # ranks it for stage 2
                return
            result.n_terms = int(np.sum(model.n_terms_))
            verdict = self._validate(model, blocks, stress)
            if isinstance(verdict, str):
                result.status, result.reason = "rejected", verdict
                result.one_step = self._one_step(model, blocks)
                return
            if model.timed_out_:
                result.reason = "cut short by the budget (the best iterate reached)"
            sq_err, sq_dev = sq_err + verdict[0], sq_dev + verdict[1]
            one_step.append(self._one_step(model, blocks))
            self._models.setdefault(c, model)
        scores = np.sqrt(sq_err / np.where(sq_dev > 0, sq_dev, 1.0))
        result.status, result.scores = "ok", scores
        result.score, result.one_step = float(np.mean(scores)), float(np.mean(one_step))

    def _validate(self, model: Narx, blocks, stress):
        """``(sum e^2, sum (y - mean)^2)`` per output over the blocks, or why it is rejected."""
        u, y, init = self._u, self._y, self._init
        sq_err, sq_dev = 0.0, 0.0
        for i, b in enumerate(blocks):
            try:
                sim = model.simulate(u[b], y0=y[b][:init])
            except SimulationDivergedError as exc:
                return (
                    f"free run diverges on validation block {i + 1} (sample {b.start + exc.sample})"
                )
            e = y[b][init:] - sim[init:]
            sq_err = sq_err + np.sum(e**2, axis=0)
            yb = y[b][init:]
            sq_dev = sq_dev + np.sum((yb - yb.mean(axis=0)) ** 2, axis=0)
        for what, us in stress:
            try:
                model.simulate(us)
            except SimulationDivergedError as exc:
                return f"free run diverges on {what} (sample {exc.sample})"
        return sq_err, sq_dev

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
        low = min(r.score for r in ok)
        tied = [r for r in ok if r.score <= low * (1 + _TIE)]
        best = min(tied, key=lambda r: (r.n_terms, *_simplicity(r.candidate), r.score))
        self.best_result_ = best
        fold_model = self._models[best.candidate]
        predicted = best.fit_time / self.folds / (1.0 - self.holdout)
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
            self.best_, self.refit_ = self._refit(best.candidate, fold_model, u, y)

    def _refit(self, c: SearchCandidate, fold_model: Narx, u, y):
        """The candidate refitted on the whole record if it stays bounded, else ``fold_model``."""
        input_names, output_names = self._names
        try:
            model = c.narx(self.criterion, self.options).fit(
                u, y, input_names=input_names, output_names=output_names, deadline=self._deadline
            )
        except IdentificationError as exc:
            return self._named(
                fold_model
            ), f"training-part model kept: refit failed ({_first_line(exc)})"
        blocks = [b for _, _, bl, _ in self._folds for b in bl] + [slice(0, u.shape[0])]
        verdict = self._validate(model, blocks, self._stress_inputs(u))
        if isinstance(verdict, str):
            return self._named(fold_model), f"training-part model kept: the refit's {verdict}"
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
        """The candidates as a text table, best validation score first, then the rejected,
        failed and skipped ones with their reasons (also after a search that found no model).

        Parameters
        ----------
        limit : int, optional
            Show at most this many rows (default all).
        """
        if not hasattr(self, "results_"):
            self._check_fitted()
        best = getattr(self, "best_result_", None)
        chosen = (
            f"chosen: {best.candidate.label()} (refit: {self.refit_})"
            if hasattr(self, "best_")
            else "no model chosen (none validated)"
        )
        rank = {"ok": 0, "rejected": 1, "failed": 2, "skipped": 3}
        rows = sorted(self.results_, key=lambda r: (rank[r.status], r.score, r.n_terms))
        shown = rows if limit is None else rows[:limit]
        head = (
            f"NarxSearch: {len(self.results_)} candidates in {self.search_time_:.1f} s "
            f"(budget {'none' if self.budget is None else f'{self.budget:g} s'}); "
            f"{sum(r.status == 'ok' for r in rows)} validated, {chosen}"
        )
        lines = [
            head,
            f"{'':2}{'candidate':<58} {'terms':>6} {'val RRSE':>9} {'1-step':>8} {'s':>6}  status",
        ]
        for r in shown:
            mark = "*" if r is best and hasattr(self, "best_") else " "
            score = f"{r.score:.4g}" if math.isfinite(r.score) else "-"
            one = f"{r.one_step:.3g}" if math.isfinite(r.one_step) else "-"
            status = r.status + (f": {r.reason}" if r.reason else "")
            lines.append(
                f"{mark} {r.candidate.label():<58} {r.n_terms:>6} {score:>9} {one:>8} "
                f"{r.fit_time:>6.2f}  {status}"
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
    N, nu = u.shape
    out = np.empty_like(u)
    for j in range(nu):
        x = u[:, j]
        mean, std = float(x.mean()), float(x.std())
        if std == 0:
            out[:, j] = mean
            continue
        f, p = signal.welch(x - mean, nperseg=min(1024, N))
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
