"""The drive-iteration gymnasium environment: one step is one iteration of the drive.

See :class:`DriveIterationEnv` for the observation, action, reward and termination, and
``README.md`` (section *Gymnasium environments*) for a training example.
"""

from __future__ import annotations

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
from .task import IterationTask, band_edges

__all__ = ["FALLBACK_TOLERANCE", "FIELD_REDRAWS", "ActionLayout", "DriveIterationEnv"]

FALLBACK_TOLERANCE = 2.0
"""Default η0 tolerance [%, every channel] on a rig whose side-car names none
(``rig.defaults.tolerance``: the side-car's ``"reconstruction": {"gym": {"tolerance": ...}}``;
the rule by which those are measured: :mod:`vrig.envs`)."""

FIELD_REDRAWS = 4
"""How often ``reset`` redraws a pseudo-field target whose IT00 drive trips the rig or exceeds
its full scale (a drawn target only; an explicit ``desired``/``field_seed`` or a desired set
raises the :class:`vrig.RigLimitError`)."""

FAST_SECONDS = 4.0
"""Length of the desired segments of the ``fast`` option [s] (the default is 20 s; the
identification drive is longer, :data:`FAST_ID_SECONDS`)."""
FAST_ID_SECONDS = 12.0
"""Identification drive length of the ``fast`` option [s]: a 4 s record is too short for a
stable inverse on the elastomeric damper (the default is the desired segment length, 20 s)."""

_ACTION_MODES = ("bands", "channels", "scalar")


@dataclass(frozen=True)
class ActionLayout:
    """How the flat action vector maps to gains.

    ``mode`` ``"bands"``: ``n_inputs * n_bands`` gains, channel-major (``action[:n_gains]
    .reshape(n_inputs, n_bands)``); ``"channels"``: one gain per drive channel; ``"scalar"``: one
    gain. With ``reidentify`` the last element (in [0, 1]) is the re-identify flag (>= 0.5: re-fit
    the inverse model from the latest drive and raw response before computing the update).

    Parameters
    ----------
    mode : {"bands", "channels", "scalar"}
        Gain resolution: per drive channel and band, per drive channel, or one gain.
    n_inputs : int
        Number of drive channels of the rig.
    n_bands : int
        Number of gain bands (used by ``mode="bands"`` only).
    reidentify : bool
        Whether the action ends with the re-identify flag.
    low, high : float
        Bounds of every gain (dimensionless; the flag's bounds are [0, 1] whatever these are).
    """

    mode: str
    n_inputs: int
    n_bands: int
    reidentify: bool
    low: float
    high: float

    @property
    def n_gains(self) -> int:
        """Number of gains in the action (``n_inputs * n_bands``, ``n_inputs`` or 1)."""
        return {"bands": self.n_inputs * self.n_bands, "channels": self.n_inputs, "scalar": 1}[
            self.mode
        ]

    @property
    def size(self) -> int:
        """Length of the flat action: :attr:`n_gains`, plus 1 for the re-identify flag."""
        return self.n_gains + int(self.reidentify)

    def action(self, gains, reidentify: bool = False) -> np.ndarray:
        """A flat action from gains (scalar, per channel or (channels, bands), broadcast to the
        mode's shape) and the re-identify flag.

        Parameters
        ----------
        gains : float or array_like
            Gains (dimensionless): a scalar, one per drive channel (``(n_inputs,)``, repeated
            over the bands in ``"bands"`` mode) or ``(n_inputs, n_bands)``; broadcast to the
            mode's shape. Not clipped to ``[low, high]`` here (the env clips).
        reidentify : bool
            The re-identify flag (1.0 when true, else 0.0); ignored unless the layout has one.

        Returns
        -------
        ndarray
            The flat float64 action of length :attr:`size`.
        """
        g = np.asarray(gains, dtype=float)
        shape = {"bands": (self.n_inputs, self.n_bands), "channels": (self.n_inputs,)}.get(
            self.mode, (1,)
        )
        if self.mode == "bands" and g.ndim == 1 and g.size == self.n_inputs != self.n_bands:
            g = g[:, None]
        flat = np.broadcast_to(g, shape).ravel()
        if self.reidentify:
            flat = np.concatenate([flat, [1.0 if reidentify else 0.0]])
        return flat.astype(np.float64)


def _check_env_options(render_mode, action_mode, max_iterations, gain_range) -> tuple[float, float]:
    """The options checked before the rig is built; returns the gain range ``(low, high)``."""
    if render_mode is not None:
        raise ValueError("DriveIterationEnv does not render (render_mode must be None)")
    if action_mode not in _ACTION_MODES:
        raise ValueError(f"action_mode must be one of {_ACTION_MODES}, got {action_mode!r}")
    if not isinstance(max_iterations, (int, np.integer)) or max_iterations < 1:
        raise ValueError(f"max_iterations must be a positive integer, got {max_iterations!r}")
    lo, hi = (float(g) for g in gain_range)
    if not (np.isfinite(lo) and np.isfinite(hi) and 0 <= lo < hi):
        raise ValueError(f"gain_range must satisfy 0 <= low < high, got {gain_range}")
    return lo, hi


class DriveIterationEnv(gym.Env):
    """Drive iteration (response reconstruction) on a virtual rig as a gymnasium environment.

    **Episode.** ``reset(seed)`` draws a desired response - a pseudo-field record (the rig's
    response to a seeded road-like drive), one of the supplied ``desired`` records, or
    ``options["desired"]`` - builds the engine with the inverse model (identified once with
    ``model_seed`` and cached), computes IT00DRV = inverse(DESRES) and plays it. Each ``step``
    is one iteration: ``ITn+1DRV = ITnDRV + gains x (inverse(DESRES) - inverse(ITnRES))`` with
    the action's gains (per drive channel and frequency band), then plays it. (An IT00 drive
    beyond the limits makes ``reset`` raise :class:`~vrig.RigLimitError`: there is no drive to
    fall back on; pseudo-field targets of the registered rigs never do.)

    **Observation** (``Dict`` of float32 boxes, clipped to their bounds):

    * ``band_error`` (outputs, bands): log10 of the band RMS of (DESRES - ITnRES) over the band
      RMS of DESRES, bands ``self.edges`` (log-spaced over the simulation band), in [-6, 3];
    * ``band_error_change`` (outputs, bands): ``band_error`` now minus at the previous
      iteration (0 at IT00), in [-3, 3] (> 0: the band's error grew);
    * ``eta0``, ``rms_error`` (outputs,): η0 (eq. 5-28) and RMS error [%], in [0, 1000];
    * ``drive_rms``, ``drive_peak`` (inputs,): of ITnDRV, as fractions of the full scale;
    * ``iteration`` (1,): n.

    **Action** (``Box`` float64, flat; see :class:`ActionLayout`): gains in ``[gain_low,
    gain_high]`` (default [0, 2]) per drive channel x band (``action_mode="bands"``), per
    channel (``"channels"``) or one (``"scalar"``), plus an optional re-identify flag
    (``reidentify_action=True``). Gains out of bounds are clipped (``info["action_clipped"]``); a
    wrong shape or a non-finite value raises ``ValueError``.

    **Reward**: ``ln(mean η0 before) - ln(mean η0 after) - energy_penalty * max(0, ln(drive
    energy growth)) - step_penalty``; a drive beyond the limits (never sent), a rig trip or a
    non-finite drive gives ``-trip_penalty`` and terminates (``info["reason"] == "limit"``; a
    diverging inverse-model free run or an unstable simulation: ``"unstable"``).

    **Termination** when every channel's η0 <= ``tolerance`` (``info["reason"] ==
    "tolerance"``); **truncation** after ``max_iterations`` steps (``"budget"``). ``info``
    carries the raw errors (``eta0``, ``rms_error``, ``damage_ratio``, ``mean_eta0``), the
    ``iteration``, ``success``, ``reason``, ``field_seed``, ``run_seed`` and any ``trip`` message.

    **Randomness**: only ``reset(seed=...)`` / ``self.np_random``: each reset draws the
    pseudo-field seed (or the index into ``desired``) and the run seed (rig noise of the
    iteration runs: ``run_seed + 1 + n``); a drawn pseudo-field target whose IT00 drive trips
    the rig or exceeds its full scale (the linear inverse overshoots a hardening rig: on the
    calibrated elastomeric damper about 1 target in 24) is redrawn from ``self.np_random`` up to
    :data:`FIELD_REDRAWS` times (``info["field_seed"]`` is the one played). ``options`` may fix ``"desired"`` (a TimeHistory or
    file), ``"field_seed"``, ``"run_seed"``: with ``model_seed=s`` and ``options={"desired": d,
    "run_seed": s}`` a fixed gain g reproduces ``vrig.reconstruct(rig, d, gain=g, seed=s)``.

    Parameters
    ----------
    rig : str or Rig
        Rig name (``vrig.list_rigs()``) or rig object.
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
        Length of the pseudo-field desired responses [s] and, unless ``id_duration`` (or
        ``fast``) sets it, of the identification drive (default 20 s, 4 s with ``fast``).
    desired : sequence of TimeHistory or paths, optional
        Desired responses to draw from instead of pseudo-field records (RPC III, CSV, MAT, NPZ
        files are read with :func:`vrig.io.read`).
    n_bands : int
        Number of observation / gain bands (default 4), log-spaced over the simulation band.
    action_mode : {"bands", "channels", "scalar"}
        Gains per drive channel and band (default), per drive channel, or one gain
        (:class:`ActionLayout`).
    reidentify_action : bool
        Append the re-identify flag to the action (default False).
    gain_range : (float, float)
        Bounds ``(low, high)`` of every gain, ``0 <= low < high`` (default (0, 2)).
    max_iterations : int
        Iteration budget (steps) before truncation; keep ``max_episode_steps`` of ``make`` equal.
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
        max_iterations: int = 10,
        tolerance: float | None = None,
        trip_penalty: float = 5.0,
        energy_penalty: float = 0.1,
        step_penalty: float = 0.0,
        model_seed: int | None = None,
        id_duration: float | None = None,
        id_rms=None,
        decimation: int | None = None,
        rig_seed: int = 0,
        rig_options: dict | None = None,
        render_mode: str | None = None,
    ):
        lo, hi = _check_env_options(render_mode, action_mode, max_iterations, gain_range)
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
        settings = IterationSettings.build(
            settings, **{k: v for k, v in given.items() if v is not None}
        )
        if fast and settings.id_duration is None:
            settings = settings.replace(id_duration=FAST_ID_SECONDS)
        self.physics = IterationPhysics(
            rig,
            settings,
            seconds=seconds if seconds is not None else (FAST_SECONDS if fast else 20.0),
            fidelity=fidelity or ("fast" if fast else "full"),
            rig_seed=rig_seed,
            rig_options=rig_options,
        )
        ph = self.physics
        self.edges = band_edges(ph.band, n_bands)
        if tolerance is None:
            tolerance = getattr(getattr(ph.rig, "defaults", None), "tolerance", None)
            tolerance = FALLBACK_TOLERANCE if tolerance is None else tolerance
        if not (np.isfinite(tolerance) and tolerance > 0):
            raise ValueError(f"tolerance must be a positive number [%], got {tolerance!r}")
        self.task = IterationTask(
            edges=self.edges,
            tolerance=float(tolerance),
            trip_penalty=trip_penalty,
            energy_penalty=energy_penalty,
            step_penalty=step_penalty,
        )
        self.max_iterations = int(max_iterations)
        self.layout = ActionLayout(
            action_mode, ph.n_inputs, n_bands, bool(reidentify_action), lo, hi
        )
        self._build_spaces(lo, hi)
        self.desired_set = None if desired is None else [self._load(d) for d in desired]
        if self.desired_set is not None and not self.desired_set:
            raise ValueError("desired must hold at least one record")
        self.engine = None
        self._done = True

    # ------------------------------------------------------------------ helpers
    def _build_spaces(self, lo: float, hi: float) -> None:
        """Action space (gains in ``[lo, hi]``, plus the re-identify flag in [0, 1]) and
        observation space of the task."""
        low = np.full(self.layout.size, lo)
        high = np.full(self.layout.size, hi)
        if self.layout.reidentify:
            low[-1], high[-1] = 0.0, 1.0
        self.action_space = spaces.Box(low, high, dtype=np.float64)
        self.observation_space = self.task.observation_space(
            self.physics.n_inputs, self.physics.n_outputs, self.max_iterations
        )

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
        a = np.asarray(action, dtype=float)
        lay = self.layout
        if a.shape == () and lay.size == 1:
            a = a.reshape(1)
        if a.shape != (lay.size,):
            raise ValueError(
                f"action must have shape ({lay.size},) ({lay.mode} gains"
                + (" + re-identify flag" if lay.reidentify else "")
                + f"), got {a.shape}"
            )
        if not np.all(np.isfinite(a)):
            raise ValueError(f"action must be finite, got {a}")
        clipped = np.clip(a, self.action_space.low, self.action_space.high)
        was_clipped = bool(np.any(clipped != a))
        g = clipped[: lay.n_gains]
        reid = bool(lay.reidentify and clipped[-1] >= 0.5)
        if lay.mode == "bands":
            g = g.reshape(lay.n_inputs, lay.n_bands)
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
        )

    # ------------------------------------------------------------------ API
    def reset(self, *, seed: int | None = None, options: dict | None = None):
        """Start an episode: draw a desired response, compute IT00DRV and play it.

        As :meth:`gymnasium.Env.reset`; a reset that raises leaves no episode (``step`` then
        raises until a reset succeeds).

        Parameters
        ----------
        seed : int, optional
            Seeds ``self.np_random`` (Gymnasium's rule: once, then leave it ``None``); the
            pseudo-field seed (or the index into ``desired``) and the run seed are drawn from it.
        options : dict, optional
            ``"desired"``: the desired response of this episode (a TimeHistory or a file, one
            column per rig output at the rig's fs); ``"field_seed"``: the pseudo-field seed (or
            the index, modulo its length, into the env's ``desired`` set); ``"run_seed"``: the
            run seed (rig noise of the iteration runs: ``run_seed + 1 + n``). Any other key is a
            ``ValueError``.

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
        """
        # the episode is over until this reset succeeds: a reset that raises leaves no episode
        # for ``step`` to continue (it would mix the old drive with the new target)
        self._done = True
        super().reset(seed=seed)
        options = dict(options or {})
        unknown = set(options) - {"desired", "field_seed", "run_seed"}
        if unknown:
            raise ValueError(
                f"unknown reset option(s) {sorted(unknown)}; use desired, field_seed, run_seed"
            )
        draw = self.np_random.integers(0, 2**31 - 1, size=2)
        self.field_seed = int(options.get("field_seed", draw[0]))
        self.run_seed = int(options.get("run_seed", draw[1]))
        ph = self.physics
        drawn = not ("desired" in options or "field_seed" in options or self.desired_set)
        for attempt in range(FIELD_REDRAWS + 1):
            if "desired" in options:
                desired = self._load(options["desired"])
            elif self.desired_set is not None:
                desired = self.desired_set[self.field_seed % len(self.desired_set)]
            else:
                desired = ph.pseudo_field(self.field_seed)
            self.desired = desired
            self.engine = ph.start(desired, self.run_seed)
            self.iteration = 0
            drive = self.engine.first_drive()
            # IT00 cannot be refused quietly: there is no previous drive to fall back on. A
            # drawn pseudo-field target the linear inverse cannot start on (its IT00 drive trips
            # or exceeds the full scale: a hardening rig, e.g. the calibrated damper) is redrawn
            try:
                self.drive_th, self.raw, self.response, self.scores = self.engine.play(drive, 0)
            except RigLimitError:
                if not drawn or attempt == FIELD_REDRAWS:
                    raise
                self.field_seed = int(self.np_random.integers(0, 2**31 - 1))
            else:
                break
        self.drive = drive
        self.log_band_error = self.task.measure(self.engine.desres.data, self.response.data, ph.fs)
        self.errors = [np.asarray(self.scores[0], dtype=float)]
        self._done = False
        return self._observe(None), self._info(self.scores)

    def step(self, action):
        """One iteration: update the drive with the action's gains and play it.

        As :meth:`gymnasium.Env.step`.

        Parameters
        ----------
        action : array_like
            The flat action of :class:`ActionLayout` (``self.layout``), shape
            ``self.action_space.shape``; gains outside ``gain_range`` are clipped, a wrong shape
            or a non-finite value is a ``ValueError``.

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
            ``max_iterations`` steps reached without termination.
        info : dict
            As :meth:`reset`'s, for this iteration: ``reason`` ``"tolerance"``, ``"budget"``,
            ``"limit"``, ``"unstable"`` or ``""`` (the episode goes on); ``trip`` the failure's
            message; ``action_clipped`` whether a gain was clipped. After a failure the errors are
            the last played iteration's and ``success`` is False.

        Raises
        ------
        RuntimeError
            No episode in progress (it ended, or the last ``reset`` raised).
        """
        if self._done:
            raise RuntimeError(
                "no episode in progress (it ended, or the last reset() raised): call reset() first"
            )
        gains, reidentify, clipped = self._gains(action)
        ph, task = self.physics, self.task
        eta_before = self.scores[0]
        energy_before = task.drive_energy(self.drive, ph.drive_full_scale)
        previous = self.log_band_error
        self.iteration += 1
        truncated = self.iteration >= self.max_iterations
        try:
            if reidentify:
                self.engine.reidentify(self.drive_th, self.raw)
            edges = self.edges if gains.ndim == 2 else None
            drive = self.engine.next_drive(self.drive, self.response, gains, edges)
            drv, raw, res, scores = self.engine.play(drive, self.iteration)
        except FAILURES as exc:
            self._done = True
            obs = self._observe(previous)
            obs["iteration"][:] = self.iteration
            reason = "limit" if isinstance(exc, RigLimitError) else "unstable"
            info = self._info(self.scores, reason=reason, trip=str(exc), clipped=clipped)
            info["success"] = False
            return obs, -task.trip_penalty, True, False, info
        self.drive_th, self.raw, self.response, self.scores, self.drive = (
            drv,
            raw,
            res,
            scores,
            drive,
        )
        self.log_band_error = task.measure(self.engine.desres.data, res.data, ph.fs)
        self.errors.append(np.asarray(scores[0], dtype=float))
        reward = task.reward(
            eta_before, scores[0], energy_before, task.drive_energy(drive, ph.drive_full_scale)
        )
        terminated = task.success(scores[0])
        reason = "tolerance" if terminated else ("budget" if truncated else "")
        self._done = terminated or truncated
        return (
            self._observe(previous),
            reward,
            terminated,
            truncated and not terminated,
            self._info(scores, reason=reason, clipped=clipped),
        )

    def close(self):
        """End the episode and drop the engine (the rig and the cached inverse model stay);
        ``reset`` starts a new episode."""
        self.engine = None
        self._done = True
