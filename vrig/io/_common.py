"""Helpers shared by the format modules of :mod:`vrig.io` (internal)."""

from __future__ import annotations

from ..errors import FileFormatError
from ..timehistory import TimeHistory


def _history(src, fmt: str, data, fs: float, names, units) -> TimeHistory:
    """A TimeHistory of what a file holds; what TimeHistory refuses (NaN, repeated names...)
    is a FileFormatError naming the file."""
    try:
        return TimeHistory(data, fs, names, units)
    except ValueError as exc:
        raise FileFormatError(src, fmt, str(exc)) from None


def _check_history(history) -> None:
    if not isinstance(history, TimeHistory):
        raise TypeError(f"expected a TimeHistory, got {type(history).__name__}")
