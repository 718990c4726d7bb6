"""The records the benchmark scores: a training part, a test part and how the test is run.

:class:`Record` is one record; :func:`public_records` reads the four public data sets with the
loaders and official splits of :mod:`benchmarks.public_data`, :func:`simulated_records` makes
the ball-and-beam records of :func:`identification.synthetic.ball_and_beam`. A user's file is
read by :mod:`.user_record`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from benchmarks.public_data import DATASETS, ENV_VAR, _score, data_file, external_data_root
from benchmarks.public_data.table import DataSet
from identification import synthetic

from .scoring import FreeRun, as_columns

#: ball-and-beam records: samples, the training fraction (the first half), the measured outputs
#: that start the test free run, and the seeds of a default run
BALL_AND_BEAM_SAMPLES = 1000
BALL_AND_BEAM_TRAIN_FRACTION = 0.5
BALL_AND_BEAM_INIT = 50
BALL_AND_BEAM_SEEDS = (0, 1, 2)
#: how a test free run starts (see :class:`ScoredPart`)
STARTS = ("init", "lags", "training")


@dataclass(frozen=True, eq=False)
class ScoredPart:
    """The test part of a record and how a model's free run over it is scored.

    The free run covers samples ``start:stop`` of the whole record ``u, y`` (2-D, time on axis
    0) and is scored from sample ``start + init`` on. ``start_from`` says which measured outputs
    start it: ``"init"`` the first ``init`` test outputs (the run begins at ``start + init``);
    ``"lags"`` the first ``p`` test outputs, ``p`` the model's largest lag (the public sets'
    :class:`~benchmarks.public_data.table.ScoredRecord` convention: the samples before
    ``start + init`` are run, not scored); ``"training"`` the ``p`` outputs before ``start``
    (the test record continues the training record: Silverbox).
    """

    u: np.ndarray
    y: np.ndarray
    start: int
    stop: int
    init: int
    start_from: str = "init"

    def __post_init__(self):
        if self.start_from not in STARTS:
            raise ValueError(f"start_from must be one of {STARTS}, got {self.start_from!r}")

    @property
    def n_scored(self) -> int:
        """Samples the score is taken over."""
        return self.stop - self.start - self.init

    def measured(self) -> np.ndarray:
        """The measured outputs the score compares with, shape (n_scored, ny)."""
        return self.y[self.start + self.init : self.stop]

    def simulated(self, model: FreeRun) -> np.ndarray:
        """The model's free run over the scored samples, shape (n_scored, ny).

        Raises :class:`~identification.SimulationDivergedError` when it diverges."""
        a, b, k, u, y = self.start, self.stop, self.init, self.u, self.y
        if self.start_from == "init":
            return model.simulate(u[a:b], y[a : a + k])[k:]
        p = model.max_lag
        if self.start_from == "lags":
            return model.simulate(u[a:b], y[a : a + p])[k:]
        return model.simulate(u[a - p : b], y[a - p : a])[p + k :]


@dataclass(frozen=True, eq=False)
class Record:
    """One record: the training part ``u, y`` (2-D), the test part, the rules of the game.

    ``max_lag``: the largest lag any model may have [samples] (the test's measured window, so
    that no model sees a measured test output after the free run starts); ``init_window``: the
    measured outputs that start each validation free run on the training part (None: the
    largest lag of the grid searched, as :class:`~identification.NarxSearch` defaults to);
    ``metric``/``metric_label``: the record's own metric (a key of
    :func:`benchmarks.public_data._score`, "" for none); ``search_grid``: the
    :class:`~identification.NarxSearch` grid of the data set (None: its default grid) and
    ``grid_note`` what it is; ``split``/``source``: printed with the scores; ``ts``: sample
    interval [s], when known.
    """

    name: str
    key: str
    u: np.ndarray
    y: np.ndarray
    test: ScoredPart
    max_lag: int
    split: str
    source: str
    init_window: int | None = None
    metric: str = ""
    metric_label: str = ""
    search_grid: dict | None = None
    grid_note: str = ""
    ts: float | None = None

    def own_metric(self, measured: np.ndarray, simulated: np.ndarray) -> float | None:
        """The record's own metric of a test free run (None when it has none)."""
        if not self.metric:
            return None
        return _score(self.metric, measured[:, 0], simulated[:, 0])


@dataclass(frozen=True)
class Skipped:
    """A record that could not be run, and why."""

    name: str
    key: str
    reason: str


def _public_record(key: str, ds: DataSet, root=None) -> Record | Skipped:
    path = data_file(ds.folder, ds.file, root)
    if path is None:
        where = external_data_root() if root is None else root
        return Skipped(
            ds.name, key, f"data file {ds.folder}/{ds.file} not found under {where} ({ENV_VAR})"
        )
    prob = ds.split(ds.load(path))
    spec = ds.search
    features = spec.features if spec is not None else ""
    u, test = (prob.sim[0][features], prob.sim[1]) if features else (prob.u, prob.test)
    tu = test.u[features] if features else test.u
    start = "training" if test.continues else "lags"
    part = ScoredPart(as_columns(tu), as_columns(test.y), test.start, test.stop, test.init, start)
    inputs = f"; {spec.note.split(';')[0]}" if features else ""
    return Record(
        name=ds.name,
        key=key,
        u=as_columns(u),
        y=as_columns(prob.y),
        test=part,
        max_lag=ds.skip,
        split=test.text + inputs,
        source=f"benchmarks/public_data DATASETS[{key!r}] ({ds.folder}/{ds.file})",
        init_window=ds.skip,
        metric=ds.metric,
        metric_label=ds.label,
        search_grid=None if spec is None else dict(spec.grid),
        grid_note="" if spec is None else spec.note,
    )


def public_records(only=None, root=None) -> list[Record | Skipped]:
    """The public data sets of :data:`benchmarks.public_data.DATASETS` (keys in ``only``, or
    all), each read with its loader and split; a :class:`Skipped` where the file is absent."""
    return [_public_record(k, ds, root) for k, ds in DATASETS.items() if not only or k in only]


def split_record(
    name: str,
    key: str,
    u,
    y,
    train_fraction: float,
    init: int,
    source: str,
    ts: float | None = None,
) -> Record:
    """A record whose first ``train_fraction`` trains and the rest tests (free run from the
    test part's first ``init`` measured outputs)."""
    u, y = as_columns(u), as_columns(y)
    n = len(y)
    cut = round(n * train_fraction)
    test = ScoredPart(u, y, cut, n, init, "init")
    split = f"train 0:{cut}, test {cut}:{n} (free run from its first {init} measured outputs)"
    split += "" if ts is None else f"; sample interval {ts:g} s"
    return Record(name, key, u[:cut], y[:cut], test, init, split, source, ts=ts)


def simulated_records(seeds=BALL_AND_BEAM_SEEDS) -> list[Record]:
    """``identification.synthetic.ball_and_beam(1000, seed=s)`` for each seed: a closed-loop
    record of an open-loop unstable double integrator, first half trains, second half tests."""
    out = []
    for s in seeds:
        r = synthetic.ball_and_beam(BALL_AND_BEAM_SAMPLES, seed=s)
        out.append(
            split_record(
                f"ball_and_beam seed {s}",
                "ball_and_beam",
                r.u,
                r.y,
                BALL_AND_BEAM_TRAIN_FRACTION,
                BALL_AND_BEAM_INIT,
                f"identification.synthetic.ball_and_beam({BALL_AND_BEAM_SAMPLES}, seed={s}): "
                "beam angle [rad] in, ball position [m] out",
                r.ts,
            )
        )
    return out


__all__ = [
    "BALL_AND_BEAM_INIT",
    "BALL_AND_BEAM_SAMPLES",
    "BALL_AND_BEAM_SEEDS",
    "BALL_AND_BEAM_TRAIN_FRACTION",
    "Record",
    "ScoredPart",
    "Skipped",
    "public_records",
    "simulated_records",
    "split_record",
]
