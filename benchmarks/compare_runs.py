"""Compare the latest two saved pytest-benchmark runs; flag benchmarks > 20 % slower.

Save runs with ``pytest benchmarks/ --benchmark-only --benchmark-autosave`` (they go to
``.benchmarks/<machine>/NNNN_*.json``), then::

    python -m benchmarks.compare_runs                   # latest two runs under .benchmarks/
    python -m benchmarks.compare_runs OLD.json NEW.json # two given runs
    python -m benchmarks.compare_runs --stat min --threshold 0.1

Exit status 1 if any benchmark's statistic (default: mean) grew by more than the threshold.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

STATS = ("mean", "min", "median")


def latest_runs(directory: Path, count: int = 2) -> list[Path]:
    """The ``count`` most recent saved runs under ``directory``, oldest first."""
    runs = sorted(directory.glob("*/*.json"), key=lambda p: json.loads(p.read_text())["datetime"])
    return runs[-count:]


def load(path: Path, stat: str) -> dict[str, float]:
    data: dict[str, Any] = json.loads(path.read_text())
    return {b["fullname"]: float(b["stats"][stat]) for b in data["benchmarks"]}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    parser.add_argument(
        "runs", nargs="*", type=Path, help="OLD.json NEW.json (default: latest two)"
    )
    parser.add_argument("--dir", type=Path, default=Path(".benchmarks"), help="autosave folder")
    parser.add_argument("--stat", choices=STATS, default="mean", help="statistic to compare")
    parser.add_argument("--threshold", type=float, default=0.20, help="allowed slow-down fraction")
    args = parser.parse_args(argv)

    runs = args.runs or latest_runs(args.dir)
    if len(runs) != 2:
        parser.error(f"need two runs to compare, found {len(runs)} (save runs with "
                     "pytest benchmarks/ --benchmark-only --benchmark-autosave)")
    old, new = (load(p, args.stat) for p in runs)
    print(f"old: {runs[0]}\nnew: {runs[1]}\n")
    width = max(map(len, old.keys() | new.keys()), default=9)
    print(f"{'benchmark':<{width}} {'old ' + args.stat:>12} {'new ' + args.stat:>12} {'change':>8}")
    regressed = []
    for name in sorted(old.keys() & new.keys()):
        change = new[name] / old[name] - 1.0
        flag = ""
        if change > args.threshold:
            regressed.append(name)
            flag = "  SLOWER"
        print(f"{name:<{width}} {old[name] * 1e3:>9.3f} ms {new[name] * 1e3:>9.3f} ms "
              f"{change:>+8.1%}{flag}")
    for name in sorted(old.keys() ^ new.keys()):
        print(f"{name:<{width}} only in the {'old' if name in old else 'new'} run")
    print(f"\n{len(regressed)} benchmark(s) more than {args.threshold:.0%} slower ({args.stat})")
    return 1 if regressed else 0


if __name__ == "__main__":
    sys.exit(main())
