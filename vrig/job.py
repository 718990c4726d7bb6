"""A reconstruction run into a results folder: the job ``vrig reconstruct`` and
``vrig.reconstruct(..., out=FOLDER)`` share.

A job checks the folder before anything is played (a folder or nothing yet, empty unless
``overwrite``, not the working directory or a folder holding it, not a mount point and holding
none, writable; :func:`check_results_folder`, :func:`check_writable`), takes its lock
(:func:`vrig.files.folder_lock`, :meth:`ResultsJob.__enter__`) and holds it to the end of the
save, checks the disk has room for the records (:func:`check_space`), runs the reconstruction,
and writes the QanTiM test folder, its plots and ``summary.json`` in one swap
(:meth:`vrig.TestFolder.save`) with the target check of the run's own identification records
(:func:`target_check`, ``summary.json``'s ``target_check``). A disk that fills up during the save
gets the records and the summary without the plots; when even that fails nothing was saved
(:class:`~vrig.errors.ResultsNotSavedError`). A failure before IT00 keeps what was made (the
identification records, the model, the refused drive) and still raises; a Ctrl-C keeps the
iterations played; a Ctrl-C during the save waits until the folder is written whole
(:class:`Interrupts`). Every stop says what to change (:func:`advice`), in the words of the door
it came through (:data:`CLI_NAMES`, :data:`PYTHON_NAMES`).

The job takes an :class:`~vrig.reconstruction.IterationSettings` already resolved by its caller,
and the settings to record in ``summary.json``; it resolves no default itself.
"""

from __future__ import annotations

import contextlib
import errno
import os
import shutil
import signal
import tempfile
import threading
import warnings
from dataclasses import asdict, dataclass
from pathlib import Path

from .errors import (
    FolderLockedError,
    ReconstructionError,
    ReconstructionInterrupted,
    ResultsFolderError,
    ResultsNotSavedError,
)
from .files import folder_lock, mount_points

__all__ = [
    "CLI_NAMES",
    "PYTHON_NAMES",
    "Interrupts",
    "OptionNames",
    "ResultsJob",
    "advice",
    "check_results_folder",
    "check_space",
    "check_writable",
    "hold_results_folder",
    "interrupted_line",
    "reconstruct_into",
    "settings_record",
    "stop_line",
    "target_check",
]


@dataclass(frozen=True)
class OptionNames:
    """How a job's messages name the caller's options: the command line's flags
    (:data:`CLI_NAMES`) or the Python keywords (:data:`PYTHON_NAMES`).

    Attributes
    ----------
    out, overwrite, out_example, lock_prefix : str
        The results folder (``"--out"``), the permission to replace it, an example of a new
        folder, and what goes before another writer's lock message.
    gain, band, order, method_frf, method_arx_or_frf, adaptive, id_match : str
        The options the advice names.
    """

    out: str
    overwrite: str
    out_example: str
    lock_prefix: str
    gain: str
    band: str
    order: str
    method_frf: str
    method_arx_or_frf: str
    adaptive: str
    id_match: str


CLI_NAMES = OptionNames(
    out="--out", overwrite="--overwrite", out_example="--out results", lock_prefix="--out: ",
    gain="--gain", band="--band", order="--order", method_frf="--method frf",
    method_arx_or_frf="--method arx or frf", adaptive="--strategy adaptive",
    id_match="--id-match",
)  # fmt: skip
PYTHON_NAMES = OptionNames(
    out="results folder", overwrite="overwrite=True", out_example='out="results"',
    lock_prefix="", gain="gain", band="bandwidth", order="order", method_frf='method="frf"',
    method_arx_or_frf='method="arx" or "frf"', adaptive='strategy="adaptive"',
    id_match="id_match=True",
)  # fmt: skip


# ---------------------------------------------------------------------------------------------
# the folder, before anything is played
# ---------------------------------------------------------------------------------------------
def check_results_folder(path: Path, overwrite: bool, names: OptionNames = PYTHON_NAMES) -> None:
    """The results folder before anything runs: a folder (or nothing yet), empty unless
    ``overwrite``, and one the save may replace: not the working directory or a folder holding
    it (the shell would be left in a deleted directory), not a mount point and holding none (a
    mounted file system would be emptied: :func:`vrig.files.mount_points`).

    Parameters
    ----------
    path : str or Path
        The results folder.
    overwrite : bool
        Whether a non-empty folder may be replaced.
    names : OptionNames
        How the message names the caller's options (:data:`CLI_NAMES`, :data:`PYTHON_NAMES`).

    Raises
    ------
    ResultsFolderError
        Naming the folder and what to change.
    """
    try:
        _check_folder(Path(path), overwrite, names)
    except OSError as exc:  # e.g. a name too long for the file system: bad input, up front
        raise ResultsFolderError(f"{names.out} {path}: {exc.strerror or exc}", path=path) from None


def _check_folder(path: Path, overwrite: bool, n: OptionNames) -> None:
    if path.exists() and not path.is_dir():
        raise ResultsFolderError(f"{n.out} {path} is a file, not a folder", path=path)
    if not path.is_dir():
        return
    if any(path.iterdir()) and not overwrite:
        raise ResultsFolderError(
            f"results folder {path} is not empty: pass {n.overwrite} to replace its records, or "
            f"choose another {n.out}",
            path=path,
        )
    here, target = Path.cwd().resolve(), path.resolve()
    if target == here or target in here.parents:
        raise ResultsFolderError(
            f"{n.out} {path} is the current directory or holds it: the results folder is "
            "replaced as a whole, which would leave your shell in a deleted directory; choose a "
            f"new folder (e.g. {n.out_example})",
            path=path,
        )
    mounted = mount_points(path)
    if mounted:
        raise ResultsFolderError(
            f"{n.out} {path}: {mounted[0]} is a mount point; replacing the folder would empty a "
            f"mounted file system (or fail to move it): choose another {n.out}",
            path=path,
        )


def check_writable(path: Path, names: OptionNames = PYTHON_NAMES) -> None:
    """Before the run: ``path`` is (or can be made) a folder this process can write into.

    Creates what is missing and a temporary file to prove it, then removes both again.

    Parameters
    ----------
    path : str or Path
        The results folder.
    names : OptionNames
        How the message names the caller's options (:data:`CLI_NAMES`, :data:`PYTHON_NAMES`).

    Raises
    ------
    ResultsFolderError
        A file on the way, or a folder this process cannot write into.
    """
    path, created = Path(path), []
    try:
        for p in [*reversed(path.parents), path]:
            if not p.exists():
                p.mkdir()
                created.append(p)
            elif not p.is_dir():
                raise ResultsFolderError(
                    f"{names.out} {path}: {p} is a file, not a folder", path=path
                )
        fd, probe = tempfile.mkstemp(dir=path, prefix=".vrig-write-test-")
        os.close(fd)
        os.unlink(probe)
    except OSError as exc:
        why = exc.strerror or str(exc)
        raise ResultsFolderError(
            f"{names.out} {path}: cannot write there ({why})", path=path
        ) from None
    finally:
        for p in reversed(created):
            with contextlib.suppress(OSError):
                p.rmdir()


def hold_results_folder(
    hold: contextlib.ExitStack, out: Path, names: OptionNames = PYTHON_NAMES
) -> None:
    """Take the lock of the results folder ``out`` (:func:`vrig.files.folder_lock`) until
    ``hold`` closes: a second writer is refused here, before it plays anything. Folders made for
    the lock file are removed again when nothing is saved.

    Parameters
    ----------
    hold : contextlib.ExitStack
        Holds the lock until it closes.
    out : str or Path
        The results folder.
    names : OptionNames
        How the message names the caller's options (:data:`CLI_NAMES`, :data:`PYTHON_NAMES`).

    Raises
    ------
    FolderLockedError
        Another writer holds the folder.
    ResultsFolderError
        The parent folder (where the lock file and the swap live) cannot be written.
    """
    out = Path(out)
    missing = [p for p in out.absolute().parents if not p.exists()]  # deepest first
    hold.callback(_remove_empty, missing)  # after the lock's release (last in, first out)
    try:
        hold.enter_context(folder_lock(out, timeout=0))
    except FolderLockedError as exc:
        if not names.lock_prefix:
            raise
        raise FolderLockedError(f"{names.lock_prefix}{exc}", path=exc.path, pid=exc.pid) from None
    except OSError as exc:  # the lock file, like the swap, lives in the parent folder
        why = exc.strerror or str(exc)
        raise ResultsFolderError(
            f"{names.out} {out}: cannot write in its parent folder {out.absolute().parent} "
            f"({why}); the results folder is replaced in one swap, made beside it",
            path=out,
        ) from None


def _remove_empty(folders: list[Path]) -> None:
    for p in folders:
        with contextlib.suppress(OSError):
            p.rmdir()


_RECORD_BYTES = {"rsp": 4, "npz": 8, "mat": 8, "csv": 25}  # per sample and channel, about


def check_space(
    out: Path, desired, rig, iterations: int, fmt: str, names: OptionNames = PYTHON_NAMES
) -> None:
    """Before the run: the disk holding ``out`` has room for the records (identification,
    desired, three per iteration, final) and the plots.

    Parameters
    ----------
    out : str or Path
        The results folder.
    desired : TimeHistory
        The desired record (the identification is as long).
    rig : Rig
        The rig (its numbers of drives and responses).
    iterations : int
        Iterations after IT00.
    fmt : {"rsp", "csv", "mat", "npz"}
        The record format.
    names : OptionNames
        How the message names the caller's options (:data:`CLI_NAMES`, :data:`PYTHON_NAMES`).

    Raises
    ------
    ResultsFolderError
        Saying how much the results need and how much the disk has free.
    """
    out = Path(out)
    n_in, n_out = len(rig.inputs), len(rig.outputs)
    per_iteration = n_in + 2 * n_out
    channels = 2 * n_in + 3 * n_out + (iterations + 2) * per_iteration
    samples = getattr(desired, "n_samples", 0)  # (the identification is as long as the record)
    need = samples * channels * _RECORD_BYTES[fmt] + 4 * 1024**2  # + the plots
    where = next(p for p in [out.absolute(), *out.absolute().parents] if p.exists())
    try:
        free = shutil.disk_usage(where).free
    except OSError:
        return
    if free < need:
        raise ResultsFolderError(
            f"{names.out} {out}: the results need about {need / 1e6:.0f} MB and the disk holding "
            f"it has {free / 1e6:.0f} MB free: free some space or choose another {names.out}",
            path=out,
        )


# ---------------------------------------------------------------------------------------------
# Ctrl-C while the results are written
# ---------------------------------------------------------------------------------------------
class Interrupts:
    """Ctrl-C around a job: the ``SIGINT`` handler notes every interrupt (``seen``) and raises
    :class:`KeyboardInterrupt`, except inside :meth:`deferred` (the results being written),
    where the interrupt waits for the block to end. ``vrig``'s :func:`~vrig.cli.main` installs it
    for a whole command (:meth:`installed`); :meth:`deferred` installs it for its block when
    nothing has (a Python caller), and then leaves the raising to the caller (``seen``)."""

    def __init__(self):
        self.seen = False
        self._defer = 0
        self._installed = False

    def _handler(self, signum, frame) -> None:
        self.seen = True
        if not self._defer:
            raise KeyboardInterrupt

    @contextlib.contextmanager
    def deferred(self):
        """Interrupts in the block are noted, not raised."""
        with contextlib.ExitStack() as stack:
            if not self._installed:
                stack.enter_context(self.installed(reset=False))
            self._defer += 1
            try:
                yield
            finally:
                self._defer -= 1

    @contextlib.contextmanager
    def installed(self, *, reset: bool = True):
        """The handler, for one command (the main thread only: signals go there).

        Parameters
        ----------
        reset : bool
            Forget the interrupts seen before.
        """
        if reset:
            self.seen, self._defer = False, 0
        if threading.current_thread() is not threading.main_thread():
            yield
            return
        previous = signal.signal(signal.SIGINT, self._handler)
        self._installed = True
        try:
            yield
        finally:
            self._installed = False
            signal.signal(signal.SIGINT, previous)


# ---------------------------------------------------------------------------------------------
# the save
# ---------------------------------------------------------------------------------------------
def target_check(rig, result) -> dict:
    """:func:`vrig.desired.reachability.check_target` of DESRES from the reconstruction's own identification
    records (no rig run) as ``summary.json``'s ``target_check``; a failure is recorded as
    ``{"error": ...}``, never raised (it must not lose the run).

    Parameters
    ----------
    rig : Rig
        The rig.
    result : ReconstructionResult
        The reconstruction (its desired response, band and identification records).

    Returns
    -------
    dict
    """
    from .desired.reachability import check_target

    if result.id_drive is None or result.id_response is None:
        return {"error": "no identification records: the identification drive was not played"}
    try:
        check = check_target(
            rig,
            result.desired,
            band=result.bandwidth,
            id_drive=result.id_drive,
            id_response=result.id_response,
        )
    except Exception as exc:  # whatever it is, the reconstruction's records come first
        return {"error": f"{type(exc).__name__}: {exc}"}
    return check.to_dict()


_DISK_FULL = {errno.ENOSPC, getattr(errno, "EDQUOT", errno.ENOSPC), errno.EFBIG}


def _nothing_saved(out: Path, exc: OSError) -> str:
    """The message of a save that failed: nothing was written (the save is one swap)."""
    kept = "keeps its previous contents" if out.is_dir() else "was not created"
    return (
        f"the results could not be written ({exc.strerror or exc}): nothing was saved, {out}/ "
        f"{kept}"
    )


class ResultsJob:
    """One reconstruction's results folder, from its checks to the end of its save.

    >>> job = ResultsJob("results/run", overwrite=True)         # doctest: +SKIP
    >>> job.check()                                  # bad input: nothing played  # doctest: +SKIP
    >>> with job:                                    # the lock, to the end       # doctest: +SKIP
    ...     job.check_space(desired, rig, settings.iterations)
    ...     result = job.run(rig, desired, settings)  # ReconstructionError: saved
    ...     written = job.save(result, rig, field=desired, settings=record)

    Parameters
    ----------
    out : str or Path
        The results folder.
    overwrite : bool
        Allow replacing the records of a non-empty folder.
    fmt : {"rsp", "csv", "mat", "npz"}
        Record format of the test folder.
    plots : bool
        Draw the plots into the folder (:func:`vrig.plots.save_reconstruction_plots`).
    names : OptionNames
        How messages name the caller's options (default: the Python keywords).
    interrupts : Interrupts, optional
        The Ctrl-C handler of the caller (the CLI's); default a new one, installed around the
        save only.
    warn : callable, optional
        ``warn(text)`` for a warning (the plots left out on a full disk); default
        :func:`warnings.warn` (``RuntimeWarning``).
    """

    def __init__(
        self,
        out,
        *,
        overwrite: bool = False,
        fmt: str = "rsp",
        plots: bool = True,
        names: OptionNames = PYTHON_NAMES,
        interrupts: Interrupts | None = None,
        warn=None,
    ):
        if fmt not in _RECORD_BYTES:
            raise ValueError(f"fmt must be one of {sorted(_RECORD_BYTES)}, got {fmt!r}")
        self.out, self.overwrite, self.fmt, self.plots = Path(out), bool(overwrite), fmt, plots
        self.names = names
        self.interrupts = interrupts if interrupts is not None else Interrupts()
        self._warn = warn or (lambda text: warnings.warn(text, RuntimeWarning, stacklevel=4))
        self._hold = contextlib.ExitStack()

    def check(self) -> None:
        """The folder before anything runs (:func:`check_results_folder`)."""
        check_results_folder(self.out, self.overwrite, self.names)

    def __enter__(self) -> ResultsJob:
        """Prove the folder writable, take its lock and check it again (now that no one else
        can change it); the lock is held until the ``with`` block ends."""
        check_writable(self.out, self.names)
        try:
            hold_results_folder(self._hold, self.out, self.names)
            self.check()
        except BaseException:
            self._hold.close()
            raise
        return self

    def __exit__(self, *exc) -> None:
        self._hold.close()

    def check_space(self, desired, rig, iterations: int) -> None:
        """The disk has room for the results (:func:`check_space`).

        Parameters
        ----------
        desired : TimeHistory
            The desired record.
        rig : Rig
            The rig.
        iterations : int
            Iterations after IT00.
        """
        check_space(self.out, desired, rig, iterations, self.fmt, self.names)

    def run(self, rig, desired, settings, *, progress: bool = False, save: dict | None = None):
        """:func:`vrig.reconstruction.reconstruct` with ``settings``; a failure before IT00
        saves what was made and raises.

        Parameters
        ----------
        rig : Rig
            The rig.
        desired : TimeHistory
            The desired response.
        settings : IterationSettings
            The resolved settings.
        progress : bool
            Progress on stderr.
        save : dict, optional
            :meth:`save`'s keywords for a failure before IT00.

        Returns
        -------
        ReconstructionResult

        Raises
        ------
        ReconstructionError
            Nothing played: its message adds what to change and what was kept in the folder
            (``exc.saved``: the files written, ``[]`` when nothing could be).
        ReconstructionInterrupted
            Ctrl-C, unsaved: the caller saves ``exc.result`` (:meth:`save`).
        ValueError
            Bad settings or a desired record the method cannot use (nothing played).
        """
        from . import reconstruction

        try:
            return reconstruction.reconstruct(rig, desired, settings, progress=progress)
        except ReconstructionError as exc:  # nothing played: keep what was made
            text = advice(exc.result.stop_kind, exc.stage, _gain(settings), exc.result, self.names)
            try:
                written = self.save(exc.result, rig, **(save or {}))
                kept = f"kept {', '.join(p.name for p in written)} in {self.out}/"
            except ResultsNotSavedError as failed:
                written, kept = [], str(failed)
            error = ReconstructionError(
                f"{exc} ({text}); {kept}", result=exc.result, cause=exc.cause, stage=exc.stage
            )
            error.saved = written
            raise error from exc

    def save(self, result, rig, *, field=None, records=None, settings=None) -> list[Path]:
        """Write the test folder, plots and ``summary.json`` of ``result`` (also one with no
        iteration played) in one swap, with the target check; a Ctrl-C waits until it is done
        (``self.interrupts.seen``). A full disk: saved again without the plots (a warning).

        Parameters
        ----------
        result : ReconstructionResult
            The reconstruction (also one that played nothing).
        rig : Rig
            The rig.
        field : TimeHistory, optional
            The record the desired response was made from (FIELD01).
        records : mapping, optional
            Further records under QanTiM names (``DESDRV``).
        settings : mapping, optional
            ``summary.json``'s ``settings``.

        Returns
        -------
        list of Path
            The files written (:meth:`vrig.TestFolder.save`).

        Raises
        ------
        ResultsNotSavedError
            Nothing could be written: the folder keeps its previous contents.
        """
        from .progress import status

        save = {"field": field, "records": records, "settings": settings}
        with self.interrupts.deferred():
            status(
                "checking the target's reachability (the identification records: no rig run) ..."
            )
            check = {"target_check": target_check(rig, result)}
            status(f"writing the test folder {self.out}/ ...")
            try:
                return self._write(result, rig, save, check, plots=self.plots)
            except OSError as exc:
                if exc.errno not in _DISK_FULL or not self.plots:
                    raise self._not_saved(result, exc) from exc
                try:  # the records matter, the plots can be drawn again from them
                    written = self._write(result, rig, save, check, plots=False)
                except OSError as again:
                    raise self._not_saved(result, again) from again
                self._warn(
                    f"warning: {exc.strerror or exc}: saved the records and summary in "
                    f"{self.out}/ without the plots"
                )
                return written

    def _write(self, result, rig, save: dict, check: dict, *, plots: bool) -> list[Path]:
        from .testfolder import TestFolder

        return TestFolder(self.out).save(
            result, fmt=self.fmt, rig=rig, overwrite=self.overwrite, summary_extra=check,
            plots=plots, lock_timeout=0, **save,
        )  # fmt: skip

    def _not_saved(self, result, exc: OSError) -> ResultsNotSavedError:
        return ResultsNotSavedError(_nothing_saved(self.out, exc), path=self.out, result=result)


def _gain(settings) -> float:
    """The (first) iteration gain of ``settings`` (resolved: an ``IterationSettings`` or a
    :class:`~vrig.reconstruction.defaults.ResolvedSettings`), for the advice."""
    gain = getattr(settings, "settings", settings).gain
    return float(gain if isinstance(gain, int | float) else gain[0])


# ---------------------------------------------------------------------------------------------
# what a stop says
# ---------------------------------------------------------------------------------------------
_NARROWER = "a narrower {band}, a lower {order} or {method_frf}"
_ADVICE = {
    # (stage, stop kind) -> what to change; stage "identification", "model", "IT00" (nothing
    # played: the gain plays no role) or "after IT00" (an iteration stopped: the gain does)
    ("identification", "interlock"): "the identification drive trips the rig even at 1/1024 of "
    "its amplitude (TRIPPEDID): check the rig's limits, or use a narrower {band}",
    ("identification", "refused"): "the identification drive is beyond the drives' full scale "
    "even at 1/1024 of its amplitude (REFUSEDID): check the rig's limits",
    ("identification", "unstable"): "the rig's simulation became unstable under the "
    "identification drive: check the rig model (time step, parameters) or use a narrower {band}",
    ("model", "diverged"): "the inverse model diverges on the desired response: try a lower "
    "{order}, {method_frf} or a narrower {band}",
    ("model", None): "the inverse model could not be fitted: try a lower {order}, "
    "{method_arx_or_frf}, or a narrower {band}",
    ("IT00", "refused"): "IT00DRV, the inverse model's first drive, needs more than the drive's "
    "full scale (refused_drive_vs_limits.png): use " + _NARROWER + ", or a smaller desired "
    "response",
    ("IT00", "interlock"): "IT00DRV, the inverse model's first drive, tripped the rig "
    "(TRIPPED00): use " + _NARROWER + ", or a smaller desired response",
    ("IT00", "unstable"): "the rig's simulation became unstable under IT00DRV (TRIPPED00): use "
    + _NARROWER
    + ", or a smaller desired response",
    ("after IT00", "interlock"): "a lower {gain}, e.g. {half}, overshoots less",
    ("after IT00", "refused"): "a lower {gain}, e.g. {half}, overshoots less",
    ("after IT00", "diverged"): "a lower {gain}, e.g. {half}, or {adaptive} "
    "(re-identify the inverse model from each iteration)",
    ("after IT00", "unstable"): "the rig's simulation became unstable under the drive: a lower "
    "{gain}, e.g. {half}",
    ("after IT00", "model"): "the re-identified inverse model is unstable: a lower {order}, or "
    "the fixed strategy",
}


def advice(
    kind: str, stage: str, gain: float, result=None, names: OptionNames = PYTHON_NAMES
) -> str:
    """What to change after a reconstruction that stopped (``stage`` ``"after IT00"``) or could
    not play any iteration (``stage`` ``"identification"``, ``"model"``, ``"IT00"``), by the
    kind of stop (``result.stop_kind``).

    A drive that overshot (refused, a trip, divergence) from a polynomial inverse identified
    below the target's peak (the identification report's ``"extrapolation"`` note) is the
    identification's doing, not the gain's: identify matched to the target.

    Parameters
    ----------
    kind : str
        The stop kind.
    stage : str
        Where it stopped.
    gain : float
        The iteration gain (half of it is suggested after IT00).
    result : ReconstructionResult or dict, optional
        The result (its ``identification`` report) or that report itself.
    names : OptionNames
        How the options are named (:data:`CLI_NAMES`, :data:`PYTHON_NAMES`).

    Returns
    -------
    str
    """
    report = getattr(result, "identification", result) or {}
    words = {**asdict(names), "half": f"{gain / 2:g}"}
    if kind == "law":  # the law's own error: no option of vrig's is to blame
        return "the control law raised it: fix the law where the message says"
    overshoot = kind in ("refused", "interlock", "diverged") and stage in ("IT00", "after IT00")
    if overshoot and report.get("extrapolation"):
        return (
            "the polynomial inverse was identified below the target's peak and extrapolates "
            "(the note above): {id_match} identifies it over the target's range"
        ).format(**words)
    text = _ADVICE.get((stage, kind)) or _ADVICE.get((stage, None))
    if text is None:
        text = (
            "try " + _NARROWER + ", or a smaller desired response"
            if stage != "after IT00"
            else "try a lower {gain}, e.g. {half}, or " + _NARROWER
        )
    return text.format(**words)


def stop_line(result, out: Path, gain: float, names: OptionNames = PYTHON_NAMES) -> str:
    """The line of a reconstruction that stopped after IT00 short of its iterations: why, what
    to change (:func:`advice`) and where the best iteration is kept.

    Parameters
    ----------
    result : ReconstructionResult
        The reconstruction that stopped.
    out : Path
        The results folder.
    gain : float
        The iteration gain.
    names : OptionNames
        How the message names the caller's options (:data:`CLI_NAMES`, :data:`PYTHON_NAMES`).

    Returns
    -------
    str
    """
    text = advice(result.stop_kind, "after IT00", gain, result, names)
    best = result.best_iteration
    return (
        f"stopped: {result.stopped} ({text}); best IT{best:02d} kept as FINDRV01/FINRES01 in {out}/"
    )


def interrupted_line(result, out: Path) -> str:
    """The line of a reconstruction Ctrl-C stopped (its results saved in ``out``).

    Parameters
    ----------
    result : ReconstructionResult
        What was played.
    out : Path
        The results folder.

    Returns
    -------
    str
    """
    n = len(result.drives)
    if result.stop_kind != "interrupted":  # Ctrl-C came after the run, during the save
        return f"interrupted while the results were saved: saved whole in {out}/"
    where = result.stopped.split(":", 1)[0]
    if not n:
        return f"interrupted ({where}): no iteration played; kept what was made in {out}/"
    best = result.best_iteration
    played = "IT00" if n == 1 else f"IT00-IT{n - 1:02d}"
    return (
        f"interrupted at {where}: kept the {n} iteration(s) played ({played}; best IT{best:02d} "
        f"as FINDRV01/FINRES01) in {out}/"
    )


# ---------------------------------------------------------------------------------------------
# the Python door
# ---------------------------------------------------------------------------------------------
def settings_record(
    settings, rig, desired, *, command: str = "vrig.reconstruct", description: str | None = None
) -> dict:
    """``summary.json``'s ``settings`` of a Python run of ``settings``, in the keys ``vrig
    reconstruct`` records (``argv`` ``None``; ``method`` the name, or the class of a method
    object, and the options given): the values the caller resolved, the update rule and its
    options included (the band, the model decimation and the identification report are
    ``summary.json``'s own entries).

    Parameters
    ----------
    settings : IterationSettings
        The resolved settings.
    rig : Rig
        The rig (its variant).
    desired : TimeHistory
        The desired response.
    command : str
        What ran the job.
    description : str, optional
        The method's one-line description (the resolver's, as ``vrig reconstruct`` records it);
        default: its name and the options given.

    Returns
    -------
    dict
    """
    method = settings.method
    options = "".join(f" {k} {v}" for k, v in settings.method_options.items())
    record = {
        "command": command,
        "argv": None,
        "variant": getattr(rig, "variant", None),
        "method": description
        or (method if isinstance(method, str) else type(method).__name__) + options,
        "gain": settings.gain,
        "iterations": settings.iterations,
        "seed": settings.id_seed,
        "desired": f"{type(desired).__name__} ({desired.duration:g} s)",
        "strategy": settings.strategy,
        "tolerance": settings.tolerance,
        "update": settings.update,
        "update_options": dict(settings.update_options),
    }
    if settings.id_match:
        record["id_match"] = True
    return record


def reconstruct_into(
    rig, desired, settings, out, *, overwrite=False, fmt="rsp", plots=True, progress=False
):
    """:func:`vrig.reconstruct` with ``out`` (see its documentation): the job, from the checks
    of the folder to the end of its save.

    Parameters
    ----------
    rig : Rig
        The rig.
    desired : TimeHistory
        The desired response.
    settings : ResolvedSettings or IterationSettings
        The resolved settings (:func:`vrig.reconstruction.defaults.resolve`).
    out : str or Path
        The results folder.
    overwrite : bool
        Allow replacing a non-empty folder's records.
    fmt : {"rsp", "csv", "mat", "npz"}
        The record format.
    plots : bool
        Draw the plots.
    progress : bool
        Progress on stderr.

    Returns
    -------
    ReconstructionResult
    """
    job = ResultsJob(out, overwrite=overwrite, fmt=fmt, plots=plots)
    job.check()
    values = getattr(settings, "settings", settings)  # a ResolvedSettings' IterationSettings
    described = getattr(settings, "description", None)
    save = {
        "field": desired,
        "settings": settings_record(values, rig, desired, description=described),
    }
    with job:
        job.check_space(desired, rig, values.iterations)
        try:
            result = job.run(rig, desired, settings, progress=progress, save=save)
        except ReconstructionInterrupted as exc:  # keep what was played, then the interrupt
            try:
                job.save(exc.result, rig, **save)
                kept = interrupted_line(exc.result, job.out)
            except ResultsNotSavedError as failed:  # the interrupt still goes first
                kept = str(failed)
            raise ReconstructionInterrupted(f"{exc}; {kept}", result=exc.result) from exc
        except ReconstructionError as exc:
            if job.interrupts.seen:  # Ctrl-C while what was made was saved: saved whole
                raise ReconstructionInterrupted(str(exc), result=exc.result) from exc
            raise
        job.save(result, rig, **save)
    if job.interrupts.seen:
        raise ReconstructionInterrupted(interrupted_line(result, job.out), result=result)
    if result.stop_kind not in ("completed", "converged"):  # the line vrig reconstruct prints
        warnings.warn(stop_line(result, job.out, _gain(settings)), RuntimeWarning, stacklevel=3)
    return result
