"""What the ``vrig`` commands share: their two error kinds, argument checks, the rig, the
simulation band, and the desired record read from a file and matched to the rig."""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from ..reconstruction.defaults import default_band

MAX_SECONDS = 3600.0  # longest record a command plays or reconstructs (--seconds, --desired)


class _UsageError(Exception):
    """A bad argument: reported with the command's name, exit code 2 (the command line's own
    control flow, never raised to a library caller: private)."""


class _Failure(Exception):
    """The rig or the iteration failed: reported with the command's name and exit code ``code``
    (default 1)."""

    def __init__(self, message: str, code: int = 1):
        super().__init__(message)
        self.code = code


def whole_number(text: str) -> int:
    """An integer argument, also written as ``2e4``: its range is checked by the command.

    Parameters
    ----------
    text : str
        The argument.

    Returns
    -------
    int
    """
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
    if not (np.isfinite(value) and value == int(value)):
        raise argparse.ArgumentTypeError(f"not a whole number: {text!r}")
    return int(value)


def load_rig(name: str, *, seed: int = 0):
    """The rig ``name`` (a shipped rig or a rig file); an unknown one is a usage error.

    Parameters
    ----------
    name : str
        A shipped rig's name or a ``.rig.json``/``.xml`` file.
    seed : int
        The rig's seed.

    Returns
    -------
    Rig
    """
    from .. import list_rigs, load_rig

    if not name.endswith((".json", ".xml")) and name not in list_rigs():
        raise _UsageError(f"unknown rig {name!r}; available rigs: {', '.join(list_rigs())}")
    if name.endswith((".json", ".xml")) and not Path(name).is_file():
        raise _UsageError(f"no rig file {name}")
    return load_rig(name, seed=seed)


def check_seed(seed: int) -> None:
    """``--seed`` is an integer >= 0.

    Parameters
    ----------
    seed : int
        The argument.
    """
    if seed < 0:
        raise _UsageError(f"--seed must be an integer >= 0, got {seed}")


def check_seconds(seconds: float | None) -> None:
    """``--seconds``, when given, lies in 2..:data:`MAX_SECONDS`.

    Parameters
    ----------
    seconds : float or None
        The argument (None: not given).
    """
    if seconds is not None and not (np.isfinite(seconds) and 2 <= seconds <= MAX_SECONDS):
        raise _UsageError(f"--seconds must be 2..{MAX_SECONDS:g}, got {seconds:g}")


def simulation_band(rig, band) -> tuple[float, float]:
    """``--band`` checked against the rig's Nyquist frequency, else the rig's default band.

    Parameters
    ----------
    rig : Rig
        The rig.
    band : (float, float) or None
        The argument (None: not given).

    Returns
    -------
    (float, float)
    """
    if band is None:
        return default_band(rig)
    lo, hi = (float(b) for b in band)
    if not (np.isfinite(lo) and np.isfinite(hi) and 0 <= lo < hi < rig.fs / 2):
        raise _UsageError(
            f"--band {lo:g} {hi:g}: need 0 <= LOW < HIGH < fs/2 = {rig.fs / 2:g} Hz for rig "
            f"{rig.name!r}"
        )
    return lo, hi


def check_desired(desired, rig):
    """Match a read desired record to the rig's responses (by name, else by position).

    Parameters
    ----------
    desired : TimeHistory
        The record read from ``--desired``.
    rig : Rig
        The rig.

    Returns
    -------
    (TimeHistory, list of str)
        The record with the rig's responses, and notes on how it was matched.
    """
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


def check_content(desired, rig) -> None:
    """The desired record (as it will be used) is something the rig can reproduce.

    Parameters
    ----------
    desired : TimeHistory
        The desired record, matched to the rig.
    rig : Rig
        The rig.
    """
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


def read_desired(path, rig):
    """Read a ``--desired`` file and match it to the rig's responses (:func:`check_desired`).

    Parameters
    ----------
    path : str or Path
        The file.
    rig : Rig
        The rig.

    Returns
    -------
    (TimeHistory, list of str)
        The record and the notes.
    """
    from .. import io

    try:
        field = io.read(path)
    except Exception as exc:  # whatever a damaged file makes the reader raise: bad input
        raise _UsageError(f"--desired: cannot read {path}: {exc}") from None
    return check_desired(field, rig)


def add_rig_argument(parser) -> None:
    """``--rig``: a shipped rig's name or a user rig's file (every rig command's).

    Parameters
    ----------
    parser : argparse.ArgumentParser
        A subcommand's parser.
    """
    parser.add_argument("--rig", required=True, help="rig name (see `vrig rigs`) or rig file")


def add_seed_argument(parser) -> None:
    """``--seed``: the random seed, an integer >= 0, default 0 (every command's).

    Parameters
    ----------
    parser : argparse.ArgumentParser
        A subcommand's parser.
    """
    parser.add_argument(
        "--seed", type=int, default=0, help="random seed, an integer >= 0 (default 0)"
    )


def add_band_argument(parser, help_text: str) -> None:
    """``--band LOW HIGH`` [Hz] with the command's own default, said in ``help_text``.

    Parameters
    ----------
    parser : argparse.ArgumentParser
        A subcommand's parser.
    help_text : str
        The option's help (what the band is and its default).
    """
    parser.add_argument("--band", type=float, nargs=2, metavar=("LOW", "HIGH"), help=help_text)
