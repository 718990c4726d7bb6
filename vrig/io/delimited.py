"""CSV time histories: a ``time,<name> [<unit>],...`` header row, then one row per sample.

(Named ``delimited`` rather than ``csv`` so that it cannot be mistaken for the standard-library
:mod:`csv` module it uses.)
"""

from __future__ import annotations

import codecs
import csv
import math
import re
from pathlib import Path

import numpy as np

from ..errors import FileFormatError
from ..files import atomic_write, read_bytes
from ..timehistory import TimeHistory
from ._common import _check_history, _history

__all__ = ["read_csv", "write_csv"]

_CSV = "CSV"  # format name in error messages
_COLUMN = re.compile(r"^(.*?)\s*\[([^\[\]]*)\]\s*$")


def write_csv(path, history: TimeHistory) -> Path:
    """Write ``time,<name> [<unit>],...`` followed by one row per sample.

    Parameters
    ----------
    path : str or Path
        Target file (replaced atomically).
    history : TimeHistory
        Names and units must not contain line breaks, units no square brackets.

    Returns
    -------
    Path
        The written file (UTF-8). Samples are written with 17 significant digits (exact float64
        round trip), times ``i / fs`` with 12.
    """
    _check_history(history)
    path = Path(path)
    for name, unit in zip(history.names, history.units, strict=True):
        if any(ch in name + unit for ch in "\r\n"):
            raise ValueError(f"channel {name!r} [{unit!r}]: line breaks cannot be stored in CSV")
        if "[" in unit or "]" in unit:
            raise ValueError(f"unit {unit!r} of channel {name!r} must not contain [ or ]")
    table = np.column_stack([history.time, history.data])
    fmt = ["%.12g"] + ["%.17g"] * history.n_channels
    with atomic_write(path, "w", encoding="utf-8") as f:
        csv.writer(f, lineterminator="\n").writerow(
            ["time"] + [f"{n} [{u}]" for n, u in zip(history.names, history.units, strict=True)]
        )
        np.savetxt(f, table, fmt=fmt, delimiter=",")
    return path


_UNICODE_BOMS = (  # UTF-32 first: its little-endian mark starts with UTF-16's
    (codecs.BOM_UTF32_LE, "UTF-32"),
    (codecs.BOM_UTF32_BE, "UTF-32"),
    (codecs.BOM_UTF16_LE, "UTF-16"),
    (codecs.BOM_UTF16_BE, "UTF-16"),
)


def _csv_text(path: Path) -> str:
    """The text of a UTF-8 CSV file (a leading byte-order mark removed); other encodings are
    refused with a FileFormatError naming the file and the offending byte."""
    raw = read_bytes(path, _CSV)
    for bom, name in _UNICODE_BOMS:
        if raw.startswith(bom):
            raise FileFormatError(
                path,
                _CSV,
                f"it is {name} text (byte-order mark {bom.hex(' ')}); vrig reads "
                "UTF-8 CSV files: save it as UTF-8",
            )
    if b"\0" in raw:
        at = raw.index(b"\0")
        raise FileFormatError(
            path,
            _CSV,
            f"it holds a NUL byte at offset {at}: binary data, or UTF-16/32 text "
            "without a byte-order mark; save it as UTF-8 text",
        )
    try:
        return raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        line = raw.count(b"\n", 0, exc.start) + 1
        raise FileFormatError(
            path,
            _CSV,
            f"it is not UTF-8 text: byte 0x{raw[exc.start]:02x} at offset "
            f"{exc.start} (line {line}) (latin-1 or Windows-1252?); save it as UTF-8",
        ) from None


def _numbers(columns: list[str]) -> bool:
    """True when every field of a row is a number (a data row where the header should be)."""
    try:
        [float(c) for c in columns]
    except ValueError:
        return False
    return True


def _csv_header(lines: list[str], src: str) -> tuple[list[str], list[str], list[str]]:
    """The header row's columns and the channel names and units (``"-"`` without ``[unit]``)."""
    if not lines or not lines[0].strip():
        raise FileFormatError(
            src, _CSV, "empty CSV file (expected a header row time,<name> [<unit>],...)"
        )
    try:
        columns = next(csv.reader([lines[0]]))
    except csv.Error as exc:  # e.g. a field beyond the csv module's 131072-character limit
        raise FileFormatError(src, _CSV, f"unreadable header row: {exc}") from None
    first = _COLUMN.match(columns[0])
    first_name = (first.group(1) if first else columns[0]).strip().lower()
    if _numbers(columns):
        raise FileFormatError(
            src,
            _CSV,
            f"no header row (the first row is numbers: {lines[0][:80]!r}); a CSV time history "
            "starts with the header row time,<name> [<unit>],... (time in s, one column per "
            "channel) and then one row per sample, uniformly spaced",
        )
    if first_name != "time" or len(columns) < 2:
        raise FileFormatError(
            src, _CSV, f"the header row must be time,<name> [<unit>],..., got {lines[0][:80]!r}"
        )
    names, units = [], []
    for col in columns[1:]:
        m = _COLUMN.match(col)
        names.append((m.group(1) if m else col).strip())
        units.append(m.group(2).strip() if m else "-")
    return columns, names, units


def read_csv(path, *, fs: float | None = None) -> TimeHistory:
    """Read a CSV written by :func:`write_csv` (or any ``time,<name> [<unit>],...`` table).

    Parameters
    ----------
    path : str or Path
        The file to read.
    fs : float, optional
        Sample rate in Hz. When omitted it is inferred from the first column (``time`` in
        seconds, uniformly spaced within 1 ppm of a step) and rounded to 10 significant digits
        when that changes it by less than 1e-9; when given the time column is not used.

    Returns
    -------
    TimeHistory
        Names and units from the header (a column without ``[unit]`` gets unit ``"-"``).

    Raises
    ------
    FileFormatError
        (a ValueError) On text that is not UTF-8 (UTF-16/32, latin-1...; a UTF-8 byte-order
        mark is fine), a missing header, a first column not called ``time``, non-numeric or
        ragged rows, no data rows, or (``fs`` omitted) a non-uniform or non-increasing time
        column or a single row; on a file that is not a regular file or is larger than
        :data:`vrig.files.MAX_FILE_BYTES`.
    FileNotFoundError
        If the file does not exist.
    """
    if fs is not None:
        try:
            ok = math.isfinite(float(fs)) and float(fs) > 0
        except (TypeError, ValueError):
            ok = False
        if not ok:
            raise ValueError(f"fs must be a positive sample rate in Hz, got {fs!r}")
    path = Path(path)
    src = str(path)
    lines = _csv_text(path).splitlines()
    columns, names, units = _csv_header(lines, src)
    rows = [line for line in lines[1:] if line.strip()]
    if not rows:
        raise FileFormatError(src, _CSV, "no data rows after the header")
    try:
        table = np.loadtxt(rows, delimiter=",", ndmin=2, dtype=np.float64)
    except ValueError as exc:
        raise FileFormatError(src, _CSV, f"unreadable data rows: {exc}") from None
    if table.shape[1] != len(columns):
        raise FileFormatError(
            src, _CSV, f"{len(columns)} header columns but {table.shape[1]} columns of data"
        )
    if fs is None:
        t = table[:, 0]
        if t.size < 2:
            raise FileFormatError(src, _CSV, "one row cannot give a sample rate; pass fs")
        span = t[-1] - t[0]
        if not (np.all(np.isfinite(t)) and span > 0):
            raise FileFormatError(src, _CSV, "the time column must increase; pass fs")
        step = span / (t.size - 1)
        err = np.max(np.abs(np.diff(t) - step))
        if err > 1e-6 * step + 1e-12 * np.max(np.abs(t)):
            raise FileFormatError(
                src,
                _CSV,
                f"the time column is not uniformly sampled (step {step:.6g} s, deviation "
                f"up to {err:.3g} s); pass fs",
            )
        fs = 1.0 / step
        nice = float(f"{fs:.10g}")
        if abs(nice - fs) <= 1e-9 * fs:
            fs = nice
    return _history(src, _CSV, table[:, 1:], fs, names, units)
