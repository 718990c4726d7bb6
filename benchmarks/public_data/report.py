"""Result rows of the public-data benchmark and the printed table."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


@dataclass
class Row:
    dataset: str
    test: str
    split: str
    metric: str
    model: str = ""
    terms: int | None = None
    vrig: float | None = None
    published: float | None = None
    published_terms: int | None = None
    sysidentpy: float | None = None
    sysidentpy_terms: int | None = None
    fit_s: float | None = None
    sysidentpy_fit_s: float | None = None
    note: str = ""
    status: str = ""  # "skipped: ..." when the data set was not run


@dataclass
class Report:
    rows: list[Row] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)
    sysidentpy_version: str | None = None


def _skipped(dataset: str, test: str, metric: str, folder: str, name: str) -> Row:
    return Row(dataset, test, "", metric, status=f"skipped: {folder}/{name} not found")


def _fmt(v, digits=5) -> str:
    if v is None:
        return "—"
    if not np.isfinite(v):
        return "diverged"
    return f"{v:.{digits}g}" if abs(v) < 1 else f"{v:.{digits - 1}f}"


def format_table(report: Report, sip_version: str | None) -> str:
    head = (
        "dataset",
        "test",
        "metric",
        "vrig model",
        "terms",
        "vrig",
        "published (terms)",
        f"SysIdentPy {sip_version} in-process (terms)" if sip_version else "SysIdentPy (terms)",
        "fit s (vrig / SIP)",
    )
    lines = []
    body = []
    for r in report.rows:
        if r.status:
            body.append((r.dataset, r.test, r.metric, r.status, "", "", "", "", ""))
            continue
        pub = "—" if r.published is None else _fmt(r.published)
        if r.published is not None and r.published_terms:
            pub += f" ({r.published_terms})"
        sipv = "—" if r.sysidentpy is None else _fmt(r.sysidentpy)
        if r.sysidentpy is not None and r.sysidentpy_terms:
            sipv += f" ({r.sysidentpy_terms})"
        fits = "—" if r.fit_s is None else f"{r.fit_s:.2f}"
        if r.sysidentpy_fit_s is not None:
            fits += f" / {r.sysidentpy_fit_s:.2f}"
        body.append(
            (r.dataset, r.test, r.metric, r.model, str(r.terms), _fmt(r.vrig), pub, sipv, fits)
        )
    widths = [max(len(str(x[i])) for x in [head, *body]) for i in range(len(head))]
    lines.append("  ".join(str(h).ljust(w) for h, w in zip(head, widths, strict=True)))
    lines.append("  ".join("-" * w for w in widths))
    lines += ["  ".join(str(c).ljust(w) for c, w in zip(b, widths, strict=True)) for b in body]
    lines.append("")
    lines.append("splits (sample ranges of each record) and notes:")
    seen = set()
    for r in report.rows:
        if r.status:
            continue
        key = (r.dataset, r.test)
        if key in seen:
            continue
        seen.add(key)
        split = r.split if r.split != "same" else "(as above)"
        lines.append(f"  {r.dataset} / {r.test}: {split}")
    for r in report.rows:
        if r.note and not r.status:
            lines.append(f"  note {r.dataset} / {r.test} / {r.model}: {r.note}")
    lines += [f"  {n}" for n in report.notes]
    return "\n".join(lines)
