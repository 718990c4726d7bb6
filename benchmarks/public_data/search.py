"""The model search of the protocol: candidate structures, free-run scores, the choice on
training data only (75/25 validation, ties to fewer terms, refit, stability on training)."""

from __future__ import annotations

import itertools
import time
import warnings
from dataclasses import dataclass

import numpy as np

from identification import (
    IdentificationError,
    Narx,
    RankDeficiencyWarning,
    SimulationDivergedError,
    StabilityWarning,
    metrics,
)

VALIDATION_FRACTION = 0.25  # of the training part, for the model search


@dataclass(frozen=True)
class Candidate:
    """One candidate structure: SysIdentPy-style ``ylag = na``, ``xlag = nb`` (lags 1..n).

    The defaults are the one-step (FROLS + least squares) models of the original rows; the
    simulation rows set ``focus="simulation"`` (output-error Levenberg-Marquardt, early stopping
    on the fit's own last ``holdout`` fraction), ``selection="simulation"`` (SEMP, model size by
    BIC on the free-run residuals), a term ``kind`` other than "full", ``n_terms=None`` (every
    candidate term, no selection) or per-input lags (``nb`` a tuple). ``features`` names the
    input columns when the bench passes several input sets (``u`` a dict, see :func:`_inputs`).
    """

    degree: int
    na: int
    nb: int | tuple[int, ...]
    n_terms: int | None
    nk: int = 1  # first input lag: 1 as in SysIdentPy, 0 adds the current input u(t)
    kind: str = "full"
    focus: str = "prediction"
    selection: str = "frols"
    holdout: float = 0.2
    max_iter: int = 50
    features: str = ""
    functions: tuple = ()  # non-polynomial terms of the inputs (Narx(functions=...))

    def model(self) -> Narx:
        extra = {}
        if self.focus == "simulation":
            extra = {"focus": "simulation", "holdout": self.holdout, "max_iter": self.max_iter}
        return Narx(
            na=self.na,
            nb=list(self.nb) if isinstance(self.nb, tuple) else self.nb,
            nk=self.nk,
            degree=self.degree,
            kind=self.kind,
            constant=True,
            n_terms=self.n_terms,
            selection=self.selection,
            functions=list(self.functions) or None,
            **extra,
        )

    def label(self, terms: int | None = None) -> str:
        t = self.n_terms if terms is None else terms
        nbs = self.nb if isinstance(self.nb, tuple) else (self.nb,)
        ulags = "/".join(f"{self.nk}..{self.nk + b - 1}" for b in nbs)
        kind = {"full": "", "pure": "pure-power "}.get(self.kind, f"{self.kind} ")
        txt = f"{kind}NARX deg {self.degree}, y lags 1..{self.na}, u lags {ulags}, {t} terms"
        if self.selection == "simulation":
            txt += f" (SEMP ≤{self.n_terms}, BIC)"
        elif self.n_terms is None and self.focus == "simulation":
            txt += " (all)"
        if self.focus == "simulation":
            txt += f", sim. focus (holdout {self.holdout:g})"
        if self.features:
            extra = [f if f == "v" else f"tanh(v/{f[5:]})" for f in self.features.split(",")]
            txt += f", inputs + {' + '.join(extra)}"
        if self.functions:
            names = [f if isinstance(f, str) else f"{f[0]}({f[1]})" for f in self.functions]
            txt += f", functions of the inputs: {', '.join(names)}"
        return txt


def grid(degrees, lags, n_terms, nk: int = 1, **kw) -> list[Candidate]:
    """Candidates over degree x lags (``na = nb``) x number of terms; ``kw``: other fields."""
    return [
        Candidate(d, n, n, k, nk, **kw) for d, n, k in itertools.product(degrees, lags, n_terms)
    ]


def _inputs(u, cand: Candidate) -> np.ndarray:
    """The input record of ``cand``: ``u`` itself, or ``u[cand.features]`` when ``u`` is a dict
    of input sets (fixed, non-learned transforms of the measured inputs, e.g. a velocity)."""
    return u[cand.features] if isinstance(u, dict) else u


def free_run(model: Narx, u: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Free run over the record ``u``, started from its first ``max_lag_`` measured outputs."""
    p = model.max_lag_
    return model.simulate(u, y0=np.asarray(y)[:p])[:, 0]


def _score(metric: str, y: np.ndarray, yhat: np.ndarray) -> float:
    if metric == "rmse_mv":
        return 1000.0 * float(metrics.rmse(y, yhat))
    if metric == "rmse":
        return float(metrics.rmse(y, yhat))
    if metric == "rrse":
        return float(metrics.rrse(y, yhat))
    if metric == "nrmse":
        return float(metrics.nrmse(y, yhat))
    raise ValueError(metric)


def _fit_and_score(cand: Candidate, u, y, fit: slice, val: slice, metric: str, skip: int):
    """Fit ``cand`` on ``u[fit], y[fit]``, free-run score on ``u[val], y[val]`` (``inf``: failed
    fit, diverged free run, or a largest lag beyond the ``skip`` window); and the model's terms."""
    try:
        model = cand.model().fit(u[fit], y[fit])
    except IdentificationError:
        return np.inf, cand.n_terms or 0
    terms = int(model.n_terms_[0])
    if model.max_lag_ > skip:
        return np.inf, terms
    try:
        sim = free_run(model, u[val], y[val])
    except SimulationDivergedError:
        return np.inf, terms
    return _score(metric, y[val][skip:], sim[skip:]), terms


def validation_score(
    cand: Candidate, u, y, metric: str, skip: int, two_fold: bool = False
) -> tuple[float, int]:
    """Fit on the first 75 % of the training data, free-run score on the last 25 %.

    ``two_fold``: also fit on the last 75 % and score on the first 25 %, and return the mean of
    the two scores (both folds are contiguous slices of the training record; for records too
    short for one 25 % slice to be representative). Returns the score (``inf`` when a free run
    diverged or the model's largest lag exceeds the ``skip`` initialisation window) and the
    number of terms of the (first) fitted model. ``u`` may be a dict of input sets.
    """
    u = _inputs(u, cand)
    n = len(y)
    cut = int(n * (1 - VALIDATION_FRACTION))
    score, terms = _fit_and_score(cand, u, y, slice(0, cut), slice(cut, n), metric, skip)
    if two_fold and np.isfinite(score):
        other, _ = _fit_and_score(cand, u, y, slice(n - cut, n), slice(0, n - cut), metric, skip)
        score = (score + other) / 2
    return score, terms


def stable_on(model: Narx, u, y) -> bool:
    """True when the model's free run over the record ``u, y`` stays within its bound."""
    try:
        free_run(model, u, y)
    except SimulationDivergedError:
        return False
    return True


@dataclass
class Selection:
    best: Candidate
    model: Narx
    val_score: float
    n_tried: int
    n_unstable: int  # better-scoring candidates whose free run over the training data diverged
    search_time: float
    fit_time: float

    def note(self) -> str:
        n = self.n_tried
        txt = (
            f"chosen from {n} candidate{'s' * (n != 1)} on training data ({self.search_time:.1f} s)"
        )
        if self.n_unstable:
            txt += f"; {self.n_unstable} better-validating one(s) rejected: unstable on training"
        return txt


@dataclass
class Pool:
    """Validation scores of a candidate grid: ``(score, terms, candidate)`` rows."""

    rows: list[tuple[float, int, Candidate]]
    time: float


def score_candidates(
    u, y, candidates: list[Candidate], metric: str, skip: int, two_fold: bool = False
) -> Pool:
    """Validation score of every candidate (:func:`validation_score`), training data only."""
    t0 = time.perf_counter()
    with warnings.catch_warnings():  # search fits: their warnings are not news here
        warnings.simplefilter("ignore", StabilityWarning)
        warnings.simplefilter("ignore", RankDeficiencyWarning)
        rows = [(*validation_score(c, u, y, metric, skip, two_fold), c) for c in candidates]
    return Pool(rows, time.perf_counter() - t0)


def choose(pool: Pool, u, y, max_terms: int | None = None) -> Selection:
    """Best candidate of ``pool``, refitted on the whole training record ``u, y``.

    Candidates are ranked by validation score; among scores within 0.1 % of the best, the model
    with fewer terms wins. The winner is refitted on all of ``u, y`` and kept if its free run over
    that record stays bounded, else the next one is tried. ``max_terms`` leaves out candidates
    whose fitted models have more terms. ``u`` may be a dict of input sets (:func:`_inputs`).
    """
    t0 = time.perf_counter()
    rows = [r for r in pool.rows if np.isfinite(r[0]) and (max_terms is None or r[1] <= max_terms)]
    n_tried = sum(1 for r in pool.rows if max_terms is None or r[1] <= max_terms)
    rejected = 0
    while rows:
        s_min = min(r[0] for r in rows)
        score, _, best = min((r for r in rows if r[0] <= s_min * 1.001), key=lambda r: (r[1], r[0]))
        t_fit = time.perf_counter()
        model = best.model().fit(_inputs(u, best), y)
        fit_time = time.perf_counter() - t_fit
        if max_terms is not None and model.n_terms_[0] > max_terms:
            rows = [r for r in rows if r[2] != best]  # the refit kept more terms: over budget
            continue
        if stable_on(model, _inputs(u, best), y):
            search = pool.time + time.perf_counter() - t0 - fit_time
            return Selection(best, model, score, n_tried, rejected, search, fit_time)
        rejected += 1
        rows = [r for r in rows if r[2] != best]
    raise IdentificationError("every candidate model diverged on the training data")


def select_and_fit(
    u,
    y,
    candidates: list[Candidate],
    metric: str,
    skip: int,
    max_terms: int | None = None,
    two_fold: bool = False,
) -> Selection:
    """Model search on the training data ``u, y`` only, then refit of the best on all of it."""
    pool = score_candidates(u, y, candidates, metric, skip, two_fold)
    return choose(pool, u, y, max_terms)


def _safe(fn) -> float:
    """Score of a free run, ``inf`` when it diverges (vrig raises, SysIdentPy returns inf/nan)."""
    try:
        v = fn()
    except (SimulationDivergedError, FloatingPointError, OverflowError, IdentificationError):
        return np.inf
    return v if np.isfinite(v) else np.inf


def _finite_score(metric, y, yhat) -> float:
    return _score(metric, y, yhat) if np.all(np.isfinite(yhat)) else np.inf


def _sim(degrees, lags, n_terms, **kw) -> tuple[Candidate, ...]:
    """A simulation-focus grid (:func:`grid` with ``focus="simulation"``)."""
    return tuple(grid(degrees, lags, n_terms, focus="simulation", **kw))
