"""The exit codes of ``vrig``: one enum whose members carry their meaning, from which the
``--help`` epilog, :data:`EXIT_CODE_MEANINGS` and the documentation's table are made."""

from __future__ import annotations

import enum

__all__ = ["EPILOG", "EXIT_CODE_MEANINGS", "STOP_EXIT", "ExitCode", "markdown_table"]


class ExitCode(enum.IntEnum):
    """The exit codes of ``vrig``; each member's ``meaning`` says when it is returned.

    >>> ExitCode.STOPPED_DIVERGED.meaning.split(":")[0]
    'vrig reconstruct stopped after IT00 on divergence'
    """

    def __new__(cls, code: int, meaning: str):
        member = int.__new__(cls, code)
        member._value_ = code
        member.meaning = meaning
        return member

    OK = (
        0,
        "success; vrig reconstruct: every iteration played, or converged (stop kind completed, "
        "converged)",
    )
    FAILED = (
        1,
        "failed: the rig or the computation of another command (an interlock trip, an unstable "
        "simulation or model); vrig reconstruct: an error of another kind after IT00 (stop kind "
        "failed, or law: a control law raised); results that could not be written",
    )
    BAD_INPUT = (
        2,
        "bad input: arguments, --desired files, rig descriptions, results folders that cannot be "
        "written, plugins that do not load, vrig bench without a source checkout",
    )
    BUG = (3, "an unexpected error (a bug: VRIG_DEBUG=1 shows the traceback)")
    STOPPED_INTERLOCK = (
        4,
        "vrig reconstruct stopped after IT00 on an interlock trip or a refused drive (stop kind "
        "interlock, refused); the best iteration is kept",
    )
    STOPPED_DIVERGED = (
        5,
        "vrig reconstruct stopped after IT00 on divergence: η0 grew, the inverse model diverged "
        "on a response or the drive update was not finite (stop kind diverged)",
    )
    STOPPED_UNSTABLE = (
        6,
        "vrig reconstruct stopped after IT00: the rig's simulation or the re-identified inverse "
        "model became unstable (stop kind unstable, model)",
    )
    FAILED_IT00 = (
        7,
        "vrig reconstruct failed before any iteration was played: the identification drive, the "
        "inverse model or IT00DRV (the identification records, model and refused drive are kept)",
    )
    INTERRUPTED = (
        130,
        "interrupted (Ctrl-C); vrig reconstruct keeps the iterations played in --out (stop kind "
        "interrupted)",
    )


STOP_EXIT = {
    "completed": ExitCode.OK,
    "converged": ExitCode.OK,
    "interlock": ExitCode.STOPPED_INTERLOCK,
    "refused": ExitCode.STOPPED_INTERLOCK,
    "diverged": ExitCode.STOPPED_DIVERGED,
    "unstable": ExitCode.STOPPED_UNSTABLE,
    "model": ExitCode.STOPPED_UNSTABLE,
    "law": ExitCode.FAILED,
    "failed": ExitCode.FAILED,
    "interrupted": ExitCode.INTERRUPTED,
}
"""``vrig reconstruct``'s exit code for each ``result.stop_kind`` of a reconstruction that played
IT00 (one that did not exits :attr:`ExitCode.FAILED_IT00`)."""

EXIT_CODE_MEANINGS = {int(c): c.meaning for c in ExitCode}
"""``{code: meaning}``, from :class:`ExitCode` (the ``--help`` epilog and the documentation's
table are made from it: they cannot drift)."""

EPILOG = "exit codes: " + "; ".join(f"{k} {v}" for k, v in EXIT_CODE_MEANINGS.items())
"""The exit-code line every ``--help`` ends with."""


def markdown_table() -> str:
    """The exit codes as a Markdown table (``docs/cli.md`` holds it; a test keeps the two
    equal)."""
    rows = ["| code | meaning |", "|---|---|"]
    rows += [f"| {int(c)} | {c.meaning} |" for c in ExitCode]
    return "\n".join(rows)
