"""Reading and writing a time history in the format its file suffix names."""

from __future__ import annotations

from pathlib import Path

from ..timehistory import TimeHistory
from ._common import _check_history
from .delimited import read_csv, write_csv
from .mat import read_mat, write_mat
from .rpc3 import RPC3_SUFFIXES, read_rpc3, write_rpc3

__all__ = ["read", "write"]

_SUPPORTED = ", ".join([*RPC3_SUFFIXES, ".csv", ".mat", ".npz"])


def _suffix(path: Path) -> str:
    suffix = path.suffix.lower()
    if suffix not in (*RPC3_SUFFIXES, ".csv", ".mat", ".npz"):
        raise ValueError(
            f"unknown time-history file type {path.suffix or '(no suffix)'!r} for {path}; "
            f"supported suffixes: {_SUPPORTED}"
        )
    return suffix


def read(path, **kwargs) -> TimeHistory:
    """Read a time history, choosing the format from the suffix.

    Parameters
    ----------
    path : str or Path
        ``.rsp``/``.drv``/``.tim`` (RPC III), ``.csv``, ``.mat`` or ``.npz`` (case-insensitive).
    **kwargs
        Passed to the format's reader (e.g. ``fs`` for :func:`~vrig.io.read_csv`).

    Raises
    ------
    ValueError
        For an unknown suffix.
    FileFormatError
        (a ValueError) For a file that is not a valid file of its suffix's format; its message
        and its ``path`` and ``format`` attributes name the file and the format.
    FileNotFoundError
        If the file does not exist.
    """
    path = Path(path)
    suffix = _suffix(path)
    if suffix in RPC3_SUFFIXES:
        return read_rpc3(path, **kwargs)
    if suffix == ".csv":
        return read_csv(path, **kwargs)
    if suffix == ".mat":
        return read_mat(path, **kwargs)
    return TimeHistory.load(path, **kwargs)


def write(path, history: TimeHistory, **kwargs) -> Path:
    """Write a time history, choosing the format from the suffix (see :func:`read`).

    Parameters
    ----------
    path : str or Path
        Target file; its suffix chooses the format (see :func:`read`).
    history : TimeHistory
        The record to write.
    **kwargs
        Passed to the format's writer (e.g. ``data_type`` for :func:`~vrig.io.write_rpc3`).

    Returns
    -------
    Path
        The written file.
    """
    path = Path(path)
    suffix = _suffix(path)
    if suffix in RPC3_SUFFIXES:
        return write_rpc3(path, history, **kwargs)
    if suffix == ".csv":
        return write_csv(path, history, **kwargs)
    if suffix == ".mat":
        return write_mat(path, history, **kwargs)
    _check_history(history)
    if kwargs:
        raise TypeError(f"writing .npz takes no options, got {sorted(kwargs)}")
    return history.save(path)
