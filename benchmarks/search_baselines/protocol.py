"""One record through the protocol (package docstring): the three model families chosen on the
training part, each scored once on the test part, the ratios and the goal."""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from benchmarks.public_data import SysIdentPy
from identification import IdentificationError, NarxSearch, SimulationDivergedError

from .baselines import Choice, VrigFreeRun, choose, frols_candidates, linear_candidates
from .records import Record
from .scoring import FreeRun, nrmse

FAMILIES = ("NarxSearch", "FROLS", "linear")
#: the goal (issue 34): NarxSearch's test NRMSE at most this multiple of FROLS+BIC's ...
GOAL_VS_FROLS = 0.5
#: ... and at most this multiple of the best linear model's, never diverging
GOAL_VS_LINEAR = 1.0
DIVERGED = "DIVERGED"


@dataclass
class Row:
    """One model's line of the table. ``nrmse``: test NRMSE (``inf``: its free run diverged or
    no model was found); ``metric``: the record's own metric (None without one); ``status``:
    ``"ok"``, ``"DIVERGED"`` or ``"failed: why"``."""

    record: str
    family: str
    model: str
    terms: int | None
    nrmse: float
    metric: float | None
    fit_s: float
    status: str = "ok"
    note: str = ""


@dataclass
class RecordResult:
    """A record's rows, the NarxSearch details, the ratios and the goal."""

    name: str
    key: str
    n_train: int
    n_test: int
    split: str
    source: str
    metric_label: str
    rows: list[Row] = field(default_factory=list)
    search: dict = field(default_factory=dict)
    ratio_frols: float = np.inf
    ratio_linear: float = np.inf
    goal: dict = field(default_factory=dict)


def _largest_lag(order) -> int:
    if isinstance(order, int):
        return order
    na, nb = order
    return max(na, *(nb if isinstance(nb, tuple) else (nb,)))


def search_arguments(rec: Record, budget: float, default_grid: bool) -> tuple[dict, str]:
    """``NarxSearch`` arguments for ``rec`` besides the budget and seed, and what they are:
    the data set's grid and init window (public sets, unless ``default_grid``), else the
    default grid with its orders capped at the record's ``max_lag``."""
    if rec.search_grid is not None and not default_grid:
        kw = dict(rec.search_grid, init_window=rec.init_window)
        note = rec.grid_note.removeprefix("grid: ")
        return kw, f"the data set's own (benchmarks/public_data DataSet.search: {note})"
    kw = {} if rec.init_window is None else {"init_window": rec.init_window}
    default = NarxSearch(budget).orders
    orders = tuple(o for o in default if _largest_lag(o) <= rec.max_lag)
    if len(orders) == len(default):
        return kw, "NarxSearch's default grid"
    kw["orders"] = orders
    return kw, (
        f"NarxSearch's default grid, orders capped at the record's {rec.max_lag}-sample "
        f"measured window: {', '.join(map(str, orders))}"
    )


def score_on_test(rec: Record, model: FreeRun) -> tuple[float, float | None, str]:
    """Test NRMSE, the record's own metric and the status of ``model``'s one test free run."""
    try:
        sim = rec.test.simulated(model)
    except (SimulationDivergedError, FloatingPointError, OverflowError):
        return np.inf, (np.inf if rec.metric else None), DIVERGED
    measured = rec.test.measured()
    v = nrmse(measured, sim)
    if not np.isfinite(v):
        return np.inf, (np.inf if rec.metric else None), DIVERGED
    return v, rec.own_metric(measured, sim), "ok"


def _search_row(rec: Record, budget: float, default_grid: bool, say) -> tuple[Row, dict]:
    kw, grid = search_arguments(rec, budget, default_grid)
    say(f"NarxSearch ({budget:g} s budget; grid: {grid.split(' (')[0].split(',')[0]}) ...")
    info = {"budget_s": budget, "grid": grid, "arguments": {k: repr(v) for k, v in kw.items()}}
    t0 = time.perf_counter()
    search = NarxSearch(budget, seed=0, **kw)
    try:
        search.fit(rec.u, rec.y)
    except IdentificationError as exc:
        wall = time.perf_counter() - t0
        info.update(search_time_s=getattr(search, "search_time_", wall), refit="no model")
        reason = str(exc).splitlines()[0]
        return Row(
            rec.name, "NarxSearch", "NarxSearch", None, np.inf, None, wall, f"failed: {reason}"
        ), info
    model = VrigFreeRun(search.best_)
    v, metric, status = score_on_test(rec, model)
    label = search.best_result_.candidate.label()
    ok = sum(r.status == "ok" for r in search.results_)
    info.update(
        search_time_s=search.search_time_,
        refit=search.refit_,
        chosen=label,
        candidates=len(search.results_),
        validated=ok,
        validation_score=float(search.best_result_.score),
    )
    note = f"{len(search.results_)} candidates, {ok} validated"
    row = Row(
        rec.name,
        "NarxSearch",
        f"NarxSearch: {label}",
        model.terms,
        v,
        metric,
        search.search_time_,
        status,
        note,
    )
    return row, info


def _window(rec: Record, cands) -> int:
    return rec.init_window or max(c.lag for c in cands)


def _family_row(rec: Record, family: str, prefix: str, cands, limits: str, say) -> Row:
    say(f"{family}: {len(cands)} candidates ...")
    t0 = time.perf_counter()
    if not cands:
        return Row(rec.name, family, prefix, None, np.inf, None, 0.0, f"failed: {limits}")
    try:
        ch: Choice = choose(cands, rec.u, rec.y, _window(rec, cands), lambda t: say("  " + t))
    except IdentificationError as exc:
        wall = time.perf_counter() - t0
        return Row(rec.name, family, prefix, None, np.inf, None, wall, f"failed: {exc}", limits)
    v, metric, status = score_on_test(rec, ch.model)
    note = "; ".join(x for x in (ch.note(), limits) if x)
    return Row(
        rec.name,
        family,
        f"{prefix}: {ch.candidate.label}",
        ch.model.terms,
        v,
        metric,
        ch.seconds,
        status,
        note,
    )


def ratio(search: float, baseline: float) -> float:
    """NarxSearch's test NRMSE over a baseline's: ``inf`` when NarxSearch diverged or failed,
    0 when only the baseline did."""
    if not np.isfinite(search):
        return np.inf
    if not np.isfinite(baseline):
        return 0.0
    return search / baseline if baseline > 0 else np.inf


def goal(r: RecordResult) -> dict:
    """The record's verdict: NarxSearch <= 0.5x FROLS, never diverging, never worse than the
    best linear model."""
    search = r.rows[0]
    checks = {
        "vs_frols": bool(r.ratio_frols <= GOAL_VS_FROLS),
        "never_diverged": bool(np.isfinite(search.nrmse)),
        "vs_linear": bool(r.ratio_linear <= GOAL_VS_LINEAR),
    }
    return {**checks, "reached": all(checks.values())}


def frols_label(sip: SysIdentPy | None, why_not: str) -> str:
    """The FROLS row's prefix: which implementation ran."""
    if sip is not None:
        return f"FROLS [SysIdentPy {sip.version}]"
    return f"FROLS [vrig: {why_not}]"


def run_record(
    rec: Record,
    budget: float,
    sip: SysIdentPy | None,
    why_no_sip: str = "sysidentpy not importable",
    default_grid: bool = False,
    progress: Callable[[str], None] | None = None,
) -> RecordResult:
    """The three families on one record; ``progress(text)`` hears each step as it ends."""

    def say(text: str) -> None:
        if progress is not None:
            progress(f"[{rec.name}] {text}")

    res = RecordResult(
        rec.name, rec.key, len(rec.y), rec.test.n_scored, rec.split, rec.source, rec.metric_label
    )
    row, res.search = _search_row(rec, budget, default_grid, say)
    res.rows.append(row)
    say(_done(row))
    nu, ny, n = rec.u.shape[1], rec.y.shape[1], len(rec.y)
    cands, limits = frols_candidates(rec.max_lag, n, nu, ny, sip)
    res.rows.append(_family_row(rec, "FROLS", frols_label(sip, why_no_sip), cands, limits, say))
    say(_done(res.rows[-1]))
    cands, limits = linear_candidates(rec.max_lag, n, nu, ny)
    res.rows.append(_family_row(rec, "linear", "best linear", cands, limits, say))
    say(_done(res.rows[-1]))
    res.ratio_frols = ratio(res.rows[0].nrmse, res.rows[1].nrmse)
    res.ratio_linear = ratio(res.rows[0].nrmse, res.rows[2].nrmse)
    res.goal = goal(res)
    return res


def warm_up() -> float:
    """Compile vrig's kernels (free run, refinement, SEMP) before the first timed search: a
    small ``NarxSearch(budget=None)`` over every option class on a 300-sample NARX record,
    not timed in any row. Returns its seconds (about 1 s with numba's on-disk cache, half a
    minute when it is cold: a search's first fits would otherwise count the compilation and
    its budget plan would skip every candidate)."""
    t0 = time.perf_counter()
    rng = np.random.default_rng(0)
    u = rng.standard_normal((300, 1))
    y = np.zeros((300, 1))
    for k in range(2, 300):
        y[k] = 0.5 * y[k - 1] - 0.1 * y[k - 2] + u[k - 1] + 0.1 * u[k - 1] ** 2
    NarxSearch(None, orders=(1, 2), degrees=(1, 2)).fit(u, y)
    return time.perf_counter() - t0


def _done(row: Row) -> str:
    v = row.status if row.status != "ok" else f"test NRMSE {row.nrmse:.4g}"
    return f"{row.model} - {v} ({row.fit_s:.1f} s)"
