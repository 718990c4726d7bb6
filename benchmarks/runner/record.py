"""One benchmark record: a reconstruction of one desired response on one rig by one method.

A record is a pure function of its key (rig, method, desired, seed, severity, target) and the
run's settings:

* the rig is ``vrig.load_rig(rig, seed=..., fidelity=..., severity=severity)``; severity None
  (the default, and every record written before the severity axis existed) is the rig as loaded,
  without ``severity=``;
* the desired response is :func:`vrig.desired.kinds.desired_response` of rig ``rig`` (loaded with seed
  0, at the record's severity) for ``target`` with seed ``desired``: for ``"pseudo-field"`` (the
  default, and every record written before the target axis existed: their keys have no
  ``target``) the pseudo-field response (:func:`vrig.desired.pseudo_field.pseudo_field`) over the rig's default
  simulation band; for ``"field:<scenario>"`` the service record of the rig's specimen in its
  vehicle (:func:`vrig.service.field_record`) on the road of seed ``desired``, at the
  scenario's speed and road class (the record's ``target_source`` says which);
* the reconstruction runs on the rig loaded with seed ``seed`` at the same severity:
  ``vrig.reconstruct(rig, desired, settings.iteration(<plugin's object>, band, seed))`` (one
  :class:`vrig.IterationSettings`; ``seed`` is both the identification and the run seed).

Scores (η0 is the DC-corrected QanTiM fit value, eq. 5-28, in %; "mean" is over the response
channels):

* ``eta0_it00``, ``eta0_final`` (the last iteration played, ITnn with nn = ``iterations_run``),
  ``eta0_best`` (at ``best_iteration``) and ``eta0_per_iteration``;
* ``iterations_to_tolerance``: the first iteration whose mean η0 is at most ``tolerance``
  (None if none is);
* ``rms_error`` [%] and ``damage_ratio`` (rainflow pseudo-damage, slope 5, achieved over
  desired) at the best iteration, mean over channels (per channel in the ``*_channels`` fields);
* modelling errors, from the processed identification records the method was fitted on (at the
  model rate), split into the first 70 % (fit) and the last 30 % (held out; ``holdout``):

  - ``inverse_model_error``: a fresh method object identified on the fit part predicts the
    held-out drive from the held-out response in free run; mean η0 of that drive;
  - ``normal_model_error``: the forward model — the method's factory (or the plugin's
    ``forward`` factory) identified with the roles of drive and response swapped — predicts
    the held-out response from the held-out drive in free run; mean η0 of that response;
  - for a method with a lead (:class:`vrig.reconstruction.protocol.InverseModelMethod`:
    vrig's ARX, NARX and error-signal inverses, each band of split spectra) the fresh inverse
    keeps the lead the reconstruction's model chose (``set_lead(fitted_lead())``), and the
    forward model has lead 0 (``set_lead(0)``: causal, the full-order structure of eq. 4-15):
    no lead search in these extra fits;

* ``model_size`` (coefficients, see :func:`~.registry.model_size`) and the method's
  ``describe()``.

``timing`` holds the wall times (``fit_s``: the method's ``identify`` calls in the
reconstruction; ``model_sim_s``: its ``drive`` calls, i.e. the inverse model's free runs;
``reconstruction_s``; ``record_s``) plus host and process id: the only fields that differ
between two runs of the same record, so they are left out when records are compared.

A record whose rig, desired response or reconstruction raises is kept with ``status
"failed"`` and ``error`` (stage, exception type, message): leaderboards show failures. So is a
record whose scores are not finite (stage ``"scores"``): :func:`check_record` says what a
finished, well-formed record is, and the store recomputes a record file that is not one.
"""

from __future__ import annotations

import functools
import math
import os
import platform
import time
from dataclasses import asdict, dataclass

import numpy as np

from vrig.reconstruction import IterationSettings
from vrig.reconstruction.protocol import InverseModelMethod, Method

from .registry import get_method, load_plugins, model_size

__all__ = [
    "SEVERITY_RANGE",
    "RecordKey",
    "Settings",
    "check_record",
    "check_severity",
    "check_target",
    "compute_record",
    "format_severity",
    "key_dict",
    "record_id",
    "strip_timing",
]

SCHEMA = 1


@dataclass(frozen=True)
class Settings:
    """Settings shared by every record of a run (part of every record)."""

    seconds: float = 30.0
    iterations: int = IterationSettings.iterations  # vrig reconstruct's
    gain: float | None = None
    fidelity: str = "full"
    tolerance: float = 5.0
    holdout: float = 0.3

    def __post_init__(self):
        if not (math.isfinite(self.seconds) and 4 <= self.seconds <= 3600):
            raise ValueError(f"seconds must be 4..3600, got {self.seconds}")
        # the iteration's own checks (one place): iterations 0..MAX_ITERATIONS, gain in (0, 2]
        IterationSettings(iterations=self.iterations, gain=self.gain)  # (None: each rig's own)
        if self.fidelity not in ("full", "fast"):
            raise ValueError(f"fidelity must be 'full' or 'fast', got {self.fidelity!r}")
        if not 0.1 <= self.holdout <= 0.5:
            raise ValueError(f"holdout must be 0.1..0.5, got {self.holdout}")

    def iteration(
        self, method, band: tuple[float, float], seed: int, *, update: str = "none"
    ) -> IterationSettings:
        """The :class:`vrig.IterationSettings` of a record: this run's iterations and gain, the
        record's method object, band and model update (the method row's), ``seed`` for the
        identification and the rig runs."""
        return IterationSettings(
            method=method,
            iterations=self.iterations,
            gain=self.gain,
            bandwidth=band,
            id_seed=seed,
            run_seed=seed,
            update=update,
        )


SEVERITY_RANGE = (0.0, 2.0)
"""Non-linearity severities a record can have (``vrig.load_rig(..., severity=s)``)."""


def check_severity(severity) -> float | None:
    """``severity`` as the record key holds it: None (the rig as loaded) or a float in
    :data:`SEVERITY_RANGE`; raises ValueError otherwise."""
    if severity is None:
        return None
    if isinstance(severity, bool) or not isinstance(severity, (int, float)):
        raise ValueError(f"severity must be a number or None, got {severity!r}")
    lo, hi = SEVERITY_RANGE
    if not (math.isfinite(severity) and lo <= severity <= hi):
        raise ValueError(f"severity must lie in [{lo:g}, {hi:g}], got {severity}")
    return float(severity)


PSEUDO_FIELD = "pseudo-field"
"""The default target of a record (the only one before the target axis existed)."""


def check_target(target) -> str:
    """``target`` as the record key holds it: ``"pseudo-field"`` or ``"field:<scenario>"``
    (resolved: ``"field"`` alone, the rig's first scenario, is named by the caller, see
    :func:`vrig.desired.kinds.parse_target`); raises ValueError otherwise."""
    if target == PSEUDO_FIELD:
        return target
    kind, _, scenario = target.partition(":") if isinstance(target, str) else ("", "", "")
    if kind != "field" or not scenario.strip() or ":" in scenario:
        raise ValueError(f"target must be 'pseudo-field' or 'field:<scenario>', got {target!r}")
    return target


@functools.total_ordering
@dataclass(frozen=True)
class RecordKey:
    """What a record is a function of (with the run :class:`Settings`).

    ``severity`` is the rig's non-linearity severity (``vrig.load_rig(rig, severity=s)``, s in
    [0, 2]); None (default) is the rig as loaded without one, which is what every record made
    before the severity axis existed is (their files have no ``severity`` in their key).
    ``target`` is the kind of desired response: ``"pseudo-field"`` (default; every record made
    before the target axis existed, whose files have no ``target`` in their key) or
    ``"field:<scenario>"`` (a service record of the rig; ``desired`` is then the road's seed)."""

    rig: str
    method: str
    desired: int
    seed: int
    severity: float | None = None
    target: str = PSEUDO_FIELD

    def __post_init__(self):
        object.__setattr__(self, "severity", check_severity(self.severity))
        check_target(self.target)

    def _order(self):
        sev = -1.0 if self.severity is None else self.severity  # None sorts first
        field = self.target != PSEUDO_FIELD  # pseudo-field sorts first
        return (self.rig, self.method, self.desired, self.seed, sev, field, self.target)

    def __lt__(self, other):
        if not isinstance(other, RecordKey):
            return NotImplemented
        return self._order() < other._order()


def key_dict(key: RecordKey) -> dict:
    """The ``key`` field of ``key``'s record: ``{rig, method, desired, seed}``, plus
    ``severity`` when it is not None and ``target`` when it is not ``"pseudo-field"`` (so a
    record at the rig as loaded on a pseudo-field target is written exactly as before the
    severity and target axes existed)."""
    d = asdict(key)
    if d["severity"] is None:
        del d["severity"]
    if d["target"] == PSEUDO_FIELD:
        del d["target"]
    return d


def format_severity(severity: float | None) -> str:
    """``"None"`` or the shortest text that reads back as the same float (``0.5``, ``1``)."""
    if severity is None:
        return "None"
    short = f"{severity:g}"
    return short if float(short) == severity else repr(float(severity))


def _safe(text: str) -> str:
    return "".join(c if c.isalnum() or c in "-_." else "_" for c in text)


def record_id(key: RecordKey) -> str:
    """File-name-safe id: ``rig--method--dDESIRED--sSEED``, with ``--sevSEVERITY`` appended
    when the key has a severity (``...--s0--sev0.5``) and ``--field-SCENARIO`` for a field
    target (``...--s0--field-rough-road``); a pseudo-field key without a severity keeps the id
    it had before these axes existed, so older results folders resume."""
    rid = f"{_safe(key.rig)}--{key.method}--d{key.desired}--s{key.seed}"
    if key.severity is not None:
        rid += f"--sev{format_severity(key.severity)}"
    if key.target != PSEUDO_FIELD:
        rid += "--field-" + _safe(key.target.partition(":")[2])
    return rid


def _is_int(x) -> bool:
    return isinstance(x, int) and not isinstance(x, bool)


def _is_finite(x) -> bool:
    return isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x)


def _check_ok(rec: dict) -> str | None:
    """Why an ``ok`` record's scores are malformed (None if they are well-formed)."""
    per = rec.get("eta0_per_iteration")
    if not (isinstance(per, list) and per and all(_is_finite(v) for v in per)):
        return "eta0_per_iteration is not a non-empty list of finite numbers"
    for name in ("eta0_it00", "eta0_final", "eta0_best"):
        if not _is_finite(rec.get(name)):
            return f"{name} is {rec.get(name)!r}, not a finite number"
    best, run = rec.get("best_iteration"), rec.get("iterations_run")
    if not (_is_int(run) and run == len(per) - 1 and _is_int(best) and 0 <= best <= run):
        return f"iterations_run {run!r} / best_iteration {best!r} do not fit {len(per)} η0 values"
    if (rec["eta0_it00"], rec["eta0_final"], rec["eta0_best"]) != (per[0], per[-1], per[best]):
        return "eta0_it00/final/best disagree with eta0_per_iteration"
    for name in ("rms_error", "damage_ratio", "normal_model_error", "inverse_model_error"):
        if rec.get(name) is not None and not _is_finite(rec[name]):
            return f"{name} is {rec[name]!r}, not a finite number or null"
    if not isinstance(rec.get("stopped"), str):
        return "stopped is not a string"
    return None


def _check_key_target(k: dict) -> str | None:
    """Why a record key's ``target`` is malformed (written only for a field target)."""
    if "target" not in k:
        return None
    if k["target"] == PSEUDO_FIELD:
        return "key target is 'pseudo-field' (a pseudo-field record has no target in its key)"
    try:
        check_target(k["target"])
    except ValueError as exc:
        return f"key {exc}"
    return None


def check_record(rec, key: RecordKey | None = None, settings: Settings | None = None) -> str | None:
    """Why ``rec`` is not a finished, well-formed record (of ``key`` and ``settings`` when
    given); None when it is.

    A record is kept by a re-run only when this returns None: a file cut short, edited by hand,
    copied from another record or another run, or with non-finite scores is recomputed.
    """
    if not isinstance(rec, dict):
        return f"not a JSON object but {type(rec).__name__}"
    if rec.get("schema") != SCHEMA:
        return f"schema {rec.get('schema')!r}, not {SCHEMA}"
    k = rec.get("key")
    fields, optional = {"rig", "method", "desired", "seed"}, {"severity", "target"}
    if not (isinstance(k, dict) and fields <= set(k) <= fields | optional):
        return "key is not {rig, method, desired, seed[, severity][, target]}"
    if not (isinstance(k["rig"], str) and isinstance(k["method"], str)):
        return "key rig/method are not strings"
    if not (_is_int(k["desired"]) and _is_int(k["seed"])):
        return "key desired/seed are not integers"
    if "severity" in k:  # written only when not None: a null severity is not a record's
        if k["severity"] is None:
            return "key severity is null (a record at the rig as loaded has no severity)"
        try:
            check_severity(k["severity"])
        except ValueError as exc:
            return f"key {exc}"
    why = _check_key_target(k)
    if why is not None:
        return why
    have = RecordKey(**k)
    if rec.get("id") != record_id(have):
        return f"id {rec.get('id')!r} does not match its key {k}"
    if key is not None and have != key:
        return f"a record of {record_id(have)}, not of {record_id(key)}"
    if settings is not None and rec.get("settings") != asdict(settings):
        return "made with other settings"
    if not isinstance(rec.get("timing"), dict):
        return "no timing"
    status = rec.get("status")
    if status == "failed":
        err = rec.get("error")
        ok = isinstance(err, dict) and all(
            isinstance(err.get(f), str) for f in ("stage", "type", "message")
        )
        return None if ok else "a failed record without {stage, type, message}"
    if status != "ok":
        return f"status {status!r}, not 'ok' or 'failed'"
    if rec.get("error") is not None:
        return "an ok record with an error"
    return _check_ok(rec)


def strip_timing(record: dict) -> dict:
    """The record without its ``timing`` (what two runs of the same record agree on)."""
    return {k: v for k, v in record.items() if k != "timing"}


def _clean(x):
    """JSON-ready: floats (non-finite -> None), lists, ints."""
    if isinstance(x, np.ndarray):
        return [_clean(v) for v in x.tolist()]
    if isinstance(x, (list, tuple)):
        return [_clean(v) for v in x]
    if isinstance(x, (bool, np.bool_)):
        return bool(x)
    if isinstance(x, (int, np.integer)):
        return int(x)
    if isinstance(x, (float, np.floating)):
        return float(x) if math.isfinite(x) else None
    return x


class _Timed:
    """Wraps a method object (a :class:`~vrig.reconstruction.protocol.Method`): times
    ``identify``/``drive`` and keeps the first identification records it was given (the
    processed, decimated IDDRV/IDRES). It is itself a ``Method``."""

    def __init__(self, method):
        self.wrapped = method
        self.fit_s = 0.0
        self.sim_s = 0.0
        self.id_records = None

    def identify(self, iddrv, idres):
        if self.id_records is None:
            self.id_records = (iddrv, idres)
        t = time.perf_counter()
        try:
            return self.wrapped.identify(iddrv, idres)
        finally:
            self.fit_s += time.perf_counter() - t

    @property
    def name(self):
        """The wrapped method's name (the defaults resolver reads its side-car block by it)."""
        return getattr(self.wrapped, "name", None)

    def drive(self, response):
        t = time.perf_counter()
        try:
            return self.wrapped.drive(response)
        finally:
            self.sim_s += time.perf_counter() - t

    def describe(self):
        if isinstance(self.wrapped, Method):
            return self.wrapped.describe()
        return type(self.wrapped).__name__  # a plugin object with identify and drive only


def _load_rig(rig_name: str, seed: int, fidelity: str, severity: float | None):
    """``vrig.load_rig`` at ``severity`` (None: the rig as loaded, no ``severity=`` given)."""
    import vrig

    extra = {} if severity is None else {"severity": severity}
    return vrig.load_rig(rig_name, seed=seed, fidelity=fidelity, **extra)


def _desired(rig_name: str, fidelity: str, seconds: float, desired: int, severity=None,
             target: str = PSEUDO_FIELD):  # fmt: skip
    """``(band, record)`` of :func:`_target` (the desired response without its source)."""
    return _target(rig_name, fidelity, seconds, desired, severity, target)[:2]


@functools.lru_cache(maxsize=8)
def _target(rig_name: str, fidelity: str, seconds: float, desired: int, severity, target: str):
    """The desired response of ``target`` (pure function of its arguments; cached per process):
    ``(band, record, source)``.

    A pseudo-field record is the response of the rig *at the record's severity* (seed 0) to the
    pseudo-field drive: the field record a real rig with that non-linearity would have given,
    so every severity has a desired response its rig can reproduce (the pseudo-field drive
    does), and the error measures the method, not an unreachable target (benchmarks/README.md,
    Runner). A field record is the service record of that rig's specimen in its vehicle on the
    road of seed ``desired``; it need not be reachable. Both are made by
    :func:`vrig.desired.kinds.desired_response` (the one place a target is made); ``band`` is the
    rig's default simulation band for either."""
    from vrig.desired.kinds import desired_response
    from vrig.reconstruction.defaults import default_band

    rig = _load_rig(rig_name, 0, fidelity, severity)
    band = default_band(rig)
    record, source, _extra = desired_response(rig, target, seconds, seed=desired, band=band)
    return band, record, source


def _error(stage: str, exc: BaseException) -> dict:
    """``{stage, type, message}``; a :class:`vrig.ReconstructionError` (nothing could be played)
    is reported by the type of the error that caused it."""
    cause = getattr(exc, "cause", None)
    kind = type(cause if isinstance(cause, BaseException) else exc).__name__
    return {"stage": stage, "type": kind, "message": str(exc)}


def _split(th, holdout: float):
    from vrig.timehistory import TimeHistory

    k = round(th.n_samples * (1 - holdout))

    def part(a, b):
        return TimeHistory(th.data[a:b], th.fs, th.names, th.units)

    return part(0, k), part(k, th.n_samples)


def _keep_lead(method, fitted) -> None:
    """Give a fresh inverse the lead(s) ``fitted`` chose (an
    :class:`~vrig.reconstruction.protocol.InverseModelMethod`; other methods: nothing to do)."""
    if isinstance(method, InverseModelMethod) and isinstance(fitted, InverseModelMethod):
        method.set_lead(fitted.fitted_lead())


def _causal(method) -> None:
    """Make a forward model causal (lead 0, no lead search) if it has a lead."""
    if isinstance(method, InverseModelMethod):
        method.set_lead(0)


def modelling_errors(plugin, rig, band, iddrv, idres, holdout: float, fitted=None) -> dict:
    """Normal and inverse modelling errors (mean η0 %, held-out free runs; see module doc)."""
    from identification import metrics
    from vrig.timehistory import TimeHistory

    out = {"normal_model_error": None, "inverse_model_error": None, "modelling_notes": []}
    d_fit, d_val = _split(iddrv, holdout)
    r_fit, r_val = _split(idres, holdout)
    try:
        inverse = plugin.make(rig, band)
        if fitted is not None:
            _keep_lead(inverse, fitted)
        inverse.identify(d_fit, r_fit)
        pred = np.asarray(inverse.drive(r_val), dtype=float).reshape(d_val.data.shape)
        out["inverse_model_error"] = float(np.mean(metrics.qantim_fit_dc(d_val.data, pred)))
    except Exception as exc:
        out["modelling_notes"].append(f"inverse: {type(exc).__name__}: {exc}")
    try:
        forward = plugin.make_forward(rig, band)
        _causal(forward)
        # roles swapped: the "drive" of the swapped problem is the response and vice versa
        forward.identify(
            TimeHistory(r_fit.data, r_fit.fs, r_fit.names, r_fit.units),
            TimeHistory(d_fit.data, d_fit.fs, d_fit.names, d_fit.units),
        )
        pred = np.asarray(forward.drive(d_val), dtype=float).reshape(r_val.data.shape)
        out["normal_model_error"] = float(np.mean(metrics.qantim_fit_dc(r_val.data, pred)))
    except Exception as exc:
        out["modelling_notes"].append(f"normal: {type(exc).__name__}: {exc}")
    return out


def compute_record(key: RecordKey, settings: Settings, plugin_specs=()) -> dict:
    """Run one record (see the module docstring). Never raises for a failing reconstruction:
    the failure is recorded. ``plugin_specs`` are loaded first (worker processes)."""
    import vrig

    t_record = time.perf_counter()
    load_plugins(plugin_specs)
    rec: dict = {
        "schema": SCHEMA,
        "id": record_id(key),
        "key": key_dict(key),
        "settings": asdict(settings),
        "status": "failed",
        "error": None,
    }
    timing = {"fit_s": None, "model_sim_s": None, "reconstruction_s": None}
    stage = "plugin"
    try:
        plugin = get_method(key.method)
        rec["method_origin"] = plugin.origin
        if plugin.linear is not None:
            rec["method_linear"] = plugin.linear
        stage = "desired response"
        band, desired, source = _target(
            key.rig, settings.fidelity, float(settings.seconds), key.desired, key.severity,
            key.target,
        )  # fmt: skip
        rec["band"] = list(band)
        if key.target != PSEUDO_FIELD:  # a pseudo-field record is written as before the axis
            rec["target_source"] = source
        stage = "rig"
        rig = _load_rig(key.rig, key.seed, settings.fidelity, key.severity)
        rec["n_drives"], rec["n_responses"] = len(rig.inputs), len(rig.outputs)
        stage = "method"
        timed = _Timed(plugin.make(rig, band))
        stage = "reconstruction"
        t = time.perf_counter()
        try:
            iteration = settings.iteration(timed, band, key.seed, update=plugin.update)
            result = vrig.reconstruct(rig, desired, iteration)
        finally:
            timing["reconstruction_s"] = time.perf_counter() - t
            timing["fit_s"], timing["model_sim_s"] = timed.fit_s, timed.sim_s
            rec["method_description"] = _describe(timed)
            if timed.id_records is not None:
                fitted = timed.wrapped if timed.fit_s > 0 else None
                rec.update(
                    modelling_errors(
                        plugin, rig, band, *timed.id_records, settings.holdout, fitted=fitted
                    )
                )
    except Exception as exc:
        rec["error"] = _error(stage, exc)
    else:
        rec.update(_scores(result, timed.wrapped, settings))
        rec["status"] = "ok"
    timing["record_s"] = time.perf_counter() - t_record
    timing["host"] = platform.node()
    timing["pid"] = os.getpid()
    rec["timing"] = timing
    rec = _clean_record(rec)
    why = check_record(rec, key, settings)
    if why is not None and rec["status"] == "ok":  # e.g. a NaN score: a failure, not a result
        rec["status"], rec["error"] = (
            "failed",
            {
                "stage": "scores",
                "type": "MalformedRecord",
                "message": why,
            },
        )
    return rec


def _describe(timed) -> str:
    try:
        return str(timed.describe())
    except Exception as exc:  # not fitted (identification failed)
        return f"({type(exc).__name__} in describe)"


def _scores(result, method, settings: Settings) -> dict:
    errors = np.asarray(result.errors)
    means = errors.mean(axis=1)
    best = int(result.best_iteration)
    reached = np.flatnonzero(means <= settings.tolerance)
    return {
        "iterations_run": len(means) - 1,
        "stopped": result.stopped,
        "decimation": result.decimation,
        "eta0_it00": means[0],
        "eta0_final": means[-1],
        "eta0_best": means[best],
        "best_iteration": best,
        "iterations_to_tolerance": int(reached[0]) if reached.size else None,
        "eta0_per_iteration": means,
        "eta0_it00_channels": errors[0],
        "eta0_best_channels": errors[best],
        "rms_error": float(np.mean(result.rms_errors[best])),
        "rms_error_channels": result.rms_errors[best],
        "damage_ratio": float(np.mean(result.damage_ratio[best])),
        "damage_ratio_channels": result.damage_ratio[best],
        "model_size": model_size(method),
    }


def _clean_record(rec: dict) -> dict:
    return {
        k: (
            _clean(v)
            if k not in ("key", "settings", "error", "timing", "modelling_notes")
            else {kk: _clean(vv) for kk, vv in v.items()}
            if isinstance(v, dict)
            else v
        )
        for k, v in rec.items()
    }
