"""Argument checks shared by the desired-response modules: a record is a TimeHistory (a band is
checked by :func:`vrig.processing.check_band`, as every band is)."""

from __future__ import annotations

from ..timehistory import TimeHistory


def _check_th(th, what: str) -> None:
    if not isinstance(th, TimeHistory):
        raise TypeError(f"{what} must be a vrig.TimeHistory, got {type(th).__name__}")
