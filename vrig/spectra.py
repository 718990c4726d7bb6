"""Spectral matrices, the H1 FRF, its resonances and the drive PSD a target response needs (§3.3).

The one spectral core of vrig: the cross-spectral matrix (:func:`spectral_matrix`), the H1
estimate with the multiple coherence (:func:`frf_h1`, :func:`frf_from_spectra`), the filtering
of a record by an FRF given on lines (:func:`frf_filter`) and the log-spaced band edges
(:func:`band_edges`); the FRF method, the iteration updates, the Rattlesnake adapter, the
linearity check, the gym environments and the benchmarks' forward FRF all use these.

Pure signal processing on arrays (time is axis 0), no rig: the matched identification of
:class:`~vrig.reconstruction.DriveIteration` (``IterationSettings(id_match=True)``) uses these
to shape its identification drive from the desired response, and they serve any other caller
that needs a MIMO frequency response estimate; :func:`frf_resonance` reads the resonance off the
direct FRFs (the observable the two-channel fuel tank twin is calibrated on: the text places its
resonance at the 12 Hz split, §3.2.1, Fig. 3.9).

Conventions (one-sided Welch spectra, ``scipy.signal.csd``):

- the cross-spectral matrix of records ``a`` (n, p) and ``b`` (n, q) is
  ``G_ab[f, i, j] = E[A_i(f) conj(B_j(f))]`` (:func:`spectral_matrix`), so the auto-spectral
  matrix ``G_aa`` is Hermitian with the auto PSDs on its diagonal;
- for a linear system ``y = H x`` (``H`` of shape (n_freq, q, p)), ``G_yy = H G_xx H^H`` and
  ``G_yx = H G_xx``, so the H1 estimate is ``H = G_yx G_xx^-1`` (Bendat & Piersol, *Random
  Data*, ch. 7: the estimate unbiased by noise on the output; :func:`frf_h1`, with the
  multiple coherence and one documented regularisation of ``G_xx^-1``);
- the drive that makes a target ``G_yy`` has ``G_xx = H^+ G_yy H^+^H`` with ``H^+`` the
  pseudo-inverse of ``H`` (exact for a square invertible ``H`` and a reachable target).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy import signal
from scipy.ndimage import uniform_filter1d

__all__ = [
    "DEFAULT_RCOND",
    "MAX_OCTAVES",
    "REGULARISATIONS",
    "FrfEstimate",
    "band_edges",
    "frf_filter",
    "frf_from_spectra",
    "frf_h1",
    "frf_resonance",
    "interpolate_lines",
    "matched_drive_psd",
    "psd_function",
    "spectral_matrix",
]


def _as_2d(x, name: str) -> np.ndarray:
    a = np.asarray(x, dtype=float)
    if a.ndim == 1:
        a = a[:, None]
    if a.ndim != 2 or a.shape[0] < 2 or not np.all(np.isfinite(a)):
        raise ValueError(
            f"{name} must be finite samples x channels (time on axis 0), got shape {a.shape}"
        )
    return a


def _check_nperseg(nperseg, n: int) -> int:
    if not isinstance(nperseg, (int, np.integer)) or isinstance(nperseg, bool) or nperseg < 8:
        raise ValueError(f"nperseg must be an integer >= 8 samples, got {nperseg!r}")
    if nperseg > n:
        raise ValueError(f"nperseg {nperseg} is longer than the record ({n} samples)")
    return int(nperseg)


def spectral_matrix(a, b=None, *, fs: float, nperseg: int) -> tuple[np.ndarray, np.ndarray]:
    """Welch cross-spectral matrix of two multichannel records (of ``a`` with itself without
    ``b``): the one spectral matrix of vrig, in the module docstring's convention.

    The Welch estimate of :func:`scipy.signal.csd` (Hann window, 50 % overlap, each segment's
    mean removed, one-sided density, the mean over the segments), computed in ``csd``'s own
    order of operations (:class:`scipy.signal.ShortTimeFFT`) but with each channel's short-time
    transform taken once, not once per channel pair, and the products formed for a block of
    lines at a time (memory: a block of lines x channel pairs x segments, about 32 MB). Bit for
    bit, ``S[:, i, j]`` is ``conj(scipy.signal.csd(a[:, i], b[:, j], fs=fs, nperseg=nperseg))``
    (``csd(x, y)`` averages ``conj(X) Y``).

    Parameters
    ----------
    a : array_like (n, p)
        First record (a 1-D array is one channel).
    b : array_like (n, q), optional
        Second record, same length (default: ``a``).
    fs : float
        Sample rate [Hz].
    nperseg : int
        Welch segment length [samples], from 8 to the record's length; the line spacing is
        ``fs / nperseg``.

    Returns
    -------
    f : ndarray (n_freq,)
        Frequencies [Hz].
    S : ndarray (n_freq, p, q), complex
        ``S[f, i, j] = E[A_i conj(B_j)]`` in (unit of a)(unit of b)/Hz.
    """
    a = _as_2d(a, "a")
    b = a if b is None else _as_2d(b, "b")
    if b.shape[0] != a.shape[0]:
        raise ValueError(f"a and b must have the same length, got {a.shape[0]} and {b.shape[0]}")
    if not (np.isfinite(fs) and fs > 0):
        raise ValueError(f"fs must be a finite sample rate > 0 Hz, got {fs!r}")
    nperseg = _check_nperseg(nperseg, a.shape[0])
    f, A = _short_time_spectra(a, fs, nperseg)
    B = A if b is a else _short_time_spectra(b, fs, nperseg)[1]
    (p, n_freq, k), q = A.shape, B.shape[0]
    # the one-sided density doubles every line but DC and (even nperseg) Nyquist
    doubled = np.arange(n_freq) >= 1
    if nperseg % 2 == 0:
        doubled[-1] = False
    # csd forms ``Y * conj(X)`` per channel pair; for a pair of at least 256 kB numpy's temporary
    # elision evaluates it in place as ``conj(X) * Y``, which rounds differently (the complex
    # product is not commutative bit for bit): the same order here keeps csd's bits
    swapped = n_freq * k * 16 >= 256 * 1024
    S = np.empty((n_freq, p, q), dtype=complex)
    step = max(1, _BLOCK_ELEMENTS // (p * q * k))
    for lo in range(0, n_freq, step):  # a block of lines at a time: bounded memory
        sl = slice(lo, lo + step)
        prod = np.conj(np.broadcast_to(A[:, None, sl], (p, q, *A[:, sl].shape[1:])))
        if swapped:
            np.multiply(prod, B[None, :, sl], out=prod)
        else:
            np.multiply(B[None, :, sl], prod, out=prod)
        prod[:, :, doubled[sl]] *= 2
        S[sl] = np.moveaxis(np.conj(prod.mean(axis=-1)), -1, 0)
    return f, S


_BLOCK_ELEMENTS = 2**21
"""Complex products per block of :func:`spectral_matrix` (32 MB)."""


def _short_time_spectra(x: np.ndarray, fs: float, nperseg: int) -> tuple[np.ndarray, np.ndarray]:
    """Each column's Welch segments' spectra (channels, lines, segments), as
    :func:`scipy.signal.csd` makes them: Hann window scaled to a density, 50 % overlap, the
    mean of each segment removed."""
    n, hop = x.shape[0], nperseg - nperseg // 2
    window = signal.get_window("hann", nperseg)
    stft = signal.ShortTimeFFT(
        window, hop, fs, fft_mode="onesided", mfft=nperseg, scale_to="psd", phase_shift=None
    )
    spectra = stft.stft_detrend(
        np.ascontiguousarray(x.T), "constant", 0, (n - nperseg // 2) // hop,
        k_offset=nperseg // 2, axis=-1,
    )  # fmt: skip
    return stft.f, spectra


REGULARISATIONS = ("global", "line", "solve")
"""The inverses of ``G_xx`` :func:`frf_from_spectra` offers (its docstring)."""

DEFAULT_RCOND = {"global": 1e-10, "line": 1e-15}
"""The default ``rcond`` of each truncated-SVD regularisation: ``"line"``'s is
:func:`numpy.linalg.pinv`'s own."""


@dataclass(frozen=True)
class FrfEstimate:
    """An H1 estimate and the spectral matrices it is made of (:func:`frf_h1`).

    Attributes
    ----------
    f : ndarray (n_freq,)
        Frequencies [Hz].
    frf : ndarray (n_freq, q, p), complex
        ``H = G_yx G_xx^+``: response per unit drive.
    coherence : ndarray (n_freq, q)
        Multiple coherence of each response with all the drives, in [0, 1].
    gxx, gyx, gyy : ndarray (n_freq, p, p), (n_freq, q, p), (n_freq, q, q), complex
        The drive, response-drive and response spectral matrices (:func:`spectral_matrix`).
    """

    f: np.ndarray
    frf: np.ndarray
    coherence: np.ndarray
    gxx: np.ndarray
    gyx: np.ndarray
    gyy: np.ndarray


def frf_h1(
    drive,
    response,
    *,
    fs: float,
    nperseg: int,
    regularisation: str = "global",
    rcond: float | None = None,
) -> FrfEstimate:
    """H1 estimate of the frequency response matrix from drives to responses, with the
    multiple coherence: :func:`spectral_matrix` of the records, then :func:`frf_from_spectra`
    (its docstring has the regularisation).

    Parameters
    ----------
    drive : array_like (n, p)
        Drive record(s) x (a 1-D array is one channel).
    response : array_like (n, q)
        Response record(s) y, same length.
    fs : float
        Sample rate [Hz].
    nperseg : int
        Welch segment length [samples].
    regularisation : {"global", "line", "solve"}
        How ``G_xx`` is inverted (:func:`frf_from_spectra`).
    rcond : float, optional
        The truncation's relative cut-off (default :data:`DEFAULT_RCOND` of the
        regularisation).

    Returns
    -------
    FrfEstimate
    """
    f, gxx = spectral_matrix(drive, fs=fs, nperseg=nperseg)
    _, gyx = spectral_matrix(response, drive, fs=fs, nperseg=nperseg)
    _, gyy = spectral_matrix(response, fs=fs, nperseg=nperseg)
    return frf_from_spectra(f, gxx, gyx, gyy, regularisation=regularisation, rcond=rcond)


def frf_from_spectra(
    f, gxx, gyx, gyy, *, regularisation: str = "global", rcond: float | None = None
) -> FrfEstimate:
    """The H1 estimate ``H = G_yx G_xx^+`` and the multiple coherence from given spectral
    matrices (e.g. spectra accumulated over several records, as the ``"frf"`` update does).

    The default regularisation, ``"global"``, is a truncated-SVD pseudo-inverse of ``G_xx``
    whose cut-off is relative to the largest singular value *over all lines*: at each line the
    singular values (``G_xx`` is Hermitian positive semi-definite: its eigenvalues) below
    ``rcond`` (1e-10) times the largest of the whole estimate are treated as zero. A line where
    the drive has no power (outside the drive's band, or a direction two collinear drives do
    not excite) is thus left at ``H = 0`` instead of dividing round-off by round-off, while a
    line that is merely weak (the skirt of a band-limited drive, 60 dB down) is still estimated,
    which a cut-off relative to each line's own largest singular value could not tell apart.

    The named alternatives, for callers whose figures were made with them:

    - ``"line"``: the cut-off relative to each line's largest singular value,
      :func:`numpy.linalg.pinv` with ``rcond`` (default 1e-15, numpy's: an inverse wherever
      ``G_xx`` is numerically non-singular; every line keeps an estimate);
    - ``"solve"``: no regularisation, ``H^H = G_xx^-1 G_xy`` by :func:`numpy.linalg.solve`
      (``rcond`` is not used; a singular line raises :class:`numpy.linalg.LinAlgError`).

    The multiple coherence of response ``i`` is ``γ²_i = (H G_xy)_ii / G_yy,ii``, the fraction
    of its power a linear function of all the drives explains (Bendat & Piersol, *Random Data*,
    ch. 7), clipped to [0, 1] (round-off); 0 where the response has no power.

    Parameters
    ----------
    f : array_like (n_freq,)
        Frequencies [Hz].
    gxx, gyx, gyy : array_like (n_freq, p, p), (n_freq, q, p), (n_freq, q, q), complex
        Drive, response-drive and response spectral matrices (:func:`spectral_matrix`).
    regularisation : {"global", "line", "solve"}
        How ``G_xx`` is inverted (above).
    rcond : float, optional
        Relative cut-off of the truncation, >= 0 (default :data:`DEFAULT_RCOND`).

    Returns
    -------
    FrfEstimate
    """
    gxx, gyx, gyy = (np.asarray(g, dtype=complex) for g in (gxx, gyx, gyy))
    n_freq, q, p = gyx.shape if gyx.ndim == 3 else (None, None, None)
    if (
        gyx.ndim != 3
        or gxx.shape != (n_freq, p, p)
        or gyy.shape != (n_freq, q, q)
        or np.shape(f) != (n_freq,)
    ):
        raise ValueError(
            "gxx, gyx, gyy must be (n_freq, p, p), (n_freq, q, p), (n_freq, q, q) on f's lines,"
            f" got {gxx.shape}, {gyx.shape}, {gyy.shape} and f {np.shape(f)}"
        )
    if regularisation not in REGULARISATIONS:
        raise ValueError(
            f"regularisation must be one of {', '.join(REGULARISATIONS)}, got {regularisation!r}"
        )
    if regularisation == "solve":
        gxy = np.conj(np.swapaxes(gyx, -1, -2))
        H = np.conj(np.swapaxes(np.linalg.solve(gxx, gxy), -1, -2))
    else:
        rcond = DEFAULT_RCOND[regularisation] if rcond is None else rcond
        if not (isinstance(rcond, (int, float, np.number)) and np.isfinite(rcond) and rcond >= 0):
            raise ValueError(f"rcond must be a finite relative cut-off >= 0, got {rcond!r}")
        H = np.einsum("fij,fjk->fik", gyx, _pinv(gxx, regularisation, rcond))  # (F, q, p)
    explained = np.real(np.einsum("fij,fij->fi", H, np.conj(gyx)))  # (H G_xy)_ii
    power = np.maximum(np.real(np.einsum("fii->fi", gyy)), 1e-300)
    coherence = np.clip(explained / power, 0.0, 1.0)
    return FrfEstimate(np.asarray(f), H, coherence, gxx, gyx, gyy)


def _pinv(gxx: np.ndarray, regularisation: str, rcond: float) -> np.ndarray:
    """The truncated-SVD pseudo-inverse of each line's ``G_xx`` (:func:`frf_from_spectra`)."""
    if regularisation == "line":
        return np.linalg.pinv(gxx, rcond=rcond)
    u, s, vh = np.linalg.svd(gxx)  # Hermitian PSD: s are its eigenvalues
    keep = s > rcond * s.max()
    s_inv = np.where(keep, 1.0 / np.where(keep, s, 1.0), 0.0)
    return np.einsum("fij,fj,fkj->fik", vh.conj().transpose(0, 2, 1), s_inv, u.conj())


def frf_filter(M, f, fs: float, x, *, dc: bool = True) -> np.ndarray:
    """Filter a record by a frequency-response matrix given on a grid of lines.

    The record is zero-padded to twice its length (no circular wrap-around of the filter's
    impulse response), ``M`` is interpolated linearly (real and imaginary parts, every entry at
    once; :func:`numpy.interp`'s rule: the end values beyond the grid) onto the padded record's
    lines and applied per line: ``Y(f) = M(f) X(f)``.

    Parameters
    ----------
    M : array_like (F, n_out, n_in), complex
        The frequency response per line of ``f``.
    f : array_like (F,)
        Its increasing frequency lines [Hz].
    fs : float
        Sample rate of ``x`` [Hz].
    x : array_like (n_samples, n_in)
        The record.
    dc : bool
        ``False`` leaves the DC line out (sets it to 0).

    Returns
    -------
    ndarray (n_samples, n_out)
    """
    M = np.asarray(M, dtype=complex)
    f = np.asarray(f, dtype=float)
    x = np.asarray(x, dtype=float)
    if M.ndim != 3 or f.shape != (M.shape[0],) or f.size < 2 or np.any(np.diff(f) <= 0):
        raise ValueError(
            f"M must be (F, n_out, n_in) on F >= 2 increasing lines f, got {M.shape} and {f.shape}"
        )
    if x.ndim != 2 or x.shape[1] != M.shape[2]:
        raise ValueError(f"x must be (n_samples, {M.shape[2]}), got {x.shape}")
    n = x.shape[0]
    n_fft = 2 * n
    X = np.fft.rfft(x, n=n_fft, axis=0)
    Mi = interpolate_lines(M, f, np.fft.rfftfreq(n_fft, 1.0 / fs))
    if not dc:
        Mi[0] = 0.0
    return np.fft.irfft(np.einsum("fij,fj->fi", Mi, X), n=n_fft, axis=0)[:n]


def interpolate_lines(M, f, f_new) -> np.ndarray:
    """A complex array given on spectral lines, interpolated linearly onto other frequencies:
    real and imaginary parts of every entry at once, in :func:`numpy.interp`'s arithmetic (bit
    for bit): the end values outside ``f``, a line's own value on it, ``slope (x - f_j) + M_j``
    between (:func:`frf_filter`'s interpolation).

    Parameters
    ----------
    M : array_like (F, ...), complex
        Values on the lines ``f``.
    f : array_like (F,)
        Increasing lines [Hz], at least 2.
    f_new : array_like (F_new,)
        Frequencies to interpolate at [Hz].

    Returns
    -------
    ndarray (F_new, ...), complex
    """
    M = np.asarray(M, dtype=complex)
    f, f_new = np.asarray(f, dtype=float), np.asarray(f_new, dtype=float)
    flat = np.ascontiguousarray(M.reshape(M.shape[0], -1)).view(float)  # (F, 2 entries)
    j = np.clip(np.searchsorted(f, f_new, side="right") - 1, 0, f.size - 2)
    x0, x1 = f[j], f[j + 1]
    y0, y1 = flat[j], flat[j + 1]
    slope = (y1 - y0) / (x1 - x0)[:, None]
    out = slope * (f_new - x0)[:, None] + y0
    on_line = (f_new == x0) | (f_new < f[0])
    out[on_line] = y0[on_line]
    beyond = f_new >= f[-1]
    out[beyond] = flat[-1]
    return out.view(complex).reshape(f_new.size, *M.shape[1:])


MAX_OCTAVES = 6
"""The octaves below the upper edge that bands from 0 Hz split (:func:`band_edges`)."""


def band_edges(band: tuple[float, float], n_bands: int) -> np.ndarray:
    """``n_bands + 1`` log-spaced band edges [Hz] over ``band``: the one band rule of vrig (the
    gym environments' bands, the ``"secant"`` update's).

    A band from 0 Hz: the first band reaches down to DC and the others split geometrically the
    octaves below the upper edge, one octave each up to :data:`MAX_OCTAVES` + 1 bands
    (``[0, hi / 2**(n-1), ..., hi / 2, hi]``) and the six octaves finer beyond, rather than
    piling up near DC, where a record has no lines (13 bands below 40 Hz in octaves would put
    the second edge at 0.01 Hz; capped, they are half-octaves down to 0.625 Hz). A band from
    ``low > 0``: ``geomspace(low, high, n_bands + 1)``. As in :func:`vrig.processing.band_gains`,
    the first band also holds every line below ``edges[1]`` and the last every line above
    ``edges[-2]``.

    Parameters
    ----------
    band : (float, float)
        ``(low, high)`` [Hz], ``0 <= low < high``.
    n_bands : int
        Number of bands (>= 1).

    Returns
    -------
    ndarray (n_bands + 1,)
    """
    if not isinstance(n_bands, (int, np.integer)) or isinstance(n_bands, bool) or n_bands < 1:
        raise ValueError(f"n_bands must be a positive integer, got {n_bands!r}")
    lo, hi = float(band[0]), float(band[1])
    if not (0 <= lo < hi and np.isfinite(hi)):
        raise ValueError(f"band must satisfy 0 <= low < high, got {band}")
    if lo > 0:
        return np.geomspace(lo, hi, n_bands + 1)
    if n_bands == 1:
        return np.array([0.0, hi])
    octaves = np.arange(n_bands - 1, -1, -1) * (min(n_bands - 1, MAX_OCTAVES) / (n_bands - 1))
    return np.concatenate([[0.0], hi / 2.0**octaves])


def frf_resonance(
    drive, response, *, fs: float, nperseg: int, band: tuple[float, float], level: float = 0.5
) -> np.ndarray:
    """The resonance frequency of each direct FRF (drive ``i`` -> response ``i``): the centroid of
    its resonant hump.

    ``H`` is the H1 estimate (:func:`frf_h1`); for each channel ``i`` the lines of ``band`` where
    ``|H_ii|²`` reaches ``level`` times its largest value in the band (``level = 0.5``: the
    half-power lines) are the hump, and the resonance is their power-weighted mean frequency
    ``Σ f |H_ii|² / Σ |H_ii|²``. For one lightly damped mode (natural frequency ``f_n``, damping
    ratio ``ζ``) the half-power lines lie symmetrically about the magnitude peak to first order
    in ``ζ``, so the centroid is ``f_n`` within about ``ζ² f_n`` (0.04 Hz at 12 Hz and
    ``ζ = 0.05``) and the line spacing ``fs / nperseg``; for two close modes of similar height,
    whose argmax would jump from one to the other with the estimate's noise, it lies between
    them, weighted by their heights.

    Parameters
    ----------
    drive : array_like (n, p)
        Drive records x (a 1-D array is one channel).
    response : array_like (n, p)
        Response records y, same length and as many channels as the drive (a square system).
    fs : float
        Sample rate [Hz].
    nperseg : int
        Welch segment length [samples]: the line spacing is ``fs / nperseg``.
    band : (float, float)
        The frequencies searched, ``0 <= low < high <= fs / 2`` [Hz].
    level : float
        The hump's threshold as a fraction of the largest ``|H_ii|²`` in the band, in (0, 1).

    Returns
    -------
    ndarray (p,)
        The resonance frequency of each direct FRF [Hz].
    """
    x, y = _as_2d(drive, "drive"), _as_2d(response, "response")
    if x.shape[1] != y.shape[1]:
        raise ValueError(
            f"a direct FRF needs as many responses as drives, got {x.shape[1]} drives and "
            f"{y.shape[1]} responses"
        )
    lo, hi = (float(b) for b in band)
    if not (np.isfinite(fs) and fs > 0):
        raise ValueError(f"fs must be a finite sample rate > 0 Hz, got {fs!r}")
    if not (0 <= lo < hi <= fs / 2):
        raise ValueError(f"band must satisfy 0 <= low < high <= fs/2 = {fs / 2:g} Hz, got {band!r}")
    if not (np.isfinite(level) and 0 < level < 1):
        raise ValueError(f"level must be a fraction in (0, 1), got {level!r}")
    est = frf_h1(x, y, fs=fs, nperseg=nperseg)
    f, h = est.f, est.frf
    inside = (f >= lo) & (f <= hi)
    if np.count_nonzero(inside) < 3:
        raise ValueError(
            f"band {lo:g}-{hi:g} Hz holds fewer than 3 lines at {fs / nperseg:g} Hz spacing"
        )
    fb = f[inside]
    power = np.abs(np.einsum("fii->fi", h[inside])) ** 2  # (n_lines, p)
    hump = power >= level * power.max(axis=0)
    weight = np.where(hump, power, 0.0)
    return (fb @ weight) / weight.sum(axis=0)


def matched_drive_psd(
    frf,
    target,
    *,
    mask=None,
    regularisation: float = 1e-3,
    smooth: int = 3,
    floor: float = 0.01,
) -> np.ndarray:
    """The drive auto-PSDs that make a linear system's response follow a target spectrum.

    ``G_xx(f) = H^+(f) G_yy(f) H^+(f)^H`` with a Tikhonov pseudo-inverse
    ``H^+ = (H^H H + λ² I)^-1 H^H``, ``λ = regularisation`` times the largest singular value of
    ``H`` over the ``mask`` (a line where the system barely responds is not answered with an
    unbounded drive). Its diagonal (one real PSD per drive channel: drives synthesised from it
    are mutually uncorrelated, as an identification drive should be) is smoothed by a moving
    average over ``smooth`` lines, set to zero outside ``mask`` and raised inside it to at least
    ``floor`` times its largest value, so that every line of the band is still excited (the
    floor's default 0.01 is 20 dB below the peak: 10 % of the peak amplitude density).

    When the target is the response to uncorrelated drives (a pseudo-field record) and ``H`` is
    square and invertible, the result is those drives' PSDs exactly (before smoothing and
    floor); otherwise the drives' cross-spectra are dropped and the auto-PSDs of the response
    are matched approximately.

    Parameters
    ----------
    frf : array_like (n_freq, q, p), complex
        Frequency response, responses per unit drive (e.g. :func:`frf_h1`); a 1-D array is a
        SISO FRF.
    target : array_like (n_freq, q, q) or (n_freq, q)
        The target response's spectral matrix (:func:`spectral_matrix` of the target)
        or its auto-PSDs only (cross-spectra taken as zero); for q = 1 a 1-D array.
    mask : array_like of bool (n_freq,), optional
        The lines to excite (the identification band); default every line.
    regularisation : float
        ``λ`` relative to the largest singular value of ``H`` in the mask (>= 0).
    smooth : int
        Width of the moving average [lines] (1: none).
    floor : float
        Lowest PSD inside the mask as a fraction of each channel's largest, in [0, 1].

    Returns
    -------
    ndarray (n_freq, p)
        Drive auto-PSDs [(drive unit)²/Hz]: their integral over frequency is the mean square
        drive that reproduces the target's level through ``H``.
    """
    h = np.asarray(frf, dtype=complex)
    h = h[:, None, None] if h.ndim == 1 else h
    g = np.asarray(target)
    g = g[:, None] if g.ndim == 1 else g
    if h.ndim != 3 or not np.all(np.isfinite(h)):
        raise ValueError(f"frf must be finite (n_freq, q, p), got shape {h.shape}")
    nf, q = h.shape[:2]
    if g.shape == (nf, q):
        g = np.einsum("fi,ij->fij", g, np.eye(q))  # auto-PSDs only: a diagonal matrix
    if g.shape != (nf, q, q) or not np.all(np.isfinite(g)):
        raise ValueError(
            f"target must be finite ({nf}, {q}, {q}) or ({nf}, {q}), got {np.shape(target)}"
        )
    m = np.ones(nf, bool) if mask is None else np.asarray(mask, bool)
    if m.shape != (nf,) or not m.any():
        raise ValueError(f"mask must be {nf} booleans with at least one True")
    _check_shaping(regularisation, smooth, floor)
    u, s, vh = np.linalg.svd(h, full_matrices=False)
    lam = regularisation * s[m].max()
    gain = s / (s**2 + lam**2) if lam > 0 else np.where(s > 0, 1.0 / np.where(s > 0, s, 1.0), 0.0)
    h_pinv = np.einsum("fki,fk,fjk->fij", vh.conj(), gain, u.conj())  # V diag U^H: (nf, p, q)
    gxx = np.einsum("fij,fjk,flk->fil", h_pinv, g, h_pinv.conj())
    psd = np.maximum(np.real(np.einsum("fii->fi", gxx)), 0.0)
    if smooth > 1:
        psd = uniform_filter1d(psd, smooth, axis=0, mode="nearest")
    psd[~m] = 0.0
    top = psd[m].max(axis=0)
    psd[m] = np.maximum(psd[m], floor * top)
    return psd


def _check_shaping(regularisation, smooth, floor) -> None:
    if not (np.isfinite(regularisation) and regularisation >= 0):
        raise ValueError(f"regularisation must be finite and >= 0, got {regularisation!r}")
    if not isinstance(smooth, (int, np.integer)) or isinstance(smooth, bool) or smooth < 1:
        raise ValueError(f"smooth must be a positive integer number of lines, got {smooth!r}")
    if not (np.isfinite(floor) and 0 <= floor <= 1):
        raise ValueError(f"floor must be a fraction in [0, 1], got {floor!r}")


def psd_function(f, psd) -> list[Callable[[np.ndarray], np.ndarray]]:
    """PSD shapes on spectral lines as functions of frequency (one per channel), for
    :func:`vrig.signals.random_drive`: linear interpolation between the lines, zero outside.

    Parameters
    ----------
    f : array_like (n_freq,)
        Increasing frequencies [Hz].
    psd : array_like (n_freq, p) or (n_freq,)
        Non-negative PSD values per channel.

    Returns
    -------
    list of callables
        ``shape(freqs) -> PSD`` per channel.
    """
    f = np.asarray(f, dtype=float)
    psd = np.asarray(psd, dtype=float)
    psd = psd[:, None] if psd.ndim == 1 else psd
    if f.ndim != 1 or psd.shape[0] != f.size or np.any(np.diff(f) <= 0):
        raise ValueError(
            f"f must be increasing and match psd's first axis, got {f.shape}, {psd.shape}"
        )
    if not np.all(np.isfinite(psd) & (psd >= 0)):
        raise ValueError("psd must be finite and non-negative")
    return [lambda x, c=c: np.interp(x, f, c, left=0.0, right=0.0) for c in psd.T]
