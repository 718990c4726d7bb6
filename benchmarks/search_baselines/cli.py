"""Command line: ``python -m benchmarks.search_baselines [--quick] [--only ...] [--record ...]``."""

from __future__ import annotations

import argparse
import datetime
import json
import platform
import sys
import time
from pathlib import Path

import numpy as np

from benchmarks.public_data import DATASETS, external_data_root, get_sysidentpy
from vrig.files import atomic_write

from .protocol import run_record, warm_up
from .records import BALL_AND_BEAM_SEEDS, Skipped, public_records, simulated_records
from .report import format_report, results_json
from .user_record import DEFAULT_INIT, DEFAULT_SPLIT, RecordError, load_user_record

RESULTS_PATH = Path(__file__).resolve().parents[2] / "results" / "search_baselines.json"
DEFAULT_BUDGET = 60.0  # seconds per NarxSearch
QUICK_BUDGET = 10.0
SIMULATED = "ball_and_beam"
#: the records of ``--quick``: the simulated ones and the short public record (1024 samples)
QUICK_RECORDS = (SIMULATED, "tanks")
DESCRIPTION = (
    "NarxSearch vs the FROLS+BIC baseline vs the best linear model, free-run test NRMSE per "
    "record (see the package docstring for the protocol)."
)


def _parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="python -m benchmarks.search_baselines", description=DESCRIPTION
    )
    p.add_argument(
        "--only",
        nargs="+",
        metavar="NAME",
        help=f"records to run: {', '.join([*DATASETS, SIMULATED])} or the --record file's stem",
    )
    p.add_argument(
        "--quick",
        action="store_true",
        help=f"{QUICK_BUDGET:g} s budget; only {', '.join(QUICK_RECORDS)} (and --record)",
    )
    p.add_argument(
        "--budget", type=float, help=f"NarxSearch budget [s] (default {DEFAULT_BUDGET:g})"
    )
    p.add_argument("--no-sysidentpy", action="store_true", help="vrig's FROLS+BIC as the baseline")
    p.add_argument(
        "--seeds",
        type=int,
        nargs="+",
        default=list(BALL_AND_BEAM_SEEDS),
        help="seeds of the ball_and_beam records",
    )
    p.add_argument(
        "--default-grid",
        action="store_true",
        help="NarxSearch's default grid on the public sets too (not their own)",
    )
    p.add_argument(
        "--record", type=Path, help="a user's record: .csv with a header, or .npz (u, y)"
    )
    p.add_argument("--input", nargs="+", default=[], metavar="COL", help="CSV input columns")
    p.add_argument("--output", nargs="+", default=[], metavar="COL", help="CSV output columns")
    p.add_argument("--split", type=float, default=DEFAULT_SPLIT, help="training fraction")
    p.add_argument(
        "--init",
        type=int,
        default=DEFAULT_INIT,
        help="measured outputs that start each test free run",
    )
    p.add_argument("--ts", type=float, help="sample interval of --record [s]")
    p.add_argument("--results", type=Path, default=RESULTS_PATH, help="JSON results file")
    return p


def _wanted(args, user) -> set[str]:
    known = [*DATASETS, SIMULATED] + ([user.key] if user else [])
    if args.only:
        unknown = [x for x in args.only if x not in known]
        if unknown:
            raise RecordError(f"--only: unknown record(s) {unknown}; known: {', '.join(known)}")
        return set(args.only)
    if user is not None:
        return {user.key}
    return set(QUICK_RECORDS) if args.quick else set(known)


def _records(args) -> tuple[list, list]:
    """(records to run, skipped) in run order: simulated, public, the user's."""
    user = None
    if args.record is not None:
        user = load_user_record(
            args.record, args.input, args.output, args.split, args.init, args.ts
        )
    elif args.input or args.output:
        raise RecordError("--input/--output need --record PATH")
    wanted = _wanted(args, user)
    recs = simulated_records(args.seeds) if SIMULATED in wanted else []
    public = [k for k in DATASETS if k in wanted]
    recs += public_records(public) if public else []
    recs += [user] if user is not None and user.key in wanted else []
    skipped = [r for r in recs if isinstance(r, Skipped)]
    return [r for r in recs if not isinstance(r, Skipped)], skipped


def _progress(text: str) -> None:
    print(text, file=sys.stderr, flush=True)


def main(argv: list[str] | None = None) -> int:
    args = _parser().parse_args(argv)
    budget = (
        args.budget if args.budget is not None else QUICK_BUDGET if args.quick else DEFAULT_BUDGET
    )
    if not (np.isfinite(budget) and budget > 0):
        print(
            f"error: --budget must be a positive number of seconds, got {budget}", file=sys.stderr
        )
        return 2
    try:
        records, skipped = _records(args)
    except RecordError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    sip = None if args.no_sysidentpy else get_sysidentpy()
    why = "--no-sysidentpy" if args.no_sysidentpy else "sysidentpy not importable"
    root = external_data_root()
    print(f"external data: {root}" + ("" if root.is_dir() else " (not found)"))
    install = "" if sip or args.no_sysidentpy else ": pip install -e .[bench] for SysIdentPy's"
    print(f"FROLS baseline: {'SysIdentPy ' + sip.version if sip else f'vrig ({why}{install})'}")
    if records:
        print(f"kernels compiled before the first search: {warm_up():.1f} s (not in any row)")
    t0 = time.perf_counter()
    results = [run_record(r, budget, sip, why, args.default_grid, _progress) for r in records]
    wall = time.perf_counter() - t0
    print(format_report(results, skipped))
    print(
        f"\nwall time {wall:.1f} s (NarxSearch budget {budget:g} s"
        + (", --quick)" if args.quick else ")")
    )
    meta = {
        "date": datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds"),
        "argv": sys.argv[1:] if argv is None else list(argv),
        "budget_s": budget,
        "quick": args.quick,
        "wall_s": wall,
        "python": platform.python_version(),
        "numpy": np.__version__,
        "sysidentpy": sip.version if sip else None,
        "frols_baseline": f"SysIdentPy {sip.version}" if sip else f"vrig ({why})",
        "data_root": str(root),
    }
    args.results.parent.mkdir(parents=True, exist_ok=True)
    with atomic_write(args.results, "w", encoding="utf-8") as f:
        f.write(json.dumps(results_json(results, skipped, meta), indent=2))
    print(f"written {args.results}")
    return 0
