"""Safe files: atomic writes, a folder replaced in one swap, and guarded reads.

Every vrig writer goes through this module, so a kill (``kill -9``, power loss after the
``fsync``) or a Ctrl-C never leaves a half-written file where a good one was:

* :func:`atomic_write` writes into a temporary file in the target's directory, flushes and
  ``fsync``-s it, then renames it over the target with :func:`os.replace` (atomic on POSIX and
  Windows) and ``fsync``-s the directory. Readers see the old content or the new one, never a
  mixture. An exception (including :class:`KeyboardInterrupt`) inside the ``with`` block
  removes the temporary file and leaves the target as it was.
* :func:`staged_directory` builds a whole folder beside the old one and swaps it in (old folder
  renamed aside, new folder renamed in, old folder deleted); :func:`recover_directory` puts the
  old folder back when a kill struck between the two renames.
* :func:`folder_lock` is the one advisory lock of a folder: every :func:`staged_directory` swap
  holds it, so two writers of one folder take turns (the second waits, bounded, or fails with
  :class:`~vrig.errors.FolderLockedError` naming the holder) and :func:`recover_directory`
  never puts an old folder back while a writer holds the lock (mid-swap, the old folder is set
  aside on purpose). A long job (``vrig reconstruct``) takes it before it plays anything and
  holds it to the end, so a second job on the same folder fails up front.

Locks
-----
The lock of folder ``DIR/NAME`` is an ``flock`` (exclusive) on the file ``DIR/.NAME.vrig-lock``
beside it (not inside: the folder is replaced by each swap). The kernel drops it the moment its
holder dies, however it dies (``kill -9`` too), so a lock is never stale; the file holds the
holder's pid, for the message, and is deleted on release (a process that then locks a deleted
file sees that it is no longer the one at that name and tries again). The lock is re-entrant
within a thread of a process; another thread of the same process waits like another process.
It is advisory: only vrig's writers take it. Linux and other POSIX systems only: on Windows
(no ``fcntl``), and on a file system without locks (``flock`` fails with ``ENOLCK``,
``EOPNOTSUPP``), :func:`folder_lock` locks only between the threads of one process, so two
processes writing one folder are not kept apart there (each swap is still atomic, but a reader's
:func:`recover_directory` may put an old folder back mid-swap); run one writer per folder.

Temporary names
---------------
A temporary file or folder is named ``.NAME.tmp-XXXXXXXX`` (a dot, the target's name, ``.tmp-``
and eight random hex digits), a folder set aside during a swap ``.NAME.old-XXXXXXXX`` (always
whole: the old folder) and one being deleted after the swap ``.NAME.del-XXXXXXXX``, all in the
target's directory. Only a kill can leave one behind (a Python exception removes it). The leading
dot hides them from ``ls``, and no vrig reader takes them for data: their names match no QanTiM
record, model or summary name and end in no time-history suffix (:func:`is_temporary` recognises
them, and the lock file ``.NAME.vrig-lock``). The next swap of the same target, holding its
lock, deletes what kills left beside it: its ``.del-`` folders, its ``.old-`` folders when the
target exists (the swap that set them aside was completed; when the target is missing, the
``.old-`` folder is put back instead) and its ``.tmp-`` folders and files (only the lock's holder
makes them, so with the lock held every one but the swap's own is debris of a writer that
died). Inside the folder, temporaries are never carried into the new folder. A temporary file of
:func:`atomic_write` beside a single file (not a folder) is left alone: no lock says whether its
writer still runs.

Reading
-------
:func:`open_regular`, :func:`read_bytes` and :func:`read_npz` refuse what is not a regular file (a
FIFO would block the reader forever, ``/dev/zero`` never ends; symlinks are followed first) and
files larger than :data:`MAX_FILE_BYTES`, with a :class:`~vrig.errors.FileFormatError` naming the
file. :func:`read_npz` also checks each array's header against the bytes stored before reading
it, so a truncated or tampered ``.npz`` cannot make it allocate more than the file holds.
(The identification package keeps its own copy of this scheme, :mod:`identification._files`,
since it never imports vrig.)
"""

from __future__ import annotations

import contextlib
import errno
import os
import re
import shutil
import stat
import threading
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import IO

import numpy as np

from identification._files import (
    _fsync_dir,
    _prefix,
    _sibling,
    atomic_write,
)
from identification._files import read_npz as _guarded_npz

from .errors import FileFormatError, FolderLockedError

try:
    import fcntl
except ImportError:  # Windows: no flock (see the module documentation)
    fcntl = None

__all__ = [
    "LOCK_WAIT_S",
    "MAX_FILE_BYTES",
    "atomic_write",
    "file_kind",
    "folder_lock",
    "is_temporary",
    "mount_points",
    "open_regular",
    "read_bytes",
    "read_npz",
    "recover_directory",
    "staged_directory",
]

MAX_FILE_BYTES = 2 * 1024**3
"""Largest file (bytes) vrig readers accept: 2 GiB, e.g. 250 million float64 samples in ``.npz``
(a 70-hour, 1 kHz, 1-channel record) or 500 million RPC III float32 samples. Larger (or
ever-growing) files raise :class:`~vrig.errors.FileFormatError` instead of exhausting memory."""

LOCK_WAIT_S = 10.0
"""Seconds a writer waits for the lock of a folder another writer holds (:func:`folder_lock`)
before it gives up with :class:`~vrig.errors.FolderLockedError`: long enough for another
process's save to finish, short enough to say so soon when a long job holds the folder."""

_TEMP = re.compile(r"^\..+\.((tmp|old|del)-[0-9a-f]{8}|vrig-lock)$")


def is_temporary(path) -> bool:
    """True for a name made by :func:`atomic_write` or :func:`staged_directory`
    (``.NAME.tmp-XXXXXXXX``, ``.NAME.old-XXXXXXXX``, ``.NAME.del-XXXXXXXX``) or the lock file
    of :func:`folder_lock` (``.NAME.vrig-lock``).

    Parameters
    ----------
    path : str or os.PathLike
        A file or folder name (only its last component is looked at).
    """
    return bool(_TEMP.match(Path(path).name))


# ---------------------------------------------------------------------------------- locks
class _Held:
    """This process's hold on one folder's lock: a re-entrant thread lock, the lock file's
    descriptor (holding the ``flock``) and the nesting depth."""

    def __init__(self):
        self.thread_lock = threading.RLock()
        self.fd: int | None = None
        self.depth = 0


_HELD: dict[str, _Held] = {}
_NO_LOCKS = {
    getattr(errno, name)
    for name in ("ENOLCK", "EOPNOTSUPP", "ENOTSUP", "ENOSYS")
    if hasattr(errno, name)
}
_HELD_GUARD = threading.Lock()


def _forget_locks_in_child() -> None:
    """After ``fork``: the child holds none of the parent's locks (its copies of the lock
    files' descriptors would keep the parent's ``flock`` alive after the parent lets go)."""
    global _HELD_GUARD
    for held in _HELD.values():
        if held.fd is not None:
            with contextlib.suppress(OSError):
                os.close(held.fd)
    _HELD.clear()
    _HELD_GUARD = threading.Lock()


if hasattr(os, "register_at_fork"):
    os.register_at_fork(after_in_child=_forget_locks_in_child)


def _lock_file(path: Path) -> Path:
    """``DIR/.NAME.vrig-lock`` of the folder ``DIR/NAME`` (``path`` already a real path)."""
    return path.with_name(f".{path.name[:200]}.vrig-lock")


def _holder(lock: Path) -> int | None:
    """The pid written in a lock file (None when unreadable)."""
    try:
        text = lock.read_text(encoding="ascii").strip()
    except (OSError, UnicodeDecodeError):
        return None
    return int(text) if text.isdigit() else None


def _busy(path: Path, lock: Path, waited: float) -> FolderLockedError:
    pid = _holder(lock)
    who = "another vrig process" if pid is None else f"vrig process {pid}"
    same = " (this process, in another thread)" if pid == os.getpid() else ""
    after = f" (waited {waited:.1f} s)" if waited >= 0.05 else ""
    return FolderLockedError(
        f"results folder {path} is being written by {who}{same}{after}: wait until it has "
        "finished, or write to another folder",
        path=path,
        pid=pid,
    )


def _same_file(fd: int, lock: Path) -> bool:
    """Whether the open lock file ``fd`` is still the file at ``lock`` (a holder that lets go
    deletes it: a lock on the deleted file locks nothing)."""
    try:
        now = os.stat(lock)
    except FileNotFoundError:
        return False
    mine = os.fstat(fd)
    return (now.st_dev, now.st_ino) == (mine.st_dev, mine.st_ino)


def _flock(path: Path, lock: Path, deadline: float, waited_from: float) -> int:
    """The descriptor of ``lock`` once this process holds its ``flock`` (FolderLockedError at
    ``deadline``); the holder's pid written into it."""
    flags = os.O_RDWR | os.O_CREAT | getattr(os, "O_CLOEXEC", 0)
    while True:
        fd = os.open(lock, flags, 0o644)
        try:
            while True:
                try:
                    fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
                    break
                except OSError as exc:
                    if exc.errno in _NO_LOCKS:  # a file system without locks: as on Windows
                        return fd
                    if not isinstance(exc, BlockingIOError):
                        raise
                    now = time.monotonic()
                    if now >= deadline:
                        raise _busy(path, lock, now - waited_from) from None
                    time.sleep(min(0.02, deadline - now))
            if _same_file(fd, lock):
                os.ftruncate(fd, 0)
                os.write(fd, f"{os.getpid()}\n".encode("ascii"))
                return fd
        except BaseException:
            os.close(fd)
            raise
        os.close(fd)  # locked a file its holder deleted on release: take the new one


def _release(lock: Path, held: _Held) -> None:
    """Drop this process's ``flock`` (the lock file deleted first, while still held)."""
    fd, held.fd = held.fd, None
    if fd is None:
        return
    with contextlib.suppress(OSError):
        if _same_file(fd, lock):
            os.unlink(lock)
    os.close(fd)  # closing the descriptor drops the flock


@contextlib.contextmanager
def folder_lock(path, *, timeout: float = LOCK_WAIT_S) -> Iterator[Path]:
    """Hold the advisory lock of the folder ``path`` (see *Locks* in the module documentation).

    Re-entrant in the thread that holds it (a :func:`staged_directory` swap inside a job that
    holds the lock does not wait for itself). The folder's parent is created when missing (the
    lock file lives there).

    Parameters
    ----------
    path : str or os.PathLike
        The folder (it need not exist yet; a symlink: the folder it points to).
    timeout : float
        Seconds to wait while another process or thread holds the lock; ``0``: fail at once.

    Yields
    ------
    Path
        The lock file, ``.NAME.vrig-lock`` beside the folder.

    Raises
    ------
    FolderLockedError
        When the lock is still held by another process (or thread) after ``timeout`` seconds;
        the message names the holder's pid.
    OSError
        When the lock file cannot be created (a read-only parent folder...).
    """
    path = Path(os.path.realpath(path))
    lock = _lock_file(path)
    start = time.monotonic()
    wait = max(float(timeout), 0.0)
    with _HELD_GUARD:
        held = _HELD.setdefault(str(path), _Held())
    if not held.thread_lock.acquire(timeout=wait if wait > 0 else -1, blocking=wait > 0):
        raise _busy(path, lock, time.monotonic() - start)
    try:
        if held.depth == 0 and fcntl is not None:
            path.parent.mkdir(parents=True, exist_ok=True)
            held.fd = _flock(path, lock, start + wait, start)
        held.depth += 1
        try:
            yield lock
        finally:
            held.depth -= 1
            if held.depth == 0:
                _release(lock, held)
    finally:
        held.thread_lock.release()


# ---------------------------------------------------------------------------------- folders
def _link_or_copy(src, dst) -> None:
    """Hard link ``src`` as ``dst`` (no data copied), or copy it where links are impossible."""
    try:
        os.link(src, dst, follow_symlinks=False)
    except OSError:
        shutil.copy2(src, dst, follow_symlinks=False)


def _carry(old: Path, new: Path, keep: Callable[[str], bool]) -> None:
    """Link the entries of ``old`` for which ``keep(name)`` is true into ``new``."""
    for entry in os.scandir(old):
        if not keep(entry.name) or os.path.lexists(new / entry.name):
            continue
        if entry.is_dir(follow_symlinks=False):
            shutil.copytree(
                entry.path, new / entry.name, symlinks=True, copy_function=_link_or_copy
            )
        else:
            _link_or_copy(entry.path, new / entry.name)


def _set_aside(path: Path) -> list[Path]:
    """The ``.NAME.old-XXXXXXXX`` folders beside ``path`` ([] when its parent is missing)."""
    prefix = _prefix(path, "old")
    try:
        return [
            Path(e.path)
            for e in os.scandir(path.parent)
            if e.name.startswith(prefix) and is_temporary(e.name) and e.is_dir()
        ]
    except OSError:  # no parent folder
        return []


def recover_directory(path) -> bool:
    """Put back a folder that a kill left set aside in the middle of a swap.

    When ``path`` does not exist but ``.NAME.old-XXXXXXXX`` (exactly one) does, the kill came
    between the two renames of :func:`staged_directory`: the set-aside folder is the old folder,
    whole, and is renamed back to ``path``. Only when no other writer holds the folder's lock
    (:func:`folder_lock`): a living writer between its two renames set the old folder aside on
    purpose and is about to finish its swap.

    Parameters
    ----------
    path : str or os.PathLike
        The folder a :func:`staged_directory` swap was replacing.

    Returns
    -------
    bool
        Whether a folder was put back.
    """
    path = Path(os.path.realpath(path))  # a symlink's folder, as staged_directory swaps it
    if os.path.lexists(path) or not _set_aside(path):
        return False
    with contextlib.ExitStack() as stack:
        try:
            stack.enter_context(folder_lock(path, timeout=0))
        except OSError:  # FolderLockedError: a writer is mid-swap; or a read-only place
            return False
        aside = _set_aside(path)
        if os.path.lexists(path) or len(aside) != 1:
            return False
        os.rename(aside[0], path)
        _fsync_dir(path.parent)
        return True


def mount_points(path) -> list[Path]:
    """The mount points inside folder ``path``, ``path`` itself included (symlinks not
    followed); stops at the first one found below ``path``.

    Replacing a folder deletes its old content: a mounted file system inside it (a USB disk, a
    network share, a bind mount) would be emptied, and a folder that is itself a mount point
    cannot be renamed aside. :func:`staged_directory` refuses both (``vrig reconstruct
    --overwrite`` before anything is played).

    Parameters
    ----------
    path : str or os.PathLike
        A folder (a path that is not a folder: none).

    Returns
    -------
    list of Path
    """
    path = Path(path)
    if not path.is_dir():
        return []
    if os.path.ismount(path):
        return [path]
    for top, dirs, _files in os.walk(path):
        for name in dirs:
            if os.path.ismount(os.path.join(top, name)):
                return [Path(top, name)]
    return []


@contextlib.contextmanager
def staged_directory(
    path, *, keep: Callable[[str], bool] | None = None, timeout: float = LOCK_WAIT_S
) -> Iterator[Path]:
    """Build a folder beside ``path`` and swap it in when the ``with`` block ends without error.

    The whole build and swap hold the folder's lock (:func:`folder_lock`), and start by deleting
    what killed writers left beside it (*Temporary names* in the module documentation).

    Parameters
    ----------
    path : str or Path
        The folder to create or replace (a symlink to a folder: the folder it points to).
    keep : callable, optional
        ``keep(name)`` is true for the entries of an existing folder that must survive the
        replacement (files the new content does not own); they are hard-linked (or copied) into
        the new folder before the swap. Default: keep nothing.
    timeout : float
        Seconds to wait for the folder's lock while another writer holds it.

    Yields
    ------
    Path
        The new, empty folder ``.NAME.tmp-XXXXXXXX`` to write into.

    Notes
    -----
    The swap renames the old folder to ``.NAME.old-XXXXXXXX``, the new one to ``path``, then the
    old one to ``.NAME.del-XXXXXXXX`` and deletes it (so a half-deleted folder never carries the
    ``.old-`` name that :func:`recover_directory` restores). An exception in the block deletes
    the new folder and leaves ``path`` untouched; a kill leaves the old folder whole: still at
    ``path``, or (between the two renames) set aside, where :func:`recover_directory` finds it.

    Raises
    ------
    FolderLockedError
        When another writer still holds the folder's lock after ``timeout`` seconds.
    FileExistsError
        When ``path`` exists and is not a folder.
    OSError
        (``errno.EBUSY``) ``path`` is or holds a mount point (:func:`mount_points`): nothing
        is written or deleted.
    """
    path = Path(os.path.realpath(path))
    with folder_lock(path, timeout=timeout):
        recover_directory(path)
        _remove_debris(path)
        if os.path.lexists(path) and not path.is_dir():
            raise FileExistsError(f"{path} exists and is not a folder")
        mounted = mount_points(path)
        if mounted:
            raise OSError(
                errno.EBUSY,
                f"{mounted[0]} is a mount point: replacing {path} would empty (or fail to move) "
                "a mounted file system; choose another folder",
                str(path),
            )
        with _staging(path, keep) as new:
            yield new


@contextlib.contextmanager
def _staging(path: Path, keep: Callable[[str], bool] | None) -> Iterator[Path]:
    """The build and swap of :func:`staged_directory` (its lock held, debris removed)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    while True:
        new = _sibling(path, "tmp")
        try:
            new.mkdir()
            break
        except FileExistsError:
            continue
    try:
        if path.is_dir():
            new.chmod(stat.S_IMODE(path.stat().st_mode))
        yield new
        if path.is_dir() and keep is not None:
            _carry(path, new, keep)
        _fsync_dir(new)
    except BaseException:
        shutil.rmtree(new, ignore_errors=True)
        raise
    _swap(new, path)


def _cwd_inside(path: Path) -> Path | None:
    """The working directory relative to ``path`` when it lies inside ``path``, else None."""
    try:
        return Path(os.getcwd()).relative_to(path)
    except (OSError, ValueError):
        return None


def _swap(new: Path, path: Path) -> None:
    """Rename ``new`` to ``path``, setting an existing ``path`` aside first and deleting it.

    A process working inside ``path`` (``vrig reconstruct --out .``) moves to the same place in
    the new folder (or its top), not into the deleted old one."""
    aside, cwd = None, _cwd_inside(path)
    try:
        if path.is_dir():
            aside = _sibling(path, "old")
            os.rename(path, aside)
        try:
            os.rename(new, path)
        except BaseException:
            if aside is not None:
                os.rename(aside, path)
            raise
    except BaseException:
        shutil.rmtree(new, ignore_errors=True)
        raise
    _fsync_dir(path.parent)
    if cwd is not None:
        os.chdir(path / cwd if (path / cwd).is_dir() else path)
    if aside is not None:
        trash = _sibling(path, "del")
        os.rename(aside, trash)
        shutil.rmtree(trash, ignore_errors=True)


def _remove_debris(path: Path) -> None:
    """Delete what killed writers left beside ``path`` (its lock held): the ``.NAME.del-``
    folders (old folders whose deletion a kill cut short), the ``.NAME.tmp-`` folders and files
    (new folders a kill cut short: only the lock's holder makes them) and, when ``path``
    exists, its ``.NAME.old-`` folders (left by a kill after a completed swap)."""
    kinds = ("del", "tmp", "old") if path.is_dir() else ("del", "tmp")
    prefixes = tuple(_prefix(path, kind) for kind in kinds)
    with contextlib.suppress(OSError):
        for entry in os.scandir(path.parent):
            if not (entry.name.startswith(prefixes) and is_temporary(entry.name)):
                continue
            if entry.is_dir(follow_symlinks=False):
                shutil.rmtree(entry.path, ignore_errors=True)
            else:
                with contextlib.suppress(OSError):
                    os.unlink(entry.path)


# ---------------------------------------------------------------------------------- reading
def file_kind(path) -> str | None:
    """What ``path`` is, in words, when it is not a regular file: ``"no file"`` (nothing
    there), ``"a folder"``, ``"a FIFO (named pipe)"``, ``"a character device"``, ... (symlinks
    followed); None for a regular file.

    Parameters
    ----------
    path : str or os.PathLike
        The path to look at.

    Raises
    ------
    OSError
        The path cannot be looked at (e.g. a name too long, no permission on a parent).
    """
    try:
        mode = os.stat(path).st_mode
    except (FileNotFoundError, NotADirectoryError):
        return "no file"
    return None if stat.S_ISREG(mode) else _kind(mode)


def _kind(mode: int) -> str:
    for test, name in (
        (stat.S_ISDIR, "a folder"),
        (stat.S_ISFIFO, "a FIFO (named pipe)"),
        (stat.S_ISCHR, "a character device"),
        (stat.S_ISBLK, "a block device"),
        (stat.S_ISSOCK, "a socket"),
    ):
        if test(mode):
            return name
    return "a special file"


def open_regular(path, fmt: str, *, limit: int | None = None) -> IO[bytes]:
    """Open a file for binary reading after checking it is a regular file of sane size.

    Parameters
    ----------
    path : str or Path
        The file; symlinks are followed.
    fmt : str
        The format expected (``"RPC III"``, ``"CSV"``...), for the error message.
    limit : int, optional
        Size limit in bytes; default :data:`MAX_FILE_BYTES`.

    Returns
    -------
    file object
        Open in binary mode, positioned at the start.

    Raises
    ------
    FileNotFoundError
        If there is no such file.
    FileFormatError
        If it is a folder, FIFO, device or socket, or larger than ``limit``.
    """
    limit = MAX_FILE_BYTES if limit is None else int(limit)
    flags = os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_BINARY", 0)
    try:
        fd = os.open(path, flags | getattr(os, "O_CLOEXEC", 0))  # O_NONBLOCK: a FIFO can't block
    except IsADirectoryError:  # Windows
        raise FileFormatError(path, fmt, "it is a folder, not a file") from None
    try:
        info = os.fstat(fd)
        if not stat.S_ISREG(info.st_mode):
            raise FileFormatError(
                path,
                fmt,
                f"it is {_kind(info.st_mode)}, not a regular file (vrig reads only regular files)",
            )
        if info.st_size > limit:
            raise FileFormatError(
                path,
                fmt,
                f"it holds {info.st_size} bytes, more than the {limit}-byte limit "
                "(vrig.files.MAX_FILE_BYTES)",
            )
        if hasattr(os, "set_blocking"):
            os.set_blocking(fd, True)
        return os.fdopen(fd, "rb")
    except BaseException:
        os.close(fd)
        raise


def read_bytes(path, fmt: str, *, limit: int | None = None) -> bytes:
    """The content of a regular file of at most ``limit`` bytes (see :func:`open_regular`).

    Memory is allocated for the bytes the file holds, not for ``limit``. A file that grows
    beyond the limit while it is read raises :class:`~vrig.errors.FileFormatError` too.

    Parameters
    ----------
    path : str or os.PathLike
        The file to read.
    fmt : str
        The format expected, for the error message (e.g. ``"RPC III"``).
    limit : int, optional
        Largest file size accepted, in bytes; default :data:`MAX_FILE_BYTES`.
    """
    limit = MAX_FILE_BYTES if limit is None else int(limit)
    with open_regular(path, fmt, limit=limit) as f:
        parts = [f.read(os.fstat(f.fileno()).st_size + 1)]
        total = len(parts[0])
        while total <= limit:  # grown since fstat, or a size-0 pseudo file: read on, capped
            chunk = f.read(min(1 << 20, limit + 1 - total))
            if not chunk:
                break
            parts.append(chunk)
            total += len(chunk)
    if total > limit:
        raise FileFormatError(path, fmt, f"it grew beyond the {limit}-byte limit while being read")
    return parts[0] if len(parts) == 1 else b"".join(parts)


def read_npz(path, fmt: str, *, limit: int | None = None) -> dict[str, np.ndarray]:
    """All arrays of an ``.npz`` file, ``{name: array}``, read defensively.

    Parameters
    ----------
    path : str or Path
        The file to read.
    fmt : str
        The format expected, for the error message (``"vrig .npz"``).
    limit : int, optional
        Largest file and largest total of uncompressed arrays in bytes; default
        :data:`MAX_FILE_BYTES`.

    Raises
    ------
    FileNotFoundError
        If there is no such file.
    FileFormatError
        Not a regular file, too large, not a zip archive, a member that is not a ``.npy``
        array, a truncated or corrupt member, object arrays.
    """
    limit = MAX_FILE_BYTES if limit is None else int(limit)
    open_regular(path, fmt, limit=limit).close()  # the regular-file and size checks, in vrig's words
    # the identification package's guarded reader (vrig depends on identification, never the
    # reverse): every array header is checked against the bytes stored before allocating
    return _guarded_npz(path, limit=limit, error=lambda detail: FileFormatError(path, fmt, detail))
