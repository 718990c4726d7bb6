"""Response reconstruction: inverse-model methods and the drive-iteration loop.

``settings`` (:class:`IterationSettings`, one frozen object) → ``engine`` (:class:`DriveIteration`:
identify, invert, play, correct) → ``iteration`` (:func:`reconstruct`: the loop) →
``result`` (:class:`ReconstructionResult`), scored by ``scores``; the inverse-model methods are in
``methods`` (their contract in ``protocol``).
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
    cross_spectra,
    make_method,
)
from .protocol import InverseModelMethod, Method, SavableMethod, SizedMethod
from .result import ReconstructionResult
from .scores import pseudo_damage
from .settings import IterationSettings

__all__ = [
    "MAX_ITERATIONS",
    "METHODS",
    "DriveIteration",
    "InverseArx",
    "InverseErrorSignal",
    "InverseFrf",
    "InverseModelMethod",
    "InverseNarx",
    "IterationSettings",
    "Method",
    "ReconstructionResult",
    "SavableMethod",
    "SizedMethod",
    "SplitSpectra",
    "band_gains",
    "cross_spectra",
    "make_method",
    "pseudo_damage",
    "reconstruct",
]
