"""Pseudo-field desired responses: the rig's own response to a road-like drive.

A *pseudo-field* desired response is the rig's own response to a road-like drive (triangular
PSD over the simulation band, reference text §6.5): the reconstruction then has a known,
reachable answer (DESDRV), so the error of an iteration method can be judged against a drive
that exists. :func:`vrig.desired.kinds.desired_response` makes it (or a service record) from a
target name.
"""

from __future__ import annotations

import os

import numpy as np

__all__ = [
    "pseudo_field",
    "pseudo_fields",
]

_FIELD_FRACTION = 0.10  # pseudo-field drive RMS as a fraction of full scale (5 mm on the damper)
_FIELD_HEADROOM = 2 / 3  # pseudo-field responses peak below this fraction of the transducer range
_FADE_S = 1.0
_FIELD_ATTEMPTS = 11  # the level halved up to ten times: down to 1/1024 of it (60 dB)


def pseudo_field(rig, band: tuple[float, float], seconds: float, *, seed: int = 0):
    """A pseudo-field drive and the rig's response to it (reference text §6.5).

    The drive has a triangular PSD over ``band`` (the QanTiM road-like shape), a 1 s fade-in and
    fade-out, and 10 % of each drive channel's full scale RMS; the level is halved (up to ten
    times: down to 1/1024 of it) until every response peaks below two thirds of its transducer
    range and the rig runs 1.5 times the drive without an interlock trip (room for the
    iterations to overshoot: a desired response made right at the following-error limit cannot
    be reached by any drive that differs from the original). A level set from the drives' full
    scales knows nothing of the responses' ranges: on a user's rig whose ranges do not match its
    drives' (a 200 m/s^2 accelerometer behind a 50 mm actuator driven to 125 Hz, the table's
    own acceleration growing with the frequency squared: ``models/README.md``'s example) the
    level that fits is 1/32 of the start, beyond the four halvings this rule used to allow.

    Each level tried is reported on stderr inside :func:`vrig.progress.enabled` (quiet
    otherwise).

    Parameters
    ----------
    rig : Rig
        The rig that makes the record; run up to 22 times (two runs per level tried).
    band : (float, float)
        Frequency band (low, high) of the triangular drive PSD [Hz].
    seconds : float
        Record length [s], fades included; ``round(seconds * rig.fs)`` samples.
    seed : int
        Seed of the random drive; the rig runs with ``seed + 10_000`` (its noise realisation).
        The same seed gives the same record, bit for bit.

    Returns
    -------
    (drive, response) : TimeHistory, TimeHistory
        DESDRV and the raw response (FIELD) at the rig's fs.
    """
    from ..errors import RigLimitError
    from ..progress import status

    out_full = np.array([c.full_scale for c in rig.outputs])
    fraction = _FIELD_FRACTION
    last_error = None
    for attempt in range(_FIELD_ATTEMPTS):
        status(
            f"desired response: {seconds:g} s pseudo-field drive at {100 * fraction:.3g} % of "
            f"full scale rms -> {rig.name}"
            + (
                f" (attempt {attempt + 1} of {_FIELD_ATTEMPTS}: the last level was too large)"
                if attempt
                else ""
            )
        )
        drive = _field_drive(rig, band, seconds, fraction, seed)
        try:
            response = rig.run(drive, seed=seed + 10_000)
        except RigLimitError as exc:
            last_error = exc
        else:
            swing = np.abs(response.data - response.data.mean(axis=0)).max(axis=0)
            if np.all(swing <= _FIELD_HEADROOM * out_full):
                status("desired response: checking that 1.5x that drive runs too")
                try:  # the same headroom on the interlocks: 1.5x the drive must run too
                    rig.run(drive.with_data(drive.data / _FIELD_HEADROOM), seed=seed + 10_000)
                except RigLimitError as exc:
                    last_error = exc
                else:
                    return drive, response
            else:
                last_error = None
        fraction /= 2
    if last_error is not None:
        raise last_error
    return drive, response


def _field_drive(rig, band, seconds: float, fraction: float, seed: int):
    """The pseudo-field drive of ``seed`` at ``fraction`` of full scale rms: triangular PSD over
    ``band``, mean removed, faded in and out over :data:`_FADE_S` (``seconds`` long)."""
    from scipy.signal.windows import tukey

    from ..signals import random_drive, triangular_psd

    n = round(seconds * rig.fs)
    full = np.array([c.full_scale for c in rig.inputs])
    fade = tukey(n, min(1.0, 2 * _FADE_S / seconds))[:, None]
    drive = random_drive(
        triangular_psd(band),
        n,
        rig.fs,
        channels=len(rig.inputs),
        rms=fraction * full,
        seed=seed,
        names=[c.name for c in rig.inputs],
        unit=rig.inputs[0].unit,
    )
    drive = drive.with_data((drive.data - drive.data.mean(axis=0)) * fade)
    return type(drive)(drive.data, drive.fs, drive.names, [c.unit for c in rig.inputs])


def pseudo_fields(rig, band: tuple[float, float], seconds: float, seeds, *,
                  threads: int | None = None) -> list:  # fmt: skip
    """:func:`pseudo_field` of many seeds, their rig runs batched (:func:`vrig.rigs.run_batch`).

    Result ``i`` is bit for bit ``pseudo_field(rig, band, seconds, seed=seeds[i])``: the same
    levels tried in the same order, the same drives, runs and run seeds, the same record or the
    same exception. Each level is two batches over the seeds still without a record: their
    drives, then 1.5 times the drives that ran within the headroom (the interlock check). When
    fewer seeds are left than the batch has threads (a single record: always), the threads
    that would idle play some of those checks ahead, beside their level's runs (in seed order,
    up to the next multiple of the threads): a check whose run fails is then wasted, a check
    whose run passes is ready one batch earlier. Each run is seeded, so played ahead or not it
    is the same run.

    Parameters
    ----------
    rig : Rig
        The rig that makes the records (any rig; a :class:`~vrig.rigs.MujocoRig` plays each
        batch across threads).
    band : (float, float)
        Frequency band (low, high) of the triangular drive PSD [Hz].
    seconds : float
        Record length [s], fades included.
    seeds : sequence of int
        Seeds of the random drives (each >= 0), as :func:`pseudo_field`'s ``seed``.
    threads : int, optional
        Worker threads of the batched rig runs (:meth:`vrig.rigs.MujocoRig.run_batch`).

    Returns
    -------
    list
        Per seed, in order: ``(drive, response)`` as :func:`pseudo_field` returns it, or the
        exception it raises (a :class:`~vrig.errors.RigLimitError` after the last level, a
        simulation error, ...), in its slot.
    """
    from ..progress import status

    seeds = [_seed(s) for s in seeds]
    out_full = np.array([c.full_scale for c in rig.outputs])
    results: list = [None] * len(seeds)
    last: dict = {}  # seed index -> (error, drive, response) of its last level
    pending = list(range(len(seeds)))
    fraction = _FIELD_FRACTION
    for _ in range(_FIELD_ATTEMPTS):
        if not pending:
            break
        status(f"desired responses: {len(pending)} x {seconds:g} s pseudo-field drives at "
               f"{100 * fraction:.3g} % of full scale rms -> {rig.name} (batched)")  # fmt: skip
        drives = {i: _field_drive(rig, band, seconds, fraction, seeds[i]) for i in pending}
        ahead = pending[: _spare_threads(rig, len(pending), threads)]  # checks played early
        checks = {i: drives[i].with_data(drives[i].data / _FIELD_HEADROOM) for i in ahead}
        jobs = {**drives, **{("check", i): c for i, c in checks.items()}}
        played = _runs(rig, jobs, {k: seeds[k[1] if isinstance(k, tuple) else k] for k in jobs},
                       threads)  # fmt: skip
        runs = {i: played[i] for i in drives}
        within = {}  # the seeds whose run swung within the headroom: their 1.5x check
        for i, response in runs.items():
            verdict, error = _field_verdict(response, out_full)
            if verdict == "fail":
                results[i] = error
            elif verdict == "retry":
                last[i] = (error, drives[i], response)
            else:
                within[i] = drives[i].with_data(drives[i].data / _FIELD_HEADROOM)
        late = _runs(rig, {i: c for i, c in within.items() if i not in checks}, seeds, threads)
        for i, check in ((i, played[("check", i)] if i in checks else late[i]) for i in within):
            verdict, error = _field_verdict(check, None)
            if verdict == "fail":
                results[i] = error
            elif verdict == "retry":
                last[i] = (error, drives[i], runs[i])
            else:
                results[i] = (drives[i], runs[i])
        pending = [i for i in pending if results[i] is None]
        fraction /= 2
    for i in pending:
        error, drive, response = last[i]
        results[i] = error if error is not None else (drive, response)
    return results


def _spare_threads(rig, pending: int, threads) -> int:
    """How many 1.5x checks a level of ``pending`` runs can play ahead on threads that would
    idle: none on a rig that plays one run at a time, else up to the next multiple of the
    batch's threads (:meth:`vrig.rigs.MujocoRig.run_batch`'s default: the cores), at most one
    per seed."""
    from ..rigs import MujocoRig, OutputSubset

    inner = rig.rig if isinstance(rig, OutputSubset) else rig
    if not isinstance(inner, MujocoRig):
        return 0
    from ..rigs.mujoco_rig import MAX_BATCH_THREADS

    t = threads if threads is not None else min(os.cpu_count() or 1, MAX_BATCH_THREADS)
    return min(-pending % max(int(t), 1), pending)


def _runs(rig, drives: dict, seeds, threads) -> dict:
    """``{i: rig.run(drives[i], seed=seeds[i] + 10_000)}`` (the response or the exception) in
    one batch (:func:`vrig.rigs.run_batch`); ``seeds`` a list or a dict over the keys of
    ``drives``."""
    from ..rigs import run_batch

    if not drives:
        return {}
    out = run_batch(rig, list(drives.values()), seeds=[seeds[i] + 10_000 for i in drives],
                    threads=threads, return_exceptions=True)  # fmt: skip
    return dict(zip(drives, out, strict=True))


def _seed(seed) -> int:
    """A checked record seed (an integer >= 0)."""
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise ValueError(f"each seed must be an integer >= 0, got {seed!r}")
    return int(seed)


def _field_verdict(run, out_full) -> tuple[str, object]:
    """A pseudo-field run judged as :func:`pseudo_field` judges it (``run``: the response or the
    exception it raised; ``out_full``: the transducer ranges, None for the 1.5x check run, whose
    swing is not looked at): ``("done", None)``, ``("retry", the level's error or None)`` or
    ``("fail", the exception pseudo_field does not catch)``."""
    from ..errors import RigLimitError

    if isinstance(run, BaseException):
        return ("retry" if isinstance(run, RigLimitError) else "fail"), run
    if out_full is not None:
        swing = np.abs(run.data - run.data.mean(axis=0)).max(axis=0)
        if not np.all(swing <= _FIELD_HEADROOM * out_full):
            return "retry", None
    return "done", None
