"""Outputs of a run: every record as JSON and CSV, the Markdown leaderboard and the plots.

* ``records.json`` — the list of records (sorted by id), exactly as in ``records/``;
* ``records.csv`` — one row per record, scalar fields (per-iteration η0 as ``a;b;c``);
* ``leaderboard.md`` — the overall ranking and one table per rig (see :func:`leaderboard`);
* ``plots/bars_<rig>.png`` — mean η0 at IT00 and at the best iteration per method;
* ``plots/error_vs_iteration_<method>.png`` — mean η0 versus iteration, one line per record.

Figures use matplotlib's Agg canvas directly (no global backend switch).
"""

from __future__ import annotations

import csv
import io
import json
from collections import defaultdict
from pathlib import Path

import numpy as np

from .execute import write_atomic

__all__ = ["aggregate", "leaderboard", "write_outputs"]

FAILED_SCORE = 100.0  # η0 [%] a failed record counts as in the overall ranking

_CSV_FIELDS = [
    "id",
    "rig",
    "method",
    "desired",
    "seed",
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


def aggregate(records: list[dict]) -> dict:
    """Per (rig, method): counts and means over the records (desired responses × seeds)."""
    groups: dict[tuple[str, str], list[dict]] = defaultdict(list)
    for r in records:
        groups[(r["key"]["rig"], r["key"]["method"])].append(r)
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
            "normal_model_error": _mean(r.get("normal_model_error") for r in recs),
            "inverse_model_error": _mean(r.get("inverse_model_error") for r in recs),
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


def _short(msg: str, n: int = 110) -> str:
    msg = " ".join(str(msg).split())
    return msg if len(msg) <= n else msg[: n - 1] + "…"


def _f(x, fmt="{:.1f}") -> str:
    return "—" if x is None else fmt.format(x)


def leaderboard(records: list[dict], settings: dict | None = None, *, title: str = "") -> str:
    """The Markdown leaderboard of ``records``.

    Overall ranking: mean over all of a method's records of the best mean η0, a failed record
    counting as 100 %; then one table per rig ranked by the mean best η0 (methods with failed
    records after those without), and the failure reasons."""
    agg = aggregate(records)
    rigs = sorted({rig for rig, _ in agg})
    methods = sorted({m for _, m in agg})
    lines = [f"# {title or 'vrig reconstruction benchmark: leaderboard'}", ""]
    if settings:
        s = settings
        lines += [
            f"{len(records)} records ({sum(r['status'] == 'ok' for r in records)} ok). "
            f"Desired responses: pseudo-field records of {s['seconds']:g} s (vrig.field); "
            f"{s['iterations']} iterations after IT00 at gain {s['gain']:g}; rig fidelity "
            f"`{s['fidelity']}`; tolerance {s['tolerance']:g} % mean η0; modelling errors on "
            f"the last {100 * s['holdout']:.0f} % of the identification records. η0 is the "
            "DC-corrected QanTiM fit value (eq. 5-28), mean over response channels, lower is "
            "better; values are means over desired responses × seeds.",
            "",
        ]
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

    lines += [
        "## Overall",
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
    for rig in rigs:
        lines += [
            f"## {rig}",
            "",
            "| rank | method | ok | IT00 η0 % | final η0 % | best η0 % | its to tol | RMS err % "
            "| damage ratio | normal model err % | inverse model err % | fit s | model size |",
            "|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|",
        ]
        for rank, (m, a) in enumerate(per_rig_rows[rig], 1):
            tol = (
                "—"
                if a["reached"] == 0
                else f"{a['iterations_to_tolerance']:.1f}"
                + ("" if a["reached"] == a["ok"] else f" ({a['reached']}/{a['ok']})")
            )
            lines.append(
                f"| {rank} | {m} | {a['ok']}/{a['n']} | {_f(a['eta0_it00'])} | "
                f"{_f(a['eta0_final'])} | {_f(a['eta0_best'])} | {tol} | {_f(a['rms_error'])} | "
                f"{_f(a['damage_ratio'], '{:.2f}')} | {_f(a['normal_model_error'])} | "
                f"{_f(a['inverse_model_error'])} | {_f(a['fit_s'], '{:.2f}')} | "
                f"{_f(a['model_size'], '{:.0f}')} |"
            )
        fails = [(m, f) for m, a in per_rig_rows[rig] for f in a["failures"]]
        if fails:
            lines += ["", "Failures:", ""]
            lines += [f"* {m}: {f}" for m, f in fails]
        lines.append("")
    descs = {}
    for (_rig, m), a in agg.items():
        descs.setdefault(m, a["description"])
    lines += ["## Methods", ""]
    lines += [f"* **{m}**: {descs.get(m) or '—'}" for m in methods]
    lines.append("")
    return "\n".join(lines)


def _csv_row(r: dict) -> dict:
    row = {**r["key"], "id": r["id"], "status": r["status"]}
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


def _figure(w=7.0, h=4.0):
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(w, h))
    FigureCanvasAgg(fig)
    return fig


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
    fig.savefig(path, dpi=100)
    return path


def plot_iterations(method: str, records: list[dict], path: Path) -> Path:
    from matplotlib.ticker import MaxNLocator

    fig = _figure()
    ax = fig.add_subplot()
    rigs = sorted({r["key"]["rig"] for r in records})
    colors = {rig: f"C{i % 10}" for i, rig in enumerate(rigs)}
    labelled = set()
    for r in sorted(records, key=lambda r: r["id"]):
        ys = [y for y in (r.get("eta0_per_iteration") or []) if y is not None]
        if r["status"] != "ok" or not ys:
            continue
        rig = r["key"]["rig"]
        ax.semilogy(
            range(len(ys)),
            ys,
            "o-",
            color=colors[rig],
            label=None if rig in labelled else rig,
            alpha=0.8,
        )
        labelled.add(rig)
    failed = sorted({r["key"]["rig"] for r in records if r["status"] != "ok"})
    title = f"{method}: error versus iteration"
    if failed:
        title += f"\n(failed on: {', '.join(failed)})"
    ax.set_title(title, fontsize=10)
    ax.set_xlabel("iteration")
    ax.xaxis.set_major_locator(MaxNLocator(integer=True))
    ax.set_ylabel("mean η0 [%]")
    ax.grid(alpha=0.3, which="both")
    if labelled:
        ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    return path


def write_outputs(
    out: Path, records: list[dict], settings: dict | None, *, plots=True
) -> list[Path]:
    """Write records.json, records.csv, leaderboard.md and the plots into ``out``."""
    out = Path(out)
    records = sorted(records, key=lambda r: r["id"])
    written = []
    for name, text in (
        ("records.json", json.dumps(records, indent=1, ensure_ascii=False) + "\n"),
        ("records.csv", _records_csv(records)),
        ("leaderboard.md", leaderboard(records, settings)),
    ):
        write_atomic(out / name, text)
        written.append(out / name)
    if plots and records:
        pdir = out / "plots"
        pdir.mkdir(exist_ok=True)
        agg = aggregate(records)
        for rig in sorted({r for r, _ in agg}):
            written.append(plot_bars(rig, agg, pdir / f"bars_{rig}.png"))
        by_method = defaultdict(list)
        for r in records:
            by_method[r["key"]["method"]].append(r)
        for m, recs in sorted(by_method.items()):
            written.append(plot_iterations(m, recs, pdir / f"error_vs_iteration_{m}.png"))
    return written
