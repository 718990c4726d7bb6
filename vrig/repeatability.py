"""Rig repeatability (reference text §3.1): the same drive played several times.

The rig is driven n times (the text uses five) with the same random drive; the mean response is
the reference. Three measures, per response channel:

* :func:`repeatability_number` — the scalar of §3.1 (Tables 3.1-3.3): ``100 - mean_i η0(ȳ, y_i)``
  [%], the mean DC-corrected QanTiM error (eq. 5-28) of each run against the mean response; 100 %
  is perfect. Given ``band``, the responses are first processed to the *simulation bandwidth*
  (zero-phase Butterworth, as QanTiM's response processing applies to every response record,
  §3.4 and App. G): the text states each table's number "for a simulation bandwidth" (0-10 Hz
  damper, 0-30 Hz motorcycle, 0-25 Hz radiator), while the recorded responses reach up to the
  DAQ's anti-alias filter (333 Hz on the radiator, §3.1.4). The text prints no formula for the
  scalar (its Fig. 3.1 is a diagram); the error measure is the one it uses for every comparison
  of two responses (eq. 5-28), the band the one it names with each table.
* :func:`repeatability_function` — ``R_f(f) = 100 (1 - mean_i |P_i(f) - P̄(f)| / P̄(f))`` [%]:
  the spread of each run's PSD about the mean PSD, per frequency line (§3.1, Fig. 3.2). As the
  text notes, comparing PSD amplitudes rates pure noise as "repeatable"; see the next measure.
* :func:`signal_to_noise` — the more sensitive measure the text asks for: per frequency line,
  ``10 log10(P_mean(f) / P_dev(f))`` [dB], the PSD of the mean response against the PSD of the
  run-to-run deviation (unbiased: scaled by n/(n-1)). It separates the repeatable part of the
  response from the non-repeatable part in every band; bands holding only noise score far
  below 0 dB (floored at -60 dB).
"""

from __future__ import annotations

import numpy as np
from scipy import signal

from identification import metrics

__all__ = ["repeatability_function", "repeatability_number", "signal_to_noise"]


def _runs(runs) -> np.ndarray:
    arrays = [np.asarray(getattr(r, "data", r), dtype=float) for r in runs]
    if len(arrays) < 2:
        raise ValueError("repeatability needs at least 2 runs of the same drive (the text uses 5)")
    shapes = {a.shape for a in arrays}
    if len(shapes) != 1:
        raise ValueError(f"all runs must have the same shape, got {sorted(shapes)}")
    a = np.stack([x[:, None] if x.ndim == 1 else x for x in arrays])  # (n_runs, N, channels)
    if not np.all(np.isfinite(a)):
        raise ValueError("runs contain NaN or inf")
    return a


def _band_limited(a: np.ndarray, fs, band, order: int) -> np.ndarray:
    """Runs (n_runs, N, ch) processed to the simulation bandwidth: zero-phase Butterworth."""
    if fs is None or not np.isfinite(fs) or fs <= 0:
        raise ValueError(f"band needs the sample rate fs > 0 [Hz], got {fs}")
    lo, hi = (float(b) for b in band)
    if not (0 <= lo < hi < fs / 2):
        raise ValueError(f"band must be (low, high) Hz with 0 <= low < high < fs/2, got {band}")
    if lo > 0:
        sos = signal.butter(order, [lo, hi], btype="bandpass", fs=fs, output="sos")
    else:
        sos = signal.butter(order, hi, btype="lowpass", fs=fs, output="sos")
    x = a - a.mean(axis=1, keepdims=True)
    return signal.sosfiltfilt(sos, x, axis=1, padlen=min(3 * (2 * len(sos) + 1), a.shape[1] - 1))


def repeatability_number(runs, *, fs: float | None = None, band=None, order: int = 4) -> np.ndarray:
    """Scalar repeatability per channel [%]: ``100 - mean_i η0(mean response, run i)``.

    With ``band`` the runs are first processed to that simulation bandwidth (the text's number,
    Tables 3.1-3.3); without it the full recorded band counts (everything up to the DAQ's
    anti-alias filter, out-of-band noise and rattle included).

    Parameters
    ----------
    runs : sequence of TimeHistory or array_like
        Two or more records of the same drive, each (N,) or (N, channels), same shape.
    fs : float, optional
        Sample rate in Hz; required with ``band`` (a TimeHistory's own ``fs`` is used if omitted).
    band : (low, high) Hz, optional
        Simulation bandwidth; ``low = 0`` gives a low-pass.
    order : int, optional
        Butterworth order of the zero-phase filter (applied forward and backward).

    Returns
    -------
    ndarray (channels,)
        Repeatability number [%], 100 for identical runs.
    """
    a = _runs(runs)
    if band is not None:
        if fs is None:
            fs = getattr(runs[0], "fs", None)
        a = _band_limited(a, fs, band, order)
    mean = a.mean(axis=0)
    errs = np.array([metrics.qantim_fit_dc(mean, r) for r in a])
    return 100.0 - errs.mean(axis=0)


def _psd(x, fs, nperseg):
    return signal.welch(x, fs=fs, nperseg=nperseg, axis=-2, detrend="constant")


def repeatability_function(runs, fs: float, *, nperseg: int = 256):
    """Frequency-related repeatability ``R_f(f)`` [%] per channel: ``(f, R_f)`` with R_f (F, ch).

    Parameters
    ----------
    runs : sequence of TimeHistory or array_like
        Two or more records of the same drive, each (N,) or (N, channels), same shape.
    fs : float
        Sample rate in Hz.
    nperseg : int, optional
        Welch segment length in samples (sets the frequency resolution ``fs / nperseg`` Hz).
    """
    a = _runs(runs)
    f, P = _psd(a, fs, nperseg)  # (n_runs, F, channels)
    Pm = P.mean(axis=0)
    with np.errstate(divide="ignore", invalid="ignore"):
        rf = 100.0 * (1.0 - np.abs(P - Pm).mean(axis=0) / Pm)
    return f, np.where(Pm > 0, rf, np.nan)


def signal_to_noise(runs, fs: float, *, nperseg: int = 256):
    """Per-frequency repeatable-to-non-repeatable ratio [dB]: ``(f, snr)`` with snr (F, ch).

    Parameters
    ----------
    runs : sequence of TimeHistory or array_like
        Two or more records of the same drive, each (N,) or (N, channels), same shape.
    fs : float
        Sample rate in Hz.
    nperseg : int, optional
        Welch segment length in samples (sets the frequency resolution ``fs / nperseg`` Hz).
    """
    a = _runs(runs)
    n = a.shape[0]
    mean = a.mean(axis=0)
    f, p_mean = _psd(mean, fs, nperseg)
    _, p_dev = _psd(a - mean, fs, nperseg)
    p_dev = p_dev.mean(axis=0) * n / (n - 1)  # deviation from the sample mean is biased low
    # the mean of n runs still carries 1/n of the noise power
    p_signal = np.maximum(p_mean - p_dev / n, 1e-6 * p_dev)  # floor: -60 dB
    with np.errstate(divide="ignore", invalid="ignore"):
        return f, 10.0 * np.log10(np.maximum(p_signal, 1e-300) / np.maximum(p_dev, 1e-300))
