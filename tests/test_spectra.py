"""Spectral matrices, the H1 FRF and drive-PSD shaping (vrig.spectra) on known linear systems.

Truth: digital filters whose frequency response scipy.signal.freqz gives exactly; targets that
are the responses of those filters to uncorrelated drives with known PSDs.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy import signal

from vrig.signals import random_drive
from vrig.spectra import frf_h1, matched_drive_psd, psd_function, spectral_matrix

FS = 200.0
# a 3 x 2 system (responses x drives) of IIR filters: low-pass, first-order, delay, band-pass
SYSTEM = {
    (0, 0): signal.butter(2, 20, fs=FS),
    (0, 1): ([0.3, 0.1], [1.0, -0.5]),
    (1, 0): ([0.0, 0.5], [1.0]),
    (1, 1): signal.cheby1(2, 1, [5, 30], btype="band", fs=FS),
    (2, 0): ([0.2, 0.2], [1.0, -0.3]),
}


def _run(x, pairs=SYSTEM, q=3):
    y = np.zeros((x.shape[0], q))
    for (i, j), (b, a) in pairs.items():
        y[:, i] += signal.lfilter(b, a, x[:, j])
    return y


def _frf(f, pairs=SYSTEM, q=3, p=2):
    h = np.zeros((f.size, q, p), complex)
    for (i, j), (b, a) in pairs.items():
        h[:, i, j] = signal.freqz(b, a, worN=f, fs=FS)[1]
    return h


def _drive_psds(f):
    """Two smooth drive PSDs, above 5 % of their peak below 40 Hz, zero above."""
    bump = np.exp(-(((f - 8) / 5) ** 2)) + 0.05
    lowpass = 1 / (1 + (f / 10) ** 2)
    return np.stack([bump, lowpass], axis=1) * (f < 40)[:, None]


def test_the_spectral_matrix_follows_scipy_welch_and_is_hermitian():
    x = np.random.default_rng(0).standard_normal((8192, 3))
    _, s = spectral_matrix(x, fs=FS, nperseg=256)
    _, pxx = signal.welch(x, fs=FS, nperseg=256, axis=0)
    np.testing.assert_allclose(np.real(np.einsum("fii->fi", s)), pxx, rtol=1e-12)
    np.testing.assert_allclose(s, np.conj(np.transpose(s, (0, 2, 1))), atol=1e-15)


def test_h1_estimates_a_known_mimo_system_despite_output_noise():
    rng = np.random.default_rng(1)
    x = rng.standard_normal((2**17, 2))
    y = _run(x) + 0.05 * rng.standard_normal((2**17, 3))  # transducer noise on the responses
    est = frf_h1(x, y, fs=FS, nperseg=512)
    f, h = est.f, est.frf
    band = (f > 1) & (f < 40)
    truth = _frf(f)
    err = np.abs(h - truth)[band] / np.abs(truth[band]).max()  # (2, 1) is no path: H = 0
    assert err.max() < 0.03


@pytest.mark.parametrize("q", [1, 2, 3])
def test_the_shaped_psd_recovers_the_drives_of_a_known_target_exactly(q):
    """Target = H D H^H for diagonal D (the response to uncorrelated drives): the drive PSD is
    D itself wherever H has full column rank (SISO, square 2 x 2, over-determined 3 x 2)."""
    f = np.linspace(0, 60, 241)
    p = 1 if q == 1 else 2
    pairs = {k: v for k, v in SYSTEM.items() if k[0] < q and k[1] < p}
    h = _frf(f, pairs, q, p)
    d = _drive_psds(f)[:, :p]
    target = np.einsum("fij,fj,fkj->fik", h, d, h.conj())
    mask = (f > 0.5) & (f < 39)  # lines where every H above has full column rank
    out = matched_drive_psd(h, target, mask=mask, regularisation=0.0, smooth=1, floor=0.0)
    np.testing.assert_allclose(out[mask], d[mask], rtol=1e-8)
    assert np.all(out[~mask] == 0)


def test_auto_psds_alone_make_a_diagonal_target_for_a_siso_system():
    f = np.linspace(0, 60, 121)
    h = _frf(f, {(0, 0): SYSTEM[(0, 0)]}, 1, 1)[:, 0, 0]
    d = _drive_psds(f)[:, 0]
    out = matched_drive_psd(h, np.abs(h) ** 2 * d, regularisation=0.0, smooth=1, floor=0.0)
    np.testing.assert_allclose(out[:, 0], d, rtol=1e-9, atol=1e-15)


def test_the_shaped_drive_through_the_system_reproduces_the_target_psd():
    """The whole chain with estimates: a probe gives H1, a target record gives its spectral
    matrix, the shaped drive is synthesised and played through the system; its responses'
    auto-PSDs (4 Hz bins) and RMS match the target's."""
    n, nper = 2**17, 512
    rng = np.random.default_rng(2)
    probe = rng.standard_normal((n, 2))
    est = frf_h1(probe, _run(probe), fs=FS, nperseg=nper)
    f, h = est.f, est.frf
    d = _drive_psds(f)
    df = f[1] - f[0]
    xt = random_drive(psd_function(f, d), n, FS, channels=2, rms=np.sqrt(d.sum(0) * df), seed=3)
    yt = _run(xt.data)
    _, gt = spectral_matrix(yt, fs=FS, nperseg=nper)
    mask = (f > 0) & (f < 40)
    psd = matched_drive_psd(h, gt, mask=mask)
    xs = random_drive(psd_function(f, psd), n, FS, channels=2, rms=np.sqrt(psd.sum(0) * df), seed=4)
    ys = _run(xs.data)
    _, gs = spectral_matrix(ys, fs=FS, nperseg=nper)
    target, got = (np.real(np.einsum("fii->fi", g)) for g in (gt, gs))
    for lo in np.arange(0, 36, 4.0):
        s = (f >= lo) & (f < lo + 4)
        np.testing.assert_allclose(got[s].sum(0), target[s].sum(0), rtol=0.06)
    np.testing.assert_allclose(ys.std(0), yt.std(0), rtol=0.03)


def test_the_floor_excites_every_line_of_the_mask_and_nothing_outside():
    f = np.linspace(0, 50, 101)
    h = np.ones(f.size)
    target = np.where((f > 10) & (f < 20), 1.0, 0.0)  # nothing to reach elsewhere
    mask = (f > 0) & (f <= 30)
    out = matched_drive_psd(h, target, mask=mask, floor=0.01, smooth=1, regularisation=0.0)[:, 0]
    assert out.max() == 1.0
    assert np.all(out[mask] >= 0.01) and np.all(out[~mask] == 0)
    np.testing.assert_array_equal(out[mask & (target == 0)], 0.01)


def test_a_line_the_system_cannot_reach_gets_a_bounded_drive():
    """A notch (|H| -> 0): the Tikhonov pseudo-inverse's gain s/(s² + λ²) is at most 1/(2λ),
    so the drive PSD is at most G/(4λ²) there instead of G/|H|² -> infinity."""
    f = np.linspace(0, 50, 101)
    h = np.abs(f - 25.0) / 25.0  # zero at 25 Hz, largest 1
    lam = 1e-2
    out = matched_drive_psd(h, np.ones(f.size), regularisation=lam, smooth=1, floor=0.0)[:, 0]
    assert np.all(np.isfinite(out))
    assert out.max() <= 1 / (4 * lam**2) * (1 + 1e-12)
    assert out[f == 25.0][0] == 0.0


@pytest.mark.parametrize(
    "call,match",
    [
        (lambda: spectral_matrix(np.zeros((100, 1)), fs=FS, nperseg=200), "longer than the record"),
        (lambda: spectral_matrix(np.zeros((100, 1)), fs=FS, nperseg=4), "nperseg"),
        (
            lambda: spectral_matrix(np.zeros((100, 1)), np.zeros((90, 1)), fs=FS, nperseg=32),
            "same length",
        ),
        (lambda: spectral_matrix([[np.nan]] * 100, fs=FS, nperseg=32), "finite"),
        (lambda: matched_drive_psd(np.ones((5, 2, 2)), np.ones((5, 3))), "target must be"),
        (lambda: matched_drive_psd(np.ones(5), np.ones(5), floor=2.0), "floor"),
        (lambda: matched_drive_psd(np.ones(5), np.ones(5), smooth=0), "smooth"),
        (lambda: matched_drive_psd(np.ones(5), np.ones(5), mask=np.zeros(5, bool)), "mask"),
        (lambda: matched_drive_psd(np.ones(5), np.ones(5), regularisation=-1), "regularisation"),
        (lambda: psd_function([0, 2, 1], [1, 1, 1]), "increasing"),
        (lambda: psd_function([0, 1, 2], [1, -1, 1]), "non-negative"),
    ],
)
def test_bad_input_is_one_clear_error(call, match):
    with pytest.raises(ValueError, match=match):
        call()
