"""Compare saved pytest-benchmark runs; flag benchmarks > 20 % slower than the previous run.

Save runs with ``pytest benchmarks/ --benchmark-only --benchmark-autosave`` (they go to
``.benchmarks/<machine>/NNNN_*.json``), then::

    python -m benchmarks.compare_runs                   # latest two runs under .benchmarks/
    python -m benchmarks.compare_runs OLD.json NEW.json # two given runs
    python -m benchmarks.compare_runs --stat min --threshold 0.1
    python -m benchmarks.compare_runs --run             # run the speed suites, save, compare
    python -m benchmarks.compare_runs --run -k rig_run  # ... only some benchmarks (pytest -k)

``--run`` runs ``pytest benchmarks/ --benchmark-only --benchmark-autosave`` (both speed suites:
``test_identification_speed.py`` and ``test_speed_suite.py``) and compares the run it saved with
the previous saved run (the first run only reports that there is nothing to compare yet).

Exit status 1 if any benchmark's statistic (default: mean) grew by more than the threshold, 2
if there is nothing to compare or the pytest run failed.
"""

from __future__ import annotations

import argparse
import json
import subprocess
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


def _context(path: Path) -> str:
    """Machine, CPU and commit of a saved run (one line)."""
    data = json.loads(path.read_text())
    m, c = data.get("machine_info", {}), data.get("commit_info", {})
    cpu = (m.get("cpu") or {}).get("brand_raw", "?")
    commit = (c.get("id") or "?")[:10] + ("+dirty" if c.get("dirty") else "")
    return f"{data.get('datetime', '?')}  node {m.get('node', '?')}  {cpu}  commit {commit}"


def compare(old_path: Path, new_path: Path, *, stat: str = "mean", threshold: float = 0.20):
    """Print the comparison table; returns the names of the benchmarks slower than threshold."""
    old, new = load(old_path, stat), load(new_path, stat)
    print(f"old: {old_path}\n     {_context(old_path)}")
    print(f"new: {new_path}\n     {_context(new_path)}\n")
    om = json.loads(old_path.read_text()).get("machine_info", {}).get("node")
    nm = json.loads(new_path.read_text()).get("machine_info", {}).get("node")
    if om != nm:
        print(f"warning: the runs come from different machines ({om} vs {nm})\n")
    width = max(map(len, old.keys() | new.keys()), default=9)
    print(f"{'benchmark':<{width}} {'old ' + stat:>12} {'new ' + stat:>12} {'change':>8}")
    regressed = []
    for name in sorted(old.keys() & new.keys()):
        change = new[name] / old[name] - 1.0
        flag = ""
        if change > threshold:
            regressed.append(name)
            flag = "  SLOWER"
        print(
            f"{name:<{width}} {old[name] * 1e3:>9.3f} ms {new[name] * 1e3:>9.3f} ms "
            f"{change:>+8.1%}{flag}"
        )
    for name in sorted(old.keys() ^ new.keys()):
        print(f"{name:<{width}} only in the {'old' if name in old else 'new'} run")
    print(f"\n{len(regressed)} benchmark(s) more than {threshold:.0%} slower ({stat})")
    for name in regressed:
        print(f"  SLOWER {name}")
    return regressed


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    parser.add_argument(
        "runs", nargs="*", type=Path, help="OLD.json NEW.json (default: latest two)"
    )
    parser.add_argument("--dir", type=Path, default=Path(".benchmarks"), help="autosave folder")
    parser.add_argument("--stat", choices=STATS, default="mean", help="statistic to compare")
    parser.add_argument("--threshold", type=float, default=0.20, help="allowed slow-down fraction")
    parser.add_argument(
        "--run",
        action="store_true",
        help="first run the speed suites with --benchmark-autosave, then compare with the "
        "previous saved run",
    )
    parser.add_argument("-k", dest="select", help="with --run: pytest -k expression")
    args = parser.parse_args(argv)

    if args.run:
        if args.runs:
            parser.error("--run compares the new run with the previous one: give no run files")
        before = set(args.dir.glob("*/*.json"))
        cmd = [sys.executable, "-m", "pytest", "benchmarks/", "--benchmark-only"]
        cmd += ["--benchmark-autosave", f"--benchmark-storage=file://{args.dir}", "-q"]
        if args.select:
            cmd += ["-k", args.select]
        print("$ " + " ".join(cmd), flush=True)
        if subprocess.call(cmd) != 0:
            print("the speed suite failed; nothing compared", file=sys.stderr)
            return 2
        saved = sorted(set(args.dir.glob("*/*.json")) - before)
        if not saved:
            print("pytest saved no run", file=sys.stderr)
            return 2
        runs = latest_runs(args.dir)
        if len(runs) < 2 or runs[-1] != saved[-1]:
            print(f"\nsaved {saved[-1]}: the first run, nothing to compare yet")
            return 0
    else:
        runs = args.runs or latest_runs(args.dir)
    if len(runs) != 2:
        parser.error(
            f"need two runs to compare, found {len(runs)} (save runs with "
            "pytest benchmarks/ --benchmark-only --benchmark-autosave, or use --run)"
        )
    regressed = compare(runs[0], runs[1], stat=args.stat, threshold=args.threshold)
    return 1 if regressed else 0


if __name__ == "__main__":
    sys.exit(main())
