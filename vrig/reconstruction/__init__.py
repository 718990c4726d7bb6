"""Response reconstruction: inverse-model methods and the drive-iteration loop."""

from .iteration import (
    DriveIteration,
    ReconstructionResult,
    band_gains,
    pseudo_damage,
    reconstruct,
)
from .methods import (
    METHODS,
    InverseArx,
    InverseErrorSignal,
    InverseFrf,
    InverseNarx,
    SplitSpectra,
    make_method,
)

__all__ = [
    "METHODS",
    "DriveIteration",
    "InverseArx",
    "InverseErrorSignal",
    "InverseFrf",
    "InverseNarx",
    "ReconstructionResult",
    "SplitSpectra",
    "band_gains",
    "make_method",
    "pseudo_damage",
    "reconstruct",
]
