"""The transducer-range check of a desired response: per response channel its peak against the
rig's transducer range (beyond it the rig's range interlock trips).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..percent import percent
from ..timehistory import TimeHistory
from ._checks import _check_th

__all__ = ["RangeReport", "RangeRow", "range_report"]


# ---------------------------------------------------------------------------- range check
@dataclass(frozen=True)
class RangeRow:
    """One response channel of a desired response against its transducer range.

    Attributes
    ----------
    name, unit : str
        The rig's response channel and its unit.
    peak : float
        Largest ``|value|`` of the desired response [unit].
    full_scale : float
        The transducer range ± [unit] (beyond it the rig's range interlock trips).
    fraction_beyond : float
        Fraction of the samples with ``|value| > full_scale`` (0 .. 1).
    """

    name: str
    unit: str
    peak: float
    full_scale: float
    fraction_beyond: float

    @property
    def peak_fraction(self) -> float:
        """``peak / full_scale`` (> 1: beyond the range)."""
        return self.peak / self.full_scale

    @property
    def exceeds(self) -> bool:
        """The peak lies beyond the transducer range."""
        return self.peak > self.full_scale

    def describe(self) -> str:
        """One line: the channel, its peak against the range and the samples beyond it."""
        return (
            f"{self.name} peaks at {self.peak:.4g} {self.unit}, {_pct(self.peak_fraction, 1.0)} "
            f"of the transducer range ±{self.full_scale:g} {self.unit}; "
            f"{_pct(self.fraction_beyond, 0.0, decimals=2)} of the samples lie beyond it"
        )


@dataclass(frozen=True)
class RangeReport:
    """A desired response against the rig's transducer ranges (:func:`range_report`).

    Attributes
    ----------
    rows : tuple of RangeRow
        One per response channel, in the rig's order.
    """

    rows: tuple[RangeRow, ...]

    @property
    def exceeding(self) -> tuple[str, ...]:
        """The channels whose peak exceeds the transducer range."""
        return tuple(r.name for r in self.rows if r.exceeds)

    def table(self) -> str:
        """The report as a text table, one line per channel."""
        rows = [["response", "peak", "transducer range", "of range", "samples beyond"]]
        rows += [
            [
                r.name,
                f"{r.peak:.4g} {r.unit}",
                f"±{r.full_scale:.4g} {r.unit}",
                _pct(r.peak_fraction, 1.0),
                _pct(r.fraction_beyond, 0.0) + ("  EXCEEDS" if r.exceeds else ""),
            ]
            for r in self.rows
        ]
        return "\n".join(_columns(rows))

    def __str__(self) -> str:
        return self.table()

    def to_dict(self) -> dict:
        """The report as JSON-able data."""
        return {
            "exceeding": list(self.exceeding),
            "channels": [
                {
                    "name": r.name,
                    "unit": r.unit,
                    "peak": r.peak,
                    "full_scale": r.full_scale,
                    "peak_fraction": r.peak_fraction,
                    "fraction_beyond": r.fraction_beyond,
                }
                for r in self.rows
            ],
        }


def range_report(rig, desired: TimeHistory) -> RangeReport:
    """Check a desired response against the rig's transducer ranges.

    Parameters
    ----------
    rig : Rig
        The rig (its ``outputs``: name, unit, full scale = the transducer range).
    desired : TimeHistory
        The desired response with the rig's response channels (matched by name).

    Returns
    -------
    RangeReport
        Per channel: peak, range, peak / range and the fraction of samples beyond it.
    """
    _check_th(desired, "desired")
    missing = [c.name for c in rig.outputs if c.name not in desired.names]
    if missing:
        raise ValueError(
            f"the desired response has no channel {missing}; its channels: {list(desired.names)}"
        )
    rows = []
    for c in rig.outputs:
        x = np.abs(desired.channel(c.name))
        rows.append(
            RangeRow(
                c.name,
                c.unit,
                float(x.max()),
                float(c.full_scale),
                float(np.mean(x > c.full_scale)),
            )
        )
    return RangeReport(tuple(rows))


def _pct(x, threshold: float | None = None, *, decimals: int = 1) -> str:
    """A fraction as ``"12.3 %"`` (``"-"``: none or not finite); with ``threshold`` (a fraction:
    1.0 the limit, 0.0 none beyond it) never rounded onto or across it
    (:func:`vrig.percent.percent`)."""
    if x is None or not math.isfinite(x):
        return "-"
    return (
        f"{100 * x:.{decimals}f} %"
        if threshold is None
        else percent(x, threshold=threshold, decimals=decimals)
    )


def _columns(rows: list[list[str]]) -> list[str]:
    """Rows of cells as lines: the first column left-aligned, the others right-aligned."""
    widths = [max(len(r[k]) for r in rows) for k in range(len(rows[0]))]
    return [
        "  ".join(
            c.ljust(w) if k == 0 else c.rjust(w)
            for k, (c, w) in enumerate(zip(r, widths, strict=True))
        )
        for r in rows
    ]
