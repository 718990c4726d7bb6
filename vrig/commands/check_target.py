"""``vrig check-target``: can the rig reach a desired response? (§2.3.2, :mod:`vrig.desired.reachability`)"""

from __future__ import annotations

from pathlib import Path

from .common import (
    _UsageError,
    add_band_argument,
    add_rig_argument,
    add_seed_argument,
    check_seconds,
    check_seed,
    load_rig,
    read_desired,
    simulation_band,
)


def _add_parser(sub, epilog: str) -> None:
    """Add the `check-target` subcommand."""
    chk = sub.add_parser(
        "check-target",
        help="can the rig reach a desired response? unreachable fraction per response, needed "
        "drive against the actuator limits (§2.3.2)",
        description="Play one identification drive on the rig (random, triangular PSD over the "
        "identification band, as reconstruct does) and print: the desired response against the "
        "transducer ranges; per response the fraction of the target no drive can reach (the "
        "residual of the best linear drive) and the rig's incoherence at the target's "
        "frequencies; per drive the peak drive and velocity the target needs against the "
        "actuator's limits. The definitions: vrig.desired.reachability.",
        epilog=epilog,
    )
    add_rig_argument(chk)
    chk.add_argument(
        "--desired",
        required=True,
        metavar="FILE",
        help="desired response with the rig's response channels at the rig's sample rate "
        "(formats as for `vrig reconstruct --desired`)",
    )
    add_band_argument(
        chk,
        "simulation bandwidth [Hz] (default as for reconstruct)",
    )
    chk.add_argument(
        "--seconds",
        type=float,
        help="length of the identification run [s] (default: the desired record's length)",
    )
    add_seed_argument(chk)


def _run(args) -> int:
    """``vrig check-target``: the range report and the target check of ``--desired``."""
    from ..desired.range_report import range_report
    from ..desired.reachability import check_target

    check_seconds(args.seconds)
    check_seed(args.seed)
    if not Path(args.desired).is_file():
        what = "a folder, not a file" if Path(args.desired).is_dir() else "no file"
        raise _UsageError(f"--desired: {what} {args.desired}")
    rig = load_rig(args.rig, seed=args.seed)
    band = simulation_band(rig, args.band)
    desired, notes = read_desired(args.desired, rig)
    for note in notes:
        print(f"note: {note}")
    print(f"rig       {rig.name} (variant {rig.variant}): {rig.description.title}")
    print(f"desired   {args.desired} ({desired.duration:g} s)\n")
    print(range_report(rig, desired).table() + "\n", flush=True)
    try:
        check = check_target(rig, desired, band=band, seconds=args.seconds, seed=args.seed)
    except ValueError as exc:  # a record too short for the spectral estimate
        raise _UsageError(str(exc)) from exc
    print(check.table())
    return 0
