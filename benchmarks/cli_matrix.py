"""Every shipped rig x method through ``vrig reconstruct``, as a new user runs it: one table.

For each rig and method the command ``vrig reconstruct --rig RIG --method METHOD --seconds S
--out TMP`` runs in this process (``vrig.cli.main``; each rig x method in a worker process with
``--jobs``), with the rig loaded at ``--fidelity`` (default ``fast``: the exploratory physics
step, :class:`vrig.rigs.MujocoRig`). Everything else is the command's own default (band, gain,
method options, identification level: the side-cars' ``"reconstruction"`` blocks). Printed per
run:

* ``exit``: the command's exit code (``vrig.cli``'s module doc);
* ``IT00`` and ``best``: mean η0 [%] of IT00 and of the iteration the command calls best;
* ``worse``: the channels whose η0 at the best iteration exceeds their IT00 value (``-``: none);
* ``stop``: why the loop stopped (``done``: all iterations played; ``ITxx: drive limit``: the
  drive check stopped a drive beyond full scale before it was sent; ``ITxx: trip``: an interlock
  tripped; ``not run``: the command stopped before the reconstruction, e.g. on bad input), and
  ``trip`` = ``yes`` when any interlock tripped or a drive was stopped for its limits;
* a method marked ``*`` is one the rig's side-car marks ``unsupported`` (the reference text
  reports it failing there): the command ran it after its one-line ``warning:`` (kept under
  ``stderr:`` below the table), so the table shows how it does;
* ``time`` [s]: wall time of the command.

    python -m benchmarks.cli_matrix [--rigs RIG ...] [--methods arx narx split frf error-signal]
        [--fidelity fast] [--seconds 20] [--jobs 2] [--out results/cli_matrix.md]
"""

from __future__ import annotations

import argparse
import contextlib
import io
import sys
import tempfile
import time
from concurrent.futures import ProcessPoolExecutor, as_completed
from pathlib import Path

import numpy as np

from vrig.reconstruction.vocabulary import BUILTIN_METHODS

METHODS = BUILTIN_METHODS  # every method of vrig reconstruct
COLUMNS = ("rig", "method", "exit", "IT00", "best", "best_mean", "worse", "trip", "stop", "time")


def _stop_text(result) -> tuple[str, bool]:
    """(short stop reason, an interlock trip or a drive beyond its limits?) of a result (None:
    the command stopped before the reconstruction)."""
    from vrig.errors import RigLimitError

    if result is None:
        return "not run", False
    err = result.error
    trip = isinstance(err, RigLimitError) or bool(result.rejected_name)
    if not result.stopped:
        return "done", trip
    text = result.stopped
    if isinstance(err, RigLimitError):
        text = text.split(":")[0] + (": drive limit" if err.time != err.time else ": trip")
    elif "diverging" in text:
        text = text.split(":")[0] + ": diverging"
    elif "converged" in text:
        text = text.split(":")[0] + ": converged"
    elif err is not None:
        text = text.split(":")[0] + f": {type(err).__name__}"
    return text, trip


def run_one(rig: str, method: str, fidelity: str, seconds: float, extra=()) -> dict:
    """One ``vrig reconstruct`` run; returns the row of the table: the printed columns and
    ``message`` (the command's ``vrig ...``/``warning:`` lines on stderr), ``warned`` (the
    side-car's unsupported warning), ``traceback``, ``stop_kind`` (``result.stop_kind``;
    ``None``: not run), ``played`` (iterations played, IT00 included) and ``worse_list``."""
    import vrig
    import vrig.reconstruction as rec
    from vrig import cli
    from vrig.errors import ReconstructionError

    captured: dict = {}
    real_reconstruct, real_load = rec.reconstruct, vrig.load_rig

    def reconstruct(*a, **k):  # keep the result (also that of a failure before IT01)
        try:
            captured["result"] = real_reconstruct(*a, **k)
        except ReconstructionError as exc:
            captured["result"] = exc.result
            raise
        return captured["result"]

    def load_rig(*a, **k):
        k.setdefault("fidelity", fidelity)
        return real_load(*a, **k)

    err = io.StringIO()
    t0 = time.perf_counter()
    rec.reconstruct, vrig.load_rig = reconstruct, load_rig
    try:
        with tempfile.TemporaryDirectory(prefix="vrig-cli-matrix-") as tmp:
            argv = ["reconstruct", "--rig", rig, "--method", method, "--seconds", f"{seconds:g}"]
            argv += ["--out", str(Path(tmp) / "out"), *extra]
            with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(err):
                code = cli.main(argv)
    finally:
        rec.reconstruct, vrig.load_rig = real_reconstruct, real_load
    wall = time.perf_counter() - t0
    result = captured.get("result")
    stop, trip = _stop_text(result)
    row = {"rig": rig, "method": method, "exit": code, "trip": trip, "stop": stop, "time": wall}
    lines = err.getvalue().replace("\r", "\n").splitlines()  # not the progress bars
    row["message"] = " ".join(x.strip() for x in lines if x.startswith(("vrig ", "warning: ")))
    row["warned"] = any(x.startswith("warning: --method") for x in lines)
    row["traceback"] = "Traceback" in err.getvalue() or code == 3
    row["stop_kind"] = None if result is None else result.stop_kind
    row["played"] = 0 if result is None else len(result.errors)  # iterations, IT00 included
    if result is not None and len(result.errors):
        e = np.asarray(result.errors)
        b = result.best_iteration
        worse = [n for n, x, y in zip(result.desired.names, e[b], e[0], strict=True) if x > y]
        row.update(
            IT00=float(e[0].mean()),
            best=f"IT{b:02d}",
            best_mean=float(e[b].mean()),
            worse=",".join(worse) or "-",
            worse_list=worse,
        )
    else:
        row.update(IT00=np.nan, best="-", best_mean=np.nan, worse="-", worse_list=[])
    return row


def _pct(value: float) -> str:
    """A mean η0 [%] of the table, ``-`` where no iteration was played."""
    return "-" if np.isnan(value) else f"{value:.2f}"


def table(rows: list[dict]) -> str:
    """The rows as a markdown table (η0 in %, time in s)."""
    head = (
        "| rig | method | exit | IT00 mean η0 [%] | best | best mean η0 [%] | channels worse "
        "than IT00 | trip | stop | time [s] |"
    )
    lines = [head, "|" + "---|" * 10]
    for r in rows:
        lines.append(
            f"| {r['rig']} | {r['method']}{'*' if r.get('warned') else ''} | {r['exit']} | "
            f"{_pct(r['IT00'])} | {r['best']} | {_pct(r['best_mean'])} | {r['worse']} | "
            f"{'yes' if r['trip'] else 'no'} | {r['stop']} | {r['time']:.0f} |"
        )
    return "\n".join(lines)


def _status(row: dict) -> None:
    """One line on stderr per finished run (the table comes at the end)."""
    print(
        f"{row['rig']} {row['method']}: exit {row['exit']}, IT00 {_pct(row['IT00'])} %, best "
        f"{row['best']} {_pct(row['best_mean'])} %, worse {row['worse']}, {row['stop']}, "
        f"{row['time']:.0f} s",
        file=sys.stderr,
        flush=True,
    )


def run_matrix(rigs, methods, fidelity="fast", seconds=20.0, jobs=1, quiet=False) -> list[dict]:
    """Every rig x method (rows in that order)."""
    cases = [(r, m) for r in rigs for m in methods]
    rows: dict = {}
    if jobs <= 1:
        for case in cases:
            rows[case] = run_one(*case, fidelity, seconds)
            if not quiet:
                _status(rows[case])
        return [rows[c] for c in cases]
    with ProcessPoolExecutor(jobs) as pool:
        futures = {pool.submit(run_one, r, m, fidelity, seconds): (r, m) for r, m in cases}
        for f in as_completed(futures):
            rows[futures[f]] = f.result()
            if not quiet:
                _status(rows[futures[f]])
    return [rows[c] for c in cases]


def main(argv=None) -> int:
    import vrig
    from vrig.files import atomic_write

    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--rigs", nargs="+", default=None, help="default: every shipped rig")
    p.add_argument("--methods", nargs="+", default=list(METHODS))
    p.add_argument("--fidelity", choices=("fast", "full"), default="fast")
    p.add_argument("--seconds", type=float, default=20.0, help="pseudo-field length [s]")
    p.add_argument("--jobs", type=int, default=1, help="worker processes (default 1)")
    p.add_argument("--out", help="also write the table (markdown) to this file")
    args = p.parse_args(argv)
    t0 = time.perf_counter()
    rows = run_matrix(
        args.rigs or vrig.list_rigs(), args.methods, args.fidelity, args.seconds, args.jobs
    )
    text = table(rows)
    notes = [f"- {r['rig']} {r['method']}: {r['message']}" for r in rows if r["message"]]
    footer = (
        f"\n{len(rows)} runs, fidelity {args.fidelity}, {args.seconds:g} s pseudo-field, "
        f"{time.perf_counter() - t0:.0f} s wall ({args.jobs} job(s))"
    )
    if any(r["warned"] for r in rows):
        footer += (
            "\n* the side-car marks the method unsupported (the reference text reports it "
            "failing on the rig): run after a one-line warning"
        )
    out = "\n".join([text, footer, *(["\nstderr:", *notes] if notes else [])])
    print(out)
    if args.out:
        Path(args.out).parent.mkdir(parents=True, exist_ok=True)
        with atomic_write(args.out, "w", encoding="utf-8") as fh:
            fh.write(out + "\n")
    return 0


if __name__ == "__main__":  # pragma: no cover
    raise SystemExit(main())
