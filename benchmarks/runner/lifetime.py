"""Process lifetime: child processes that die with the runner, and a pid lock file.

**Children die with their parent.** A ``kill -9`` of ``python -m benchmarks run`` gives the
runner no chance to stop its pool workers or the thesis-report process: left alone they run on
(a worker blocked on its task queue never sees end-of-file, because every worker holds a copy of
the queue's write end) and the thesis process keeps writing into the folder a re-run uses.
:func:`die_with_parent`, called first thing in each child, makes the kernel end it instead:

* on Linux, ``prctl(PR_SET_PDEATHSIG, SIGKILL)`` (through :mod:`ctypes`): the kernel sends
  ``SIGKILL`` to the child the moment its parent exits, however it exits, with no polling and
  nothing to keep alive in the child. The signal follows the *thread* that started the child;
  the runner starts its children from the thread that runs the backend and ends them before
  that thread returns, so this is the parent's lifetime. A parent that died before the call
  cannot signal any more: the child compares ``os.getppid()`` with the parent pid it was given
  and exits at once if they differ (no race);
* elsewhere (macOS, or a Linux without ``prctl``), a daemon watchdog thread checks every
  ``interval`` seconds that ``os.getppid()`` is still the parent and ends the process with
  ``os._exit`` when it is not (the child is re-parented when its parent dies).

The kernel signal is preferred where it exists: it cannot be starved by a busy interpreter (a
watchdog thread needs the GIL, which a long C call such as a MuJoCo rollout or a numba kernel
may hold for seconds) and it cannot be missed.

**Pid lock.** :class:`PidLock` is a lock file holding its owner's pid. The lock itself is an
``flock`` on the file (POSIX): the kernel drops it the moment the owner dies, however it dies, so
a lock left by a dead process is stale by construction, with no pid guessing (a recycled pid
cannot keep it) and no race between two processes taking over the same stale lock. The pid in
the file says who holds a live lock. Without ``fcntl`` (Windows) the file is created with
``O_EXCL`` and a lock whose pid is dead (:func:`pid_alive`) is stale and taken over.
"""

from __future__ import annotations

import contextlib
import ctypes
import os
import signal
import sys
import threading
from pathlib import Path

try:
    import fcntl
except ImportError:  # Windows
    fcntl = None

__all__ = ["LockHeldError", "PidLock", "die_with_parent", "pid_alive"]

_PR_SET_PDEATHSIG = 1


def _prctl_pdeathsig(sig: int) -> bool:
    """``prctl(PR_SET_PDEATHSIG, sig)``; False where it is not available."""
    if not sys.platform.startswith("linux"):
        return False
    try:
        libc = ctypes.CDLL(None, use_errno=True)
        return libc.prctl(_PR_SET_PDEATHSIG, int(sig), 0, 0, 0) == 0
    except (OSError, AttributeError):
        return False


def _watchdog(parent_pid: int, interval: float) -> None:
    def watch() -> None:
        while True:
            if os.getppid() != parent_pid:
                os._exit(1)
            threading.Event().wait(interval)

    threading.Thread(target=watch, name="vrig-parent-watchdog", daemon=True).start()


def die_with_parent(parent_pid: int, *, interval: float = 0.5) -> str:
    """Make this (child) process end when its parent ``parent_pid`` ends (see module doc).

    Parameters
    ----------
    parent_pid : int
        The pid of the parent as the parent saw it (``os.getpid()`` there), passed to the child.
    interval : float
        Polling interval [s] of the watchdog thread (only where ``prctl`` is not available).

    Returns
    -------
    str
        ``"pdeathsig"`` or ``"watchdog"``: the mechanism in force. Does not return (the process
        exits) when the parent is already gone.
    """
    how = "pdeathsig" if _prctl_pdeathsig(signal.SIGKILL) else "watchdog"
    if os.getppid() != int(parent_pid):  # the parent died before the signal was armed
        os._exit(1)
    if how == "watchdog":
        _watchdog(int(parent_pid), interval)
    return how


def pid_alive(pid: int) -> bool:
    """Whether process ``pid`` runs (exists and, where ``/proc`` says so, is not a zombie)."""
    if pid <= 0:
        return False
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # exists, owned by someone else
        pass
    with contextlib.suppress(OSError, ValueError, IndexError):
        stat = Path(f"/proc/{pid}/stat").read_text()
        if stat[stat.rindex(")") + 2] in "ZX":  # zombie or dead: it no longer runs
            return False
    return True


class LockHeldError(RuntimeError):
    """The lock is held by a live process.

    Attributes
    ----------
    pid : int or None
        The owner's pid (None if its file could not be read).
    path : Path
        The lock file.
    """

    def __init__(self, path: Path, pid: int | None):
        who = "another process" if pid is None else f"the running process {pid}"
        super().__init__(f"{path} is held by {who}")
        self.path, self.pid = Path(path), pid


class PidLock:
    """A lock file naming its owner's pid; stale when the owner is dead (see the module doc).

    >>> with PidLock(out / "thesis_reproduction.lock"):      # doctest: +SKIP
    ...     write_the_report()

    Parameters
    ----------
    path : str or Path
        The lock file (its folder must exist). It is left in place on release (emptied): with
        ``flock`` the file's existence means nothing, only the lock on it.
    """

    def __init__(self, path):
        self.path = Path(path)
        self._fd: int | None = None

    def owner(self) -> int | None:
        """The pid written in the lock file (None if missing, empty or unreadable)."""
        try:
            text = self.path.read_text(encoding="ascii").strip()
        except (OSError, UnicodeDecodeError):
            return None
        return int(text) if text.isdigit() else None

    def acquire(self) -> PidLock:
        """Take the lock; raises :class:`LockHeldError` when a live process holds it."""
        if self._fd is not None:
            return self
        if fcntl is None:
            return self._acquire_exclusive()
        fd = os.open(self.path, os.O_RDWR | os.O_CREAT, 0o644)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:  # BlockingIOError: held (by a live process: the kernel says so)
            os.close(fd)
            raise LockHeldError(self.path, self.owner()) from None
        os.ftruncate(fd, 0)
        os.write(fd, f"{os.getpid()}\n".encode("ascii"))
        os.fsync(fd)
        self._fd = fd
        return self

    def _acquire_exclusive(self) -> PidLock:
        for _attempt in range(3):
            try:
                fd = os.open(self.path, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o644)
            except FileExistsError:
                pid = self.owner()
                if pid is not None and pid_alive(pid):
                    raise LockHeldError(self.path, pid) from None
                self.path.unlink(missing_ok=True)  # stale: its owner is dead
                continue
            os.write(fd, f"{os.getpid()}\n".encode("ascii"))
            os.fsync(fd)
            self._fd = fd
            return self
        raise LockHeldError(self.path, self.owner())

    def release(self) -> None:
        """Give the lock up (this process must hold it; otherwise nothing happens)."""
        if self._fd is None:
            return
        fd, self._fd = self._fd, None
        if fcntl is None:
            os.close(fd)
            self.path.unlink(missing_ok=True)
            return
        os.ftruncate(fd, 0)
        os.close(fd)  # closing the last descriptor drops the flock

    def __enter__(self) -> PidLock:
        return self.acquire()

    def __exit__(self, *exc) -> None:
        self.release()
