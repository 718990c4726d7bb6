"""Physics of the drive-iteration environments: the rig, its inverse model and the iteration engine.

No observation, reward or termination here (that is :mod:`vrig.envs.task`), dm_control style:
:class:`IterationPhysics` owns the rig (built once), identifies the inverse model once per
(rig, method, options, band, identification length and level, decimation, identification seed)
and keeps it in a small process-wide cache, and starts one
:class:`~vrig.reconstruction.DriveIteration` engine per episode around a desired response with
a private copy of that model (re-identification during an episode never leaks into the next one).
"""

from __future__ import annotations

import copy
from collections import OrderedDict

import numpy as np

from identification.errors import SimulationDivergedError

from ..errors import RigLimitError, SimulationInstabilityError
from ..field import default_band, pseudo_field
from ..reconstruction import DriveIteration
from ..rigs import load_rig
from ..timehistory import TimeHistory

__all__ = ["IterationPhysics", "clear_model_cache"]

_CACHE_SIZE = 16
_FIELD_CACHE_SIZE = 256  # pseudo-field records per physics (a 20 s SISO record is 80 kB)
_MODELS: OrderedDict = OrderedDict()


def clear_model_cache() -> None:
    """Forget every identified inverse model (the next reset identifies again)."""
    _MODELS.clear()


def _freeze(value):
    """A hashable, repr-stable version of an option value for the cache key."""
    if isinstance(value, dict):
        return tuple(sorted((k, _freeze(v)) for k, v in value.items()))
    if isinstance(value, (list, tuple, np.ndarray)):
        return tuple(_freeze(v) for v in np.asarray(value, dtype=object).ravel())
    if isinstance(value, (str, int, float, bool, type(None), np.generic)):
        return value
    return repr(value)


class IterationPhysics:
    """The rig and its inverse model, ready to iterate a drive for any desired response.

    Parameters
    ----------
    rig : str or Rig
        A shipped rig name (built with ``load_rig(rig, seed=rig_seed, fidelity=fidelity,
        **rig_options)``) or a rig object.
    method : str
        Reconstruction method (``"arx"``, ``"narx"``, ``"split"``, ``"frf"``); ``method_options``
        go to it (``order``, ``degree``, ``split_hz``, ...).
    bandwidth : (low, high) Hz, optional
        Simulation band (default :func:`vrig.field.default_band`).
    seconds : float
        Length of the pseudo-field desired responses and (unless ``id_duration`` is given) of
        the identification drive.
    id_duration, id_rms, decimation
        As in :func:`vrig.reconstruct` (``id_duration`` defaults to ``seconds``).
    model_seed : int
        Seed of the identification drive and of the identification run: fixed for the life of
        the physics, so every episode reuses the same identified model.
    """

    def __init__(
        self,
        rig,
        *,
        method: str = "arx",
        method_options: dict | None = None,
        bandwidth: tuple[float, float] | None = None,
        seconds: float = 20.0,
        id_duration: float | None = None,
        id_rms=None,
        decimation: int | None = None,
        model_seed: int = 0,
        fidelity: str = "full",
        rig_seed: int = 0,
        rig_options: dict | None = None,
    ):
        if not (np.isfinite(seconds) and seconds >= 2.0):
            raise ValueError(f"seconds must be a finite number >= 2, got {seconds!r}")
        rig_options = dict(rig_options or {})
        if isinstance(rig, str):
            self.rig = load_rig(rig, seed=rig_seed, fidelity=fidelity, **rig_options)
            rig_key = (rig, fidelity, rig_seed, _freeze(rig_options))
        else:
            self.rig = rig
            rig_key = ("object", id(rig))
        self.method_name = method
        self.method_options = dict(method_options or {})
        self.band = tuple(float(b) for b in (bandwidth or default_band(self.rig)))
        self.seconds = float(seconds)
        self.id_duration = float(id_duration) if id_duration is not None else self.seconds
        self.id_rms = id_rms
        self.decimation = decimation
        self.model_seed = int(model_seed)
        self._fields: OrderedDict = OrderedDict()
        self.inputs = list(self.rig.inputs)
        self.outputs = list(self.rig.outputs)
        self.fs = float(self.rig.fs)
        self.drive_full_scale = np.array([c.full_scale for c in self.inputs], dtype=float)
        self._key = (
            rig_key,
            method,
            _freeze(self.method_options),
            self.band,
            self.id_duration,
            _freeze(id_rms),
            decimation,
            self.model_seed,
        )

    @property
    def n_inputs(self) -> int:
        return len(self.inputs)

    @property
    def n_outputs(self) -> int:
        return len(self.outputs)

    def pseudo_field(self, seed: int) -> TimeHistory:
        """A pseudo-field desired response (the rig's response to a seeded road-like drive);
        the last few are kept (a seed always gives the same record, bit for bit)."""
        seed = int(seed)
        record = self._fields.get(seed)
        if record is None:
            record = pseudo_field(self.rig, self.band, self.seconds, seed=seed)[1]
            self._fields[seed] = record
            while len(self._fields) > _FIELD_CACHE_SIZE:
                self._fields.popitem(last=False)
        return record

    def start(self, desired: TimeHistory, run_seed: int) -> DriveIteration:
        """An engine for ``desired`` with the (cached) identified inverse model; its rig runs use
        the seeds ``run_seed + 1 + iteration`` (as :func:`vrig.reconstruct` with ``seed=run_seed``).
        """
        engine = DriveIteration(
            self.rig,
            desired,
            method=self.method_name,
            bandwidth=self.band,
            id_duration=self.id_duration,
            id_rms=self.id_rms,
            decimation=self.decimation,
            seed=self.model_seed,
            **self.method_options,
        )
        cached = _MODELS.get(self._key)
        if cached is None:
            engine.identify()
            _MODELS[self._key] = (copy.deepcopy(engine.method), engine.id_drive, engine.id_response)
            while len(_MODELS) > _CACHE_SIZE:
                _MODELS.popitem(last=False)
        else:
            _MODELS.move_to_end(self._key)
            method, id_drive, id_response = cached
            engine.use_identified(copy.deepcopy(method), id_drive, id_response)
        engine.seed = int(run_seed)  # from here on the engine's seed only seeds the rig runs
        return engine


FAILURES = (RigLimitError, SimulationInstabilityError, SimulationDivergedError)
"""The exceptions a step turns into a terminated episode with the trip penalty (a refused or
tripped drive, an unstable simulation, a diverging inverse-model free run)."""
