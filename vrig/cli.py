"""The ``vrig`` command line.

::

    vrig rigs                                   # the shipped rigs, one line each
    vrig describe shock-absorber                # channels, limits, parameters
    vrig reconstruct --rig shock-absorber --method arx
    vrig repeatability --rig shock-absorber
    vrig check-linearity --rig elastomeric-damper --plot   # is NARX worth it? (§5.8)
    vrig check-target --rig fuel-tank-2ch --desired road.rsp   # can the rig reach it? (§2.3.2)
    vrig demo                                   # identify a generated non-linear MIMO system
    vrig bench run --quick                      # the benchmark runner (= python -m benchmarks)

``vrig reconstruct`` without ``--desired`` reconstructs a pseudo-field response (reference text
§6.5): the rig's response to a road-like random drive (triangular PSD over the simulation band,
10 % of each drive's full scale RMS, halved until the rig runs it with its responses within two
thirds of their transducer ranges; 1 s fade-in and fade-out). It writes the QanTiM test folder
(:class:`vrig.testfolder.TestFolder`) and the plots (:mod:`vrig.plots`) into ``--out``. A
``--method`` the rig's side-car marks ``unsupported`` (the reference text reports it failing on
the rig) runs all the same, after one ``warning:`` line on stderr quoting the text: only the drive
checks and the interlocks stop a run.

``vrig repeatability`` plays one random drive five times (§3.1, Fig. 3.1); its first column is
the text's scalar repeatability number (Tables 3.1-3.3): ``100 - mean η0`` of each run against
the mean response, the responses processed to the drive band (by default the simulation
bandwidth the text names with the rig's table, side-car ``"repeatability"``, e.g. 0-25 Hz for the
radiator, whose number it then prints beside; else the reconstruction band), then the same over
the full recorded band, the mean in-band ``R_f`` and the SNR (:mod:`vrig.repeatability`).

Progress of the long phases (desired-response generation, identification, long rig runs, the
iterations) goes to stderr when stderr is a terminal; ``VRIG_PROGRESS=1`` shows it anyway,
``VRIG_PROGRESS=0`` never (:mod:`vrig.progress`).

Exit codes: every error is one line on stderr, ``vrig COMMAND: ...``, never a traceback; a
``vrig reconstruct`` that stopped early or failed says why on one line too, with what to change,
and keeps what it made in ``--out``. The codes are the members of :class:`ExitCode`
(:mod:`vrig.commands.exit_codes`), each with its ``meaning``; ``vrig --help`` ends with their
table, :data:`EXIT_CODE_MEANINGS` holds it and ``docs/cli.md`` shows it; :data:`STOP_EXIT` maps
``summary.json``'s ``stop_kind`` to its code.

Ctrl-C at any moment is one line on stderr and exit code 130, never a traceback and never exit
code 0 (also during the start-up import and after the command's work, through the console
script :mod:`vrig_console`). In ``vrig reconstruct`` it stops the run where it is and saves what
was played (every whole iteration, the identification records, the desired response) in
``--out`` as after any other stop; a Ctrl-C while the results are being written waits until they
are written whole (seconds). ``vrig reconstruct`` holds the lock of ``--out``
(:func:`vrig.files.folder_lock`) from its argument checks to the end: a second run on the same
folder is refused (exit code 2) before it plays anything; ``vrig repeatability`` and ``vrig
check-linearity --plot`` hold the lock of their ``--out`` the same way, from their checks until
the plot is written (atomically). The test folder and the plots are
written in one swap: a full disk or a kill leaves the previous folder (or none), never new
records beside old plots.

``vrig reconstruct`` is the library's job (:mod:`vrig.job`, also ``vrig.reconstruct(...,
out=FOLDER)``): this module parses, resolves the rig's defaults, calls the job and prints. The
other commands live in :mod:`vrig.commands`, one module each.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np

from .commands import bench, check_target, demo, info, linearity, reconstruct_options, repeatability
from .commands.common import MAX_SECONDS as _MAX_SECONDS
from .commands.common import _Failure, _UsageError
from .commands.common import check_content as _check_content
from .commands.common import check_seed as _check_seed
from .commands.common import load_rig as _load_rig
from .commands.common import read_desired as _read_desired
from .commands.common import simulation_band as _band
from .commands.exit_codes import EPILOG as _EXIT_CODES
from .commands.exit_codes import EXIT_CODE_MEANINGS, STOP_EXIT, ExitCode
from .desired.kinds import TARGET_KINDS, desired_response, parse_target
from .files import file_kind
from .job import CLI_NAMES, Interrupts, ResultsJob, advice, interrupted_line, stop_line

__all__ = ["EXIT_CODE_MEANINGS", "STOP_EXIT", "ExitCode", "main"]


EXIT_OK, EXIT_FAILED, EXIT_USAGE, EXIT_BUG, EXIT_INTERRUPTED = (
    ExitCode.OK, ExitCode.FAILED, ExitCode.BAD_INPUT, ExitCode.BUG, ExitCode.INTERRUPTED,
)  # fmt: skip


# ---------------------------------------------------------------------------------------------
# parser
# ---------------------------------------------------------------------------------------------
def _parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="vrig",
        description="vrig: virtual test rigs, ARX/NARX "
        "identification and dynamic response reconstruction",
        epilog=_EXIT_CODES,
    )
    from . import __version__  # the package's one version (pyproject reads it from there)

    p.add_argument("--version", action="version", version=f"%(prog)s {__version__}")
    sub = p.add_subparsers(dest="command", required=True)
    demo._add_parser(sub, _EXIT_CODES)
    info._add_parsers(sub, _EXIT_CODES)
    reconstruct_options._add_parser(sub, _EXIT_CODES)
    bench._add_parser(sub)
    repeatability._add_parser(sub, _EXIT_CODES)
    linearity._add_parser(sub, _EXIT_CODES)
    check_target._add_parser(sub, _EXIT_CODES)
    return p


_LAW_FLAGS = {
    "law_parameters": "extra_parameters",
    "law_nperseg": "nperseg",
    "law_oversample": "oversample",
}


def _law_options(args) -> dict:
    """The Rattlesnake law's options given on the command line (``--law-parameters TEXT|@FILE``,
    ``--law-nperseg``, ``--law-oversample``) as ``RattlesnakeLaw`` keywords; a usage error when
    they are given to another method or ``@FILE`` cannot be read."""
    given = {k: getattr(args, k, None) for k in _LAW_FLAGS}
    given = {k: v for k, v in given.items() if v is not None}
    if not given:
        return {}
    if not str(args.method).startswith("rattlesnake:"):
        flag = "--" + next(iter(given)).replace("_", "-")
        raise _UsageError(f"{flag} applies to --method rattlesnake:FILE.py:NAME only")
    text = given.get("law_parameters")
    if text is not None and text.startswith("@"):
        path = Path(text[1:])
        try:
            given["law_parameters"] = path.read_text(encoding="utf-8")
        except (OSError, UnicodeDecodeError) as exc:
            raise _UsageError(f"--law-parameters @{path}: cannot read it ({exc})") from None
    return {_LAW_FLAGS[k]: v for k, v in given.items()}


def _resolve(args, rig):
    """``reconstruct``'s settings: what the user gave (None where a flag was not given) resolved
    by the one resolver every door uses (:func:`vrig.reconstruction.defaults.resolve`: the rig
    side-car's method block, then its rig block, then the built-in defaults). A method the
    side-car marks ``unsupported`` (the reference text reports it failing on the rig) runs
    anyway, after one ``warning:`` line on stderr quoting the side-car: a benchmark lets a user
    see a method do badly. A bad option is a usage error."""
    from .reconstruction import IterationSettings, MethodOptionError
    from .reconstruction.defaults import resolve

    if args.tolerance is not None and not (np.isfinite(args.tolerance) and args.tolerance > 0):
        raise _UsageError(f"--tolerance must be an η0 > 0 [%], got {args.tolerance:g}")
    options = {k: getattr(args, k, None) for k in ("order", "degree", "split_hz", "budget")}
    options["search"] = bool(getattr(args, "search", False))
    options.update(_law_options(args))
    try:
        given = IterationSettings(
            method=args.method,
            method_options={k: v for k, v in options.items() if v is not None},
            iterations=args.iterations,
            gain=args.gain,
            strategy=args.strategy,
            bandwidth=None if args.band is None else _band(rig, args.band),
            id_seed=args.seed,
            run_seed=args.seed,
            tolerance=args.tolerance,
            id_match=bool(getattr(args, "id_match", False)),
            update=getattr(args, "update", "none"),
        )
        resolved = resolve(rig, given)
    except MethodOptionError as exc:
        raise _UsageError(exc.cli) from None
    except (ValueError, TypeError) as exc:  # e.g. a Rattlesnake law's file or signature
        raise _UsageError(f"--method {args.method}: {exc}") from None
    if resolved.warning:
        text = rig.defaults.method(args.method).unsupported
        print(_unsupported_warning(args.method, rig.name, text), file=sys.stderr)
    return resolved


def _defaults_line(resolved, rig) -> str:
    """The header line of the values the resolver filled in (not given on the command line),
    each with where it came from; the band and method have lines of their own."""
    parts = []
    for name, entry in resolved.record().items():
        if entry["source"] == "caller" or name in ("method", "bandwidth"):
            continue
        value = entry["value"]
        if name == "id_rms":
            unit = rig.inputs[0].unit
            value = ", ".join(f"{v:.4g} {unit}" for v in value)
        elif isinstance(value, list):
            value = ", ".join(f"{v:g}" for v in value)
        elif isinstance(value, float):
            value = f"{value:g}"
        parts.append(f"{name} {value} ({entry['source']})")
    return "defaults  " + ("; ".join(parts) or "none: every value given")


def _unsupported_warning(method: str, rig_name: str, text: str) -> str:
    """The one-line warning of a ``--method`` the rig's side-car marks ``unsupported``: its
    ``reconstruction.methods.METHOD.unsupported`` text, quoted, and that the run goes ahead."""
    quoted = " ".join(str(text).split())
    return (
        f"warning: --method {method} on rig {rig_name!r}: the reference text reports it failing "
        f'here ("{quoted}"); running it anyway (models/<rig>/<rig>.rig.json '
        "reconstruction.methods)"
    )


def _method_stem(method: str) -> str:
    """The method's part of the default results folder name (a Rattlesnake law: its name)."""
    if method.startswith("rattlesnake:"):
        return "rattlesnake-" + method.rpartition(":")[2]
    return method


def _read_field(args, rig, band):
    """The desired (field) record: ``--desired``, else ``--target`` (a pseudo-field or a
    service record, :func:`vrig.desired.kinds.desired_response`).

    Returns (field, description, extra records)."""
    target = getattr(args, "target", None)
    if target is not None and args.desired is not None:
        raise _UsageError("give --desired FILE or --target KIND, not both")
    if target is not None and target.partition(":")[0] not in TARGET_KINDS:
        args.desired, target = target, None  # a file path given as the target
    if args.desired is None:
        seconds = 30.0 if args.seconds is None else args.seconds
        try:
            parse_target(rig, target or "pseudo-field")
        except ValueError as exc:
            raise _UsageError(f"--target: {exc}") from None
        field, source, extra = desired_response(
            rig, target or "pseudo-field", seconds, seed=args.seed, band=band
        )
        if target is not None and target != "pseudo-field":
            _check_content(field, rig)
        return field, source, extra
    field, notes = _read_desired(args.desired, rig)
    if args.seconds is not None:
        if args.seconds > field.duration:
            raise _UsageError(
                f"--seconds {args.seconds:g} is longer than the {field.duration:g} s in "
                f"{args.desired}"
            )
        field = field.window(0.0, args.seconds)
    if field.duration > _MAX_SECONDS:
        raise _UsageError(
            f"--desired {args.desired} is {field.duration:g} s long; at most "
            f"{_MAX_SECONDS:g} s are reconstructed at once: pass --seconds to use its start"
        )
    _check_content(field, rig)
    for note in notes:
        print(f"note: {note}")
    return field, f"{args.desired} ({field.duration:g} s)", {}


def _check_reconstruct_args(args) -> None:
    if args.iterations < 0 or args.iterations > 99:
        raise _UsageError(f"--iterations must be 0..99, got {args.iterations}")
    if args.gain is not None and not 0 < args.gain <= 2:
        raise _UsageError(f"--gain must lie in (0, 2], got {args.gain:g}")
    if args.seconds is not None and not (
        np.isfinite(args.seconds) and 2 <= args.seconds <= _MAX_SECONDS
    ):
        raise _UsageError(f"--seconds must be 2..{_MAX_SECONDS:g}, got {args.seconds:g}")
    _check_seed(args.seed)
    if args.desired is not None:
        try:
            kind = file_kind(args.desired)
        except OSError as exc:  # e.g. a name too long
            raise _UsageError(f"--desired {args.desired}: {exc.strerror or exc}") from None
        if kind in ("no file", "a folder"):
            what = "no file" if kind == "no file" else "a folder, not a file"
            raise _UsageError(f"--desired: {what} {args.desired}")
        if kind is not None:  # a FIFO, a device...: never "no file" (issue 25)
            raise _UsageError(f"--desired {args.desired} is not a regular file: it is {kind}")


# ---------------------------------------------------------------------------------------------
# reconstruct
# ---------------------------------------------------------------------------------------------
def _cmd_reconstruct(args) -> int:
    """``vrig reconstruct``: the job (:class:`vrig.job.ResultsJob`) holds the lock of ``--out``
    from its checks to the end of the save; this prints what it did."""
    from .errors import ReconstructionError, ReconstructionInterrupted
    from .progress import is_enabled, status

    t_start = time.perf_counter()
    _check_reconstruct_args(args)
    status(f"loading rig {args.rig} (building its simulation) ...")
    rig = _load_rig(args.rig, seed=args.seed)
    resolved = _resolve(args, rig)  # the rig side-car's defaults for what the user did not give
    band, method_text = resolved.settings.bandwidth, resolved.description
    args.gain = resolved.settings.gain  # (the advice's "a lower --gain")
    stem = f"{Path(rig.name).stem}-{_method_stem(args.method)}"
    out = Path(args.out) if args.out else Path("results") / stem
    job = ResultsJob(
        out, overwrite=args.overwrite, fmt=args.fmt, names=CLI_NAMES, interrupts=_SIGINT,
        warn=lambda text: _say("reconstruct", text),
    )  # fmt: skip
    job.check()
    if args.desired is not None:  # a file: read and check it first
        field, source, records = _read_field(args, rig, band)
    with job:  # one writer per folder, from here to the end of the save
        if args.desired is None:  # a pseudo-field response: a rig run
            field, source, records = _read_field(args, rig, band)
        job.check_space(field, rig, args.iterations)
        iteration = resolved.settings
        save = {"field": field, "records": records, "settings": _record(args, rig, method_text,
                source, iteration)}  # fmt: skip
        _print_header(rig, method_text, band, source, iteration)
        print(_defaults_line(resolved, rig), flush=True)
        try:
            result = _usage(job.run, rig, field, resolved, progress=is_enabled(), save=save)
        except ReconstructionInterrupted as exc:  # Ctrl-C: keep what was played
            result = exc.result
        except ReconstructionError as exc:  # nothing played: what was made is kept (exit 7)
            _print_saved(exc.saved, out)
            if _SIGINT.seen:  # Ctrl-C while it was saved: saved whole, then the interrupt
                raise KeyboardInterrupt from exc
            raise _Failure(str(exc), ExitCode.FAILED_IT00) from exc
        with _SIGINT.deferred():  # from here on a Ctrl-C waits until the results are written
            if result.drives:
                _print_result(result, args)
            _print_saved(job.save(result, rig, **save), out)
    print(f"time       {time.perf_counter() - t_start:.1f} s")
    if result.stop_kind == "interrupted" or _SIGINT.seen:
        _say("reconstruct", interrupted_line(result, out))
        return ExitCode.INTERRUPTED
    code = STOP_EXIT.get(result.stop_kind, ExitCode.FAILED)
    if code != ExitCode.OK:  # a script reads the code; a person reads this line
        _say("reconstruct", stop_line(result, out, args.gain, CLI_NAMES))
    return code


def _usage(func, *args, **kwargs):
    """``func(*args, **kwargs)``; a ``ValueError`` (e.g. a desired record too short for the
    model) is bad input."""
    try:
        return func(*args, **kwargs)
    except ValueError as exc:
        raise _UsageError(str(exc)) from exc


def _record(args, rig, method_text: str, source: str, iteration) -> dict:
    """``summary.json``'s ``settings``: the command line and every resolved setting."""
    return {
        "command": "vrig reconstruct",
        "argv": args.argv,
        "variant": rig.variant,
        "method": method_text,
        "gain": args.gain,
        "iterations": args.iterations,
        "seed": args.seed,
        "desired": source,
        "strategy": iteration.strategy,
        "tolerance": iteration.tolerance,
        **({"id_match": True} if iteration.id_match else {}),
        "update": iteration.update,
        "update_options": dict(iteration.update_options),
    }


def _print_header(rig, method_text: str, band, source: str, iteration) -> None:
    """The lines before the run: the rig and every resolved setting."""
    rule = iteration.update + (f" {dict(iteration.update_options)}" if iteration.update_options
                               else "")  # fmt: skip
    tolerance = "none" if iteration.tolerance is None else f"{iteration.tolerance:g} %"
    matched = ", identification matched to the desired response" if iteration.id_match else ""
    print(f"rig       {rig.name} (variant {rig.variant}): {rig.description.title}")
    print(f"method    {method_text}, gain {iteration.gain:g}, {iteration.iterations} iterations")
    print(f"update    {rule}, strategy {iteration.strategy}, tolerance {tolerance}{matched}")
    print(f"band      {band[0]:g}-{band[1]:g} Hz (simulation bandwidth)")
    print(f"desired   {source}", flush=True)


def _print_saved(written: list, out: Path) -> None:
    """The files a save wrote (none: nothing was saved, the error says so)."""
    if not written:
        return
    plots = [p for p in written if p.suffix == ".png"]
    records = [p for p in written if p.suffix != ".png"]
    names = [p.name for p in records]
    shown = names if len(names) <= 11 else [*names[:6], "...", *names[-5:]]
    print(f"\ntest folder {out}/ ({len(records)} files: {', '.join(shown)})")
    print("plots      " + (", ".join(str(p) for p in plots) or "none"))


def _advice(kind: str, stage: str, gain: float, identification: dict | None = None) -> str:
    """What to change after a stop, in the command line's words (:func:`vrig.job.advice`)."""
    return advice(kind, stage, gain, identification, CLI_NAMES)


def _print_result(result, args) -> None:
    """The per-iteration table, the best iteration's scores and why the loop stopped."""
    print()
    print(result.table())
    best = result.best_iteration
    print(
        f"\nbest      IT{best:02d}: η0 "
        + ", ".join(
            f"{n} {e:.2f} %" for n, e in zip(result.desired.names, result.errors[best], strict=True)
        )
        + "; RMS error "
        + ", ".join(f"{e:.2f} %" for e in result.rms_errors[best])
        + "; damage ratio "
        + ", ".join(f"{d:.3g}" for d in result.damage_ratio[best])
    )
    print(f"stopped   {result.stopped or f'after all {args.iterations} iterations'}")
    ident = result.identification
    if ident:
        level = ", ".join(f"{v:.3g}" for v in ident["rms_percent"])
        print(f"identification {ident['mode']}: {level} % of full scale rms; {ident['reason']}")
        if ident.get("extrapolation"):
            print(ident["extrapolation"])


_COMMANDS = {
    "demo": demo._run,
    "rigs": info._run_rigs,
    "describe": info._run_describe,
    "reconstruct": _cmd_reconstruct,
    "repeatability": repeatability._run,
    "check-linearity": linearity._run,
    "check-target": check_target._run,
}

_SIGINT = Interrupts()  # Ctrl-C: noted always, raised except while results are written


def _say(command: str, text: str) -> None:
    """One line on stderr: ``vrig COMMAND: text`` (newlines in messages are folded)."""
    print(f"vrig {command}: " + " ".join(str(text).split()), file=sys.stderr)


def _progress_mode() -> bool | None:
    """``VRIG_PROGRESS``: ``1`` progress on stderr always, ``0`` never, unset (or anything
    else) when stderr is a terminal."""
    return {"1": True, "0": False}.get(os.environ.get("VRIG_PROGRESS", "").strip())


def _run(command: str, func, arg) -> int:
    """Run a command; map every error to one line on stderr and an exit code (module doc)."""
    from .errors import (
        ERRORS,
        ControlLawError,
        FolderLockedError,
        ResultsFolderError,
        ResultsNotSavedError,
        RigModelError,
    )
    from .progress import enabled

    try:
        with enabled(_progress_mode()):
            return func(arg)
    except (_UsageError, RigModelError, FolderLockedError, ResultsFolderError) as exc:
        _say(command, exc)  # (a results folder that cannot be written, or another writer's)
        return EXIT_USAGE
    except (_Failure, ResultsNotSavedError) as exc:
        _say(command, f"failed: {exc}")
        return getattr(exc, "code", EXIT_FAILED)
    except ERRORS as exc:  # any other vrig or identification error: the run failed
        hint = " (try a narrower --band, a lower --order or --gain, or a smaller desired response)"
        if _caused_by(exc, ControlLawError):  # the law's own error: its file and line say it
            hint = ""
        _say(command, f"failed: {exc}{hint}")
        return EXIT_FAILED
    except OSError as exc:  # e.g. a disk that filled up while the results were written
        _say(command, f"failed: {exc}")
        return EXIT_FAILED
    except Exception as exc:
        if os.environ.get("VRIG_DEBUG"):
            raise
        _say(
            command,
            f"unexpected error {type(exc).__name__}: {exc} (a bug: VRIG_DEBUG=1 shows "
            "the traceback)",
        )
        return EXIT_BUG


def main(argv: list[str] | None = None) -> int:
    """The ``vrig`` command (see the module docstring); returns the exit code.

    Parameters
    ----------
    argv : list of str, optional
        The command-line arguments after the program name (``["reconstruct", "--rig",
        "shock-absorber"]``); ``None`` (default): ``sys.argv[1:]``.
    """
    raw = list(sys.argv[1:] if argv is None else argv)
    command = raw[0] if raw else "vrig"
    try:
        with _SIGINT.installed():
            if raw[:1] == ["bench"]:
                code = _run("bench", bench._run, raw[1:])
            else:
                args = _parser().parse_args(raw)
                args.argv = raw
                code = _run(args.command, _COMMANDS[args.command], args)
    except KeyboardInterrupt:
        _say(command, "interrupted")
        return EXIT_INTERRUPTED
    if _SIGINT.seen and code != EXIT_INTERRUPTED:  # an interrupt something swallowed
        _say(command, "interrupted")
        return EXIT_INTERRUPTED
    return code


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())


def _caused_by(exc: BaseException, kind: type) -> bool:
    """Whether ``exc`` or an exception in its cause chain is a ``kind``."""
    seen = set()
    while exc is not None and id(exc) not in seen:
        if isinstance(exc, kind):
            return True
        seen.add(id(exc))
        exc = exc.__cause__ or exc.__context__
    return False
