"""Response reconstruction: inverse-model methods and the drive-iteration loop."""

from .iteration import ReconstructionResult, pseudo_damage, reconstruct
from .methods import METHODS, InverseArx, InverseFrf, InverseNarx, SplitSpectra, make_method

__all__ = [
    "METHODS",
    "InverseArx",
    "InverseFrf",
    "InverseNarx",
    "ReconstructionResult",
    "SplitSpectra",
    "make_method",
    "pseudo_damage",
    "reconstruct",
]
