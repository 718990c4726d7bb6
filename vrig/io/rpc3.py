"""MTS RPC III time histories (``.rsp``, ``.drv``, ``.tim``): :func:`read_rpc3`,
:func:`read_rpc3_header` and :func:`write_rpc3`.

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

Header text
-----------
A header value holds at most 95 bytes of latin-1 text (plus the NUL terminator). Channel names,
units and other values are written by a fixed rule, :func:`rpc3_text`, so no character makes a
write fail (a strain unit ``µε`` is everyday; latin-1 has ``µ`` but no ``ε``):

1. text that latin-1 encodes, without control characters, is written as it is (``µm``, ``°C``);
2. any other text is written in ASCII: each character of :data:`RPC3_TRANSLITERATION` by its
   entry (``µ``/``μ`` -> ``u``, ``ε`` -> ``e``, ``Ω`` -> ``Ohm``, ``°`` -> ``deg``, the Greek
   alphabet by ISO 843 but ``β`` -> ``b``), accented letters and compatibility forms by their
   Unicode NFKD decomposition without the accents (``é`` -> ``e``, ``²`` -> ``2``), control
   characters (NUL, tab, line breaks) by a space, anything else by ``?``: ``µε`` -> ``ue``.

A value still longer than 95 bytes is refused (``ValueError``) by :func:`write_rpc3`.
The rule is not invertible on its own (``ue`` could have been written ``ue``): the original is
kept beside the file by whoever needs it (:class:`vrig.TestFolder` also cuts longer labels to
95 bytes, and stores the original names and units in ``summary.json`` and gives them back when
it reads the record). :func:`rpc3_labels` says what :func:`read_rpc3` will return for a
record's channels once written.
"""

from __future__ import annotations

import datetime
import math
import unicodedata
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import NamedTuple

import numpy as np

from ..errors import FileFormatError
from ..files import MAX_FILE_BYTES, atomic_write, read_bytes
from ..timehistory import TimeHistory
from ._common import _check_history, _history

__all__ = [
    "DELTA_T_RANGE",
    "RPC3_SUFFIXES",
    "RPC3_TRANSLITERATION",
    "read_rpc3",
    "read_rpc3_header",
    "rpc3_labels",
    "rpc3_text",
    "write_rpc3",
]

RPC3_SUFFIXES = (".rsp", ".drv", ".tim")
"""File suffixes handled as RPC III time histories by :func:`vrig.io.read` and
:func:`vrig.io.write`."""

DELTA_T_RANGE = (1e-9, 86400.0)
"""The time steps [s] :func:`read_rpc3` and :func:`write_rpc3` accept: sample rates from one a
day (1.16e-5 Hz) to 1 GHz. A test-rig time history outside is not physical (a corrupt or
mis-scaled DELTA_T, e.g. 1e-300 s) and is refused instead of becoming fs = 1e300 Hz."""

_RPC3 = "RPC III"  # format name in error messages
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


class _Layout(NamedTuple):
    """What the header says about the data section."""

    dtype: np.dtype  # stored sample type, with its byte order
    data_type: str  # SHORT_INTEGER or FLOATING_POINT
    dt: float  # DELTA_T, s
    n_chan: int
    per_frame: int  # points per frame (per channel)
    per_group: int  # points per group (per channel)
    frames: int
    n_samples: int  # record length (per channel)


def _rpc3_dtype(header: dict[str, str], src: str) -> tuple[np.dtype, str]:
    """The stored sample dtype and DATA_TYPE from FORMAT, FILE_TYPE and DATA_TYPE."""
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
    return np.dtype(_FORMATS[fmt] + _DATA_TYPES[data_type]), data_type


def _rpc3_layout(header: dict[str, str], src: str) -> _Layout:
    """The data layout a parsed header describes (header part of :func:`read_rpc3`)."""
    dtype, data_type = _rpc3_dtype(header, src)
    if "DELTA_T" not in header:
        raise FileFormatError(src, _RPC3, "header keyword DELTA_T is missing")
    dt = _parse_float(header["DELTA_T"], "DELTA_T", src)
    lo, hi = DELTA_T_RANGE
    if not lo <= dt <= hi:
        raise FileFormatError(
            src,
            _RPC3,
            f"DELTA_T = {header['DELTA_T']!r} s is not a time step of a rig record: it must lie "
            f"in {lo:g}..{hi:g} s (sample rates {1 / hi:.3g} Hz to {1 / lo:.3g} Hz)",
        )
    n_chan = _required_int(header, "CHANNELS", src, 1)
    per_frame = _required_int(header, "PTS_PER_FRAME", src, 1)
    per_group = _required_int(header, "PTS_PER_GROUP", src, 1)
    frames = _required_int(header, "FRAMES", src, 1)
    _check_sizes(header, n_chan, per_group, frames * per_frame, src)
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
    return _Layout(dtype, data_type, dt, n_chan, per_frame, per_group, frames, n_samples)


def _check_sizes(header, n_chan: int, per_group: int, n_points: int, src: str) -> None:
    """What the header's sizes claim, in exact integers, before any array is made: one group
    and the whole record must each fit in :data:`~vrig.files.MAX_FILE_BYTES` (no readable
    file holds more; numpy would refuse the arrays with a bare ValueError, or try to allocate
    them)."""
    item = int(np.dtype(_DATA_TYPES[header.get("DATA_TYPE", "SHORT_INTEGER").upper()]).itemsize)
    for what, dims in (
        ("one group of PTS_PER_GROUP x CHANNELS", (per_group, n_chan)),
        ("a record of FRAMES x PTS_PER_FRAME x CHANNELS", (n_points, n_chan)),
    ):
        n_bytes = math.prod(dims) * item
        if n_bytes > MAX_FILE_BYTES:
            raise FileFormatError(
                src,
                _RPC3,
                f"the header claims {what} = {' x '.join(map(str, dims))} points of {item} "
                f"bytes ({n_bytes:.3g} bytes), more than any readable file holds "
                f"({MAX_FILE_BYTES} bytes, vrig.files.MAX_FILE_BYTES): a corrupt header",
            )


def _channel_labels(header: dict[str, str], n_chan: int) -> tuple[list[str], list[str]]:
    """Channel names (``DESC.CHAN_n``, made unique) and units (``UNITS.CHAN_n``)."""
    names = []
    units = []
    for n in range(1, n_chan + 1):
        names.append(_unquote(header.get(f"DESC.CHAN_{n}", "")) or f"ch{n}")
        units.append(_unquote(header.get(f"UNITS.CHAN_{n}", "-")))
    return _unique_names(names), units


def _stored_groups(layout: _Layout, available: int, src: str) -> tuple[int, int]:
    """(whole groups, points of a last group cut after its frames) in a data section of
    ``available`` bytes: whole groups (standard) or a last group cut after its frames, each
    optionally padded to a whole block; any other size is a FileFormatError."""
    n_chan, per_group, dtype = layout.n_chan, layout.per_group, layout.dtype
    n_points = layout.frames * layout.per_frame
    n_groups = -(-n_points // per_group)
    full_groups, rest = divmod(n_points, per_group)
    whole = n_groups * per_group * n_chan * dtype.itemsize
    compact = n_points * n_chan * dtype.itemsize
    if available == whole or (available != compact and whole < available <= _padded(whole)):
        return n_groups, 0
    if not (rest and compact <= available <= _padded(compact)):
        what = "truncated: it" if available < compact else "inconsistent with the header: it"
        raise FileFormatError(
            src,
            _RPC3,
            f"data section is {what} holds {available} bytes but CHANNELS = {n_chan}, "
            f"FRAMES = {layout.frames}, PTS_PER_FRAME = {layout.per_frame}, PTS_PER_GROUP = "
            f"{per_group} and DATA_TYPE = {layout.data_type} need {whole} bytes ({n_groups} "
            f"groups of {per_group} points x {n_chan} channels x {dtype.itemsize} bytes)",
        )
    return full_groups, rest


def _channel_scales(header: dict[str, str], layout: _Layout, src: str) -> np.ndarray:
    """``SCALE.CHAN_n`` per channel for integer data (required), ones for float data."""
    scales = np.ones(layout.n_chan)
    if layout.data_type == "SHORT_INTEGER":
        for n in range(1, layout.n_chan + 1):
            key = f"SCALE.CHAN_{n}"
            if key not in header:
                raise FileFormatError(
                    src, _RPC3, f"{key} is missing (needed to scale SHORT_INTEGER data)"
                )
            scales[n - 1] = _parse_float(header[key], key, src)
    return scales


def _demultiplex(buf: bytes, start: int, layout: _Layout, full_groups: int, rest: int):
    """The stored samples as a float64 (samples, channels) array: (groups, channels, points)
    -> (channels, time), the record cut to ``n_samples``."""
    dtype, n_chan, per_group = layout.dtype, layout.n_chan, layout.per_group
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
    return np.ascontiguousarray(chans[:, : layout.n_samples].T, dtype=np.float64)


def _rpc3_payload(buf: bytes, start: int, header, layout: _Layout, src: str) -> np.ndarray:
    """The samples in engineering units, (samples, channels) float64, from the data section
    starting at byte ``start`` (payload part of :func:`read_rpc3`)."""
    full_groups, rest = _stored_groups(layout, len(buf) - start, src)
    scales = _channel_scales(header, layout, src)
    data = _demultiplex(buf, start, layout, full_groups, rest)
    with np.errstate(over="ignore", invalid="ignore"):
        data *= scales
    bad = ~np.isfinite(data)
    if bad.any():
        i, c = np.argwhere(bad)[0]
        raise FileFormatError(
            src, _RPC3, f"non-finite value in channel {c + 1} at sample {i} (corrupt data or SCALE)"
        )
    return data


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
        ``FRAMES`` or (integer data) ``SCALE.CHAN_n``; a ``DELTA_T`` outside
        :data:`DELTA_T_RANGE`; a group or record larger than any readable file (checked before
        anything is allocated); a data section whose size does not match
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
    layout = _rpc3_layout(header, src)
    data = _rpc3_payload(buf, n_blocks * _BLOCK, header, layout, src)
    names, units = _channel_labels(header, layout.n_chan)
    return _history(src, _RPC3, data, _snap_rate(1.0 / layout.dt), names, units)


# ---------------------------------------------------------------------------------------------
# RPC III: writing
# ---------------------------------------------------------------------------------------------
def _fmt_e(x: float) -> str:
    """Shortest round-tripping E format with at least 6 decimals (``3.906250E-03``)."""
    return np.format_float_scientific(float(x), unique=True, min_digits=6, exp_digits=2).upper()


def _is_pow2(n) -> bool:
    return isinstance(n, (int, np.integer)) and n >= 1 and (int(n) & (int(n) - 1)) == 0


RPC3_TRANSLITERATION: dict[str, str] = {
    "\u00b5": "u",  # micro sign (latin-1, but written in ASCII with the rest of the text)
    "\u03bc": "u",  # Greek mu, as the micro prefix (SI in ASCII: um, us, ue)
    "\u2126": "Ohm",  # ohm sign
    "\u03a9": "Ohm",  # capital omega, as the unit
    "\u00b0": "deg",
    "\u00b1": "+-",
    "\u00d7": "x",
    "\u00b7": ".",
    "\u2212": "-",  # minus sign
    "\u2013": "-",
    "\u2014": "-",
    "\u2030": "permille",
    "\u221a": "sqrt",
    **dict(
        zip(
            "\u03b1\u03b2\u03b3\u03b4\u03b5\u03b6\u03b7\u03b8\u03b9\u03ba\u03bb\u03bd"
            "\u03be\u03bf\u03c0\u03c1\u03c3\u03c2\u03c4\u03c5\u03c6\u03c7\u03c8\u03c9",
            "a b g d e z i th i k l n x o p r s s t y f ch ps o".split(),
            strict=True,
        )
    ),
    **dict(
        zip(
            "\u0391\u0392\u0393\u0394\u0395\u0396\u0397\u0398\u0399\u039a\u039b\u039c"
            "\u039d\u039e\u039f\u03a0\u03a1\u03a3\u03a4\u03a5\u03a6\u03a7\u03a8",
            "A B G D E Z I Th I K L M N X O P R S T Y F Ch Ps".split(),
            strict=True,
        )
    ),
}
"""Characters :func:`rpc3_text` writes as an ASCII spelling in an RPC III header that latin-1
cannot hold as it is: the micro sign and Greek mu as ``u`` (SI prefixes in ASCII: ``um``,
``ue``), ohm as ``Ohm``, a few unit symbols, and the Greek alphabet by ISO 843 (but ``β`` ->
``b``, ``μ`` -> ``u``, ``Ω`` -> ``Ohm``)."""


def _ascii_char(ch: str) -> str:
    """One character of a text that is written in ASCII (rule 2 of :func:`rpc3_text`)."""
    if ch.isascii():
        return " " if unicodedata.category(ch) == "Cc" else ch
    if ch in RPC3_TRANSLITERATION:
        return RPC3_TRANSLITERATION[ch]
    if unicodedata.category(ch) == "Cc":
        return " "
    plain = "".join(
        c for c in unicodedata.normalize("NFKD", ch) if not unicodedata.combining(c)
    )
    return plain if plain and plain.isascii() else "?"


def rpc3_text(text: str) -> str:
    """The text an RPC III header stores for ``text`` (a channel name, a unit, a value).

    Text that latin-1 encodes, without control characters, is stored as it is; any other text by
    the rule of the module documentation (*Header text*): in ASCII (:data:`RPC3_TRANSLITERATION`,
    then Unicode NFKD without accents, control characters as spaces, anything else ``?``). The
    length is not changed but by the ASCII spellings (a header value holds 95 bytes: longer text
    is refused by :func:`write_rpc3`).

    Parameters
    ----------
    text : str
        The text to store.

    Returns
    -------
    str
        Latin-1 text (one byte a character) without control characters.

    Examples
    --------
    >>> rpc3_text("µε"), rpc3_text("µm"), rpc3_text("N·m"), rpc3_text("kΩ")
    ('ue', 'µm', 'N·m', 'kOhm')
    """
    text = str(text)
    try:
        text.encode("latin-1")
        plain = not any(unicodedata.category(ch) == "Cc" for ch in text)
    except UnicodeEncodeError:
        plain = False
    if not plain:
        text = "".join(_ascii_char(ch) for ch in text)
    return text


def rpc3_labels(history: TimeHistory) -> tuple[list[str], list[str]]:
    """The channel names and units :func:`read_rpc3` returns for ``history`` once written by
    :func:`write_rpc3`: equal to ``history.names`` and ``history.units`` unless
    :func:`rpc3_text` changed them or the reader's rules do (surrounding blanks and quotes
    removed, an empty name read as ``ch<n>``, repeated names made unique).

    Parameters
    ----------
    history : TimeHistory
        The record.

    Returns
    -------
    names, units : list of str

    Raises
    ------
    ValueError
        For a label longer than 95 bytes once stored (as :func:`write_rpc3`).
    """
    header = {}
    for k, (name, unit) in enumerate(zip(history.names, history.units, strict=True), start=1):
        header[f"DESC.CHAN_{k}"] = _text(_encode_field(rpc3_text(name), _VALUE_LEN, "name"))
        header[f"UNITS.CHAN_{k}"] = _text(_encode_field(rpc3_text(unit), _VALUE_LEN, "unit"))
    return _channel_labels(header, history.n_channels)


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


class _WriteOptions(NamedTuple):
    """The validated layout options of :func:`write_rpc3`."""

    data_type: str  # SHORT_INTEGER or FLOATING_POINT
    time_type: str  # TIME_TYPE keyword value
    pts_per_frame: int
    per_group: int  # points per group (per channel)
    byte_order: str  # "little" or "big"


def _check_rate(fs: float) -> None:
    """A sample rate whose DELTA_T lies in :data:`DELTA_T_RANGE` (ValueError otherwise: the
    file would not read back)."""
    lo, hi = DELTA_T_RANGE
    if not lo <= 1.0 / fs <= hi:
        raise ValueError(
            f"an RPC III file holds time steps of {lo:g}..{hi:g} s (DELTA_T_RANGE); the record's "
            f"fs = {fs:g} Hz is outside ({1 / hi:.3g} Hz to {1 / lo:.3g} Hz)"
        )


def _write_options(
    data_type, time_type, pts_per_frame, frames_per_group, byte_order
) -> _WriteOptions:
    """Check and normalise :func:`write_rpc3`'s layout arguments (ValueError if invalid)."""
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
    return _WriteOptions(data_type, tt, pts_per_frame, per_group, byte_order)


def _stored_values(history: TimeHistory, data_type: str, full_scale) -> tuple[np.ndarray, ...]:
    """(``SCALE`` per channel, the values to store): int16 counts ``round(x / SCALE)`` for
    SHORT_INTEGER, the data themselves (SCALE 1) for FLOATING_POINT. ValueError on data beyond
    ``full_scale`` or the float32 range."""
    x = history.data
    n_chan = x.shape[1]
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
    return scales, values


def _header_records(history: TimeHistory, opts: _WriteOptions, scales) -> dict[str, str]:
    """The header keyword records in file order (``NUM_HEADER_BLOCKS`` and ``NUM_PARAMS`` still
    empty), without the caller's ``extra_header``."""
    n, n_chan = history.data.shape
    frames = -(-n // opts.pts_per_frame)
    n_points = frames * opts.pts_per_frame
    now = datetime.datetime.now().strftime("%d-%b-%Y %H:%M:%S")
    little = opts.byte_order == "little"
    records: dict[str, str] = {
        "FORMAT": "BINARY_IEEE_LITTLE_END" if little else "BINARY_IEEE_BIG_END",
        "NUM_HEADER_BLOCKS": "",
        "NUM_PARAMS": "",
        "FILE_TYPE": "TIME_HISTORY",
        "TIME_TYPE": opts.time_type,
        "DELTA_T": _fmt_e(1.0 / history.fs),
        "CHANNELS": str(n_chan),
        "PTS_PER_FRAME": str(opts.pts_per_frame),
        "PTS_PER_GROUP": str(opts.per_group),
        "FRAMES": str(frames),
        "DATA_TYPE": opts.data_type,
        "BYPASS_FILTER": "0",
        "HALF_FRAMES": "0",
        "REPEATS": "1",
    }
    if opts.data_type == "SHORT_INTEGER":
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
    x = history.data
    lo, hi = x.min(axis=0), x.max(axis=0)
    for c in range(n_chan):
        k = c + 1
        records[f"DESC.CHAN_{k}"] = rpc3_text(history.names[c])
        records[f"UNITS.CHAN_{k}"] = rpc3_text(history.units[c])
        records[f"SCALE.CHAN_{k}"] = _fmt_e(scales[c])
        records[f"LOWER_LIMIT.CHAN_{k}"] = _fmt_e(lo[c])
        records[f"UPPER_LIMIT.CHAN_{k}"] = _fmt_e(hi[c])
        records[f"MAP.CHAN_{k}"] = str(k)
    return records


def _add_extra_header(records: dict[str, str], extra_header, n_chan: int) -> None:
    """Add the caller's keyword records; ValueError for an empty keyword or one that describes
    the data layout or a channel's identity."""
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
        records[key_text] = rpc3_text(str(value))


def _encode_header(records: dict[str, str], n_chan: int) -> bytes:
    """The header blocks: the records as 32-byte keywords and 96-byte values, four to a
    512-byte block, ``NUM_HEADER_BLOCKS`` and ``NUM_PARAMS`` filled in."""
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
    return head.ljust(n_blocks * _BLOCK, b"\0")


def _rpc3_header_bytes(history: TimeHistory, opts: _WriteOptions, scales, extra_header) -> bytes:
    """The encoded header of a record (header part of :func:`write_rpc3`)."""
    records = _header_records(history, opts, scales)
    n_chan = history.data.shape[1]
    _add_extra_header(records, extra_header, n_chan)
    return _encode_header(records, n_chan)


def _rpc3_payload_bytes(values: np.ndarray, opts: _WriteOptions) -> bytes:
    """The data section without its block padding (payload part of :func:`write_rpc3`): the
    record held at its last value to the end of its last frame, zeros to the end of the last
    group, stored as (groups, channels, points)."""
    n, n_chan = values.shape
    frames = -(-n // opts.pts_per_frame)
    n_points = frames * opts.pts_per_frame
    n_groups = -(-n_points // opts.per_group)
    endian = "<" if opts.byte_order == "little" else ">"
    dtype = np.dtype(endian + _DATA_TYPES[opts.data_type])
    out = np.zeros((n_chan, n_groups * opts.per_group), dtype=dtype)
    out[:, :n] = values.T
    out[:, n:n_points] = values[-1][:, None]  # hold the last value to the end of the frame
    return out.reshape(n_chan, n_groups, opts.per_group).transpose(1, 0, 2).tobytes()


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
        The record. Channel names become ``DESC.CHAN_n``, units ``UNITS.CHAN_n``, as
        :func:`rpc3_text` stores them (latin-1 text as it is, any other text transliterated to
        ASCII: ``µε`` -> ``ue``; :func:`rpc3_labels` says what reads back), at most 95 bytes
        each.
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
        Further keyword-value pairs (values converted with ``str`` and stored by
        :func:`rpc3_text`); they may replace the
        informational defaults (``DATE``, ``OPERATION``, ``REPEATS``, ``BYPASS_FILTER``,
        ``LOWER_LIMIT.CHAN_n``, ``UPPER_LIMIT.CHAN_n``, ``MAP.CHAN_n``, ``PARTITIONS``...) but not
        keywords that describe the data layout or channel identity.

    Returns
    -------
    Path
        The written file.

    Raises
    ------
    ValueError
        Among others: a sample rate whose time step lies outside :data:`DELTA_T_RANGE` (the
        file would not read back).

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
    _check_rate(history.fs)
    path = Path(path)
    opts = _write_options(data_type, time_type, pts_per_frame, frames_per_group, byte_order)
    scales, values = _stored_values(history, opts.data_type, full_scale)
    head = _rpc3_header_bytes(history, opts, scales, extra_header)
    body = _rpc3_payload_bytes(values, opts)
    with atomic_write(path) as f:
        f.write(head)
        f.write(body)
        f.write(bytes(_padded(len(body)) - len(body)))  # whole 512-byte blocks
    return path
