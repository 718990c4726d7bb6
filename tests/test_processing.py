"""GPREPRO processing: zero-phase band-pass, de-trend/DC, identification band, split, decimation."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import signal

from vrig import TimeHistory
from vrig.processing import band_split, decimate, f2d, gprepro, identification_band

FS = 200.0


def _tones(freqs, n=8000, offset=0.0, trend=0.0):
    t = np.arange(n) / FS
    x = sum(np.sin(2 * np.pi * f * t) for f in freqs) + offset + trend * t
    return TimeHistory(x, FS, ["x"], ["m"])


def test_band_pass_keeps_in_band_tones_without_phase_shift():
    th = _tones([5.0, 80.0], offset=3.0, trend=0.5)
    out = gprepro(th, (2.0, 30.0)).data[:, 0]
    ref = np.sin(2 * np.pi * 5.0 * np.arange(8000) / FS)
    mid = slice(1000, 7000)
    np.testing.assert_allclose(out[mid], ref[mid], atol=0.02)  # zero phase: no lag
    assert abs(out.mean()) < 1e-12


def test_low_pass_when_band_starts_at_zero():
    out = gprepro(_tones([1.0, 60.0]), (0.0, 20.0), detrend=False).data[:, 0]
    f, p = signal.welch(out, fs=FS, nperseg=1024)
    assert p[np.argmin(abs(f - 60))] < 1e-6 * p[np.argmin(abs(f - 1))]


def test_identification_band_is_twenty_percent_broader():
    assert identification_band((1.0, 25.0)) == pytest.approx((1 / 1.2, 30.0))
    assert identification_band((0.0, 90.0), fs=FS)[1] == pytest.approx(0.45 * FS)


def test_band_split_is_complementary():
    th = _tones([3.0, 30.0])
    low, high = band_split(th, 12.0)
    np.testing.assert_allclose(low.data + high.data, th.data, atol=1e-12)
    f, pl = signal.welch(low.data[:, 0], fs=FS, nperseg=1024)
    _, ph = signal.welch(high.data[:, 0], fs=FS, nperseg=1024)
    i3, i30 = np.argmin(abs(f - 3)), np.argmin(abs(f - 30))
    assert pl[i3] > 1e3 * ph[i3] and ph[i30] > 1e3 * pl[i30]


def test_decimate_and_f2d():
    th = _tones([2.0])
    d = decimate(th, 4)
    assert d.fs == 50.0 and d.n_samples == 2000 and d.names == ("x",)
    assert f2d(th) is th
    scaled = f2d(th, lambda r: r.with_data(2 * r.data))
    np.testing.assert_allclose(scaled.data, 2 * th.data)
    with pytest.raises(TypeError, match="must return a TimeHistory"):
        f2d(th, lambda r: r.data)


def test_bad_bands():
    with pytest.raises(ValueError, match="band"):
        gprepro(_tones([1.0]), (10.0, 5.0))
    with pytest.raises(ValueError, match="above Nyquist"):
        gprepro(_tones([1.0]), (150.0, 200.0))
    with pytest.raises(ValueError, match="split frequency"):
        band_split(_tones([1.0]), 150.0)


def test_the_filter_designed_once_is_scipys_design_every_time():
    """gprepro keeps each band's Butterworth design (issue 26: one design per iteration was a
    visible part of a gym step): the result is the textbook pipeline with a fresh
    ``scipy.signal.butter`` design, bit for bit, on every call and for every band kind."""
    th = _tones([1.0, 5.0, 40.0, 90.0], offset=1.0, trend=0.3)
    for band, kind, edges in (
        ((2.0, 30.0), "bandpass", [2.0, 30.0]),
        ((0.0, 30.0), "lowpass", 30.0),
        ((2.0, 100.0), "highpass", 2.0),
    ):
        sos = signal.butter(4, edges, btype=kind, fs=FS, output="sos")
        x = signal.detrend(th.data, axis=0, type="linear")
        x = signal.sosfiltfilt(sos, x, axis=0, padlen=3 * (2 * len(sos) + 1))
        truth = x - x.mean(axis=0)
        for _ in range(2):
            np.testing.assert_array_equal(gprepro(th, band).data, truth)
