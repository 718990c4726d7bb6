"""Model files (internal): atomic writes and a guarded ``.npz`` reader.

The package never imports vrig; vrig's file safety builds on these (:mod:`vrig.files` documents
the scheme and adds staged folders and the recovery of interrupted ones):

* :func:`atomic_write` writes a temporary ``.NAME.tmp-XXXXXXXX`` in the target's folder,
  ``fsync``-s it and renames it over the target (:func:`os.replace`): a kill leaves the old file
  or the new one, and only a kill leaves the hidden temporary file behind.
* :func:`read_npz` opens only regular files (no FIFO, no device) of at most ``limit`` bytes and
  checks every array header against the bytes stored before anything is allocated, so a
  truncated, foreign or tampered file raises ``error(detail)`` instead of ``BadZipFile``,
  ``EOFError``, ``MemoryError`` or a hang.
"""

from __future__ import annotations

import contextlib
import errno
import math
import os
import secrets
import stat
import tokenize
import zipfile
import zlib
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import IO

import numpy as np

__all__ = ["atomic_write", "read_npz"]

_BROKEN = (  # what zipfile and numpy raise on corrupt input (found by fuzzing)
    zipfile.BadZipFile,
    zlib.error,
    EOFError,
    ValueError,
    NotImplementedError,
    KeyError,
    OverflowError,
    UnicodeDecodeError,
    SyntaxError,
    tokenize.TokenError,  # a .npy header numpy parses with tokenize
    OSError,  # a seek to an offset from a corrupt directory (EINVAL); other errnos re-raised
)


def _prefix(path: Path, kind: str) -> str:
    """``.NAME.kind-`` (NAME cut to 200 characters: the whole name stays under NAME_MAX)."""
    return f".{path.name[:200]}.{kind}-"


def _sibling(path: Path, kind: str) -> Path:
    return path.with_name(_prefix(path, kind) + secrets.token_hex(4))


def _fsync_dir(folder: Path) -> None:
    """Make a rename in ``folder`` durable (no-op where directories cannot be opened)."""
    try:
        fd = os.open(folder, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)


def _create_temporary(path: Path) -> tuple[Path, int]:
    """A new temporary sibling of ``path`` (mode: the target's, else 0o666 less the umask)."""
    flags = os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_BINARY", 0)
    flags |= getattr(os, "O_CLOEXEC", 0)
    while True:
        tmp = _sibling(path, "tmp")
        try:
            fd = os.open(tmp, flags, 0o666)
            break
        except FileExistsError:  # 1 in 4 billion: draw another name
            continue
    try:
        os.chmod(tmp, stat.S_IMODE(os.stat(path).st_mode))  # keep an existing file's mode
    except OSError:
        pass
    return tmp, fd


@contextlib.contextmanager
def atomic_write(path, mode: str = "wb", *, encoding: str | None = None) -> Iterator[IO]:
    """Open a temporary file that replaces ``path`` when the ``with`` block ends without error.

    Parameters
    ----------
    path : str or Path
        The target file. Its directory must exist.
    mode : {"wb", "w"}
        Binary or text.
    encoding : str, optional
        Text mode only (default UTF-8). Lines are written as given (no newline translation).

    Yields
    ------
    file object
        The temporary file ``.NAME.tmp-XXXXXXXX`` beside the target (see the module docstring).

    Examples
    --------
    >>> with atomic_write("summary.json", "w") as f:  # doctest: +SKIP
    ...     f.write(text)
    """
    if mode not in ("wb", "w"):
        raise ValueError(f"atomic_write mode must be 'wb' or 'w', got {mode!r}")
    path = Path(path)
    tmp, fd = _create_temporary(path)
    try:
        try:
            if mode == "w":
                f = os.fdopen(fd, "w", encoding=encoding or "utf-8", newline="")
            else:
                f = os.fdopen(fd, "wb")
        except BaseException:
            os.close(fd)
            raise
        with f:
            yield f
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except BaseException:
        with contextlib.suppress(OSError):
            tmp.unlink()
        raise
    _fsync_dir(path.parent)


def _open_regular(path: Path, limit: int, error: Callable[[str], Exception]) -> IO[bytes]:
    fd = os.open(path, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_BINARY", 0))
    try:
        info = os.fstat(fd)
        if not stat.S_ISREG(info.st_mode):
            raise error("it is not a regular file (a folder, FIFO or device)")
        if info.st_size > limit:
            raise error(f"it holds {info.st_size} bytes, more than the {limit}-byte limit")
        if hasattr(os, "set_blocking"):
            os.set_blocking(fd, True)
        return os.fdopen(fd, "rb")
    except BaseException:
        os.close(fd)
        raise


class _Invalid(Exception):
    """A problem found while reading (converted to ``error(detail)`` by :func:`read_npz`)."""


def _member(zf: zipfile.ZipFile, info: zipfile.ZipInfo) -> np.ndarray:
    """One ``.npy`` member, its header checked against its stored size before reading."""
    with zf.open(info) as m:
        version = np.lib.format.read_magic(m)
        if version == (1, 0):
            shape, _, dtype = np.lib.format.read_array_header_1_0(m)
        elif version == (2, 0):
            shape, _, dtype = np.lib.format.read_array_header_2_0(m)
        else:
            raise _Invalid(f"array {info.filename!r} has unsupported .npy version {version}")
        if dtype.hasobject:
            raise _Invalid(f"array {info.filename!r} holds Python objects (refused)")
        nbytes = math.prod(shape) * dtype.itemsize
        if nbytes > info.file_size:
            raise _Invalid(
                f"array {info.filename!r} declares shape {shape} ({nbytes} bytes) but stores "
                f"only {info.file_size} bytes (truncated or tampered)"
            )
    with zf.open(info) as m:
        return np.lib.format.read_array(m, allow_pickle=False)


def read_npz(path, *, limit: int, error: Callable[[str], Exception]) -> dict[str, np.ndarray]:
    """All arrays of an ``.npz`` file, ``{name: array}``.

    Parameters
    ----------
    path : str or Path
    limit : int
        Largest file, and largest total of uncompressed arrays, in bytes.
    error : callable
        ``error(detail)`` builds the exception raised for a file that is not a valid ``.npz``.

    Raises
    ------
    FileNotFoundError
        If there is no such file.
    Exception
        ``error(detail)``: not a regular file, too large, not a zip archive, a member that is
        not a ``.npy`` array, a truncated or corrupt member, object arrays.
    """
    with _open_regular(Path(path), limit, error) as f:
        try:
            with zipfile.ZipFile(f) as zf:
                infos = zf.infolist()
                total = sum(i.file_size for i in infos)
                if total > limit:
                    raise _Invalid(
                        f"its arrays hold {total} bytes, more than the {limit}-byte limit"
                    )
                out = {}
                for info in infos:
                    if not info.filename.endswith(".npy"):
                        raise _Invalid(f"member {info.filename!r} is not a .npy array")
                    out[info.filename[:-4]] = _member(zf, info)
                return out
        except _Invalid as exc:
            raise error(str(exc)) from None
        except _BROKEN as exc:
            if isinstance(exc, OSError) and exc.errno != errno.EINVAL:
                raise  # a real I/O error, not a corrupt file
            raise error(f"corrupt or not an .npz archive ({type(exc).__name__}: {exc})") from None
