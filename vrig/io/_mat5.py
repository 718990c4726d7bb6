"""Structural check of MATLAB files before :func:`scipy.io.loadmat` reads them (internal).

SciPy's v5 reader is not hardened against corrupt input (its documentation says so): an element
whose data-type code is not one of the 15 defined codes makes it index a C array out of bounds
and crash the interpreter with a segmentation fault (a corrupt file found by fuzzing
:func:`vrig.io.read_mat`, two changed bytes; scipy/scipy#25349 describes the same defect), and a
forged dimension can make it allocate far more than the file holds. :func:`check` walks every
data element of a level-5 (v6/v7) file -- inside ``miMATRIX`` and, decompressed, inside
``miCOMPRESSED`` elements -- and refuses unknown type codes, elements that overrun their parent,
nesting deeper than 32 levels, fewer than 2 or negative dimensions (a char array without
dimensions crashes SciPy's ``chars_to_strings``, another segmentation fault found by fuzzing),
and arrays with more elements than bytes.
It also names v7.3 (HDF5) files, which SciPy cannot read.

File layout (MATLAB "MAT-File Format", level 5): a 128-byte header (text, subsystem offset,
version at bytes 124-125, endian indicator ``IM``/``MI`` at 126-127), then data elements: an
8-byte tag (type code, byte count) or a 4-byte "small element" tag (byte count in the upper 16
bits, at most 4 data bytes), the data, and (nested elements) padding to 8 bytes.
"""

from __future__ import annotations

import math
import struct
import zlib

from ..errors import FileFormatError

__all__ = ["check"]

_FMT = "MATLAB .mat"
_TYPES = frozenset({1, 2, 3, 4, 5, 6, 7, 9, 12, 13, 14, 15, 16, 17, 18})  # miINT8 .. miUTF32
_NUMERIC = frozenset({1, 2, 3, 4, 5, 6, 7, 9, 12, 13})  # SciPy has a dtype for these codes ...
_CHARS = _NUMERIC | {16, 17, 18}  # ... and for miUTF8/16/32
_INT8_STRING = frozenset({1, 16})  # miINT8 (or miUTF8, accepted by SciPy)
_INT32S = frozenset({5, 6})  # miINT32 (or miUINT32)
_MI_UINT32, _MI_MATRIX, _MI_COMPRESSED = 6, 14, 15
_CELL, _STRUCT, _OBJECT, _CHAR, _SPARSE, _FUNCTION, _OPAQUE = 1, 2, 3, 4, 5, 16, 17
_NUMERIC_CLASSES = range(6, 16)  # mxDOUBLE_CLASS .. mxUINT64_CLASS
_MAX_DEPTH = 32
_MAX_DIMS = 32


def version(buf: bytes) -> tuple[int, int]:
    """(major, minor) as SciPy decides it: (0, 0) level 4, (1, 0) level 5, (2, 0) v7.3."""
    if len(buf) < 128 or 0 in buf[:4]:
        return (0, 0)
    major_first = int(buf[126] == ord("I"))
    return buf[124 + major_first], buf[125 - major_first]


def _elements(buf: bytes, pos: int, end: int, order: str, src, top: bool) -> list[tuple]:
    """``(type code, data start, data end, small)`` of the elements in ``buf[pos:end]``.

    Nested elements are padded to 8 bytes and the padding must lie inside the parent, so the
    positions agree with SciPy's sequential reads; top-level elements are not padded."""
    out = []
    while pos < end:
        if end - pos < 8:
            raise FileFormatError(src, _FMT, f"truncated data element tag at byte {pos}")
        mdtype, nbytes = struct.unpack_from(order + "II", buf, pos)
        small = mdtype >> 16 != 0
        if small:  # small data element: at most 4 bytes inside the tag
            mdtype, nbytes, start = mdtype & 0xFFFF, mdtype >> 16, pos + 4
            stop, nxt = start + nbytes, pos + 8
            if nbytes > 4:
                raise FileFormatError(src, _FMT, f"small data element at byte {pos} is corrupt")
        else:
            start = pos + 8
            stop = start + nbytes
            nxt = stop if top else start + -(-nbytes // 8) * 8
        if mdtype not in _TYPES:
            raise FileFormatError(
                src, _FMT, f"data element at byte {pos} has unknown type code {mdtype}"
            )
        if nxt > end:
            raise FileFormatError(
                src,
                _FMT,
                f"data element at byte {pos} needs {nxt - pos} bytes, only {end - pos} remain "
                "(truncated or corrupt file)",
            )
        out.append((mdtype, start, stop, small))
        pos = nxt
    return out


class _Cursor:
    """The sub-elements of one matrix, taken in the order SciPy reads them."""

    def __init__(self, subs, where: int, src):
        self.subs, self.where, self.src, self.i = subs, where, src, 0

    def take(self, allowed, what: str, *, full: bool = False) -> tuple[int, int]:
        if self.i == len(self.subs):
            raise FileFormatError(
                self.src, _FMT, f"the matrix at byte {self.where} ends before its {what}"
            )
        mdtype, a, b, small = self.subs[self.i]
        self.i += 1
        if mdtype not in allowed or (full and small):
            raise FileFormatError(
                self.src,
                _FMT,
                f"the {what} of the matrix at byte {self.where} has type code {mdtype}",
            )
        return a, b


def _dims(buf, a: int, b: int, order: str, src, where: int, room: int) -> tuple[int, ...]:
    if (b - a) % 4 or not 2 <= (b - a) // 4 <= _MAX_DIMS:  # MATLAB arrays have >= 2 dims
        raise FileFormatError(
            src, _FMT, f"the matrix at byte {where} must have 2 to {_MAX_DIMS} dimensions"
        )
    dims = struct.unpack_from(f"{order}{(b - a) // 4}i", buf, a)
    if min(dims, default=0) < 0 or math.prod(dims) > room:
        raise FileFormatError(
            src,
            _FMT,
            f"the matrix at byte {where} claims dimensions {dims}, impossible in its {room} bytes",
        )
    return dims


def _matrix(buf: bytes, start: int, stop: int, order: str, src, depth: int) -> None:
    """Check one ``miMATRIX`` element's content: the sub-elements SciPy reads, in order."""
    if depth > _MAX_DEPTH:
        raise FileFormatError(src, _FMT, f"matrices nested deeper than {_MAX_DEPTH} levels")
    if start == stop:
        return  # an empty matrix (e.g. an empty cell)
    where = start - 8
    cur = _Cursor(_elements(buf, start, stop, order, src, top=False), where, src)

    def child(what: str) -> None:
        _matrix(buf, *cur.take({_MI_MATRIX}, what, full=True), order, src, depth + 1)

    a, b = cur.take({_MI_UINT32}, "array flags", full=True)
    if b - a != 8:
        raise FileFormatError(src, _FMT, f"the array flags of the matrix at byte {where} corrupt")
    flags = struct.unpack_from(order + "I", buf, a)[0]
    mclass, is_complex = flags & 0xFF, flags >> 11 & 1
    if mclass == _OPAQUE:
        for what in ("name", "type system", "class name"):
            cur.take(_INT8_STRING, what)
        return child("object")
    dims = _dims(buf, *cur.take(_INT32S, "dimensions"), order, src, where, stop - start)
    cur.take(_INT8_STRING, "name")
    if mclass in _NUMERIC_CLASSES:
        parts = ["real part"] + ["imaginary part"] * is_complex
    elif mclass == _SPARSE:
        parts = ["row indices", "column pointers", "values"] + ["imaginary values"] * is_complex
    elif mclass == _CHAR:
        cur.take(_CHARS, "characters")
        return None
    elif mclass == _CELL:
        for _ in range(math.prod(dims)):
            child("cell")
        return None
    elif mclass in (_STRUCT, _OBJECT):
        return _fields(buf, cur, child, math.prod(dims), mclass == _OBJECT, order, src)
    elif mclass == _FUNCTION:
        return child("function")
    else:
        raise FileFormatError(src, _FMT, f"the matrix at byte {where} has unknown class {mclass}")
    for what in parts:
        cur.take(_NUMERIC, what)
    return None


def _fields(buf, cur: _Cursor, child, n: int, is_object: bool, order: str, src) -> None:
    """The field names and the field matrices of a struct (or object) array of ``n`` items."""
    if is_object:
        cur.take(_INT8_STRING, "class name")
    a, b = cur.take(_INT32S, "field name length")
    length = struct.unpack_from(order + "i", buf, a)[0] if b - a == 4 else 0
    if length <= 0:
        raise FileFormatError(src, _FMT, f"the struct at byte {cur.where} has a corrupt field name")
    a, b = cur.take(_INT8_STRING, "field names")
    for _ in range(n * ((b - a) // length)):
        child("field")


def _inflate(data: bytes, budget: int, src) -> bytes:
    d = zlib.decompressobj()
    try:
        out = d.decompress(data, budget + 1)
    except zlib.error as exc:
        raise FileFormatError(src, _FMT, f"corrupt compressed variable ({exc})") from None
    if len(out) > budget:
        raise FileFormatError(
            src, _FMT, f"compressed variables expand beyond the {budget}-byte limit"
        )
    return out


def check(buf: bytes, src, limit: int) -> None:
    """Raise :class:`~vrig.errors.FileFormatError` unless ``buf`` is a well-formed level-5 file.

    Parameters
    ----------
    buf : bytes
        The whole file.
    src : str or Path
        The file, for messages.
    limit : int
        Largest total size of the decompressed variables.
    """
    major, _ = version(buf)
    if major == 2:
        raise FileFormatError(
            src,
            _FMT,
            "it is a MATLAB v7.3 (HDF5) file, which vrig cannot read; save it with "
            "save(file, ..., '-v7') in MATLAB (or write it with vrig.io.write_mat)",
        )
    if major != 1:
        return  # level 4 (SciPy's pure-Python reader) or unknown: left to SciPy
    order = "<" if buf[126:128] == b"IM" else ">"
    budget = limit
    for mdtype, a, b, _ in _elements(buf, 128, len(buf), order, src, top=True):
        if mdtype == _MI_COMPRESSED:
            inner = _inflate(buf[a:b], budget, src)
            budget -= len(inner)
            for mdt, c, d, _ in _elements(inner, 0, len(inner), order, src, top=False):
                if mdt != _MI_MATRIX:
                    raise FileFormatError(src, _FMT, f"compressed element at {a} holds no matrix")
                _matrix(inner, c, d, order, src, 1)
        elif mdtype == _MI_MATRIX:
            _matrix(buf, a, b, order, src, 1)
        else:
            raise FileFormatError(src, _FMT, f"top-level element at byte {a - 8} is no variable")
