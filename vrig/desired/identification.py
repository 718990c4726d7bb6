"""The identification records of a rig (IDDRV, IDRES) as a reconstruction makes them: what
:func:`vrig.desired.reachability.check_target` estimates a rig's reach from when it is given none.
"""

from __future__ import annotations

import numpy as np

from ..processing import identification_band
from ..reconstruction.defaults import default_band
from ..timehistory import TimeHistory
from ._checks import _check_band

__all__ = ["identification_records"]


# ------------------------------------------------------------------------ identification run
def _default_id_rms(rig) -> np.ndarray:
    """The identification level of ``vrig reconstruct``: the side-car's ``id_rms`` fraction of
    each drive's full scale, else 5 %."""
    full = np.array([c.full_scale for c in rig.inputs], dtype=float)
    fraction = getattr(getattr(rig, "defaults", None), "id_rms", None)
    return (0.05 if fraction is None else float(fraction)) * full


def identification_records(
    rig, *, band=None, seconds: float = 30.0, id_rms=None, seed: int = 0
) -> tuple[TimeHistory, TimeHistory]:
    """IDDRV and IDRES as :meth:`vrig.reconstruction.DriveIteration.identify` makes them.

    A random drive with a triangular PSD over the identification band
    (:func:`vrig.processing.identification_band` of ``band``), independent per drive channel,
    ``id_rms`` RMS, seeded with ``seed``, checked against the drives' full scales and played with
    ``rig.run(drive, seed=seed)``; the level is halved (up to three times) while the rig refuses
    it or trips. The same arguments give the records a reconstruction with ``id_seed=seed``
    identifies from.

    Parameters
    ----------
    rig : Rig
        The rig.
    band : (float, float), optional
        Simulation band [Hz] (default :func:`vrig.reconstruction.defaults.default_band`).
    seconds : float
        Record length [s].
    id_rms : float or sequence of float, optional
        Drive RMS per drive channel in its unit (default: the rig side-car's ``id_rms`` fraction
        of full scale, else 5 %, as ``vrig reconstruct``).
    seed : int
        Seed of the drive and of the rig run.

    Returns
    -------
    (drive, response) : TimeHistory, TimeHistory
    """
    from ..errors import RigLimitError
    from ..rigs.limits import check_drive_limits
    from ..signals import random_drive, triangular_psd

    band = _check_band(default_band(rig) if band is None else band, rig.fs)
    if not (np.isfinite(seconds) and seconds > 0):
        raise ValueError(f"seconds must be a finite duration > 0 s, got {seconds!r}")
    id_band = identification_band(band, fs=rig.fs)
    shape = triangular_psd((max(id_band[0], 0.0), id_band[1]))
    rms = _default_id_rms(rig) if id_rms is None else np.asarray(id_rms, float)
    names = [c.name for c in rig.inputs]
    for _ in range(4):
        drive = random_drive(
            shape,
            round(seconds * rig.fs),
            rig.fs,
            channels=len(names),
            rms=rms,
            seed=seed,
            names=names,
            unit=rig.inputs[0].unit,
        )
        try:
            check_drive_limits(rig.inputs, drive.data, fs=rig.fs, what="the identification drive")
            return drive, rig.run(drive, seed=seed)
        except RigLimitError as exc:
            rms, last = rms / 2, exc
    raise last
