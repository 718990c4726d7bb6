"""Peak memory of long rig runs: flat in the record length (``MujocoRig.run`` in chunks).

Each case runs in a fresh subprocess: ``fuel-tank-7ch`` (7 drives, 7 accelerations, 5 kHz
physics) plays a band-limited random drive (as in :mod:`benchmarks.rig_speed`) of 1, 5 and 10
minutes with the default chunk length, and 1 minute in one piece (``chunk_seconds=inf``, how
every run was simulated before: the whole physics trajectory in memory) for contrast. Printed per
case: the process's peak resident memory (``ru_maxrss``: interpreter, MuJoCo, numba, SciPy and
the rig included), its resident memory before the run, the growth, the peak of the Python and
NumPy allocations during the run (``tracemalloc``) and the real-time factor. A last subprocess
plays the 1-minute drive in 0.7 s chunks and in one piece and prints the largest difference of
the two responses (0.0: bit-identical). Target: 10 minutes <= 300 MB peak.

    python -m benchmarks.rig_memory [--minutes 1 5 10] [--rig fuel-tank-7ch]
"""

from __future__ import annotations

import argparse
import json
import math
import resource
import subprocess
import sys
import time
import tracemalloc
from pathlib import Path

TARGET_MB = 300.0


def _rss_mb() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0  # kB on Linux


def _setup(rig_name: str, minutes: float):
    import vrig

    from .rig_speed import _drive

    rig = vrig.load_rig(rig_name)
    return rig, _drive(rig, minutes * 60.0)


def child_memory(rig_name: str, minutes: float, chunk_seconds: float) -> dict:
    """One case, in this (fresh) process: the memory of ``rig.run`` on a ``minutes`` drive."""
    rig, drive = _setup(rig_name, minutes)
    before = _rss_mb()
    tracemalloc.start()
    t0 = time.perf_counter()
    out = rig.run(drive, seed=1, chunk_seconds=chunk_seconds)
    wall = time.perf_counter() - t0
    _, traced = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    return {
        "rig": rig_name,
        "minutes": minutes,
        "chunk_seconds": chunk_seconds,
        "samples": out.n_samples,
        "rss_before_mb": before,
        "rss_peak_mb": _rss_mb(),
        "traced_peak_mb": traced / 2**20,
        "rtf": minutes * 60.0 / wall,
    }


def child_difference(rig_name: str, minutes: float) -> dict:
    """Largest difference between 0.7 s chunks and one piece on the same drive and seed."""
    rig, drive = _setup(rig_name, minutes)
    a = rig.run(drive, seed=1, chunk_seconds=0.7).data
    b = rig.run(drive, seed=1, chunk_seconds=math.inf).data
    return {"rig": rig_name, "minutes": minutes, "max_abs_difference": float(abs(a - b).max())}


def _spawn(*args: str) -> dict:
    cmd = [sys.executable, "-m", "benchmarks.rig_memory", "--child", *args]
    done = subprocess.run(cmd, capture_output=True, text=True, check=False)
    if done.returncode != 0:
        raise RuntimeError(f"{' '.join(cmd)} failed:\n{done.stderr[-2000:]}")
    return json.loads(done.stdout.strip().splitlines()[-1])


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--minutes", type=float, nargs="*", default=[1.0, 5.0, 10.0])
    p.add_argument("--rig", default="fuel-tank-7ch")
    p.add_argument("--output", default="results/rig_memory.json")
    p.add_argument("--child", nargs="+", help=argparse.SUPPRESS)
    args = p.parse_args(argv)
    if args.child:  # internal: one case in this fresh process, JSON on stdout
        kind, rig, minutes, *rest = args.child
        if kind == "memory":
            row = child_memory(rig, float(minutes), float(rest[0]))
        else:
            row = child_difference(rig, float(minutes))
        print(json.dumps(row))
        return 0
    default = _default_chunk()
    cases = [(m, default) for m in args.minutes] + [(min(args.minutes), math.inf)]
    print(
        f"{'rig':<15} {'minutes':>7} {'chunk s':>8} {'RSS before':>11} {'RSS peak':>9} "
        f"{'growth':>7} {'traced':>7} {'RTF':>5}  (MB)"
    )
    rows = []
    for minutes, chunk in cases:
        r = _spawn("memory", args.rig, repr(minutes), repr(chunk))
        rows.append(r)
        print(
            f"{r['rig']:<15} {minutes:>7g} {chunk:>8g} {r['rss_before_mb']:>11.1f} "
            f"{r['rss_peak_mb']:>9.1f} {r['rss_peak_mb'] - r['rss_before_mb']:>7.1f} "
            f"{r['traced_peak_mb']:>7.1f} {r['rtf']:>5.1f}",
            flush=True,
        )
    diff = _spawn("difference", args.rig, repr(min(args.minutes)))
    print(
        f"chunked (0.7 s) vs one piece, {diff['minutes']:g} min: largest difference "
        f"{diff['max_abs_difference']:g}"
    )
    longest = max((r for r in rows if r["chunk_seconds"] == default), key=lambda r: r["minutes"])
    ok = longest["rss_peak_mb"] <= TARGET_MB and diff["max_abs_difference"] == 0.0
    print(
        f"target: {longest['minutes']:g} min <= {TARGET_MB:g} MB peak and bit-identical chunks: "
        f"{'PASS' if ok else 'MISS'}"
    )
    from .runner.execute import write_atomic

    out = Path(args.output)
    out.parent.mkdir(parents=True, exist_ok=True)
    write_atomic(out, json.dumps({"cases": rows, "difference": diff, "pass": ok}, indent=2))
    print(f"results written to {out}")
    return 0


def _default_chunk() -> float:
    from vrig.rigs import MujocoRig

    return float(MujocoRig.chunk_seconds)


if __name__ == "__main__":
    raise SystemExit(main())
