"""vrig: virtual servo-hydraulic test rigs and dynamic response reconstruction.

The identification library lives in the sibling package :mod:`identification`; the rigs,
signals, processing, reconstruction workflow, gymnasium environments and CLI live here.
"""

from .errors import RigLimitError, RigModelError, SimulationInstabilityError
from .rigs import ChannelSpec, MujocoRig, list_rigs, load_rig, rig_path
from .timehistory import TimeHistory

__version__ = "0.1.0"

__all__ = [
    "ChannelSpec",
    "MujocoRig",
    "RigLimitError",
    "RigModelError",
    "SimulationInstabilityError",
    "TimeHistory",
    "__version__",
    "list_rigs",
    "load_rig",
    "rig_path",
]
