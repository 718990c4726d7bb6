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

__all__ = ["ITERATION_MAX", "IterationTask", "band_edges", "band_error_ratios"]

LOG_RATIO_RANGE = (-6.0, 3.0)
"""Range of the log10 band-error ratios in the observation (values beyond are clipped)."""
LOG_CHANGE_RANGE = (-3.0, 3.0)
"""Range of the log10 band-error changes in the observation (values beyond are clipped)."""
PERCENT_MAX = 1000.0
"""η0 and RMS errors above this [%] are clipped in the observation (``info`` has the raw ones)."""
ITERATION_MAX = MAX_ITERATIONS
"""Upper bound of the ``iteration`` observation (99: the records are named IT00..IT99; the env
does not know the episode's budget, which is the ``TimeLimit`` wrapper's); later iterations are
observed as 99."""


def band_edges(band: tuple[float, float], n_bands: int) -> np.ndarray:
    """``n_bands + 1`` log-spaced band edges [Hz] over the simulation ``band``.

    A band starting at 0 Hz gets ``[0, hi / 2**(n-1), ..., hi / 2, hi]`` (octaves below ``hi``,
    the first band reaching down to DC); otherwise ``geomspace(lo, hi, n_bands + 1)``. As in
    :func:`vrig.reconstruction.band_gains`, the first band also holds everything below
    ``edges[1]`` and the last everything above ``edges[-2]``.

    Parameters
    ----------
    band : tuple of float
        ``(low, high)`` simulation band in Hz, ``0 <= low < high``.
    n_bands : int
        Number of bands (>= 1).
    """
    if not isinstance(n_bands, (int, np.integer)) or n_bands < 1:
        raise ValueError(f"n_bands must be a positive integer, got {n_bands!r}")
    lo, hi = float(band[0]), float(band[1])
    if not (0 <= lo < hi):
        raise ValueError(f"band must satisfy 0 <= low < high, got {band}")
    if lo <= 0:
        return np.concatenate([[0.0], hi / 2.0 ** np.arange(n_bands - 1, -1, -1)])
    return np.geomspace(lo, hi, n_bands + 1)


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
    """

    edges: np.ndarray
    tolerance: float = 1.0
    trip_penalty: float = 5.0
    energy_penalty: float = 0.1
    step_penalty: float = 0.0

    def __post_init__(self):
        """Penalties finite and >= 0, the tolerance finite and > 0 (a NaN or infinite penalty
        would make every reward NaN or infinite)."""
        if not (np.isfinite(self.tolerance) and self.tolerance > 0):
            raise ValueError(f"tolerance must be a finite number > 0 [%], got {self.tolerance!r}")
        for name in ("trip_penalty", "energy_penalty", "step_penalty"):
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
        (n_outputs, n_bands), η0 and RMS error per output [%], drive RMS and peak per input
        (fractions of full scale) and the iteration number (in [0, :data:`ITERATION_MAX`]).

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
        """
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
        E_before)) - step_penalty``.

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
        return float(gain - self.energy_penalty * growth - self.step_penalty)

    def success(self, eta0: np.ndarray) -> bool:
        """True when every channel's η0 is at or below ``tolerance``.

        Parameters
        ----------
        eta0 : ndarray (n_outputs,)
            η0 per response channel, in %.
        """
        return bool(np.all(np.asarray(eta0) <= self.tolerance))
