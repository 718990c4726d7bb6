"""``vrig rigs`` (the shipped rigs, one line each) and ``vrig describe RIG`` (channels, limits,
parameters)."""

from __future__ import annotations

from .common import load_rig


def _add_parsers(sub, epilog: str) -> None:
    """Add the `rigs` and `describe` subcommands."""
    sub.add_parser("rigs", help="list the shipped rigs")
    desc = sub.add_parser("describe", help="a rig's channels, limits and parameters", epilog=epilog)
    desc.add_argument("rig", help="rig name (see `vrig rigs`) or a user rig's .rig.json/.xml")


def _run_rigs(args) -> int:
    """``vrig rigs``: one line per shipped rig (a broken side-car does not hide the others)."""
    from ..rigs import list_rigs, rig_path
    from ..rigs.spec import read_description

    names = list_rigs()
    width = max((len(n) for n in names), default=0)
    for name in names:
        try:
            d = read_description(rig_path(name))
            lo, hi = d.bandwidth
            line = (
                f"{d.title}  [{len(d.inputs)} drive(s) -> {len(d.outputs)} response(s), "
                f"fs {d.fs:g} Hz, band {lo:g}-{hi:g} Hz]"
            )
        except Exception as exc:  # a broken side-car file must not hide the others
            line = f"(description unreadable: {exc})"
        print(f"{name:<{width}}  {line}")
    print(f"\n{len(names)} rigs; `vrig describe RIG` for channels, limits and parameters")
    return 0


def _run_describe(args) -> int:
    """``vrig describe RIG``: the rig's channels, limits and parameters."""
    rig = load_rig(args.rig)
    print(rig.describe())
    return 0
