"""The identification drive, written once: IDDRV -> rig -> IDRES (§3.3, App. G).

A random drive with a PSD shape over the identification band (by default triangular:
:func:`vrig.signals.triangular_psd` over :func:`vrig.processing.identification_band` of the
simulation band), independent per drive channel at a given RMS, seeded; checked against the
drives' full scales and played. A level the rig refuses (beyond full scale) or trips on (an
interlock) is halved and the drive made again, up to :data:`ID_ATTEMPTS` tries (down to 1/1024
of the level, 60 dB): a level set from the drives' full scales knows nothing of the responses'
ranges, and a user's rig may take only a small fraction of it.

:meth:`vrig.reconstruction.DriveIteration.identify` identifies from it (its ``send`` keeps a
refused or tripped drive as ``REFUSEDID`` / ``TRIPPEDID``), and the target check
(:func:`vrig.desired.reachability.check_target`) makes its identification records with it, so a target
check and a reconstruction with the same band, level and seed see the same records.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from ..errors import RigLimitError
from ..processing import identification_band
from ..progress import status
from ..rigs.limits import check_drive_limits
from ..signals import random_drive, triangular_psd
from ..timehistory import TimeHistory

__all__ = ["ID_ATTEMPTS", "IdentificationRun", "identification_run"]

ID_ATTEMPTS = 11
"""Tries of the identification drive: the level halved up to ten times (1/1024, 60 dB)."""


@dataclass(frozen=True)
class IdentificationRun:
    """What :func:`identification_run` played.

    Attributes
    ----------
    drive, response : TimeHistory
        IDDRV and the rig's raw response IDRES.
    rms : ndarray (n_inputs,)
        The drive's RMS per channel that the rig took [drive units].
    halvings : int
        How often the level was halved before the rig took it (0: the level asked for).
    last_trip : RigLimitError or None
        The refusal or trip that made the last halving (None when there was none).
    """

    drive: TimeHistory
    response: TimeHistory
    rms: np.ndarray
    halvings: int
    last_trip: RigLimitError | None


def identification_run(
    rig,
    band: tuple[float, float],
    samples: int,
    rms,
    *,
    seed: int,
    psd=None,
    send: Callable | None = None,
    attempts: int = ID_ATTEMPTS,
    label: str = "IDDRV",
) -> IdentificationRun:
    """Make and play the identification drive, halving its level while the rig refuses it or
    trips (module docstring).

    Parameters
    ----------
    rig : Rig
        The rig (``inputs``, ``fs``, ``run``).
    band : (float, float)
        The simulation band [Hz]; the drive covers its identification band.
    samples : int
        Drive length [samples at ``rig.fs``].
    rms : float or array_like (n_inputs,)
        Drive RMS per channel at the first try [drive units].
    seed : int or sequence of int
        Seed of the drive (:func:`numpy.random.default_rng`'s; every try draws the same phases)
        and, with the default ``send``, of the rig run.
    psd : callable or list of callables, optional
        PSD shape of the drive (:func:`vrig.signals.random_drive`); default triangular over the
        identification band.
    send : callable, optional
        ``send(drive) -> (drive, response)``: checks and plays a drive, raising
        :class:`~vrig.RigLimitError` for one refused or tripped (default: the drive limits
        check, then ``rig.run(drive, seed=seed)``).
    attempts : int
        Tries at most (default :data:`ID_ATTEMPTS`).
    label : str
        What the status line calls the drive (``"IDDRV"``; the matched identification's probe
        says ``"probe"``).

    Returns
    -------
    IdentificationRun

    Raises
    ------
    RigLimitError
        The last refusal or trip when even the last try's level is refused or trips.
    SimulationInstabilityError
        The rig's simulation became unstable (not retried: a lower level is no remedy for a
        broken model).
    """
    if not (isinstance(samples, (int, np.integer)) and samples > 0):
        raise ValueError(f"samples must be a positive integer, got {samples!r}")
    id_band = identification_band(band, fs=rig.fs)
    shape = psd if psd is not None else triangular_psd((max(id_band[0], 0.0), id_band[1]))
    names = [c.name for c in rig.inputs]
    full = np.array([c.full_scale for c in rig.inputs], dtype=float)
    rms = np.broadcast_to(np.asarray(rms, dtype=float), full.shape)
    if send is None:

        def send(drive):
            check_drive_limits(rig.inputs, drive.data, fs=rig.fs, what="the identification drive")
            return drive, rig.run(drive, seed=seed)

    last = None
    for attempt in range(attempts):
        level = 100 * np.max(rms / full)
        status(
            f"identifying: {label} {samples / rig.fs:g} s ({level:.3g} % of full scale rms"
            f"{f', halved {attempt}x' if attempt else ''}) -> {rig.name}"
        )
        drive = random_drive(
            shape, samples, rig.fs, channels=len(names), rms=rms, seed=seed, names=names,
            unit=rig.inputs[0].unit,
        )  # fmt: skip
        try:
            drive, response = send(drive)
        except RigLimitError as exc:  # halve the amplitude and try again
            rms, last = rms / 2, exc
            continue
        return IdentificationRun(drive, response, np.array(rms), attempt, last)
    raise last
