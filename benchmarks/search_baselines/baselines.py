"""The two baseline families and how each is chosen on the training part.

* FROLS + BIC: SysIdentPy 0.9 ``FROLS(order_selection=True, info_criteria="bic")`` with its
  Polynomial basis, LeastSquares estimation (as the project's other SysIdentPy runs,
  :class:`benchmarks.public_data.SysIdentPy`) and its other defaults (``n_info_values=15``);
  or, where SysIdentPy is not importable (or ``--no-sysidentpy``), vrig's
  ``Narx(na=n, nb=n, nk=1, degree=d, selection="frols", criterion="bic", constant=True)``.
  Grid: ``ylag = xlag = n`` in :data:`FROLS_LAGS`, degree in :data:`FROLS_DEGREES`. SysIdentPy
  fits one MISO model per output (inputs and that output's past); vrig one MIMO model.
* Linear: ARX (least squares) and linear output error (``Narx(degree=1, focus="simulation")``),
  ``Narx(order=n, degree=1, constant=True)`` (output lags 1..n, input lags 0..n) for n in
  :data:`LINEAR_ORDERS`.

Every grid is capped by the record: no lag above its ``max_lag`` (the test's measured window),
no candidate set larger than half the rows it is fitted on. :func:`choose` picks within a
family by the held-out free run on the training part (see the package docstring).
"""

from __future__ import annotations

import inspect
import time
import warnings
from collections.abc import Callable
from dataclasses import dataclass
from math import comb

import numpy as np

from benchmarks.public_data import SysIdentPy
from identification import (
    IdentificationError,
    Narx,
    RankDeficiencyWarning,
    SimulationDivergedError,
    StabilityWarning,
)

from .scoring import FreeRun, validation_cut, validation_score

FROLS_LAGS = (1, 2, 4, 8)
FROLS_DEGREES = (1, 2)
LINEAR_ORDERS = (1, 2, 3, 4, 6, 8)
#: validation scores within this relative margin of the best tie; the tie goes to fewer terms
#: (the rule of :func:`benchmarks.public_data.choose`)
TIE = 1e-3
#: a SysIdentPy free run beyond this multiple of the training output's peak counts as diverged,
#: the bound vrig's models apply to their own free runs (``Narx(bound_factor=...)``'s default)
BOUND_FACTOR = inspect.signature(Narx).parameters["bound_factor"].default
#: what a failed candidate fit raises (vrig: IdentificationError, a ValueError; SysIdentPy:
#: ValueError, LinAlgError, arithmetic errors)
FIT_ERRORS = (ValueError, ArithmeticError, np.linalg.LinAlgError)


class VrigFreeRun:
    """A fitted :class:`~identification.Narx` as a :class:`~.scoring.FreeRun`."""

    def __init__(self, narx: Narx):
        self.narx = narx
        self.max_lag = int(narx.max_lag_)
        self.terms = int(np.sum(narx.n_terms_))

    def simulate(self, u, y0):
        return self.narx.simulate(u, y0=y0)


class SipFreeRun:
    """SysIdentPy models, one per output, as a :class:`~.scoring.FreeRun`: each runs free
    (``predict(steps_ahead=None)``) from its last ``max_lag`` measured outputs; a run that is
    not finite or leaves ``bound`` raises :class:`~identification.SimulationDivergedError`."""

    def __init__(self, models, bound: np.ndarray):
        self.models, self.bound = list(models), np.asarray(bound, dtype=float)
        self.max_lag = max(int(m.max_lag) for m in self.models)
        self.terms = sum(SysIdentPy.n_terms(m) for m in self.models)

    def simulate(self, u, y0):
        n, k = len(u), len(y0)
        out = np.empty((n, len(self.models)))
        out[:k] = y0
        for j, m in enumerate(self.models):
            p = int(m.max_lag)
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                run = np.asarray(m.predict(X=u[k - p :], y=y0[k - p :, j : j + 1])).ravel()
            out[k:, j] = run[p : p + n - k]
        bad = ~np.isfinite(out) | (np.abs(out) > self.bound)
        if bad.any():
            k, j = np.argwhere(bad)[0]
            raise SimulationDivergedError(
                int(j),
                f"y{j}",
                int(k),
                float(out[k, j]),
                float(self.bound[j]),
                "free-run simulation",
            )
        return out


@dataclass(frozen=True)
class Candidate:
    """One model of a family's grid: ``fit(u, y)`` returns the fitted :class:`FreeRun`."""

    label: str
    lag: int
    fit: Callable[[np.ndarray, np.ndarray], FreeRun]


@dataclass
class Choice:
    """The candidate :func:`choose` kept, refitted on the whole training part."""

    candidate: Candidate
    model: FreeRun
    val_score: float
    n_tried: int
    n_failed: int  # fit failed or validation free run diverged
    n_unstable: int  # better-validating ones whose refit diverged on the training part
    seconds: float

    def note(self) -> str:
        """One line: what was tried and rejected."""
        txt = (
            f"chosen from {self.n_tried} candidates (validation NRMSE {self.val_score:.4g}; "
            f"{self.n_failed} failed or diverged on validation"
        )
        if self.n_unstable:
            txt += f"; {self.n_unstable} better one(s) diverged on training after the refit"
        return txt + ")"


def _fit_quietly(cand: Candidate, u, y) -> FreeRun | None:
    with warnings.catch_warnings():
        for w in (StabilityWarning, RankDeficiencyWarning, RuntimeWarning):
            warnings.simplefilter("ignore", w)
        try:
            return cand.fit(u, y)
        except FIT_ERRORS:
            return None


def choose(candidates: list[Candidate], u, y, window: int, progress=None) -> Choice:
    """The best candidate by held-out free run, refitted on the whole training part.

    Each candidate is fitted on the first 75 % of ``u, y`` and run free on the last 25 % from
    that slice's first ``window`` measured outputs (NRMSE of the rest); the best (ties within
    :data:`TIE`: fewer terms) is refitted on all of ``u, y`` and kept if its free run over them
    stays bounded, else the next is tried. ``progress(text)`` is told each validation score.
    Raises :class:`~identification.IdentificationError` when none is left.
    """
    t0 = time.perf_counter()
    cut = validation_cut(len(y))
    rows, failed = [], 0
    for c in candidates:
        m = _fit_quietly(c, u[:cut], y[:cut])
        s = np.inf if m is None else validation_score(m, u[cut:], y[cut:], window)
        if progress is not None:
            progress(f"{c.label}: validation NRMSE {s:.4g}" + (" (fit failed)" * (m is None)))
        if np.isfinite(s):
            rows.append((s, m.terms, c))
        else:
            failed += 1
    unstable = 0
    while rows:
        s_min = min(r[0] for r in rows)
        score, _, best = min((r for r in rows if r[0] <= s_min * (1 + TIE)), key=lambda r: r[:2])
        model = _fit_quietly(best, u, y)
        if model is not None and np.isfinite(validation_score(model, u, y, window)):
            elapsed = time.perf_counter() - t0
            return Choice(best, model, score, len(candidates), failed, unstable, elapsed)
        unstable += 1
        rows = [r for r in rows if r[2] is not best]
    raise IdentificationError(
        f"every one of {len(candidates)} candidates failed, diverged on validation or diverged "
        "on the training part after its refit"
    )


def _regressors(lag: int, n_past: int, nu: int, degree: int) -> int:
    """Candidate terms (constant included) of a polynomial of ``n_past`` output lags and ``nu``
    input lags, each 1..lag."""
    return comb(lag * (n_past + nu) + degree, degree)


def _sip_candidate(sip: SysIdentPy, n: int, d: int, nu: int, ny: int) -> Candidate:
    xlag = n if nu == 1 else [list(range(1, n + 1))] * nu

    def fit(u, y):
        models = [
            sip.fit(
                u, y[:, j], degree=d, ylag=n, xlag=xlag, order_selection=True, info_criteria="bic"
            )[0]
            for j in range(ny)
        ]
        peak = np.max(np.abs(y), axis=0)
        return SipFreeRun(models, BOUND_FACTOR * np.where(peak > 0, peak, 1.0))

    return Candidate(f"FROLS+BIC ylag=xlag={n}, degree {d}", n, fit)


def _vrig_frols_candidate(n: int, d: int) -> Candidate:
    def fit(u, y):
        narx = Narx(na=n, nb=n, nk=1, degree=d, selection="frols", criterion="bic", constant=True)
        return VrigFreeRun(narx.fit(u, y))

    return Candidate(f"FROLS+BIC ylag=xlag={n}, degree {d}", n, fit)


def frols_candidates(max_lag: int, n_train: int, nu: int, ny: int, sip: SysIdentPy | None):
    """The FROLS grid within the record's limits (SysIdentPy's when ``sip`` is given, else
    vrig's) and a note on what the limits left out."""
    rows = validation_cut(n_train)
    out, dropped = [], []
    for n in FROLS_LAGS:
        for d in FROLS_DEGREES:
            size = _regressors(n, 1 if sip else ny, nu, d)
            if n > max_lag or size > (rows - n) / 2:
                dropped.append(f"lag {n} degree {d}")
                continue
            out.append(_sip_candidate(sip, n, d, nu, ny) if sip else _vrig_frols_candidate(n, d))
    return out, _dropped_note(dropped, max_lag)


def _linear_candidate(n: int, output_error: bool) -> Candidate:
    def fit(u, y):
        extra = {"focus": "simulation"} if output_error else {}
        return VrigFreeRun(Narx(order=n, degree=1, constant=True, **extra).fit(u, y))

    name = "linear OE" if output_error else "ARX"
    return Candidate(f"{name} order {n}", n, fit)


def linear_candidates(max_lag: int, n_train: int, nu: int, ny: int):
    """ARX and linear output-error models of every order of :data:`LINEAR_ORDERS` within the
    record's limits, and a note on what the limits left out."""
    rows = validation_cut(n_train)
    out, dropped = [], []
    for n in LINEAR_ORDERS:
        if n > max_lag or _regressors(n, ny, nu, 1) + nu > (rows - n) / 2:
            dropped.append(f"order {n}")
            continue
        out += [_linear_candidate(n, False), _linear_candidate(n, True)]
    return out, _dropped_note(dropped, max_lag)


def _dropped_note(dropped: list[str], max_lag: int) -> str:
    if not dropped:
        return ""
    return (
        f"left out ({', '.join(dropped)}): a lag above the record's {max_lag}-sample measured "
        "window or more candidate terms than half the fitting rows"
    )
