"""Issue 15 acceptance: every shipped rig x {arx, narx, split, frf, error-signal} through
``vrig reconstruct`` at fast fidelity runs without an interlock trip and without a traceback,
exits with a documented code, and keeps an iteration where no channel is worse than at IT00 (slow:
the whole matrix takes minutes; ``python -m benchmarks.cli_matrix`` prints the same table).

A method the rig's side-car marks ``unsupported`` (the reference text reports it failing there)
is not refused (issue 23): the command warns once and runs it, and the run must end in a played
iteration or in a stop of the drive checks or the interlocks, with that stop's documented exit
code (a benchmark lets a user see a method do badly). Every other run must finish (exit 0, or a
divergence stop that keeps a better iteration) with its best mean η0 below IT00's and no trip.
"""

from __future__ import annotations

import pytest

import vrig
from benchmarks.cli_matrix import METHODS, run_matrix, table
from vrig import cli

pytestmark = pytest.mark.slow


def _documented_codes() -> set[int]:
    """The exit codes the CLI documents (its module constants)."""
    codes = {v for k, v in vars(cli).items() if k.startswith("EXIT_") and isinstance(v, int)}
    exit_code = getattr(cli, "ExitCode", None)  # finer codes, when the CLI has them
    if exit_code is not None:
        codes |= {int(c) for c in exit_code}
    return codes


def _played_or_stopped_by_a_limit(row: dict) -> bool:
    """A run that played an iteration (a best one kept) with its stop's exit code, or that the
    drive check / an interlock stopped before IT00 was played (exit FAILED_IT00)."""
    if row["best"] != "-":  # IT00 played: exit 0 or the code of the stop kind
        return row["exit"] in {int(c) for c in cli.STOP_EXIT.values()}
    return row["trip"] and row["exit"] == cli.ExitCode.FAILED_IT00


def test_every_rig_and_method_runs_from_the_cli():
    rows = run_matrix(vrig.list_rigs(), (*METHODS, "error-signal"), "fast", 20.0, jobs=2, quiet=True)
    print(table(rows))
    codes = _documented_codes()
    problems = []
    for r in rows:
        rig = vrig.rigs.spec.read_defaults(vrig.rigs.rig_path(r["rig"]))
        unsupported = rig.method(r["method"]).unsupported
        where = f"{r['rig']} {r['method']}"
        if r["traceback"] or r["exit"] not in codes:
            problems.append(f"{where}: exit {r['exit']} ({r['message']})")
        if bool(unsupported) != r["warned"]:
            problems.append(f"{where}: warned {r['warned']}, side-car unsupported {unsupported!r}")
        if r["worse_list"]:
            problems.append(f"{where}: best {r['best']} worse than IT00 on {r['worse_list']}")
        if unsupported:
            if not _played_or_stopped_by_a_limit(r):
                problems.append(f"{where}: exit {r['exit']}, {r['stop']} ({r['message']})")
            continue
        if r["trip"]:
            problems.append(f"{where}: an interlock trip or a drive beyond its limits ({r['stop']})")
        if r["exit"] not in (0, cli.ExitCode.STOPPED_DIVERGED) or not r["best_mean"] < r["IT00"]:
            # a divergence stop (documented code 5) keeps a best iteration better than IT00
            problems.append(
                f"{where}: exit {r['exit']}, IT00 {r['IT00']:.2f} %, best {r['best_mean']:.2f} % "
                f"({r['stop']}; {r['message']})"
            )
    assert not problems, "\n".join(problems)
