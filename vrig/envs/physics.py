"""Physics of the drive-iteration environments: the rig, its inverse model and the iteration engine.

No observation, reward or termination here (that is :mod:`vrig.envs.task`), dm_control style:
:class:`IterationPhysics` owns the rig (built once), identifies the inverse model once per
rig and identification settings (:meth:`~vrig.reconstruction.IterationSettings.identification_key`)
and keeps it in a small process-wide cache, and starts one
:class:`~vrig.reconstruction.DriveIteration` engine per episode around a desired response with
a private copy of that model (re-identification during an episode never leaks into the next one).
It makes the desired responses too, of its ``target`` (pseudo-field or a service scenario's field
record, :func:`vrig.desired.kinds.desired_response`), one per seed (:meth:`IterationPhysics.target_record`).
"""

from __future__ import annotations

import copy
import hashlib
import warnings
from collections import OrderedDict

import numpy as np

from identification.errors import SimulationDivergedError

from ..desired.kinds import desired_responses, parse_target
from ..errors import RigLimitError, SimulationInstabilityError, UnsupportedMethodWarning
from ..reconstruction import DriveIteration, IterationSettings
from ..reconstruction.defaults import resolve
from ..reconstruction.settings import cache_key
from ..rigs import load_rig
from ..timehistory import TimeHistory

__all__ = ["IterationPhysics", "clear_model_cache"]

_CACHE_SIZE = 16
_FIELD_CACHE_SIZE = 256  # desired records per physics (a 20 s SISO record is 80 kB)
_MODELS: OrderedDict = OrderedDict()


def clear_model_cache() -> None:
    """Forget every identified inverse model (the next reset identifies again)."""
    _MODELS.clear()


def _env_warning(resolved, rig) -> None:
    """The one-line warning of a method the rig's side-car marks ``unsupported`` (the resolver's
    text, and the env's default method on the rig)."""
    if resolved.warning:
        default = getattr(getattr(rig, "defaults", None), "gym_method", None) or "arx"
        warnings.warn(
            f"{resolved.warning} (the env's default method on this rig: {default!r})",
            UnsupportedMethodWarning,
            stacklevel=3,
        )


class IterationPhysics:
    """The rig and its inverse model, ready to iterate a drive for any desired response.

    Parameters
    ----------
    rig : str or Rig
        A shipped rig name (built with ``load_rig(rig, seed=rig_seed, fidelity=fidelity,
        **rig_options)``) or a rig object.
    settings : IterationSettings, optional
        The identification settings (method and its options, band, identification drive,
        decimation, taper, ``id_seed``); the band defaults to :func:`vrig.reconstruction.defaults.default_band` and
        ``id_duration`` to ``seconds``. ``id_seed`` is fixed for the life of the physics, so every
        episode reuses the same identified model; the run seed is per episode (:meth:`start`).
        Resolved by :func:`vrig.reconstruction.defaults.resolve` as every door resolves them
        (the caller's values, then the rig side-car's method options, band and identification
        level, then the built-in defaults; the gain is the env's action, not a setting); a method
        the side-car marks ``unsupported`` runs after a one-line
        :class:`~vrig.errors.UnsupportedMethodWarning` quoting the side-car.
    seconds : float
        Length of the desired responses [s].
    fidelity : {"full", "fast"}
        Rig fidelity of a named rig.
    rig_seed : int
        Seed of a named rig (its noise realisation).
    rig_options : dict, optional
        Further ``load_rig`` options of a named rig (``variant``, ``severity``, parameters).
    target : str
        What the desired responses are (:func:`vrig.desired.kinds.desired_response`, checked here with
        :func:`vrig.desired.kinds.parse_target`): ``"pseudo-field"`` (default: the rig's response to a
        seeded road-like drive over the band), ``"field:<scenario>"`` (a service record of the
        rig's specimen in its vehicle, :func:`vrig.service.field_record`: each seed a new road
        profile, at the scenario's own speed and road class) or ``"field"`` (the rig's first
        scenario). Kept resolved in :attr:`target` (``"pseudo-field"`` or
        ``"field:<scenario>"``).
    **options
        Settings by name on top of ``settings`` (:meth:`IterationSettings.build`);
        ``model_seed`` is the identification seed (``id_seed``).
    """

    def __init__(
        self,
        rig,
        settings: IterationSettings | None = None,
        *,
        seconds: float = 20.0,
        fidelity: str = "full",
        rig_seed: int = 0,
        rig_options: dict | None = None,
        target: str = "pseudo-field",
        **options,
    ):
        if not (np.isfinite(seconds) and seconds >= 2.0):
            raise ValueError(f"seconds must be a finite number >= 2, got {seconds!r}")
        rig_options = dict(rig_options or {})
        if isinstance(rig, str):
            self.rig = load_rig(rig, seed=rig_seed, fidelity=fidelity, **rig_options)
            rig_key = (rig, fidelity, rig_seed, cache_key(rig_options))
        else:
            self.rig = rig
            rig_key = cache_key(rig)  # by identity, kept alive by the key
        if "model_seed" in options:
            options["id_seed"] = options.pop("model_seed")
        settings = IterationSettings.build(settings, **options)
        if settings.id_duration is None:
            settings = settings.replace(id_duration=float(seconds))
        self.resolved = resolve(self.rig, settings)  # the one resolver, as every door
        _env_warning(self.resolved, self.rig)
        self.settings = self.resolved.settings
        self.band = self.settings.bandwidth
        self.seconds = float(seconds)
        kind, scenario = parse_target(self.rig, target)
        self.target = kind if scenario is None else f"{kind}:{scenario}"
        self._fields: OrderedDict = OrderedDict()
        self._failed: OrderedDict = OrderedDict()  # seeds whose record raised
        self._twins: dict = {}  # field target -> its field twin
        self.inputs = list(self.rig.inputs)
        self.outputs = list(self.rig.outputs)
        self.fs = float(self.rig.fs)
        self.drive_full_scale = np.array([c.full_scale for c in self.inputs], dtype=float)
        self._key = (rig_key, self.settings.identification_key())

    @property
    def n_inputs(self) -> int:
        """Number of drive channels."""
        return len(self.inputs)

    @property
    def n_outputs(self) -> int:
        """Number of response channels."""
        return len(self.outputs)

    def target_record(self, seed: int) -> TimeHistory:
        """The desired response of seed ``seed`` for this physics' :attr:`target`.

        A pseudo-field record (:func:`vrig.desired.pseudo_field.pseudo_field` over ``self.band``, the drive's
        seed ``seed``) or a service record (:func:`vrig.service.field_record`: the road's seed
        ``seed``; the scenario's speed and road class), ``self.seconds`` long, made by
        :func:`vrig.desired.kinds.desired_response`; the last 256 records are kept (a seed always gives
        the same record, bit for bit).

        Parameters
        ----------
        seed : int
            Seed of the record (of the pseudo-field drive or of the road profile).
        """
        return self._record(self.target, seed)

    def pseudo_field(self, seed: int) -> TimeHistory:
        """A pseudo-field desired response (the rig's response to a seeded road-like drive),
        whatever :attr:`target` is; with the default target it is :meth:`target_record`'s.

        Parameters
        ----------
        seed : int
            Seed of :func:`vrig.desired.pseudo_field.pseudo_field` (over ``self.band``, ``self.seconds`` long);
            the last 256 records are kept.
        """
        return self._record("pseudo-field", seed)

    def target_records(self, seeds, *, threads: int | None = None) -> list:
        """:meth:`target_record` of many seeds, those not kept yet made together, their rig runs
        batched (:func:`vrig.desired.kinds.desired_responses`, across threads).

        Record ``i`` is bit for bit ``target_record(seeds[i])``; a seed whose record cannot be
        made (its last pseudo-field level trips, say) gets the exception in its slot, and
        :meth:`target_record` of that seed raises it (once: then it is made again). A vector env
        calls this with the seeds of every resetting sub-env before they start.

        Parameters
        ----------
        seeds : sequence of int
            Seeds of the records (each >= 0).
        threads : int, optional
            Worker threads of the batched rig runs (:meth:`vrig.rigs.MujocoRig.run_batch`).

        Returns
        -------
        list of TimeHistory (or Exception)
        """
        return self._records(self.target, seeds, threads)

    def _record(self, target: str, seed: int) -> TimeHistory:
        """:func:`vrig.desired.kinds.desired_response`'s record of ``target`` and ``seed`` (cached; a
        failure left by :meth:`target_records` is raised once)."""
        record = self._records(target, [seed], None)[0]
        if isinstance(record, BaseException):
            self._failed.pop((target, int(seed)), None)
            raise record
        return record

    def _records(self, target: str, seeds, threads) -> list:
        """The records of ``target`` and ``seeds``: kept, failed before, or made in one batch
        (:func:`vrig.desired.kinds.desired_responses`), the made ones kept (the last 256) and the
        failures noted (for the next :meth:`_record`: they are made again after that)."""
        keys = [(target, int(s)) for s in seeds]
        found = {k: self._fields.get(k, self._failed.get(k)) for k in keys}
        missing = list(dict.fromkeys(k[1] for k, v in found.items() if v is None))
        if missing:
            twin = None if target == "pseudo-field" else self._field_twin(target)
            made = desired_responses(self.rig, target, self.seconds, missing, band=self.band,
                                     threads=threads, twin=twin)  # fmt: skip
            for s, m in zip(missing, made, strict=True):
                key = (target, s)
                found[key] = m if isinstance(m, BaseException) else m[0]
                if isinstance(m, BaseException):
                    self._failed[key] = m
                else:
                    self._fields[key] = m[0]
            while len(self._fields) > _FIELD_CACHE_SIZE:
                self._fields.popitem(last=False)
            while len(self._failed) > _FIELD_CACHE_SIZE:
                self._failed.popitem(last=False)
        return [found[k] for k in keys]

    def _field_twin(self, target: str):
        """The field twin of a ``"field:<scenario>"`` target (built once per physics: its
        construction costs about as much as a short record)."""
        twin = self._twins.get(target)
        if twin is None:
            from ..service import field_twin

            twin = self._twins[target] = field_twin(self.rig, target.partition(":")[2])
        return twin

    def start(self, desired: TimeHistory, run_seed: int) -> DriveIteration:
        """An engine for ``desired`` with the (cached) identified inverse model; its rig runs use
        the seeds ``run_seed + 1 + iteration`` (as :func:`vrig.reconstruct` with ``seed=run_seed``).

        Parameters
        ----------
        desired : TimeHistory
            The desired response, one column per rig output, at the rig's fs.
        run_seed : int
            The engine's run seed (:attr:`IterationSettings.run_seed`); the identification seed
            stays the physics' own (the inverse model is identified once, then copied from the
            cache).
        """
        engine = DriveIteration(self.rig, desired, self.resolved.replace(run_seed=int(run_seed)))
        key = self._key
        if self.settings.id_match:  # the model depends on the target too: one per target
            key = (*key, hashlib.sha256(np.ascontiguousarray(desired.data).tobytes()).hexdigest())
        cached = _MODELS.get(key)
        if cached is None:
            engine.identify()
            _MODELS[key] = (copy.deepcopy(engine.method), engine.id_drive, engine.id_response)
            while len(_MODELS) > _CACHE_SIZE:
                _MODELS.popitem(last=False)
        else:
            _MODELS.move_to_end(key)
            method, id_drive, id_response = cached
            engine.use_identified(copy.deepcopy(method), id_drive, id_response)
        return engine


FAILURES = (RigLimitError, SimulationInstabilityError, SimulationDivergedError)
"""The exceptions a step turns into a terminated episode with the trip penalty (a refused or
tripped drive, an unstable simulation, a diverging inverse-model free run)."""
