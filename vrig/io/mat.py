"""MATLAB ``.mat`` time histories: variables ``data`` (N x channels), ``fs``, ``names``, ``units``."""

from __future__ import annotations

import io as _stdio
from pathlib import Path

import numpy as np

from .. import files
from ..errors import FileFormatError
from ..files import atomic_write, read_bytes
from ..timehistory import TimeHistory
from . import _mat5
from ._common import _check_history, _history

__all__ = ["read_mat", "write_mat"]

_MAT = "MATLAB .mat"  # format name in error messages


def write_mat(path, history: TimeHistory) -> Path:
    """Write a MATLAB (v5) ``.mat`` file with ``data`` (N x channels), ``fs``, ``names`` and
    ``units`` (cell arrays of char).

    Parameters
    ----------
    path : str or os.PathLike
        Target file (replaced atomically).
    history : TimeHistory
        The record to write.

    Returns
    -------
    Path
        The written file.
    """
    from scipy.io import savemat

    _check_history(history)
    path = Path(path)
    content = {
        "data": history.data,
        "fs": history.fs,
        "names": np.array(history.names, dtype=object),
        "units": np.array(history.units, dtype=object),
    }
    with atomic_write(path) as f:
        savemat(f, content)
    return path


def _strings(value, key: str, src: str) -> list[str]:
    """A cell array of char or a (space-padded) char matrix as a list of str."""
    arr = np.asarray(value)
    if arr.dtype.kind == "U":  # char matrix: one row per string
        return [str(s).rstrip() for s in arr.reshape(-1)]
    if arr.dtype == object:
        out = []
        for item in arr.reshape(-1):
            item = np.asarray(item)
            if item.dtype.kind != "U":
                raise FileFormatError(src, _MAT, f"variable {key} must hold strings")
            out.append("".join(str(s) for s in item.reshape(-1)))
        return out
    raise FileFormatError(src, _MAT, f"variable {key} must be a cell array of strings")


def read_mat(path) -> TimeHistory:
    """Read a ``.mat`` file with ``data`` (N x channels) and ``fs`` and optional ``names`` and
    ``units`` (cell arrays of char or char matrices), as written by :func:`write_mat`.

    MATLAB level-5 files (``save -v6``/``-v7``, the default) and level-4 files are read with
    :func:`scipy.io.loadmat`, after a structural check of every data element that keeps a
    corrupt file from crashing SciPy's reader (see :mod:`vrig.io._mat5`).

    Parameters
    ----------
    path : str or os.PathLike
        The file to read.

    Raises
    ------
    FileFormatError
        (a ValueError) If the file is not a MATLAB file SciPy can read (corrupt, truncated, a
        v7.3 HDF5 file, not a regular file, larger than :data:`vrig.files.MAX_FILE_BYTES`), or
        a variable is missing or malformed.
    FileNotFoundError
        If the file does not exist.
    """
    from scipy.io import loadmat

    path = Path(path)
    src = str(path)
    buf = read_bytes(path, _MAT)
    _mat5.check(buf, src, files.MAX_FILE_BYTES)
    try:
        content = loadmat(_stdio.BytesIO(buf), variable_names=["data", "fs", "names", "units"])
    except Exception as exc:  # anything SciPy raises on a file that passed the check
        raise FileFormatError(src, _MAT, f"{type(exc).__name__}: {exc}") from None
    missing = [k for k in ("data", "fs") if k not in content]
    if missing:
        raise FileFormatError(src, _MAT, f"missing variable(s) {', '.join(missing)}")
    data = np.asarray(content["data"])
    if data.dtype.kind not in "iuf":
        raise FileFormatError(src, _MAT, f"data must be a real numeric matrix, got {data.dtype}")
    fs_arr = np.asarray(content["fs"])
    if fs_arr.size != 1 or fs_arr.dtype.kind not in "iuf":
        raise FileFormatError(src, _MAT, "fs must be a numeric scalar")
    names = _strings(content["names"], "names", src) if "names" in content else ()
    units = _strings(content["units"], "units", src) if "units" in content else ()
    return _history(src, _MAT, data, float(fs_arr.reshape(())), names, units)
