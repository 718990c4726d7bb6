"""Free runs and the one error measure every model of the benchmark is judged by.

A model here is anything with ``simulate(u, y0)`` (a free run over ``u`` started from the
measured outputs ``y0``: the first ``len(y0)`` samples of the result are ``y0``), ``max_lag``
and ``terms`` (:class:`FreeRun`); vrig's and SysIdentPy's models are wrapped in
:mod:`.baselines`. A free run that diverges raises :class:`~identification.SimulationDivergedError`.
"""

from __future__ import annotations

from typing import Protocol

import numpy as np

from benchmarks.public_data import VALIDATION_FRACTION
from identification import SimulationDivergedError, metrics

__all__ = [
    "VALIDATION_FRACTION",
    "FreeRun",
    "as_columns",
    "nrmse",
    "validation_cut",
    "validation_score",
]


class FreeRun(Protocol):
    """What the benchmark needs of a fitted model."""

    max_lag: int
    terms: int

    def simulate(self, u: np.ndarray, y0: np.ndarray) -> np.ndarray:
        """Free run over ``u`` (N, nu) from the measured outputs ``y0`` (L, ny): (N, ny)."""
        ...


def as_columns(x) -> np.ndarray:
    """``x`` as a float array with time on axis 0 and one column per channel."""
    a = np.asarray(x, dtype=float)
    return a.reshape(len(a), -1)


def nrmse(y: np.ndarray, yhat: np.ndarray) -> float:
    """RMSE / standard deviation of the measured ``y``, mean over the outputs (``inf`` when the
    free run is not finite)."""
    if not np.all(np.isfinite(yhat)):
        return np.inf
    return float(np.mean(metrics.nrmse(as_columns(y), as_columns(yhat))))


def validation_cut(n: int) -> int:
    """First sample of the validation slice of an ``n``-sample training part (its last
    :data:`VALIDATION_FRACTION`)."""
    return int(n * (1 - VALIDATION_FRACTION))


def validation_score(model: FreeRun, u: np.ndarray, y: np.ndarray, window: int) -> float:
    """NRMSE of the free run over ``u, y`` started from its first ``window`` measured outputs,
    scored on the rest; ``inf`` when it diverges."""
    try:
        sim = model.simulate(u, y[:window])
    except SimulationDivergedError:
        return np.inf
    return nrmse(y[window:], sim[window:])
