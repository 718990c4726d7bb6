"""``python -m benchmarks`` (= ``vrig bench``): the reconstruction benchmark runner.

::

    python -m benchmarks run --quick [--thesis]            # ends with its slowest records, wall time
    python -m benchmarks run [--rigs R ...] [--methods M ...] [--desired D ...] [--seeds S ...]
                             [--severity S ...] [--targets T ...] [--out DIR]
                             [--backend process|serial|ray] [--workers N]
                             [--address RAY_ADDRESS] [--plugin MODULE_OR_FILE.py ...]
                             [--no-thesis]
    python -m benchmarks report --out DIR                  # rebuild leaderboard/plots
    python -m benchmarks list                              # rigs and registered methods

Exit status: 0 done (failed *records* are results, not errors), 1 the thesis report failed,
2 bad arguments, a plugin that does not load, a results folder that cannot be written or was made
with other settings, 3 an unexpected error (``VRIG_DEBUG=1`` shows the traceback), 130
interrupted (Ctrl-C, SIGTERM). Every error is one line on stderr.
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import os
import signal
import sys
import threading
import time
from dataclasses import asdict, replace
from pathlib import Path

from ..threads import one_blas_thread
from .execute import BACKENDS, SettingsMismatchError, Store, execute, write_atomic
from .lifetime import LockHeldError, PidLock, die_with_parent
from .record import (
    PSEUDO_FIELD,
    SEVERITY_RANGE,
    RecordKey,
    Settings,
    check_severity,
    format_severity,
)
from .registry import (
    PluginError,
    default_plugin_specs,
    get_method,
    load_plugins,
    method_names,
    plugin_spec,
)
from .report import write_outputs

POLICIES = Path("results/learned_iteration.json")
_POLICIES_HELP = (
    "learned-iteration results for the leaderboard's Policies section (default "
    "results/learned_iteration.json; python -m benchmarks.learned_iteration makes it)"
)

__all__ = ["FULL", "QUICK", "main"]

FULL = Settings(seconds=30.0, fidelity="full", tolerance=5.0)
"""The full run: every rig × every registered method × desired 0, 1, 2 × seed 0."""
QUICK = Settings(seconds=12.0, iterations=3, fidelity="fast", tolerance=5.0)
"""``--quick``: every rig but fuel-tank-7ch × the quick methods × desired 0 × seed 0, short
records, fast rigs; no thesis reproduction (``--thesis`` adds it; see :data:`QUICK_THESIS_NOTE`)."""
FULL_DESIRED, QUICK_DESIRED = (0, 1, 2), (0,)
QUICK_EXCLUDED_RIGS = ("fuel-tank-7ch",)
"""Left out of ``--quick``: a 7 × 7 record takes minutes (delay estimation and inverse fits of
every channel pair, three times per record); it is in the full run."""


def _parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="python -m benchmarks",
        description="vrig reconstruction benchmark: rigs × methods × desired responses × seeds "
        "(× non-linearity severities)",
    )
    sub = p.add_subparsers(dest="command", required=True)
    run = sub.add_parser(
        "run",
        help="run the benchmark (resumable) and write records, leaderboard, plots",
        description="Run every rig × method × desired response × seed record that the results "
        "folder does not hold yet, then write records.json/.csv, leaderboard.md, plots/ and the "
        "thesis reproduction report. Re-running resumes an interrupted run.",
    )
    run.add_argument("--quick", action="store_true", help="short records, fast rigs, 1 desired")
    run.add_argument("--rigs", nargs="+", help="rig names (default: all shipped rigs)")
    run.add_argument("--methods", nargs="+", help="method names (default: all registered)")
    run.add_argument("--desired", nargs="+", type=int, help="desired-response seeds")
    run.add_argument("--seeds", nargs="+", type=int, help="rig/identification seeds (default 0)")
    run.add_argument(
        "--severity",
        nargs="+",
        type=float,
        metavar="S",
        help="non-linearity severities in [0, 2] (vrig.load_rig(rig, severity=S); 0 linearised, "
        "1 as loaded, 2 twice as non-linear); rigs without a severity axis run once as loaded. "
        "Default: the rigs as loaded, no severity axis",
    )
    run.add_argument(
        "--targets",
        nargs="+",
        metavar="T",
        default=[PSEUDO_FIELD],
        help="kinds of desired response (vrig.desired.kinds.desired_response): 'pseudo-field' "
        "(default), 'field:<scenario>' (a rig's service scenario; a rig without it is skipped, "
        "with a note), 'field' (each rig's first scenario); a record-key axis",
    )
    run.add_argument("--seconds", type=float, help="desired record length [s]")
    run.add_argument("--iterations", type=int, help="iterations after IT00")
    run.add_argument(
        "--gain", type=float, help="iteration gain (default: each rig's own, as vrig reconstruct)"
    )
    run.add_argument("--fidelity", choices=("full", "fast"), help="rig fidelity")
    run.add_argument("--tolerance", type=float, help="mean η0 [%%] for 'iterations to tolerance'")
    run.add_argument("--out", type=Path, help="results folder (default results/benchmarks[-quick])")
    run.add_argument("--backend", choices=BACKENDS, default="process", help="default process")
    run.add_argument("--workers", type=int, help="parallel records (default: CPU count)")
    run.add_argument("--address", help="Ray cluster address (--backend ray; default: local Ray)")
    run.add_argument(
        "--plugin",
        action="append",
        default=[],
        metavar="MODULE_OR_FILE",
        help="load a method plugin (module name or .py file); repeatable",
    )
    run.add_argument(
        "--overwrite", action="store_true", help="delete records made with other settings"
    )
    run.add_argument("--no-plots", action="store_true", help="skip the plots")
    run.add_argument("--policies", type=Path, default=POLICIES, help=_POLICIES_HELP)
    run.add_argument(
        "--no-thesis", action="store_true", help="skip the thesis reproduction (full run)"
    )
    run.add_argument(
        "--thesis",
        action="store_true",
        help="with --quick: run the thesis reproduction alongside the records too (not part of "
        "--quick; python -m benchmarks.thesis_tables --quick runs it alone)",
    )
    run.add_argument("--quiet", action="store_true", help="no per-record lines")

    rep = sub.add_parser("report", help="rebuild records.json/.csv, leaderboard and plots")
    rep.add_argument("--out", type=Path, default=Path("results/benchmarks"), help="results folder")
    rep.add_argument("--no-plots", action="store_true")
    rep.add_argument("--policies", type=Path, default=POLICIES, help=_POLICIES_HELP)

    lst = sub.add_parser("list", help="rigs and registered methods")
    lst.add_argument("--plugin", action="append", default=[], metavar="MODULE_OR_FILE")
    return p


def _specs(extra: list[str]):
    return default_plugin_specs() + [plugin_spec(t) for t in extra]


def _settings(args) -> Settings:
    base = QUICK if args.quick else FULL
    changes = {
        k: getattr(args, k)
        for k in ("seconds", "iterations", "gain", "fidelity", "tolerance")
        if getattr(args, k) is not None
    }
    return replace(base, **changes)


def _code_version() -> dict:
    """vrig version and git commit of the checkout (records assume unchanged code)."""
    import subprocess

    import vrig

    info = {"vrig": getattr(vrig, "__version__", "?"), "commit": None, "dirty": None}
    root = Path(__file__).resolve().parents[2]
    try:
        info["commit"] = subprocess.run(
            ["git", "rev-parse", "HEAD"], cwd=root, capture_output=True, text=True, check=True
        ).stdout.strip()
        status = subprocess.run(
            ["git", "status", "--porcelain", "--untracked-files=no"],
            cwd=root,
            capture_output=True,
            text=True,
            check=True,
        ).stdout
        info["dirty"] = bool(status.strip())
    except (OSError, subprocess.CalledProcessError):
        pass
    return info


QUICK_THESIS_NOTE = (
    "thesis reproduction not part of --quick (python -m benchmarks.thesis_tables --quick runs "
    "it alone; --thesis runs it alongside the records)"
)


def _thesis_skipped(args) -> str | None:
    """Why this run does not start the thesis reproduction (None: it does): ``--no-thesis``,
    or ``--quick`` without ``--thesis``."""
    if args.no_thesis:
        return "thesis reproduction skipped (--no-thesis)"
    if args.quick and not args.thesis:
        return QUICK_THESIS_NOTE
    return None


def _thesis_available() -> str | None:
    """None if benchmarks.thesis_tables.thesis_report can be called, else why not."""
    try:
        from benchmarks import thesis_tables
    except ImportError as exc:
        return f"benchmarks.thesis_tables not importable ({exc})"
    if not callable(getattr(thesis_tables, "thesis_report", None)):
        return "benchmarks.thesis_tables has no thesis_report"
    return None


THESIS_LOCK = "thesis_reproduction.lock"
"""Lock file of the thesis reproduction in a results folder (owner's pid; see lifetime.py)."""


def _thesis_child(out: str, quick: bool, conn, parent_pid: int | None = None) -> None:
    """Run the thesis reproduction (in its own process; its log goes to a file).

    The process dies with the runner (``parent_pid``; :func:`~.lifetime.die_with_parent`) and
    holds ``thesis_reproduction.lock`` in ``out`` while it writes there: when another run's
    thesis reproduction holds it, this one is skipped, so two never write the same files."""
    if parent_pid is not None:
        die_with_parent(parent_pid)
    out_dir = Path(out)
    try:
        with PidLock(out_dir / THESIS_LOCK):
            result = _thesis_report(out_dir, quick)
    except LockHeldError as exc:
        result = (
            f"thesis reproduction skipped: another run's (pid {exc.pid}) is writing "
            f"{out_dir / 'thesis_reproduction.md'}",
            True,
        )
    conn.send(result)
    conn.close()


def _thesis_report(out_dir: Path, quick: bool) -> tuple[str, bool]:
    import contextlib

    t = time.perf_counter()
    with (
        open(out_dir / "thesis_reproduction.log", "w", encoding="utf-8", buffering=1) as fh,
        contextlib.redirect_stdout(fh),
        contextlib.redirect_stderr(fh),
    ):
        try:
            from benchmarks.thesis_tables import thesis_report

            thesis_report(out_dir, quick)
            return (
                f"thesis reproduction {out_dir / 'thesis_reproduction.md'} "
                f"({time.perf_counter() - t:.0f} s; log thesis_reproduction.log)",
                True,
            )
        except Exception as exc:
            import traceback

            traceback.print_exc()
            return (f"thesis reproduction FAILED: {type(exc).__name__}: {exc}", False)


class _Thesis:
    """The thesis reproduction, run in a separate (spawned) process alongside the records:
    it is one serial job, so it overlaps the records' pool instead of following it."""

    def __init__(self, out: Path, quick: bool):
        import multiprocessing

        one_blas_thread()  # it runs beside the record workers (benchmarks/threads.py)
        ctx = multiprocessing.get_context("spawn")
        self.recv, send = ctx.Pipe(duplex=False)
        self.proc = ctx.Process(
            target=_thesis_child, args=(str(out), quick, send, os.getpid()), daemon=False
        )
        self.proc.start()
        send.close()

    def result(self) -> tuple[str, bool]:
        try:
            line, ok = self.recv.recv()
        except EOFError:
            line, ok = "thesis reproduction FAILED: its process died (see the log)", False
        self.proc.join()
        return line, ok

    def stop(self) -> None:
        if self.proc.is_alive():
            self.proc.terminate()
        self.proc.join()


def _terminate(signum, frame):
    raise KeyboardInterrupt(f"signal {signum}")


def cmd_run(args) -> int:
    import vrig

    t0 = time.perf_counter()
    try:
        settings = _settings(args)
        specs = _specs(args.plugin)
    except (ValueError, FileNotFoundError) as exc:
        print(f"benchmarks run: {exc}", file=sys.stderr)
        return 2
    load_plugins(specs)
    rigs = args.rigs or [
        r for r in vrig.list_rigs() if not (args.quick and r in QUICK_EXCLUDED_RIGS)
    ]
    unknown = [r for r in rigs if r not in vrig.list_rigs()]
    methods = args.methods or method_names(quick=args.quick)
    try:
        for m in methods:
            get_method(m)
        if unknown:
            raise KeyError(f"unknown rig(s) {unknown}; available: {', '.join(vrig.list_rigs())}")
    except KeyError as exc:
        print(f"benchmarks run: {exc.args[0]}", file=sys.stderr)
        return 2
    desired = args.desired or (QUICK_DESIRED if args.quick else FULL_DESIRED)
    seeds = args.seeds or (0,)
    out = args.out or Path("results") / ("benchmarks-quick" if args.quick else "benchmarks")
    severities = _rig_severities(rigs, args.severity)
    targets = _rig_targets(rigs, args.targets, settings.fidelity)
    keys = [
        RecordKey(r, m, d, s, sev, t)
        for r in rigs
        for m in methods
        for d in desired
        for s in seeds
        for sev in severities[r]
        for t in targets[r]
    ]
    store = Store(out)
    try:
        store.prepare(settings, overwrite=args.overwrite)
    except SettingsMismatchError as exc:
        print(f"benchmarks run: {exc}", file=sys.stderr)
        return 2
    except OSError as exc:
        print(f"benchmarks run: --out {out}: cannot write there ({exc})", file=sys.stderr)
        return 2
    print(
        f"benchmark: {len(rigs)} rigs × {len(methods)} methods ({', '.join(methods)}) × "
        f"{len(desired)} desired × {len(seeds)} seeds"
        + (
            f" × severities {', '.join(map(format_severity, args.severity))}"
            if args.severity
            else ""
        )
        + ("" if args.targets == [PSEUDO_FIELD] else f" × targets {', '.join(args.targets)}")
        + f" -> {out}/"
    )
    flat = [r for r in rigs if severities[r] == [None]]
    if args.severity and flat:
        print(
            f"note: {', '.join(flat)} ha{'s' if len(flat) == 1 else 've'} no severity axis "
            "(linear rigs; vrig.severity_rigs()): run once as loaded (severity None)"
        )
    if threading.current_thread() is threading.main_thread():  # SIGTERM -> clean stop
        signal.signal(signal.SIGTERM, _terminate)
    thesis = None
    thesis_line, ok = _thesis_skipped(args), True
    if thesis_line is None:
        why_not = _thesis_available()
        if why_not:
            thesis_line = f"thesis reproduction skipped: {why_not}"
        else:
            print(f"thesis reproduction started alongside (log {out}/thesis_reproduction.log)")
            thesis = _Thesis(out, args.quick)
    try:
        summary = execute(
            keys,
            settings,
            store,
            plugin_specs=specs,
            backend=args.backend,
            workers=args.workers,
            address=args.address,
            log=None if args.quiet else print,
        )
    except KeyboardInterrupt:
        if thesis is not None:
            thesis.stop()
        done = sum(store.finished(k, settings) for k in keys)
        print(
            f"\ninterrupted: {done} of {len(keys)} records are in {out}/records; run the same "
            "command again to finish the others",
            file=sys.stderr,
        )
        return 130
    wanted = {store.path(k).name for k in keys}
    records = [r for r in store.all_records(settings) if f"{r['id']}.json" in wanted]
    written = write_outputs(
        out, records, asdict(settings), plots=not args.no_plots, policies=args.policies
    )
    if thesis is not None:
        if not args.quiet:
            print("records done; waiting for the thesis reproduction ...", flush=True)
        try:
            thesis_line, ok = thesis.result()
        except KeyboardInterrupt:
            thesis.stop()
            print("\ninterrupted during the thesis reproduction", file=sys.stderr)
            return 130
    wall = time.perf_counter() - t0
    run_info = {
        "settings": asdict(settings),
        "rigs": rigs,
        "methods": methods,
        "desired": list(desired),
        "seeds": list(seeds),
        "severity": args.severity,
        "targets": {r: targets[r] for r in rigs},
        "backend": args.backend,
        "workers": args.workers,
        "computed": len(summary["computed"]),
        "skipped": len(summary["skipped"]),
        "failed_records": len(summary["failed"]),
        "records_wall_s": summary["wall_s"],
        "wall_s": wall,
        "code": _code_version(),
    }
    write_atomic(out / "run.json", json.dumps(run_info, indent=1) + "\n")
    n_ok = sum(r["status"] == "ok" for r in records)
    print(
        f"\n{len(records)} records ({n_ok} ok, {len(records) - n_ok} failed; "
        f"{len(summary['computed'])} computed now, {len(summary['skipped'])} resumed)"
    )
    print(f"leaderboard {out / 'leaderboard.md'}")
    print(f"records     {out / 'records.json'}, {out / 'records.csv'}")
    n_plots = sum(1 for p in written if p.suffix == ".png")
    if n_plots:
        print(f"plots       {out / 'plots'}/ ({n_plots} figures)")
    print(thesis_line)
    for line in timing_lines(records, summary["computed"], summary["wall_s"]):
        print(line)
    print(f"wall time   {wall:.0f} s ({wall / 60:.1f} min), the whole run")
    return 0 if ok else 1


SLOWEST = 8
"""How many records the end-of-run time summary lists (the slowest first)."""


def timing_lines(records: list[dict], computed, records_wall_s: float, *,
                 slowest: int = SLOWEST) -> list[str]:  # fmt: skip
    """The end-of-run time summary of the records computed in this run: their wall time, the
    sum of their ``record_s`` and the ``slowest`` of them (seconds and share of the sum).

    Parameters
    ----------
    records : list of dict
        The run's records (those resumed from an earlier run are left out: their times are not
        this run's).
    computed : collection of str
        Ids of the records computed in this run.
    records_wall_s : float
        Wall time [s] of the records' phase (the pool, or the serial loop).
    slowest : int
        How many records to list.

    Returns
    -------
    list of str
        Lines to print.
    """
    ids = set(computed)
    now = sorted((r for r in records if r["id"] in ids), key=lambda r: -r["timing"]["record_s"])
    if not now:
        return ["records     none computed in this run (every record resumed): no record times"]
    total = sum(r["timing"]["record_s"] for r in now)
    lines = [
        f"records     {len(now)} computed in {records_wall_s:.0f} s of wall time ({total:.0f} s "
        f"summed over the records); the slowest {min(slowest, len(now))}:"
    ]
    for r in now[:slowest]:
        t = r["timing"]["record_s"]
        failed = "" if r["status"] == "ok" else " (failed)"
        lines.append(f"  {t:7.1f} s {100 * t / max(total, 1e-12):5.1f} %  {r['id']}{failed}")
    return lines


def cmd_report(args) -> int:
    store = Store(args.out)
    records = store.all_records()
    for name, why in store.rejected().items():
        print(f"benchmarks report: left out {name}: {why}", file=sys.stderr)
    if not records:
        print(f"benchmarks report: no records in {args.out}/records", file=sys.stderr)
        return 2
    settings_path = args.out / "settings.json"
    settings = json.loads(settings_path.read_text()) if settings_path.exists() else None
    write_outputs(args.out, records, settings, plots=not args.no_plots, policies=args.policies)
    print(f"{len(records)} records -> {args.out / 'leaderboard.md'}")
    return 0


def cmd_list(args) -> int:
    import vrig

    load_plugins(_specs(args.plugin))
    print("rigs:    " + ", ".join(vrig.list_rigs()))
    print("methods:")
    for name in method_names():
        p = get_method(name)
        quick = "" if p.quick else " (not in --quick)"
        print(f"  {name:<10} {p.description}{quick}  [{p.origin}]")
    return 0


def _rig_severities(rigs: list[str], severity: list[float] | None) -> dict[str, list]:
    """The severities each rig runs at: ``[None]`` (as loaded) without ``--severity`` and for
    a rig without a severity axis (a linear rig refuses ``severity=``: it runs once, as
    loaded, instead of failing or being dropped); else ``--severity``'s values."""
    import vrig

    if not severity:
        return {r: [None] for r in rigs}
    axis = set(vrig.severity_rigs())
    values = sorted({check_severity(s) for s in severity})
    return {r: (values if r in axis else [None]) for r in rigs}


class _BadInput(Exception):
    """Bad input found before the run: one line, exit status 2."""


def _rig_targets(rigs: list[str], targets: list[str], fidelity: str) -> dict[str, list[str]]:
    """The targets each rig runs on, resolved (``"field"`` alone: the rig's first scenario).

    A field target a rig does not have is skipped on it, one note per target on stdout naming
    the rigs; a target that no rig has (or that is not a target name) is a :class:`_BadInput`.
    Without a field target no rig is loaded.
    """
    from vrig.desired.kinds import parse_target

    if targets == [PSEUDO_FIELD]:
        return {r: [PSEUDO_FIELD] for r in rigs}
    import vrig
    from vrig.service import field_scenarios

    loaded = {r: vrig.load_rig(r, fidelity=fidelity) for r in rigs}
    out: dict[str, list[str]] = {r: [] for r in rigs}
    for target in dict.fromkeys(targets):
        skipped, why = [], ""
        for r, rig in loaded.items():
            try:
                kind, scenario = parse_target(rig, target)
            except ValueError as exc:
                names = field_scenarios(rig)
                skipped.append(f"{r} ({', '.join(names) if names else 'no scenario'})")
                why = str(exc)
                continue
            resolved = kind if scenario is None else f"{kind}:{scenario}"
            if resolved not in out[r]:
                out[r].append(resolved)
        _note_skipped(target, skipped, why, len(rigs))
    return out


def _note_skipped(target: str, skipped: list[str], why: str, n_rigs: int) -> None:
    """The one line of a target skipped on some rigs; a :class:`_BadInput` when on all."""
    if not skipped:
        return
    if target.partition(":")[0] != "field":  # not a target name: every rig refuses it
        raise _BadInput(f"--targets: {why}")
    if len(skipped) == n_rigs:
        raise _BadInput(
            f"--targets {target}: no rig of this run has it; their service scenarios: "
            + "; ".join(skipped)
        )
    print(
        f"note: target {target} skipped on {', '.join(skipped)}: not a service scenario of "
        + ("that rig" if len(skipped) == 1 else "those rigs")
    )


def _check_run_args(args) -> None:
    if args.thesis and args.no_thesis:
        raise _BadInput("--thesis and --no-thesis contradict each other: give one")
    if args.workers is not None and args.workers < 1:
        raise _BadInput(f"--workers must be >= 1, got {args.workers}")
    for flag, values in (("--desired", args.desired), ("--seeds", args.seeds)):
        if values and min(values) < 0:
            raise _BadInput(f"{flag} must be integers >= 0, got {values}")
    lo, hi = SEVERITY_RANGE
    bad = [s for s in args.severity or () if not lo <= s <= hi]  # NaN fails too
    if bad:
        raise _BadInput(
            f"--severity must lie in [{lo:g}, {hi:g}] (0 linearised, 1 as loaded, 2 twice as "
            f"non-linear), got {', '.join(map(str, bad))}"
        )
    if args.backend == "ray" and importlib.util.find_spec("ray") is None:
        raise _BadInput("--backend ray needs Ray: pip install 'vrig[ray]' (or 'ray>=2.9')")
    if args.out is not None and args.out.exists() and not args.out.is_dir():
        raise _BadInput(f"--out {args.out} is a file, not a folder")


def main(argv: list[str] | None = None, *, prog: str | None = None) -> int:
    """``python -m benchmarks`` / ``vrig bench``; returns the exit status (module doc)."""
    parser = _parser()
    if prog:
        parser.prog = prog
    args = parser.parse_args(argv)
    name = f"{parser.prog} {args.command}".replace("python -m benchmarks", "benchmarks")
    try:
        if args.command == "run":
            _check_run_args(args)
        return {"run": cmd_run, "report": cmd_report, "list": cmd_list}[args.command](args)
    except KeyboardInterrupt:
        print(f"{name}: interrupted", file=sys.stderr)
        return 130
    except (_BadInput, PluginError) as exc:
        print(f"{name}: " + " ".join(str(exc).split()), file=sys.stderr)
        return 2
    except OSError as exc:  # e.g. a disk that filled up while the outputs were written
        print(f"{name}: failed: {exc}", file=sys.stderr)
        return 1
    except Exception as exc:
        if os.environ.get("VRIG_DEBUG"):
            raise
        msg = " ".join(f"{type(exc).__name__}: {exc}".split())
        print(
            f"{name}: unexpected error {msg} (a bug: VRIG_DEBUG=1 shows the traceback)",
            file=sys.stderr,
        )
        return 3
