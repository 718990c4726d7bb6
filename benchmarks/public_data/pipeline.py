"""The generic pipeline: every row of any :class:`~.table.DataSet` record, and the whole run."""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from identification import IdentificationError, Narx, NarxSearch

from .data import data_file
from .datasets import DATASETS
from .report import Report, Row, _fmt, _skipped
from .search import Candidate, Selection, _inputs, _safe, choose, free_run, score_candidates
from .simulation import Scoring, simulation_rows
from .sysidentpy import SKIP_SYSIDENTPY, SysIdentPy, get_sysidentpy
from .table import DataSet, Problem, Published, ScoredRecord


@dataclass
class Fitted:
    """What :func:`run_dataset` chose: the one-step selections (unbudgeted first) and the
    simulation rows' selections (None where every candidate failed)."""

    problem: Problem
    one_step: list[Selection]
    simulation: list


def run_dataset(
    report: Report, ds: DataSet, sip: SysIdentPy | None, quick: bool, root=None
) -> Fitted | None:
    """All rows of one data set, in order: the one-step search rows, the published
    configuration, the chosen model on the further tests, the simulation rows and their model
    on the further tests; None (and a "skipped" row) when the data file is absent."""
    path = data_file(ds.folder, ds.file, root)
    if path is None:
        report.rows.append(_skipped(ds.name, ds.test, ds.label, ds.folder, ds.file))
        return None
    prob = ds.split(ds.load(path))
    sels, first = _one_step_rows(report, ds, prob, sip, quick)
    sip_model = _config_row(report, ds, prob, sip, quick) if ds.config else None
    what = f"the first {ds.test} model"
    _transfer_rows(report, ds, prob, sels[0].model, what, sip, sip_model)
    u, test = prob.sim or (prob.u, prob.test)
    fig = ds.figure()
    sc = Scoring(
        ds.name,
        ds.metric,
        ds.label,
        ds.skip,
        prob.test.text,
        lambda m, cand: test.score(ds.metric, _runner(m), m.max_lag_, cand),
        *_figure_columns(fig),
        old=first.vrig,
    )
    sim = simulation_rows(report, sc, ds.simulation, quick, u, prob.y)
    if sim and sim[0] is not None:
        _transfer_rows(report, ds, prob, sim[0].model, "the first simulation-focus model")
    if ds.sweep is not None and not quick:
        _sweep_note(report, ds, prob, sels[0].best)
    if ds.search is not None and not quick:  # a minute per data set: the full run only
        _search_row(report, ds, prob, quick)
    return Fitted(prob, sels, sim)


#: how close to the best row of the data set's grids the NarxSearch row must come (issue 24)
SEARCH_GOAL = 1.10


def _search_row(report: Report, ds: DataSet, prob: Problem, quick: bool) -> None:
    """The :class:`~identification.NarxSearch` row and its note: the one call, scored on the
    main test, against the best figure the data set's grids found (rows above, main test)."""
    spec = ds.search
    u_all, test = prob.sim if prob.sim and spec.features else (prob.u, prob.test)
    cand = Candidate(1, 1, 1, None, features=spec.features)  # only names the input set
    budget = spec.quick_budget if quick else spec.budget
    t0 = time.perf_counter()
    try:
        search = NarxSearch(budget, init_window=ds.skip, **spec.grid).fit(
            _inputs(u_all, cand), prob.y
        )
    except IdentificationError as exc:
        report.rows.append(
            Row(ds.name, ds.test, test.text, ds.label, "NarxSearch", status=f"failed: {exc}")
        )
        return
    wall = time.perf_counter() - t0
    m = search.best_
    v = _safe(lambda: test.score(ds.metric, _runner(m), m.max_lag_, cand))
    label = f"NarxSearch ({budget:g} s): {search.best_result_.candidate.label()}"
    fig = ds.figure()
    tried = len(search.results_)
    ok = sum(r.status == "ok" for r in search.results_)
    widened = sum(r.origin == "widening" for r in search.results_)
    note = (
        f"{tried} candidates ({widened} from widening), {ok} validated on "
        f"{search.n_folds_} fold(s); budget used {search.search_time_:.1f} of {budget:g} s; "
        f"refit: {search.refit_}"
    )
    report.rows.append(
        Row(
            ds.name,
            ds.test,
            test.text,
            ds.label,
            label,
            int(np.sum(m.n_terms_)),
            v,
            *_figure_columns(fig),
            fit_s=wall,
            note="; ".join(x for x in (spec.note, note) if x),
        )
    )
    report.notes.append(_search_goal(report, ds, v, wall, budget))


def _search_goal(report: Report, ds: DataSet, v: float, wall: float, budget: float) -> str:
    """The goal line of the NarxSearch row: within 10 % of the best grid row, never diverged,
    within the budget."""
    grid_rows = [
        r.vrig
        for r in report.rows[:-1]
        if r.dataset == ds.name
        and r.test == ds.test
        and r.vrig is not None
        and np.isfinite(r.vrig)
        and "published config" not in r.model
    ]
    best = min(grid_rows, default=np.inf)
    ratio = v / best if np.isfinite(best) and best > 0 else np.inf
    within = bool(np.isfinite(v) and ratio <= SEARCH_GOAL)
    return (
        f"goal {ds.name} / NarxSearch: {ds.label} within 10 % of the best grid row "
        f"({_fmt(best)}): {_fmt(v)} ({ratio:.2f}x) - {'reached' if within else 'NOT reached'}; "
        f"{'never diverged' if np.isfinite(v) else 'DIVERGED on the test'}; "
        f"{wall:.1f} s wall ({'within' if wall <= 1.2 * budget else 'OVER'} the {budget:g} s "
        "budget)"
    )


def _runner(model: Narx):
    return lambda u, y: free_run(model, u, y)


def _vrig_score(ds: DataSet, test: ScoredRecord, model: Narx) -> float:
    return _safe(lambda: test.score(ds.metric, _runner(model), model.max_lag_))


def _sip_score(ds: DataSet, test: ScoredRecord, sip: SysIdentPy, model, nk: int = 1) -> float:
    return _safe(
        lambda: test.score(ds.metric, lambda u, y: sip.free_run(model, u, y, nk), model.max_lag)
    )


def _figure_columns(fig: Published | None) -> tuple[float | None, int | None]:
    return (None, None) if fig is None else (fig.value, fig.terms)


def _one_step_rows(report, ds: DataSet, prob: Problem, sip, quick: bool):
    """The one-step search (and budget) rows; SysIdentPy mirrors the first when ``ds.mirror``.
    Returns the selections and the first row."""
    grid_ = list(ds.quick_grid if quick else ds.grid)
    pool = score_candidates(prob.u, prob.y, grid_, ds.metric, ds.skip)
    fig = ds.figure()
    sels, rows = [], []
    for max_terms in (None, fig.terms) if ds.budget else (None,):
        sel = choose(pool, prob.u, prob.y, max_terms)
        terms = int(sel.model.n_terms_[0])
        test = ds.test if max_terms is None else f"{ds.test} ≤{max_terms} terms"
        note = "; ".join(x for x in (ds.inputs, sel.note(), ds.mirror) if x)
        vrig = _vrig_score(ds, prob.test, sel.model)
        rows.append(
            Row(
                ds.name,
                test,
                prob.test.text,
                ds.label,
                sel.best.label(terms),
                terms,
                vrig,
                *_figure_columns(fig),
                fit_s=sel.fit_time,
                note=note,
            )
        )
        sels.append(sel)
    if sip is not None and ds.mirror:
        best = sels[0].best
        n_inputs = 1 if np.ndim(prob.u) == 1 else np.shape(prob.u)[1]
        m, fit_s = sip.mirror(best, n_inputs, prob.u, prob.y)
        rows[0].sysidentpy = _sip_score(ds, prob.test, sip, m, best.nk)
        rows[0].sysidentpy_terms, rows[0].sysidentpy_fit_s = sip.n_terms(m), fit_s
    report.rows += rows
    return sels, rows[0]


def _config_row(report, ds: DataSet, prob: Problem, sip, quick: bool):
    """The published configuration's row; returns SysIdentPy's model (None if not run)."""
    cfg, fig = ds.config, ds.figure()
    pub = cfg.model().fit(prob.u, prob.y)
    row = Row(
        ds.name,
        ds.test,
        prob.test.text,
        ds.label,
        cfg.label,
        int(pub.n_terms_[0]),
        _vrig_score(ds, prob.test, pub),
        *_figure_columns(fig),
        fit_s=pub.fit_time_,
        note=cfg.note,
    )
    report.rows.append(row)
    if sip is None:
        return None
    if quick and cfg.quick_skip:
        row.note = cfg.quick_skip
        return None
    model, fit_s = sip.fit(prob.u, prob.y, **cfg.sysidentpy)
    row.sysidentpy = _sip_score(ds, prob.test, sip, model)
    row.sysidentpy_terms, row.sysidentpy_fit_s = sip.n_terms(model), fit_s
    row.note = cfg.sysidentpy_note or row.note
    return model


def _transfer_rows(report, ds: DataSet, prob: Problem, model, what, sip=None, sip_model=None):
    """Rows of ``model`` (and SysIdentPy's ``sip_model``) on the further tests, no refit."""
    if ds.transfer is None:
        return
    terms = int(model.n_terms_[0])
    extra = ds.transfer.sysidentpy_note if sip_model is not None else ""
    for name in ds.transfer.tests:
        test, fig = prob.others[name], ds.figure(name)
        row = Row(
            ds.name,
            name,
            test.text,
            ds.label,
            what,
            terms,
            _vrig_score(ds, test, model),
            fig.value,
            None,
            note=ds.transfer.note + extra,
        )
        if sip_model is not None:
            row.sysidentpy = _sip_score(ds, test, sip, sip_model)
            row.sysidentpy_terms = sip.n_terms(sip_model)
        report.rows.append(row)


def _sweep_note(report: Report, ds: DataSet, prob: Problem, best: Candidate) -> None:
    """Informational only (not used for any choice): the main test error of the chosen one-step
    structure against its number of FROLS terms."""
    sweep = []
    for k in ds.sweep.n_terms:
        m = Candidate(best.degree, best.na, best.nb, k, best.nk).model().fit(prob.u, prob.y)
        sweep.append(f"{int(m.n_terms_[0])}: {_fmt(_vrig_score(ds, prob.test, m))}")
    report.notes.append(
        f"{ds.sweep.title} of the chosen structure (deg {best.degree}, lags {best.na}) vs number "
        "of terms (informational, not used for selection): " + ", ".join(sweep)
    )


def run(quick: bool = False, only=None, root=None, use_sysidentpy: bool = True) -> Report:
    """Every data set of :data:`DATASETS` (or those named in ``only``), in table order."""
    report = Report()
    sip = get_sysidentpy() if use_sysidentpy else None
    if sip is None:
        report.notes.append(
            SKIP_SYSIDENTPY
            if use_sysidentpy
            else "SysIdentPy comparison disabled (--no-sysidentpy)"
        )
    for name, ds in DATASETS.items():
        if only and name not in only:
            continue
        run_dataset(report, ds, sip, quick, root)
    report.sysidentpy_version = sip.version if sip else None
    return report
