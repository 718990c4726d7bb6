"""Value checks shared by the side-car reader, the rig dataclasses and ``load_rig`` overrides.

Each check names the key and the allowed range in a :class:`~vrig.errors.RigParameterError`.
"""

from __future__ import annotations

import math
import numbers

from ..errors import RigParameterError

__all__ = ["check_number", "describe_range", "replace_fields"]


def describe_range(
    *,
    minimum=None,
    exclusive_minimum=None,
    maximum=None,
    exclusive_maximum=None,
    nonzero: bool = False,
    integer: bool = False,
) -> str:
    """The allowed range in words, e.g. ``"a finite number > 0"`` or ``"an integer in [1, 20]"``."""
    what = "an integer" if integer else "a finite number"
    low = (f"[{minimum:g}" if minimum is not None else None) or (
        f"({exclusive_minimum:g}" if exclusive_minimum is not None else None
    )
    high = (f"{maximum:g}]" if maximum is not None else None) or (
        f"{exclusive_maximum:g})" if exclusive_maximum is not None else None
    )
    if low and high:
        text = f"{what} in {low}, {high}"
    elif low:
        text = f"{what} {'>=' if low[0] == '[' else '>'} {low[1:]}"
    elif high:
        text = f"{what} {'<=' if high[-1] == ']' else '<'} {high[:-1]}"
    else:
        text = what
    return text + (", not 0" if nonzero else "")


def check_number(key: str, value, *, where: str = "", **bounds):
    """``value`` if it is a real number (not a bool) within ``bounds`` (the keywords of
    :func:`describe_range`), else :class:`RigParameterError` naming ``key`` and the range."""
    integer = bounds.get("integer", False)
    ok = isinstance(value, numbers.Real) and not isinstance(value, bool)
    if ok and integer:
        ok = isinstance(value, numbers.Integral) or (math.isfinite(value) and value == int(value))
    if ok:
        v = float(value)
        lo, lo_x = bounds.get("minimum"), bounds.get("exclusive_minimum")
        hi, hi_x = bounds.get("maximum"), bounds.get("exclusive_maximum")
        ok = (
            math.isfinite(v)
            and (lo is None or v >= lo)
            and (lo_x is None or v > lo_x)
            and (hi is None or v <= hi)
            and (hi_x is None or v < hi_x)
            and not (bounds.get("nonzero") and v == 0)
        )
    if not ok:
        allowed = describe_range(**bounds)
        prefix = f"{where}: " if where else ""
        raise RigParameterError(
            f"{prefix}{key} must be {allowed}, got {value!r}", key=key, value=value, allowed=allowed
        )
    return int(value) if integer else value


def replace_fields(obj, changes: dict, what: str):
    """A copy of the dataclass ``obj`` with ``changes``; an unknown field name is a
    RigParameterError naming ``what`` and the known fields (the copy's own checks run)."""
    from dataclasses import asdict, fields

    names = {f.name for f in fields(obj)}
    unknown = set(changes) - names
    if unknown:
        raise RigParameterError(
            f"unknown {what}(s) {sorted(unknown)}; known: {sorted(names)}",
            key=", ".join(sorted(unknown)),
            allowed=", ".join(sorted(names)),
        )
    return type(obj)(**{**asdict(obj), **changes})

