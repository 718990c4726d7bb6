"""Argument checks shared by the desired-response modules: a record is a TimeHistory, a band
lies in (0, fs/2)."""

from __future__ import annotations

import numpy as np

from ..timehistory import TimeHistory


def _check_th(th, what: str) -> None:
    if not isinstance(th, TimeHistory):
        raise TypeError(f"{what} must be a vrig.TimeHistory, got {type(th).__name__}")


def _check_band(band, fs: float) -> tuple[float, float]:
    try:
        lo, hi = (float(b) for b in band)
    except (TypeError, ValueError):
        raise ValueError(f"band must be (low, high) in Hz, got {band!r}") from None
    if not (np.isfinite(lo) and np.isfinite(hi) and 0 <= lo < hi <= fs / 2):
        raise ValueError(
            f"band must satisfy 0 <= low < high <= fs/2 = {fs / 2:g} Hz, got ({lo:g}, {hi:g})"
        )
    return lo, hi
