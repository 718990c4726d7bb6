"""The printed table, the per-record and overall goal lines, and the JSON results."""

from __future__ import annotations

from dataclasses import asdict

import numpy as np

from .protocol import DIVERGED, GOAL_VS_FROLS, GOAL_VS_LINEAR, RecordResult
from .records import Skipped

HEAD = (
    "record",
    "N train/test",
    "model",
    "terms",
    "test NRMSE",
    "record metric",
    "fit s",
    "NS/FROLS",
    "NS/linear",
)
GOAL_TEXT = (
    f"NarxSearch <= {GOAL_VS_FROLS:g}x FROLS, never diverging, never worse than the best linear "
    "model"
)


def _num(v: float | None) -> str:
    if v is None:
        return "—"
    if not np.isfinite(v):
        return DIVERGED
    return f"{v:.4g}"


def _ratio(v: float) -> str:
    return DIVERGED if not np.isfinite(v) else f"{v:.3g}x"


def _cells(r: RecordResult) -> list[tuple]:
    out = []
    for i, row in enumerate(r.rows):
        v = "failed" if row.status.startswith("failed") else _num(row.nrmse)
        metric = "—" if row.metric is None else f"{_num(row.metric)} ({r.metric_label})"
        first = i == 0
        out.append(
            (
                r.name if first else "",
                f"{r.n_train}/{r.n_test}" if first else "",
                row.model,
                "—" if row.terms is None else str(row.terms),
                v,
                metric,
                f"{row.fit_s:.1f}",
                _ratio(r.ratio_frols) if first else "",
                _ratio(r.ratio_linear) if first else "",
            )
        )
    return out


def _table(results: list[RecordResult]) -> list[str]:
    body = [c for r in results for c in _cells(r)]
    widths = [max(len(str(x[i])) for x in [HEAD, *body]) for i in range(len(HEAD))]

    def line(cells):
        return "  ".join(str(c).ljust(w) for c, w in zip(cells, widths, strict=True)).rstrip()

    return [line(HEAD), line(["-" * w for w in widths]), *map(line, body)]


def _verdict(r: RecordResult) -> str:
    g = r.goal
    yes = {True: "yes", False: "NO"}
    return (
        f"goal {r.name}: NarxSearch <= {GOAL_VS_FROLS:g}x FROLS ({_ratio(r.ratio_frols)}: "
        f"{yes[g['vs_frols']]}), never diverging ({yes[g['never_diverged']]}), never worse than "
        f"the best linear model ({_ratio(r.ratio_linear)} <= {GOAL_VS_LINEAR:g}x: "
        f"{yes[g['vs_linear']]}) - {'reached' if g['reached'] else 'NOT reached'}"
    )


def _row_text(row) -> str:
    return "; ".join(x for x in (row.status if row.status != "ok" else "", row.note) if x)


def _details(r: RecordResult) -> list[str]:
    s, search = r.search, r.rows[0]
    used = s.get("search_time_s")
    used = "—" if used is None else f"{used:.1f} s"
    lines = [
        f"{r.name}: {r.split}",
        f"  source: {r.source}",
        f"  NarxSearch: budget {s['budget_s']:g} s, used {used}; {_row_text(search)}; "
        f"refit: {s.get('refit')}; grid: {s['grid']}",
    ]
    lines += [f"  {row.family}: {_row_text(row)}" for row in r.rows[1:] if _row_text(row)]
    return [*lines, "  " + _verdict(r)]


def overall(results: list[RecordResult]) -> dict:
    """How many records reach the goal, and which do not."""
    missed = [r.name for r in results if not r.goal["reached"]]
    return {"records": len(results), "reached": len(results) - len(missed), "not_reached": missed}


def format_report(results: list[RecordResult], skipped: list[Skipped]) -> str:
    """The table, then per record its split, the NarxSearch details and the goal line, the
    skipped records and the overall line."""
    lines = _table(results) if results else ["(no record was run)"]
    lines.append("")
    for r in results:
        lines += _details(r)
    lines += [f"{s.name}: skipped - {s.reason}" for s in skipped]
    o = overall(results)
    tail = f"; not reached: {', '.join(o['not_reached'])}" if o["not_reached"] else ""
    lines.append(
        f"overall: goal ({GOAL_TEXT}) reached on {o['reached']} of {o['records']} records{tail}"
    )
    return "\n".join(lines)


def _finite(x):
    """JSON-safe: ``inf``/``nan`` become None (the row's status says DIVERGED)."""
    if isinstance(x, float) and not np.isfinite(x):
        return None
    if isinstance(x, dict):
        return {k: _finite(v) for k, v in x.items()}
    if isinstance(x, list):
        return [_finite(v) for v in x]
    return x


def results_json(results: list[RecordResult], skipped: list[Skipped], meta: dict) -> dict:
    """Everything printed, as a JSON-ready dict (``inf`` as None)."""
    return _finite(
        {
            **meta,
            "goal": GOAL_TEXT,
            "records": [asdict(r) for r in results],
            "skipped": [asdict(s) for s in skipped],
            "overall": overall(results),
        }
    )
