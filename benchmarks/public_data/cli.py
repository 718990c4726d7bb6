"""Command line: ``python -m benchmarks.public_data [--quick] [--only ...] [--no-sysidentpy]``."""

from __future__ import annotations

import argparse
import datetime
import json
import platform
import time
from dataclasses import asdict
from pathlib import Path

import numpy as np

from vrig.files import atomic_write

from .data import external_data_root
from .datasets import DATASETS
from .pipeline import run
from .report import format_table

RESULTS_PATH = Path(__file__).resolve().parents[2] / "results" / "public_data.json"
DESCRIPTION = (
    "Free-run scores of vrig's polynomial NARX/ARX models on public nonlinear benchmark data."
)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=DESCRIPTION)
    parser.add_argument("--quick", action="store_true", help="smaller searches, skip slow runs")
    parser.add_argument(
        "--only", nargs="+", choices=sorted(DATASETS), help="run only these data sets"
    )
    parser.add_argument("--no-sysidentpy", action="store_true", help="skip SysIdentPy runs")
    parser.add_argument("--output", type=Path, default=RESULTS_PATH, help="JSON results file")
    args = parser.parse_args(argv)
    t0 = time.perf_counter()
    root = external_data_root()
    print(f"external data: {root}" + ("" if root.is_dir() else " (not found)"))
    report = run(args.quick, args.only, None, not args.no_sysidentpy)
    wall = time.perf_counter() - t0
    print(format_table(report, report.sysidentpy_version))
    print(f"\nwall time {wall:.1f} s" + (" (--quick)" if args.quick else ""))
    out = {
        "date": datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds"),
        "quick": args.quick,
        "wall_s": wall,
        "python": platform.python_version(),
        "numpy": np.__version__,
        "sysidentpy": report.sysidentpy_version,
        "data_root": str(root),
        "rows": [
            {
                k: (None if isinstance(v, float) and not np.isfinite(v) else v)
                for k, v in asdict(r).items()
            }
            for r in report.rows
        ],
        "notes": report.notes,
    }
    args.output.parent.mkdir(parents=True, exist_ok=True)
    with atomic_write(args.output, "w", encoding="utf-8") as f:
        f.write(json.dumps(out, indent=2))
    print(f"written {args.output}")
    return 0
