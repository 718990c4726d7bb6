"""The reconstruction defaults, each written once, and the one resolver that applies them.

Every door into a reconstruction (``vrig reconstruct``, :func:`vrig.reconstruct` /
:class:`~vrig.reconstruction.DriveIteration`, the gymnasium environments, the benchmark runner and
the benchmarks) resolves its settings here, so the same rig, method, desired response and seed
give the same figure by any door.
"""

from __future__ import annotations

import numpy as np

__all__ = ["default_band", "default_split_hz"]


def default_band(rig) -> tuple[float, float]:
    """The simulation band reconstructions use on ``rig`` unless told otherwise [Hz].

    The rig's side-car band (``rig.defaults.band``, side-car ``"reconstruction": {"band": ...}``)
    where it differs from the test band (e.g. the shaker's 10-60 Hz: its README), else the test
    band ``rig.bandwidth`` (also for a rig without a side-car, e.g. a user's own :class:`vrig.rigs.Rig`).

    Parameters
    ----------
    rig : Rig
        Any rig with a ``bandwidth`` (low, high) [Hz]; a ``defaults.band`` [Hz] wins when given.
    """
    band = getattr(getattr(rig, "defaults", None), "band", None)
    return tuple(rig.bandwidth if band is None else band)


def default_split_hz(band: tuple[float, float], rig=None) -> float:
    """The split frequency [Hz] of method ``"split"`` when the caller gives none.

    The one rule of ``vrig reconstruct``, :func:`vrig.reconstruct` and the gym envs: the rig
    side-car's ``reconstruction.methods.split.split_hz`` when it names one (a frequency chosen
    below the rig's first resonance in the band, as the reference text's §3.2.1 splits the fuel
    tank's 0-40 Hz at 12 Hz from its identification FRF); else, from the band alone (a user's own
    rig, whose side-car has no ``"reconstruction"`` block), the band's geometric mean
    ``sqrt(low * high)``, or a quarter of its upper edge ``high / 4`` for a band from 0 Hz (no
    geometric mean: the two octaves below the upper edge go to the high band). Either way the
    split lies inside the band (``low < split < high``) for any band ``0 <= low < high``.

    Parameters
    ----------
    band : (float, float)
        The simulation band ``(low, high)`` [Hz] of the reconstruction.
    rig : Rig, optional
        The rig; its ``defaults.method("split").split_hz`` wins when set. None: the band rule.

    Returns
    -------
    float
        The split frequency [Hz].
    """
    defaults = getattr(rig, "defaults", None)
    split = None if defaults is None else defaults.method("split").split_hz
    if split is not None:
        return float(split)
    lo, hi = (float(b) for b in band)
    return float(np.sqrt(lo * hi)) if lo > 0 else hi / 4
