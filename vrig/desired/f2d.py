"""Field-to-desired processing (F2D): a field record made into a rig's desired response (DESRES).

:func:`f2d` maps the record's channels by name, checks the units (and converts them by a given
factor, :data:`UNIT_FACTORS` names the known ones), resamples to the rig's rate, band-limits with
:func:`vrig.processing.gprepro` (de-trend, DC removal, zero-phase band-pass), then checks the
result against the rig's transducer ranges (:func:`vrig.desired.range_report.range_report`; one
warning per channel beyond its range).
"""

from __future__ import annotations

import warnings
from collections.abc import Mapping
from fractions import Fraction

import numpy as np
from scipy import signal

from ..processing import check_band, gprepro
from ..reconstruction.defaults import default_band
from ..timehistory import TimeHistory
from ._checks import _check_th
from .range_report import range_report

__all__ = ["UNIT_FACTORS", "f2d"]

UNIT_FACTORS = {
    ("g", "m/s^2"): 9.80665,
    ("mm", "m"): 1e-3,
    ("in", "m"): 0.0254,
    ("kN", "N"): 1e3,
    ("lbf", "N"): 4.4482216152605,
    ("um/m", "-"): 1e-6,
}
"""Known unit conversions ``(field unit, rig unit) -> factor``: named in :func:`f2d`'s error
message (the factor to pass as ``scale``); never applied silently."""

_MAX_DENOMINATOR = 1000  # of the rational resampling ratio


# ------------------------------------------------------------------------------------- F2D
def _mapped_columns(field: TimeHistory, rig, channels) -> list[int]:
    """Column of ``field`` for each rig output (``channels``: rig output -> field channel)."""
    outputs = [c.name for c in rig.outputs]
    mapping = dict(channels or {})
    unknown = sorted(set(mapping) - set(outputs))
    if unknown:
        raise ValueError(f"channels maps {unknown}, which are not responses of the rig {outputs}")
    wanted = [mapping.get(name, name) for name in outputs]
    missing = [
        f"{o} (<- {w})" if w != o else o
        for o, w in zip(outputs, wanted, strict=True)
        if w not in field.names
    ]
    if missing:
        raise ValueError(
            f"the field record has no channel for the rig's response(s) {missing}; its channels "
            f"are {list(field.names)}: map them with channels={{rig response: field channel}}"
        )
    return [field.index(w) for w in wanted]


def _unit_factors(field: TimeHistory, cols, rig, scale) -> np.ndarray:
    """Per rig output: the factor from the field channel to the rig's unit (``scale``), checked."""
    outputs = list(rig.outputs)
    if scale is None:
        given = {}
    elif isinstance(scale, Mapping):
        unknown = sorted(set(scale) - {c.name for c in outputs})
        if unknown:
            raise ValueError(f"scale names {unknown}, which are not responses of the rig")
        given = {k: float(v) for k, v in scale.items()}
    else:
        given = dict.fromkeys((c.name for c in outputs), float(scale))
    for name, value in given.items():
        if not (np.isfinite(value) and value != 0):
            raise ValueError(f"scale of {name!r} must be a finite non-zero factor, got {value!r}")
    out = np.ones(len(outputs))
    for k, (c, col) in enumerate(zip(outputs, cols, strict=True)):
        unit = field.units[col]
        if c.name in given:
            out[k] = given[c.name]
        elif unit != c.unit:
            known = UNIT_FACTORS.get((unit, c.unit))
            hint = f" (1 {unit} = {known:g} {c.unit})" if known else ""
            raise ValueError(
                f"field channel {field.names[col]!r} is in {unit!r} but the rig's response "
                f"{c.name!r} is in {c.unit!r}: pass scale={{{c.name!r}: factor}}{hint}"
            )
    return out


def _resample(x: np.ndarray, fs_in: float, fs_out: float) -> np.ndarray:
    """``x`` at ``fs_out`` (``resample_poly`` by the rational approximation of the ratio)."""
    if fs_in == fs_out:
        return x
    ratio = Fraction(fs_out / fs_in).limit_denominator(_MAX_DENOMINATOR)
    up, down = ratio.numerator, ratio.denominator
    error = abs(fs_in * up / down - fs_out) / fs_out
    if error > 1e-6:
        warnings.warn(
            f"f2d: {fs_in:g} -> {fs_out:g} Hz resampled by {up}/{down} (the nearest ratio with "
            f"a denominator <= {_MAX_DENOMINATOR}): the time scale is off by {error:.2g}",
            UserWarning,
            stacklevel=3,
        )
    return signal.resample_poly(x, up, down, axis=0, padtype="line")


def f2d(field: TimeHistory, rig, band=None, *, channels=None, scale=None) -> TimeHistory:
    """Field-to-desired processing (F2D): DESRES for ``rig`` from a field record.

    In this order: the rig's responses are taken from the field channels of the same name
    (or as ``channels`` maps them; other field channels are dropped); each is multiplied by its
    ``scale`` factor (required where the field unit differs from the rig's: the factor from
    the one to the other); the record is resampled to ``rig.fs`` with
    :func:`scipy.signal.resample_poly` by the rational approximation ``up/down`` of
    ``rig.fs / field.fs`` with ``down <= 1000`` (exact for rates with a common divisor, e.g.
    256 -> 250 Hz by 125/128; a warning says so when the approximation changes the time scale
    by more than 1e-6); then :func:`vrig.processing.gprepro` over ``band`` (linear de-trend, DC
    removal, zero-phase Butterworth band-pass). Finally the result is checked against the rig's
    transducer ranges: one :class:`UserWarning` line per channel whose peak exceeds its range
    (:func:`range_report` gives the whole table).

    Parameters
    ----------
    field : TimeHistory
        The field record (any sample rate).
    rig : Rig
        The rig the desired response is for (its ``outputs``, ``fs`` and band).
    band : (float, float), optional
        Simulation band (low, high) [Hz]; default :func:`vrig.reconstruction.defaults.default_band` of the rig.
    channels : mapping of str to str, optional
        Rig response name -> field channel name, where the names differ (default: the same
        names).
    scale : float or mapping of str to float, optional
        Factor from the field channel's unit to the rig response's unit (one for all channels or
        one per rig response name), a level scaling included; required for a channel whose unit
        differs from the rig's (:data:`UNIT_FACTORS` names the usual ones).

    Returns
    -------
    TimeHistory
        DESRES: the rig's responses (names and units) at ``rig.fs``.

    Raises
    ------
    ValueError
        A rig response without a field channel, a unit mismatch without a ``scale``, a bad
        band or factor, a record too short to filter.
    """
    _check_th(field, "field")
    cols = _mapped_columns(field, rig, channels)
    factors = _unit_factors(field, cols, rig, scale)
    band = check_band(default_band(rig) if band is None else band, rig.fs)
    x = signal.detrend(field.data[:, cols], axis=0, type="linear") * factors
    x = _resample(x, field.fs, float(rig.fs))
    if x.shape[0] < 16:
        raise ValueError(f"the field record is too short: {x.shape[0]} samples at {rig.fs:g} Hz")
    names, units = [c.name for c in rig.outputs], [c.unit for c in rig.outputs]
    desired = gprepro(TimeHistory(x, rig.fs, names, units), band)
    report = range_report(rig, desired)
    for row in report.rows:
        if row.exceeds:
            warnings.warn(f"f2d: {row.describe()}", UserWarning, stacklevel=2)
    return desired
