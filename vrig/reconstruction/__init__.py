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
    cross_spectra,
    make_method,
)
from .protocol import InverseModelMethod, Method, SizedMethod

__all__ = [
    "METHODS",
    "DriveIteration",
    "InverseArx",
    "InverseErrorSignal",
    "InverseFrf",
    "InverseModelMethod",
    "InverseNarx",
    "Method",
    "ReconstructionResult",
    "SizedMethod",
    "SplitSpectra",
    "band_gains",
    "cross_spectra",
    "make_method",
    "pseudo_damage",
    "reconstruct",
]
