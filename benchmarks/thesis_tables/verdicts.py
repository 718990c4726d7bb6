"""The thesis tables' verdicts: which row a twin was calibrated on, and vrig's figures judged
against the text's (the ordering, the calibrated row's band, the predicted rows' gains; the
rule in :mod:`benchmarks.thesis_tables`)."""

from __future__ import annotations

import numpy as np

from benchmarks.thesis_tables.data import Table

__all__ = [
    "CALIBRATED_VARIANT",
    "GAIN_TOLERANCE",
    "calibrated_row",
    "calibrated_verdict",
    "figure_verdict",
    "gain_verdicts",
]


def calibrated_row(table: Table) -> int | None:
    """Index of the row the rig's ``"thesis"`` variant was calibrated on, taken from
    ``benchmarks.calibrate.CALIBRATIONS`` (the single source of truth): the inverse ARX of the
    calibration's order, on its responses, at IT00, in its band. ``None`` if the rig was not
    calibrated (every row a prediction). A calibrated rig whose table has no such row, or whose
    text figure for it differs from the calibration's target, is an error."""
    from benchmarks.calibrate import CALIBRATIONS
    from vrig.reconstruction import InverseArx

    cal = CALIBRATIONS.get(table.rig)
    if cal is None or cal["target"] is None:  # no calibration, or none on a linear baseline
        return None
    if tuple(table.band) != tuple(cal["band"]):
        raise ValueError(
            f"{table.name}: band {table.band} Hz is not the band {cal['band']} Hz "
            f"{table.rig!r} was calibrated in (benchmarks/calibrate.py)"
        )
    responses = list(cal["responses"]) if cal.get("responses") else None
    for i, row in enumerate(table.verdict_rows()):
        if row.iteration or not callable(row.method):
            continue
        method = row.method()
        if not isinstance(method, InverseArx) or method.order != cal["arx_order"]:
            continue
        if (list(method.responses) if method.responses is not None else None) != responses:
            continue
        chans = _cal_channels(table)
        texts = [t for c, t in zip(table.channels, row.thesis, strict=False) if c in chans]
        if any(t != cal["target"] for t in texts):
            raise ValueError(
                f"{table.name}: row {row.label!r} gives the text's figure {row.thesis} but "
                f"{table.rig!r} was calibrated on {cal['target']:g} % (benchmarks/calibrate.py)"
            )
        return i
    raise ValueError(
        f"{table.name}: no row is the linear baseline {table.rig!r} was calibrated on "
        f"(inverse ARX({cal['arx_order']}) on {responses or 'all responses'}, IT00; "
        "benchmarks/calibrate.py CALIBRATIONS)"
    )


def _cal_channels(table: Table) -> list:
    """The channels the calibration's objective is taken on (its ``channels``, default the
    table's first channel: the rig's first output in every table here)."""
    from benchmarks.calibrate import CALIBRATIONS

    cal = CALIBRATIONS.get(table.rig, {})
    return list(cal.get("channels") or table.channels[:1])


def _ordering(table: Table, values) -> bool | None:
    """Does vrig give the text's ordering (``table.verdict``)? ``None``: a procedure failed."""
    n = len(table.verdict_rows())
    if any(isinstance(v, str) for v in values[:n]):
        return None
    return bool(eval(table.verdict, {}, {"v": values}))  # expressions: module constants above


def _verdict(table: Table, values) -> str:
    ok = _ordering(table, values)
    if ok is None:
        return "not comparable (a procedure failed)"
    return f"{'same ordering as' if ok else 'different ordering from'} the text ({table.claim})"


CALIBRATED_VARIANT = "thesis"  # the variant benchmarks.calibrate writes (write_variant)


def calibrated_verdict(table: Table, values, variant: str | None = CALIBRATED_VARIANT) -> str:
    """The calibrated row's verdict: each objective channel within the calibration's
    tolerance of the text's figure (the tolerance and target from ``CALIBRATIONS``). On
    another ``variant`` than the calibrated one it is said to be a comparison only."""
    from benchmarks.calibrate import CALIBRATIONS, TOLERANCE

    i = calibrated_row(table)
    if i is None:
        return (
            f"no row calibrated on: {table.rig!r} has no linear-baseline calibration "
            "(benchmarks/calibrate.py); every row is a prediction"
        )
    cal, row, v = CALIBRATIONS[table.rig], table.rows[i], values[i]
    if isinstance(v, str):
        return f"calibrated row ({row.label}) failed: {v[:120]}"
    lo, hi = cal["target"] * (1 - TOLERANCE), cal["target"] * (1 + TOLERANCE)
    figs = {c: v[table.channels.index(c)] for c in _cal_channels(table)}
    ok = all(lo <= x <= hi for x in figs.values())
    shown = ", ".join(f"{c} {x:.1f} %" for c, x in figs.items())
    note = (
        ""
        if variant == CALIBRATED_VARIANT
        else f" (variant {variant!r} is not the calibrated {CALIBRATED_VARIANT!r}: a comparison)"
    )
    return (
        f"calibrated row ({row.label}): {shown} vs the text's {cal['target']:g} % -> "
        f"{'within' if ok else 'OUTSIDE'} ±{TOLERANCE:.0%} ({lo:.1f}-{hi:.1f} %){note}"
    )


GAIN_TOLERANCE = 0.25  # relative: a predicted gain "as the text's" if within ±25 % of it


def gain_verdicts(table: Table, values, baseline: int) -> list[str]:
    """Per text-reported row other than ``baseline`` and per channel the text reports for both:
    vrig's gain over the baseline row (percentage points, and as a fraction of the baseline)
    against the text's. The size is judged on the fraction (the calibrated baseline itself
    only lands within ±25 % of the text's): "as the text's" within ±25 % relative of it,
    else larger or smaller; "none" where vrig's row is not below its baseline."""
    out = []
    for i, k, t_base, t_row in _gain_pairs(table, baseline):
        text_gain = t_base - t_row
        head = f"{table.rows[i].label}, {table.channels[k]}: "
        text = f"the text's {text_gain:g} pts ({text_gain / t_base:.0%} of {t_base:g} %)"
        if isinstance(values[i], str) or isinstance(values[baseline], str):
            out.append(head + f"not comparable (a procedure failed) vs {text}")
            continue
        b, r = values[baseline][k], values[i][k]
        gain, frac = b - r, (b - r) / b
        out.append(
            head
            + f"gain {gain:.1f} pts ({frac:.0%} of {b:.1f} %) vs {text} -> "
            + _gain_size(frac, text_gain / t_base)
        )
    return out


def _text_figure(row, k: int):
    """The text's figure of ``row`` on channel ``k`` (``None``: the text gives none)."""
    return row.thesis[k] if k < len(row.thesis) else None


def _gain_pairs(table, baseline: int):
    """``(row, channel, text baseline, text figure)`` indices and figures of every text-reported
    row other than ``baseline`` and channel the text gives a figure for in both rows."""
    for i, row in enumerate(table.verdict_rows()):
        if i == baseline:
            continue
        for k in range(len(table.channels)):
            t_base, t_row = _text_figure(table.rows[baseline], k), _text_figure(row, k)
            if t_base is not None and t_row is not None:
                yield i, k, t_base, t_row


def _gain_size(frac: float, text_frac: float) -> str:
    """vrig's relative gain ``frac`` against the text's ``text_frac`` (both signed fractions of
    their baselines: negative = worse than the baseline)."""
    if text_frac == 0:
        return "as the text's (none)" if abs(frac) < 0.05 else "a change where the text has none"
    ratio = frac / text_frac
    if ratio <= 0:
        return "none (not below the baseline)" if text_frac > 0 else "opposite to the text's"
    if _gain_holds(ratio):
        return "as the text's"
    return f"{'larger' if ratio > 1 else 'smaller'} ({ratio:.2f} x the text's)"


def _gain_holds(ratio: float) -> bool:
    """A gain ``ratio`` x the text's (relative gains) is the text's within :data:`GAIN_TOLERANCE`."""
    return abs(ratio - 1) <= GAIN_TOLERANCE


def figure_verdict(text: float, vrig, *, text_base: float | None = None, vrig_base=None) -> str:
    """The closing table's verdict on one figure (the rule in the module documentation).

    Parameters
    ----------
    text : float
        The text's figure [%] (η0 of the row on one channel).
    vrig : float or str
        vrig's figure [%] for the same row and channel; a string: the procedure failed (why).
    text_base, vrig_base : float or str, optional
        The text's and vrig's figures [%] of the table's linear baseline row on the same
        channel. Given, the figure is a predicted row judged on its gain over that baseline
        (each gain a fraction of its own baseline, as :func:`gain_verdicts`); omitted, the
        figure itself is judged (the calibrated row).

    Returns
    -------
    str
        ``"within ±25 %"`` or ``"outside (×r)"`` (``r`` = vrig / text) for a figure;
        ``"holds"`` or ``"misses (×r)"`` (``r`` = vrig's relative gain / the text's) for a gain;
        ``"not comparable (failed)"`` where vrig's procedure failed.

    Raises
    ------
    ValueError
        If only one of ``text_base`` and ``vrig_base`` is given, or a text figure is not
        positive.
    """
    from benchmarks.calibrate import TOLERANCE

    if (text_base is None) != (vrig_base is None):
        raise ValueError("give both text_base and vrig_base (a gain) or neither (a figure)")
    if not text > 0 or (text_base is not None and not text_base > 0):
        raise ValueError(f"the text's figures must be > 0 %, got {text!r} and {text_base!r}")
    if isinstance(vrig, str) or isinstance(vrig_base, str):
        return "not comparable (failed)"
    if text_base is None:
        within = text * (1 - TOLERANCE) <= vrig <= text * (1 + TOLERANCE)
        return f"within ±{100 * TOLERANCE:g} %" if within else f"outside (×{vrig / text:.2f})"
    if not vrig_base > 0:
        return "not comparable (vrig's baseline is 0 %)"
    frac, text_frac = (vrig_base - vrig) / vrig_base, (text_base - text) / text_base
    if text_frac == 0:
        return "holds" if abs(frac) < 0.05 else "misses (the text has no gain)"
    ratio = frac / text_frac
    return "holds" if _gain_holds(ratio) else f"misses (×{ratio:.2f})"


def _baseline(table: Table) -> int:
    i = calibrated_row(table)
    return table.baseline if i is None else i


_3_7_KEYS = ("triangular", "rig-specific (Alg. 3.1)")  # table_3_7's results, inverse models


def _rig_specific_better(out: dict, suffix: str = "") -> int | None:
    """On how many channels the rig-specific PSD gives the lower modelling error than the
    triangular one (``suffix`` ``" normal"``: the normal models); ``None``: a model failed."""
    tri, spec = (out.get(k + suffix) for k in _3_7_KEYS)
    if tri is None or spec is None or isinstance(tri, str) or isinstance(spec, str):
        return None
    return int(np.sum(np.asarray(spec) < np.asarray(tri)))
