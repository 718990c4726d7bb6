"""Spectral matrices, the H1 FRF, its resonances and the drive PSD a target response needs (§3.3).

Pure signal processing on arrays (time is axis 0), no rig: the matched identification of
:class:`~vrig.reconstruction.DriveIteration` (``IterationSettings(id_match=True)``) uses these
to shape its identification drive from the desired response, and they serve any other caller
that needs a MIMO frequency response estimate; :func:`frf_resonance` reads the resonance off the
direct FRFs (the observable the two-channel fuel tank twin is calibrated on: the text places its
resonance at the 12 Hz split, §3.2.1, Fig. 3.9).

Conventions (one-sided Welch spectra, ``scipy.signal.csd``):

- the cross-spectral matrix of records ``a`` (n, p) and ``b`` (n, q) is
  ``G_ab[f, i, j] = E[A_i(f) conj(B_j(f))]`` (:func:`spectral_matrix`, the convention of
  :func:`vrig.reconstruction.cross_spectra`), so the auto-spectral matrix ``G_aa`` is Hermitian
  with the auto PSDs on its diagonal;
- for a linear system ``y = H x`` (``H`` of shape (n_freq, q, p)), ``G_yy = H G_xx H^H`` and
  ``G_yx = H G_xx``, so the H1 estimate is ``H = G_yx G_xx^-1`` (Bendat & Piersol, *Random
  Data*, ch. 7: the estimate unbiased by noise on the output);
- the drive that makes a target ``G_yy`` has ``G_xx = H^+ G_yy H^+^H`` with ``H^+`` the
  pseudo-inverse of ``H`` (exact for a square invertible ``H`` and a reachable target).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from scipy import signal
from scipy.ndimage import uniform_filter1d

__all__ = ["frf_h1", "frf_resonance", "matched_drive_psd", "psd_function", "spectral_matrix"]


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
    ``b``), in the convention of :func:`vrig.reconstruction.cross_spectra`.

    Parameters
    ----------
    a : array_like (n, p)
        First record (a 1-D array is one channel).
    b : array_like (n, q), optional
        Second record, same length (default: ``a``).
    fs : float
        Sample rate [Hz].
    nperseg : int
        Welch segment length [samples] (Hann window, 50 % overlap, segment means removed); the
        line spacing is ``fs / nperseg``.

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
    # scipy's csd(x, y) averages conj(X) Y: x = b_j, y = a_i gives A_i conj(B_j)
    f, s = signal.csd(b[:, None, :], a[:, :, None], fs=fs, nperseg=nperseg, axis=0)
    return f, s


def frf_h1(drive, response, *, fs: float, nperseg: int, rcond: float = 1e-10):
    """H1 estimate of the frequency response matrix from drives to responses.

    ``H(f) = G_yx(f) G_xx(f)^+``: the pseudo-inverse (singular values below ``rcond`` times the
    largest *over all frequencies* treated as zero) keeps a line where the drive has no power
    (e.g. 0 Hz of de-trended records, or outside the drive's band) at ``H = 0`` instead of
    dividing by round-off.

    Parameters
    ----------
    drive : array_like (n, p)
        Drive record(s) x.
    response : array_like (n, q)
        Response record(s) y, same length.
    fs : float
        Sample rate [Hz].
    nperseg : int
        Welch segment length [samples].
    rcond : float
        Relative cut-off of the drive spectral matrix's singular values.

    Returns
    -------
    f : ndarray (n_freq,)
        Frequencies [Hz].
    H : ndarray (n_freq, q, p), complex
        Response per unit drive at each frequency.
    """
    f, gxx = spectral_matrix(drive, fs=fs, nperseg=nperseg)
    _, gyx = spectral_matrix(response, drive, fs=fs, nperseg=nperseg)
    u, s, vh = np.linalg.svd(gxx)  # Hermitian PSD: s are its eigenvalues
    keep = s > rcond * s.max()
    s_inv = np.where(keep, 1.0 / np.where(keep, s, 1.0), 0.0)
    gxx_pinv = np.einsum("fij,fj,fkj->fik", vh.conj().transpose(0, 2, 1), s_inv, u.conj())
    return f, gyx @ gxx_pinv


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
    f, h = frf_h1(x, y, fs=fs, nperseg=nperseg)
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
