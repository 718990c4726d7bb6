"""File I/O for time histories: MTS RPC III, CSV, MATLAB ``.mat`` and vrig ``.npz``.

:func:`read` and :func:`write` dispatch on the file suffix:

* ``.rsp``, ``.drv``, ``.tim``: MTS RPC III time history (:func:`read_rpc3`,
  :func:`write_rpc3`);
* ``.csv``: a ``time,<name> [<unit>],...`` table (:func:`read_csv`, :func:`write_csv`);
* ``.mat``: MATLAB variables ``data``, ``fs``, ``names``, ``units`` (:func:`read_mat`,
  :func:`write_mat`);
* ``.npz``: :meth:`TimeHistory.save` / :meth:`TimeHistory.load`.

RPC III time-history layout
---------------------------
The file is a sequence of 512-byte blocks. The header is ``NUM_HEADER_BLOCKS`` blocks of four
128-byte records, each a 32-byte keyword and a 96-byte value (ASCII, NUL terminated and padded).
The first three records are ``FORMAT``, ``NUM_HEADER_BLOCKS`` and ``NUM_PARAMS`` in that order;
the others may come in any order. Data start at byte ``512 * NUM_HEADER_BLOCKS`` and are stored
in groups of ``PTS_PER_GROUP`` points per channel; within a group the channels follow one another
(array shape ``(groups, channels, PTS_PER_GROUP)``). The last group is written whole, padded
after the last frame. ``SHORT_INTEGER`` samples are ``int16 * SCALE.CHAN_n``; ``FLOATING_POINT``
samples are IEEE float32 already in engineering units (``SCALE`` is written as 1 and not applied,
as other RPC readers do).

This layout was confirmed on two real nCode-written files: decoding them this way reproduces
nCode's own per-channel statistics (``NCODE_STAT1_CHAN_n`` = max, min, mean, std, rms): mean,
std and rms within 0.013 count, max/min within the one count of int16 quantisation, and the sample
indices of the extremes (``NCODE_STAT2_CHAN_n``) exactly; channel-interleaved or
channel-contiguous decodings of the multi-group file miss max/min by hundreds to thousands of
counts.

Record length: ``FRAMES * PTS_PER_FRAME`` samples, or ``SAMPLES`` when that (non-standard,
written by some tools and by :func:`write_rpc3` for records that are not a whole number of
frames) keyword is present. For the 2-frame sample ``test1.rsp`` this gives 2048 samples: nCode's
mean and rms agree with the 2048-sample record to 1e-6 relative but differ by up to 2.6e-4 from a
2047-sample one; the "8.188 s" quoted elsewhere for that file is the time of the last sample,
2047 * dt, not a record length.
``HALF_FRAMES`` is not interpreted (stored points are returned as they are).

Data sections that hold exactly the whole groups (the standard), or whose last group holds only
the points of its frames (as some writers produce), are accepted, each optionally followed by
padding up to the next 512-byte block; any other size raises :class:`~vrig.FileFormatError`.

Safety
------
Writers replace their file atomically (:func:`vrig.files.atomic_write`): a kill or Ctrl-C
during a write leaves the previous file, never a partial one. Readers accept only regular files
of at most :data:`vrig.files.MAX_FILE_BYTES` (no FIFO, device or endless file) and raise
:class:`~vrig.FileFormatError` (a ValueError naming the file and the format) for anything that
is not a valid file of the format: truncated, corrupt, foreign, CSV not in UTF-8 (a UTF-8
byte-order mark is fine), MATLAB v7.3, or holding values a :class:`TimeHistory` refuses.
"""

from __future__ import annotations

import codecs
import csv
import datetime
import io as _stdio
import math
import re
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np

from . import _mat5, files
from .errors import FileFormatError
from .files import atomic_write, read_bytes
from .timehistory import TimeHistory

__all__ = [
    "RPC3_SUFFIXES",
    "read",
    "read_csv",
    "read_mat",
    "read_rpc3",
    "read_rpc3_header",
    "write",
    "write_csv",
    "write_mat",
    "write_rpc3",
]

RPC3_SUFFIXES = (".rsp", ".drv", ".tim")
"""File suffixes handled as RPC III time histories by :func:`read` and :func:`write`."""

_RPC3, _CSV, _MAT = "RPC III", "CSV", "MATLAB .mat"  # format names in error messages
_BLOCK = 512
_RECORD = 128
_KEY_LEN = 32
_VALUE_LEN = 96
_MAX_PARAMS = 1024  # 256 header blocks x 4 records (MTS limit, enforced on writing)
_INT16_FULL_SCALE = 32767
_TIME_TYPES = {
    "1": "DRIVE",
    "2": "RESPONSE",
    "3": "MULT_DRIVE",
    "4": "MULT_RESP",
    "5": "CONFIG_DRIVE",
    "6": "CONFIG_RESP",
    "7": "PEAK_PICK",
}
_FORMATS = {"BINARY_IEEE_LITTLE_END": "<", "BINARY": "<", "BINARY_IEEE_BIG_END": ">"}
_DATA_TYPES = {"SHORT_INTEGER": "i2", "FLOATING_POINT": "f4"}
# keywords write_rpc3 derives from the data and arguments; extra_header may not set them
_LAYOUT_KEYWORDS = (
    "FORMAT",
    "NUM_HEADER_BLOCKS",
    "NUM_PARAMS",
    "FILE_TYPE",
    "TIME_TYPE",
    "DELTA_T",
    "CHANNELS",
    "PTS_PER_FRAME",
    "PTS_PER_GROUP",
    "FRAMES",
    "DATA_TYPE",
    "HALF_FRAMES",
    "INT_FULL_SCALE",
    "SAMPLES",
)


def _history(src, fmt: str, data, fs: float, names, units) -> TimeHistory:
    """A TimeHistory of what a file holds; what TimeHistory refuses (NaN, repeated names...)
    is a FileFormatError naming the file."""
    try:
        return TimeHistory(data, fs, names, units)
    except ValueError as exc:
        raise FileFormatError(src, fmt, str(exc)) from None


# ---------------------------------------------------------------------------------------------
# RPC III: header
# ---------------------------------------------------------------------------------------------
def _text(raw: bytes) -> str:
    """A NUL-terminated latin-1 field, surrounding blanks removed."""
    return raw.split(b"\0", 1)[0].decode("latin-1").strip()


def _record(buf: bytes, i: int) -> tuple[str, str]:
    start = i * _RECORD
    return _text(buf[start : start + _KEY_LEN]), _text(buf[start + _KEY_LEN : start + _RECORD])


def _parse_int(text: str, key: str, src: str) -> int:
    try:
        return int(text)
    except ValueError:
        pass
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not value.is_integer():
        raise FileFormatError(src, _RPC3, f"header keyword {key} must be an integer, got {text!r}")
    return int(value)


def _parse_float(text: str, key: str, src: str) -> float:
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not math.isfinite(value):
        raise FileFormatError(
            src, _RPC3, f"header keyword {key} must be a finite number, got {text!r}"
        )
    return value


def _parse_header(buf: bytes, src: str) -> tuple[dict[str, str], int]:
    """Keyword -> value (stripped strings) and the number of header blocks."""
    if len(buf) < _BLOCK:
        raise FileFormatError(
            src,
            _RPC3,
            f"its {len(buf)} bytes are too short (the header alone is at least one "
            f"{_BLOCK}-byte block)",
        )
    expected = ("FORMAT", "NUM_HEADER_BLOCKS", "NUM_PARAMS")
    first = [_record(buf, i) for i in range(3)]
    for pos, (want, (key, _)) in enumerate(zip(expected, first, strict=True)):
        if key != want:
            raise FileFormatError(
                src,
                _RPC3,
                f"header record {pos + 1} must be {want} (the first "
                f"three records are FORMAT, NUM_HEADER_BLOCKS, NUM_PARAMS in that order), found "
                f"{key!r}",
            )
    n_blocks = _parse_int(first[1][1], "NUM_HEADER_BLOCKS", src)
    if n_blocks < 1:
        raise FileFormatError(src, _RPC3, f"NUM_HEADER_BLOCKS must be >= 1, got {n_blocks}")
    if n_blocks * _BLOCK > len(buf):
        raise FileFormatError(
            src,
            _RPC3,
            f"NUM_HEADER_BLOCKS = {n_blocks} ({n_blocks * _BLOCK} bytes) but the file "
            f"holds only {len(buf)} bytes (truncated file or corrupt header)",
        )
    n_params = _parse_int(first[2][1], "NUM_PARAMS", src)
    n_slots = 4 * n_blocks
    if not 3 <= n_params <= n_slots:
        raise FileFormatError(
            src,
            _RPC3,
            f"NUM_PARAMS = {n_params} must lie between 3 and the {n_slots} records of "
            f"{n_blocks} header blocks",
        )
    header = {key: value for key, value in first}
    found = 3
    for i in range(3, n_slots):
        if found == n_params:
            break
        key, value = _record(buf, i)
        if not key:  # unused record
            continue
        found += 1
        if key in header and header[key] != value:
            raise FileFormatError(
                src,
                _RPC3,
                f"header keyword {key} appears twice with different values "
                f"({header[key]!r} and {value!r})",
            )
        header[key] = value
    if found < n_params:
        raise FileFormatError(
            src,
            _RPC3,
            f"NUM_PARAMS = {n_params} but the {n_blocks} header blocks hold only {found} "
            "keyword records",
        )
    return header, n_blocks


def read_rpc3_header(path) -> dict[str, str]:
    """The keyword-value pairs of an RPC III header, in file order.

    Parameters
    ----------
    path : str or Path
        An RPC III file.

    Returns
    -------
    dict of str to str
        Values are the stripped strings found in the file (``"3.906250E-003"``, ``"BINARY"``).

    Raises
    ------
    FileFormatError
        If the header is malformed (see :func:`read_rpc3`).
    """
    path = Path(path)
    header, _ = _parse_header(read_bytes(path, _RPC3), str(path))
    return header


# ---------------------------------------------------------------------------------------------
# RPC III: reading
# ---------------------------------------------------------------------------------------------
def _required_int(header, key, src, minimum):
    if key not in header:
        raise FileFormatError(src, _RPC3, f"header keyword {key} is missing")
    value = _parse_int(header[key], key, src)
    if value < minimum:
        raise FileFormatError(src, _RPC3, f"header keyword {key} must be >= {minimum}, got {value}")
    return value


def _unique_names(names: list[str]) -> list[str]:
    """Make repeated channel descriptions unique by appending ``_2``, ``_3``, ..."""
    seen: set[str] = set()
    out = []
    for name in names:
        candidate, k = name, 1
        while candidate in seen:
            k += 1
            candidate = f"{name}_{k}"
        seen.add(candidate)
        out.append(candidate)
    return out


def _unquote(text: str) -> str:
    if len(text) >= 2 and text[0] == text[-1] == '"':
        return text[1:-1].strip()
    return text


def _padded(n_bytes: int) -> int:
    return -(-n_bytes // _BLOCK) * _BLOCK


def _snap_rate(fs: float) -> float:
    """Undo the last-bit error of ``1 / (1 / fs)`` for sample rates with few digits."""
    nice = float(f"{fs:.12g}")
    return nice if abs(nice - fs) <= 4 * np.spacing(fs) else fs


def read_rpc3(path) -> TimeHistory:
    """Read an MTS RPC III time-history file (``.rsp``, ``.drv``, ``.tim``).

    Parameters
    ----------
    path : str or Path
        The file. ``FORMAT`` may be ``BINARY_IEEE_LITTLE_END``, ``BINARY`` (little-endian) or
        ``BINARY_IEEE_BIG_END``; ``DATA_TYPE`` ``SHORT_INTEGER`` (the default when absent) or
        ``FLOATING_POINT``.

    Returns
    -------
    TimeHistory
        ``fs = 1 / DELTA_T``; channel names from ``DESC.CHAN_n`` (``ch<n>`` when absent, repeated
        descriptions made unique with ``_2``, ``_3``, ...), units from ``UNITS.CHAN_n`` (``"-"``
        when absent); ``FRAMES * PTS_PER_FRAME`` samples, or ``SAMPLES`` when given. Integer data
        are scaled by ``SCALE.CHAN_n``. See the module docstring for the data layout.

    Raises
    ------
    FileFormatError
        (a ValueError) If the file is not a readable RPC III time history: first three records
        not ``FORMAT``, ``NUM_HEADER_BLOCKS``, ``NUM_PARAMS``; ``ASCII`` or unknown ``FORMAT``; a
        missing or non-numeric ``CHANNELS``, ``DELTA_T``, ``PTS_PER_FRAME``, ``PTS_PER_GROUP``,
        ``FRAMES`` or (integer data) ``SCALE.CHAN_n``; a data section whose size does not match
        the header (truncated file, wrong ``CHANNELS``...); non-finite samples; not a regular
        file (FIFO, device...) or larger than :data:`vrig.files.MAX_FILE_BYTES`.
    FileNotFoundError
        If the file does not exist.

    Examples
    --------
    >>> th = read_rpc3("road.rsp")  # doctest: +SKIP
    >>> th.fs, th.names[0], th.units[0]  # doctest: +SKIP
    (256.0, 'WFT1@LF_Z_Acceler.RN_1', 'g')
    """
    path = Path(path)
    src = str(path)
    buf = read_bytes(path, _RPC3)
    header, n_blocks = _parse_header(buf, src)

    fmt = header["FORMAT"].upper()
    if fmt == "ASCII":
        raise FileFormatError(
            src,
            _RPC3,
            f"FORMAT = ASCII RPC III files are not supported; only binary files "
            f"({', '.join(_FORMATS)}) can be read",
        )
    if fmt not in _FORMATS:
        raise FileFormatError(
            src,
            _RPC3,
            f"unknown FORMAT {header['FORMAT']!r}; expected one of {', '.join(_FORMATS)}",
        )
    file_type = header.get("FILE_TYPE", "TIME_HISTORY").upper()
    if file_type != "TIME_HISTORY":
        raise FileFormatError(
            src, _RPC3, f"FILE_TYPE = {header['FILE_TYPE']!r}; only TIME_HISTORY files can be read"
        )
    data_type = header.get("DATA_TYPE", "SHORT_INTEGER").upper()
    if data_type not in _DATA_TYPES:
        raise FileFormatError(
            src,
            _RPC3,
            f"unknown DATA_TYPE {header['DATA_TYPE']!r}; expected SHORT_INTEGER or FLOATING_POINT",
        )
    if "DELTA_T" not in header:
        raise FileFormatError(src, _RPC3, "header keyword DELTA_T is missing")
    dt = _parse_float(header["DELTA_T"], "DELTA_T", src)
    if dt <= 0 or not math.isfinite(1.0 / dt):
        raise FileFormatError(
            src, _RPC3, f"DELTA_T must be a positive time step, got {header['DELTA_T']!r}"
        )
    n_chan = _required_int(header, "CHANNELS", src, 1)
    per_frame = _required_int(header, "PTS_PER_FRAME", src, 1)
    per_group = _required_int(header, "PTS_PER_GROUP", src, 1)
    frames = _required_int(header, "FRAMES", src, 1)
    n_points = frames * per_frame  # points in the frames (per channel)
    n_samples = n_points
    if "SAMPLES" in header:
        n_samples = _parse_int(header["SAMPLES"], "SAMPLES", src)
        if not 1 <= n_samples <= n_points:
            raise FileFormatError(
                src,
                _RPC3,
                f"SAMPLES = {n_samples} must lie between 1 and FRAMES * PTS_PER_FRAME = {n_points}",
            )

    # ---- data-section size: whole groups (standard) or a last group cut after its frames
    dtype = np.dtype(_FORMATS[fmt] + _DATA_TYPES[data_type])
    n_groups = -(-n_points // per_group)
    full_groups, rest = divmod(n_points, per_group)
    whole = n_groups * per_group * n_chan * dtype.itemsize
    compact = n_points * n_chan * dtype.itemsize
    start = n_blocks * _BLOCK
    available = len(buf) - start
    if available == whole or (available != compact and whole < available <= _padded(whole)):
        full_groups, rest = n_groups, 0
    elif not (rest and compact <= available <= _padded(compact)):
        what = "truncated: it" if available < compact else "inconsistent with the header: it"
        raise FileFormatError(
            src,
            _RPC3,
            f"data section is {what} holds {available} bytes but CHANNELS = {n_chan}, "
            f"FRAMES = {frames}, PTS_PER_FRAME = {per_frame}, PTS_PER_GROUP = {per_group} and "
            f"DATA_TYPE = {data_type} need {whole} bytes ({n_groups} groups of "
            f"{per_group} points x {n_chan} channels x {dtype.itemsize} bytes)",
        )

    scales = np.ones(n_chan)
    if data_type == "SHORT_INTEGER":
        for n in range(1, n_chan + 1):
            key = f"SCALE.CHAN_{n}"
            if key not in header:
                raise FileFormatError(
                    src, _RPC3, f"{key} is missing (needed to scale SHORT_INTEGER data)"
                )
            scales[n - 1] = _parse_float(header[key], key, src)

    # ---- demultiplex: (groups, channels, points) -> (channels, time)
    head = np.frombuffer(buf, dtype, count=full_groups * n_chan * per_group, offset=start)
    chans = head.reshape(full_groups, n_chan, per_group).transpose(1, 0, 2)
    chans = chans.reshape(n_chan, full_groups * per_group)
    if rest:
        tail = np.frombuffer(
            buf,
            dtype,
            count=n_chan * rest,
            offset=start + full_groups * n_chan * per_group * dtype.itemsize,
        )
        chans = np.concatenate([chans, tail.reshape(n_chan, rest)], axis=1)
    data = np.ascontiguousarray(chans[:, :n_samples].T, dtype=np.float64)
    with np.errstate(over="ignore", invalid="ignore"):
        data *= scales
    bad = ~np.isfinite(data)
    if bad.any():
        i, c = np.argwhere(bad)[0]
        raise FileFormatError(
            src, _RPC3, f"non-finite value in channel {c + 1} at sample {i} (corrupt data or SCALE)"
        )

    names = []
    units = []
    for n in range(1, n_chan + 1):
        names.append(_unquote(header.get(f"DESC.CHAN_{n}", "")) or f"ch{n}")
        units.append(_unquote(header.get(f"UNITS.CHAN_{n}", "-")))
    return _history(src, _RPC3, data, _snap_rate(1.0 / dt), _unique_names(names), units)


# ---------------------------------------------------------------------------------------------
# RPC III: writing
# ---------------------------------------------------------------------------------------------
def _fmt_e(x: float) -> str:
    """Shortest round-tripping E format with at least 6 decimals (``3.906250E-03``)."""
    return np.format_float_scientific(float(x), unique=True, min_digits=6, exp_digits=2).upper()


def _is_pow2(n) -> bool:
    return isinstance(n, (int, np.integer)) and n >= 1 and (int(n) & (int(n) - 1)) == 0


def _check_history(history) -> None:
    if not isinstance(history, TimeHistory):
        raise TypeError(f"expected a TimeHistory, got {type(history).__name__}")


def _encode_field(text: str, limit: int, what: str) -> bytes:
    try:
        raw = text.encode("latin-1")
    except UnicodeEncodeError:
        raise ValueError(
            f"{what} {text!r} cannot be stored in an RPC III header (latin-1 text only)"
        ) from None
    if b"\0" in raw:
        raise ValueError(f"{what} {text!r} contains a NUL character")
    if len(raw) > limit - 1:
        raise ValueError(
            f"{what} {text!r} is {len(raw)} bytes; RPC III header fields hold at most "
            f"{limit - 1} (plus the NUL terminator)"
        )
    return raw.ljust(limit, b"\0")


def write_rpc3(
    path,
    history: TimeHistory,
    *,
    data_type: str = "FLOATING_POINT",
    time_type: str | int = "RESPONSE",
    pts_per_frame: int = 1024,
    frames_per_group: int | None = None,
    full_scale: float | Sequence[float] | None = None,
    byte_order: str = "little",
    extra_header: Mapping[str, object] | None = None,
) -> Path:
    """Write a TimeHistory as an MTS RPC III time-history file.

    Parameters
    ----------
    path : str or Path
        Output file (any suffix; ``.rsp`` response, ``.drv`` drive, ``.tim`` time history).
    history : TimeHistory
        The record. Channel names become ``DESC.CHAN_n``, units ``UNITS.CHAN_n`` (latin-1, at
        most 95 characters each).
    data_type : {"FLOATING_POINT", "SHORT_INTEGER"}
        ``FLOATING_POINT`` stores float32 in engineering units (``SCALE`` = 1), exact for
        float32-representable data. ``SHORT_INTEGER`` (understood by every RPC III program)
        stores ``round(x / SCALE)`` as int16 with ``SCALE = full_scale / 32767``: the error is at
        most half a count, ``SCALE / 2``.
    time_type : str or int
        ``TIME_TYPE``: ``DRIVE``, ``RESPONSE``, ``MULT_DRIVE``, ``MULT_RESP``, ``CONFIG_DRIVE``,
        ``CONFIG_RESP``, ``PEAK_PICK`` or the old numeric codes 1-7.
    pts_per_frame : int
        ``PTS_PER_FRAME``, a power of two between 2 and 16384.
    frames_per_group : int, optional
        Frames per group, a power of two; ``PTS_PER_GROUP = pts_per_frame * frames_per_group``.
        Default: groups of ``max(2048, pts_per_frame)`` points.
    full_scale : float or sequence of float, optional
        ``SHORT_INTEGER`` only: engineering-unit full scale per channel (or one for all); the
        default is each channel's peak ``max|x|`` (1 count for an all-zero channel). Data beyond
        the full scale raise ValueError rather than clip.
    byte_order : {"little", "big"}
        ``FORMAT = BINARY_IEEE_LITTLE_END`` or ``BINARY_IEEE_BIG_END``.
    extra_header : mapping, optional
        Further keyword-value pairs (values converted with ``str``); they may replace the
        informational defaults (``DATE``, ``OPERATION``, ``REPEATS``, ``BYPASS_FILTER``,
        ``LOWER_LIMIT.CHAN_n``, ``UPPER_LIMIT.CHAN_n``, ``MAP.CHAN_n``, ``PARTITIONS``...) but not
        keywords that describe the data layout or channel identity.

    Returns
    -------
    Path
        The written file.

    Notes
    -----
    The header starts ``FORMAT, NUM_HEADER_BLOCKS, NUM_PARAMS`` and holds ``FILE_TYPE =
    TIME_HISTORY``, ``TIME_TYPE``, ``DELTA_T`` (E format, shortest exact repr), ``CHANNELS``,
    ``PTS_PER_FRAME``, ``PTS_PER_GROUP``, ``FRAMES``, ``DATA_TYPE``, ``BYPASS_FILTER = 0``,
    ``HALF_FRAMES = 0``, ``REPEATS = 1``, ``INT_FULL_SCALE = 32767`` (integer data), ``DATE``,
    ``OPERATION``, one partition and per channel ``DESC``, ``UNITS``, ``SCALE``,
    ``LOWER_LIMIT``/``UPPER_LIMIT`` (the channel's minimum/maximum) and ``MAP``. A record that
    is not a whole number of frames is padded to the end of its last frame with its last value
    (no step at the end of a drive) and ``SAMPLES`` gives the true length, which
    :func:`read_rpc3` honours; the rest of the last group is zero, as in the MTS specification,
    and the file is zero-padded to a whole number of 512-byte blocks.
    """
    _check_history(history)
    path = Path(path)
    n, n_chan = history.data.shape

    data_type = str(data_type).upper()
    if data_type not in _DATA_TYPES:
        raise ValueError(
            f"data_type must be 'FLOATING_POINT' or 'SHORT_INTEGER', got {data_type!r}"
        )
    tt = str(time_type).upper()
    tt = _TIME_TYPES.get(tt, tt)
    if tt not in _TIME_TYPES.values():
        raise ValueError(
            f"time_type must be one of {', '.join(_TIME_TYPES.values())} (or 1-7), got "
            f"{time_type!r}"
        )
    if not _is_pow2(pts_per_frame) or not 2 <= pts_per_frame <= 16384:
        raise ValueError(
            f"pts_per_frame must be a power of two between 2 and 16384, got {pts_per_frame!r}"
        )
    pts_per_frame = int(pts_per_frame)
    if frames_per_group is None:
        frames_per_group = max(1, 2048 // pts_per_frame)
    if not _is_pow2(frames_per_group):
        raise ValueError(f"frames_per_group must be a power of two, got {frames_per_group!r}")
    per_group = pts_per_frame * int(frames_per_group)
    if byte_order not in ("little", "big"):
        raise ValueError(f"byte_order must be 'little' or 'big', got {byte_order!r}")

    x = history.data
    peak = np.max(np.abs(x), axis=0)
    if data_type == "SHORT_INTEGER":
        if full_scale is None:
            fsc = np.where(peak > 0, peak, _INT16_FULL_SCALE)  # all-zero channel: SCALE = 1
        else:
            fsc = np.broadcast_to(np.asarray(full_scale, dtype=float), (n_chan,)).copy()
            if not np.all(np.isfinite(fsc) & (fsc > 0)):
                raise ValueError(f"full_scale must be positive and finite, got {full_scale!r}")
            over = np.flatnonzero(peak > fsc)
            if over.size:
                c = over[0]
                raise ValueError(
                    f"channel {history.names[c]!r} peaks at {peak[c]:.6g} {history.units[c]}, "
                    f"beyond full_scale {fsc[c]:.6g}; SHORT_INTEGER data would clip"
                )
        scales = np.array([float(_fmt_e(s)) for s in fsc / _INT16_FULL_SCALE])
        values = np.clip(np.rint(x / scales), -_INT16_FULL_SCALE, _INT16_FULL_SCALE)
    else:
        big = float(np.finfo(np.float32).max)
        if np.any(peak > big):
            c = int(np.argmax(peak))
            raise ValueError(
                f"channel {history.names[c]!r} peaks at {peak[c]:.6g}, beyond the float32 range "
                "of FLOATING_POINT data"
            )
        scales = np.ones(n_chan)
        values = x

    frames = -(-n // pts_per_frame)
    n_points = frames * pts_per_frame
    n_groups = -(-n_points // per_group)

    now = datetime.datetime.now().strftime("%d-%b-%Y %H:%M:%S")
    records: dict[str, str] = {
        "FORMAT": "BINARY_IEEE_LITTLE_END" if byte_order == "little" else "BINARY_IEEE_BIG_END",
        "NUM_HEADER_BLOCKS": "",
        "NUM_PARAMS": "",
        "FILE_TYPE": "TIME_HISTORY",
        "TIME_TYPE": tt,
        "DELTA_T": _fmt_e(1.0 / history.fs),
        "CHANNELS": str(n_chan),
        "PTS_PER_FRAME": str(pts_per_frame),
        "PTS_PER_GROUP": str(per_group),
        "FRAMES": str(frames),
        "DATA_TYPE": data_type,
        "BYPASS_FILTER": "0",
        "HALF_FRAMES": "0",
        "REPEATS": "1",
    }
    if data_type == "SHORT_INTEGER":
        records["INT_FULL_SCALE"] = str(_INT16_FULL_SCALE)
    if n != n_points:
        records["SAMPLES"] = str(n)
    records |= {
        "DATE": now,
        "OPERATION": "vrig.io.write_rpc3",
        "PARTITIONS": "1",
        "PART.CHAN_1": "1",
        "PART.NCHAN_1": str(n_chan),
    }
    lo, hi = x.min(axis=0), x.max(axis=0)
    for c in range(n_chan):
        k = c + 1
        records[f"DESC.CHAN_{k}"] = history.names[c]
        records[f"UNITS.CHAN_{k}"] = history.units[c]
        records[f"SCALE.CHAN_{k}"] = _fmt_e(scales[c])
        records[f"LOWER_LIMIT.CHAN_{k}"] = _fmt_e(lo[c])
        records[f"UPPER_LIMIT.CHAN_{k}"] = _fmt_e(hi[c])
        records[f"MAP.CHAN_{k}"] = str(k)

    reserved = set(_LAYOUT_KEYWORDS)
    reserved |= {f"{p}.CHAN_{c + 1}" for p in ("DESC", "UNITS", "SCALE") for c in range(n_chan)}
    for key, value in (extra_header or {}).items():
        key_text = str(key).strip()
        if not key_text:
            raise ValueError("extra_header keywords must not be empty")
        if key_text.upper() in reserved:
            raise ValueError(
                f"extra_header may not set {key_text}: it describes the data layout or a "
                "channel and is written from the TimeHistory and the arguments"
            )
        records[key_text] = str(value)

    n_params = len(records)
    if n_params > _MAX_PARAMS:
        raise ValueError(
            f"the header would need {n_params} keyword records; RPC III allows at most "
            f"{_MAX_PARAMS} ({n_chan} channels with 6 records each)"
        )
    n_blocks = -(-n_params // 4)
    records["NUM_HEADER_BLOCKS"] = str(n_blocks)
    records["NUM_PARAMS"] = str(n_params)
    head = b"".join(
        _encode_field(key, _KEY_LEN, "header keyword")
        + _encode_field(value, _VALUE_LEN, f"value of {key}")
        for key, value in records.items()
    )
    head = head.ljust(n_blocks * _BLOCK, b"\0")

    dtype = np.dtype(("<" if byte_order == "little" else ">") + _DATA_TYPES[data_type])
    out = np.zeros((n_chan, n_groups * per_group), dtype=dtype)
    out[:, :n] = values.T
    out[:, n:n_points] = values[-1][:, None]  # hold the last value to the end of the frame
    body = out.reshape(n_chan, n_groups, per_group).transpose(1, 0, 2).tobytes()
    with atomic_write(path) as f:
        f.write(head)
        f.write(body)
        f.write(bytes(_padded(len(body)) - len(body)))  # whole 512-byte blocks
    return path


# ---------------------------------------------------------------------------------------------
# CSV
# ---------------------------------------------------------------------------------------------
_COLUMN = re.compile(r"^(.*?)\s*\[([^\[\]]*)\]\s*$")


def write_csv(path, history: TimeHistory) -> Path:
    """Write ``time,<name> [<unit>],...`` followed by one row per sample.

    Parameters
    ----------
    path : str or Path
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


# ---------------------------------------------------------------------------------------------
# MATLAB
# ---------------------------------------------------------------------------------------------
def write_mat(path, history: TimeHistory) -> Path:
    """Write a MATLAB (v5) ``.mat`` file with ``data`` (N x channels), ``fs``, ``names`` and
    ``units`` (cell arrays of char).

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
    corrupt file from crashing SciPy's reader (see :mod:`vrig._mat5`).

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


# ---------------------------------------------------------------------------------------------
# dispatch
# ---------------------------------------------------------------------------------------------
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
        Passed to the format's reader (e.g. ``fs`` for :func:`read_csv`).

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
    history : TimeHistory
    **kwargs
        Passed to the format's writer (e.g. ``data_type`` for :func:`write_rpc3`).

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
