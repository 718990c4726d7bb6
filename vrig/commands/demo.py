"""``vrig demo``: identify and simulate a generated non-linear MIMO system (:mod:`vrig.demo`)."""

from __future__ import annotations

from .common import _Failure, _UsageError, add_seed_argument, check_seed, whole_number

SAMPLES = (2000, 100_000)  # = vrig.demo's MIN/MAX_SAMPLES (454 terms per output)


def _add_parser(sub, epilog: str) -> None:
    """Add the `demo` subcommand: identify and simulate a generated NARX system."""
    demo = sub.add_parser(
        "demo", help="identify and simulate a generated non-linear MIMO system", epilog=epilog
    )
    add_seed_argument(demo)
    demo.add_argument(
        "--samples",
        type=whole_number,
        default=20_000,
        help=f"record length {SAMPLES[0]}..{SAMPLES[1]} (default 20000; 2e4 is accepted)",
    )
    demo.add_argument(
        "--noise",
        type=float,
        default=0.01,
        help="output noise as a fraction of the output std (default 0.01)",
    )


def _run(args) -> int:
    """``vrig demo``: :func:`vrig.demo.run_demo` with the checked arguments."""
    from identification.errors import SimulationDivergedError, UnstableModelError

    from ..demo import run_demo

    lo, hi = SAMPLES
    if not lo <= args.samples <= hi:
        raise _UsageError(f"--samples must be >= {lo} and <= {hi}, got {args.samples}")
    if not 0 <= args.noise < 1:
        raise _UsageError(f"--noise must be in [0, 1), got {args.noise:g}")
    check_seed(args.seed)
    try:
        run_demo(seed=args.seed, n_samples=args.samples, noise=args.noise)
    except (UnstableModelError, SimulationDivergedError) as exc:  # the fit was refused
        raise _Failure(
            f"{exc} ({args.samples} samples are few for the 454 terms per output: try more "
            "--samples, or another --seed)"
        ) from exc
    return 0
