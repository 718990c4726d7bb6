"""ARX/NARX system identification, simulation and inversion (pure NumPy/SciPy + numba).

This package never imports ``vrig`` or MuJoCo: it works on any (N, channels) records.

>>> from identification import Narx, metrics
>>> model = Narx(order=4, degree=2).fit(u, y)          # doctest: +SKIP
>>> y_sim = model.simulate(u_new)                       # doctest: +SKIP
>>> metrics.qantim_fit_dc(y_new, y_sim)                 # doctest: +SKIP

Conventions shared with SysIdentPy and nonlinear_benchmarks:

* ``model.predict(u, y, steps_ahead=...)``: ``None`` free run from the first ``max_lag_``
  measured outputs (``simulate(u, y0=y[:max_lag_])``), ``1`` one step ahead, ``k`` k steps
  ahead (re-initialised from the measured outputs every k samples). **The default is 1**
  (what ``predict(u, y)`` always returned), **not SysIdentPy's None**: pass
  ``steps_ahead=None`` to score a model as SysIdentPy's ``predict`` does.
* ``model.simulate(u, y0=y[:n])`` takes any initialisation window of ``n >= max_lag_``
  samples (nonlinear_benchmarks uses 50) and starts from its last ``max_lag_``.
* :func:`from_input_output_data` / :func:`to_input_output_data` convert nonlinear_benchmarks'
  ``Input_output_data`` (optional extra ``interop``).
"""

from . import budget, metrics, solvers, validation
from .error_model import ErrorSignalModel
from .errors import (
    IdentificationError,
    IllConditionedWarning,
    InsufficientDataError,
    MemoryBudgetError,
    ModelFileError,
    RankDeficiencyWarning,
    SimulationDivergedError,
    StabilityWarning,
    UnstableModelError,
)
from .interop import from_input_output_data, to_input_output_data
from .inverse import InverseModel, estimate_delay
from .models import Arx, Narx
from .narx_search import CandidateResult, NarxSearch, SearchCandidate
from .order_selection import OrderScan, order_scan
from .regression import regression_matrix
from .selection import ForwardSelection, forward_regression
from .split_spectra import SplitSpectraModel
from .structure import ChannelStructure, term_count, term_count_combinatorial
from .synthetic import band_limited_noise, random_narx
from .validation import (
    CorrelationTests,
    InformationCriteria,
    PressResult,
    correlation_tests,
    criterion_value,
    information_criteria,
    press,
)

__all__ = [
    "Arx",
    "CandidateResult",
    "ChannelStructure",
    "CorrelationTests",
    "ErrorSignalModel",
    "ForwardSelection",
    "IdentificationError",
    "IllConditionedWarning",
    "InformationCriteria",
    "InsufficientDataError",
    "InverseModel",
    "MemoryBudgetError",
    "ModelFileError",
    "Narx",
    "NarxSearch",
    "OrderScan",
    "PressResult",
    "RankDeficiencyWarning",
    "SearchCandidate",
    "SimulationDivergedError",
    "SplitSpectraModel",
    "StabilityWarning",
    "UnstableModelError",
    "band_limited_noise",
    "budget",
    "correlation_tests",
    "criterion_value",
    "estimate_delay",
    "forward_regression",
    "from_input_output_data",
    "information_criteria",
    "metrics",
    "order_scan",
    "press",
    "random_narx",
    "regression_matrix",
    "solvers",
    "term_count",
    "term_count_combinatorial",
    "to_input_output_data",
    "validation",
]
