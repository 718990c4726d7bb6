"""vrig: virtual servo-hydraulic test rigs and dynamic response reconstruction.

The identification library lives in the sibling package :mod:`identification`; the rigs,
signals, processing, reconstruction workflow, gymnasium environments and CLI live here.
"""

__version__ = "0.1.0"

__all__ = ["__version__"]
