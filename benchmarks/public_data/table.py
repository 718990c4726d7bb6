"""The record types of the data-set table (``datasets.DATASETS``): one frozen :class:`DataSet`
per data set (where it is, loader, split, published figures and their sources, model grids,
how it is scored), and the split records its ``split`` function returns."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from identification import Narx

from .search import Candidate, _finite_score, _inputs
from .simulation import SimSearch


@dataclass(frozen=True)
class Published:
    """A published figure a data set's rows are compared with, and where it was published."""

    value: float
    source: str
    terms: int | None = None  # the published model's number of terms, when given
    test: str = ""  # the test it scores ("": the data set's main test)
    in_table: bool = True  # False: quoted in a goal line only (another model class)


@dataclass(frozen=True, eq=False)
class ScoredRecord:
    """A record a model is scored on: free run over ``u[start:stop]``, error from sample ``start + init`` on.

    ``continues``: the record continues the training record, so the free run starts from the
    ``p`` measured samples before ``start`` (``p`` the model's largest lag); else from the test
    record's own first samples. ``u`` may be a dict of input sets (:func:`_inputs`); ``text``
    is the split as printed.
    """

    u: Any
    y: np.ndarray
    start: int
    stop: int
    init: int
    text: str
    continues: bool = False

    def score(self, metric: str, simulate, p: int, cand: Candidate | None = None) -> float:
        """``metric`` of ``simulate(u, y)`` (a free run from ``y``'s first ``p`` samples)."""
        u, a, b, k = _inputs(self.u, cand), self.start, self.stop, self.init
        if self.continues:
            sim = simulate(u[a - p : b], self.y[a - p : b])[p + k :]
        else:
            sim = simulate(u[a:b], self.y[a:b])[k:]
        return _finite_score(metric, self.y[a + k : b], sim)


@dataclass(frozen=True, eq=False)
class Problem:
    """A loaded data set, split: the training record ``u, y``, the main test, further tests of
    the chosen models by test name (``others``), and the training inputs and test of the
    simulation rows when they differ (``sim``: input sets with derived columns)."""

    u: Any
    y: np.ndarray
    test: ScoredRecord
    others: dict[str, ScoredRecord] = field(default_factory=dict)
    sim: tuple[Any, ScoredRecord] | None = None


@dataclass(frozen=True)
class PublishedConfig:
    """The published model's configuration, run by vrig and (when importable) by SysIdentPy.

    ``note`` is printed always, ``sysidentpy_note`` when SysIdentPy ran; ``quick_skip``, when set,
    skips SysIdentPy's run in ``--quick`` and is the note that says so.
    """

    label: str
    model: Callable[[], Narx]
    sysidentpy: dict[str, Any]  # SysIdentPy FROLS arguments
    note: str = ""
    sysidentpy_note: str = ""
    quick_skip: str = ""


@dataclass(frozen=True)
class Transfer:
    """Further tests of the chosen models, no refit (keys of :attr:`Problem.others`, each with
    its published figure); the row note, and what it adds when SysIdentPy's column holds the
    published configuration's model."""

    tests: tuple[str, ...]
    note: str
    sysidentpy_note: str = ""


@dataclass(frozen=True, eq=False)
class SearchRow:
    """The data set's :class:`identification.NarxSearch` row: one call, the search's own
    validation on the training data only, then one score on the main test.

    ``grid``: the ``NarxSearch`` arguments (orders, degrees, kinds, options, ...; the
    initialisation window is the data set's); ``features``: the input set when the data set's
    simulation rows use several (the key of their input dict); ``budget``/``quick_budget``:
    seconds of the normal and ``--quick`` runs; ``note``: printed with the row.
    """

    grid: dict
    features: str = ""
    budget: float = 60.0
    quick_budget: float = 20.0
    note: str = ""


@dataclass(frozen=True)
class Sweep:
    """Informational note (full run only): the main test's error of the chosen one-step
    structure against its number of FROLS terms."""

    n_terms: tuple[int, ...]
    title: str


@dataclass(frozen=True)
class DataSet:
    """One public data set: where it is, how it is loaded and split, the published figures it is
    compared with, the model grids and how every row is scored (see the module docstring).

    ``grid``/``quick_grid``: the one-step (FROLS) candidates of the normal and ``--quick`` runs;
    ``budget``: also a row whose search keeps to the published model's number of terms;
    ``mirror``: SysIdentPy fits the chosen one-step structure (the note says so); ``inputs``:
    names the inputs in the note; ``simulation``: the simulation-error searches; ``search``: the
    :class:`identification.NarxSearch` row.
    """

    name: str
    folder: str
    file: str
    load: Callable[[Path], Any]
    split: Callable[[Any], Problem]
    metric: str  # a key of :func:`_score`
    label: str  # the table's metric column, with the unit
    test: str  # the main test's name
    skip: int  # initialisation window of the validation free runs [samples]
    grid: tuple[Candidate, ...]
    quick_grid: tuple[Candidate, ...]
    published: tuple[Published, ...] = ()
    unpublished: str = ""  # why there is no published figure, when there is none
    budget: bool = False
    config: PublishedConfig | None = None
    mirror: str = ""
    inputs: str = ""
    transfer: Transfer | None = None
    simulation: tuple[SimSearch, ...] = ()
    sweep: Sweep | None = None
    search: SearchRow | None = None

    def figure(self, test: str = "") -> Published | None:
        """The published figure printed beside ``test`` (default: the main test), if any."""
        test = test or self.test
        return next(
            (p for p in self.published if p.in_table and (p.test or self.test) == test), None
        )
