"""``vrig check-linearity``: is the rig non-linear? mean-level, scaling, coherence and
ARX-vs-NARX tests (§5.8, :mod:`vrig.linearity`)."""

from __future__ import annotations

import contextlib
from pathlib import Path

import numpy as np

from ..job import CLI_NAMES, check_writable, hold_results_folder
from .common import (
    _UsageError,
    add_band_argument,
    add_rig_argument,
    add_seed_argument,
    check_seconds,
    check_seed,
    load_rig,
    simulation_band,
)


def _add_parser(sub, epilog: str) -> None:
    """Add the `check-linearity` subcommand."""
    lin = sub.add_parser(
        "check-linearity",
        help="is the rig non-linear? mean-level, scaling, coherence and ARX-vs-NARX tests",
        description="Play a band-limited random drive u on the rig (and 2u, -u, u again, zero, "
        "an offset b and u + b), judge each test against the measured noise floor and print "
        "the evidence; the last line is 'verdict: linear' or 'verdict: non-linear' (exit 0 "
        "either way). The rule is in vrig.linearity's documentation.",
        epilog=epilog,
    )
    add_rig_argument(lin)
    lin.add_argument(
        "--level",
        type=float,
        default=0.10,
        help="random drive rms as a fraction of each drive's full scale, in (0, 0.5] "
        "(default 0.10; halved on an interlock trip)",
    )
    lin.add_argument(
        "--seconds", type=float, default=8.0, help="analysed length of each record (default 8 s)"
    )
    add_band_argument(
        lin,
        "drive band [Hz] (default: the band of the text's repeatability test of the rig "
        "where the side-car gives one, else as for reconstruct)",
    )
    add_seed_argument(lin)
    lin.add_argument("--plot", action="store_true", help="write linearity.png into --out")
    lin.add_argument("--out", help="folder of the plot (default ./results/<rig>-linearity)")


def _run(args) -> int:
    """``vrig check-linearity``, holding the lock of ``--out`` when the plot is asked for."""
    with contextlib.ExitStack() as hold:  # the plot folder's lock, from the checks to the end
        return _check_linearity(args, hold)


def _check_linearity(args, hold: contextlib.ExitStack) -> int:
    """``vrig check-linearity``; ``hold`` keeps the lock of ``--out`` when the plot is asked
    for."""
    from ..linearity import check_rig_linearity

    if not (np.isfinite(args.level) and 0 < args.level <= 0.5):
        raise _UsageError(
            f"--level must be a fraction of full scale in (0, 0.5], got {args.level:g}"
        )
    check_seconds(args.seconds)
    check_seed(args.seed)
    if args.out is not None and not args.plot:
        raise _UsageError("--out is the folder of the plot: pass --plot too")
    rig = load_rig(args.rig, seed=args.seed)
    band = simulation_band(rig, args.band)
    out = Path(args.out) if args.out else Path("results") / f"{Path(rig.name).stem}-linearity"
    if args.plot:
        if out.exists() and not out.is_dir():
            raise _UsageError(f"--out {out} is a file, not a folder")
        check_writable(out, CLI_NAMES)  # before the runs, not after them
        hold_results_folder(hold, out, CLI_NAMES)  # one writer per folder: refused before runs
    result = check_rig_linearity(  # its bar follows VRIG_PROGRESS (a terminal by default)
        rig, level=args.level, seconds=args.seconds, band=band, seed=args.seed
    )
    lines = result.table().splitlines()
    print("\n".join(lines[:-1]))
    if args.plot:
        out.mkdir(parents=True, exist_ok=True)
        print(f"plot       {result.plot(out / 'linearity.png')}")
    print(lines[-1])
    return 0
