"""Desired responses without a field measurement: the pseudo-field record (reference text §6.5).

A *pseudo-field* desired response is the rig's own response to a road-like drive (triangular
PSD over the simulation band): the reconstruction then has a known, reachable answer (DESDRV), so
the error of an iteration method can be judged against a drive that exists. Used by the CLI's
main command, the gymnasium environments and the benchmarks.
"""

from __future__ import annotations

import numpy as np

__all__ = ["default_band", "pseudo_field"]

_FIELD_FRACTION = 0.10  # pseudo-field drive RMS as a fraction of full scale (5 mm on the damper)
_FIELD_HEADROOM = 2 / 3  # pseudo-field responses peak below this fraction of the transducer range
_FADE_S = 1.0


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


def pseudo_field(rig, band: tuple[float, float], seconds: float, *, seed: int = 0):
    """A pseudo-field drive and the rig's response to it (reference text §6.5).

    The drive has a triangular PSD over ``band`` (the QanTiM road-like shape), a 1 s fade-in and
    fade-out, and 10 % of each drive channel's full scale RMS; the level is halved (up to four
    times) until every response peaks below two thirds of its transducer range and the rig runs
    1.5 times the drive without an interlock trip (room for the iterations to overshoot: a
    desired response made right at the following-error limit cannot be reached by any drive
    that differs from the original).

    Parameters
    ----------
    rig : Rig
        The rig that makes the record; run up to ten times (two runs per level tried).
    band : (float, float)
        Frequency band (low, high) of the triangular drive PSD [Hz].
    seconds : float
        Record length [s], fades included; ``round(seconds * rig.fs)`` samples.
    seed : int
        Seed of the random drive; the rig runs with ``seed + 10_000`` (its noise realisation).
        The same seed gives the same record, bit for bit.

    Returns
    -------
    (drive, response) : TimeHistory, TimeHistory
        DESDRV and the raw response (FIELD) at the rig's fs.
    """
    from scipy.signal.windows import tukey

    from .errors import RigLimitError
    from .signals import random_drive, triangular_psd

    n = round(seconds * rig.fs)
    full = np.array([c.full_scale for c in rig.inputs])
    out_full = np.array([c.full_scale for c in rig.outputs])
    fade = tukey(n, min(1.0, 2 * _FADE_S / seconds))[:, None]
    fraction = _FIELD_FRACTION
    last_error = None
    for _attempt in range(5):
        drive = random_drive(
            triangular_psd(band),
            n,
            rig.fs,
            channels=len(rig.inputs),
            rms=fraction * full,
            seed=seed,
            names=[c.name for c in rig.inputs],
            unit=rig.inputs[0].unit,
        )
        drive = drive.with_data((drive.data - drive.data.mean(axis=0)) * fade)
        drive = type(drive)(drive.data, drive.fs, drive.names, [c.unit for c in rig.inputs])
        try:
            response = rig.run(drive, seed=seed + 10_000)
        except RigLimitError as exc:
            last_error = exc
        else:
            swing = np.abs(response.data - response.data.mean(axis=0)).max(axis=0)
            if np.all(swing <= _FIELD_HEADROOM * out_full):
                try:  # the same headroom on the interlocks: 1.5x the drive must run too
                    rig.run(drive.with_data(drive.data / _FIELD_HEADROOM), seed=seed + 10_000)
                except RigLimitError as exc:
                    last_error = exc
                else:
                    return drive, response
            else:
                last_error = None
        fraction /= 2
    if last_error is not None:
        raise last_error
    return drive, response
