"""The one spectral core (vrig.spectra): equivalence with every implementation it replaced, and
analytic truth.

Equivalence: each ``_old_*`` function below is a frozen copy of the PRE-REFACTOR implementation
(commit 83cad8a, the start of issue 33's spectral-core work), kept here verbatim (names changed,
comments added) so the core can be compared with it: bit for bit where the arithmetic is the
same, else to the stated tolerance with the reason. The target check's spectral functions (then
``vrig/targets.py``, now :mod:`vrig.desired.reachability`) are frozen here too: the tests say
which core call reproduces each, and the rewired ``multiple_coherence`` is compared with its old
self, singular lines included.

Truth: a 2 x 2 FIR system driven by white noise (its FRF exactly from ``scipy.signal.freqz``),
with and without output noise of known level (coherence ``S / (S + N)``), and a drive spectral
matrix that is singular by construction.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy import signal

from vrig.spectra import (
    DEFAULT_RCOND,
    band_edges,
    frf_filter,
    frf_from_spectra,
    frf_h1,
    interpolate_lines,
    spectral_matrix,
)

FS = 100.0


# ---------------------------------------------------------------- pre-refactor implementations
def _old_cross_spectra(a, b, fs, nperseg):
    """PRE-REFACTOR vrig/reconstruction/methods.py::cross_spectra (83cad8a)."""
    f = None
    out = []
    for i in range(a.shape[1]):
        row = []
        for j in range(b.shape[1]):
            f, s = signal.csd(a[:, i], b[:, j], fs=fs, nperseg=nperseg)
            row.append(np.conj(s))  # scipy's csd(x, y) = conj(X) Y: conj gives X conj(Y)
        out.append(row)
    return f, np.array(out).transpose(2, 0, 1)


def _old_h1_from_spectra(f, suu, syu, syy):
    """PRE-REFACTOR vrig/reconstruction/methods.py::h1_from_spectra (83cad8a)."""
    suu_inv = np.linalg.pinv(suu)
    H = np.einsum("fij,fjk->fik", syu, suu_inv)  # (F, ny, nu)
    coherence = np.real(
        np.einsum("fij,fjk,fki->fi", syu, suu_inv, syu.conj().transpose(0, 2, 1))
        / np.maximum(np.real(np.einsum("fii->fi", syy)), 1e-300)
    )
    return {"f": f, "suu": suu, "syu": syu, "syy": syy, "H": H, "coherence": coherence}


def _old_h1_spectra(u, y, fs, nperseg):
    """PRE-REFACTOR vrig/reconstruction/methods.py::h1_spectra (83cad8a)."""
    f, suu = _old_cross_spectra(u, u, fs, nperseg)
    _, syu = _old_cross_spectra(y, u, fs, nperseg)
    _, syy = _old_cross_spectra(y, y, fs, nperseg)
    return _old_h1_from_spectra(f, suu, syu, syy)


def _old_frf_filter(M, f, fs, x, *, dc=True):
    """PRE-REFACTOR vrig/reconstruction/methods.py::frf_filter (83cad8a); the benchmarks'
    ``ForwardFrf.drive`` was the same code with ``dc=True``."""
    n = x.shape[0]
    n_fft = 2 * n
    X = np.fft.rfft(x, n=n_fft, axis=0)
    fr = np.fft.rfftfreq(n_fft, 1.0 / fs)
    Mi = np.empty((fr.size, *M.shape[1:]), dtype=complex)
    for i in range(M.shape[1]):
        for j in range(M.shape[2]):
            Mi[:, i, j] = np.interp(fr, f, M[:, i, j].real) + 1j * np.interp(fr, f, M[:, i, j].imag)
    if not dc:
        Mi[0] = 0.0
    return np.fft.irfft(np.einsum("fij,fj->fi", Mi, X), n=n_fft, axis=0)[:n]


def _old_forward_frf_h(x, y, fs, nperseg):
    """PRE-REFACTOR benchmarks/runner/registry.py::ForwardFrf.identify's H (83cad8a)."""
    nper = min(nperseg, x.shape[0] // 4)
    f, sxx = _old_cross_spectra(x, x, fs, nper)
    _, syx = _old_cross_spectra(y, x, fs, nper)
    return f, np.einsum("fij,fjk->fik", syx, np.linalg.pinv(sxx))


def _old_spectral_matrix(a, b, fs, nperseg):
    """PRE-REFACTOR vrig/spectra.py::spectral_matrix's arithmetic (83cad8a; checks left out)."""
    f, s = signal.csd(b[:, None, :], a[:, :, None], fs=fs, nperseg=nperseg, axis=0)
    return f, s


def _old_frf_h1(drive, response, fs, nperseg, rcond=1e-10):
    """PRE-REFACTOR vrig/spectra.py::frf_h1 (83cad8a), returning (f, H)."""
    f, gxx = _old_spectral_matrix(drive, drive, fs, nperseg)
    _, gyx = _old_spectral_matrix(response, drive, fs, nperseg)
    return (f, *_old_frf_h1_from(gxx, gyx, rcond))


def _old_frf_h1_from(gxx, gyx, rcond=1e-10):
    """The inverse and product of PRE-REFACTOR vrig/spectra.py::frf_h1 (83cad8a), from given
    spectral matrices."""
    u, s, vh = np.linalg.svd(gxx)  # Hermitian PSD: s are its eigenvalues
    keep = s > rcond * s.max()
    s_inv = np.where(keep, 1.0 / np.where(keep, s, 1.0), 0.0)
    gxx_pinv = np.einsum("fij,fj,fkj->fik", vh.conj().transpose(0, 2, 1), s_inv, u.conj())
    return (gyx @ gxx_pinv,)


def _old_csd_matrix(x, y, fs, nperseg):
    """PRE-REFACTOR vrig/linearity.py::_csd_matrix (83cad8a)."""
    kw = dict(fs=fs, nperseg=nperseg, detrend="constant", axis=0)
    nu, ny = x.shape[1], y.shape[1]
    f, _ = signal.welch(x[:, 0], **kw)
    suu = np.empty((f.size, nu, nu), complex)
    suy = np.empty((f.size, nu, ny), complex)
    for i in range(nu):
        for j in range(nu):
            suu[:, i, j] = signal.csd(x[:, i], x[:, j], **kw)[1]
        for j in range(ny):
            suy[:, i, j] = signal.csd(x[:, i], y[:, j], **kw)[1]
    syy = signal.welch(y, **kw)[1]
    return f, suu, suy, syy


def _old_linearity_coherence(x, y, fs, nperseg):
    """PRE-REFACTOR vrig/linearity.py::_multiple_coherence (83cad8a)."""
    f, suu, suy, syy = _old_csd_matrix(x, y, fs, nperseg)
    if x.shape[1] == 1:
        g = np.abs(suy[:, 0, :]) ** 2 / np.maximum(suu[:, 0, 0].real[:, None] * syy, 1e-300)
    else:
        g = np.empty_like(syy)
        for i in range(f.size):
            h = np.linalg.pinv(suu[i]) @ suy[i]  # (nu, ny)
            g[i] = np.real(np.sum(np.conj(suy[i]) * h, axis=0)) / np.maximum(syy[i], 1e-300)
    return f, np.clip(g, 0.0, 1.0), syy


def _old_linearity_h1(x, y, fs, nperseg, inb):
    """PRE-REFACTOR vrig/linearity.py::_coherence_test's H1 (83cad8a): (F, nu, ny)."""
    _f, suu, suy, _ = _old_csd_matrix(x, y, fs, nperseg)
    h1 = np.zeros_like(suy)
    for i in np.flatnonzero(inb):
        h1[i] = np.linalg.pinv(suu[i]) @ suy[i]
    return h1


def _old_env_band_edges(band, n_bands):
    """PRE-REFACTOR vrig/envs/task.py::band_edges (83cad8a; checks left out)."""
    lo, hi = float(band[0]), float(band[1])
    if lo <= 0:
        return np.concatenate([[0.0], hi / 2.0 ** np.arange(n_bands - 1, -1, -1)])
    return np.geomspace(lo, hi, n_bands + 1)


def _old_log_band_edges(band, n_bands):
    """PRE-REFACTOR vrig/reconstruction/updates.py::log_band_edges (83cad8a)."""
    lo, hi = float(band[0]), float(band[1])
    if lo <= 0:
        if n_bands == 1:
            return np.array([0.0, hi])
        low = hi / 2.0 ** min(n_bands - 1, 6)
        return np.concatenate([[0.0], np.geomspace(low, hi, n_bands)])
    return np.geomspace(lo, hi, n_bands + 1)


_TARGETS_BLOCK = 64  # vrig/targets.py::_BLOCK


def _targets_spectra(z, fs, nperseg):
    """PRE-REFACTOR vrig/targets.py::_spectra (83cad8a)."""
    step = nperseg - nperseg // 2  # scipy's noverlap = nperseg // 2
    window = signal.get_window("hann", nperseg)
    segments = np.lib.stride_tricks.sliding_window_view(z, nperseg, axis=0)[::step]
    f = np.fft.rfftfreq(nperseg, 1.0 / fs)
    G = np.zeros((f.size, z.shape[1], z.shape[1]), dtype=complex)
    for i in range(0, segments.shape[0], _TARGETS_BLOCK):  # one block of segments at a time
        seg = segments[i : i + _TARGETS_BLOCK]
        Z = np.fft.rfft((seg - seg.mean(axis=-1, keepdims=True)) * window, axis=-1)
        G += np.einsum("kif,kjf->fij", Z, np.conj(Z))
    G *= 2.0 / (fs * np.sum(window**2) * segments.shape[0])
    G[0] /= 2
    if nperseg % 2 == 0:
        G[-1] /= 2
    return f, G


def _targets_h1(Sxx, Sxy):
    """PRE-REFACTOR vrig/targets.py::_h1 (83cad8a)."""
    return np.conj(np.swapaxes(np.linalg.solve(Sxx, Sxy), -1, -2))


def _targets_multiple_coherence(x, y, fs, nperseg=256):
    """PRE-REFACTOR vrig/targets.py::multiple_coherence (83cad8a; input checks left out)."""
    m = x.shape[1]
    f, S = _targets_spectra(np.hstack([x, y]), fs, nperseg)
    Sxx, Sxy, Syy = S[:, :m, :m], S[:, :m, m:], S[:, m:, m:]
    with np.errstate(invalid="ignore", divide="ignore"):
        ok = np.linalg.matrix_rank(Sxx) == m
        Sc = np.full(Syy.shape, np.nan, dtype=complex)
        Sc[ok] = np.conj(np.swapaxes(Sxy[ok], -1, -2)) @ np.linalg.solve(Sxx[ok], Sxy[ok])
        gamma2 = np.diagonal(Sc, axis1=1, axis2=2).real / np.diagonal(Syy, axis1=1, axis2=2).real
    return f, np.clip(gamma2, 0.0, 1.0)


def _targets_interp_lines(f, M, f_new):
    """PRE-REFACTOR vrig/targets.py::_interp_lines (83cad8a)."""
    flat = M.reshape(M.shape[0], -1)
    out = np.empty((f_new.size, flat.shape[1]), dtype=complex)
    for k in range(flat.shape[1]):  # one column per matrix entry (a few dozen), not per sample
        out[:, k] = np.interp(f_new, f, flat[:, k].real) + 1j * np.interp(f_new, f, flat[:, k].imag)
    return out.reshape(f_new.size, *M.shape[1:])


# ---------------------------------------------------------------- records
def _records(n, p, q, seed=0, noise=0.1):
    """Drives (n, p) and responses (n, q) of a random-FIR MIMO system with output noise."""
    rng = np.random.default_rng(seed)
    x = rng.standard_normal((n, p))
    taps = rng.standard_normal((q, p, 5))
    y = np.zeros((n, q))
    for i in range(q):
        for j in range(p):
            y[:, i] += signal.lfilter(taps[i, j], [1.0], x[:, j])
    return x, y + noise * rng.standard_normal((n, q))


# records x segment lengths: small and large pairs on both sides of numpy's temporary-elision
# threshold (lines x segments >= 16384: 129 lines x 127 segments is below, x 128 at it)
SHAPES = [(5000, 3, 2, 256), (4001, 1, 1, 255), (16384, 1, 2, 256), (16512, 2, 1, 256),
          (20000, 7, 7, 512), (3000, 2, 10, 100)]  # fmt: skip


# ---------------------------------------------------------------- equivalence: reconstruction
@pytest.mark.parametrize(("n", "p", "q", "nperseg"), SHAPES)
def test_the_spectral_matrix_is_the_frf_methods_cross_spectra_bit_for_bit(n, p, q, nperseg):
    x, y = _records(n, p, q)
    f0, gyx0 = _old_cross_spectra(y, x, FS, nperseg)
    f, gyx = spectral_matrix(y, x, fs=FS, nperseg=nperseg)
    np.testing.assert_array_equal(f, f0)
    np.testing.assert_array_equal(gyx, gyx0)
    np.testing.assert_array_equal(spectral_matrix(x, fs=FS, nperseg=nperseg)[1],
                                  _old_cross_spectra(x, x, FS, nperseg)[1])  # fmt: skip


def test_the_spectral_matrix_is_blocked_over_lines_without_changing_a_bit(monkeypatch):
    import vrig.spectra as spectra

    x, y = _records(6000, 3, 2)
    whole = spectral_matrix(y, x, fs=FS, nperseg=256)[1]
    monkeypatch.setattr(spectra, "_BLOCK_ELEMENTS", 1000)  # a few lines per block
    np.testing.assert_array_equal(spectral_matrix(y, x, fs=FS, nperseg=256)[1], whole)


@pytest.mark.parametrize(("n", "p", "q", "nperseg"), SHAPES[:4])
def test_h1_line_is_the_frf_methods_h1_bit_for_bit(n, p, q, nperseg):
    """InverseFrf, the "frf" and "ilc" updates and the Rattlesnake adapter: ``h1_spectra`` /
    ``h1_from_spectra`` are ``frf_h1`` / ``frf_from_spectra`` with ``regularisation="line"``.
    H and the spectra are bit for bit; the coherence is now ``Re sum_j H_ij conj(G_yx,ij)``
    (one formula for every regularisation) instead of a three-operand einsum through
    ``G_xx^+``, the same sum in another order, and is clipped to [0, 1]: 1e-14."""
    x, y = _records(n, p, q)
    old = _old_h1_spectra(x, y, FS, nperseg)
    new = frf_h1(x, y, fs=FS, nperseg=nperseg, regularisation="line")
    for key, got in (("f", new.f), ("suu", new.gxx), ("syu", new.gyx), ("syy", new.gyy),
                     ("H", new.frf)):  # fmt: skip
        np.testing.assert_array_equal(got, old[key], err_msg=key)
    np.testing.assert_allclose(new.coherence, np.clip(old["coherence"], 0, 1), rtol=0, atol=1e-14)
    again = frf_from_spectra(old["f"], old["suu"], old["syu"], old["syy"], regularisation="line")
    np.testing.assert_array_equal(again.frf, old["H"])


def test_the_benchmarks_forward_frf_is_h1_line_and_frf_filter_bit_for_bit():
    x, y = _records(4000, 2, 3)
    f0, h0 = _old_forward_frf_h(x, y, FS, 512)
    est = frf_h1(x, y, fs=FS, nperseg=min(512, x.shape[0] // 4), regularisation="line")
    np.testing.assert_array_equal(est.f, f0)
    np.testing.assert_array_equal(est.frf, h0)
    r = np.random.default_rng(3).standard_normal((999, 2))
    np.testing.assert_array_equal(frf_filter(h0, f0, FS, r), _old_frf_filter(h0, f0, FS, r))


@pytest.mark.parametrize("fs", [FS, 37.3])
@pytest.mark.parametrize("dc", [True, False])
def test_frf_filter_is_the_old_per_entry_interpolation_bit_for_bit(fs, dc):
    """The record's lines on and between the FRF's lines, and beyond its last (fs > FS)."""
    x, y = _records(3000, 2, 3)
    h = _old_h1_spectra(x, y, FS, 256)
    r = np.random.default_rng(1).standard_normal((777, 2))
    new = frf_filter(h["H"], h["f"], fs, r, dc=dc)
    np.testing.assert_array_equal(new, _old_frf_filter(h["H"], h["f"], fs, r, dc=dc))


def test_frf_filter_uses_the_end_values_beyond_the_grid_as_numpy_interp():
    f = np.array([1.0, 2.0, 4.0])
    M = (np.array([1.0, 2.0, 3.0]) + 1j * np.array([0.0, -1.0, 5.0]))[:, None, None]
    r = np.random.default_rng(2).standard_normal((50, 1))
    np.testing.assert_array_equal(frf_filter(M, f, 20.0, r), _old_frf_filter(M, f, 20.0, r))


# ---------------------------------------------------------------- equivalence: vrig.spectra's own
def test_the_spectral_matrix_is_the_old_broadcast_csd_to_round_off():
    """The old ``spectral_matrix`` called ``csd`` on broadcast (n, p, q) records: numpy's
    complex product of a broadcast operand takes another loop than csd's per-pair product (and
    csd's ``Y conj(X)`` is not ``conj(X) Y`` bit for bit), so the two differ by round-off."""
    x, y = _records(8192, 3, 2)
    _, old = _old_spectral_matrix(y, x, FS, 256)
    _, new = spectral_matrix(y, x, fs=FS, nperseg=256)
    np.testing.assert_allclose(new, old, rtol=0, atol=1e-15 * np.abs(old).max())


def test_h1_global_is_the_old_frf_h1_to_round_off():
    """The matched identification and ``frf_resonance``: the default (``"global"``) is the old
    ``frf_h1``'s regularisation, the same code; from the same spectra the inverse is bit for
    bit and only the product differs (``einsum`` here, BLAS ``@`` before): 1e-13 relative to
    the largest |H|. From the records, the spectra differ by round-off as well (above)."""
    x, y = _records(8192, 3, 2)
    f, gxx = spectral_matrix(x, fs=FS, nperseg=256)
    _, gyx = spectral_matrix(y, x, fs=FS, nperseg=256)
    _, gyy = spectral_matrix(y, fs=FS, nperseg=256)
    (old,) = _old_frf_h1_from(gxx, gyx)
    new = frf_from_spectra(f, gxx, gyx, gyy)
    assert DEFAULT_RCOND["global"] == 1e-10
    np.testing.assert_allclose(new.frf, old, rtol=0, atol=1e-13 * np.abs(old).max())
    _, old_records = _old_frf_h1(x, y, FS, 256)
    est = frf_h1(x, y, fs=FS, nperseg=256)
    np.testing.assert_allclose(est.frf, old_records, rtol=0, atol=1e-13 * np.abs(old).max())


# ---------------------------------------------------------------- equivalence: linearity
@pytest.mark.parametrize("p", [1, 2])
def test_the_linearity_checks_coherence_and_h1_are_h1_line_to_round_off(p):
    """``linearity._csd_matrix`` used ``csd(x_i, x_j)`` (the transposed convention, a different
    rounding of the same products) and per-line ``pinv(S_uu) @ S_uy``: the coherence agrees to
    1e-13, the H1 (transposed) to 1e-12 of its largest entry, the PSDs (``welch``'s
    ``|X|²`` against the real part of ``X conj(X)``) to a few ulp, 4e-15 relative."""
    x, y = _records(6000, p, 2)
    f0, g0, pyy0 = _old_linearity_coherence(x, y, FS, 256)
    est = frf_h1(x, y, fs=FS, nperseg=256, regularisation="line")
    np.testing.assert_array_equal(est.f, f0)
    np.testing.assert_allclose(est.coherence, g0, rtol=0, atol=1e-13)
    np.testing.assert_allclose(np.real(np.einsum("fii->fi", est.gyy)), pyy0, rtol=4e-15)
    inb = (f0 > 2) & (f0 < 30)
    h0 = _old_linearity_h1(x, y, FS, 256, inb)
    h = np.where(inb[:, None, None], np.swapaxes(est.frf, 1, 2), 0.0)
    np.testing.assert_allclose(h, h0, rtol=0, atol=1e-12 * np.abs(h0).max())


# ---------------------------------------------------------------- equivalence: band edges
@pytest.mark.parametrize("band", [(0.0, 40.0), (0.0, 10.0), (2.0, 32.0), (10.0, 60.0)])
@pytest.mark.parametrize("n_bands", range(1, 14))
def test_band_edges_are_the_envs_octaves_exactly_and_the_secants_to_round_off(band, n_bands):
    """Up to 7 bands from 0 Hz the two old rules agreed in value; the core is the environments'
    ``hi / 2**k`` bit for bit there (the gym figures stay) and the updates' six-octave cap beyond
    (the environments' rule put 13 bands' second edge at 0.01 Hz); the updates' ``geomspace``
    was off the exact octaves by up to 3 ulp (1e-15 relative), which the core no longer is."""
    new = band_edges(band, n_bands)
    if band[0] > 0 or n_bands <= 7:
        np.testing.assert_array_equal(new, _old_env_band_edges(band, n_bands))
    np.testing.assert_allclose(new, _old_log_band_edges(band, n_bands), rtol=1e-15, atol=0)
    if band[0] > 0:
        np.testing.assert_array_equal(new, _old_log_band_edges(band, n_bands))


def test_band_edges_from_zero_cap_at_six_octaves():
    np.testing.assert_array_equal(band_edges((0.0, 64.0), 7), [0, 1, 2, 4, 8, 16, 32, 64])
    fine = band_edges((0.0, 64.0), 13)
    assert fine[1] == 1.0 and fine[-1] == 64.0  # six octaves, in half-octave bands
    np.testing.assert_allclose(np.diff(np.log2(fine[1:])), 0.5, rtol=1e-12)


# ---------------------------------------------------------------- targets.py, for the rewiring
def test_targets_spectra_is_the_spectral_matrix_to_summation_order():
    """``targets._spectra(z)`` is ``spectral_matrix(z)``: it sums the segments' products in
    blocks by einsum and scales once, csd scales each segment and takes numpy's mean: 1e-14
    relative to the largest entry."""
    x, y = _records(20000, 3, 4)
    z = np.hstack([x, y])
    for nperseg in (256, 255):
        f0, g0 = _targets_spectra(z, FS, nperseg)
        f, g = spectral_matrix(z, fs=FS, nperseg=nperseg)
        np.testing.assert_allclose(f, f0, rtol=1e-15)
        np.testing.assert_allclose(g, g0, rtol=0, atol=1e-14 * np.abs(g0).max())


def test_targets_h1_is_frf_from_spectra_solve_bit_for_bit():
    """``targets._h1(Sxx, Sxy)`` is ``frf_from_spectra(f, Sxx, conj(Sxy)^T, Syy,
    regularisation="solve").frf`` bit for bit, from the same spectra."""
    x, y = _records(6000, 3, 2)
    f, S = _targets_spectra(np.hstack([x, y]), FS, 256)
    Sxx, Sxy, Syy = S[:, :3, :3], S[:, :3, 3:], S[:, 3:, 3:]
    gyx = np.conj(np.swapaxes(Sxy, -1, -2))
    new = frf_from_spectra(f, Sxx, gyx, Syy, regularisation="solve")
    np.testing.assert_array_equal(new.frf, _targets_h1(Sxx, Sxy))


def test_targets_interp_lines_is_interpolate_lines_bit_for_bit():
    """``targets._interp_lines(f, M, f_new)`` is ``interpolate_lines(M, f, f_new)``."""
    x, y = _records(3000, 2, 3)
    h = _old_h1_spectra(x, y, FS, 256)
    f_new = np.fft.rfftfreq(1234, 1.0 / FS)[1:-3]
    new = interpolate_lines(h["H"], h["f"], f_new)
    np.testing.assert_array_equal(new, _targets_interp_lines(h["f"], h["H"], f_new))


def test_targets_multiple_coherence_is_h1_solves_coherence_to_round_off():
    """``targets.multiple_coherence(x, y, fs, nperseg=n)`` is ``frf_h1(x, y, fs=fs, nperseg=n,
    regularisation="solve").coherence`` to 1e-12 (the spectra's summation order, above) where
    the drives' spectral matrix has full rank; where it has not, targets gives NaN and "solve"
    raises (the rewiring should keep a rank test, or use the default and accept finite γ²)."""
    x, y = _records(20000, 2, 3)
    f0, g0 = _targets_multiple_coherence(x, y, FS, 256)
    est = frf_h1(x, y, fs=FS, nperseg=256, regularisation="solve")
    np.testing.assert_allclose(est.f, f0, rtol=1e-15)
    np.testing.assert_allclose(est.coherence, g0, rtol=0, atol=1e-12)


def test_the_rewired_multiple_coherence_is_the_old_one_singular_lines_included():
    """:func:`vrig.desired.reachability.multiple_coherence` on the core (spectral_matrix, H1 by
    "solve" on the lines whose drives' matrix has full rank, NaN elsewhere) against the frozen
    pre-refactor one: the same NaN lines, the others to 1e-12 (summation order)."""
    from vrig.desired.reachability import multiple_coherence

    x, y = _records(20000, 2, 3)
    f0, g0 = _targets_multiple_coherence(x, y, FS, 256)
    f1, g1 = multiple_coherence(x, y, FS, nperseg=256)
    np.testing.assert_array_equal(f1, f0)
    np.testing.assert_allclose(g1, g0, rtol=0, atol=1e-12)
    twin = np.hstack([x[:, :1], x[:, :1]])  # two identical drives: singular on every line
    f0, g0 = _targets_multiple_coherence(twin, y, FS, 256)
    f1, g1 = multiple_coherence(twin, y, FS, nperseg=256)
    assert np.isnan(g0).all() and np.isnan(g1).all()


# ---------------------------------------------------------------- analytic truth
TAPS = {(0, 0): [0.5, 0.3, -0.1], (0, 1): [0.0, 0.4], (1, 0): [0.2, -0.2, 0.1], (1, 1): [1.0, 0.5]}


def _fir(x, noise, seed):
    rng = np.random.default_rng(seed)
    y = np.zeros_like(x)
    for (i, j), b in TAPS.items():
        y[:, i] += signal.lfilter(b, [1.0], x[:, j])
    return y + noise * rng.standard_normal(y.shape)


def _fir_frf(f):
    h = np.zeros((f.size, 2, 2), complex)
    for (i, j), b in TAPS.items():
        h[:, i, j] = signal.freqz(b, [1.0], worN=f, fs=FS)[1]
    return h


@pytest.mark.parametrize("regularisation", ["global", "line", "solve"])
def test_h1_of_a_2x2_fir_system_under_white_noise_is_its_frf_with_unit_coherence(regularisation):
    """Noise-free: H1 is the FIR's FRF up to the Welch estimate's leakage bias (taps of at most
    3 samples against 256-sample Hann segments: well under 1 %), and every response is a linear
    function of the drives, γ² = 1 but for the same bias (the part of a segment's response
    whose drive fell before the segment: about the taps' length over the segment's, 1 %)."""
    x = np.random.default_rng(0).standard_normal((2**15, 2))
    est = frf_h1(x, _fir(x, 0.0, 1), fs=FS, nperseg=256, regularisation=regularisation)
    truth = _fir_frf(est.f)
    assert np.abs(est.frf - truth).max() < 0.01 * np.abs(truth).max()
    assert est.coherence.min() > 0.99


def test_h1_with_output_noise_has_coherence_snr_over_one_plus_snr():
    """White drives (PSD 2/fs each), independent white output noise of rms σ (PSD 2σ²/fs):
    ``SNR_i(f) = Σ_j |H_ij|² / σ²`` and ``γ²_i = SNR / (1 + SNR)``. Estimated from 255 averages
    (bias (1 - γ²) m / n_d, random error ~ sqrt(2/n_d) (1 - γ²)): within 0.02 on the median line,
    0.1 on every line. H1 stays unbiased by the output noise: its error is the random error
    ``E|ΔH_ij|² = N / (n_e G_xx) = σ² / n_e`` of ``n_e = n_d / 1.06`` independent averages (50 %
    overlapped Hann segments): the rms over lines within 1.5 times that, no entry beyond 5."""
    sigma = 0.5
    x = np.random.default_rng(0).standard_normal((2**15, 2))
    est = frf_h1(x, _fir(x, sigma, 1), fs=FS, nperseg=256)
    truth = _fir_frf(est.f)
    snr = np.sum(np.abs(truth) ** 2, axis=2) / sigma**2
    predicted = snr / (1 + snr)
    err = np.abs(est.coherence - predicted)
    assert np.median(err) < 0.02 and err.max() < 0.1
    n_e = ((2**15 - 128) // 128) / 1.06
    random_error = sigma / np.sqrt(n_e)
    dh = np.abs(est.frf - truth)[1:-1]  # DC and Nyquist: real lines, another distribution
    assert np.sqrt(np.mean(dh**2)) < 1.5 * random_error
    assert dh.max() < 5 * random_error


def test_an_ill_conditioned_drive_matrix_is_truncated_as_documented():
    """Two drives, the second a copy of the first: G_xx has rank 1 at every line. The default
    truncation drops the unexcited direction (s_2 ~ 1e-16 s_1 < 1e-10 of the largest), giving
    the minimum-norm H that explains the response (``H G_xx = G_yx``, the drive's FRF split
    equally between the two copies: 0.5 (h_0 + h_1)) and γ² = 1 (but for the leakage bias of
    the test above); ``"solve"`` divides by
    round-off (unbounded H or LinAlgError); a band-limited drive leaves lines without power at
    H = 0 under the default."""
    rng = np.random.default_rng(4)
    x1 = rng.standard_normal(2**14)
    x = np.stack([x1, x1], axis=1)
    y = _fir(x, 0.0, 1)
    est = frf_h1(x, y, fs=FS, nperseg=256)
    truth = _fir_frf(est.f)
    combined = truth.sum(axis=2)  # both drives are x1: y_i = (h_i0 + h_i1) x1
    np.testing.assert_allclose(est.frf, 0.5 * combined[:, :, None] * np.ones(2), atol=0.01)
    assert est.coherence.min() > 0.99
    np.testing.assert_allclose(est.frf @ est.gxx, est.gyx, atol=1e-12 * np.abs(est.gyx).max())
    try:
        bad = frf_h1(x, y, fs=FS, nperseg=256, regularisation="solve").frf
    except np.linalg.LinAlgError:
        pass
    else:
        assert np.abs(bad).max() > 100 * np.abs(combined).max()
    # a drive with no power above 20 Hz: the default leaves those lines at H = 0
    low = signal.lfilter(*signal.butter(8, 15, fs=FS), rng.standard_normal((2**14, 2)), axis=0)
    low = signal.sosfiltfilt(signal.butter(12, 20, fs=FS, output="sos"), low, axis=0)
    est = frf_h1(low, _fir(low, 0.0, 2), fs=FS, nperseg=256)
    s = np.linalg.svd(est.gxx, compute_uv=False)
    dead = s[:, 0] <= 1e-10 * s.max()
    assert dead.any()
    np.testing.assert_array_equal(est.frf[dead], 0.0)


@pytest.mark.parametrize(
    ("call", "match"),
    [
        (lambda g: frf_from_spectra(g[0], g[1], g[2], g[3], regularisation="tikhonov"),
         "regularisation must be one of"),
        (lambda g: frf_from_spectra(g[0], g[1], g[2], g[3], rcond=-1.0), "rcond"),
        (lambda g: frf_from_spectra(g[0], g[1][:, :1], g[2], g[3]), "gxx, gyx, gyy"),
        (lambda g: frf_filter(g[2], g[0][::-1], FS, np.zeros((10, 2))), "increasing"),
        (lambda g: frf_filter(g[2], g[0], FS, np.zeros((10, 3))), "x must be"),
        (lambda g: band_edges((5.0, 1.0), 4), "band must"),
        (lambda g: band_edges((0.0, 10.0), 0), "n_bands"),
    ],
)  # fmt: skip
def test_bad_input_is_refused_clearly(call, match):
    x, y = _records(1000, 2, 2)
    f, gxx = spectral_matrix(x, fs=FS, nperseg=64)
    _, gyx = spectral_matrix(y, x, fs=FS, nperseg=64)
    _, gyy = spectral_matrix(y, fs=FS, nperseg=64)
    with pytest.raises(ValueError, match=match):
        call((f, gxx, gyx, gyy))
