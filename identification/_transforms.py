"""Static functions of a regressor (non-polynomial NARX terms, §7.4.1), compiled.

A regressor ``x = source(t - lag)`` may enter the condensed structure through a static
function ``g(x)``; the polynomial terms are then products of the ``g(x)``. Codes:

====  =================  =====================================  ==========================
code  name               g(x)                                   dg/dx
====  =================  =====================================  ==========================
0     ``identity``       x                                      1
1     ``abs``            |x|                                    sign(x)
2     ``deadzone``       sign(x) * max(|x| - b, 0)              1 if |x| > b else 0
3     ``saturation``     clip(x, -b, b)                         1 if |x| < b else 0
4     ``sign_square``    sign(x) * x**2 = x * |x|               2 |x|
====  =================  =====================================  ==========================

``b`` is the breakpoint (in the regressor's units, > 0 for the dead zone and the saturation).
At the kinks (x = 0 for ``abs``, |x| = b) the derivative takes the one-sided value above,
a valid subgradient.
"""

from __future__ import annotations

import numba as nb
import numpy as np

__all__ = ["FUNCTIONS", "apply", "apply_array", "derivative", "function_code"]

FUNCTIONS = ("identity", "abs", "deadzone", "saturation", "sign_square")
NEEDS_BREAKPOINT = ("deadzone", "saturation")


def function_code(name: str) -> int:
    """Integer code of a regressor function name (see the module table)."""
    return FUNCTIONS.index(name)


@nb.njit(cache=True, nogil=True, inline="always")
def apply(code, b, x):  # pragma: no cover - compiled
    """``g(x)`` for function ``code`` with breakpoint ``b``."""
    if code == 0:
        return x
    if code == 1:
        return abs(x)
    if code == 2:
        if x > b:
            return x - b
        if x < -b:
            return x + b
        return 0.0
    if code == 3:
        if x > b:
            return b
        if x < -b:
            return -b
        return x
    return x * abs(x)


@nb.njit(cache=True, nogil=True, inline="always")
def derivative(code, b, x):  # pragma: no cover - compiled
    """``dg/dx`` for function ``code`` with breakpoint ``b``."""
    if code == 0:
        return 1.0
    if code == 1:
        return 1.0 if x >= 0.0 else -1.0
    if code == 2:
        return 1.0 if abs(x) > b else 0.0
    if code == 3:
        return 1.0 if abs(x) < b else 0.0
    return 2.0 * abs(x)


def apply_array(code: int, b: float, x: np.ndarray) -> np.ndarray:
    """Vectorised ``g(x)`` (NumPy), the same values as :func:`apply`."""
    if code == 0:
        return x
    if code == 1:
        return np.abs(x)
    if code == 2:
        return np.sign(x) * np.maximum(np.abs(x) - b, 0.0)
    if code == 3:
        return np.clip(x, -b, b)
    return x * np.abs(x)
