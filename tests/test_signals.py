"""Drive signals: PSD shapes, exact band limits, scaling, independence, sweeps, Algorithm 3.1."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import signal

from vrig import TimeHistory
from vrig.signals import (
    flat_psd,
    one_over_f_psd,
    random_drive,
    rig_specific_psd,
    sine_sweep,
    triangular_psd,
)

FS = 256.0


def test_band_limits_are_exact():
    d = random_drive(flat_psd((2.0, 30.0)), 4096, FS, seed=1)
    spectrum = np.abs(np.fft.rfft(d.data[:, 0]))
    f = np.fft.rfftfreq(4096, 1 / FS)
    outside = (f < 2.0) | (f > 30.0)
    assert spectrum[outside].max() < 1e-9 * spectrum.max()
    assert spectrum[~outside].min() > 1e-3 * spectrum.max()


def test_triangular_psd_shape_is_reproduced():
    d = random_drive(triangular_psd((0.0, 40.0)), 2**16, FS, seed=2)
    f, p = signal.welch(d.data[:, 0], fs=FS, nperseg=1024)
    ratio = p[(f > 5) & (f < 15)].mean() / p[(f > 25) & (f < 35)].mean()
    expected = (40 - 10) / (40 - 30)  # PSD at the bands' centres
    assert ratio == pytest.approx(expected, rel=0.15)


def test_one_over_f_psd_slope():
    d = random_drive(one_over_f_psd((1.0, 100.0), n=2.0), 2**16, FS, seed=3)
    f, p = signal.welch(d.data[:, 0], fs=FS, nperseg=2048)
    sel = (f > 5) & (f < 80)
    slope = np.polyfit(np.log(f[sel]), np.log(p[sel]), 1)[0]
    assert slope == pytest.approx(-2.0, abs=0.15)


def test_rms_and_peak_scaling_and_units():
    d = random_drive(
        flat_psd((0, 50)),
        8192,
        FS,
        channels=3,
        rms=[1.0, 2.0, 0.5],
        seed=4,
        names=["a", "b", "c"],
        unit="m",
    )
    np.testing.assert_allclose(np.sqrt((d.data**2).mean(axis=0)), [1.0, 2.0, 0.5], rtol=1e-12)
    assert d.units == ("m", "m", "m") and d.names == ("a", "b", "c") and d.fs == FS
    p = random_drive(flat_psd((0, 50)), 8192, FS, peak=0.01, seed=4)
    assert np.abs(p.data).max() == pytest.approx(0.01)


def test_channels_are_uncorrelated_and_seeded():
    d = random_drive(triangular_psd((0, 40)), 2**15, FS, channels=4, seed=5)
    c = np.corrcoef(d.data.T)
    assert np.max(np.abs(c - np.eye(4))) < 0.05
    assert np.array_equal(
        d.data, random_drive(triangular_psd((0, 40)), 2**15, FS, channels=4, seed=5).data
    )
    assert not np.array_equal(
        d.data, random_drive(triangular_psd((0, 40)), 2**15, FS, channels=4, seed=6).data
    )


def test_linear_and_log_sweeps():
    lin = sine_sweep(1.0, 50.0, 10.0, FS, amplitude=2.0)
    assert lin.n_samples == 2560 and np.abs(lin.data).max() == pytest.approx(2.0, rel=1e-3)
    analytic = signal.hilbert(lin.data[:, 0])
    inst = np.diff(np.unwrap(np.angle(analytic))) * FS / (2 * np.pi)
    mid = inst[1200:1400].mean()  # at t ~ 5 s a linear sweep is at the band's middle
    assert mid == pytest.approx(1 + 49 * 1300 / 2560, rel=0.03)
    log = sine_sweep(1.0, 64.0, 12.0, FS, kind="log")
    inst = np.diff(np.unwrap(np.angle(signal.hilbert(log.data[:, 0])))) * FS / (2 * np.pi)
    assert inst[1536 - 50 : 1536 + 50].mean() == pytest.approx(8.0, rel=0.05)  # geometric middle


def test_rig_specific_psd_lowers_excitation_at_resonance():
    # a resonant "rig" at 20 Hz: the sweep response peaks there, so Algorithm 3.1 lowers it
    sweep = sine_sweep(1.0, 60.0, 60.0, FS, amplitude=1.0)
    b, a = signal.iirpeak(20.0, Q=5, fs=FS)
    resp = sweep.with_data(signal.lfilter(b, a, sweep.data[:, 0]) + 0.3 * sweep.data[:, 0])
    (shape,) = rig_specific_psd(sweep, resp, nperseg=512)
    f = np.array([10.0, 20.0, 45.0, 100.0])
    level = shape(f)
    assert level[1] < 0.5 * level[0] and level[1] < 0.5 * level[2]
    assert level[3] == 0.0  # outside the swept band
    drive = random_drive(shape, 2**14, FS, rms=1.0, seed=1)
    fw, p = signal.welch(drive.data[:, 0], fs=FS, nperseg=512)
    assert p[np.argmin(abs(fw - 20))] < 0.5 * p[np.argmin(abs(fw - 10))]


def test_bad_arguments():
    with pytest.raises(ValueError, match="band"):
        random_drive(flat_psd((30.0, 2.0)), 1024, FS)
    with pytest.raises(ValueError, match="rms or peak"):
        random_drive(flat_psd((0, 10)), 1024, FS, rms=1, peak=1)
    with pytest.raises(ValueError, match="zero at every"):
        random_drive(flat_psd((200.0, 250.0)), 1024, FS)
    with pytest.raises(ValueError, match="pairs drive k"):
        rig_specific_psd(TimeHistory(np.ones((100, 2)), 10), TimeHistory(np.ones((100, 1)), 10))
    with pytest.raises(ValueError, match="kind"):
        sine_sweep(1, 10, 1, FS, kind="exp")
