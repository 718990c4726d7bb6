"""A ratio printed as a percentage on the same side of a threshold as the ratio itself.

A message that compares a value with a threshold ("identified on responses that peak below the
target's", "beyond full scale", "held at 95 % of full scale") must not print the value rounded
onto or across that threshold: 0.996 of the target's peak printed ``f"{100 * r:.0f} %"`` reads
"100 %" next to a sentence saying it is below. :func:`percent` adds decimals until the printed
number lies on the ratio's own side of the threshold (equal only when the ratio equals it), and
when a few more decimals do not get there says ``"< 100 %"`` / ``"> 100 %"``.
"""

from __future__ import annotations

import math

__all__ = ["EXTRA_DECIMALS", "percent"]

EXTRA_DECIMALS = 2
"""Decimals :func:`percent` may add beyond the ones asked for before it prints ``"< T %"`` /
``"> T %"`` instead of a number."""


def _side(a: float, b: float) -> int:
    return (a > b) - (a < b)


def percent(ratio: float, *, threshold: float, decimals: int = 0) -> str:
    """``ratio`` as a percentage (``"99.6 %"``), never rounded onto or across ``threshold``.

    The number has ``decimals`` decimals, or up to :data:`EXTRA_DECIMALS` more when fewer would
    print it at or beyond the threshold from the other side; a ratio still too close to the
    threshold prints as ``"< T %"`` or ``"> T %"`` (``T`` the threshold in percent). A ratio
    equal to the threshold prints as the threshold (``T`` itself when it has more decimals than
    allowed); a value that is not finite as Python formats it (``"nan %"``, ``"inf %"``).

    Parameters
    ----------
    ratio : float
        The value as a fraction (1.0: 100 %).
    threshold : float
        The threshold the text compares the value with, as a fraction (1.0: 100 %).
    decimals : int, optional
        Decimals of the percentage (default 0).

    Returns
    -------
    str

    Examples
    --------
    >>> percent(0.996, threshold=1.0), percent(1.004, threshold=1.0), percent(1.0, threshold=1.0)
    ('99.6 %', '100.4 %', '100 %')
    >>> percent(0.42, threshold=1.0), percent(0.9999999, threshold=1.0)
    ('42 %', '< 100 %')
    """
    if isinstance(decimals, bool) or not isinstance(decimals, int) or decimals < 0:
        raise ValueError(f"decimals must be a whole number >= 0, got {decimals!r}")
    if not math.isfinite(threshold):
        raise ValueError(f"threshold must be a finite fraction, got {threshold!r}")
    value, limit = 100 * float(ratio), 100 * float(threshold)
    if not math.isfinite(value):
        return f"{value:.{decimals}f} %"
    side = _side(value, limit)
    for d in range(decimals, decimals + EXTRA_DECIMALS + 1):
        text = f"{value:.{d}f}"
        if _side(float(text), limit) == side:
            return f"{text} %"
    if side == 0:  # the threshold itself, with more decimals than it has been given
        return f"{limit:g} %"
    return f"{'<' if side < 0 else '>'} {limit:g} %"
