"""The settings of one drive iteration: one frozen object shared by every caller.

:func:`~vrig.reconstruct`, :class:`~vrig.reconstruction.DriveIteration`, the gymnasium environments
(:class:`~vrig.envs.IterationPhysics`) and the benchmark runner all take an
:class:`IterationSettings`; the keyword arguments they also accept (``method="narx", gain=0.5,
order=4, ...``) are turned into one with :meth:`IterationSettings.build`, so every default and every
check lives here, once.

Two seeds: ``id_seed`` seeds the identification drive and the identification run (so the identified
model is a function of it alone), ``run_seed`` the rig's noise in the iteration runs (ITxx is run
with ``run_seed + 1 + xx``). The single ``seed=`` keyword of :func:`~vrig.reconstruct` sets both.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any

import numpy as np

__all__ = ["MAX_ITERATIONS", "STRATEGIES", "UPDATES", "IterationSettings", "cache_key"]

MAX_ITERATIONS = 99
"""Most iterations after IT00 (the records are named IT00 .. IT99)."""

STRATEGIES = ("fixed", "adaptive")
"""``"fixed"``: one inverse model for the whole iteration; ``"adaptive"``: re-identified from the
latest drive / raw response pair before every update."""

UPDATES = ("none", "frf", "secant", "reidentify", "ilc")
"""How the correction model learns from the iteration's data (:mod:`.updates`): ``"none"``
(the inverse identified before IT00, as is), ``"frf"``, ``"secant"``, ``"reidentify"``,
``"ilc"``."""


def _check_seed(seed, name: str) -> int:
    if not isinstance(seed, (int, np.integer)) or isinstance(seed, bool) or seed < 0:
        raise ValueError(f"{name} must be a non-negative integer, got {seed!r}")
    return int(seed)


def _frozen(value):
    """Arrays and lists as (nested) tuples, so a settings object is immutable all the way down."""
    if isinstance(value, np.ndarray):
        return value.item() if value.ndim == 0 else tuple(_frozen(v) for v in value)
    if isinstance(value, list):
        return tuple(_frozen(v) for v in value)
    return value


@dataclass(frozen=True)
class IterationSettings:
    """Everything that decides a drive iteration apart from the rig and the desired response.

    Frozen: derive a variant with :meth:`replace`. Rig-independent values are checked here, when the
    object is made; the values that need the rig (the band against its Nyquist frequency, the
    identification level against its full scale, one gain per drive channel) when an iteration
    starts (:class:`~vrig.reconstruction.DriveIteration`).

    Parameters
    ----------
    method : str or method object
        ``"arx"``, ``"narx"``, ``"split"``, ``"frf"``, ``"error-signal"``,
        ``"rattlesnake:<file.py>:<name>"`` (a Rattlesnake control law,
        :mod:`vrig.reconstruction.rattlesnake`) or an object implementing the
        :class:`~vrig.reconstruction.Method` protocol; a name is built by
        :func:`~vrig.reconstruction.method_spec`.
    method_options : mapping
        Options of a named method (``order``, ``degree``, ``split_hz``, ...); stored read-only.
    iterations : int
        Correction iterations after IT00 (0 .. :data:`MAX_ITERATIONS`; default 5).
    gain : float or sequence of float, optional
        Iteration gain in (0, 2], one value or one per drive channel (default None: the rig
        side-car's, else :data:`vrig.reconstruction.defaults.DEFAULT_GAIN`, applied by
        :func:`vrig.reconstruction.defaults.resolve`).
    strategy : {"fixed", "adaptive"}
        See :data:`STRATEGIES`.
    bandwidth : (low, high) Hz, optional
        Simulation band applied to every record (default: the rig side-car's
        ``reconstruction.band`` where it names one, else the rig's test band ``rig.bandwidth``:
        :func:`vrig.reconstruction.defaults.default_band`).
    id_duration : float, optional
        Identification drive length [s] (default: the desired record's).
    id_rms : float or sequence of float, optional
        Identification drive RMS per drive channel, in the drive's unit (default: the rig
        side-car's fraction of full scale, else
        :data:`~vrig.reconstruction.defaults.DEFAULT_ID_RMS_FRACTION`; halved until the rig
        accepts it).
    id_psd : callable or list of callables, optional
        PSD shape of the identification drive (default: triangular over the identification band).
    id_match : bool
        Identification matched to the target (§3.3-3.4; :mod:`~vrig.reconstruction.matching`):
        a short broadband probe at ``id_rms`` measures the rig's FRF, the identification drive's
        PSD is shaped from DESRES through its inverse, and its level is raised (within the drives'
        full scale, halved on an interlock trip) until the identification responses reach the
        target's RMS and peak, so that the model has seen the amplitudes it must reproduce (a
        large, slow, non-Gaussian service target). Costs the probe and up to four identification
        runs; replaces ``id_psd`` (give one of them). Default ``False``: the drive above.
    decimation : int, optional
        Models work at ``fs / decimation`` (default: at least 8 samples per period of the
        identification band's upper edge).
    taper : float
        Every drive and correction is tapered to zero over its first and last ``taper`` seconds.
    id_seed : int
        Seeds the identification drive and the identification run.
    run_seed : int, optional
        Seeds the rig noise of the iteration runs (ITxx: ``run_seed + 1 + xx``); default
        ``id_seed``.
    divergence : float
        Stop when the mean η0 exceeds ``divergence`` times the best so far (>= 1; ``np.inf``:
        never) ...
    min_increase : float
        ... and by more than ``min_increase`` percentage points.
    tolerance : float, optional
        Stop as soon as every channel's η0 is at or below ``tolerance`` [%] (``result.stopped``
        says "converged"); ``None`` (default): play all ``iterations``. The iteration kept is
        still chosen by :func:`~vrig.reconstruction.result.best_iteration`.
    update : {"none", "frf", "secant", "reidentify", "ilc"}
        How the correction model learns from the iteration's drives and responses
        (:mod:`vrig.reconstruction.updates`; :data:`UPDATES`): ``"none"`` (default) keeps the
        inverse identified before IT00; ``"frf"`` corrects through an H1 FRF updated from the
        identification and every iteration record (forgetting factor, coherence guard);
        ``"secant"`` corrects the inverse per band by a Broyden (secant) update; ``"reidentify"``
        refits the method on the identification and the iteration records; ``"ilc"``:
        norm-optimal ILC with the identified forward FRF. Not with ``strategy="adaptive"``.
    update_options : mapping
        Parameters of the update (stored read-only; checked by
        :func:`vrig.reconstruction.updates.check_update_options`): ``forgetting``,
        ``coherence``, ``nperseg`` (frf, ilc), ``n_bands``, ``clip``, ``min_change`` (secant),
        ``records`` (reidentify), ``q``, ``r`` (ilc).
    """

    method: Any = "arx"
    method_options: Mapping[str, Any] = field(default_factory=dict)
    iterations: int = 5
    gain: float | tuple[float, ...] | None = None
    strategy: str = "fixed"
    bandwidth: tuple[float, float] | None = None
    id_duration: float | None = None
    id_rms: float | tuple[float, ...] | None = None
    id_psd: Any = None
    id_match: bool = False
    decimation: int | None = None
    taper: float = 0.25
    id_seed: int = 0
    run_seed: int | None = None
    divergence: float = 1.5
    min_increase: float = 1.0
    tolerance: float | None = None
    update: str = "none"
    update_options: Mapping[str, Any] = field(default_factory=dict)

    def __post_init__(self):
        put = object.__setattr__
        put(self, "method_options", MappingProxyType(dict(self.method_options)))
        opts = self.update_options
        if not isinstance(opts, Mapping):
            raise ValueError(f"update_options must be a mapping, got {type(opts).__name__}")
        put(self, "update_options", MappingProxyType({k: _frozen(v) for k, v in opts.items()}))
        for name in ("gain", "bandwidth", "id_rms", "id_psd"):
            put(self, name, _frozen(getattr(self, name)))
        self._check()

    def _check(self) -> None:
        it = self.iterations
        if not isinstance(it, (int, np.integer)) or isinstance(it, bool) or not 0 <= it <= MAX_ITERATIONS:
            raise ValueError(
                f"iterations must be an integer in 0..{MAX_ITERATIONS} (records are named IT00 to "
                f"IT{MAX_ITERATIONS}), got {it!r}"
            )
        if self.strategy not in STRATEGIES:
            raise ValueError(f"strategy must be 'fixed' or 'adaptive', got {self.strategy!r}")
        if not (isinstance(self.divergence, (int, float, np.number)) and self.divergence >= 1):
            raise ValueError(
                f"divergence must be a factor >= 1 (np.inf: never stop on divergence), got "
                f"{self.divergence!r}"
            )
        if not (isinstance(self.min_increase, (int, float, np.number)) and self.min_increase >= 0):
            raise ValueError(
                f"min_increase must be >= 0 percentage points, got {self.min_increase!r}"
            )
        tol = self.tolerance
        if tol is not None and not (
            isinstance(tol, (int, float, np.number)) and not isinstance(tol, bool)
            and np.isfinite(tol) and tol > 0
        ):
            raise ValueError(
                f"tolerance must be a finite η0 > 0 [%] (or None: no tolerance stop), got {tol!r}"
            )
        if self.gain is not None:
            self._check_gain()
        d = self.decimation
        if d is not None and (not isinstance(d, (int, np.integer)) or isinstance(d, bool) or d < 1):
            raise ValueError(f"decimation must be a positive integer, got {d!r}")
        if not (isinstance(self.taper, (int, float, np.number)) and np.isfinite(self.taper)
                and self.taper >= 0):
            raise ValueError(f"taper must be a non-negative duration [s], got {self.taper!r}")
        dur = self.id_duration
        if dur is not None and not (np.isfinite(dur) and dur > 0):
            raise ValueError(
                f"id_duration must be a finite number of seconds > 0 (or None: the desired "
                f"record's length), got {dur!r}"
            )
        if not isinstance(self.id_match, (bool, np.bool_)):
            raise ValueError(f"id_match must be True or False, got {self.id_match!r}")
        if self.id_match and self.id_psd is not None:
            raise ValueError(
                "id_match shapes the identification drive's PSD from the desired response: "
                "give id_psd or id_match=True, not both"
            )
        _check_seed(self.id_seed, "id_seed")
        if self.run_seed is not None:
            _check_seed(self.run_seed, "run_seed")
        self._check_update()

    def _check_gain(self) -> None:
        try:
            gain = np.asarray(self.gain)
            if gain.dtype.kind == "c":  # never drop an imaginary part silently
                raise TypeError
            gain = gain.astype(float)
        except (TypeError, ValueError):
            raise ValueError(
                f"gain must be a real number or one per drive channel, got {self.gain!r}"
            ) from None
        if gain.ndim > 1 or np.any(~np.isfinite(gain)) or np.any(gain <= 0) or np.any(gain > 2):
            raise ValueError(f"gain must lie in (0, 2], got {gain}")

    def _check_update(self) -> None:
        """``update`` one of :data:`UPDATES`, its options known and in range."""
        from .updates import check_update_options  # the rules own their options

        if not isinstance(self.update, str) or self.update not in UPDATES:
            raise ValueError(f"update must be one of {', '.join(UPDATES)}, got {self.update!r}")
        if self.update != "none" and self.strategy == "adaptive":
            raise ValueError(
                f"update={self.update!r} and strategy='adaptive' both re-fit the correction "
                "model from the iteration's data: choose one (strategy='fixed' with an update)"
            )
        check_update_options(self.update, self.update_options)

    # ------------------------------------------------------------------ construction
    @classmethod
    def field_names(cls) -> tuple[str, ...]:
        """The names of the settings (the dataclass fields)."""
        return tuple(f.name for f in dataclasses.fields(cls))

    @classmethod
    def build(cls, settings: IterationSettings | None = None, **options) -> IterationSettings:
        """``settings`` (default: the defaults) with ``options`` applied on top.

        Parameters
        ----------
        settings : IterationSettings, optional
            The starting point.
        **options
            Settings by name; ``seed`` sets both ``id_seed`` and ``run_seed``; any other name is a
            method option (merged into ``method_options``), as in ``reconstruct(..., order=4)``.

        Returns
        -------
        IterationSettings
        """
        if settings is not None and not isinstance(settings, IterationSettings):
            raise TypeError(f"settings must be an IterationSettings, got {type(settings).__name__}")
        base = settings if settings is not None else cls()
        if not options:
            return base
        names = set(cls.field_names())
        changes = {k: v for k, v in options.items() if k in names}
        if "seed" in options:
            seed = _check_seed(options["seed"], "seed")
            changes["id_seed"], changes["run_seed"] = seed, seed
        extra = {k: v for k, v in options.items() if k not in names and k != "seed"}
        if extra:
            changes["method_options"] = {**changes.get("method_options", base.method_options), **extra}
        return dataclasses.replace(base, **changes)

    def replace(self, **changes) -> IterationSettings:
        """A copy with ``changes`` (setting names) applied; checked like a new object.

        Parameters
        ----------
        **changes
            New values of settings, by name.

        Returns
        -------
        IterationSettings
        """
        return dataclasses.replace(self, **changes)

    # ------------------------------------------------------------------ derived values
    @property
    def rig_run_seed(self) -> int:
        """The seed of the iteration runs: ``run_seed``, or ``id_seed`` when it is unset."""
        return int(self.id_seed if self.run_seed is None else self.run_seed)

    def gains_for(self, n_inputs: int) -> np.ndarray:
        """The gain per drive channel (``n_inputs`` values).

        Parameters
        ----------
        n_inputs : int
            Number of drive channels of the rig.

        Returns
        -------
        ndarray (n_inputs,)

        Raises
        ------
        ValueError
            ``gain`` is None: not resolved yet (:func:`vrig.reconstruction.defaults.resolve`).
        """
        if self.gain is None:
            raise ValueError("gain is not resolved: vrig.reconstruction.defaults.resolve first")
        return np.broadcast_to(np.asarray(self.gain, dtype=float), (n_inputs,)).copy()

    def identification_key(self) -> tuple:
        """What the identified model depends on (not the iteration's gain, strategy, taper, run
        seed or stopping rule): a hashable key for model caches. With ``id_match`` the model
        also depends on the desired response (its identification drive is matched to it): a
        cache must key on that too.

        Returns
        -------
        tuple
        """
        return (
            cache_key(self.method),
            cache_key(dict(self.method_options)),
            cache_key(self.bandwidth),
            self.id_duration,
            cache_key(self.id_rms),
            cache_key(self.id_psd),
            bool(self.id_match),
            self.decimation,
            self.id_seed,
        )


def cache_key(value):
    """A hashable, repr-stable version of a setting value for cache keys.

    Mappings become sorted tuples, sequences and arrays tuples, numbers and strings stay; any
    other object is compared by identity and kept alive by the key itself (so its ``id`` is never
    reused by another object while the key exists).

    Parameters
    ----------
    value : object
        A setting value.

    Returns
    -------
    hashable
    """
    if isinstance(value, Mapping):
        return tuple(sorted((k, cache_key(v)) for k, v in value.items()))
    if isinstance(value, (list, tuple, np.ndarray)):
        return tuple(cache_key(v) for v in np.asarray(value, dtype=object).ravel())
    if isinstance(value, (str, int, float, bool, type(None), np.generic)):
        return value
    return _Identity(value)


class _Identity:
    """An object compared by identity (a key holding it keeps it alive: its id is not reused)."""

    __slots__ = ("obj",)

    def __init__(self, obj):
        self.obj = obj

    def __hash__(self) -> int:
        return id(self.obj)

    def __eq__(self, other) -> bool:
        return isinstance(other, _Identity) and other.obj is self.obj

    def __repr__(self) -> str:
        return f"<{type(self.obj).__name__} at {id(self.obj):#x}>"
