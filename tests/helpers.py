"""Small helpers shared by test modules (``from helpers import ...``: pytest puts this folder on
``sys.path``)."""

from __future__ import annotations

import numpy as np


def records_equal(a, b) -> bool:
    """Nested dicts, tuples, lists and arrays equal bit for bit (arrays by ``np.array_equal``)."""
    if isinstance(a, dict):
        return a.keys() == b.keys() and all(records_equal(a[k], b[k]) for k in a)
    if isinstance(a, (tuple, list)):
        return len(a) == len(b) and all(records_equal(x, y) for x, y in zip(a, b, strict=True))
    if isinstance(a, np.ndarray):
        return np.array_equal(a, b)
    return a == b
