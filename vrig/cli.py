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

Exit codes (every error is one line on stderr, ``vrig COMMAND: ...``, never a traceback; a
``vrig reconstruct`` that stopped early or failed says why on one line too, with what to change,
and keeps what it made in ``--out``; the codes are the constants of :class:`ExitCode`, the stop
kinds ``summary.json``'s ``stop_kind``):

=====  ========================================================================================
0      success; ``vrig reconstruct``: every iteration played, or converged (stop kind
       completed, converged)
1      failed: the rig or the computation of another command (an interlock trip, an unstable
       simulation or model); ``vrig reconstruct``: an error of another kind after IT00 (stop
       kind failed); results that could not be written
2      bad input: arguments, ``--desired`` files, rig descriptions, results folders that cannot
       be written, plugins that do not load, ``vrig bench`` without a source checkout
3      an unexpected error (a bug: ``VRIG_DEBUG=1`` shows the traceback)
4      ``vrig reconstruct`` stopped after IT00 on an interlock trip or a refused drive (stop
       kind interlock, refused); the best iteration is kept
5      ``vrig reconstruct`` stopped after IT00 on divergence: η0 grew, the inverse model
       diverged on a response or the drive update was not finite (stop kind diverged)
6      ``vrig reconstruct`` stopped after IT00: the rig's simulation or the re-identified
       inverse model became unstable (stop kind unstable, model)
7      ``vrig reconstruct`` failed before any iteration was played: the identification drive,
       the inverse model or IT00DRV (the identification records, model and refused drive are
       kept)
130    interrupted (Ctrl-C); ``vrig reconstruct`` keeps the iterations played in ``--out`` (stop
       kind interrupted)
=====  ========================================================================================

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
"""

from __future__ import annotations

import argparse
import contextlib
import enum
import errno
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

import numpy as np

from .desired.kinds import TARGET_KINDS, desired_response, parse_target
from .desired.pseudo_field import pseudo_field
from .files import file_kind, mount_points
from .reconstruction.defaults import default_band

__all__ = ["EXIT_CODE_MEANINGS", "STOP_EXIT", "ExitCode", "main"]


class _MethodChoices(tuple):
    """``--method``'s choices: the built-in names (listed in the help and the error), and any
    ``rattlesnake:FILE.py:NAME`` (:func:`vrig.reconstruction.vocabulary.is_method_name`)."""

    def __contains__(self, value) -> bool:
        return super().__contains__(value) or (
            isinstance(value, str) and value.startswith("rattlesnake:")
        )


_METHODS = _MethodChoices(("arx", "narx", "split", "frf", "error-signal"))
_DEMO_SAMPLES = (2000, 100_000)  # = vrig.demo's MIN/MAX_SAMPLES (454 terms per output)
DEFAULT_GAIN = 0.8  # reconstruct's iteration gain unless the rig's side-car names its own
_MAX_SECONDS = 3600.0  # longest record a command plays or reconstructs (--seconds, --desired)


class ExitCode(enum.IntEnum):
    """The exit codes of ``vrig`` (the table of the :mod:`vrig.cli` documentation)."""

    OK = 0
    FAILED = 1
    BAD_INPUT = 2
    BUG = 3
    STOPPED_INTERLOCK = 4
    STOPPED_DIVERGED = 5
    STOPPED_UNSTABLE = 6
    FAILED_IT00 = 7
    INTERRUPTED = 130


EXIT_OK, EXIT_FAILED, EXIT_USAGE, EXIT_BUG, EXIT_INTERRUPTED = (
    ExitCode.OK, ExitCode.FAILED, ExitCode.BAD_INPUT, ExitCode.BUG, ExitCode.INTERRUPTED,
)  # fmt: skip

STOP_EXIT = {
    "completed": ExitCode.OK,
    "converged": ExitCode.OK,
    "interlock": ExitCode.STOPPED_INTERLOCK,
    "refused": ExitCode.STOPPED_INTERLOCK,
    "diverged": ExitCode.STOPPED_DIVERGED,
    "unstable": ExitCode.STOPPED_UNSTABLE,
    "model": ExitCode.STOPPED_UNSTABLE,
    "failed": ExitCode.FAILED,
    "interrupted": ExitCode.INTERRUPTED,
}
"""``vrig reconstruct``'s exit code for each ``result.stop_kind`` of a reconstruction that played
IT00 (one that did not exits :attr:`ExitCode.FAILED_IT00`)."""


def _exit_code_table(doc: str | None) -> dict[int, str]:
    """``{code: meaning}`` from the exit-code table of the module documentation (reST markup
    removed, continuation lines joined)."""
    lines = (doc or "").splitlines()
    start = next((i for i, line in enumerate(lines) if line.startswith("Exit codes")), None)
    if start is None:  # python -OO drops docstrings: the names of the constants
        return {int(c): c.name.lower().replace("_", " ") for c in ExitCode}
    rows: dict[int, str] = {}
    code = None
    for line in lines[start:]:
        head = line[:7].strip()
        if head.isdigit():
            code = int(head)
            rows[code] = line[7:].strip()
        elif code is not None and line.startswith(" " * 7) and line.strip():
            rows[code] += " " + line.strip()
        elif rows and line.startswith("====="):
            break
    return {k: v.replace("``", "") for k, v in rows.items()}


EXIT_CODE_MEANINGS = _exit_code_table(__doc__)
"""``{code: meaning}``: the module documentation's table, from which the ``--help`` epilog is
made (one table: the two cannot drift)."""
_EXIT_CODES = "exit codes: " + "; ".join(f"{k} {v}" for k, v in EXIT_CODE_MEANINGS.items())


class _UsageError(Exception):
    """A bad argument: reported with the command's name, exit code 2."""


class _Failure(Exception):
    """The rig or the iteration failed: reported with the command's name and exit code ``code``
    (default 1)."""

    def __init__(self, message: str, code: int = ExitCode.FAILED):
        super().__init__(message)
        self.code = code


# ---------------------------------------------------------------------------------------------
# parser
# ---------------------------------------------------------------------------------------------
def _whole_number(text: str) -> int:
    """An integer argument, also written as ``2e4``: its range is checked by the command."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
    if not (np.isfinite(value) and value == int(value)):
        raise argparse.ArgumentTypeError(f"not a whole number: {text!r}")
    return int(value)


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
    _add_demo_parser(sub)
    _add_rig_info_parsers(sub)
    _add_reconstruct_parser(sub)
    _add_bench_parser(sub)
    _add_repeatability_parser(sub)
    _add_linearity_parser(sub)
    _add_check_target_parser(sub)
    return p


def _add_demo_parser(sub) -> None:
    """Add the `demo` subcommand: identify and simulate a generated NARX system."""
    demo = sub.add_parser(
        "demo", help="identify and simulate a generated non-linear MIMO system", epilog=_EXIT_CODES
    )
    demo.add_argument(
        "--seed", type=int, default=0, help="random seed, an integer >= 0 (default 0)"
    )
    demo.add_argument(
        "--samples",
        type=_whole_number,
        default=20_000,
        help=f"record length {_DEMO_SAMPLES[0]}..{_DEMO_SAMPLES[1]} (default 20000; 2e4 is "
        "accepted)",
    )
    demo.add_argument(
        "--noise",
        type=float,
        default=0.01,
        help="output noise as a fraction of the output std (default 0.01)",
    )


def _add_rig_info_parsers(sub) -> None:
    """Add the `rigs` and `describe` subcommands."""
    sub.add_parser("rigs", help="list the shipped rigs")
    desc = sub.add_parser(
        "describe", help="a rig's channels, limits and parameters", epilog=_EXIT_CODES
    )
    desc.add_argument("rig", help="rig name (see `vrig rigs`) or a user rig's .rig.json/.xml")


def _add_reconstruct_parser(sub) -> None:
    """Add the `reconstruct` subcommand: drive iteration on a rig."""
    rec = sub.add_parser(
        "reconstruct",
        help="drive iteration: reproduce a desired response on a rig",
        description="Identify the rig's inverse model, iterate the drive towards the desired "
        "response, print the per-iteration error table and write the QanTiM test folder and "
        "plots. Without --desired the desired response is a pseudo-field response: the rig's "
        "response to a road-like random drive (triangular PSD over the simulation band).",
        epilog=_EXIT_CODES,
    )
    rec.add_argument("--rig", required=True, help="rig name (see `vrig rigs`) or rig file")
    _add_model_arguments(rec)
    rec.add_argument(
        "--desired",
        metavar="FILE",
        help="desired response (.rsp/.drv/.tim RPC III, .csv, .mat, .npz) with the rig's "
        "response channels (`vrig describe RIG`) at the rig's sample rate. CSV: UTF-8, a header "
        "row 'time,<name> [<unit>],...' (first column time [s], uniformly spaced: it gives the "
        "sample rate; one column per response, matched by name, else by position), then one "
        "row of numbers per sample, comma-separated; a file without the header row is refused",
    )
    rec.add_argument(
        "--target",
        metavar="KIND",
        help="desired response to generate when no --desired file is given: 'pseudo-field' "
        "(default: the rig's response to a road-like random drive), 'field:SCENARIO' (the rig's "
        "specimen in its vehicle driven over a road: a service record, `vrig describe RIG` lists "
        "the scenarios) or 'field' (the rig's first scenario); a file path works as --desired",
    )
    rec.add_argument("--iterations", type=int, default=5, help="iterations after IT00 (default 5)")
    rec.add_argument(
        "--gain",
        type=float,
        help=f"iteration gain in (0, 2] (default: the rig side-car's "
        f"reconstruction.methods.METHOD.gain, else reconstruction.gain, else {DEFAULT_GAIN:g})",
    )
    rec.add_argument(
        "--band",
        type=float,
        nargs=2,
        metavar=("LOW", "HIGH"),
        help="simulation bandwidth [Hz] (default: the rig's test band; shaker 10-60 Hz because "
        "its accelerometer is deaf below 10 Hz)",
    )
    rec.add_argument(
        "--seconds",
        type=float,
        help="length of the generated record (--target, default 30 s); with --desired, use "
        "only the first SECONDS of the file",
    )
    rec.add_argument("--seed", type=int, default=0, help="random seed, an integer >= 0 (default 0)")
    rec.add_argument(
        "--format",
        dest="fmt",
        choices=("rsp", "csv", "mat", "npz"),
        default="rsp",
        help="record format of the test folder (default rsp: RPC III .drv/.rsp)",
    )
    rec.add_argument("--out", help="results folder (default ./results/<rig>-<method>)")
    rec.add_argument(
        "--overwrite", action="store_true", help="replace the records of an existing results folder"
    )


def _add_model_arguments(rec) -> None:
    """Add ``reconstruct``'s inverse-model and iteration-strategy options (defaults: the rig
    side-car's ``reconstruction`` block, :func:`_defaults`)."""
    rec.add_argument(
        "--method",
        choices=_METHODS,
        default="arx",
        help="inverse model: arx (QanTiM), narx, split (split spectra), frf (H1, RPC-style), "
        "error-signal (ARX + NARX of its drive error, §5.5.4); default arx. A method the "
        "reference text reports as failing on the rig runs after a one-line warning quoting "
        "it (the rig's side-car: reconstruction.methods.METHOD.unsupported, models/README.md). "
        "rattlesnake:FILE.py:NAME runs a Sandia Rattlesnake transient control law (function, "
        "generator or class NAME in FILE.py) on vrig's identification (docs/reconstruction.md)",
    )
    rec.add_argument(
        "--order",
        type=int,
        help="model order (arx/narx/split/error-signal; default: the rig side-car's "
        "reconstruction.methods.METHOD.order, else 4; error-signal: 3)",
    )
    rec.add_argument(
        "--degree",
        type=int,
        help="NARX polynomial degree (narx: default 2; split: makes the low band NARX; "
        "error-signal: of the error NARX, default 2)",
    )
    rec.add_argument(
        "--search",
        action="store_true",
        help="narx: search the inverse's structure and fitting options by free-run validation "
        "(orders up to twice --order, degrees 1..--degree, least squares / simulation focus, "
        "all / FROLS / SEMP terms; identification.NarxSearch) instead of fitting one model",
    )
    rec.add_argument(
        "--budget",
        type=float,
        metavar="S",
        help="seconds the --search may take (default 60)",
    )
    rec.add_argument(
        "--split-hz",
        type=float,
        help="split frequency [Hz] (split; default: the rig side-car's, else the geometric mean "
        "of the band, or a quarter of its upper edge for a band from 0 Hz)",
    )
    rec.add_argument(
        "--strategy",
        choices=("fixed", "adaptive"),
        default="fixed",
        help="fixed: one inverse model for the whole iteration (QanTiM; default); adaptive: "
        "re-identified from the latest drive and response before every update",
    )
    rec.add_argument(
        "--update",
        choices=("none", "frf", "secant", "reidentify", "ilc"),
        default="none",
        help="how the correction model learns from the iteration (vrig.reconstruction.updates): "
        "none (default: the inverse identified before IT00), frf (H1 FRF updated from every "
        "record, TWR-style), secant (per-band Broyden update), reidentify (the method refitted "
        "on identification + iteration records), ilc (norm-optimal ILC); not with --strategy "
        "adaptive",
    )
    rec.add_argument(
        "--tolerance",
        type=float,
        metavar="PCT",
        help="stop as soon as every channel's η0 [%%] is at or below PCT (default: play all "
        "--iterations)",
    )
    rec.add_argument(
        "--id-match",
        action="store_true",
        help="identify matched to the desired response (§3.3-3.4): a short probe measures the "
        "rig's FRF, the identification drive's PSD is shaped from the desired response and its "
        "level raised until the identification responses reach the desired RMS and peaks "
        "(within the drives' full scale); default: a triangular random drive at 5 %% of full "
        "scale (or the rig side-car's level), which a large, slow, non-Gaussian target outgrows",
    )


def _add_bench_parser(sub) -> None:
    """Add the `bench` subcommand: passes its arguments on to the benchmark runner."""
    bench = sub.add_parser(
        "bench",
        help="the reconstruction benchmark runner (= python -m benchmarks; source checkout)",
        add_help=False,
    )
    bench.add_argument("args", nargs=argparse.REMAINDER, help="run|report|list and options")


def _add_repeatability_parser(sub) -> None:
    """Add the `repeatability` subcommand."""
    rep = sub.add_parser(
        "repeatability",
        help="play one random drive several times: the repeatability number of §3.1 (in the drive "
        "band), R_f and SNR per channel",
        epilog=_EXIT_CODES,
    )
    rep.add_argument("--rig", required=True, help="rig name (see `vrig rigs`) or rig file")
    rep.add_argument("--runs", type=int, default=5, help="number of runs (default 5, as §3.1)")
    rep.add_argument("--seconds", type=float, default=20.0, help="drive length (default 20 s)")
    rep.add_argument(
        "--band",
        type=float,
        nargs=2,
        metavar=("LOW", "HIGH"),
        help="drive band [Hz] (default: the band of the text's repeatability test of the rig "
        "where the side-car gives one, else as for reconstruct)",
    )
    rep.add_argument("--seed", type=int, default=0, help="random seed, an integer >= 0 (default 0)")
    rep.add_argument("--out", help="folder of the plot (default ./results/<rig>-repeatability)")


def _add_linearity_parser(sub) -> None:
    """Add the `check-linearity` subcommand."""
    lin = sub.add_parser(
        "check-linearity",
        help="is the rig non-linear? mean-level, scaling, coherence and ARX-vs-NARX tests",
        description="Play a band-limited random drive u on the rig (and 2u, -u, u again, zero, "
        "an offset b and u + b), judge each test against the measured noise floor and print "
        "the evidence; the last line is 'verdict: linear' or 'verdict: non-linear' (exit 0 "
        "either way). The rule is in vrig.linearity's documentation.",
        epilog=_EXIT_CODES,
    )
    lin.add_argument("--rig", required=True, help="rig name (see `vrig rigs`) or rig file")
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
    lin.add_argument(
        "--band",
        type=float,
        nargs=2,
        metavar=("LOW", "HIGH"),
        help="drive band [Hz] (default: the band of the text's repeatability test of the rig "
        "where the side-car gives one, else as for reconstruct)",
    )
    lin.add_argument("--seed", type=int, default=0, help="random seed, an integer >= 0 (default 0)")
    lin.add_argument("--plot", action="store_true", help="write linearity.png into --out")
    lin.add_argument("--out", help="folder of the plot (default ./results/<rig>-linearity)")


def _add_check_target_parser(sub) -> None:
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
        epilog=_EXIT_CODES,
    )
    chk.add_argument("--rig", required=True, help="rig name (see `vrig rigs`) or rig file")
    chk.add_argument(
        "--desired",
        required=True,
        metavar="FILE",
        help="desired response with the rig's response channels at the rig's sample rate "
        "(formats as for `vrig reconstruct --desired`)",
    )
    chk.add_argument(
        "--band",
        type=float,
        nargs=2,
        metavar=("LOW", "HIGH"),
        help="simulation bandwidth [Hz] (default as for reconstruct)",
    )
    chk.add_argument(
        "--seconds",
        type=float,
        help="length of the identification run [s] (default: the desired record's length)",
    )
    chk.add_argument("--seed", type=int, default=0, help="random seed, an integer >= 0 (default 0)")


# ---------------------------------------------------------------------------------------------
# helpers
# ---------------------------------------------------------------------------------------------
def _load_rig(name: str, *, seed: int = 0):
    from . import list_rigs, load_rig

    if not name.endswith((".json", ".xml")) and name not in list_rigs():
        raise _UsageError(f"unknown rig {name!r}; available rigs: {', '.join(list_rigs())}")
    if name.endswith((".json", ".xml")) and not Path(name).is_file():
        raise _UsageError(f"no rig file {name}")
    return load_rig(name, seed=seed)


def _check_seed(seed: int) -> None:
    if seed < 0:
        raise _UsageError(f"--seed must be an integer >= 0, got {seed}")


def _check_writable(path: Path, flag: str = "--out") -> None:
    """Before the run: ``path`` is (or can be made) a folder this process can write into.

    Creates what is missing and a temporary file to prove it, then removes both again."""
    created = []
    try:
        for p in [*reversed(path.parents), path]:
            if not p.exists():
                p.mkdir()
                created.append(p)
            elif not p.is_dir():
                raise _UsageError(f"{flag} {path}: {p} is a file, not a folder")
        fd, probe = tempfile.mkstemp(dir=path, prefix=".vrig-write-test-")
        os.close(fd)
        os.unlink(probe)
    except OSError as exc:
        why = exc.strerror or str(exc)
        raise _UsageError(f"{flag} {path}: cannot write there ({why})") from None
    finally:
        for p in reversed(created):
            with contextlib.suppress(OSError):
                p.rmdir()


def _band(rig, band) -> tuple[float, float]:
    if band is None:
        return default_band(rig)
    lo, hi = (float(b) for b in band)
    if not (np.isfinite(lo) and np.isfinite(hi) and 0 <= lo < hi < rig.fs / 2):
        raise _UsageError(
            f"--band {lo:g} {hi:g}: need 0 <= LOW < HIGH < fs/2 = {rig.fs / 2:g} Hz for rig "
            f"{rig.name!r}"
        )
    return lo, hi


def _check_desired(desired, rig):
    """Match a read desired record to the rig's responses (by name, else by position)."""
    names = [c.name for c in rig.outputs]
    if abs(desired.fs - rig.fs) > 1e-6 * rig.fs:
        raise _UsageError(
            f"--desired is sampled at {desired.fs:g} Hz but rig {rig.name!r} runs at "
            f"{rig.fs:g} Hz: resample it first"
        )
    desired = type(desired)(desired.data, rig.fs, desired.names, desired.units)  # exact fs
    notes = []
    if all(n in desired.names for n in names):
        if list(desired.names) != names:
            notes.append(f"using channels {names} of the {desired.n_channels} in the file")
        desired = desired[names]
    elif desired.n_channels == len(names):
        notes.append(
            f"channel names {list(desired.names)} differ from the rig's responses {names}: "
            "matched by position"
        )
        desired = type(desired)(desired.data, desired.fs, names, desired.units)
    else:
        raise _UsageError(
            f"--desired has {desired.n_channels} channels {list(desired.names)} but rig "
            f"{rig.name!r} has {len(names)} responses {names}"
        )
    units = [c.unit for c in rig.outputs]
    if list(desired.units) != units:
        notes.append(f"units {list(desired.units)} differ from the rig's {units}")
    return desired, notes


def _check_content(desired, rig) -> None:
    """The desired record (as it will be used) is something the rig can reproduce."""
    data = np.asarray(desired.data)
    for k, c in enumerate(rig.outputs):
        peak = float(np.max(np.abs(data[:, k])))
        if peak > c.full_scale:
            raise _UsageError(
                f"--desired channel {c.name!r} peaks at {peak:.6g} {c.unit}, beyond the rig's "
                f"transducer range ±{c.full_scale:g} {c.unit}: the rig cannot produce it"
            )
        if np.ptp(data[:, k]) == 0:
            raise _UsageError(
                f"--desired channel {c.name!r} is constant: there is nothing to reconstruct"
            )


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
        print(
            _unsupported_warning(
                args.method, rig.name, rig.defaults.method(args.method).unsupported
            ),
            file=sys.stderr,
        )
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


def _out_dir(out, default: str, overwrite: bool) -> Path:
    path = Path(out) if out else Path("results") / default
    try:
        _check_out_dir(path, overwrite)
    except OSError as exc:  # e.g. a name too long for the file system: bad input, up front
        raise _UsageError(f"--out {path}: {exc.strerror or exc}") from None
    return path


def _check_out_dir(path: Path, overwrite: bool) -> None:
    """``--out`` before anything runs: a folder (or nothing yet), empty unless ``--overwrite``,
    and one the save may replace: not the working directory or a folder holding it (the shell
    would be left in a deleted directory), not a mount point and holding none (a mounted file
    system would be emptied: :func:`vrig.files.mount_points`)."""
    if path.exists() and not path.is_dir():
        raise _UsageError(f"--out {path} is a file, not a folder")
    if not path.is_dir():
        return
    if any(path.iterdir()) and not overwrite:
        raise _UsageError(
            f"results folder {path} is not empty: pass --overwrite to replace its records, or "
            "choose another --out"
        )
    here, target = Path.cwd().resolve(), path.resolve()
    if target == here or target in here.parents:
        raise _UsageError(
            f"--out {path} is the current directory or holds it: the results folder is replaced "
            "as a whole, which would leave your shell in a deleted directory; choose a new "
            "folder (e.g. --out results)"
        )
    mounted = mount_points(path)
    if mounted:
        raise _UsageError(
            f"--out {path}: {mounted[0]} is a mount point; replacing the folder would empty a "
            "mounted file system (or fail to move it): choose another --out"
        )


# ---------------------------------------------------------------------------------------------
# commands
# ---------------------------------------------------------------------------------------------
def _cmd_rigs(args) -> int:
    from .rigs import list_rigs, rig_path
    from .rigs.spec import read_description

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


def _cmd_describe(args) -> int:
    rig = _load_rig(args.rig)
    print(rig.describe())
    return 0


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


def _read_desired(path, rig):
    """Read a ``--desired`` file and match it to the rig's responses (:func:`_check_desired`):
    (record, notes)."""
    from . import io

    try:
        field = io.read(path)
    except Exception as exc:  # whatever a damaged file makes the reader raise: bad input
        raise _UsageError(f"--desired: cannot read {path}: {exc}") from None
    return _check_desired(field, rig)


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


def _cmd_reconstruct(args) -> int:
    with contextlib.ExitStack() as hold:  # the results folder's lock, held to the end
        return _reconstruct_holding(args, hold)


def _reconstruct_holding(args, hold: contextlib.ExitStack) -> int:
    """``vrig reconstruct``; ``hold`` keeps the results folder's lock (:func:`_hold_out`)."""
    from .errors import ReconstructionInterrupted
    from .progress import status

    t_start = time.perf_counter()
    _check_reconstruct_args(args)
    status(f"loading rig {args.rig} (building its simulation) ...")
    rig = _load_rig(args.rig, seed=args.seed)
    resolved = _resolve(args, rig)  # the rig side-car's defaults for what the user did not give
    band, gain = resolved.settings.bandwidth, resolved.settings.gain
    args.gain = gain  # (the advice's "a lower --gain")
    method_text = resolved.description
    default_out = f"{Path(rig.name).stem}-{_method_stem(args.method)}"
    out = _out_dir(args.out, default_out, args.overwrite)
    if args.desired is not None:  # a file: read and check it first
        field, source, records = _read_field(args, rig, band)
    _check_writable(out)  # before the run, not after it
    _hold_out(hold, out)  # one writer per folder, from here to the end of the save
    out = _out_dir(args.out, default_out, args.overwrite)  # locked
    if args.desired is None:  # a pseudo-field response: a rig run
        field, source, records = _read_field(args, rig, band)
    _check_space(out, field, rig, args)
    print(f"rig       {rig.name} (variant {rig.variant}): {rig.description.title}")
    print(f"method    {method_text}, gain {gain:g}, {args.iterations} iterations")
    print(_defaults_line(resolved, rig))
    print(f"band      {band[0]:g}-{band[1]:g} Hz (simulation bandwidth)")
    print(f"desired   {source}", flush=True)
    settings = {
        "command": "vrig reconstruct",
        "argv": args.argv,
        "variant": rig.variant,
        "method": method_text,
        "gain": args.gain,
        "iterations": args.iterations,
        "seed": args.seed,
        "desired": source,
        "strategy": args.strategy,
        "tolerance": args.tolerance,
        "update": resolved.settings.update,
        **({"id_match": True} if resolved.settings.id_match else {}),
    }
    save = {"field": field, "records": records, "settings": settings}
    try:
        result = _reconstruct(rig, field, resolved, args, out, save)
    except ReconstructionInterrupted as exc:  # Ctrl-C: keep what was played
        result = exc.result
    with _SIGINT.deferred():  # from here on a Ctrl-C waits until the results are written
        if result.drives:
            _print_result(result, args)
        _save(result, out, rig, args, save)
    print(f"time       {time.perf_counter() - t_start:.1f} s")
    if result.stop_kind == "interrupted" or _SIGINT.seen:
        _say("reconstruct", _interrupted_line(result, out))
        return ExitCode.INTERRUPTED
    code = STOP_EXIT.get(result.stop_kind, ExitCode.FAILED)
    if code != ExitCode.OK:  # a script reads the code; a person reads this line
        best = result.best_iteration
        _say(
            "reconstruct",
            f"stopped: {result.stopped} "
            f"({_advice(result.stop_kind, 'after IT00', args.gain, result.identification)}); "
            f"best IT{best:02d} kept as FINDRV01/FINRES01 in {out}/",
        )
    return code


def _interrupted_line(result, out: Path) -> str:
    """The one line of a reconstruction Ctrl-C stopped (its results saved in ``out``)."""
    n = len(result.drives)
    if result.stop_kind != "interrupted":  # Ctrl-C came after the run, during the save
        return f"interrupted while the results were saved: saved whole in {out}/"
    where = result.stopped.split(":", 1)[0]
    if not n:
        return f"interrupted ({where}): no iteration played; kept what was made in {out}/"
    best = result.best_iteration
    played = "IT00" if n == 1 else f"IT00-IT{n - 1:02d}"
    return (
        f"interrupted at {where}: kept the {n} iteration(s) played ({played}; best IT{best:02d} "
        f"as FINDRV01/FINRES01) in {out}/"
    )


def _hold_out(hold: contextlib.ExitStack, out: Path) -> None:
    """Take the lock of the results folder ``out`` (:func:`vrig.files.folder_lock`) for the
    rest of the command: a second run on the folder is refused here, before it plays anything.
    Folders made for the lock file are removed again when the command saves nothing."""
    from .errors import FolderLockedError
    from .files import folder_lock

    missing = [p for p in out.absolute().parents if not p.exists()]  # deepest first
    hold.callback(_remove_empty, missing)  # after the lock's release (last in, first out)
    try:
        hold.enter_context(folder_lock(out, timeout=0))
    except FolderLockedError as exc:
        raise _UsageError(f"--out: {exc}") from None
    except OSError as exc:  # the lock file, like the swap, lives in the parent folder
        why = exc.strerror or str(exc)
        raise _UsageError(
            f"--out {out}: cannot write in its parent folder {out.absolute().parent} ({why}); "
            "the results folder is replaced in one swap, made beside it"
        ) from None


def _remove_empty(folders: list[Path]) -> None:
    for p in folders:
        with contextlib.suppress(OSError):
            p.rmdir()


_RECORD_BYTES = {"rsp": 4, "npz": 8, "mat": 8, "csv": 25}  # per sample and channel, about


def _check_space(out: Path, field, rig, args) -> None:
    """Before the run: the disk holding ``out`` has room for the records (identification,
    desired, three per iteration, final) and the plots, or the run is refused."""
    n_in, n_out = len(rig.inputs), len(rig.outputs)
    per_iteration = n_in + 2 * n_out
    channels = 2 * n_in + 3 * n_out + (args.iterations + 2) * per_iteration
    samples = getattr(field, "n_samples", 0)  # (the identification is as long as the record)
    need = samples * channels * _RECORD_BYTES[args.fmt] + 4 * 1024**2  # + the plots
    where = next(p for p in [out.absolute(), *out.absolute().parents] if p.exists())
    try:
        free = shutil.disk_usage(where).free
    except OSError:
        return
    if free < need:
        raise _UsageError(
            f"--out {out}: the results need about {need / 1e6:.0f} MB and the disk holding it "
            f"has {free / 1e6:.0f} MB free: free some space or choose another --out"
        )


def _reconstruct(rig, field, resolved, args, out: Path, save: dict):
    """Run the reconstruction with the resolved settings (:func:`_resolve`); a failure before
    IT00 saves what was made and raises :class:`_Failure` (exit code 7)."""
    from .errors import ReconstructionError
    from .progress import is_enabled
    from .reconstruction import reconstruct

    try:
        return reconstruct(rig, field, resolved, progress=is_enabled())
    except ValueError as exc:  # e.g. a desired record too short for the model: bad input
        raise _UsageError(str(exc)) from exc
    except ReconstructionError as exc:  # nothing played: keep what was made, say what to change
        advice = _advice(exc.result.stop_kind, exc.stage, args.gain, exc.result.identification)
        try:
            written = _save(exc.result, out, rig, args, save)
        except _Failure as failed:
            raise _Failure(f"{exc} ({advice}); {failed}", ExitCode.FAILED_IT00) from exc
        if _SIGINT.seen:  # Ctrl-C while it was saved: saved whole, then the interrupt
            raise KeyboardInterrupt from exc
        raise _Failure(
            f"{exc} ({advice}); kept {', '.join(p.name for p in written)} in {out}/",
            ExitCode.FAILED_IT00,
        ) from exc


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


def _save(result, out: Path, rig, args, save: dict) -> list[Path]:
    """Write the test folder and the plots of a result (also one with no iteration played), in
    one swap (:meth:`TestFolder.save` with ``plots=True``). Ctrl-C waits until the save is
    done (it is noted in ``_SIGINT``). A disk that fills up: saved again without the plots;
    when that fails too, :class:`_Failure` says that nothing was saved."""
    from .progress import status

    with _SIGINT.deferred():
        status("checking the target's reachability (the identification records: no rig run) ...")
        check = {"target_check": _target_check(rig, result)}
        status(f"writing the test folder {out}/ ...")
        try:
            written = _write_folder(result, out, rig, args, save, check, plots=True)
        except OSError as exc:
            if exc.errno not in _DISK_FULL:
                raise _Failure(_nothing_saved(out, exc)) from exc
            try:  # the records matter, the plots can be drawn again from them
                written = _write_folder(result, out, rig, args, save, check, plots=False)
            except OSError as again:
                raise _Failure(_nothing_saved(out, again)) from again
            _say("reconstruct", f"warning: {exc.strerror or exc}: saved the records and "
                 f"summary in {out}/ without the plots")  # fmt: skip
    plots = [p for p in written if p.suffix == ".png"]
    records = [p for p in written if p.suffix != ".png"]
    names = [p.name for p in records]
    shown = names if len(names) <= 11 else [*names[:6], "...", *names[-5:]]
    print(f"\ntest folder {out}/ ({len(records)} files: {', '.join(shown)})")
    print("plots      " + (", ".join(str(p) for p in plots) or "none"))
    return written


_DISK_FULL = {errno.ENOSPC, getattr(errno, "EDQUOT", errno.ENOSPC), errno.EFBIG}


def _write_folder(result, out: Path, rig, args, save: dict, check: dict, *, plots: bool):
    from .testfolder import TestFolder

    return TestFolder(out).save(
        result, fmt=args.fmt, rig=rig, overwrite=args.overwrite, summary_extra=check,
        plots=plots, lock_timeout=0, **save,
    )  # fmt: skip


def _nothing_saved(out: Path, exc: OSError) -> str:
    """The message of a save that failed: nothing was written (the save is one swap)."""
    kept = "keeps its previous contents" if out.is_dir() else "was not created"
    return (
        f"the results could not be written ({exc.strerror or exc}): nothing was saved, {out}/ "
        f"{kept}"
    )


def _target_check(rig, result) -> dict:
    """:func:`vrig.desired.reachability.check_target` of DESRES from the reconstruction's own identification
    records (no rig run) as ``summary.json``'s ``target_check``; a failure is recorded as
    ``{"error": ...}``, never raised (it must not lose the run)."""
    from .desired.reachability import check_target

    if result.id_drive is None or result.id_response is None:
        return {"error": "no identification records: the identification drive was not played"}
    try:
        check = check_target(
            rig,
            result.desired,
            band=result.bandwidth,
            id_drive=result.id_drive,
            id_response=result.id_response,
        )
    except Exception as exc:  # whatever it is, the reconstruction's records come first
        return {"error": f"{type(exc).__name__}: {exc}"}
    return check.to_dict()


_NARROWER = "a narrower --band, a lower --order or --method frf"
_ADVICE = {
    # (stage, stop kind) -> what to change; stage "identification", "model", "IT00" (nothing
    # played: the gain plays no role) or "after IT00" (an iteration stopped: the gain does)
    ("identification", "interlock"): "the identification drive trips the rig even at 1/1024 of "
    "its amplitude (TRIPPEDID): check the rig's limits, or use a narrower --band",
    ("identification", "refused"): "the identification drive is beyond the drives' full scale "
    "even at 1/1024 of its amplitude (REFUSEDID): check the rig's limits",
    ("identification", "unstable"): "the rig's simulation became unstable under the "
    "identification drive: check the rig model (time step, parameters) or use a narrower --band",
    ("model", "diverged"): "the inverse model diverges on the desired response: try a lower "
    "--order, --method frf or a narrower --band",
    ("model", None): "the inverse model could not be fitted: try a lower --order, --method arx "
    "or frf, or a narrower --band",
    ("IT00", "refused"): "IT00DRV, the inverse model's first drive, needs more than the drive's "
    "full scale (refused_drive_vs_limits.png): use " + _NARROWER + ", or a smaller desired "
    "response",
    ("IT00", "interlock"): "IT00DRV, the inverse model's first drive, tripped the rig "
    "(TRIPPED00): use " + _NARROWER + ", or a smaller desired response",
    ("IT00", "unstable"): "the rig's simulation became unstable under IT00DRV (TRIPPED00): use "
    + _NARROWER
    + ", or a smaller desired response",
    ("after IT00", "interlock"): "a lower --gain, e.g. {half}, overshoots less",
    ("after IT00", "refused"): "a lower --gain, e.g. {half}, overshoots less",
    ("after IT00", "diverged"): "a lower --gain, e.g. {half}, or --strategy adaptive "
    "(re-identify the inverse model from each iteration)",
    ("after IT00", "unstable"): "the rig's simulation became unstable under the drive: a lower "
    "--gain, e.g. {half}",
    ("after IT00", "model"): "the re-identified inverse model is unstable: a lower --order, or "
    "the fixed strategy",
}


def _advice(kind: str, stage: str, gain: float, identification: dict | None = None) -> str:
    """What to change after a reconstruction that stopped (``stage`` ``"after IT00"``) or could
    not play any iteration (``stage`` ``"identification"``, ``"model"``, ``"IT00"``), by the
    kind of stop (``result.stop_kind``). A drive that overshot (refused, a trip, divergence)
    from a polynomial inverse identified below the target's peak (``identification``'s
    ``"extrapolation"`` note) is the identification's doing, not the gain's: ``--id-match``."""
    overshoot = kind in ("refused", "interlock", "diverged") and stage in ("IT00", "after IT00")
    if overshoot and (identification or {}).get("extrapolation"):
        return (
            "the polynomial inverse was identified below the target's peak and extrapolates "
            "(the note above): --id-match identifies it over the target's range"
        )
    text = _ADVICE.get((stage, kind)) or _ADVICE.get((stage, None))
    if text is None:
        return (
            "try " + _NARROWER + ", or a smaller desired response"
            if stage != "after IT00"
            else "try a lower --gain, e.g. {half}, or " + _NARROWER
        ).format(half=f"{gain / 2:g}")
    return text.format(half=f"{gain / 2:g}")


def _cmd_repeatability(args) -> int:
    with contextlib.ExitStack() as hold:  # the plot folder's lock, from the checks to the end
        return _repeatability(args, hold)


def _repeatability(args, hold: contextlib.ExitStack) -> int:
    """``vrig repeatability``; ``hold`` keeps the lock of ``--out`` (:func:`_hold_out`)."""
    from .plots import repeatability_plot, save_figure
    from .progress import bar
    from .repeatability import repeatability_function, repeatability_number, signal_to_noise

    if not 2 <= args.runs <= 50:
        raise _UsageError(f"--runs must be 2..50 (the text uses 5), got {args.runs}")
    if not (np.isfinite(args.seconds) and 2 <= args.seconds <= _MAX_SECONDS):
        raise _UsageError(f"--seconds must be 2..{_MAX_SECONDS:g}, got {args.seconds:g}")
    _check_seed(args.seed)
    rig = _load_rig(args.rig, seed=args.seed)
    text = getattr(getattr(rig, "description", None), "repeatability", None) or {}
    band = _band(rig, text["band"] if args.band is None and text else args.band)
    out = Path(args.out) if args.out else Path("results") / f"{Path(rig.name).stem}-repeatability"
    if out.exists() and not out.is_dir():
        raise _UsageError(f"--out {out} is a file, not a folder")
    _check_writable(out)  # before the runs, not after them
    _hold_out(hold, out)  # one writer per folder: a second one is refused before its runs

    drive, first = pseudo_field(rig, band, args.seconds, seed=args.seed)
    rms = np.sqrt(np.mean(drive.data**2, axis=0)) / [c.full_scale for c in rig.inputs]
    print(f"rig    {rig.name}: {rig.description.title}")
    print(
        f"drive  {args.seconds:g} s random, triangular PSD {band[0]:g}-{band[1]:g} Hz, "
        f"{100 * rms.max():.3g} % of full scale rms, played {args.runs} times"
    )
    runs = [first]  # run 1 of the bar: pseudo_field played the drive once already
    with bar(args.runs, desc=f"{rig.name}: runs", unit="run", initial=1) as runs_bar:
        for k in range(1, args.runs):
            runs.append(rig.run(drive, seed=args.seed + 10_000 + k))
            runs_bar.update(1)
    number = repeatability_number(runs, fs=rig.fs, band=band)  # the text's (Tables 3.1-3.3)
    full = repeatability_number(runs)  # the recorded band, up to the anti-alias filter
    nperseg = int(min(drive.n_samples // 4, 2 ** np.ceil(np.log2(2 * rig.fs))))
    f, rf = repeatability_function(runs, rig.fs, nperseg=nperseg)
    _, snr = signal_to_noise(runs, rig.fs, nperseg=nperseg)
    inband = (f >= band[0]) & (f <= band[1]) & (f > 0)
    names = runs[0].names
    width = max(len(n) for n in names)
    print(
        f"\nrepeatability number (reference text §3.1, Tables 3.1-3.3): 100 - mean eta0 (eq. 5-28) "
        f"of each run against the mean response, responses in the drive band {band[0]:g}-"
        f"{band[1]:g} Hz; full band: the same over everything up to the anti-alias filter"
    )
    numbers = text.get("numbers", {}) if tuple(band) == tuple(text.get("band", ())) else {}
    if numbers:
        print(f"text   {text['table']} in the same band: its number per channel (last column)")
    print(
        f"{'channel':<{width}}  repeatability  full band  R_f in band (mean)  "
        "SNR in band: mean   min" + ("   text" if numbers else "")
    )
    for k, name in enumerate(names):
        quoted = f"  {numbers[name]:>6.2f}%" if name in numbers else ""
        print(
            f"{name:<{width}}  {number[k]:>12.2f}%  {full[k]:>8.2f}%  "
            f"{np.nanmean(rf[inband, k]):>17.1f}%  "
            f"{np.mean(snr[inband, k]):>15.1f} dB {np.min(snr[inband, k]):>5.1f} dB" + quoted
        )
    out.mkdir(parents=True, exist_ok=True)
    fig = repeatability_plot(
        f,
        rf,
        snr,
        names,
        band=band,
        title=f"{rig.name}: repeatability of {args.runs} runs of one drive",
    )
    path = save_figure(fig, out / "repeatability.png", dpi=110)
    print(f"\nplot   {path}")
    return 0


def _cmd_check_linearity(args) -> int:
    with contextlib.ExitStack() as hold:  # the plot folder's lock, from the checks to the end
        return _check_linearity(args, hold)


def _check_linearity(args, hold: contextlib.ExitStack) -> int:
    """``vrig check-linearity``; ``hold`` keeps the lock of ``--out`` (:func:`_hold_out`)
    when the plot is asked for."""
    from .linearity import check_rig_linearity

    if not (np.isfinite(args.level) and 0 < args.level <= 0.5):
        raise _UsageError(
            f"--level must be a fraction of full scale in (0, 0.5], got {args.level:g}"
        )
    if not (np.isfinite(args.seconds) and 2 <= args.seconds <= _MAX_SECONDS):
        raise _UsageError(f"--seconds must be 2..{_MAX_SECONDS:g}, got {args.seconds:g}")
    _check_seed(args.seed)
    if args.out is not None and not args.plot:
        raise _UsageError("--out is the folder of the plot: pass --plot too")
    rig = _load_rig(args.rig, seed=args.seed)
    band = _band(rig, args.band)
    out = Path(args.out) if args.out else Path("results") / f"{Path(rig.name).stem}-linearity"
    if args.plot:
        if out.exists() and not out.is_dir():
            raise _UsageError(f"--out {out} is a file, not a folder")
        _check_writable(out)  # before the runs, not after them
        _hold_out(hold, out)  # one writer per folder: a second one is refused before its runs
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


def _cmd_check_target(args) -> int:
    from .desired.range_report import range_report
    from .desired.reachability import check_target

    if args.seconds is not None and not (
        np.isfinite(args.seconds) and 2 <= args.seconds <= _MAX_SECONDS
    ):
        raise _UsageError(f"--seconds must be 2..{_MAX_SECONDS:g}, got {args.seconds:g}")
    _check_seed(args.seed)
    if not Path(args.desired).is_file():
        what = "a folder, not a file" if Path(args.desired).is_dir() else "no file"
        raise _UsageError(f"--desired: {what} {args.desired}")
    rig = _load_rig(args.rig, seed=args.seed)
    band = _band(rig, args.band)
    desired, notes = _read_desired(args.desired, rig)
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


def _cmd_demo(args) -> int:
    from identification.errors import SimulationDivergedError, UnstableModelError

    from .demo import run_demo

    lo, hi = _DEMO_SAMPLES
    if not lo <= args.samples <= hi:
        raise _UsageError(f"--samples must be >= {lo} and <= {hi}, got {args.samples}")
    if not 0 <= args.noise < 1:
        raise _UsageError(f"--noise must be in [0, 1), got {args.noise:g}")
    _check_seed(args.seed)
    try:
        run_demo(seed=args.seed, n_samples=args.samples, noise=args.noise)
    except (UnstableModelError, SimulationDivergedError) as exc:  # the fit was refused
        raise _Failure(
            f"{exc} ({args.samples} samples are few for the 454 terms per output: try more "
            "--samples, or another --seed)"
        ) from exc
    return 0


_COMMANDS = {
    "demo": _cmd_demo,
    "rigs": _cmd_rigs,
    "describe": _cmd_describe,
    "reconstruct": _cmd_reconstruct,
    "repeatability": _cmd_repeatability,
    "check-linearity": _cmd_check_linearity,
    "check-target": _cmd_check_target,
}


def _benchmarks_dir() -> Path:
    """``benchmarks/`` of the source checkout the running ``vrig`` package lives in (an editable
    install or ``PYTHONPATH``); missing when ``vrig`` is an installed wheel."""
    return Path(__file__).resolve().parents[1] / "benchmarks"


def _cmd_bench(argv: list[str]) -> int:
    """Forward to the benchmark runner, which lives in the source checkout's ``benchmarks/``
    (found next to the ``vrig`` package, whatever the current directory), run in a child
    interpreter; returns its exit code."""
    bench = _benchmarks_dir()
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


class _Interrupts:
    """Ctrl-C in ``vrig``: the ``SIGINT`` handler of :func:`main` notes every interrupt
    (``seen``) and raises :class:`KeyboardInterrupt`, except inside :meth:`deferred` (the
    results being written), where the interrupt waits for the block to end."""

    def __init__(self):
        self.seen = False
        self._defer = 0

    def _handler(self, signum, frame) -> None:
        self.seen = True
        if not self._defer:
            raise KeyboardInterrupt

    @contextlib.contextmanager
    def deferred(self):
        """Interrupts in the block are noted, not raised."""
        self._defer += 1
        try:
            yield
        finally:
            self._defer -= 1

    @contextlib.contextmanager
    def installed(self):
        """The handler, for one command (the main thread only: signals go there)."""
        self.seen, self._defer = False, 0
        if threading.current_thread() is not threading.main_thread():
            yield
            return
        previous = signal.signal(signal.SIGINT, self._handler)
        try:
            yield
        finally:
            signal.signal(signal.SIGINT, previous)


_SIGINT = _Interrupts()


def _say(command: str, text: str) -> None:
    """One line on stderr: ``vrig COMMAND: text`` (newlines in messages are folded)."""
    print(f"vrig {command}: " + " ".join(str(text).split()), file=sys.stderr)


def _progress_mode() -> bool | None:
    """``VRIG_PROGRESS``: ``1`` progress on stderr always, ``0`` never, unset (or anything
    else) when stderr is a terminal."""
    return {"1": True, "0": False}.get(os.environ.get("VRIG_PROGRESS", "").strip())


def _run(command: str, func, arg) -> int:
    """Run a command; map every error to one line on stderr and an exit code (module doc)."""
    from .errors import ERRORS, FolderLockedError, RigModelError
    from .progress import enabled

    try:
        with enabled(_progress_mode()):
            return func(arg)
    except (_UsageError, RigModelError, FolderLockedError) as exc:  # (another writer's folder)
        _say(command, exc)
        return EXIT_USAGE
    except _Failure as exc:
        _say(command, f"failed: {exc}")
        return exc.code
    except ERRORS as exc:  # any other vrig or identification error: the run failed
        hint = " (try a narrower --band, a lower --order or --gain, or a smaller desired response)"
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
                code = _run("bench", _cmd_bench, raw[1:])
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
