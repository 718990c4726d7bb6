"""ARX/NARX system identification, simulation and inversion (pure NumPy/SciPy + numba).

This package never imports ``vrig`` or MuJoCo: it works on any (N, channels) records.

>>> from identification import Narx, metrics
>>> model = Narx(order=4, degree=2).fit(u, y)          # doctest: +SKIP
>>> y_sim = model.simulate(u_new)                       # doctest: +SKIP
>>> metrics.qantim_fit_dc(y_new, y_sim)                 # doctest: +SKIP
"""

from . import metrics, solvers
from .error_model import ErrorSignalModel
from .errors import (
    IdentificationError,
    IllConditionedWarning,
    InsufficientDataError,
    RankDeficiencyWarning,
    SimulationDivergedError,
)
from .inverse import InverseModel, estimate_delay
from .models import Arx, Narx
from .order_selection import OrderScan, order_scan
from .regression import regression_matrix
from .selection import ForwardSelection, forward_regression
from .structure import ChannelStructure, term_count, term_count_combinatorial
from .synthetic import band_limited_noise, random_narx

__all__ = [
    "Arx",
    "ChannelStructure",
    "ErrorSignalModel",
    "ForwardSelection",
    "IdentificationError",
    "IllConditionedWarning",
    "InsufficientDataError",
    "InverseModel",
    "Narx",
    "OrderScan",
    "RankDeficiencyWarning",
    "SimulationDivergedError",
    "band_limited_noise",
    "estimate_delay",
    "forward_regression",
    "metrics",
    "order_scan",
    "random_narx",
    "regression_matrix",
    "solvers",
    "term_count",
    "term_count_combinatorial",
]
