"""Response reconstruction: inverse-model methods and the drive-iteration loop.

``settings`` (:class:`IterationSettings`, one frozen object) resolved by ``defaults`` (the one
resolver of every door: caller, rig side-car, built-in defaults) → ``engine`` (:class:`DriveIteration`:
identify - by ``id_drive``, the one identification drive - invert, play, correct) → ``iteration`` (:func:`reconstruct`: the loop) →
``result`` (:class:`ReconstructionResult`), scored by ``scores``; the inverse-model methods are in
``methods`` (their contract in ``protocol``), built from a name and options by ``vocabulary``
(:func:`method_spec`); Rattlesnake control laws run as methods through ``rattlesnake``.
"""

from ..processing import band_gains
from .engine import DriveIteration
from .iteration import MAX_ITERATIONS, reconstruct
from .methods import (
    METHODS,
    InverseArx,
    InverseErrorSignal,
    InverseFrf,
    InverseNarx,
    SplitSpectra,
    make_method,
)
from .protocol import InverseModelMethod, Method, ObservingMethod, SavableMethod, SizedMethod
from .rattlesnake import RattlesnakeLaw
from .result import ReconstructionResult
from .scores import pseudo_damage
from .settings import UPDATES, IterationSettings
from .vocabulary import MethodOptionError, MethodSpec, method_spec

__all__ = [
    "MAX_ITERATIONS",
    "METHODS",
    "UPDATES",
    "DriveIteration",
    "InverseArx",
    "InverseErrorSignal",
    "InverseFrf",
    "InverseModelMethod",
    "InverseNarx",
    "IterationSettings",
    "Method",
    "MethodOptionError",
    "MethodSpec",
    "ObservingMethod",
    "RattlesnakeLaw",
    "ReconstructionResult",
    "SavableMethod",
    "SizedMethod",
    "SplitSpectra",
    "band_gains",
    "make_method",
    "method_spec",
    "pseudo_damage",
    "reconstruct",
]
