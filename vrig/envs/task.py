"""Task of the drive-iteration environments: observation, reward and termination.

Nothing here runs the rig (that is :mod:`vrig.envs.physics`); the task turns the records of one
iteration (processed desired response, processed response, drive) into the observation, scores a
transition and says when the episode is over.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from gymnasium import spaces

from ..reconstruction.settings import MAX_ITERATIONS
from ..spectra import band_edges  # the one band rule, re-exported

__all__ = [
    "ITERATION_MAX",
    "IterationTask",
    "band_edges",
    "band_error_ratios",
    "response_change_ratios",
]

LOG_RATIO_RANGE = (-6.0, 3.0)
"""Range of the log10 band-error ratios in the observation (values beyond are clipped)."""
LOG_CHANGE_RANGE = (-3.0, 3.0)
"""Range of the log10 band-error changes in the observation (values beyond are clipped)."""
LOG_CHANGE_RATIO_RANGE = (-3.0, 3.0)
"""Range of the log10 magnitudes of the realised / predicted response-change ratios in the
observation (values beyond are clipped; their phases are in [-pi, pi] rad)."""
PERCENT_MAX = 1000.0
"""η0 and RMS errors above this [%] are clipped in the observation (``info`` has the raw ones)."""
ITERATION_MAX = MAX_ITERATIONS
"""Upper bound of the ``iteration`` observation (99: the records are named IT00..IT99; the env
does not know the episode's budget, which is the ``TimeLimit`` wrapper's); later iterations are
observed as 99."""


def band_error_ratios(desired: np.ndarray, response: np.ndarray, fs: float, edges) -> np.ndarray:
    """Per channel and band: RMS of ``desired - response`` over RMS of ``desired`` in the band.

    Returns (n_channels, n_bands); bands are assigned as in :func:`band_edges` (the first from
    0 Hz, the last to Nyquist). A band where the desired response has no power gets the ratio of
    the error's band power to the desired response's total power.

    Parameters
    ----------
    desired : ndarray (N, n_channels)
        Desired response.
    response : ndarray (N, n_channels)
        Achieved response, same shape and units.
    fs : float
        Sample rate in Hz.
    edges : array_like
        ``n_bands + 1`` band edges in Hz (from :func:`band_edges`).
    """
    d = np.asarray(desired, dtype=float)
    e = d - np.asarray(response, dtype=float)
    edges = np.asarray(edges, dtype=float)
    n_bands = edges.size - 1
    f = np.fft.rfftfreq(d.shape[0], 1.0 / fs)
    band = np.clip(np.searchsorted(edges, f, side="right") - 1, 0, n_bands - 1)
    pd = np.abs(np.fft.rfft(d, axis=0)) ** 2
    pe = np.abs(np.fft.rfft(e, axis=0)) ** 2
    sd = np.zeros((n_bands, d.shape[1]))
    se = np.zeros((n_bands, d.shape[1]))
    np.add.at(sd, band, pd)
    np.add.at(se, band, pe)
    floor = np.maximum(sd.sum(axis=0), 1e-300)
    sd = np.where(sd > 1e-12 * floor, sd, floor)
    return np.sqrt(se / sd).T


def _band_index(n_samples: int, fs: float, edges: np.ndarray) -> np.ndarray:
    """Band of each ``rfft`` bin of an ``n_samples`` record (the first band from 0 Hz, the last
    to Nyquist, as :func:`band_edges` says)."""
    f = np.fft.rfftfreq(n_samples, 1.0 / fs)
    return np.clip(np.searchsorted(edges, f, side="right") - 1, 0, edges.size - 2)


def _predicted_gain(gains, n_bands: int) -> np.ndarray:
    """The gain per band (n_bands,) the model predicts the response change with: the mean over
    drive channels of the action's gains (complex with phases), broadcast over the bands for
    per-channel or scalar gains."""
    g = np.asarray(gains)
    g = g.astype(complex if np.iscomplexobj(g) else float)
    if g.ndim == 2:
        if g.shape[1] != n_bands:
            raise ValueError(f"gains must have {n_bands} bands (columns), got shape {g.shape}")
        return g.mean(axis=0)
    if g.ndim > 1:
        raise ValueError(
            f"gains must be a scalar, (n_inputs,) or (n_inputs, n_bands), got {g.shape}"
        )
    return np.full(n_bands, g.mean() if g.size else np.nan)


def response_change_ratios(
    desired: np.ndarray, previous: np.ndarray, response: np.ndarray, fs: float, edges, gains
) -> np.ndarray:
    """Per output channel and band: the complex ratio of the realised to the predicted response
    change of one iteration (complex, (n_outputs, n_bands)).

    The update ``ITnDRV = ITn-1DRV + G (inverse(DESRES) - inverse(ITn-1RES))`` aims, through the
    inverse model, at the response change ``P = g_b (DESRES - ITn-1RES)`` in band ``b``, where
    ``g_b`` is the band's gain (the mean over drive channels of the action's gains in that band,
    complex in the phase-aware mode: exact for SISO rigs and for gains equal across drive
    channels, an approximation otherwise). The realised change is ``R = ITnRES - ITn-1RES``.
    With ``R_k``, ``P_k`` their ``rfft`` bins, the ratio of band ``b`` is the least-squares
    complex factor ``rho_b = sum_k R_k conj(P_k) / sum_k |P_k|^2`` over the band's bins (the
    per-band secant estimate: ``rho = c`` exactly when ``R = c P``). 1 means the model
    predicted the change exactly, ``|rho| < 1`` the response moved less than aimed at (the
    model overestimates the rig's gain there), a phase ``arg(rho)`` > 0 a phase lead of the
    realised change. A band where the predicted change has no power (a zero gain, or no error
    left: ``sum |P_k|^2`` at most 1e-12 of the error's total power, or no power at all) is
    given the ratio 1.

    Parameters
    ----------
    desired : ndarray (N, n_outputs)
        Desired response (DESRES, processed).
    previous : ndarray (N, n_outputs)
        Response of the previous iteration (ITn-1RES), same units.
    response : ndarray (N, n_outputs)
        Response of this iteration (ITnRES), same units.
    fs : float
        Sample rate [Hz].
    edges : array_like
        ``n_bands + 1`` band edges [Hz] (:func:`band_edges`).
    gains : float or array_like
        The gains of the update (dimensionless): a scalar, one per drive channel, or
        (n_inputs, n_bands), real or complex (magnitude and phase [rad]).

    Returns
    -------
    ndarray (n_outputs, n_bands), complex
    """
    d, prev, res = (np.asarray(x, dtype=float) for x in (desired, previous, response))
    if not (d.shape == prev.shape == res.shape and d.ndim == 2):
        raise ValueError(
            f"desired, previous and response must be (N, n_outputs) of one shape, got {d.shape}, "
            f"{prev.shape} and {res.shape}"
        )
    edges = np.asarray(edges, dtype=float)
    n_bands = edges.size - 1
    g = _predicted_gain(gains, n_bands)
    band = _band_index(d.shape[0], fs, edges)
    E = np.fft.rfft(d - prev, axis=0)
    R = np.fft.rfft(res - prev, axis=0)
    cross = np.zeros((n_bands, d.shape[1]), dtype=complex)
    power = np.zeros((n_bands, d.shape[1]))
    np.add.at(cross, band, R * np.conj(E))
    np.add.at(power, band, np.abs(E) ** 2)
    # P = g_b E in band b: sum R conj(P) = conj(g_b) cross, sum |P|^2 = |g_b|^2 power
    num = np.conj(g)[:, None] * cross
    den = np.abs(g)[:, None] ** 2 * power
    floor = 1e-12 * power.sum(axis=0)
    ok = np.isfinite(den) & (den > floor) & (den > 0)
    rho = np.ones_like(num)
    rho[ok] = num[ok] / den[ok]
    return rho.T


@dataclass(frozen=True)
class IterationTask:
    """Observation, reward and termination of a drive-iteration episode.

    Parameters
    ----------
    edges : ndarray
        Band edges [Hz] of the observation bands (and of per-band gains).
    tolerance : float
        The episode terminates (success) when every channel's η0 is at or below this [%].
    trip_penalty : float
        Reward of a step whose drive was refused or tripped the rig (the episode terminates).
    energy_penalty : float
        Weight of ``max(0, ln(E_n / E_n-1))``, the growth of the drive energy
        ``E = sum_channels (drive RMS / full scale)^2``, subtracted from the reward.
    step_penalty : float
        Constant subtracted from every step's reward (a price per iteration).
    success_bonus : float
        Added to the reward of the step that meets the tolerance (:meth:`success`: every
        channel's η0 at or below ``tolerance``; the episode terminates there), so the return
        pays for reaching the tolerance, as the iterations-to-tolerance benchmarks score.
    """

    edges: np.ndarray
    tolerance: float = 1.0
    trip_penalty: float = 5.0
    energy_penalty: float = 0.1
    step_penalty: float = 0.0
    success_bonus: float = 1.0

    def __post_init__(self):
        """Penalties and the bonus finite and >= 0, the tolerance finite and > 0 (a NaN or
        infinite penalty would make every reward NaN or infinite)."""
        if not (np.isfinite(self.tolerance) and self.tolerance > 0):
            raise ValueError(f"tolerance must be a finite number > 0 [%], got {self.tolerance!r}")
        for name in ("trip_penalty", "energy_penalty", "step_penalty", "success_bonus"):
            value = getattr(self, name)
            if not (
                isinstance(value, (int, float, np.number))
                and not isinstance(value, bool)
                and np.isfinite(value)
                and value >= 0
            ):
                raise ValueError(f"{name} must be a finite number >= 0, got {value!r}")

    @property
    def n_bands(self) -> int:
        """Number of observation bands (``len(edges) - 1``)."""
        return len(self.edges) - 1

    def observation_space(self, n_inputs: int, n_outputs: int) -> spaces.Dict:
        """The gymnasium observation space of an episode: band errors and their change
        (n_outputs, n_bands), the log10 magnitude and the phase [rad] of the realised /
        predicted response-change ratios (n_outputs, n_bands; :func:`response_change_ratios`),
        η0 and RMS error per output [%], drive RMS and peak per input (fractions of full scale)
        and the iteration number (in [0, :data:`ITERATION_MAX`]).

        Parameters
        ----------
        n_inputs, n_outputs : int
            Numbers of drive and response channels.
        """
        f32 = np.float32
        nb = self.n_bands
        return spaces.Dict(
            {
                "band_error": spaces.Box(*LOG_RATIO_RANGE, shape=(n_outputs, nb), dtype=f32),
                "band_error_change": spaces.Box(
                    *LOG_CHANGE_RANGE, shape=(n_outputs, nb), dtype=f32
                ),
                "change_ratio": spaces.Box(
                    *LOG_CHANGE_RATIO_RANGE, shape=(n_outputs, nb), dtype=f32
                ),
                "change_phase": spaces.Box(-np.pi, np.pi, shape=(n_outputs, nb), dtype=f32),
                "eta0": spaces.Box(0.0, PERCENT_MAX, shape=(n_outputs,), dtype=f32),
                "rms_error": spaces.Box(0.0, PERCENT_MAX, shape=(n_outputs,), dtype=f32),
                "drive_rms": spaces.Box(0.0, 1.0, shape=(n_inputs,), dtype=f32),
                "drive_peak": spaces.Box(0.0, 1.0, shape=(n_inputs,), dtype=f32),
                "iteration": spaces.Box(0.0, float(ITERATION_MAX), shape=(1,), dtype=f32),
            }
        )

    def measure(self, desres: np.ndarray, response: np.ndarray, fs: float) -> np.ndarray:
        """log10 band-error ratios (n_outputs, n_bands), unclipped.

        Parameters
        ----------
        desres : ndarray (N, n_outputs)
            Desired response.
        response : ndarray (N, n_outputs)
            Achieved response, same shape and units.
        fs : float
            Sample rate in Hz.
        """
        ratio = band_error_ratios(desres, response, fs, self.edges)
        return np.log10(np.maximum(ratio, 1e-300))

    def observe(
        self,
        *,
        log_band_error: np.ndarray,
        previous_log_band_error: np.ndarray | None,
        eta0: np.ndarray,
        rms_error: np.ndarray,
        drive: np.ndarray,
        full_scale: np.ndarray,
        iteration: int,
        change_ratio: np.ndarray | None = None,
    ) -> dict:
        """The observation dictionary (fresh float32 arrays, clipped to the space).

        Parameters
        ----------
        log_band_error : ndarray (n_outputs, n_bands)
            This iteration's log10 band-error ratios (from :meth:`measure`).
        previous_log_band_error : ndarray (n_outputs, n_bands) or None
            The previous iteration's (None at IT00: the change is zero).
        eta0 : ndarray (n_outputs,)
            QanTiM error η0 per response channel, in %.
        rms_error : ndarray (n_outputs,)
            RMS error per response channel, in % of the desired RMS.
        drive : ndarray (N, n_inputs)
            The drive played, in the drive channels' units.
        full_scale : ndarray (n_inputs,)
            Full scale of each drive channel, same units.
        iteration : int
            The iteration number (0: IT00; observed as at most :data:`ITERATION_MAX`).
        change_ratio : ndarray (n_outputs, n_bands), complex, optional
            This iteration's realised / predicted response-change ratios
            (:func:`response_change_ratios`); None (IT00, or a step that played nothing): 1,
            observed as log10 magnitude 0 and phase 0.
        """
        rho = np.ones_like(log_band_error) if change_ratio is None else change_ratio
        rho = np.asarray(rho, dtype=complex)
        change = (
            np.zeros_like(log_band_error)
            if previous_log_band_error is None
            else log_band_error - previous_log_band_error
        )
        rms = np.sqrt(np.mean(np.asarray(drive) ** 2, axis=0)) / full_scale
        peak = np.max(np.abs(drive), axis=0) / full_scale

        def box(x, lo, hi):
            return np.clip(np.nan_to_num(np.asarray(x, float), nan=hi), lo, hi).astype(np.float32)

        return {
            "band_error": box(log_band_error, *LOG_RATIO_RANGE),
            "band_error_change": box(change, *LOG_CHANGE_RANGE),
            "change_ratio": box(np.log10(np.maximum(np.abs(rho), 1e-300)), *LOG_CHANGE_RATIO_RANGE),
            "change_phase": box(np.angle(rho), -np.pi, np.pi),
            "eta0": box(eta0, 0.0, PERCENT_MAX),
            "rms_error": box(rms_error, 0.0, PERCENT_MAX),
            "drive_rms": box(rms, 0.0, 1.0),
            "drive_peak": box(peak, 0.0, 1.0),
            "iteration": np.array([min(iteration, ITERATION_MAX)], dtype=np.float32),
        }

    @staticmethod
    def drive_energy(drive: np.ndarray, full_scale: np.ndarray) -> float:
        """Drive energy ``E = sum_channels (drive RMS / full scale)^2`` (dimensionless).

        Parameters
        ----------
        drive : ndarray (N, n_inputs)
            A drive, in the drive channels' units.
        full_scale : ndarray (n_inputs,)
            Full scale of each drive channel, same units.
        """
        return float(np.sum(np.mean(np.asarray(drive) ** 2, axis=0) / full_scale**2))

    def reward(
        self,
        eta_before: np.ndarray,
        eta_after: np.ndarray,
        energy_before: float,
        energy_after: float,
    ) -> float:
        """``ln(mean η0 before) - ln(mean η0 after) - energy_penalty * max(0, ln(E_after /
        E_before)) - step_penalty``, plus ``success_bonus`` when ``eta_after`` meets the
        tolerance (:meth:`success`).

        Parameters
        ----------
        eta_before, eta_after : ndarray (n_outputs,)
            η0 per response channel before and after the step, in %.
        energy_before, energy_after : float
            Drive energy (:meth:`drive_energy`) before and after the step.
        """
        gain = np.log(max(float(np.mean(eta_before)), 1e-12)) - np.log(
            max(float(np.mean(eta_after)), 1e-12)
        )
        growth = max(0.0, np.log(max(energy_after, 1e-300) / max(energy_before, 1e-300)))
        bonus = self.success_bonus if self.success(eta_after) else 0.0
        return float(gain - self.energy_penalty * growth - self.step_penalty + bonus)

    def success(self, eta0: np.ndarray) -> bool:
        """True when every channel's η0 is at or below ``tolerance``.

        Parameters
        ----------
        eta0 : ndarray (n_outputs,)
            η0 per response channel, in %.
        """
        return bool(np.all(np.asarray(eta0) <= self.tolerance))
