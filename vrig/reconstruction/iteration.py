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
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import rainflow
from scipy import signal
from tqdm.auto import tqdm

from identification import metrics
from identification.errors import SimulationDivergedError

from ..errors import ReconstructionError, RigLimitError, SimulationInstabilityError
from ..processing import decimate, gprepro, identification_band
from ..rigs.spec import check_drive_limits
from ..signals import random_drive, triangular_psd
from ..timehistory import TimeHistory
from .methods import make_method

__all__ = [
    "MAX_ITERATIONS",
    "DriveIteration",
    "ReconstructionResult",
    "band_gains",
    "pseudo_damage",
    "reconstruct",
]

MAX_ITERATIONS = 99
"""Most iterations after IT00 (the records are named IT00 .. IT99)."""


def pseudo_damage(x: np.ndarray, *, slope: float = 5.0) -> float:
    """Rainflow pseudo-damage ``sum n_i S_i^slope`` of a record (ranges S_i, counts n_i)."""
    return float(
        sum(count * rng**slope for rng, _mean, count, _i, _j in rainflow.extract_cycles(x))
    )


@dataclass
class ReconstructionResult:
    """Everything a reconstruction produced (QanTiM names).

    Attributes
    ----------
    errors : ndarray (n_iterations_run + 1, n_outputs)
        η0 [%] (eq. 5-28) of ITxxRES against DESRES, IT00 first.
    rms_errors : ndarray, same shape
        RMS error [%] of ITxxRES against DESRES (means removed).
    damage_ratio : ndarray, same shape
        Rainflow pseudo-damage of ITxxRES over that of DESRES (S-N slope 5).
    drives, responses, raw_responses : list of TimeHistory
        ITxxDRV, ITxxRES (processed) and RITxxRES (raw) per iteration.
    best_iteration : int
        Iteration with the smallest mean η0; ``final_drive``/``final_response`` are its records.
        ``-1`` when no iteration was played (the result of a :class:`~vrig.ReconstructionError`).
    id_drive, id_response : TimeHistory or None
        IDDRV and IDRES (raw); ``None`` when the identification drive could not be played.
    stopped : str
        Why the loop stopped before the last iteration ("" when it ran them all).
    error : Exception or None
        The exception that stopped the loop (None when it completed or diverged).
    rejected_name, rejected_drive : str, TimeHistory or None
        The drive that was refused before it was sent (``"REFUSEDxx"``, ``"REFUSEDID"`` for the
        identification drive) or that tripped the rig (``"TRIPPEDxx"``, ``"TRIPPEDID"``), when
        the loop stopped on one; ``""``/``None`` otherwise.
    """

    desired: TimeHistory
    id_drive: TimeHistory | None
    id_response: TimeHistory | None
    method: object
    bandwidth: tuple[float, float]
    errors: np.ndarray
    rms_errors: np.ndarray
    damage_ratio: np.ndarray
    drives: list = field(default_factory=list)
    responses: list = field(default_factory=list)
    raw_responses: list = field(default_factory=list)
    best_iteration: int = 0
    stopped: str = ""
    decimation: int = 1
    gain: np.ndarray | None = None
    strategy: str = "fixed"
    seed: int = 0
    error: Exception | None = None
    rejected_name: str = ""
    rejected_drive: TimeHistory | None = None

    @property
    def final_drive(self) -> TimeHistory:
        return self.drives[self._best()]

    @property
    def final_response(self) -> TimeHistory:
        return self.responses[self._best()]

    def _best(self) -> int:
        if not self.drives or not 0 <= self.best_iteration < len(self.drives):
            raise ValueError(f"no iteration was played ({self.stopped or 'empty result'})")
        return self.best_iteration

    def table(self) -> str:
        """Per-iteration, per-channel η0 table."""
        names = self.desired.names
        head = f"{'iteration':>9} " + " ".join(f"{n[:14]:>14}" for n in names) + f" {'mean':>8}"
        rows = [head]
        for i, e in enumerate(self.errors):
            mark = " *" if i == self.best_iteration else ""
            rows.append(
                f"{f'IT{i:02d}':>9} "
                + " ".join(f"{v:>13.2f}%" for v in e)
                + f" {e.mean():>7.2f}%{mark}"
            )
        return "\n".join(rows)


def _scores(desired: TimeHistory, response: TimeHistory):
    eta0 = metrics.qantim_fit_dc(desired.data, response.data)
    rms = metrics.rms_error_percent(desired.data, response.data)
    dmg = np.array(
        [
            pseudo_damage(response.data[:, k]) / max(pseudo_damage(desired.data[:, k]), 1e-300)
            for k in range(desired.n_channels)
        ]
    )
    return eta0, rms, dmg


def _check_drive(rig, drive: np.ndarray, what: str) -> None:
    check_drive_limits(rig.inputs, drive, fs=rig.fs, what=what)


def band_gains(x: np.ndarray, fs: float, gains: np.ndarray, edges) -> np.ndarray:
    """Scale each frequency band of each channel of ``x`` by its own gain.

    ``gains`` is (n_channels, n_bands); band ``b`` holds the frequencies in
    ``[edges[b], edges[b + 1])`` (the first band starts at 0 Hz, the last runs to Nyquist,
    whatever ``edges[0]`` / ``edges[-1]`` say). The scaling is a piecewise-constant weighting of the
    record's (zero-padded) spectrum, so gains equal across bands give exactly ``gain * x``.
    """
    x = np.asarray(x, dtype=float)
    gains = np.asarray(gains, dtype=float)
    edges = np.asarray(edges, dtype=float)
    if gains.ndim != 2 or gains.shape[0] != x.shape[1] or gains.shape[1] != edges.size - 1:
        raise ValueError(
            f"gains must be (n_channels={x.shape[1]}, n_bands={edges.size - 1}), got {gains.shape}"
        )
    if np.all(gains == gains[:, :1]):
        return x * gains[:, 0]
    n = x.shape[0]
    X = np.fft.rfft(x, n=2 * n, axis=0)
    f = np.fft.rfftfreq(2 * n, 1.0 / fs)
    band = np.clip(np.searchsorted(edges, f, side="right") - 1, 0, edges.size - 2)
    return np.fft.irfft(X * gains[:, band].T, n=2 * n, axis=0)[:n]


def _check_seed(seed) -> int:
    if not isinstance(seed, (int, np.integer)) or isinstance(seed, bool) or seed < 0:
        raise ValueError(f"seed must be a non-negative integer, got {seed!r}")
    return int(seed)


def _check_band(band, fs: float) -> tuple[float, float]:
    """The simulation band: two finite numbers with 0 <= low < high <= fs/2 (Nyquist)."""
    try:
        lo, hi = (float(b) for b in band)
    except (TypeError, ValueError):
        raise ValueError(f"bandwidth must be (low, high) in Hz, got {band!r}") from None
    if not (np.isfinite(lo) and np.isfinite(hi) and 0 <= lo < hi <= fs / 2):
        raise ValueError(
            f"bandwidth must satisfy 0 <= low < high <= fs/2 = {fs / 2:g} Hz (Nyquist), got "
            f"({lo:g}, {hi:g})"
        )
    return lo, hi


def _check_id_rms(id_rms, full: np.ndarray) -> np.ndarray:
    """Identification drive RMS per channel: finite, > 0 and at most the full scale."""
    rms = np.asarray(id_rms if id_rms is not None else 0.05 * full, float)
    try:
        rms = np.broadcast_to(rms, full.shape)
    except ValueError:
        raise ValueError(
            f"id_rms must be one value or one per drive channel ({full.size}), got {id_rms!r}"
        ) from None
    if not np.all(np.isfinite(rms) & (rms > 0) & (rms <= full)):
        raise ValueError(
            f"id_rms must be finite, > 0 and <= each drive's full scale {full.tolist()}, "
            f"got {rms.tolist()}"
        )
    return rms


def _check_content(desired: TimeHistory, desres: TimeHistory, band) -> None:
    """See :meth:`DriveIteration.check_desired`."""
    scale = np.abs(desired.data).max(axis=0)
    rms = np.sqrt(np.mean(desres.data**2, axis=0))
    empty = ~(rms > 1e-9 * scale)
    if empty.any():
        k = int(np.argmax(empty))
        raise ValueError(
            f"desired channel {desired.names[k]!r} has no content in the simulation band "
            f"{band[0]:g}-{band[1]:g} Hz after de-trending and DC removal (RMS {rms[k]:.3g} "
            f"against a peak of {scale[k]:.3g}): a constant or out-of-band record cannot be "
            "reconstructed"
        )


class DriveIteration:
    """One reconstruction, step by step: the engine of :func:`reconstruct` and of the gymnasium
    environments (so a policy's fixed gain reproduces ``reconstruct`` exactly).

    >>> it = DriveIteration(rig, desired, method="arx", seed=0)     # doctest: +SKIP
    >>> it.identify()                                               # IDDRV -> IDRES -> model
    >>> drive = it.first_drive()                                    # IT00DRV = inverse(DESRES)
    >>> raw, res, (eta0, rms, damage) = it.play(drive, 0)            # RIT00RES, IT00RES, scores
    >>> drive = it.next_drive(drive, res, gain=0.8)                 # IT01DRV

    Parameters are those of :func:`reconstruct`. ``play`` raises :class:`~vrig.RigLimitError`
    for a drive beyond the rig's limits *before* sending it, or when the rig trips. A drive that
    was refused or tripped the rig (in ``play`` or ``identify``) is kept in ``rejected`` as
    ``("REFUSEDxx" | "TRIPPEDxx", drive)`` (``xx`` the iteration, ``ID`` for the identification
    drive) until the next drive is played; a drive that is not finite is refused but not kept.
    """

    def __init__(
        self,
        rig,
        desired: TimeHistory,
        *,
        method="arx",
        bandwidth: tuple[float, float] | None = None,
        id_duration: float | None = None,
        id_rms: float | None = None,
        id_psd=None,
        decimation: int | None = None,
        taper: float = 0.25,
        seed: int = 0,
        **method_options,
    ):
        if not isinstance(desired, TimeHistory):
            raise TypeError("desired must be a vrig.TimeHistory")
        if desired.fs != rig.fs:
            raise ValueError(f"desired is sampled at {desired.fs:g} Hz, the rig at {rig.fs:g} Hz")
        if desired.n_channels != len(rig.outputs):
            raise ValueError(
                f"desired has {desired.n_channels} channels, the rig {len(rig.outputs)} responses"
            )
        self.rig = rig
        self.seed = _check_seed(seed)
        self.band = _check_band(bandwidth if bandwidth is not None else rig.bandwidth, rig.fs)
        self.id_band = identification_band(self.band, fs=rig.fs)
        self.method = make_method(method, **method_options)
        if decimation is None:
            decimation = max(1, int(rig.fs // (8 * self.id_band[1])))
        if not isinstance(decimation, (int, np.integer)) or decimation < 1:
            raise ValueError(f"decimation must be a positive integer, got {decimation!r}")
        self.decimation = int(decimation)
        if not (np.isfinite(taper) and taper >= 0):
            raise ValueError(f"taper must be a non-negative duration [s], got {taper!r}")
        self.taper = float(taper)
        self.n_inputs = len(rig.inputs)
        full = np.array([c.full_scale for c in rig.inputs])
        self.id_rms = _check_id_rms(id_rms, full)
        self.id_psd = id_psd
        if id_duration is not None and not (np.isfinite(id_duration) and id_duration > 0):
            raise ValueError(
                f"id_duration must be a finite number of seconds > 0 (or None: the desired "
                f"record's length), got {id_duration!r}"
            )
        self.id_samples = round((id_duration or desired.duration) * rig.fs)
        self.desres = gprepro(desired, self.band)
        self._desired = desired
        self.n = self.desres.n_samples
        self.names = [c.name for c in rig.inputs]
        self.units = [c.unit for c in rig.inputs]
        self.id_drive: TimeHistory | None = None
        self.id_response: TimeHistory | None = None
        self.target: np.ndarray | None = None
        self.rejected: tuple[str, TimeHistory] | None = None

    # -- resampling between the rig rate and the model rate
    def down(self, th: TimeHistory) -> TimeHistory:
        return decimate(th, self.decimation)

    def up(self, x: np.ndarray) -> np.ndarray:
        if self.decimation == 1:
            return x
        return signal.resample_poly(x, self.decimation, 1, axis=0)[: self.n]

    def identify(self) -> None:
        """IDDRV (``id_psd``, default triangular over the identification band) -> IDRES ->
        inverse model.

        The drive RMS is halved (up to three times) while the rig refuses or trips on it."""
        rig, rms = self.rig, self.id_rms
        shape = self.id_psd
        if shape is None:
            shape = triangular_psd((max(self.id_band[0], 0.0), self.id_band[1]))
        for _attempt in range(4):
            iddrv = random_drive(
                shape,
                self.id_samples,
                rig.fs,
                channels=self.n_inputs,
                rms=rms,
                seed=self.seed,
                names=self.names,
                unit=rig.inputs[0].unit,
            )
            try:
                _, idres = self._send(iddrv, "ID", "the identification drive", self.seed)
                break
            except RigLimitError as exc:  # halve the amplitude and try again
                rms, last_trip = rms / 2, exc
        else:
            raise last_trip  # even at 1/8 of the amplitude the identification drive trips
        self.id_drive, self.id_response = iddrv, idres
        self._fit(iddrv, idres)

    def reidentify(self, drive: TimeHistory, raw: TimeHistory) -> None:
        """Adaptive strategy: re-fit the inverse from the latest drive / raw response pair."""
        self._fit(drive, raw)

    def _fit(self, drive: TimeHistory, response: TimeHistory) -> None:
        self.method.identify(
            self.down(gprepro(drive, self.id_band)), self.down(gprepro(response, self.id_band))
        )
        self.target = self._inverse(self.desres, "DESRES")

    def _inverse(self, response: TimeHistory, what: str) -> np.ndarray:
        """The method's drive for ``response`` at the model rate; a non-finite value raises
        :class:`~identification.SimulationDivergedError` (as a diverging free run does)."""
        x = np.asarray(self.method.drive(self.down(response)), dtype=float)
        bad = ~np.isfinite(x)
        if bad.any():
            i, j = np.argwhere(bad)[0]
            raise SimulationDivergedError(
                j, f"{self.names[j]} (inverse of {what})", i, x[i, j], np.inf
            )
        return x

    def use_identified(self, method, id_drive: TimeHistory, id_response: TimeHistory) -> None:
        """Take an already identified method (e.g. a cached inverse model, identified by
        :meth:`identify` on the same rig, band and settings) instead of identifying again."""
        self.method = make_method(method)
        self.id_drive, self.id_response = id_drive, id_response
        self.target = self._inverse(self.desres, "DESRES")

    def shape(self, x: np.ndarray) -> np.ndarray:
        """A drive (or drive correction) as it may be sent: band-limited to the identification
        band (zero-phase, as every other record: what the model does outside the band it was
        identified in is drift, not information) and tapered to zero over the first and last
        ``taper`` seconds (the rig starts and ends at rest; a step at the start would trip the
        following-error interlock)."""
        th = TimeHistory(x, self.rig.fs, self.names, self.units)
        y = np.array(gprepro(th, self.id_band, detrend=False).data)
        m = min(round(self.taper * self.rig.fs), self.n // 4)
        if m > 0:
            ramp = 0.5 - 0.5 * np.cos(np.pi * np.arange(m) / m)
            y[:m] *= ramp[:, None]
            y[self.n - m :] *= ramp[::-1, None]
        return y

    def check_desired(self) -> None:
        """Raise ``ValueError`` when a desired channel has nothing to reproduce in the band
        (constant, a pure trend or out of band): its η0 would be a ratio of round-off
        (2.3e14 % for a constant record). Called by :meth:`first_drive` and, before the
        identification, by :func:`reconstruct`; identifying alone needs no desired content."""
        _check_content(self._desired, self.desres, self.band)

    def first_drive(self) -> np.ndarray:
        """IT00DRV = inverse(DESRES), band-limited and tapered (:meth:`shape`), at the rig rate."""
        if self.target is None:
            raise RuntimeError("identify() first")
        self.check_desired()
        return self.shape(self.up(self.target))

    def play(self, drive: np.ndarray, iteration: int):
        """Check and send ``drive`` (ITxxDRV); returns (drive, raw, processed, (η0, rms, damage)).

        Raises RigLimitError (nothing is sent when the drive itself is beyond the limits)."""
        what = f"IT{iteration:02d}DRV"
        drv, raw = self._send(drive, f"{iteration:02d}", what, self.seed + 1 + iteration)
        res = gprepro(raw, self.band)
        return drv, raw, res, _scores(self.desres, res)

    def _send(self, drive, tag: str, what: str, seed: int):
        """Check ``drive`` (TimeHistory or array) against the limits and play it; returns
        (drive as TimeHistory, raw response). A refused drive or one that trips the rig (an
        interlock, an unstable simulation) is kept in ``rejected`` before the error goes on."""
        self.rejected = None
        data = drive.data if isinstance(drive, TimeHistory) else np.asarray(drive, dtype=float)
        drv = None
        if np.all(np.isfinite(data)):
            drv = drive if isinstance(drive, TimeHistory) else self._th(data)
        try:
            _check_drive(self.rig, data, what)
        except RigLimitError:
            self.rejected = None if drv is None else (f"REFUSED{tag}", drv)
            raise
        try:
            raw = self.rig.run(drv, seed=seed)
        except (RigLimitError, SimulationInstabilityError):
            self.rejected = (f"TRIPPED{tag}", drv)
            raise
        return drv, raw

    def _th(self, data: np.ndarray) -> TimeHistory:
        return TimeHistory(data, self.rig.fs, self.names, self.units)

    def correction(self, response: TimeHistory) -> np.ndarray:
        """``inverse(DESRES) - inverse(ITxxRES)`` at the rig rate (the un-scaled update),
        band-limited and tapered like the drive (:meth:`shape`)."""
        return self.shape(self.up(self.target - self._inverse(response, "the response")))

    def next_drive(self, drive: np.ndarray, response: TimeHistory, gain, edges=None) -> np.ndarray:
        """``ITn+1DRV = ITnDRV + gain * (inverse(DESRES) - inverse(ITnRES))``.

        ``gain`` is a scalar, one value per drive channel, or (channels, bands) with band
        ``edges`` [Hz] (see :func:`band_gains`)."""
        corr = self.correction(response)
        g = np.asarray(gain, dtype=float)
        if g.ndim == 2:
            if edges is None:
                raise ValueError("per-band gains need the band edges")
            return drive + band_gains(corr, self.rig.fs, g, edges)
        return drive + np.broadcast_to(g, (self.n_inputs,)) * corr


def _check_loop_options(iterations, divergence, min_increase, gain, n_inputs: int) -> np.ndarray:
    """Validate the iteration loop's options; returns the gain per drive channel."""
    if not isinstance(iterations, (int, np.integer)) or not 0 <= iterations <= MAX_ITERATIONS:
        raise ValueError(
            f"iterations must be an integer in 0..{MAX_ITERATIONS} (records are named IT00 to "
            f"IT{MAX_ITERATIONS}), got {iterations!r}"
        )
    if not (isinstance(divergence, (int, float, np.number)) and divergence >= 1):
        raise ValueError(
            f"divergence must be a factor >= 1 (np.inf: never stop on divergence), got "
            f"{divergence!r}"
        )
    if not (isinstance(min_increase, (int, float, np.number)) and min_increase >= 0):
        raise ValueError(f"min_increase must be >= 0 percentage points, got {min_increase!r}")
    gain = np.broadcast_to(np.asarray(gain, dtype=float), (n_inputs,)).copy()
    if np.any(~np.isfinite(gain)) or np.any(gain <= 0) or np.any(gain > 2):
        raise ValueError(f"gain must lie in (0, 2], got {gain}")
    return gain


def reconstruct(
    rig,
    desired: TimeHistory,
    *,
    method="arx",
    iterations: int = 8,
    gain=0.8,
    bandwidth: tuple[float, float] | None = None,
    strategy: str = "fixed",
    id_duration: float | None = None,
    id_rms: float | None = None,
    id_psd=None,
    divergence: float = 1.5,
    min_increase: float = 1.0,
    decimation: int | None = None,
    taper: float = 0.25,
    seed: int = 0,
    progress: bool = False,
    **method_options,
) -> ReconstructionResult:
    """Reproduce ``desired`` on ``rig`` by drive iteration.

    Parameters
    ----------
    rig : Rig
        Anything with ``inputs``, ``outputs``, ``fs`` and ``run(drive, seed=None)``.
    desired : TimeHistory
        The desired response (DESRES before processing), the rig's outputs at ``rig.fs``.
    method : str or method object
        ``"arx"``, ``"narx"``, ``"split"``, ``"frf"`` (options such as ``order``, ``degree``,
        ``split_hz`` go to the method) or an object with ``identify``/``drive``.
    iterations : int
        Number of correction iterations after IT00.
    gain : float or sequence (one per drive channel)
        Iteration gain.
    bandwidth : (low, high) Hz
        Simulation bandwidth applied to every record (default: the rig's test band).
    strategy : {"fixed", "adaptive"}
        ``"adaptive"`` re-identifies the inverse from the latest drive/response pair each time.
    id_duration, id_rms : float
        Identification drive length [s] (default: the desired record's) and RMS per channel
        (default: 5 % of full scale, halved until the rig accepts it).
    id_psd : callable or list of callables, optional
        PSD shape of the identification drive (one per drive channel allowed), e.g. the
        rig-specific PSDs of Algorithm 3.1 (:func:`vrig.signals.rig_specific_psd`). Default:
        triangular over the identification band (QanTiM).
    divergence, min_increase : float
        Stop when the mean η0 exceeds ``divergence`` times the best so far and by more than
        ``min_increase`` percentage points (so scatter at the noise floor is not divergence).
    decimation : int, optional
        Models work at ``fs / decimation`` (zero-phase decimation of the processed records; the
        drives are interpolated back to fs before they are sent). Default: the largest integer
        keeping at least 8 samples per period of the identification band's upper edge: a record
        sampled far above its band makes the lagged regressors nearly collinear (Table 5.1).
    taper : float
        Every drive and correction is band-limited to the identification band and tapered to
        zero over its first and last ``taper`` seconds (:meth:`DriveIteration.shape`).
    seed : int
        Seeds the identification drive and every rig run (reproducible).

    Returns
    -------
    ReconstructionResult
        Every iteration played, IT00 first, and the best one. Any error after IT00 (a drive
        refused or a rig trip, an unstable simulation, a diverged inverse model, a non-finite
        drive update) stops the loop instead of propagating: ``stopped`` says where and why,
        ``error`` holds the exception and ``rejected_drive`` the drive refused or tripped.

    Raises
    ------
    ValueError
        Bad arguments (before anything is played).
    ReconstructionError
        Nothing could be played: the identification drive tripped the rig even at 1/8 of its
        amplitude, the inverse model could not be fitted or diverged on DESRES, or IT00DRV was
        refused or tripped. ``exc.result`` holds what was made (identification records, model,
        the rejected drive); ``exc.cause`` the original error.
    """
    if strategy not in ("fixed", "adaptive"):
        raise ValueError(f"strategy must be 'fixed' or 'adaptive', got {strategy!r}")
    gain = _check_loop_options(iterations, divergence, min_increase, gain, len(rig.inputs))
    engine = DriveIteration(
        rig,
        desired,
        method=method,
        bandwidth=bandwidth,
        id_duration=id_duration,
        id_rms=id_rms,
        id_psd=id_psd,
        decimation=decimation,
        taper=taper,
        seed=seed,
        **method_options,
    )
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
        strategy=strategy,
        seed=int(seed),
    )
    drive = _first_drive(engine, result)
    bar = tqdm(
        total=iterations + 1, desc=f"{rig.name}: iterations", disable=not progress, leave=False
    )
    try:
        _iterate(engine, result, drive, iterations, gain, strategy, (divergence, min_increase), bar)
    finally:
        bar.close()
    return result


def _fail(result: ReconstructionResult, engine: DriveIteration, where: str, exc: Exception) -> None:
    """Record in ``result`` why the loop stopped (and the drive refused or tripped, if any)."""
    what = str(exc) if isinstance(exc, RigLimitError) else f"{type(exc).__name__}: {exc}"
    result.stopped, result.error = f"{where}: {what}", exc
    if engine.rejected is not None:
        result.rejected_name, result.rejected_drive = engine.rejected


def _first_drive(engine: DriveIteration, result: ReconstructionResult) -> np.ndarray:
    """Identify and compute IT00DRV; any failure raises ReconstructionError with ``result``."""
    try:
        engine.identify()
        drive = engine.first_drive()
    except Exception as exc:
        stage = "identification" if engine.id_response is None else "model"
        result.id_drive, result.id_response = engine.id_drive, engine.id_response
        _fail(result, engine, stage, exc)
        raise ReconstructionError(
            f"no iteration played: {result.stopped}", result=result, cause=exc, stage=stage
        ) from exc
    result.id_drive, result.id_response = engine.id_drive, engine.id_response
    return drive


def _iterate(engine, result, drive, iterations, gain, strategy, guard, bar) -> None:
    """The loop of :func:`reconstruct` from IT00 on: fills ``result`` until the last iteration,
    divergence (``guard`` = (divergence, min_increase)) or the first error after IT00."""
    divergence, min_increase = guard
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
        result.best_iteration = int(np.argmin(np.where(np.isnan(means), np.inf, means)))
        bar.update(1)
        best = means[result.best_iteration]
        if means[-1] > divergence * best and means[-1] - best > min_increase:
            result.stopped = (
                f"IT{it:02d}: diverging (mean η0 {means[-1]:.1f} % > {divergence} x best)"
            )
            break
        if it == iterations:
            break
        try:
            if strategy == "adaptive":
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
            break
