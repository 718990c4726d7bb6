"""Run-time limit checks: is this drive within the rig's limits (before it is sent)?

One concept: a drive (or a drive file, or an iteration's drive) checked against the channels'
± full scales, the check every rig and the iteration engine make before anything is played. The
side-car parsing that sets those full scales is :mod:`vrig.rigs.spec`; the interlocks that trip
*during* a run are the servo callback's (stroke, force, following error:
:mod:`vrig.rigs.hydraulics`) and :meth:`~vrig.rigs.MujocoRig.run`'s (transducer range).
"""

from __future__ import annotations

import numpy as np

from ..errors import RigLimitError

__all__ = ["check_drive_limits"]


def check_drive_limits(
    channels, drive, *, fs: float | None = None, what: str = "the drive"
) -> None:
    """Raise :class:`~vrig.errors.RigLimitError` if any drive channel exceeds its full scale.

    A drive beyond a channel's ± full scale (or not finite) is never sent: the error names the
    channel, the first offending sample (and its time when ``fs`` is given) and says the drive
    was not sent.

    Parameters
    ----------
    channels : sequence of ChannelSpec
        The drive channels, one per column of ``drive``.
    drive : ndarray
        Drive samples, shape (samples, channels), in each channel's unit.
    fs : float, optional
        Sample rate [Hz]; when given, the error states the offending sample's time [s].
    what : str
        What the drive is, for the error message (``"the drive"``, ``"the drive file"``,
        ``"IT03DRV"``).
    """
    for j, c in enumerate(channels):
        over = ~(np.abs(drive[:, j]) <= c.full_scale)  # NaN counts as over: never sent either
        if over.any():
            i = int(np.argmax(over))
            when = f"sample {i}" + (f", t = {i / fs:.4f} s" if fs else "")
            fix = "scale it down" if np.isfinite(drive[i, j]) else "it is not finite"
            raise RigLimitError(
                "drive",
                c.name,
                float("nan"),
                drive[i, j],
                c.full_scale,
                c.unit,
                hint=f"({when}): {what} was not sent; {fix}.",
            )
