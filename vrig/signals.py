"""Drive signals: random drives from a PSD, sine sweeps, rig-specific PSDs (Algorithm 3.1).

Random drives are synthesised in the frequency domain: each spectral line gets the amplitude of
the target PSD and a random phase (independent per channel, so multi-channel drives are
uncorrelated), and lines outside the band are exactly zero. The result is scaled to the
requested RMS or peak. All functions take ``fs`` in Hz and a seed (int or Generator).
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Sequence

import numpy as np
from scipy import signal

from identification.budget import check_allocation, product

from .timehistory import TimeHistory

__all__ = [
    "control_noise_psd",
    "flat_psd",
    "flicker_sos",
    "one_over_f_psd",
    "random_drive",
    "rig_specific_psd",
    "sine_sweep",
    "triangular_psd",
]


def _check_record(n_samples, fs, channels: int, what: str) -> None:
    """Validate a generated record's size before anything is allocated: ``n_samples`` an
    integer >= 8, ``fs`` finite > 0, and samples x channels x 8 bytes within the memory budget
    (:mod:`identification.budget`, 2 GiB per array)."""
    if not isinstance(n_samples, (int, np.integer)) or isinstance(n_samples, bool):
        raise ValueError(f"n_samples must be an integer, got {n_samples!r}")
    if n_samples < 8:
        raise ValueError(f"n_samples must be >= 8, got {n_samples}")
    if not (isinstance(fs, (int, float, np.integer, np.floating)) and np.isfinite(fs) and fs > 0):
        raise ValueError(f"fs must be a finite sample rate > 0 Hz, got {fs!r}")
    check_allocation(
        product(n_samples, channels, 8),
        f"{what} of {int(n_samples):,} samples x {channels} channel(s) x 8 bytes",
        "generate a shorter record",
    )


def _band(f, band):
    lo, hi = band
    if not (0 <= lo < hi):
        raise ValueError(f"band must be (low, high) Hz with 0 <= low < high, got {band}")
    return (f >= lo) & (f <= hi)


def flat_psd(band: tuple[float, float]) -> Callable[[np.ndarray], np.ndarray]:
    """Flat (white) PSD inside ``band`` (Hz), zero outside.

    Parameters
    ----------
    band : tuple of float
        ``(low, high)`` edges of the band, in Hz.
    """

    def psd(f):
        return _band(f, band).astype(float)

    return psd


def triangular_psd(band: tuple[float, float]) -> Callable[[np.ndarray], np.ndarray]:
    """Triangular PSD: largest at the band's low edge, falling linearly to zero at its high edge
    (the identification PSD QanTiM prefers, §3.3, Fig. 3.18b).

    Parameters
    ----------
    band : tuple of float
        ``(low, high)`` edges of the band, in Hz.
    """
    lo, hi = band

    def psd(f):
        return np.where(_band(f, band), (hi - f) / (hi - lo), 0.0)

    return psd


def one_over_f_psd(band: tuple[float, float], n: float = 1.0) -> Callable[[np.ndarray], np.ndarray]:
    """``1/f^n`` PSD inside ``band`` (Hz) (the frequency-domain tools' default, §3.3, Fig. 3.18a).

    A band starting at 0 Hz is held flat below its first non-zero line.

    Parameters
    ----------
    band : tuple of float
        ``(low, high)`` edges of the band, in Hz.
    n : float, optional
        Exponent of the frequency (1: pink, 2: brown).
    """
    lo = band[0]

    def psd(f):
        f_eff = np.maximum(f, max(lo, 1e-3))
        return np.where(_band(f, band), f_eff ** (-float(n)), 0.0)

    return psd


def control_noise_psd(corner_hz: float, *, low_hz: float = 0.1) -> Callable[[np.ndarray], np.ndarray]:
    """Flicker PSD of a controller's low-frequency noise: ``1/f`` above ``low_hz``, rolled off
    as a second-order low-pass above ``corner_hz``: ``S(f) = f^-1 / (1 + (f/f_c)^4)`` (0 below
    ``low_hz``).

    Parameters
    ----------
    corner_hz : float
        Corner frequency f_c of the roll-off [Hz], > 0.
    low_hz : float, optional
        Lowest frequency of the noise [Hz], > 0 (below it the record is too short to hold it).
    """
    if not (np.isfinite(corner_hz) and corner_hz > 0 and np.isfinite(low_hz) and low_hz > 0):
        raise ValueError(f"corner_hz and low_hz must be > 0 Hz, got {corner_hz!r}, {low_hz!r}")

    def psd(f):
        f = np.asarray(f, dtype=float)
        return np.where(
            f >= low_hz, 1.0 / (np.maximum(f, low_hz) * (1.0 + (f / corner_hz) ** 4)), 0.0
        )

    return psd


def flicker_sos(corner_hz: float, fs: float, *, low_hz: float = 0.1) -> tuple[np.ndarray, float]:
    """A causal filter whose output, for white noise of unit variance per sample, has the
    spectrum of :func:`control_noise_psd`: 1/f from ``low_hz`` (flat below) to ``corner_hz``,
    a second-order low-pass beyond.

    The 1/f slope (-10 dB per decade) comes from real poles and zeros alternating every quarter
    decade up to ten times the corner (or fs/4) (each pole-zero pair averages half a pole's -20 dB per decade; ripple about 0.3 dB),
    mapped to discrete time by the bilinear transform, then a second-order Butterworth low-pass
    at ``corner_hz``. Causal and with state, so a record filtered in chunks (``sosfilt`` with
    ``zi``) is the record filtered in one piece.

    Parameters
    ----------
    corner_hz : float
        Corner frequency of the roll-off [Hz], ``low_hz < corner_hz < fs / 2``.
    fs : float
        Sample rate of the filter [Hz].
    low_hz : float, optional
        Lowest frequency of the 1/f band [Hz], > 0.

    Returns
    -------
    (sos, rms) : ndarray, float
        Second-order sections, and the RMS of the output per unit-variance white input. The
        design is made once per ``(corner_hz, fs, low_hz)`` and kept (a rig designs the same
        filter for every run); each call returns its own copy of the sections.
    """
    if not (np.isfinite(fs) and fs > 0 and 0 < low_hz < corner_hz < fs / 2):
        raise ValueError(
            f"need 0 < low_hz < corner_hz < fs/2, got low_hz={low_hz!r}, "
            f"corner_hz={corner_hz!r}, fs={fs!r}"
        )
    sos, rms = _flicker_design(float(corner_hz), float(fs), float(low_hz))
    return sos.copy(), rms  # the cache's stays as designed


@functools.lru_cache(maxsize=64)
def _flicker_design(corner_hz: float, fs: float, low_hz: float) -> tuple[np.ndarray, float]:
    """The design of :func:`flicker_sos` (checked arguments), made once per corner, rate and
    low edge; its sections are read-only (callers get copies)."""
    top = min(10.0 * corner_hz, fs / 4)  # the 1/f chain runs on under the roll-off
    edges = low_hz * 10.0 ** np.arange(0.0, np.log10(top / low_hz) + 0.25, 0.25)
    poles, zeros = edges[0::2], edges[1::2][: edges[0::2].size]
    if zeros.size < poles.size:
        zeros = np.append(zeros, poles[-1] * 10**0.25)
    z, p = -2 * np.pi * zeros, -2 * np.pi * poles
    k = np.prod(p) / np.prod(z)  # unit gain at DC
    zd, pd, kd = signal.bilinear_zpk(z, p, k, fs)
    sos = np.vstack(
        [signal.zpk2sos(zd, pd, kd), signal.butter(2, corner_hz, fs=fs, output="sos")]
    )
    f = np.concatenate([[0.0], np.geomspace(low_hz * 1e-3, fs / 2, 20000)])
    _, h = signal.sosfreqz(sos, worN=f, fs=fs)
    rms = np.sqrt(2.0 / fs * np.trapezoid(np.abs(h) ** 2, f))
    sos.setflags(write=False)
    return sos, float(rms)


def random_drive(
    psd,
    n_samples: int,
    fs: float,
    *,
    channels: int = 1,
    rms=None,
    peak=None,
    seed=None,
    names: Sequence[str] | None = None,
    unit: str = "-",
) -> TimeHistory:
    """Random drive with the PSD shape ``psd`` (a function of f in Hz, or one per channel).

    Parameters
    ----------
    psd : callable or sequence of callables
        PSD shape(s); only the shape matters (the level is set by ``rms`` or ``peak``).
    n_samples, fs : int, float
        Length and sample rate.
    channels : int
        Number of uncorrelated channels (independent random phases).
    rms, peak : float or sequence, optional
        Scale each channel to this RMS or this peak magnitude (give one; default RMS 1).
    seed : int or numpy.random.Generator, optional
        Random seed or generator of the phases (default: fresh entropy).
    names : sequence of str, optional
        Channel names of the returned TimeHistory (default ``drive1, drive2, ...``).
    unit : str, optional
        Unit of every channel of the returned TimeHistory.
    """
    if not isinstance(channels, (int, np.integer)) or isinstance(channels, bool) or channels < 1:
        raise ValueError(f"channels must be a positive integer, got {channels!r}")
    _check_record(n_samples, fs, int(channels), "the random drive")
    if rms is not None and peak is not None:
        raise ValueError("give rms or peak, not both")
    for name, level in (("rms", rms), ("peak", peak)):
        if level is not None and not np.all(
            np.isfinite(np.asarray(level, float)) & (np.asarray(level, float) >= 0)
        ):
            raise ValueError(f"{name} must be finite and >= 0 for every channel, got {level!r}")
    shapes = list(psd) if isinstance(psd, Sequence) else [psd] * channels
    if len(shapes) != channels:
        raise ValueError(f"{len(shapes)} PSDs for {channels} channels")
    rng = np.random.default_rng(seed)
    f = np.fft.rfftfreq(n_samples, 1.0 / fs)
    out = np.empty((n_samples, channels))
    for k, shape in enumerate(shapes):
        level = np.asarray(shape(f), dtype=float)
        if level.shape != f.shape or np.any(level < 0) or not np.all(np.isfinite(level)):
            raise ValueError("the PSD function must return finite, non-negative values per line")
        if not np.any(level > 0):
            raise ValueError(
                "the PSD is zero at every spectral line: widen the band or lengthen the record"
            )
        spectrum = np.sqrt(level) * np.exp(2j * np.pi * rng.random(f.size))
        spectrum[0] = np.sqrt(level[0])  # real DC line
        if n_samples % 2 == 0:
            spectrum[-1] = np.sqrt(level[-1]) * rng.choice([-1.0, 1.0])  # real Nyquist line
        x = np.fft.irfft(spectrum, n=n_samples)
        out[:, k] = x / np.sqrt(np.mean(x**2))
    if peak is not None:
        out *= np.broadcast_to(np.asarray(peak, float), (channels,)) / np.abs(out).max(axis=0)
    elif rms is not None:
        out *= np.broadcast_to(np.asarray(rms, float), (channels,))
    return TimeHistory(
        out, fs, names or [f"drive{k + 1}" for k in range(channels)], [unit] * channels
    )


def sine_sweep(
    f0: float,
    f1: float,
    duration: float,
    fs: float,
    *,
    amplitude: float = 1.0,
    kind: str = "linear",
    name: str = "sweep",
    unit: str = "-",
) -> TimeHistory:
    """Linear or logarithmic sine sweep from ``f0`` to ``f1`` Hz (scipy.signal.chirp).

    Parameters
    ----------
    f0, f1 : float
        Start and end frequencies in Hz (``0 <= f0 < fs/2``, ``0 < f1 <= fs/2``; ``f0 > 0`` for a
        logarithmic sweep).
    duration : float
        Length of the sweep in s.
    fs : float
        Sample rate in Hz.
    amplitude : float, optional
        Peak amplitude, in ``unit``.
    kind : {"linear", "log"}, optional
        Linear or logarithmic frequency progression.
    name : str, optional
        Channel name of the returned TimeHistory.
    unit : str, optional
        Channel unit of the returned TimeHistory.
    """
    if kind not in ("linear", "log"):
        raise ValueError(f"kind must be 'linear' or 'log', got {kind!r}")
    if not (np.isfinite(duration) and duration > 0):
        raise ValueError(f"duration must be a finite number of seconds > 0, got {duration!r}")
    if not (np.isfinite(fs) and fs > 0):
        raise ValueError(f"fs must be a finite sample rate > 0 Hz, got {fs!r}")
    _check_record(max(round(duration * fs), 8), fs, 1, "the sine sweep")
    if not (0 <= f0 < fs / 2 and 0 < f1 <= fs / 2) or (kind == "log" and f0 <= 0):
        raise ValueError(
            f"sweep {f0}-{f1} Hz must lie in (0, fs/2 = {fs / 2}] (log sweeps need f0 > 0)"
        )
    t = np.arange(round(duration * fs)) / fs
    method = "linear" if kind == "linear" else "logarithmic"
    x = amplitude * signal.chirp(t, f0=f0, t1=duration, f1=f1, method=method, phi=-90)
    return TimeHistory(x, fs, [name], [unit])


def rig_specific_psd(sweep_drive, sweep_response, *, nperseg: int = 256, floor: float = 0.02):
    """Rig-specific identification PSDs from a low-amplitude sweep (Algorithm 3.1).

    For each channel k: ``psd_jk = mean(drvpsd_k) * (2 - respsd_jk / mean(respsd_k))``: the drive
    PSD is lowered where the response is resonant and raised where it is weak. Values below
    ``floor`` times the mean drive PSD are raised to it (the formula goes negative at strong
    resonances; a PSD must stay non-negative).

    Parameters
    ----------
    sweep_drive, sweep_response : TimeHistory
        The sweep drives and the rig's responses (same number of channels: channel k of the
        response is paired with drive k, as in the text).
    nperseg : int, optional
        Welch segment length in samples.
    floor : float, optional
        Lowest PSD value, as a fraction of the mean drive PSD.

    Returns
    -------
    list of callables, one PSD shape per channel (interpolating the spectral lines).
    """
    if not isinstance(sweep_drive, TimeHistory) or not isinstance(sweep_response, TimeHistory):
        raise TypeError("sweep_drive and sweep_response must be TimeHistory records")
    if sweep_drive.n_channels != sweep_response.n_channels:
        raise ValueError(
            f"Algorithm 3.1 pairs drive k with response k: got {sweep_drive.n_channels} drives and "
            f"{sweep_response.n_channels} responses"
        )
    if sweep_drive.fs != sweep_response.fs or sweep_drive.n_samples != sweep_response.n_samples:
        raise ValueError("sweep drive and response must have the same fs and length")
    fs = sweep_drive.fs
    f, drv = signal.welch(sweep_drive.data, fs=fs, nperseg=nperseg, axis=0)
    _, res = signal.welch(sweep_response.data, fs=fs, nperseg=nperseg, axis=0)
    band = drv.mean(axis=1) > 1e-3 * drv.mean(axis=1).max()  # the swept band
    shapes = []
    for k in range(drv.shape[1]):
        mean_drv = drv[band, k].mean()
        mean_res = res[band, k].mean()
        amp = mean_drv * (2.0 - res[:, k] / mean_res)
        amp = np.where(band, np.maximum(amp, floor * mean_drv), 0.0)
        shapes.append(lambda x, amp=amp: np.interp(x, f, amp, left=0.0, right=0.0))
    return shapes
