"""Response processing (GPREPRO, §3.4 and App. G): zero-phase band-pass, de-trend, DC removal.

The reference text's rule: one *simulation bandwidth* is applied to every record of a
reconstruction (IDDRV, IDRES, DESRES and every ITxxRES), and the identification band is somewhat
broader than the desired response's (20 % by default here, :func:`identification_band`).
Filters are zero-phase (forward-backward Butterworth, scipy ``sosfiltfilt``), time is axis 0.
"""

from __future__ import annotations

import functools
from collections.abc import Callable

import numpy as np
from scipy import signal

from identification import split_spectra

from .timehistory import TimeHistory

__all__ = [
    "band_gains",
    "band_split",
    "check_band",
    "decimate",
    "f2d",
    "gprepro",
    "identification_band",
]


def check_band(band, fs: float, name: str = "band") -> tuple[float, float]:
    """A simulation band checked: two finite numbers with ``0 <= low < high <= fs/2``
    (Nyquist); the one check of every band a record is processed over.

    Parameters
    ----------
    band : (float, float)
        The band [Hz].
    fs : float
        The sample rate [Hz].
    name : str
        What the message calls it (``"band"``, ``"bandwidth"``).

    Returns
    -------
    (float, float)

    Raises
    ------
    ValueError
        Not two numbers, or outside ``0 <= low < high <= fs/2``.
    """
    try:
        lo, hi = (float(b) for b in band)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be (low, high) in Hz, got {band!r}") from None
    if not (np.isfinite(lo) and np.isfinite(hi) and 0 <= lo < hi <= fs / 2):
        raise ValueError(
            f"{name} must satisfy 0 <= low < high <= fs/2 = {fs / 2:g} Hz (Nyquist), got "
            f"({lo:g}, {hi:g})"
        )
    return lo, hi


def _check(th):
    if not isinstance(th, TimeHistory):
        raise TypeError(f"expected a TimeHistory, got {type(th).__name__}")


def _sos(band, fs, order):
    lo, hi = band
    nyq = fs / 2
    if not (0 <= lo < hi):
        raise ValueError(f"band must be (low, high) Hz with 0 <= low < high, got {band}")
    if lo >= nyq:
        raise ValueError(f"band {band} Hz lies above Nyquist ({nyq:g} Hz)")
    if lo <= 0 and hi >= nyq:
        return None
    return _butter(float(lo), float(hi), float(fs), int(order)).copy()  # the cache's stays


@functools.lru_cache(maxsize=64)
def _butter(lo: float, hi: float, fs: float, order: int) -> np.ndarray:
    """The Butterworth SOS of :func:`_sos` (a checked band), designed once per band, rate and
    order (a drive iteration processes every record over one band)."""
    if lo <= 0:
        sos = signal.butter(order, hi, btype="lowpass", fs=fs, output="sos")
    elif hi >= fs / 2:
        sos = signal.butter(order, lo, btype="highpass", fs=fs, output="sos")
    else:
        sos = signal.butter(order, [lo, hi], btype="bandpass", fs=fs, output="sos")
    return sos


def gprepro(
    th: TimeHistory,
    band: tuple[float, float],
    *,
    order: int = 4,
    detrend: bool = True,
    remove_dc: bool = True,
) -> TimeHistory:
    """General response pre-processing: de-trend, DC removal and a zero-phase band-pass.

    Parameters
    ----------
    th : TimeHistory
        The record to process (any units; its sample rate sets the filter).
    band : (low, high) Hz
        Simulation bandwidth; ``low = 0`` gives a low-pass, ``high >= fs/2`` a high-pass.
    order : int
        Butterworth order of each pass (the zero-phase result has twice the attenuation slope).
    detrend, remove_dc : bool
        Remove a linear trend / the mean before filtering.
    """
    _check(th)
    x = np.array(th.data)
    if detrend:
        x = signal.detrend(x, axis=0, type="linear")
    elif remove_dc:
        x = x - x.mean(axis=0)
    sos = _sos(band, th.fs, order)
    if sos is not None:
        padlen = min(3 * (2 * len(sos) + 1), x.shape[0] - 1)
        x = signal.sosfiltfilt(sos, x, axis=0, padlen=padlen)
    if remove_dc:
        x = x - x.mean(axis=0)
    return th.with_data(x)


def identification_band(band: tuple[float, float], *, widen: float = 0.2, fs: float | None = None):
    """The identification band: the simulation band widened by ``widen`` (20 %) at both edges.

    The low edge moves down by ``widen`` of itself, the high edge up (capped below Nyquist).

    Parameters
    ----------
    band : tuple of float
        ``(low, high)`` simulation band in Hz.
    widen : float, optional
        Fraction of each edge by which the band is widened (0.2: 20 %).
    fs : float, optional
        Sample rate in Hz; when given the high edge is kept below Nyquist.
    """
    lo, hi = band
    if widen < 0:
        raise ValueError("widen must be >= 0")
    hi2 = hi * (1 + widen)
    if fs is not None:
        hi2 = min(hi2, 0.45 * fs)
    return (lo / (1 + widen), hi2)


def band_split(
    th: TimeHistory, split_hz: float, *, order: int = 4
) -> tuple[TimeHistory, TimeHistory]:
    """Split a record at ``split_hz`` into complementary low and high bands (split spectra, §3.2).

    The low band is a zero-phase low-pass; the high band is the remainder, so
    ``low + high == th`` exactly. The split is :func:`identification.split_spectra.band_split`,
    the one the forward :class:`identification.SplitSpectraModel` uses (its docstring says why
    the split is complementary).

    Parameters
    ----------
    th : TimeHistory
        The record to split.
    split_hz : float
        Split frequency in Hz, in (0, fs/2).
    order : int, optional
        Poles of the Butterworth low-pass (per pass).
    """
    _check(th)
    if not 0 < split_hz < th.fs / 2:
        raise ValueError(
            f"split frequency must lie in (0, fs/2 = {th.fs / 2:g}) Hz, got {split_hz}"
        )
    low, high = split_spectra.band_split(th.data, split_hz, th.fs, order=order)
    return th.with_data(low), th.with_data(high)


def decimate(th: TimeHistory, factor: int) -> TimeHistory:
    """Reduce the sample rate by an integer ``factor`` (zero-phase anti-alias FIR).

    Parameters
    ----------
    th : TimeHistory
        The record to decimate.
    factor : int
        Decimation factor (>= 1; 1 returns ``th`` itself); the new rate is ``fs / factor`` Hz.
    """
    _check(th)
    if not isinstance(factor, (int, np.integer)) or factor < 1:
        raise ValueError(f"factor must be a positive integer, got {factor!r}")
    if factor == 1:
        return th
    y = signal.decimate(th.data, factor, ftype="fir", axis=0, zero_phase=True)
    return TimeHistory(y, th.fs / factor, th.names, th.units)


def f2d(
    field: TimeHistory, transform: Callable[[TimeHistory], TimeHistory] | None = None
) -> TimeHistory:
    """Field-to-desired processing (F2D): the user's transform of the field record, checked.

    ``transform`` maps a TimeHistory to a TimeHistory (editing, scaling, channel mapping,
    resampling); it must keep the record finite. Without one, the field record is the desired
    response.

    Parameters
    ----------
    field : TimeHistory
        The field (or pseudo-field) record.
    transform : callable, optional
        ``transform(field) -> TimeHistory``; None: the field record unchanged.
    """
    _check(field)
    out = field if transform is None else transform(field)
    if not isinstance(out, TimeHistory):
        raise TypeError(f"the F2D transform must return a TimeHistory, got {type(out).__name__}")
    return out


def band_gains(x: np.ndarray, fs: float, gains: np.ndarray, edges) -> np.ndarray:
    """Scale (and, with complex gains, phase-shift) each frequency band of each channel of ``x``.

    ``gains`` is (n_channels, n_bands); band ``b`` holds the frequencies in
    ``[edges[b], edges[b + 1])`` (the first band starts at 0 Hz, the last runs to Nyquist,
    whatever ``edges[0]`` / ``edges[-1]`` say). The scaling is a piecewise-constant weighting of the
    record's (zero-padded, one-sided: ``rfft``) spectrum, so gains equal across bands give exactly
    ``gain * x``.

    A complex gain ``g * exp(1j * phi)`` multiplies the band's positive-frequency bins: a sinusoid
    ``cos(2 pi f t)`` in the band becomes ``g * cos(2 pi f t + phi)`` (``phi > 0``: phase lead,
    ``phi < 0``: a delay of ``-phi / (2 pi f)`` s). The DC and Nyquist bins get the magnitude
    ``|g|`` only, so the result stays real. Complex gains whose imaginary parts are all zero are
    the real gains, bit for bit.

    Parameters
    ----------
    x : ndarray (n_samples, n_channels)
        The record (e.g. a drive correction).
    fs : float
        Sample rate [Hz].
    gains : ndarray (n_channels, n_bands), real or complex
        Gain per channel and band (dimensionless; complex: magnitude and phase [rad]).
    edges : sequence of float
        ``n_bands + 1`` band edges [Hz].

    Returns
    -------
    ndarray (n_samples, n_channels)
    """
    x = np.asarray(x, dtype=float)
    gains = np.asarray(gains)
    if np.iscomplexobj(gains) and not np.any(gains.imag):
        gains = gains.real
    complex_gains = np.iscomplexobj(gains)
    gains = gains.astype(complex if complex_gains else float)
    edges = np.asarray(edges, dtype=float)
    if gains.ndim != 2 or gains.shape[0] != x.shape[1] or gains.shape[1] != edges.size - 1:
        raise ValueError(
            f"gains must be (n_channels={x.shape[1]}, n_bands={edges.size - 1}), got {gains.shape}"
        )
    if not complex_gains and np.all(gains == gains[:, :1]):
        return x * gains[:, 0]
    n = x.shape[0]
    X = np.fft.rfft(x, n=2 * n, axis=0)
    f = np.fft.rfftfreq(2 * n, 1.0 / fs)
    band = np.clip(np.searchsorted(edges, f, side="right") - 1, 0, edges.size - 2)
    weight = gains[:, band].T
    if complex_gains:  # DC and Nyquist (2n is even): the magnitude only, the record stays real
        weight[[0, -1]] = np.abs(weight[[0, -1]])
    return np.fft.irfft(X * weight, n=2 * n, axis=0)[:n]
