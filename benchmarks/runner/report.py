"""Outputs of a run: every record as JSON and CSV, the Markdown leaderboard and the plots.

* ``records.json`` — the list of records (sorted by id), exactly as in ``records/``;
* ``records.csv`` — one row per record, scalar fields (per-iteration η0 as ``a;b;c``);
* ``leaderboard.md`` — the overall ranking and one table per rig (see :func:`leaderboard`; a
  modelling error that blew up — above :data:`BLEW_UP_PERCENT` — is marked † and left out of
  the mean, a damage ratio outside 1/:data:`DAMAGE_FACTOR`..:data:`DAMAGE_FACTOR` is marked ‡,
  each with a footnote under the table saying what it means);
  a rig run at a non-linearity severity s is its own "rig" ``rig@s`` there; records on field
  targets (``--targets field:<scenario>``) are ranked apart, in a section "Field targets"
  (:func:`field_section`), each rig on a scenario its own "rig" ``rig:scenario``; when a rig
  has records at more than one severity, a section "Severity" follows (:func:`severity_section`);
  given the learned-iteration results (``policies=``, the runner's ``--policies``, default
  ``results/learned_iteration.json``), a section "Policies" ends it (:func:`policies_section`);
* ``plots/bars_<rig>.png`` — mean η0 at IT00 and at the best iteration per method
  (``bars_<rig>--sev<s>.png`` at severity s);
* ``plots/error_vs_iteration_<method>.png`` — mean η0 versus iteration, one line per record;
* ``plots/severity-<rig>.png`` — per rig with more than one severity: each method's IT00 and
  best η0 against severity (:func:`plot_severity`).

Figures use matplotlib's Agg canvas directly (no global backend switch) and are written
atomically (``vrig.files.atomic_write``).
"""

from __future__ import annotations

import csv
import io
import json
from collections import defaultdict
from pathlib import Path

import numpy as np

from .execute import write_atomic
from .record import PSEUDO_FIELD, format_severity

__all__ = [
    "aggregate",
    "field_section",
    "leaderboard",
    "method_linearity",
    "plot_severity",
    "policies_section",
    "severity_crossover",
    "severity_section",
    "severity_tables",
    "write_outputs",
]

FAILED_SCORE = 100.0  # η0 [%] a failed record counts as in the overall ranking

BLEW_UP_PERCENT = 1000.0
"""A modelling error (held-out free-run η0, %) above this is a model that blew up: η0 = 100 %
is what a prediction of zero scores, so above 1000 % the prediction is more than ten times the
record it predicts (a diverging recursion or an ill-conditioned fit: the FIR plugin's forward
model scored 4.5e9 %). The leaderboard marks it "blew up †" and leaves it out of the mean."""

DAMAGE_FACTOR = 10.0
"""A damage ratio (achieved over desired rainflow pseudo-damage, S-N slope 5) off by more than
this factor (outside [1/DAMAGE_FACTOR, DAMAGE_FACTOR]) is marked ‡ in the leaderboard, with the
size of load cycles it means: the slope-5 power turns load cycles 2.67 times the desired ones'
size into a ratio of 136 (ratio^(1/5) = 2.67), cycles 1.6 times their size into 10."""

DAMAGE_SLOPE = 5.0  # = vrig.reconstruction.scores.DAMAGE_SLOPE (the records' pseudo-damage)

_CSV_FIELDS = [
    "id",
    "rig",
    "method",
    "desired",
    "seed",
    "severity",
    "target",
    "status",
    "eta0_it00",
    "eta0_final",
    "eta0_best",
    "best_iteration",
    "iterations_run",
    "iterations_to_tolerance",
    "rms_error",
    "damage_ratio",
    "normal_model_error",
    "inverse_model_error",
    "model_size",
    "fit_s",
    "model_sim_s",
    "reconstruction_s",
    "record_s",
    "eta0_per_iteration",
    "stopped",
    "error_stage",
    "error_type",
    "error_message",
    "method_description",
]


def _mean(values):
    vals = [v for v in values if v is not None]
    return float(np.mean(vals)) if vals else None


def severity_of(record: dict) -> float | None:
    """The record's severity (None: the rig as loaded, and every record older than the axis)."""
    return record["key"].get("severity")


def target_of(record: dict) -> str:
    """The record's target: ``"field:<scenario>"``, or ``"pseudo-field"`` (also every record
    older than the target axis: their keys have no ``target``)."""
    return record["key"].get("target", PSEUDO_FIELD)


def _base_label(record: dict) -> str:
    """``rig``, or ``rig:scenario`` for a record on a field target."""
    target = target_of(record)
    rig = record["key"]["rig"]
    return rig if target == PSEUDO_FIELD else f"{rig}:{target.partition(':')[2]}"


def rig_label(record: dict) -> str:
    """``rig``, ``rig@s`` for a record at severity s, ``rig:scenario`` (``rig:scenario@s``)
    for a record on a field target (a rig at two severities or on two targets is two rigs in
    the leaderboard's tables: their errors are not averaged together)."""
    sev = severity_of(record)
    label = _base_label(record)
    return label if sev is None else f"{label}@{format_severity(sev)}"


def _file_label(label: str) -> str:
    return label.replace("@", "--sev").replace(":", "--field-")


def aggregate(records: list[dict]) -> dict:
    """Per (rig, method): counts and means over the records (desired responses × seeds); the
    rig is :func:`rig_label` (``rig@s`` at severity s)."""
    groups: dict[tuple[str, str], list[dict]] = defaultdict(list)
    for r in records:
        groups[(rig_label(r), r["key"]["method"])].append(r)
    out = {}
    for (rig, method), recs in sorted(groups.items()):
        ok = [r for r in recs if r["status"] == "ok"]
        reached = [
            r["iterations_to_tolerance"] for r in ok if r["iterations_to_tolerance"] is not None
        ]
        out[(rig, method)] = {
            "n": len(recs),
            "ok": len(ok),
            "eta0_it00": _mean(r["eta0_it00"] for r in ok),
            "eta0_final": _mean(r["eta0_final"] for r in ok),
            "eta0_best": _mean(r["eta0_best"] for r in ok),
            "reached": len(reached),
            "iterations_to_tolerance": _mean(reached),
            "rms_error": _mean(r["rms_error"] for r in ok),
            "damage_ratio": _mean(r["damage_ratio"] for r in ok),
            **_modelling("normal", recs),
            **_modelling("inverse", recs),
            "fit_s": _mean(r["timing"].get("fit_s") for r in ok),
            "model_size": _mean(r.get("model_size") for r in ok),
            "score": float(
                np.mean([FAILED_SCORE if r["status"] != "ok" else r["eta0_best"] for r in recs])
            ),
            "failures": sorted(
                {
                    f"{r['error']['stage']}: {r['error']['type']}: {_short(r['error']['message'])}"
                    for r in recs
                    if r["status"] != "ok"
                }
            ),
            "description": next((r.get("method_description") for r in ok), None),
        }
    return out


def _modelling(which: str, recs: list[dict]) -> dict:
    """``{which}_model_error`` (mean over the records' values at most :data:`BLEW_UP_PERCENT`),
    ``{which}_model_n`` (records with a value) and ``{which}_model_blew_up`` (the values above
    it) of a group of records."""
    values = [v for v in (r.get(f"{which}_model_error") for r in recs) if v is not None]
    return {
        f"{which}_model_error": _mean(v for v in values if v <= BLEW_UP_PERCENT),
        f"{which}_model_n": len(values),
        f"{which}_model_blew_up": [v for v in values if not v <= BLEW_UP_PERCENT],
    }


def _modelling_cell(a: dict, which: str) -> str:
    """A modelling-error cell: the mean, with ``(k/n blew up †)`` or ``blew up †`` alone."""
    n, bad = a[f"{which}_model_n"], len(a[f"{which}_model_blew_up"])
    if n == 0:
        return "—"
    if bad == n:
        return "blew up †"
    mean = _f(a[f"{which}_model_error"])
    return mean if not bad else f"{mean} ({bad}/{n} blew up †)"


def _damage_flagged(ratio) -> bool:
    return ratio is not None and not 1 / DAMAGE_FACTOR <= ratio <= DAMAGE_FACTOR


def _damage_cell(ratio) -> str:
    return _f(ratio, "{:.2f}") + (" ‡" if _damage_flagged(ratio) else "")


def _flag_notes(rows: list) -> list[str]:
    """The footnotes of a rig table's † and ‡ marks (none when nothing is marked)."""
    blew = [
        (m, which, v)
        for m, a in rows
        for which in ("normal", "inverse")
        for v in a[f"{which}_model_blew_up"]
    ]
    damage = [(m, a["damage_ratio"]) for m, a in rows if _damage_flagged(a["damage_ratio"])]
    notes = []
    if blew:
        worst = max(v for *_, v in blew)
        notes.append(
            f"† blew up: the model's held-out free run came out more than ten times the size of "
            f"the record it predicts (η0 above {BLEW_UP_PERCENT:g} %, here up to {worst:.2g} %; "
            "100 % is what a prediction of zero scores): a diverging recursion or an "
            "ill-conditioned fit, not a modelling error. Left out of the mean; the raw values "
            "are in records.csv. "
            + "; ".join(f"{m} ({w}): {v:.2g} %" for m, w, v in blew)
            + "."
        )
    if damage:
        notes.append(
            f"‡ damage ratio outside {1 / DAMAGE_FACTOR:g}-{DAMAGE_FACTOR:g}: the achieved "
            f"response's rainflow pseudo-damage (S-N slope {DAMAGE_SLOPE:g}) is off the desired "
            f"one's by more than a factor {DAMAGE_FACTOR:g}. The slope-{DAMAGE_SLOPE:g} power "
            f"magnifies: a ratio R means load cycles R^(1/{DAMAGE_SLOPE:g}) times the desired "
            "ones' size (a reconstruction that missed its target, see its η0): "
            + "; ".join(f"{m} {r:.3g} → {r ** (1 / DAMAGE_SLOPE):.2f} x" for m, r in damage)
            + "."
        )
    return ["", *notes] if notes else []


def _short(msg: str, n: int = 110) -> str:
    msg = " ".join(str(msg).split())
    return msg if len(msg) <= n else msg[: n - 1] + "…"


def _f(x, fmt="{:.1f}") -> str:
    return "—" if x is None else fmt.format(x)


def leaderboard(records: list[dict], settings: dict | None = None, *, title: str = "") -> str:
    """The Markdown leaderboard of ``records``.

    Overall ranking: mean over all of a method's records of the best mean η0, a failed record
    counting as 100 %; then one table per rig ranked by the mean best η0 (methods with failed
    records after those without), and the failure reasons. Records on pseudo-field targets
    come first (the layout of a run without field targets; in a section "Pseudo-field targets"
    when there are field targets too); records on field targets follow in their own section
    (:func:`field_section`), ranked apart."""
    pseudo = [r for r in records if target_of(r) == PSEUDO_FIELD]
    field = [r for r in records if target_of(r) != PSEUDO_FIELD]
    lines = [f"# {title or 'vrig reconstruction benchmark: leaderboard'}", ""]
    if settings:
        s = settings
        lines += [
            f"{len(records)} records ({sum(r['status'] == 'ok' for r in records)} ok). "
            f"Desired responses: pseudo-field records of {s['seconds']:g} s "
            "(vrig.desired.pseudo_field); "
            f"{s['iterations']} iterations after IT00 at "
            + (f"gain {s['gain']:g}" if s.get("gain") is not None else "each rig's own gain")
            + "; rig fidelity "
            f"`{s['fidelity']}`; tolerance {s['tolerance']:g} % mean η0; modelling errors on "
            f"the last {100 * s['holdout']:.0f} % of the identification records. η0 is the "
            "DC-corrected QanTiM fit value (eq. 5-28), mean over response channels, lower is "
            "better; values are means over desired responses × seeds."
            + (" Service records (field targets): section *Field targets*." if field else ""),
            "",
        ]
    if any(severity_of(r) is not None for r in records):
        lines += [
            "`rig@s` is the rig at non-linearity severity s (`vrig.load_rig(rig, severity=s)`: "
            "0 linearised, 1 as loaded, 2 twice as non-linear; the desired response is the "
            "pseudo-field response of the rig at that severity); a rig without `@` is the rig "
            "as loaded.",
            "",
        ]
    if not field:
        lines += _ranking(pseudo, "##")
    elif pseudo:
        lines += ["## Pseudo-field targets", "", _PSEUDO_FIELD_TEXT, ""]
        lines += _ranking(pseudo, "###")
    lines += field_section(field)
    lines += severity_section(records)
    lines += _methods_lines(records)
    return "\n".join(lines)


_PSEUDO_FIELD_TEXT = (
    "Desired responses: pseudo-field records (`vrig.desired.pseudo_field.pseudo_field`: the rig's own response "
    "to a seeded road-like drive over its simulation band): reachable by construction."
)


def _per_rig_rows(agg: dict, rigs: list[str], methods: list[str]):
    """``({rig: [(method, aggregate), ...] best first}, {method: rigs won})``."""
    wins: dict[str, int] = defaultdict(int)
    per_rig_rows = {}
    for rig in rigs:
        entries = [(m, agg[(rig, m)]) for m in methods if (rig, m) in agg]
        entries.sort(
            key=lambda e: (
                e[1]["ok"] == 0,
                e[1]["ok"] < e[1]["n"],
                e[1]["eta0_best"] if e[1]["eta0_best"] is not None else np.inf,
            )
        )
        per_rig_rows[rig] = entries
        if entries and entries[0][1]["ok"] == entries[0][1]["n"]:
            wins[entries[0][0]] += 1
    return per_rig_rows, wins


def _overall_lines(agg, rigs, methods, wins, h: str) -> list[str]:
    lines = [
        f"{h} Overall",
        "",
        f"Score: mean best η0 over all records, a failed record counting as {FAILED_SCORE:g} %.",
        "",
        "| rank | method | score % | ok / records | rigs won | " + " | ".join(rigs) + " |",
        "|---:|---|---:|---:|---:|" + "---:|" * len(rigs),
    ]
    overall = []
    for m in methods:
        mine = [agg[(rig, m)] for rig in rigs if (rig, m) in agg]
        n = sum(a["n"] for a in mine)
        score = sum(a["score"] * a["n"] for a in mine) / n
        overall.append((score, m, sum(a["ok"] for a in mine), n))
    for rank, (score, m, ok, n) in enumerate(sorted(overall), 1):
        cells = []
        for rig in rigs:
            a = agg.get((rig, m))
            if a is None:
                cells.append("")
            elif a["ok"] == 0:
                cells.append("fail")
            else:
                cells.append(
                    _f(a["eta0_best"]) + ("" if a["ok"] == a["n"] else f" ({a['ok']}/{a['n']})")
                )
        lines.append(
            f"| {rank} | {m} | {score:.1f} | {ok} / {n} | {wins.get(m, 0)} | "
            + " | ".join(cells)
            + " |"
        )
    lines.append("")
    return lines


def _rig_lines(rig: str, rows: list, h: str) -> list[str]:
    lines = [
        f"{h} {rig}",
        "",
        "| rank | method | ok | IT00 η0 % | final η0 % | best η0 % | its to tol | RMS err % "
        "| damage ratio | normal model err % | inverse model err % | fit s | model size |",
        "|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for rank, (m, a) in enumerate(rows, 1):
        tol = (
            "—"
            if a["reached"] == 0
            else f"{a['iterations_to_tolerance']:.1f}"
            + ("" if a["reached"] == a["ok"] else f" ({a['reached']}/{a['ok']})")
        )
        lines.append(
            f"| {rank} | {m} | {a['ok']}/{a['n']} | {_f(a['eta0_it00'])} | "
            f"{_f(a['eta0_final'])} | {_f(a['eta0_best'])} | {tol} | {_f(a['rms_error'])} | "
            f"{_damage_cell(a['damage_ratio'])} | {_modelling_cell(a, 'normal')} | "
            f"{_modelling_cell(a, 'inverse')} | {_f(a['fit_s'], '{:.2f}')} | "
            f"{_f(a['model_size'], '{:.0f}')} |"
        )
    lines += _flag_notes(rows)
    fails = [(m, f) for m, a in rows for f in a["failures"]]
    if fails:
        lines += ["", "Failures:", ""]
        lines += [f"* {m}: {f}" for m, f in fails]
    lines.append("")
    return lines


def _ranking(records: list[dict], h: str) -> list[str]:
    """The overall ranking (heading ``h`` Overall) and one table per rig label of ``records``."""
    agg = aggregate(records)
    rigs = sorted({rig for rig, _ in agg})
    methods = sorted({m for _, m in agg})
    per_rig_rows, wins = _per_rig_rows(agg, rigs, methods)
    lines = _overall_lines(agg, rigs, methods, wins, h)
    for rig in rigs:
        lines += _rig_lines(rig, per_rig_rows[rig], h)
    return lines


def field_section(records: list[dict]) -> list[str]:
    """The leaderboard's "Field targets" section (empty without field-target records): what
    the targets are, then the ranking of the field-target records (its own overall table and
    one table per ``rig:scenario``), apart from the pseudo-field one.

    Parameters
    ----------
    records : list of dict
        The records on field targets (``key["target"]`` ``"field:<scenario>"``).
    """
    if not records:
        return []
    lines = [
        "## Field targets",
        "",
        "Desired responses: service records "
        '(`vrig.desired.kinds.desired_response(rig, "field:<scenario>")`): the rig\'s specimen in its '
        "vehicle (`vrig.service`) driven over a seeded ISO 8608 road at the scenario's speed; "
        "the road's seed is the record's desired-response seed. Unlike a pseudo-field record, a "
        "service record need not be reachable (the rig lacks the vehicle's boundary conditions "
        "and degrees of freedom), so these errors are ranked apart from the pseudo-field ones. "
        "`rig:scenario` is the rig on that scenario's records; the targets (as made for the "
        "lowest seed):",
        "",
    ]
    first: dict[str, dict] = {}
    for r in sorted(records, key=lambda r: r["key"]["desired"]):
        first.setdefault(_base_label(r), r)
    for label, r in sorted(first.items()):
        lines.append(f"* `{label}`: {r.get('target_source') or '(not recorded: failed before)'}")
    lines.append("")
    return lines + _ranking(records, "###")


def _methods_lines(records: list[dict]) -> list[str]:
    agg = aggregate(records)
    methods = sorted({m for _, m in agg})
    descs = {}
    for (_rig, m), a in agg.items():
        descs.setdefault(m, a["description"])
    linear = method_linearity(records)
    kind = {True: " (linear)", False: " (non-linear)", None: ""}
    lines = ["## Methods", ""]
    lines += [f"* **{m}**{kind[linear.get(m)]}: {descs.get(m) or '—'}" for m in methods]
    lines.append("")
    return lines


# ---------------------------------------------------------------------------------------------
# the severity axis
# ---------------------------------------------------------------------------------------------
def method_linearity(records: list[dict]) -> dict[str, bool | None]:
    """``{method: True (linear) | False (non-linear) | None (unclassified)}``: the
    ``method_linear`` field of its records (the registry's ``linear`` flag when the record
    was made), else the flag of the method registered in this process, else None."""
    from .registry import get_method

    out: dict[str, bool | None] = {}
    for r in records:
        m = r["key"]["method"]
        if r.get("method_linear") is not None:
            out[m] = bool(r["method_linear"])
        else:
            out.setdefault(m, None)
    for m, flag in out.items():
        if flag is None:
            try:
                out[m] = get_method(m).linear
            except KeyError:
                pass
    return out


def severity_tables(records: list[dict]) -> dict[str, dict]:
    """Per rig (``rig:scenario`` on a field target) with records at two or more severities
    (None, the rig as loaded, is not a point of the axis): ``{"severities": [s, ...], "methods": [m, ...], "cells": {(m, s):
    {"n", "ok", "eta0_it00", "eta0_best"}}}``; the η0 values [%] are means over the ok records
    (desired responses × seeds) of the mean over channels."""
    by_rig: dict[str, dict] = defaultdict(lambda: defaultdict(list))
    for r in records:
        sev = severity_of(r)
        if sev is not None:
            by_rig[_base_label(r)][(r["key"]["method"], sev)].append(r)
    out = {}
    for rig, groups in sorted(by_rig.items()):
        sevs = sorted({s for _m, s in groups})
        if len(sevs) < 2:
            continue
        cells = {}
        for key, recs in groups.items():
            ok = [r for r in recs if r["status"] == "ok"]
            cells[key] = {
                "n": len(recs),
                "ok": len(ok),
                "eta0_it00": _mean(r["eta0_it00"] for r in ok),
                "eta0_best": _mean(r["eta0_best"] for r in ok),
            }
        out[rig] = {
            "severities": sevs,
            "methods": sorted({m for m, _s in groups}),
            "cells": cells,
        }
    return out


def severity_crossover(
    it00: dict[str, dict[float, float | None]], linear: dict[str, bool | None]
) -> dict:
    """The lowest severity at which the best non-linear method beats the best linear one at
    IT00.

    ``it00[method][severity]`` is the method's mean IT00 η0 [%] at that severity, None where
    it failed (or has no record there); a failed method reaches nothing, so it is beaten by
    any method that ran. ``linear[method]`` is True/False/None (None: left out). "Beats" is a
    strictly lower η0. Returns ``{"severity": s or None, "reason": str, "nonlinear": (method,
    η0) or None, "linear": (method, η0) or None, "not_at": [higher severities where the
    non-linear method does not beat the linear one again]}``."""
    lin = [m for m in it00 if linear.get(m) is True]
    nonlin = [m for m in it00 if linear.get(m) is False]
    out = {"severity": None, "nonlinear": None, "linear": None, "not_at": []}
    if not lin or not nonlin:
        out["reason"] = (
            "no crossover: needs a linear and a non-linear method "
            f"(linear: {', '.join(lin) or 'none'}; non-linear: {', '.join(nonlin) or 'none'})"
        )
        return out

    def best(methods, s):
        vals = [(it00[m].get(s), m) for m in methods if it00[m].get(s) is not None]
        return min(vals) if vals else None

    sevs = sorted({s for m in it00 for s in it00[m]})
    beats = {}
    for s in sevs:
        b_nl, b_l = best(nonlin, s), best(lin, s)
        beats[s] = b_nl is not None and (b_l is None or b_nl[0] < b_l[0])
        if beats[s] and out["severity"] is None:
            out["severity"] = s
            out["nonlinear"] = (b_nl[1], b_nl[0])
            out["linear"] = None if b_l is None else (b_l[1], b_l[0])
    if out["severity"] is None:
        out["reason"] = (
            f"no crossover in the range {format_severity(sevs[0])}–{format_severity(sevs[-1])}: "
            f"the best non-linear method ({', '.join(nonlin)}) never beats the best linear one "
            f"({', '.join(lin)}) at IT00"
        )
        return out
    out["not_at"] = [s for s in sevs if s > out["severity"] and not beats[s]]
    (m_nl, v_nl), b_l = out["nonlinear"], out["linear"]
    versus = "every linear method failed" if b_l is None else f"{b_l[0]} {b_l[1]:.1f} %"
    out["reason"] = (
        f"crossover at severity {format_severity(out['severity'])}: {m_nl} {v_nl:.1f} % "
        f"beats {versus} (IT00 η0)"
        + (
            f"; not again at {', '.join(map(format_severity, out['not_at']))}"
            if out["not_at"]
            else ""
        )
    )
    return out


def _it00_by_method(table: dict) -> dict[str, dict[float, float | None]]:
    """``{method: {severity: IT00 η0 or None}}``: None where a record failed or is missing."""
    out = {}
    for m in table["methods"]:
        out[m] = {}
        for s in table["severities"]:
            c = table["cells"].get((m, s))
            ok = c is not None and c["ok"] == c["n"] and c["eta0_it00"] is not None
            out[m][s] = c["eta0_it00"] if ok else None
    return out


def _cell(c: dict | None, field: str) -> str:
    if c is None:
        return ""
    if c["ok"] == 0:
        return "fail"
    return _f(c[field]) + ("" if c["ok"] == c["n"] else f" ({c['ok']}/{c['n']})")


def severity_section(records: list[dict]) -> list[str]:
    """The leaderboard's "Severity" section (empty when no rig has two or more severities):
    per rig, method × severity tables of IT00 and best η0 and the crossover
    (:func:`severity_crossover`)."""
    tables = severity_tables(records)
    if not tables:
        return []
    linear = method_linearity(records)
    kind = {True: "linear", False: "non-linear", None: "unclassified"}
    lines = [
        "## Severity",
        "",
        "Each method's mean η0 [%] against the rig's non-linearity severity s [-] "
        "(`vrig.load_rig(rig, severity=s)`: 0 linearised, 1 as loaded, 2 twice as non-linear; "
        "the desired response is the pseudo-field response of the rig at that severity). "
        "Crossover: the lowest severity at which the best non-linear method beats the best "
        "linear one at IT00 (method classes from the registry's `linear` flag; a failed record "
        "counts as worse than any result). Plots: `plots/severity-<rig>.png`.",
        "",
    ]
    for rig, table in tables.items():
        sevs = table["severities"]
        head = "| method | class | " + " | ".join(f"s = {format_severity(s)}" for s in sevs)
        rule = "|---|---|" + "---:|" * len(sevs)
        lines += [f"### {rig}", ""]
        for field, what in (("eta0_it00", "IT00"), ("eta0_best", "best")):
            lines += [f"{what} η0 [%]:", "", head + " |", rule]
            for m in table["methods"]:
                cells = [_cell(table["cells"].get((m, s)), field) for s in sevs]
                lines.append(f"| {m} | {kind[linear.get(m)]} | " + " | ".join(cells) + " |")
            lines.append("")
        cross = severity_crossover(_it00_by_method(table), linear)
        lines += [f"**{cross['reason']}**", ""]
    return lines


def plot_severity(rig: str, table: dict, linear: dict, path: Path) -> Path:
    """Each method's IT00 (left) and best (right) mean η0 against severity; linear methods
    solid, non-linear dashed, unclassified dotted; a failed point is a red × at the top; the
    crossover (if any) a vertical line. Log y when the values span more than a decade."""
    from matplotlib.transforms import blended_transform_factory

    sevs = table["severities"]
    fig = _figure(10.0, 4.2)
    axes = fig.subplots(1, 2, sharey=True)
    values = [
        c[f]
        for c in table["cells"].values()
        for f in ("eta0_it00", "eta0_best")
        if c["ok"] and c[f] is not None and c[f] > 0
    ]
    log = bool(values) and max(values) / min(values) > 10
    style = {True: ("-", "o", "linear"), False: ("--", "s", "non-linear"), None: (":", "^", "")}
    cross = severity_crossover(_it00_by_method(table), linear)
    for ax, field, what in zip(
        axes, ("eta0_it00", "eta0_best"), ("IT00", "best iteration"), strict=True
    ):
        top = blended_transform_factory(ax.transData, ax.transAxes)
        for i, m in enumerate(table["methods"]):
            ls, marker, cls = style[linear.get(m)]
            xs, ys, failed = [], [], []
            for s in sevs:
                c = table["cells"].get((m, s))
                if c is None:
                    continue
                if c["ok"] < c["n"] or c[field] is None:
                    failed.append(s)
                if c["ok"] and c[field] is not None:
                    xs.append(s)
                    ys.append(c[field])
            label = f"{m} ({cls})" if cls else m
            ax.plot(xs, ys, linestyle=ls, marker=marker, color=f"C{i % 10}", label=label)
            if failed:
                ax.plot(
                    failed, [0.96] * len(failed), "x", color="tab:red", ms=9, mew=2,
                    transform=top, label=f"{m}: failed record(s)",
                )  # fmt: skip
        if cross["severity"] is not None:
            ax.axvline(cross["severity"], color="0.4", linestyle="-.", linewidth=1)
            ax.text(cross["severity"], 0.02, " crossover", transform=top, color="0.3", fontsize=8)
        if log:
            ax.set_yscale("log")
            _plain_log_ticks(ax.yaxis)
        ax.set_xticks(sevs, [format_severity(s) for s in sevs])
        ax.set_xlabel("severity [-]")
        ax.set_title(f"{what}")
        ax.grid(alpha=0.3, which="both")
    axes[0].set_ylabel("mean η0 [%]")
    axes[1].legend(fontsize=8)
    fig.suptitle(f"{rig}: reconstruction error against non-linearity severity", fontsize=11)
    fig.tight_layout()
    return _save(fig, path)


def _csv_row(r: dict) -> dict:
    row = {**r["key"], "id": r["id"], "status": r["status"], "target": target_of(r)}
    for k in _CSV_FIELDS:
        if k in r and k not in row:
            v = r[k]
            row[k] = (
                ";".join(f"{x:.6g}" if x is not None else "" for x in v)
                if isinstance(v, list)
                else v
            )
    for k in ("fit_s", "model_sim_s", "reconstruction_s", "record_s"):
        row[k] = r["timing"].get(k)
    if r.get("error"):
        row["error_stage"] = r["error"]["stage"]
        row["error_type"] = r["error"]["type"]
        row["error_message"] = r["error"]["message"]
    return row


def _records_csv(records: list[dict]) -> str:
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=_CSV_FIELDS, extrasaction="ignore")
    w.writeheader()
    for r in records:
        w.writerow(_csv_row(r))
    return buf.getvalue()


def _plain_log_ticks(axis) -> None:
    """20, 50, 100 on a log axis of η0 rather than matplotlib's "2 × 10^1"."""
    from vrig.plots import plain_log_ticks

    plain_log_ticks(axis)


def _figure(w=7.0, h=4.0):
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(w, h))
    FigureCanvasAgg(fig)
    return fig


def _save(fig, path: Path) -> Path:
    """Write ``fig`` as PNG to ``path`` atomically (a killed run leaves no half image)."""
    from vrig.files import atomic_write

    with atomic_write(path, "wb") as fh:
        fig.savefig(fh, format="png", dpi=100)
    return path


def plot_bars(rig: str, agg: dict, path: Path) -> Path:
    methods = sorted(m for r, m in agg if r == rig)
    fig = _figure(max(5.0, 1.1 * len(methods) + 2), 4.0)
    ax = fig.add_subplot()
    x = np.arange(len(methods))
    it00 = [agg[(rig, m)]["eta0_it00"] for m in methods]
    best = [agg[(rig, m)]["eta0_best"] for m in methods]
    ax.bar(x - 0.2, [v or 0 for v in it00], 0.4, label="IT00", color="tab:gray")
    ax.bar(x + 0.2, [v or 0 for v in best], 0.4, label="best iteration", color="tab:blue")
    top = max([v for v in it00 + best if v is not None] or [1.0])
    for i, m in enumerate(methods):
        a = agg[(rig, m)]
        if a["ok"] < a["n"]:
            ax.text(
                i,
                0.02 * top,
                "failed" if a["ok"] == 0 else f"{a['ok']}/{a['n']} ok",
                ha="center",
                va="bottom",
                color="tab:red",
                rotation=90,
            )
    ax.set_xticks(x, methods)
    ax.set_ylabel("mean η0 [%]")
    ax.set_title(f"{rig}: reconstruction error per method")
    ax.legend()
    ax.grid(axis="y", alpha=0.3)
    fig.tight_layout()
    return _save(fig, path)


def plot_iterations(method: str, records: list[dict], path: Path) -> Path:
    from matplotlib.ticker import MaxNLocator

    fig = _figure()
    ax = fig.add_subplot()
    rigs = sorted({rig_label(r) for r in records})
    colors = {rig: f"C{i % 10}" for i, rig in enumerate(rigs)}
    labelled = set()
    for r in sorted(records, key=lambda r: r["id"]):
        ys = [y for y in (r.get("eta0_per_iteration") or []) if y is not None]
        if r["status"] != "ok" or not ys:
            continue
        rig = rig_label(r)
        ax.semilogy(
            range(len(ys)),
            ys,
            "o-",
            color=colors[rig],
            label=None if rig in labelled else rig,
            alpha=0.8,
        )
        labelled.add(rig)
    failed = sorted({rig_label(r) for r in records if r["status"] != "ok"})
    title = f"{method}: error versus iteration"
    if failed:
        title += f"\n(failed on: {', '.join(failed)})"
    ax.set_title(title, fontsize=10)
    ax.set_xlabel("iteration")
    ax.xaxis.set_major_locator(MaxNLocator(integer=True))
    ax.set_ylabel("mean η0 [%]")
    if labelled:
        _plain_log_ticks(ax.yaxis)
    ax.grid(alpha=0.3, which="both")
    if labelled:
        ax.legend(fontsize=8)
    fig.tight_layout()
    return _save(fig, path)


# ---------------------------------------------------------------------------------------------
# the policy leaderboard (benchmarks/learned_iteration.py)
# ---------------------------------------------------------------------------------------------
POLICIES_HOWTO = "python -m benchmarks.learned_iteration"


def policies_section(path) -> list[str]:
    """The "## Policies" section: a policy × rig table of the learned-iteration benchmark.

    Each cell is ``mean iterations to tolerance / mean final η0 % / trips`` over the held-out
    targets (an episode that never met the tolerance counts as budget + 1), read from the
    ``policies`` list of ``path`` (``results/learned_iteration.json``, written by
    ``python -m benchmarks.learned_iteration``). Rows in the order of the file; a policy not
    scored on a rig has an empty cell. A missing file gives one line saying how to make it; a
    file without a readable ``policies`` list raises ``ValueError`` naming it.

    Parameters
    ----------
    path : str or Path
        The learned-iteration results (JSON).
    """
    path = Path(path)
    if not path.exists():
        return [f"Policy leaderboard: no {path} (make it with `{POLICIES_HOWTO}`).", ""]
    try:
        doc = json.loads(path.read_text(encoding="utf-8"))
        recs = doc["policies"]
        cells = {
            (r["policy"], r["rig"]): (
                float(r["mean_iterations"]), float(r["mean_final_eta0"]), int(r["trips"]),
                int(r["held_out"]),
            )
            for r in recs
        }  # fmt: skip
    except (ValueError, KeyError, TypeError) as exc:
        raise ValueError(
            f"{path}: not learned-iteration results with a 'policies' list ({exc!r}); "
            f"remake it with `{POLICIES_HOWTO}`"
        ) from None
    policies = list(dict.fromkeys(p for p, _ in cells))
    rigs = list(dict.fromkeys(r for _, r in cells))
    tolerance = {  # the η0 tolerance each rig was scored at, when the file says
        r.get("rig"): r.get("tolerance_percent") for r in doc.get("rigs", []) if isinstance(r, dict)
    }
    n = sorted({c[3] for c in cells.values()})
    lines = [
        "## Policies",
        "",
        f"Drive-iteration policies on held-out desired responses ({'/'.join(map(str, n))} per "
        f"rig; `{path}`, made by `{POLICIES_HOWTO}`). Cell: mean iterations to tolerance "
        "(never met = budget + 1) / mean final η0 % / trips; lower is better.",
        "",
        "| policy | "
        + " | ".join(
            rig if tolerance.get(rig) is None else f"{rig} (η0 ≤ {tolerance[rig]:g} %)"
            for rig in rigs
        )
        + " |",
        "|---|" + "---:|" * len(rigs),
    ]
    for p in policies:
        row = []
        for rig in rigs:
            c = cells.get((p, rig))
            row.append("" if c is None else f"{c[0]:.2f} / {c[1]:.2f} / {c[2]}")
        lines.append(f"| {p} | " + " | ".join(row) + " |")
    lines.append("")
    return lines


def write_outputs(
    out: Path, records: list[dict], settings: dict | None, *, plots=True, policies=None
) -> list[Path]:
    """Write records.json, records.csv, leaderboard.md and the plots into ``out``; with
    ``policies`` (the path of ``results/learned_iteration.json``) the leaderboard ends with
    :func:`policies_section`."""
    out = Path(out)
    records = sorted(records, key=lambda r: r["id"])
    written = []
    board = leaderboard(records, settings)
    if policies is not None:
        board = board.rstrip("\n") + "\n\n" + "\n".join(policies_section(policies)) + "\n"
    for name, text in (
        ("records.json", json.dumps(records, indent=1, ensure_ascii=False) + "\n"),
        ("records.csv", _records_csv(records)),
        ("leaderboard.md", board),
    ):
        write_atomic(out / name, text)
        written.append(out / name)
    if plots and records:
        pdir = out / "plots"
        pdir.mkdir(exist_ok=True)
        agg = aggregate(records)
        for rig in sorted({r for r, _ in agg}):
            written.append(plot_bars(rig, agg, pdir / f"bars_{_file_label(rig)}.png"))
        by_method = defaultdict(list)
        for r in records:
            by_method[r["key"]["method"]].append(r)
        for m, recs in sorted(by_method.items()):
            written.append(plot_iterations(m, recs, pdir / f"error_vs_iteration_{m}.png"))
        linear = method_linearity(records)
        for rig, table in severity_tables(records).items():
            path = pdir / f"severity-{_file_label(rig)}.png"
            written.append(plot_severity(rig, table, linear, path))
    return written
