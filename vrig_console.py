"""The ``vrig`` console script: Ctrl-C is one line and exit code 130 from the first instant.

``import vrig`` takes about two seconds (NumPy, SciPy, numba, MuJoCo, gymnasium). A console
script whose entry point lives inside the package runs nothing of its own before that import,
so a Ctrl-C during it printed a raw ``KeyboardInterrupt`` traceback. This module lies outside the
package (it imports nothing heavy) and is the entry point of the ``vrig`` command
(``[project.scripts]`` in ``pyproject.toml``):

* a Ctrl-C while ``vrig`` is imported ends the command with ``vrig COMMAND: interrupted`` on
  stderr and exit code 130;
* the command itself is :func:`vrig.cli.main` (which says ``interrupted`` and returns 130 for a
  Ctrl-C during the command, and keeps what a reconstruction played);
* a Ctrl-C after the command's work exits 130 too (one line, never a traceback and never the
  command's exit code 0); the process then ends at once (``atexit`` functions run, output
  flushed), without the interpreter's finalisation: about 2 s here after a reconstruction,
  during which Python's handler is gone and a Ctrl-C killed the process without a line.

The handler is installed by this module's first statements, when the console script imports
it (through CPython's built-in ``_signal``, before ``signal.py``, ``atexit``, ``threading`` and
every other import), not when :func:`main` is called. What no code of vrig's can cover is what
runs before that: the interpreter's own start-up and its ``site`` module, which executes every
``.pth`` file of the environment (setuptools' editable finder ``__editable___vrig_*_finder`` in a
development install, and whatever other packages put there), then the first lines of the
launcher pip writes (``import re``, and the import system finding and loading this module). That
is 20 to 30 ms on a development install here; a Ctrl-C in it is Python's (a
``KeyboardInterrupt`` traceback with no frame of vrig's, or ``Fatal Python error:
init_import_site``). Only a ``.pth`` file of vrig's own would run earlier, and it would run in
every Python process of the environment: not done.
"""

from __future__ import annotations

# _signal: CPython's built-in signal module, nothing to run (``signal.py`` builds its enums on
# import: milliseconds in which an interrupt landed before the handler); os and sys are loaded
import _signal
import os
import sys

INTERRUPTED = 130


def _command() -> str:
    """``vrig COMMAND`` for the one line (``vrig`` alone before a command is known)."""
    args = [a for a in sys.argv[1:2] if not a.startswith("-")]
    return " ".join(["vrig", *args])


def _interrupt_now(signum, frame) -> None:
    """SIGINT outside the command's own handling (while ``vrig`` is imported, or after the
    command while the interpreter shuts down): flush what was printed, one line, exit 130."""
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except Exception:  # closed, or a reentrant call into the stream this handler cut into
            pass
    try:  # unbuffered: never a reentrant call into sys.stderr's buffer
        os.write(2, f"{_command()}: interrupted\n".encode(errors="replace"))
    finally:
        os._exit(INTERRUPTED)


# the earliest point vrig's code runs (the launcher's ``from vrig_console import main``): Python's
# own handler (a traceback) is replaced at once; a handler someone else installed, or SIGINT
# ignored (a background job of a script), is left as it is until main()
try:
    if _signal.getsignal(_signal.SIGINT) is _signal.default_int_handler:
        _signal.signal(_signal.SIGINT, _interrupt_now)
except ValueError:  # imported by a thread other than the main one: signals are not its own
    pass

import atexit  # noqa: E402  (after the handler: these imports are in its cover)
import signal  # noqa: E402
import threading  # noqa: E402

__all__ = ["main"]


def _interrupted() -> int:
    sys.stderr.write(f"{_command()}: interrupted\n")
    sys.stderr.flush()
    return INTERRUPTED


def _exit(code) -> None:
    """End the process now with ``code``: output flushed and the ``atexit`` functions run as at
    a normal exit, the interpreter's finalisation skipped (about 2 s here after a
    reconstruction, tearing down the objects and the 1,700 modules loaded, during which
    Python's handler is gone and a Ctrl-C killed the process without its line).
    Returns (a normal exit follows) when another non-daemon thread still runs."""
    if any(
        t.is_alive() and not t.daemon
        for t in threading.enumerate()
        if t is not threading.main_thread()
    ):
        return
    atexit._run_exitfuncs()
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except Exception:
            pass
    try:  # what C libraries (MuJoCo's warnings) left in their stdio buffers
        import ctypes

        ctypes.CDLL(None).fflush(None)
    except Exception:
        pass
    os._exit(code if isinstance(code, int) else 1)


def main() -> int:
    """Run ``vrig`` (:func:`vrig.cli.main`) with Ctrl-C handled from the first instant.

    Returns
    -------
    int
        The command's exit code (130 after a Ctrl-C at any moment); normally the process ends
        here instead (:func:`_exit`), with that code.
    """
    if threading.current_thread() is threading.main_thread():
        signal.signal(signal.SIGINT, _interrupt_now)  # vrig.cli.main puts it back when done
    try:
        from vrig.cli import main as run

        code = run()
    except KeyboardInterrupt:  # (when another handler was in force)
        code = _interrupted()
    _exit(code)
    return code


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
