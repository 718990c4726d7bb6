"""vrig: virtual servo-hydraulic test rigs and dynamic response reconstruction.

The identification library lives in the sibling package :mod:`identification`; the rigs,
signals, processing, reconstruction workflow, gymnasium environments and CLI live here.
"""

from . import envs as _envs  # noqa: F401  (registers the vrig/ gymnasium environments)
from . import roads
from .desired.f2d import f2d
from .desired.kinds import desired_response
from .desired.pseudo_field import pseudo_field
from .desired.range_report import range_report
from .desired.reachability import TargetCheck, check_target
from .errors import (
    ERRORS,
    FileFormatError,
    FolderLockedError,
    ReconstructionError,
    ReconstructionInterrupted,
    RigLimitError,
    RigModelError,
    RigParameterError,
    SimulationInstabilityError,
    VrigError,
)
from .linearity import LinearityResult, check_linearity, check_rig_linearity
from .reconstruction import IterationSettings, ReconstructionResult, reconstruct
from .rigs import ChannelSpec, FileRig, MujocoRig, list_rigs, load_rig, rig_path, severity_rigs
from .service import field_record, field_scenarios
from .testfolder import TestFolder
from .timehistory import TimeHistory

# the one place the version is written: pyproject.toml reads it ([tool.setuptools.dynamic]),
# `vrig --version` prints it, importlib.metadata.version("vrig") gives it for an installed package
__version__ = "0.1.0"

__all__ = [
    "ERRORS",
    "ChannelSpec",
    "FileFormatError",
    "FileRig",
    "FolderLockedError",
    "IterationSettings",
    "LinearityResult",
    "MujocoRig",
    "ReconstructionError",
    "ReconstructionInterrupted",
    "ReconstructionResult",
    "RigLimitError",
    "RigModelError",
    "RigParameterError",
    "SimulationInstabilityError",
    "TargetCheck",
    "TestFolder",
    "TimeHistory",
    "VrigError",
    "__version__",
    "check_linearity",
    "check_rig_linearity",
    "check_target",
    "desired_response",
    "f2d",
    "field_record",
    "field_scenarios",
    "list_rigs",
    "load_rig",
    "pseudo_field",
    "range_report",
    "reconstruct",
    "rig_path",
    "roads",
    "severity_rigs",
]
