"""The drive-iteration gymnasium environment: one step is one iteration of the drive.

See :class:`DriveIterationEnv` for the observation, action, reward and termination, and
``README.md`` (section *Gymnasium environments*) for a training example.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import ClassVar

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from ..errors import RigLimitError
from ..reconstruction import IterationSettings
from ..timehistory import TimeHistory
from .physics import FAILURES, IterationPhysics
from .task import IterationTask, band_edges, response_change_ratios

__all__ = [
    "FALLBACK_TOLERANCE",
    "FIELD_REDRAWS",
    "PHYSICS_OPTIONS",
    "ActionLayout",
    "DriveIterationEnv",
]

FALLBACK_TOLERANCE = 2.0
"""Default η0 tolerance [%, every channel] on a rig whose side-car names none
(``rig.defaults.tolerance``: the side-car's ``"reconstruction": {"gym": {"tolerance": ...}}``;
the rule by which those are measured: :mod:`vrig.envs`)."""

FIELD_REDRAWS = 4
"""How often ``reset`` redraws a target (pseudo-field or field) whose IT00 drive trips the rig
or exceeds its full scale (a drawn target only; an explicit ``desired``/``field_seed`` or a desired set
raises the :class:`vrig.RigLimitError`)."""

FAST_SECONDS = 4.0
"""Length of the desired segments of the ``fast`` option [s] (the default is 20 s; the
identification drive is longer, :data:`FAST_ID_SECONDS`)."""
FAST_ID_SECONDS = 12.0
"""Identification drive length of the ``fast`` option [s]: a 4 s record is too short for a
stable inverse on the elastomeric damper (the default is the desired segment length, 20 s)."""

_ACTION_MODES = ("bands", "channels", "scalar", "complex")


@dataclass(frozen=True)
class ActionLayout:
    """How the flat action vector maps to gains (and phases).

    ``mode`` ``"bands"``: ``n_inputs * n_bands`` gains, channel-major (``action[:n_gains]
    .reshape(n_inputs, n_bands)``); ``"channels"``: one gain per drive channel; ``"scalar"``: one
    gain; ``"complex"``: ``n_inputs * n_bands`` gain magnitudes then as many phases [rad], both
    channel-major (``action[:n_gains]`` and ``action[n_gains:2 * n_gains]``, each reshaped to
    ``(n_inputs, n_bands)``). With ``reidentify`` the last element (in [0, 1]) is the re-identify
    flag (>= 0.5: re-fit the inverse model from the latest drive and raw response before
    computing the update).

    Parameters
    ----------
    mode : {"bands", "channels", "scalar", "complex"}
        Gain resolution: per drive channel and band, per drive channel, one gain, or per drive
        channel and band a magnitude and a phase.
    n_inputs : int
        Number of drive channels of the rig.
    n_bands : int
        Number of gain bands (used by ``mode="bands"`` and ``"complex"``).
    reidentify : bool
        Whether the action ends with the re-identify flag.
    low, high : float
        Bounds of every gain magnitude (dimensionless; the flag's bounds are [0, 1] whatever these
        are).
    phase_max : float
        Bound of every phase, ``[-phase_max, phase_max]`` rad (``mode="complex"`` only; default
        pi/2).
    """

    mode: str
    n_inputs: int
    n_bands: int
    reidentify: bool
    low: float
    high: float
    phase_max: float = np.pi / 2

    @property
    def n_gains(self) -> int:
        """Number of gains (magnitudes) in the action (``n_inputs * n_bands``, ``n_inputs`` or
        1)."""
        per_band = self.n_inputs * self.n_bands
        return {"bands": per_band, "complex": per_band, "channels": self.n_inputs}.get(
            self.mode, 1
        )

    @property
    def n_phases(self) -> int:
        """Number of phases in the action (:attr:`n_gains` in ``"complex"`` mode, else 0)."""
        return self.n_gains if self.mode == "complex" else 0

    @property
    def size(self) -> int:
        """Length of the flat action: :attr:`n_gains` + :attr:`n_phases`, plus 1 for the
        re-identify flag."""
        return self.n_gains + self.n_phases + int(self.reidentify)

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """The action's bounds ``(low, high)``: gains ``[low, high]``, phases ``[-phase_max,
        phase_max]`` rad, the flag [0, 1]."""
        ng, nph = self.n_gains, self.n_phases
        low = np.r_[np.full(ng, self.low), np.full(nph, -self.phase_max)]
        high = np.r_[np.full(ng, self.high), np.full(nph, self.phase_max)]
        if self.reidentify:
            low, high = np.r_[low, 0.0], np.r_[high, 1.0]
        return low, high

    def _shaped(self, values, what: str) -> np.ndarray:
        """``values`` broadcast to the mode's shape and flattened channel-major."""
        v = np.asarray(values, dtype=float)
        per_band = self.mode in ("bands", "complex")
        shape = (self.n_inputs, self.n_bands) if per_band else (self.n_inputs,)
        if self.mode == "scalar":
            shape = (1,)
        if per_band and v.ndim == 1 and v.size == self.n_inputs != self.n_bands:
            v = v[:, None]
        try:
            return np.broadcast_to(v, shape).ravel()
        except ValueError:
            raise ValueError(f"{what} of shape {v.shape} do not fit the {shape} of "
                             f"action_mode={self.mode!r}") from None

    def action(self, gains, phases=None, reidentify: bool = False) -> np.ndarray:
        """A flat action from gains (scalar, per channel or (channels, bands), broadcast to the
        mode's shape), phases (``"complex"`` mode) and the re-identify flag.

        Parameters
        ----------
        gains : float or array_like
            Gains (dimensionless; magnitudes in ``"complex"`` mode): a scalar, one per drive
            channel (``(n_inputs,)``, repeated over the bands in ``"bands"``/``"complex"``
            mode) or ``(n_inputs, n_bands)``; broadcast to the mode's shape. Not clipped to
            ``[low, high]`` here (the env clips).
        phases : float or array_like, optional
            ``"complex"`` mode only: phases [rad] (> 0: phase lead), shaped like ``gains``
            (default 0: the ``"bands"`` update). Not clipped here.
        reidentify : bool
            The re-identify flag (1.0 when true, else 0.0); ignored unless the layout has one.

        Returns
        -------
        ndarray
            The flat float64 action of length :attr:`size`.
        """
        if isinstance(phases, (bool, np.bool_)):
            raise TypeError(
                "phases must be numbers: pass the re-identify flag by keyword, "
                "action(gains, reidentify=...)"
            )
        if phases is not None and self.mode != "complex":
            raise ValueError(f"phases need action_mode='complex' (this layout: {self.mode!r})")
        flat = self._shaped(gains, "gains")
        if self.mode == "complex":
            flat = np.r_[flat, self._shaped(0.0 if phases is None else phases, "phases")]
        if self.reidentify:
            flat = np.concatenate([flat, [1.0 if reidentify else 0.0]])
        return flat.astype(np.float64)


def _check_env_options(render_mode, action_mode, max_iterations, gain_range, phase_max):
    """The options checked before the rig is built; returns the gain range ``(low, high)``."""
    if render_mode is not None:
        raise ValueError("DriveIterationEnv does not render (render_mode must be None)")
    if max_iterations is not None:
        raise TypeError(
            "max_iterations was removed in v1: the iteration budget is TimeLimit's, "
            "gymnasium.make(..., max_episode_steps=n) (default 10), or wrap the env in "
            "gymnasium.wrappers.TimeLimit(env, n)"
        )
    if action_mode not in _ACTION_MODES:
        raise ValueError(f"action_mode must be one of {_ACTION_MODES}, got {action_mode!r}")
    lo, hi = (float(g) for g in gain_range)
    if not (np.isfinite(lo) and np.isfinite(hi) and 0 <= lo < hi):
        raise ValueError(f"gain_range must satisfy 0 <= low < high, got {gain_range}")
    if isinstance(phase_max, bool) or not (
        isinstance(phase_max, (int, float, np.number)) and 0 < phase_max <= np.pi
    ):
        raise ValueError(f"phase_max must be a number in (0, pi] rad, got {phase_max!r}")
    return lo, hi


_RESET_OPTIONS = ("desired", "field_seed", "run_seed")


def _check_reset_options(options) -> dict:
    """The reset ``options`` as a dict, checked: only :data:`_RESET_OPTIONS`, the seeds
    integers >= 0 (``1.5`` is not the seed 1)."""
    if options is not None and not isinstance(options, Mapping):
        raise TypeError(f"options must be a dict or None, got {type(options).__name__}")
    options = dict(options or {})
    unknown = set(options) - set(_RESET_OPTIONS)
    if unknown:
        raise ValueError(
            f"unknown reset option(s) {sorted(unknown)}; use desired, field_seed, run_seed"
        )
    for key in ("field_seed", "run_seed"):
        if key in options:
            value = options[key]
            if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 0:
                raise ValueError(f"reset option {key} must be an integer >= 0, got {value!r}")
            options[key] = int(value)
    return options


def _tolerance(rig, tolerance) -> float:
    """The η0 tolerance [%]: ``tolerance``, else the rig's side-car one, else the fallback."""
    if tolerance is None:
        tolerance = getattr(getattr(rig, "defaults", None), "tolerance", None)
        tolerance = FALLBACK_TOLERANCE if tolerance is None else tolerance
    if not (np.isfinite(tolerance) and tolerance > 0):
        raise ValueError(f"tolerance must be a positive number [%], got {tolerance!r}")
    return float(tolerance)


PHYSICS_OPTIONS = frozenset(
    {"settings", "method", "method_options", "fast", "fidelity", "seconds", "bandwidth",
     "model_seed", "id_duration", "id_rms", "decimation", "rig_seed", "rig_options", "target"}
)  # fmt: skip
"""The :class:`DriveIterationEnv` arguments that build its :class:`IterationPhysics` (the rest are
the task's and the action's): left unset when the env is given an ``IterationPhysics``."""


def _check_shared_physics(given: dict, **options) -> None:
    """No physics-building argument next to a given :class:`IterationPhysics` (they are its own)."""
    defaults = {"fast": False, "rig_seed": 0, "target": "pseudo-field"}
    named = [k.replace("id_seed", "model_seed") for k, v in given.items() if v is not None]
    named += [k for k, v in options.items() if v is not None and v != defaults.get(k, None)]
    if named:
        raise ValueError(
            f"{sorted(named)} cannot be given with an IterationPhysics: they are the physics' own"
        )


def _physics(rig, given: dict, settings, *, fast, fidelity, seconds, rig_seed, rig_options,
             target):  # fmt: skip
    """The env's :class:`IterationPhysics`: ``rig`` itself when it is one (shared, see
    :func:`_check_shared_physics`), else built from the rig and the settings."""
    if isinstance(rig, IterationPhysics):  # shared (a batched vector env's sub-envs)
        _check_shared_physics(
            given, settings=settings, fast=fast, fidelity=fidelity, seconds=seconds,
            rig_seed=rig_seed, rig_options=rig_options, target=target,
        )  # fmt: skip
        return rig
    settings = IterationSettings.build(settings, **{k: v for k, v in given.items() if v is not None})
    if fast and settings.id_duration is None:
        settings = settings.replace(id_duration=FAST_ID_SECONDS)
    return IterationPhysics(
        rig,
        settings,
        seconds=seconds if seconds is not None else (FAST_SECONDS if fast else 20.0),
        fidelity=fidelity or ("fast" if fast else "full"),
        rig_seed=rig_seed,
        rig_options=rig_options,
        target=target,
    )


class DriveIterationEnv(gym.Env):
    """Drive iteration (response reconstruction) on a virtual rig as a gymnasium environment.

    **Episode.** ``reset(seed)`` draws a desired response - a record of the env's ``target``
    (default a pseudo-field record: the rig's response to a seeded road-like drive; or a service
    record of the rig's specimen in its vehicle on a seeded road), one of the supplied
    ``desired`` records, or ``options["desired"]`` - builds the engine with the inverse model (identified once with
    ``model_seed`` and cached), computes IT00DRV = inverse(DESRES) and plays it. Each ``step``
    is one iteration: ``ITn+1DRV = ITnDRV + gains x (inverse(DESRES) - inverse(ITnRES))`` with
    the action's gains (per drive channel and frequency band; complex per band in ``"complex"``
    mode), then plays it. (An IT00 drive beyond the limits makes ``reset`` raise
    :class:`~vrig.RigLimitError`: there is no drive to fall back on; pseudo-field targets of the
    registered rigs never do.)

    **Observation** (``Dict`` of float32 boxes, clipped to their bounds):

    * ``band_error`` (outputs, bands): log10 of the band RMS of (DESRES - ITnRES) over the band
      RMS of DESRES, bands ``self.edges`` (log-spaced over the simulation band), in [-6, 3];
    * ``band_error_change`` (outputs, bands): ``band_error`` now minus at the previous
      iteration (0 at IT00), in [-3, 3] (> 0: the band's error grew);
    * ``change_ratio``, ``change_phase`` (outputs, bands): log10 magnitude, in [-3, 3], and
      phase [rad], in [-pi, pi], of the realised / predicted response-change ratio of the last
      iteration (v2; :func:`~vrig.envs.task.response_change_ratios`): per band the
      least-squares complex factor ``rho`` with ``ITnRES - ITn-1RES ~ rho * g_b * (DESRES -
      ITn-1RES)``, ``g_b`` the band's gain of the last action (mean over drive channels,
      complex in ``"complex"`` mode). 0 and 0 (``rho = 1``: the model predicted the change) at
      IT00, after a failed step, and in a band with no predicted change (gain 0 or no error);
      ``rho < 1``: the response moved less than the correction aimed at. What a secant / model
      update uses, so a policy can learn an update rule;
    * ``eta0``, ``rms_error`` (outputs,): η0 (eq. 5-28) and RMS error [%], in [0, 1000];
    * ``drive_rms``, ``drive_peak`` (inputs,): of ITnDRV, as fractions of the full scale;
    * ``iteration`` (1,): n, in [0, 99] (:data:`~vrig.envs.task.ITERATION_MAX`: the records are
      named IT00..IT99; a longer episode observes 99 from then on).

    **Action** (``Box`` float64, flat; see :class:`ActionLayout`): gains in ``[gain_low,
    gain_high]`` (default [0, 2]) per drive channel x band (``action_mode="bands"``), per
    channel (``"channels"``) or one (``"scalar"``); or (``"complex"``) per drive channel x band
    a gain magnitude in ``gain_range`` and a phase in ``[-phase_max, phase_max]`` rad (default
    pi/2): the flat action is the magnitudes, then the phases (both channel-major), and the
    band's correction is multiplied by ``g * exp(1j * phi)`` in the frequency domain
    (:func:`vrig.processing.band_gains`: ``phi > 0`` a phase lead, ``phi < 0`` a delay; phases 0
    are the ``"bands"`` update bit for bit). Any mode may end with the re-identify flag
    (``reidentify_action=True``). Values out of bounds are clipped (``info["action_clipped"]``);
    a wrong shape or a non-finite value raises ``ValueError``, a complex (or other non-real)
    action ``TypeError`` (its imaginary part is never dropped: a phase is ``"complex"`` mode's).

    **Spaces by rig size** (default ``n_bands=4``; ``n_inputs x n_outputs``; the flat
    observation is ``gymnasium.wrappers.FlattenObservation``'s length,
    ``4 * n_outputs * n_bands + 2 * n_outputs + 2 * n_inputs + 1``; the action lengths are
    without the re-identify flag, +1 with it; ``"scalar"`` is always 1):

    | inputs x outputs: rigs                  | band_error | flat obs | bands | channels | complex |
    |-----------------------------------------|------------|----------|-------|----------|---------|
    | 1 x 1: shock absorber, damper, shaker   | (1, 4)     | 21       | 4     | 1        | 8       |
    | 1 x 2: radiator, motorcycle rear        | (2, 4)     | 39       | 4     | 1        | 8       |
    | 1 x 3: pneumatic trailer                | (3, 4)     | 57       | 4     | 1        | 8       |
    | 2 x 2: fuel tank 2ch                    | (2, 4)     | 41       | 8     | 2        | 16      |
    | 6 x 10: light-truck front               | (10, 4)    | 193      | 24    | 6        | 48      |
    | 7 x 7: fuel tank 7ch                    | (7, 4)     | 141      | 28    | 7        | 56      |

    In general ``band_error`` / ``band_error_change`` / ``change_ratio`` / ``change_phase`` are
    ``(n_outputs, n_bands)``, ``eta0`` /
    ``rms_error`` ``(n_outputs,)``, ``drive_rms`` / ``drive_peak`` ``(n_inputs,)``; the action
    is ``n_inputs * n_bands`` (``"bands"``), ``n_inputs`` (``"channels"``), 1 (``"scalar"``) or
    ``2 * n_inputs * n_bands`` (``"complex"``) long.

    **Reward**: ``ln(mean η0 before) - ln(mean η0 after) - energy_penalty * max(0, ln(drive
    energy growth)) - step_penalty``, plus ``success_bonus`` (default 1) on the step that meets
    the tolerance (v2: the return pays for reaching it, which the iterations-to-tolerance
    benchmark counts; with a discount < 1 or a ``step_penalty`` > 0 it pays more the sooner);
    a drive beyond the limits (never sent), a rig trip or a
    non-finite drive gives ``-trip_penalty`` and terminates (``info["reason"] == "limit"``; a
    diverging inverse-model free run or an unstable simulation: ``"unstable"``).

    **Termination** when every channel's η0 <= ``tolerance`` (``info["reason"] ==
    "tolerance"``). **Truncation** is not the env's: it never truncates (``truncated`` is always
    False); the iteration budget is the ``TimeLimit`` wrapper's (``gymnasium.make(...,
    max_episode_steps=n)``, default 10 for the registered ids, or a ``TimeLimit`` you add), as
    Gymnasium's convention is. :func:`vrig.policies.run_episode` reports a truncated episode
    with reason ``"budget"``. ``info`` carries the raw errors (``eta0``, ``rms_error``,
    ``damage_ratio``, ``mean_eta0``), the ``iteration``, ``success``, ``reason``, ``field_seed``,
    ``run_seed`` and any ``trip`` message.

    **Targets** (``target``, :func:`vrig.desired.kinds.desired_response`): ``"pseudo-field"``
    (default), ``"field:<scenario>"`` (one of the rig's service scenarios,
    :func:`vrig.service.field_scenarios`) or ``"field"`` (its first). A field target's reset draws a new road: the field seed is the
    seed of the road profile (:func:`vrig.service.field_record`); the vehicle speed and the ISO
    8608 road class stay the scenario's defaults (its side-car ``"service"`` block), so episodes
    differ by their road, not by how it is driven. A service record is not reachable by
    construction (the rig lacks the vehicle's boundary conditions), so the tolerance may not be
    met. The env's target is ``self.physics.target`` (resolved: ``"field"`` alone names its
    scenario).

    **Randomness**: only ``reset(seed=...)`` / ``self.np_random``: each reset draws the field
    seed (of the pseudo-field drive or of the road, or the index into ``desired``) and the run
    seed (rig noise of the iteration runs: ``run_seed + 1 + n``); a drawn target whose IT00
    drive trips the rig or exceeds its full scale (the linear inverse overshoots a hardening rig: on the
    calibrated elastomeric damper about 1 target in 24) is redrawn from ``self.np_random`` up to
    :data:`FIELD_REDRAWS` times (``info["field_seed"]`` is the one played). ``options`` may fix
    ``"desired"`` (a TimeHistory or file), ``"field_seed"``, ``"run_seed"``: with
    ``model_seed=s`` and ``options={"desired": d, "run_seed": s}`` a fixed gain g reproduces
    ``vrig.reconstruct(rig, d, gain=g, seed=s)``.

    **Split steps for batched rig runs.** ``step(action)`` is ``finish_step(play(
    *prepare_step(action)))`` and ``reset`` is ``prepare_reset`` then ``finish_reset`` (again
    while it returns None), where *play* plays ``(drive, iteration)`` on ``self.engine``
    (``self.engine.play(drive, iteration)``) and gives its ``(drive, raw, processed, scores)``
    tuple or the exception it raised. A vector env prepares N envs, plays their drives in one
    batched rig call, then finishes each: the results are those of N ``step`` calls. The
    contract (per env, in this order; anything else is a ``RuntimeError``):

    1. ``drive, n = env.prepare_step(action)`` (or ``env.prepare_reset(seed=..., options=...)``);
       ``drive is None`` means the update itself failed (a diverging free run): nothing to
       play, pass ``None`` on;
    2. play ``drive`` as iteration ``n`` on ``env.engine``; the outcome is the play tuple, or
       the exception the play raised (:data:`~vrig.envs.physics.FAILURES` end the episode with
       the trip penalty; any other exception is re-raised by the finish, which ends the
       episode);
    3. ``env.finish_step(outcome)`` -> ``(obs, reward, terminated, truncated, info)``, or
       ``env.finish_reset(outcome)`` -> ``(obs, info)``, or None when the drawn target tripped
       at IT00 and another was drawn: play ``env.pending`` (its IT00 drive) and finish again.

    ``prepare_reset`` is itself ``draw_reset`` (seed, draw the field and run seeds; it returns
    the seed of the target record the reset needs) then ``start_reset``: a vector env draws
    every resetting sub-env, makes their records in one batch
    (:meth:`~vrig.envs.IterationPhysics.target_records`), then starts each.

    The split methods are the unwrapped env's: a vector env calling them applies the step budget
    itself (as ``TimeLimit`` would) and the passive checker is not in the way.

    **Version History**

    * v2 (issue 26): the observation gains ``change_ratio`` and ``change_phase`` (the realised /
      predicted response-change ratio per output and band; the flat observation grows by
      ``2 * n_outputs * n_bands``), the reward the ``success_bonus`` term (default 1, paid on
      the step that meets the tolerance). Drives, responses, errors and terminations are v1's:
      fixed-gain episodes are identical in their records; only the rewards of a successful step
      and the observation differ. The registered ids are ``-v2``; ``gymnasium.make`` of a ``-v1``
      (or ``-v0``) id raises gymnasium's ``DeprecatedEnv`` naming the ``-v2`` one.
    * v1 (issue 16): ``TimeLimit`` alone owns truncation (the env never truncates;
      ``max_iterations`` removed: a ``TypeError`` says to use ``max_episode_steps``; the
      ``iteration`` observation is bounded by 99 instead of the budget; ``info["reason"]`` is
      never ``"budget"`` from the env); the ``"complex"`` action mode (per band a gain
      magnitude and a phase, ``phase_max``); ids for every rig; the step split
      (``prepare_step`` / ``finish_step``, ``prepare_reset`` / ``finish_reset``) for batched
      rig runs. Fixed-gain episodes of v0 and v1 are identical step for step.
    * v0 (issue 5): initial: gains per channel x band, per channel or one, optional re-identify
      flag; the env truncated itself at ``max_iterations`` (and ``make`` also wrapped it in
      ``TimeLimit(max_episode_steps=10)``); ids for the SISO rigs with a side-car gym id.

    Parameters
    ----------
    rig : str, Rig or IterationPhysics
        Rig name (``vrig.list_rigs()``) or rig object; or an :class:`IterationPhysics` to share
        (its rig, identification settings and cached inverse model: the sub-envs of
        :class:`~vrig.envs.DriveIterationVectorEnv`), with none of :data:`PHYSICS_OPTIONS` given
        (a ``ValueError`` otherwise).
    settings : IterationSettings, optional
        The identification settings (method and options, band, identification drive, taper,
        ``id_seed``, ...); the keyword arguments below, when given, override its values. The
        iteration's gains come from the actions and the run seed from ``reset``.
    method : str, optional
        Inverse-model method (default ``"arx"``).
    method_options : dict, optional
        Options of the method, e.g. ``{"order": 4}``.
    fast : bool
        Reduced-fidelity rig (``fidelity="fast"``), :data:`FAST_SECONDS` (4 s) desired segments
        and a :data:`FAST_ID_SECONDS` (12 s) identification drive instead of the full-fidelity
        rig and 20 s for both (overridden by explicit ``fidelity`` / ``seconds`` /
        ``id_duration``).
    fidelity : {"full", "fast"}, optional
        Rig fidelity of a named rig (default: ``"fast"`` with ``fast=True``, else ``"full"``).
    seconds : float, optional
        Length of the drawn desired responses [s] (pseudo-field or field) and, unless ``id_duration`` (or
        ``fast``) sets it, of the identification drive (default 20 s, 4 s with ``fast``).
    desired : sequence of TimeHistory or paths, optional
        Desired responses to draw from instead of ``target``'s records (RPC III, CSV, MAT, NPZ
        files are read with :func:`vrig.io.read`); not with a ``target`` other than
        ``"pseudo-field"`` (a ``ValueError``).
    n_bands : int
        Number of observation / gain bands (default 4), log-spaced over the simulation band.
    action_mode : {"bands", "channels", "scalar", "complex"}
        Gains per drive channel and band (default), per drive channel, one gain, or per drive
        channel and band a gain magnitude and a phase (:class:`ActionLayout`).
    reidentify_action : bool
        Append the re-identify flag to the action (default False).
    gain_range : (float, float)
        Bounds ``(low, high)`` of every gain (magnitude), ``0 <= low < high`` (default (0, 2)).
    phase_max : float
        Bound of every phase in ``"complex"`` mode, ``[-phase_max, phase_max]`` rad,
        ``0 < phase_max <= pi`` (default pi/2; ignored by the other modes).
    max_iterations : None
        Removed in v1 (the budget is ``TimeLimit``'s: ``gymnasium.make(...,
        max_episode_steps=n)``); any value raises ``TypeError``.
    tolerance : float, optional
        η0 tolerance [%] (default: the rig's side-car tolerance ``rig.defaults.tolerance``,
        else :data:`FALLBACK_TOLERANCE`, 2 %; the rule: :mod:`vrig.envs`).
    trip_penalty : float
        Reward of a step whose drive was refused, tripped the rig or went unstable (the
        episode terminates), negated: the reward is ``-trip_penalty`` (default 5, >= 0).
    energy_penalty : float
        Weight of the drive-energy growth ``max(0, ln(E_after / E_before))`` in the reward,
        ``E = sum_channels (drive RMS / full scale)^2`` (default 0.1, >= 0).
    step_penalty : float
        Constant subtracted from every step's reward (default 0, >= 0).
    success_bonus : float
        Added to the reward of the step that meets the tolerance (every channel's η0 <=
        ``tolerance``; the episode terminates there; default 1, >= 0): the return then pays for
        reaching the tolerance, as the benchmark's iterations to tolerance count (see
        **Reward**).
    model_seed : int, optional
        Identification seed (``settings.id_seed``, default 0; fixed per env, so the identified
        model is reused).
    bandwidth, id_duration, id_rms, decimation
        As in :func:`vrig.reconstruct`.
    rig_seed : int
        Seed of a named rig (its noise realisation; default 0).
    rig_options : dict, optional
        Further ``load_rig`` options of a named rig (``variant``, ``severity``, documented
        parameters).
    target : str
        What each reset draws (see **Targets**): ``"pseudo-field"`` (default),
        ``"field:<scenario>"`` or ``"field"``; checked when the env is made
        (:func:`vrig.desired.kinds.parse_target`: an unknown scenario is a ``ValueError`` listing the
        rig's scenarios, a rig without any is one too).
    render_mode : None
        Must be ``None``: the environment does not render (``metadata["render_modes"]`` is
        empty).
    """

    metadata: ClassVar[dict] = {"render_modes": []}

    def __init__(
        self,
        rig="shock-absorber",
        *,
        settings: IterationSettings | None = None,
        method: str | None = None,
        method_options: dict | None = None,
        fast: bool = False,
        fidelity: str | None = None,
        seconds: float | None = None,
        desired=None,
        bandwidth: tuple[float, float] | None = None,
        n_bands: int = 4,
        action_mode: str = "bands",
        reidentify_action: bool = False,
        gain_range: tuple[float, float] = (0.0, 2.0),
        phase_max: float = np.pi / 2,
        max_iterations: None = None,
        tolerance: float | None = None,
        trip_penalty: float = 5.0,
        energy_penalty: float = 0.1,
        step_penalty: float = 0.0,
        success_bonus: float = 1.0,
        model_seed: int | None = None,
        id_duration: float | None = None,
        id_rms=None,
        decimation: int | None = None,
        rig_seed: int = 0,
        rig_options: dict | None = None,
        target: str = "pseudo-field",
        render_mode: str | None = None,
    ):
        lo, hi = _check_env_options(
            render_mode, action_mode, max_iterations, gain_range, phase_max
        )
        self.render_mode = None
        given = {
            "method": method,
            "method_options": method_options,
            "bandwidth": bandwidth,
            "id_duration": id_duration,
            "id_rms": id_rms,
            "decimation": decimation,
            "id_seed": model_seed,
        }
        if desired is not None and target != "pseudo-field":
            raise ValueError(f"give desired or target={target!r}, not both (desired wins over it)")
        self.physics = _physics(
            rig, given, settings, fast=fast, fidelity=fidelity, seconds=seconds,
            rig_seed=rig_seed, rig_options=rig_options, target=target,
        )  # fmt: skip
        ph = self.physics
        self.edges = band_edges(ph.band, n_bands)
        self.task = IterationTask(
            edges=self.edges,
            tolerance=_tolerance(ph.rig, tolerance),
            trip_penalty=trip_penalty,
            energy_penalty=energy_penalty,
            step_penalty=step_penalty,
            success_bonus=success_bonus,
        )
        self.layout = ActionLayout(
            action_mode, ph.n_inputs, n_bands, bool(reidentify_action), lo, hi, float(phase_max)
        )
        self.action_space = spaces.Box(*self.layout.bounds(), dtype=np.float64)
        self.observation_space = self.task.observation_space(ph.n_inputs, ph.n_outputs)
        self.desired_set = None if desired is None else [self._load(d) for d in desired]
        if self.desired_set is not None and not self.desired_set:
            raise ValueError("desired must hold at least one record")
        self.engine = None
        self.change_ratio = None
        self._pending = None
        self._done = True

    # ------------------------------------------------------------------ helpers
    def _load(self, item) -> TimeHistory:
        if isinstance(item, (str, Path)):
            from ..io import read

            item = read(item)
        if not isinstance(item, TimeHistory):
            raise TypeError(f"a desired response must be a TimeHistory or a file, got {item!r}")
        ph = self.physics
        if abs(item.fs - ph.fs) > 1e-6 * ph.fs or item.n_channels != ph.n_outputs:
            raise ValueError(
                f"a desired response must be {ph.n_outputs} channel(s) at {ph.fs:g} Hz, got "
                f"{item.n_channels} at {item.fs:g} Hz"
            )
        return TimeHistory(item.data, ph.fs, item.names, item.units)

    def _gains(self, action):
        """The checked action: (gains, re-identify flag, whether a value was clipped); gains are
        real (n_inputs, n_bands) / (n_inputs,) / (1,), or complex (n_inputs, n_bands) in
        ``"complex"`` mode when a phase is not 0 (all phases 0: the real magnitudes)."""
        a = np.asarray(action)
        if a.dtype.kind not in "biuf":  # complex (its imaginary part), object, str...
            raise TypeError(
                f"action must be real numbers, got dtype {a.dtype}"
                + (" (a complex gain is a magnitude and a phase: action_mode='complex')"
                   if a.dtype.kind == "c" else "")
            )  # fmt: skip
        a = a.astype(float)
        lay = self.layout
        if a.shape == () and lay.size == 1:
            a = a.reshape(1)
        if a.shape != (lay.size,):
            raise ValueError(
                f"action must have shape ({lay.size},) ({lay.mode} gains"
                + (" and phases" if lay.n_phases else "")
                + (" + re-identify flag" if lay.reidentify else "")
                + f"), got {a.shape}"
            )
        if not np.all(np.isfinite(a)):
            raise ValueError(f"action must be finite, got {a}")
        clipped = np.clip(a, self.action_space.low, self.action_space.high)
        was_clipped = bool(np.any(clipped != a))
        g = clipped[: lay.n_gains]
        reid = bool(lay.reidentify and clipped[-1] >= 0.5)
        if lay.mode in ("bands", "complex"):
            g = g.reshape(lay.n_inputs, lay.n_bands)
        if lay.n_phases:
            phi = clipped[lay.n_gains : lay.n_gains + lay.n_phases].reshape(g.shape)
            if np.any(phi):
                g = g * np.exp(1j * phi)
        return g, reid, was_clipped

    def _info(self, scores, *, reason: str = "", trip: str = "", clipped: bool = False) -> dict:
        eta0, rms, dmg = scores
        return {
            "eta0": np.array(eta0, dtype=float),
            "rms_error": np.array(rms, dtype=float),
            "damage_ratio": np.array(dmg, dtype=float),
            "mean_eta0": float(np.mean(eta0)),
            "iteration": int(self.iteration),
            "success": self.task.success(eta0),
            "reason": reason,
            "trip": trip,
            "action_clipped": clipped,
            "field_seed": int(self.field_seed),
            "run_seed": int(self.run_seed),
        }

    def _observe(self, previous) -> dict:
        return self.task.observe(
            log_band_error=self.log_band_error,
            previous_log_band_error=previous,
            eta0=self.scores[0],
            rms_error=self.scores[1],
            drive=self.drive,
            full_scale=self.physics.drive_full_scale,
            iteration=self.iteration,
            change_ratio=self.change_ratio,
        )

    def _play(self, drive, iteration: int):
        """The outcome of playing ``drive`` on this env's engine: the play tuple, or the
        :data:`~vrig.envs.physics.FAILURES` exception it raised (others propagate)."""
        try:
            return self.engine.play(drive, iteration)
        except FAILURES as exc:
            return exc

    def _take_pending(self, kind: str) -> dict:
        pending = self._pending
        if pending is None or pending["kind"] != kind:
            raise RuntimeError(f"finish_{kind} without a pending prepare_{kind}")
        self._pending = None
        return pending

    @property
    def pending(self):
        """The prepared play ``(drive, iteration)`` waiting for its finish (``drive`` None: the
        update failed, nothing to play), or None when nothing is pending."""
        if self._pending is None or self._pending["kind"] == "draw":
            return None
        return self._pending["drive"], self.iteration

    # ------------------------------------------------------------------ API
    def reset(self, *, seed: int | None = None, options: dict | None = None):
        """Start an episode: draw a desired response, compute IT00DRV and play it.

        As :meth:`gymnasium.Env.reset` (``prepare_reset``, play, ``finish_reset`` until it
        returns the observation). A reset that raises leaves the env as before any reset: no
        episode, no engine (``step`` raises ``RuntimeError`` until a reset succeeds), and the next
        reset works as on a new env (with ``gymnasium.make``'s checker too:
        :mod:`vrig.envs.checker`). Reset options are checked before anything changes.

        Parameters
        ----------
        seed : int, optional
            Seeds ``self.np_random`` (Gymnasium's rule: once, then leave it ``None``); the
            field seed (of the target's record, or the index into ``desired``) and the run seed
            are drawn from it.
        options : dict, optional
            ``"desired"``: the desired response of this episode (a TimeHistory or a file, one
            column per rig output at the rig's fs); ``"field_seed"``: the seed of the target's
            record (pseudo-field drive or road; or the index, modulo its length, into the env's
            ``desired`` set); ``"run_seed"``: the run seed (rig noise of the iteration runs:
            ``run_seed + 1 + n``). The seeds are integers >= 0 (``1.5`` is a ``ValueError``, not
            the seed 1). Any other key is a ``ValueError``.

        Returns
        -------
        observation : dict
            The observation of IT00 (see the class docstring).
        info : dict
            ``eta0``, ``rms_error`` [%] and ``damage_ratio`` (per output), ``mean_eta0`` [%],
            ``iteration`` (0), ``success``, ``reason`` (``""``), ``trip`` (``""``),
            ``action_clipped`` (False), ``field_seed`` (the one played, after any redraw) and
            ``run_seed``.

        Raises
        ------
        RigLimitError
            The IT00 drive of an explicit ``desired``/``field_seed``, of the ``desired`` set or
            of the last of :data:`FIELD_REDRAWS` redrawn targets exceeds a limit.
        ValueError
            An unknown option, or a seed that is not an integer >= 0.
        """
        drive, n = self.prepare_reset(seed=seed, options=options)
        while True:
            try:
                done = self.finish_reset(self._play(drive, n))
            except BaseException:
                self._abandon()
                raise
            if done is not None:
                return done
            drive, n = self.pending

    def prepare_reset(self, *, seed: int | None = None, options: dict | None = None):
        """First half of :meth:`reset`: seed, draw the target, start the engine and compute its
        IT00 drive (see the class docstring for the split contract).

        Parameters
        ----------
        seed : int, optional
            As :meth:`reset`'s.
        options : dict, optional
            As :meth:`reset`'s.

        Returns
        -------
        (drive, iteration) : (ndarray (n, n_inputs), int)
            IT00DRV and 0: play it on ``self.engine`` and pass the outcome to
            :meth:`finish_reset`.
        """
        self.draw_reset(seed=seed, options=options)
        return self.start_reset()

    def draw_reset(self, *, seed: int | None = None, options: dict | None = None):
        """First part of :meth:`prepare_reset`: check the options, seed, draw the field and run
        seeds; :meth:`start_reset` then starts the target. A vector env draws every resetting
        sub-env first, makes their target records in one batch
        (:meth:`~vrig.envs.IterationPhysics.target_records`), then starts each.

        Parameters
        ----------
        seed : int, optional
            As :meth:`reset`'s.
        options : dict, optional
            As :meth:`reset`'s.

        Returns
        -------
        int or None
            The seed of the target record the reset starts on
            (:meth:`~vrig.envs.IterationPhysics.target_record`), or None when it plays a given
            ``desired`` or one of the env's ``desired`` set.
        """
        # the episode is over until this reset succeeds: a reset that raises leaves no episode
        # for ``step`` to continue (it would mix the old drive with the new target)
        self._abandon()
        options = _check_reset_options(options)  # a refused reset changes nothing else
        super().reset(seed=seed)
        draw = self.np_random.integers(0, 2**31 - 1, size=2)
        self.field_seed = int(options.get("field_seed", draw[0]))
        self.run_seed = int(options.get("run_seed", draw[1]))
        drawn = not ("desired" in options or "field_seed" in options or self.desired_set)
        self._pending = {"kind": "draw", "drive": None, "options": options, "drawn": drawn}
        given = "desired" in options or self.desired_set is not None
        return None if given else self.field_seed

    def start_reset(self):
        """Second part of :meth:`prepare_reset` (after :meth:`draw_reset`): start the engine on
        the drawn target and compute its IT00 drive.

        Returns
        -------
        (drive, iteration) : (ndarray (n, n_inputs), int)
            As :meth:`prepare_reset`'s.

        Raises
        ------
        RuntimeError
            No :meth:`draw_reset` pending.
        """
        pending = self._pending
        if pending is None or pending["kind"] != "draw":
            raise RuntimeError("start_reset without a pending draw_reset")
        try:
            return self._start_target(pending["options"], pending["drawn"], 0)
        except BaseException:
            self._abandon()
            raise

    def _abandon(self) -> None:
        """No episode: the state before any reset (no engine, nothing pending, ``step``
        refused), as a reset or finish that raises leaves the env."""
        self.engine = None
        self._pending = None
        self._done = True

    def _start_target(self, options: dict, drawn: bool, attempt: int):
        """The engine and IT00 drive of this reset's target (attempt ``attempt``)."""
        ph = self.physics
        if "desired" in options:
            desired = self._load(options["desired"])
        elif self.desired_set is not None:
            desired = self.desired_set[self.field_seed % len(self.desired_set)]
        else:
            desired = ph.target_record(self.field_seed)
        self.desired = desired
        self.engine = ph.start(desired, self.run_seed)
        self.iteration = 0
        drive = self.engine.first_drive()
        self._pending = {
            "kind": "reset",
            "drive": drive,
            "options": options,
            "drawn": drawn,
            "attempt": attempt,
        }
        return drive, 0

    def finish_reset(self, outcome):
        """Second half of :meth:`reset`: take the IT00 play's outcome.

        Parameters
        ----------
        outcome : tuple or BaseException
            What playing the prepared IT00 drive gave: the ``(drive, raw, processed, scores)``
            tuple of :meth:`vrig.reconstruction.DriveIteration.play`, or the exception raised.

        Returns
        -------
        (observation, info) or None
            As :meth:`reset`'s; None when a drawn pseudo-field target tripped at IT00 and
            another was drawn (:data:`FIELD_REDRAWS`): play :attr:`pending` and finish again.

        Raises
        ------
        RigLimitError
            As :meth:`reset`'s (a trip that is not redrawn); any other exception ``outcome`` is
            raised as it is.
        """
        pending = self._take_pending("reset")
        try:
            return self._finish_reset(pending, outcome)
        except BaseException:
            self._abandon()
            raise

    def _finish_reset(self, pending: dict, outcome):
        """:meth:`finish_reset`'s body (``pending``: the taken reset)."""
        if isinstance(outcome, BaseException):
            # IT00 cannot be refused quietly: there is no previous drive to fall back on. A
            # drawn pseudo-field target the linear inverse cannot start on (its IT00 drive trips
            # or exceeds the full scale: a hardening rig, e.g. the calibrated damper) is redrawn
            attempt = pending["attempt"]
            if not (
                isinstance(outcome, RigLimitError)
                and pending["drawn"]
                and attempt < FIELD_REDRAWS
            ):
                raise outcome
            self.field_seed = int(self.np_random.integers(0, 2**31 - 1))
            self._start_target(pending["options"], True, attempt + 1)
            return None
        self.drive_th, self.raw, self.response, self.scores = outcome
        self.drive = pending["drive"]
        self.log_band_error = self.task.measure(
            self.engine.desres.data, self.response.data, self.physics.fs
        )
        self.errors = [np.asarray(self.scores[0], dtype=float)]
        self.change_ratio = None  # IT00: no change yet
        self._done = False
        return self._observe(None), self._info(self.scores)

    def step(self, action):
        """One iteration: update the drive with the action's gains and play it.

        As :meth:`gymnasium.Env.step` (``finish_step(play(*prepare_step(action)))``). An
        exception other than a rig failure (e.g. ``KeyboardInterrupt`` during the play) ends the
        episode.

        Parameters
        ----------
        action : array_like
            The flat action of :class:`ActionLayout` (``self.layout``), shape
            ``self.action_space.shape``; gains (and phases) outside their bounds are clipped, a
            wrong shape or a non-finite value is a ``ValueError``, a complex action a
            ``TypeError``.

        Returns
        -------
        observation : dict
            The observation after the iteration (after a failure: the errors of the last
            played iteration, ``band_error_change`` 0, and the new iteration count).
        reward : float
            See the class docstring; ``-trip_penalty`` on a failure.
        terminated : bool
            Every channel's η0 <= ``tolerance``, or a failure (drive beyond the limits, rig trip,
            unstable simulation or free run).
        truncated : bool
            Always False: the budget is the ``TimeLimit`` wrapper's (``max_episode_steps``).
        info : dict
            As :meth:`reset`'s, for this iteration: ``reason`` ``"tolerance"``, ``"limit"``,
            ``"unstable"`` or ``""`` (the episode goes on); ``trip`` the failure's message;
            ``action_clipped`` whether a value was clipped. After a failure the errors are the
            last played iteration's and ``success`` is False.

        Raises
        ------
        RuntimeError
            No episode in progress (it ended, or the last ``reset`` raised).
        """
        drive, n = self.prepare_step(action)
        try:
            outcome = None if drive is None else self._play(drive, n)
        except BaseException:
            self._pending, self._done = None, True
            raise
        return self.finish_step(outcome)

    def prepare_step(self, action):
        """First half of :meth:`step`: check the action and compute the next drive (see the
        class docstring for the split contract).

        Parameters
        ----------
        action : array_like
            As :meth:`step`'s.

        Returns
        -------
        (drive, iteration) : (ndarray (n, n_inputs) or None, int)
            ITn+1DRV and n+1: play it on ``self.engine`` and pass the outcome to
            :meth:`finish_step`. ``drive`` is None when the update itself failed (a diverging
            inverse-model free run, recorded): pass ``None`` to :meth:`finish_step`.

        Raises
        ------
        RuntimeError
            No episode in progress, or a prepared step or reset not finished yet.
        ValueError
            A wrong shape or a non-finite action (nothing changes).
        TypeError
            A complex (or other non-real) action (nothing changes).
        """
        if self._done:
            raise RuntimeError(
                "no episode in progress (it ended, or the last reset() raised): call reset() first"
            )
        if self._pending is not None:
            raise RuntimeError(f"a prepared {self._pending['kind']} is not finished yet")
        gains, reidentify, clipped = self._gains(action)
        ph, task = self.physics, self.task
        pending = {
            "kind": "step",
            "drive": None,
            "failure": None,
            "clipped": clipped,
            "eta_before": self.scores[0],
            "energy_before": task.drive_energy(self.drive, ph.drive_full_scale),
            "previous": self.log_band_error,
            "previous_response": self.response.data,
            "gains": gains,
        }
        self.iteration += 1
        try:
            if reidentify:
                self.engine.reidentify(self.drive_th, self.raw)
            edges = self.edges if gains.ndim == 2 else None
            pending["drive"] = self.engine.next_drive(self.drive, self.response, gains, edges)
        except FAILURES as exc:
            pending["failure"] = exc
        self._pending = pending
        return pending["drive"], self.iteration

    def finish_step(self, outcome):
        """Second half of :meth:`step`: take the play's outcome, observe and score it.

        Parameters
        ----------
        outcome : tuple, BaseException or None
            What playing the prepared drive gave: the ``(drive, raw, processed, scores)`` tuple
            of :meth:`vrig.reconstruction.DriveIteration.play` or the exception raised; ignored
            (pass None) when :meth:`prepare_step` returned no drive.

        Returns
        -------
        (observation, reward, terminated, truncated, info)
            As :meth:`step`'s.
        """
        pending = self._take_pending("step")
        failure = pending["failure"]
        if failure is None and isinstance(outcome, BaseException):
            if not isinstance(outcome, FAILURES):
                self._done = True
                raise outcome
            failure = outcome
        if failure is not None:
            self._done = True
            self.change_ratio = None  # nothing played: no realised change
            obs = self._observe(pending["previous"])
            reason = "limit" if isinstance(failure, RigLimitError) else "unstable"
            info = self._info(
                self.scores, reason=reason, trip=str(failure), clipped=pending["clipped"]
            )
            info["success"] = False
            return obs, -self.task.trip_penalty, True, False, info
        task, drive = self.task, pending["drive"]
        self.drive_th, self.raw, self.response, self.scores = outcome
        self.drive = drive
        scores = self.scores
        self.log_band_error = task.measure(
            self.engine.desres.data, self.response.data, self.physics.fs
        )
        self.errors.append(np.asarray(scores[0], dtype=float))
        self.change_ratio = response_change_ratios(
            self.engine.desres.data, pending["previous_response"], self.response.data,
            self.physics.fs, self.edges, pending["gains"],
        )  # fmt: skip
        reward = task.reward(
            pending["eta_before"],
            scores[0],
            pending["energy_before"],
            task.drive_energy(drive, self.physics.drive_full_scale),
        )
        terminated = task.success(scores[0])
        self._done = terminated
        return (
            self._observe(pending["previous"]),
            reward,
            terminated,
            False,
            self._info(
                scores, reason="tolerance" if terminated else "", clipped=pending["clipped"]
            ),
        )

    def close(self):
        """End the episode and drop the engine (the rig and the cached inverse model stay);
        ``reset`` starts a new episode."""
        self._abandon()
