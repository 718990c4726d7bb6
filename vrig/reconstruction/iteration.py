"""The drive-iteration loop (§1.3, App. G): identify, invert, play, correct.

IDDRV (random, triangular PSD over the identification band) → rig → IDRES → GPREPRO (one
simulation bandwidth for every record) → inverse model → IT00DRV = inverse(DESRES) → rig →
RIT00RES → GPREPRO → IT00RES → error → ``ITn+1DRV = ITnDRV + gain (inverse(DESRES) -
inverse(ITnRES))`` → ...

Every drive is checked against the rig's full scale before it is sent; a diverging iteration
(η0 grows by ``divergence`` over the best so far) stops, and the best drive is kept. So does any
error after IT00 (a drive refused or a rig trip, an unstable simulation, a diverged inverse
model, a non-finite drive update): :func:`reconstruct` returns every iteration played, says why
it stopped (``result.stopped``, ``result.error``) and keeps the drive that was refused or tripped
(``result.rejected_name``, ``result.rejected_drive``). A failure before any iteration was played
raises :class:`~vrig.ReconstructionError` carrying the same kind of result with zero iterations
(the identification records and model, when they were made).

Ctrl-C (``SIGINT``, a :class:`KeyboardInterrupt`) is kept by the same rule, wherever it strikes
(the identification, the fit, a rig run, a drive update, the bookkeeping): the result holds
every iteration played whole (one the interrupt cut short is dropped), ``stop_kind`` is
``"interrupted"``, and :func:`reconstruct` raises :class:`~vrig.ReconstructionInterrupted` (a
:class:`KeyboardInterrupt`: a Ctrl-C is never swallowed) with that result attached, before or
after IT00.

The steps themselves are :class:`~vrig.reconstruction.DriveIteration`'s (:mod:`.engine`), the
settings one :class:`~vrig.reconstruction.IterationSettings` (:mod:`.settings`), the result a
:class:`~vrig.reconstruction.ReconstructionResult` (:mod:`.result`).
"""

from __future__ import annotations

import numpy as np
from tqdm import tqdm  # plain text bars (vrig.progress: never tqdm.auto)

from identification.errors import IdentificationError, SimulationDivergedError

from ..errors import (
    ControlLawError,
    ReconstructionError,
    ReconstructionInterrupted,
    RigLimitError,
    SimulationInstabilityError,
)
from ..progress import enabled_if
from ..timehistory import TimeHistory
from .defaults import resolved
from .engine import DriveIteration
from .result import ReconstructionResult, best_iteration
from .settings import MAX_ITERATIONS, IterationSettings

__all__ = ["MAX_ITERATIONS", "reconstruct"]


def reconstruct(
    rig,
    desired: TimeHistory,
    settings: IterationSettings | None = None,
    *,
    progress: bool = False,
    out=None,
    overwrite: bool = False,
    fmt: str = "rsp",
    plots: bool = True,
    **options,
) -> ReconstructionResult:
    """Reproduce ``desired`` on ``rig`` by drive iteration.

    >>> import vrig
    >>> result = vrig.reconstruct(rig, desired, method="narx", gain=0.5, order=4)  # doctest: +SKIP
    >>> settings = vrig.IterationSettings(method="arx", iterations=5, id_seed=1, run_seed=2)
    >>> result = vrig.reconstruct(rig, desired, settings)                          # doctest: +SKIP
    >>> result = vrig.reconstruct(rig, desired, out="results/run")               # doctest: +SKIP

    Parameters
    ----------
    rig : Rig
        Anything with ``inputs``, ``outputs``, ``fs`` and ``run(drive, seed=None)``
        (:class:`~vrig.rigs.Rig`).
    desired : TimeHistory
        The desired response (DESRES before processing), the rig's outputs at ``rig.fs``.
    settings : IterationSettings, optional
        Method, iterations, gain, band, identification drive, seeds, stopping rule (default:
        the defaults of :class:`~vrig.reconstruction.IterationSettings`).
    progress : bool
        Show a progress bar over the iterations and the status of the identification, the fit
        and long rig runs on stderr (:mod:`vrig.progress`; ``False`` leaves an outer
        :func:`vrig.progress.enabled` in force).
    out : str or Path, optional
        A results folder: write into it the QanTiM test folder, its plots and ``summary.json``
        that ``vrig reconstruct --out`` writes (the job of :mod:`vrig.job`). The folder is
        checked before anything is played (a folder or nothing yet, empty unless
        ``overwrite``, not the working directory or a folder holding it, not a mount point,
        writable, with room on its disk for the records); its lock is held from those checks to
        the end of the save, which swaps the new folder in whole; a disk that fills up during
        the save gets the records and the summary without the plots (a ``RuntimeWarning`` says
        so); ``summary.json`` holds the target check of the run's identification records and
        its ``settings`` every resolved setting (:func:`vrig.job.settings_record`). Default:
        nothing is written.
    overwrite : bool
        With ``out``: allow replacing the records of a non-empty folder.
    fmt : {"rsp", "csv", "mat", "npz"}
        With ``out``: the record format (default RPC III ``.drv``/``.rsp``).
    plots : bool
        With ``out``: draw the plots into the folder (default).
    **options
        Settings by name on top of ``settings``: ``method`` (``"arx"``, ``"narx"``, ``"split"``,
        ``"frf"``, ``"error-signal"``, ``"rattlesnake:<file.py>:<name>"`` or a method object;
        names are built by :func:`~vrig.reconstruction.method_spec`), ``iterations``, ``gain``,
        ``strategy``, ``bandwidth``, ``id_duration``, ``id_rms``, ``id_psd``, ``id_match``,
        ``decimation``, ``taper``, ``id_seed``, ``run_seed``, ``divergence``, ``min_increase``,
        ``tolerance``, ``update``, ``update_options``; ``seed`` sets both seeds; any other
        name is a method option (``order``, ``degree``, ``split_hz``, ...).
        See :class:`~vrig.reconstruction.IterationSettings` for their meaning and defaults.

    Returns
    -------
    ReconstructionResult
        Every iteration played, IT00 first, and the best one. Any error after IT00 (a drive
        refused or a rig trip, an unstable simulation, a diverged inverse model, a non-finite
        drive update) stops the loop instead of propagating: ``stopped`` says where and why,
        ``error`` holds the exception and ``rejected_drive`` the drive refused or tripped.
        With ``out`` the result is saved before it is returned, and a stop short of the
        iterations (not ``completed`` or ``converged``) issues a ``RuntimeWarning`` with the
        line ``vrig reconstruct`` prints: why, what to change, where the best iteration is kept.

    Raises
    ------
    ValueError
        Bad arguments (before anything is played), among them an identification record (by
        default the desired record) too short for the method
        (:meth:`~vrig.reconstruction.DriveIteration.check_length` states the rule).
    ReconstructionError
        Nothing could be played: the identification drive tripped the rig even at 1/1024 of
        its amplitude, the inverse model could not be fitted or diverged on DESRES, or IT00DRV was
        refused or tripped. ``exc.result`` holds what was made (identification records, model,
        the rejected drive); ``exc.cause`` the original error. With ``out``, what was made is
        saved first (``exc.saved``: the files written, ``[]`` when nothing could be) and the
        message adds what to change and what was kept, as ``vrig reconstruct``'s exit 7 does.
    ReconstructionInterrupted
        Ctrl-C (a :class:`KeyboardInterrupt`): ``exc.result`` holds every iteration played
        before it (``stop_kind`` ``"interrupted"``), or what was made before IT00. With ``out``
        it is raised after ``exc.result`` was saved; a Ctrl-C during the save waits until the
        folder is written whole, then raises (the result attached).
    ResultsFolderError
        With ``out``: a folder that cannot be used (a file, not empty without ``overwrite``, the
        working directory, a mount point, not writable, a disk without room), before anything
        is played; a :class:`ValueError`, naming the folder.
    FolderLockedError
        With ``out``: another writer holds the folder (nothing is played).
    ResultsNotSavedError
        With ``out``: the results could not be written, not even without the plots (an
        :class:`OSError`; ``exc.result`` holds the reconstruction, the folder keeps its
        previous contents).
    """
    with enabled_if(progress):  # status lines of the identification, rig run bars
        if out is None:
            return _reconstruct(rig, desired, settings, progress, options)
        from ..job import reconstruct_into  # the job sits above the loop: imported when used

        settings = resolved(rig, settings, **options)  # resolved once: the job records it
        return reconstruct_into(
            rig, desired, settings, out, overwrite=overwrite, fmt=fmt, plots=plots,
            progress=progress,
        )  # fmt: skip


def _reconstruct(rig, desired, settings, progress: bool, options) -> ReconstructionResult:
    """:func:`reconstruct`'s body (progress switched on or off by the caller)."""
    engine = DriveIteration(rig, desired, settings, **options)  # resolves every default
    settings = engine.settings
    gain = settings.gains_for(len(rig.inputs))
    engine.check_desired()  # ValueError before anything is played
    result = ReconstructionResult(
        desired=engine.desres,
        id_drive=None,
        id_response=None,
        method=engine.method,
        bandwidth=engine.band,
        errors=np.empty((0, desired.n_channels)),
        rms_errors=np.empty((0, desired.n_channels)),
        damage_ratio=np.empty((0, desired.n_channels)),
        best_iteration=-1,
        decimation=engine.decimation,
        gain=gain,
        strategy=settings.strategy,
        seed=settings.id_seed,
        settings=settings,
        resolved=engine.resolved.record(),
        updates=engine.update_log,  # the rule's own list: filled as the loop runs
    )
    bar = None
    try:
        drive = _first_drive(engine, result)
        bar = tqdm(
            total=settings.iterations + 1,
            desc=f"{rig.name}: iterations",
            disable=not progress,
            leave=False,
        )
        _iterate(engine, result, drive, gain, bar)
        if not result.stop_kind:  # a stop that set no kind is an error of some other sort
            result.stop_kind = "failed" if result.stopped else "completed"
    except ReconstructionInterrupted:
        raise
    except KeyboardInterrupt as exc:  # Ctrl-C: the iterations played are kept (module doc)
        _whole_iterations(result)
        _fail(result, engine, f"IT{len(result.drives):02d}", exc)
        raise ReconstructionInterrupted(
            f"interrupted: {result.stopped}; {len(result.drives)} iteration(s) played",
            result=result,
        ) from exc
    finally:
        if bar is not None:
            bar.close()
    return result


def stop_kind(exc: BaseException) -> str:
    """The :data:`~vrig.reconstruction.result.STOP_KINDS` entry of an error that stopped a
    reconstruction.

    Parameters
    ----------
    exc : Exception
        The error.

    Returns
    -------
    str
        ``"refused"`` (a drive beyond full scale, never sent), ``"interlock"`` (a rig trip),
        ``"unstable"`` (the simulation), ``"diverged"`` (an inverse model's free run),
        ``"model"`` (any other identification error: the model could not be fitted),
        ``"law"`` (a user's control law raised: :class:`~vrig.errors.ControlLawError`),
        ``"interrupted"`` (Ctrl-C: a :class:`KeyboardInterrupt`) or ``"failed"``.
    """
    if isinstance(exc, ControlLawError):
        return "law"
    if isinstance(exc, RigLimitError):
        return "refused" if exc.time != exc.time else "interlock"  # time NaN: never sent
    if isinstance(exc, SimulationInstabilityError):
        return "unstable"
    if isinstance(exc, SimulationDivergedError):
        return "diverged"
    if isinstance(exc, IdentificationError):
        return "model"
    if isinstance(exc, KeyboardInterrupt):
        return "interrupted"
    return "failed"


def _fail(
    result: ReconstructionResult, engine: DriveIteration, where: str, exc: BaseException
) -> None:
    """Record in ``result`` why the loop stopped (and the drive refused or tripped, if any)."""
    if isinstance(exc, KeyboardInterrupt):
        what = "interrupted (Ctrl-C)"
    elif isinstance(exc, RigLimitError):
        what = str(exc)
    else:
        what = f"{type(exc).__name__}: {exc}"
    result.stopped, result.error = f"{where}: {what}", exc
    result.stop_kind = stop_kind(exc)
    if engine.rejected is not None:
        result.rejected_name, result.rejected_drive = engine.rejected


def _first_drive(engine: DriveIteration, result: ReconstructionResult) -> np.ndarray:
    """Identify and compute IT00DRV; any failure raises ReconstructionError with ``result``
    (Ctrl-C: ReconstructionInterrupted with it)."""
    try:
        engine.identify()
        drive = engine.first_drive()
    except (Exception, KeyboardInterrupt) as exc:
        stage = "identification" if engine.id_response is None else "model"
        result.id_drive, result.id_response = engine.id_drive, engine.id_response
        result.identification = engine.id_report
        _fail(result, engine, stage, exc)
        if isinstance(exc, KeyboardInterrupt):
            raise ReconstructionInterrupted(
                f"interrupted: {result.stopped}; no iteration played", result=result
            ) from exc
        raise ReconstructionError(
            f"no iteration played: {result.stopped}", result=result, cause=exc, stage=stage
        ) from exc
    result.id_drive, result.id_response = engine.id_drive, engine.id_response
    result.identification = engine.id_report
    return drive


def _whole_iterations(result: ReconstructionResult) -> None:
    """Cut ``result`` back to the iterations it holds whole (records and scores), after an
    interrupt that may have struck between appending an iteration's records and its scores."""
    n = min(
        len(result.drives),
        len(result.raw_responses),
        len(result.responses),
        len(result.errors),
        len(result.rms_errors),
        len(result.damage_ratio),
    )
    del result.drives[n:], result.raw_responses[n:], result.responses[n:]
    result.errors = np.asarray(result.errors)[:n]
    result.rms_errors = np.asarray(result.rms_errors)[:n]
    result.damage_ratio = np.asarray(result.damage_ratio)[:n]
    result.best_iteration = best_iteration(result.errors)


def _iterate(engine: DriveIteration, result, drive, gain, bar) -> None:
    """The loop of :func:`reconstruct` from IT00 on: fills ``result`` until the last iteration,
    divergence (``engine.settings``' ``divergence`` and ``min_increase``, against the lowest mean
    η0 so far), the tolerance (``tolerance``: every channel's η0 at or below it) or the first
    error after IT00. The kept iteration follows :func:`~.result.best_iteration`."""
    s = engine.settings
    iterations, divergence, min_increase = s.iterations, s.divergence, s.min_increase
    errs, rmss, dmgs = [], [], []
    for it in range(iterations + 1):
        try:
            drv, raw, res, (e, r, d) = engine.play(drive, it)
        except Exception as exc:
            _fail(result, engine, f"IT{it:02d}", exc)
            if it == 0:
                raise ReconstructionError(
                    f"no iteration played: {result.stopped}", result=result, cause=exc, stage="IT00"
                ) from exc
            break
        result.drives.append(drv)
        result.raw_responses.append(raw)
        result.responses.append(res)
        errs.append(e)
        rmss.append(r)
        dmgs.append(d)
        result.errors, result.rms_errors, result.damage_ratio = (
            np.array(errs),
            np.array(rmss),
            np.array(dmgs),
        )
        means = result.errors.mean(axis=1)
        result.best_iteration = best_iteration(result.errors)
        bar.update(1)
        best = np.min(np.where(np.isnan(means), np.inf, means))  # divergence: the lowest mean
        if means[-1] > divergence * best and means[-1] - best > min_increase:
            result.stopped = (
                f"IT{it:02d}: diverging (mean η0 {means[-1]:.1f} % > {divergence} x best)"
            )
            result.stop_kind = "diverged"
            break
        if s.tolerance is not None and np.all(e <= s.tolerance):  # NaN never meets it
            result.stopped = (
                f"IT{it:02d}: converged (every channel's η0 <= the tolerance {s.tolerance:g} %)"
            )
            result.stop_kind = "converged"
            break
        if it == iterations:
            break
        try:
            if s.strategy == "adaptive":
                engine.reidentify(drv, raw)
            drive = engine.next_drive(drive, res, gain)
        except Exception as exc:
            _fail(result, engine, f"IT{it + 1:02d}DRV", exc)
            break
        if not np.all(np.isfinite(drive)):
            result.stopped = (
                f"IT{it + 1:02d}DRV: the drive update is not finite (the inverse model diverged "
                f"on IT{it:02d}RES): not sent"
            )
            result.stop_kind = "diverged"
            break
