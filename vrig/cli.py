"""The ``vrig`` command line."""

from __future__ import annotations

import argparse
import sys

__all__ = ["main"]


def _parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="vrig",
        description="vrig: virtual test rigs, ARX/NARX "
        "identification and dynamic response reconstruction",
    )
    sub = p.add_subparsers(dest="command", required=True)
    demo = sub.add_parser("demo", help="identify and simulate a generated non-linear MIMO system")
    demo.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    demo.add_argument("--samples", type=int, default=20_000, help="record length (default 20000)")
    demo.add_argument(
        "--noise",
        type=float,
        default=0.01,
        help="output noise as a fraction of the output std (default 0.01)",
    )
    return p


def main(argv: list[str] | None = None) -> int:
    args = _parser().parse_args(argv)
    if args.command == "demo":
        from .demo import run_demo

        if args.samples < 2000:
            print("vrig demo: --samples must be >= 2000", file=sys.stderr)
            return 2
        if not 0 <= args.noise < 1:
            print("vrig demo: --noise must be in [0, 1)", file=sys.stderr)
            return 2
        run_demo(seed=args.seed, n_samples=args.samples, noise=args.noise)
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
