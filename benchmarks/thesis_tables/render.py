"""The thesis tables' rendering: each table's markdown (vrig beside the text, with its
verdicts), Table 3.7's, the normal tables', and the closing "text vs vrig" table."""

from __future__ import annotations

import numpy as np

from benchmarks.thesis_tables.data import THESIS_3_7, NormalTable, Table
from benchmarks.thesis_tables.run import TableRun
from benchmarks.thesis_tables.verdicts import (
    _3_7_KEYS,
    CALIBRATED_VARIANT,
    _baseline,
    _ordering,
    _rig_specific_better,
    _text_figure,
    _verdict,
    calibrated_row,
    calibrated_verdict,
    figure_verdict,
    gain_verdicts,
)

__all__ = ["closing_table"]


def _setting_text(setting: tuple, requested: str | None) -> str:
    variant, severity = setting
    text = f"variant {variant!r}"
    if requested is not None and requested != variant:
        text += f" (the rig has no {requested!r})"
    if severity is not None:
        text += f", severity {severity:g}"
    return text


def _fmt(v, k) -> str:
    if isinstance(v, str):
        return v if k == 0 else ""
    return f"{v[k]:.1f}"


def _markdown(table: Table, runs) -> str:
    """``runs``: a list of :class:`TableRun`, one per variant and target."""
    chans = table.channels
    cal_i = calibrated_row(table)
    head = "| procedure | role | "
    cols = []
    for c in chans:
        cols += [f"vrig({run[0]}) {c} [%]" for run in runs] + [f"text {c} [%]"]
    head += " | ".join(cols) + " |"
    lines = [
        f"### {table.name}",
        "",
        f"rig `{table.rig}`, band {table.band[0]:g}-{table.band[1]:g} Hz; "
        + "; ".join(f"vrig({run[0]}) ran on {run[1]}" for run in runs),
    ]
    if table.note:
        lines.append(f"({table.note})")
    lines += ["", head, "|" + "---|" * (2 + len(cols))]
    for i, row in enumerate(table.rows):
        role = "CALIBRATED ON" if i == cal_i else "predicted"
        cells = []
        for k in range(len(chans)):
            cells += [_fmt(run[2][i], k) for run in runs]
            t = row.thesis[k] if k < len(row.thesis) else None
            cells.append("-" if t is None else f"{t:g}")
        lines.append(f"| {row.label} | {role} | " + " | ".join(cells) + " |")
    lines.append("")
    base = _baseline(table)
    for name, _text, values, variant, _target in runs:
        tag = f"vrig({name})"
        lines.append(f"**Calibrated, {tag}:** {calibrated_verdict(table, values, variant)}  ")
        lines.append(f"**Predicted ordering, {tag}:** {_verdict(table, values)}  ")
        gains = gain_verdicts(table, values, base)
        what = "gain over the calibrated row" if cal_i is not None else "gain over the first row"
        for g in gains:
            lines.append(f"**Predicted {what}, {tag}:** {g}  ")
    lines.append("")
    return "\n".join(lines)


def _markdown_normal(table: NormalTable, runs) -> str:
    """``runs``: a list of (column name, setting text, values, notes, rms text) per column."""
    lines = [
        f"### {table.name}",
        "",
        f"rig `{table.rig}`, band {table.band[0]:g}-{table.band[1]:g} Hz, normal (forward) "
        f"models {', '.join(table.inputs)} -> {', '.join(table.channels)}; fitted on one "
        "identification-type record (triangular PSD, seed 1), η0 [%] in free run on a held-out "
        "record (seed 2); " + "; ".join(f"vrig({r[0]}): {r[1]}, drive RMS {r[4]}" for r in runs),
    ]
    if table.note:
        lines.append(f"({table.note})")
    head = (
        "| procedure | channel | " + " | ".join(f"vrig({r[0]}) [%]" for r in runs) + " | text [%] |"
    )
    lines += ["", head, "|" + "---|" * (3 + len(runs))]
    for i, row in enumerate(table.rows):
        for k, c in enumerate(table.channels):
            cells = []
            for r in runs:
                v, note = r[2][i], r[3][i]
                cell = _fmt(v, k)
                if note and not isinstance(v, str):
                    cell += f" ({note})"
                cells.append(cell)
            t = row.thesis[k] if k < len(row.thesis) else None
            lines.append(
                f"| {row.label} | {c} | "
                + " | ".join(cells)
                + f" | {'-' if t is None else f'{t:g}'} |"
            )
        if len(table.channels) > 1:
            cells = [_fmt([float(np.mean(r[2][i]))], 0) if not isinstance(r[2][i], str) else ""
                     for r in runs]  # fmt: skip
            lines.append(
                f"| {row.label} | mean of {len(table.channels)} | " + " | ".join(cells) + " | - |"
            )
    lines.append("")
    for name, _s, values, _n, _r in runs:
        tag = f"vrig({name})"
        lines.append(f"**Predicted ordering, {tag}:** {_verdict(table, values)}  ")
        for g in gain_verdicts(table, values, 0):
            lines.append(f"**Predicted gain over the first row, {tag}:** {g}  ")
    lines.append("")
    return "\n".join(lines)


def _markdown_3_7(names, out, setting: str = "its default variant") -> str:
    lines = [
        "### Table 3.7: seven-channel fuel tank, modelling error per channel",
        "",
        f"rig `fuel-tank-7ch` ({setting}), band 1-40 Hz, QanTiM 4th order, same identification RMS for both "
        "PSDs; error = η0 [%] in free run on a held-out record of the same PSD: the inverse "
        "model's drive per drive channel (the text's measure) and the normal model's response "
        "per response channel",
        "",
        "| channel | inverse, triangular | inverse, rig-specific | text (inverse, rig-specific) "
        "| normal, triangular | normal, rig-specific |",
        "|---|---|---|---|---|---|",
    ]
    keys = ["triangular", "rig-specific (Alg. 3.1)"]
    cols = [out[k] for k in keys] + [out[k + " normal"] for k in keys]
    if any(isinstance(c, str) for c in cols):
        lines.append(
            "| failed | " + " | ".join(c if isinstance(c, str) else "" for c in cols) + " |"
        )
        return "\n".join([*lines, "", "**Verdict:** not comparable", ""])
    for i, name in enumerate(names):
        a, b, c, d = (col[i] for col in cols)
        lines.append(f"| {name} | {a:.1f} | {b:.1f} | {THESIS_3_7[i]:g} | {c:.1f} | {d:.1f} |")
    inv_better, fwd_better = _rig_specific_better(out), _rig_specific_better(out, " normal")
    useless = np.min(cols[:2]) >= 100
    verdict = (
        f"rig-specific PSDs give the lower inverse modelling error on {inv_better} of 7 "
        f"channels and the lower normal modelling error on {fwd_better} of 7 (the text: better "
        "on all seven)"
    )
    if useless:
        verdict += (
            "; but every inverse error is >= 100 %: the drive's low-frequency displacement, "
            "which dominates a triangular displacement PSD, leaves almost no acceleration "
            "signature, so no inverse reproduces it and the comparison is not meaningful"
        )
    return "\n".join([*lines, "", f"**Verdict:** {verdict}", ""])


_ORDERING = {None: "not comparable", True: "same ordering", False: "different ordering"}


def _cell(v) -> str:
    """vrig's figure [%] in the closing table, or the failure's kind."""
    return f"failed ({v.split(':')[0]})" if isinstance(v, str) else f"{v:.1f}"


def _channel_value(values, i: int, k: int):
    """Row ``i``'s figure on channel ``k`` (the failure string for a failed row)."""
    return values[i] if isinstance(values[i], str) else values[i][k]


def _closing_rows(table: Table, run: TableRun) -> list[tuple]:
    """The closing table's rows of one table run: (table, row, run, text, vrig, role, verdict)
    per figure the text reports, then the table's ordering."""
    short = table.name.split(":")[0].removeprefix("Table ")
    cal_i, base = calibrated_row(table), _baseline(table)
    out = []
    for i, row in enumerate(table.verdict_rows()):
        for k, channel in enumerate(table.channels):
            t, v = _text_figure(row, k), _channel_value(run.values, i, k)
            if t is None:
                continue
            label = row.label if len(table.channels) == 1 else f"{row.label}, {channel}"
            t_base = _text_figure(table.rows[base], k)
            if i == base or t_base is None:  # the figure itself
                if i == cal_i:
                    role = "calibrated on" if run.variant == CALIBRATED_VARIANT else (
                        "calibrated row (comparison)"
                    )  # fmt: skip
                else:
                    role = "prediction (baseline)" if i == base else "prediction (figure)"
                cells = (f"{t:g}", _cell(v), role, figure_verdict(t, v))
            else:  # a predicted row: its gain over the baseline row
                vb = _channel_value(run.values, base, k)
                gain = "" if isinstance(v, str) or isinstance(vb, str) else (
                    f" (gain {vb - v:.1f} of {vb:.1f})"
                )  # fmt: skip
                cells = (
                    f"{t:g} (gain {t_base - t:g} of {t_base:g})",
                    _cell(v) + gain,
                    "prediction",
                    figure_verdict(t, v, text_base=t_base, vrig_base=vb),
                )
            out.append((short, label, run.name, *cells))
    ordering = _ORDERING[_ordering(table, run.values)]
    out.append((short, f"ordering: {table.claim}", run.name, "-", "-", "prediction", ordering))
    return out


def _closing_rows_3_7(names, out: dict, variant: str) -> list[tuple]:
    """Table 3.7's closing rows: each channel's inverse modelling error with the rig-specific
    PSD against the text's, then the ordering (rig-specific below triangular everywhere)."""
    if not names:
        return []
    run = f"{variant}, held-out identification record"
    spec = out.get(_3_7_KEYS[1], "no result")
    rows = [
        ("3.7", f"inverse ARX(4), rig-specific PSD, {name}", run, f"{THESIS_3_7[i]:g}",
         _cell(_channel_value([spec], 0, i)), "prediction (figure)",
         figure_verdict(THESIS_3_7[i], _channel_value([spec], 0, i)))
        for i, name in enumerate(names)
    ]  # fmt: skip
    better = _rig_specific_better(out)
    ordering = _ORDERING[None if better is None else better == len(names)]
    if better is not None and better != len(names):
        ordering += f" ({better} of {len(names)} channels)"
    claim = "ordering: rig-specific PSD below triangular on every channel (inverse)"
    return [*rows, ("3.7", claim, run, "-", "-", "prediction", ordering)]


def closing_table(table_runs, runs_3_7=()) -> str:
    """The report's closing table "text vs vrig" (markdown): one row per figure the text
    reports in the tables of ``table_runs`` and in Table 3.7, per run, with its verdict
    (:func:`figure_verdict`; the rule in the module documentation), and a count per verdict.

    Parameters
    ----------
    table_runs : sequence of (Table, list of TableRun)
        Each table with its runs (one per variant and target kind).
    runs_3_7 : sequence of (str, list, dict)
        Table 3.7's runs: (variant, channel names, :func:`table_3_7`'s results).

    Returns
    -------
    str
        The markdown section.
    """
    rows = [r for table, runs in table_runs for run in runs for r in _closing_rows(table, run)]
    rows += [r for variant, names, out in runs_3_7 for r in _closing_rows_3_7(names, out, variant)]
    lines = [
        "### Text vs vrig: the closing verdicts",
        "",
        "One row per figure the text reports (η0 [%]). Calibrated row: within ±25 % of the "
        "text's figure or not (`r` = vrig / text). Predicted row: its gain over the table's "
        "linear baseline row (points, of that baseline) against the text's gain, each as a "
        "fraction of its own baseline: holds within ±25 % of the text's, else misses (`r` = "
        "vrig's relative gain / the text's). Ordering: the table's ordering verdict.",
        "",
        "| table | row (method/model) | run (variant, target kind) | text [%] | vrig [%] | role "
        "| verdict |",
        "|---|---|---|---|---|---|---|",
        *("| " + " | ".join(r) + " |" for r in rows),
        "",
    ]
    counts: dict = {}
    for r in rows:
        counts[r[6].split(" (")[0]] = counts.get(r[6].split(" (")[0], 0) + 1
    lines.append("verdicts: " + ", ".join(f"{n} {v}" for v, n in counts.items()))
    return "\n".join([*lines, ""])
