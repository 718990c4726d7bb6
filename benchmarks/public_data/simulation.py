"""Simulation-error rows: searches of models with simulation focus and/or SEMP selection,
and the note that says whether a row reaches the issue's goal (see ``datasets``)."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from identification import IdentificationError, Narx

from .report import Report, Row, _fmt
from .search import Candidate, _safe, select_and_fit


@dataclass(frozen=True)
class SimSearch:
    """A row of vrig with simulation focus and/or SEMP selection (see the module docstring).

    ``full`` and ``quick``: the candidate grids of the normal and the ``--quick`` run, searched on
    the training data only (:func:`select_and_fit`, ``two_fold`` validation if set); ``goal`` and
    ``reference``: the target of the issue (None: no goal line) and the literature figures it
    quotes; ``missed``: why the goal is not reached, printed when it is not.
    """

    test: str
    full: tuple[Candidate, ...]
    quick: tuple[Candidate, ...]
    goal: float | None
    reference: str
    two_fold: bool = False
    missed: str = ""
    note: str = ""


@dataclass
class Scoring:
    """How a data set's simulation rows are scored: ``test(model, candidate)`` -> score."""

    dataset: str
    metric: str  # a key of :func:`_score`
    label: str  # the table's metric column
    skip: int  # validation initialisation window
    split: str
    test: Callable[[Narx, Candidate], float]
    published: float | None = None
    published_terms: int | None = None
    old: float | None = None  # the one-step (prediction-focus) search row's score


def simulation_rows(report: Report, sc: Scoring, searches, quick: bool, u, y) -> list:
    """Search, refit and score every :class:`SimSearch`; one row and one goal note each.

    Returns the :class:`Selection` of each search (None where every candidate failed).
    """
    out = []
    for s in searches:
        try:
            sel = select_and_fit(
                u, y, list(s.quick if quick else s.full), sc.metric, sc.skip, two_fold=s.two_fold
            )
        except IdentificationError as exc:
            report.rows.append(Row(sc.dataset, s.test, sc.split, sc.label, status=f"failed: {exc}"))
            out.append(None)
            continue
        m, best = sel.model, sel.best
        terms = int(m.n_terms_[0])
        v = _safe(lambda m=m, best=best: sc.test(m, best))
        how = "two folds (fit first/last 75 %, free-run last/first 25 %)" if s.two_fold else ""
        note = sel.note() + (f", validation on {how}" if how else "")
        report.rows.append(
            Row(
                sc.dataset,
                s.test,
                sc.split,
                sc.label,
                best.label(terms),
                terms,
                v,
                sc.published,
                sc.published_terms,
                fit_s=sel.fit_time,
                note="; ".join(x for x in (s.note, note, _refinement_note(m)) if x),
            )
        )
        if s.goal is not None:
            report.notes.append(goal_note(sc, s, best.label(terms), v))
        out.append(sel)
    return out


def _refinement_note(model: Narx) -> str:
    r = getattr(model, "refinement_", None)
    txt = "" if r is None else f"LM {r.iterations} iterations"
    remedy = getattr(model, "stability_", {}).get("remedy")
    return txt + (f", stability remedy: {remedy}" if remedy else "")


def goal_note(sc: Scoring, s: SimSearch, label: str, v: float) -> str:
    """The note line that says whether a simulation row reaches the issue's goal (and why not)."""
    ok = bool(np.isfinite(v) and v <= s.goal)
    txt = (
        f"goal {sc.dataset} / {s.test}: {sc.label} <= {s.goal:g} ({s.reference}); "
        f"{label}: {_fmt(v)}, one-step search row {_fmt(sc.old)}: "
        + ("reached" if ok else "NOT reached")
    )
    return txt + (f" - {s.missed}" if s.missed and not ok else "")
