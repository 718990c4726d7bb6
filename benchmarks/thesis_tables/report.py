"""The thesis report: every table run per requested variant and target, rendered, written, and
the command line ``python -m benchmarks.thesis_tables``."""

from __future__ import annotations

import argparse
import time
from pathlib import Path

from benchmarks.thesis_tables import render, run
from benchmarks.thesis_tables.data import NORMAL_TABLES, TABLES
from benchmarks.thesis_tables.render import _setting_text
from benchmarks.thesis_tables.run import TableRun, _setting, resolve_variant
from vrig.files import atomic_write

__all__ = ["main", "normal_report", "report_name", "thesis_report", "time_summary"]


def normal_report(requested, severity, *, seconds: float, log=print, times=None) -> list:
    """Run the normal tables (each per requested variant and drive level): markdown parts.
    ``times`` (a list, optional) gets ``(table name, wall time [s])`` per table."""
    parts = []
    for table in NORMAL_TABLES:
        t0 = time.perf_counter()
        done, runs = {}, []
        for req in requested:
            setting = _setting(table.rig, req, severity)
            for level in table.levels:
                if (setting, level) not in done:
                    log(f"{table.name} [{_setting_text(setting, req)}, {level:.0%} FS]")
                    done[(setting, level)] = run.run_normal_table(
                        table, seconds=seconds, level=level, variant=setting[0],
                        severity=setting[1], log=log,
                    )  # fmt: skip
                values, notes, rms_text = done[(setting, level)]
                runs.append((f"{req or setting[0]}, {level:.0%} FS", _setting_text(setting, req),
                             values, notes, rms_text))  # fmt: skip
        wall = time.perf_counter() - t0
        parts.append(render._markdown_normal(table, runs) + f"_wall time {wall:.0f} s_\n")
        if times is not None:
            times.append((table.name.split(":")[0], wall))
    return parts


def report_name(variants=None, severity: float | None = None) -> str:
    """The report's file name: ``thesis_reproduction.md`` on the rigs' defaults, else tagged
    with the variants and severity it ran on (so a variant run never overwrites the default's)."""
    tag = "".join(f"_{v}" for v in variants or ())
    if severity is not None:
        tag += f"_s{severity:g}"
    return f"thesis_reproduction{tag}.md"


def _check_variants(variants) -> list:
    """``variants`` as a list (``[None]``: each rig's default); a name no rig has is an error."""
    if not variants:
        return [None]
    from vrig.rigs import list_rigs, rig_path
    from vrig.rigs.spec import read_description

    known = set()
    for name in list_rigs():
        known |= set(read_description(rig_path(name)).variants)
    bad = [v for v in variants if v not in known]
    if bad:
        raise ValueError(f"unknown variant(s) {bad}: the rigs have {sorted(known)}")
    if len(set(variants)) != len(variants):
        raise ValueError(f"variant named twice in {list(variants)}")
    return list(variants)


def _table_runs(table, requested, severity, seconds, id_seconds, cache, log, quick=False) -> list:
    """The table run once per requested variant and per target: the text's kind of target
    first, then the pseudo-field record beside it (once, where the text's kind is pseudo-field);
    a list of :class:`TableRun` for :func:`_markdown`."""
    done: dict = {}  # (setting, target) -> values: a variant the rig lacks runs its default once
    runs = []
    for req in requested:
        setting = _setting(table.rig, req, severity)
        for target in dict.fromkeys([table.target, "pseudo-field"]):
            if (setting, target) not in done:
                log(f"{table.name} [{_setting_text(setting, req)}, {target}]")
                done[setting, target] = run.run_table(
                    table, seconds=seconds, id_seconds=id_seconds, cache=cache,
                    variant=setting[0], severity=setting[1], target=target, quick=quick, log=log,
                )  # fmt: skip
            name = f"{req or setting[0]}, {target}"
            text = f"{_setting_text(setting, req)} with a {target} desired response"
            variant = setting[0] if target == "pseudo-field" else f"{setting[0]} on {target}"
            runs.append(TableRun(name, text, done[setting, target], variant, target))
    return runs


def thesis_report(
    out_dir: Path | str,
    quick: bool = False,
    log=print,
    *,
    variants=None,
    severity: float | None = None,
    times: list | None = None,
) -> str:
    """Run every table, write the report into ``out_dir`` (:func:`report_name`) and return it.

    ``variants``: names, each table run once per name on the rig's variant of that name where
    it has one, else its default (``None``: once, on each rig's default variant).
    ``severity``: in [0, 2], for the rigs with a severity axis (``None``: as loaded).
    ``times`` (a list, optional) gets ``(table, wall time [s])`` per table (Table 3.7 and the
    Belgian road example once per variant), in the order they ran; the report's last line
    gives the same per table and the total."""
    requested = _check_variants(variants)
    if severity is not None and not (0.0 <= float(severity) <= 2.0):
        raise ValueError(f"severity must lie in [0, 2], got {severity!r}")
    seconds, id_seconds = (20.0, 30.0) if quick else (30.0, 60.0)
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    flags = " --quick" if quick else ""
    if variants:
        flags += " --variant " + " ".join(variants)
    if severity is not None:
        flags += f" --severity {severity:g}"
    parts = [
        "# Reference-text tables reproduced on the virtual rigs",
        "",
        f"desired responses of {seconds:g} s — each table on the text's own kind of target "
        "(a service record of the rig's field twin, `vrig.service`, where the text's came from "
        "a field measurement; Table 6.16 a pseudo-field record as the text's) and on a "
        "pseudo-field record beside it — identification records of "
        f"{id_seconds:g} s, seed 0; η0 (eq. 5-28) in %. Generated by "
        f"`python -m benchmarks.thesis_tables{flags}`. Role: CALIBRATED ON = the row the "
        "rig's `thesis` variant was calibrated on (benchmarks/calibrate.py CALIBRATIONS; it "
        "only says something on that variant); predicted = never tuned.",
        "",
    ]
    cache: dict = {}
    table_runs, runs_3_7, times = [], [], [] if times is None else times
    for table in TABLES:
        t = time.perf_counter()
        runs = _table_runs(table, requested, severity, seconds, id_seconds, cache, log, quick)
        times.append((table.name.split(":")[0], time.perf_counter() - t))
        table_runs.append((table, runs))
        parts.append(render._markdown(table, runs))
    parts += normal_report(requested, severity, seconds=id_seconds, log=log, times=times)
    settings_7 = {}
    for req in requested:
        settings_7.setdefault(resolve_variant("fuel-tank-7ch", req), req)
    for variant, req in settings_7.items():
        text = _setting_text((variant, None), req)
        log(f"Table 3.7: seven-channel fuel tank [{text}]")
        t = time.perf_counter()
        names, out = run.table_3_7(seconds=id_seconds, variant=variant, log=log)
        runs_3_7.append((variant, names, out))
        parts.append(render._markdown_3_7(names, out, text))
        log(f"Belgian road on the seven-channel fuel tank [{text}]")
        t1 = time.perf_counter()
        parts.append(run.belgian_road_example(seconds=seconds, variant=variant, log=log))
        times += [("Table 3.7", t1 - t), ("Belgian road", time.perf_counter() - t1)]
    parts.append(render.closing_table(table_runs, runs_3_7))
    per_table = ", ".join(f"{name} {sec:.0f} s" for name, sec in times)
    parts.append(f"_wall time per table: {per_table}; total {time.perf_counter() - t0:.0f} s_\n")
    text = "\n".join(parts)
    with atomic_write(out_dir / report_name(variants, severity), "w", encoding="utf-8") as f:
        f.write(text)
    return text


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(
        prog="python -m benchmarks.thesis_tables", description=_package_doc().split("\n")[0]
    )
    ap.add_argument(
        "--quick",
        action="store_true",
        help="shorter records (desired 20 s, identification 30 s instead of 30 s and 60 s), "
        "without the vrig-only rows of the full report (Table 6.16's two SEMP rows)",
    )
    ap.add_argument(
        "--out", default="results/thesis", help="output folder (default results/thesis)"
    )
    ap.add_argument(
        "--variant",
        nargs="+",
        metavar="NAME",
        help="run each table on the rig's variant NAME where it has one, else on its default "
        "(default: each rig's default variant); several names: side by side",
    )
    ap.add_argument(
        "--severity",
        type=float,
        metavar="S",
        help="non-linearity severity in [0, 2] of the rigs with a severity axis "
        "(default: as loaded); the linear rigs run as loaded",
    )
    args = ap.parse_args(argv)
    t0, times = time.perf_counter(), []
    try:
        text = thesis_report(
            args.out, quick=args.quick, variants=args.variant, severity=args.severity, times=times
        )
    except ValueError as exc:
        ap.error(str(exc))
    print(text)
    for line in time_summary(times, time.perf_counter() - t0):
        print(line)
    return 0


def time_summary(times, wall_s: float) -> list[str]:
    """The end-of-run lines of ``python -m benchmarks.thesis_tables``: each table's wall time
    and share of the run, the slowest first, then the run's total wall time.

    Parameters
    ----------
    times : list of (str, float)
        ``(table, wall time [s])`` as :func:`thesis_report` fills them.
    wall_s : float
        The whole run's wall time [s].

    Returns
    -------
    list of str
    """
    lines = ["", "wall time per table (slowest first):"]
    for name, sec in sorted(times, key=lambda t: -t[1]):
        lines.append(f"  {sec:7.1f} s {100 * sec / max(wall_s, 1e-12):5.1f} %  {name}")
    lines.append(f"wall time {wall_s:.0f} s ({wall_s / 60:.1f} min), the whole run")
    return lines


def _package_doc() -> str:
    """The package's documentation (its first line is the command's description)."""
    import benchmarks.thesis_tables

    return benchmarks.thesis_tables.__doc__
