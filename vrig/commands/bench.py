"""``vrig bench``: the benchmark runner of the source checkout (= ``python -m benchmarks``), run
in a child interpreter (the library never imports the benchmarks)."""

from __future__ import annotations

import argparse
import os
import signal
import subprocess
import sys
import threading
from pathlib import Path

from .common import _UsageError


def _add_parser(sub) -> None:
    """Add the `bench` subcommand: passes its arguments on to the benchmark runner.

    Parameters
    ----------
    sub : argparse._SubParsersAction
        The subcommands of the ``vrig`` parser.
    """
    bench = sub.add_parser(
        "bench",
        help="the reconstruction benchmark runner (= python -m benchmarks; source checkout)",
        add_help=False,
    )
    bench.add_argument("args", nargs=argparse.REMAINDER, help="run|report|list and options")


def benchmarks_dir() -> Path:
    """``benchmarks/`` of the source checkout the running ``vrig`` package lives in (an editable
    install or ``PYTHONPATH``); missing when ``vrig`` is an installed wheel."""
    return Path(__file__).resolve().parents[2] / "benchmarks"


def _run(argv: list[str]) -> int:
    """Forward to the benchmark runner, which lives in the source checkout's ``benchmarks/``
    (found next to the ``vrig`` package, whatever the current directory), run in a child
    interpreter.

    Parameters
    ----------
    argv : list of str
        The arguments after ``vrig bench``.

    Returns
    -------
    int
        The runner's exit code.
    """
    bench = benchmarks_dir()
    if not (bench / "runner" / "cli.py").is_file():
        raise _UsageError(
            f"vrig bench needs a source checkout: there is no benchmark runner at {bench} (a "
            "wheel ships none); clone the vrig repository (git clone ...), run `pip install -e .` "
            "in it, and run `vrig bench ...` again"
        )
    # a separate interpreter: vrig (the library) never imports the benchmarks (the floor above
    # it); the runner and the workers it spawns import them from the checkout root
    root = str(bench.parent)
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(p for p in (root, env.get("PYTHONPATH")) if p)
    code = (
        "import sys; from pathlib import Path; import benchmarks\n"
        "if Path(benchmarks.__file__).resolve().parent != Path(sys.argv[1]):\n"
        "    sys.exit(f'vrig bench: another package named benchmarks ({benchmarks.__file__}) "
        "hides the benchmark runner at {sys.argv[1]}')\n"
        "from benchmarks.runner.cli import main\n"
        "sys.exit(main(sys.argv[2:], prog='vrig bench'))"
    )
    child = subprocess.Popen([sys.executable, "-c", code, str(bench), *argv], env=env)
    # Ctrl-C reaches the whole foreground process group: the child says "interrupted" and exits
    # 130, so this process waits for it instead of printing a second line
    main_thread = threading.current_thread() is threading.main_thread()
    previous = signal.signal(signal.SIGINT, signal.SIG_IGN) if main_thread else None
    try:
        return child.wait()
    finally:
        if main_thread:
            signal.signal(signal.SIGINT, previous)
