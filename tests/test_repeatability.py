"""Repeatability (§3.1): the measures on synthetic runs and the ordering physics predicts."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import signal

import vrig
from identification import band_limited_noise
from vrig.repeatability import repeatability_function, repeatability_number, signal_to_noise
from vrig.signals import random_drive, triangular_psd


def test_identical_runs_are_perfectly_repeatable():
    x = band_limited_noise(4000, 2, seed=1)
    assert np.allclose(repeatability_number([x, x, x]), 100.0)
    _f, rf = repeatability_function([x, x], fs=100.0)
    assert np.allclose(rf[np.isfinite(rf)], 100.0)


def test_number_falls_with_noise_and_snr_tracks_it_per_band():
    rng = np.random.default_rng(2)
    s = band_limited_noise(2**15, 1, cutoff=0.2, seed=3)[:, 0]  # signal below 0.2 Nyquist
    runs = [s + 0.01 * rng.standard_normal(s.size) for _ in range(5)]
    noisy = [s + 0.1 * rng.standard_normal(s.size) for _ in range(5)]
    assert repeatability_number(runs)[0] > repeatability_number(noisy)[0]
    f, snr = signal_to_noise(runs, fs=1.0, nperseg=512)
    in_band, out_band = snr[f < 0.08, 0], snr[(f > 0.2) & (f < 0.5), 0]
    # in band: signal PSD ~ 1/(0.1 * ... ) vs white noise 1e-4 per unit band: tens of dB
    assert np.median(in_band) > 20.0
    assert np.median(out_band) < -10.0  # noise only: no repeatable content


def test_number_in_the_simulation_bandwidth_ignores_out_of_band_noise():
    # a repeatable signal below 25 Hz plus run-to-run noise only above 100 Hz (rattle, hiss): in
    # the 0-25 Hz simulation bandwidth the runs are identical, in the full band they are not
    fs = 1000.0
    rng = np.random.default_rng(5)
    s = band_limited_noise(2**14, 1, cutoff=25 / (fs / 2), seed=6)[:, 0]
    hp = signal.butter(8, 100.0, btype="highpass", fs=fs, output="sos")
    hiss = signal.sosfiltfilt(hp, rng.standard_normal((2**14, 5)), axis=0)
    runs = [s + 0.3 * s.std() * h / h.std() for h in hiss.T]
    full = repeatability_number(runs)[0]
    in_band = repeatability_number(runs, fs=fs, band=(0.0, 25.0))[0]
    assert full < 90.0  # 30 % rms noise: the full-band number falls far below 100
    assert in_band > 99.9  # the filter's stop band leaves < 0.1 % of it
    # run-to-run noise inside the band counts: 1 % rms white noise on every run
    noisy = [s + 0.01 * s.std() * rng.standard_normal(s.size) for _ in range(5)]
    r = repeatability_number(noisy, fs=fs, band=(0.0, 25.0))[0]
    # white noise keeps 25/500 of its power in 0-25 Hz: eta0 (mean |e| / mean |y|) of a run
    # against the mean of 5 ~ sqrt(4/5) * 0.01 * sqrt(25/500) = 0.2 % of the signal
    assert 99.7 < r < 99.9


def _five_runs(rig, seconds, band, rms):
    drive = random_drive(
        triangular_psd(band),
        int(seconds * rig.fs),
        rig.fs,
        rms=rms,
        seed=4,
        names=[c.name for c in rig.inputs],
        unit=rig.inputs[0].unit,
    )
    return [rig.run(drive) for _ in range(5)]  # successive noise streams of one rig


def test_rigs_order_as_physics_says():
    shaker = repeatability_number(_five_runs(vrig.load_rig("shaker"), 8, (0, 80), 0.5))[0]
    damper = repeatability_number(_five_runs(vrig.load_rig("shock-absorber"), 8, (0, 10), 0.003))[0]
    assert shaker > damper  # no backlash or friction on the shaker (text: 99.75 % vs 98.5 %)


@pytest.mark.xfail(
    strict=True,
    reason="a prediction the calibrated twin misses (issue 23): with the controller's noise "
    "calibrated on Table 3.2, that noise dominates both channels and the strain comes out less "
    "repeatable than the acceleration (97.8 vs 98.2 %); the text's ordering comes from the "
    "accelerometer's poor low-frequency sensitivity, which the energy-weighted number hardly sees",
)
def test_motorcycle_strain_more_repeatable_than_acceleration():
    """At the text's procedure (``vrig repeatability``: a 20 s pseudo-field drive over 0-30 Hz,
    five runs, the number in that band)."""
    from vrig.desired.pseudo_field import pseudo_field

    moto = vrig.load_rig("motorcycle-rear", seed=0)
    drive, first = pseudo_field(moto, (0.0, 30.0), 20.0, seed=0)
    runs = [first] + [moto.run(drive, seed=10_000 + k) for k in range(1, 5)]
    r = repeatability_number(runs, fs=moto.fs, band=(0.0, 30.0))
    names = [c.name for c in moto.outputs]
    strain = r[next(i for i, n in enumerate(names) if "strain" in n)]
    acc = r[next(i for i, n in enumerate(names) if "acc" in n)]
    assert strain > acc  # the text: strain 98.15 % > acceleration 97.80 %


def test_bad_input():
    with pytest.raises(ValueError, match="at least 2 runs"):
        repeatability_number([np.ones(10)])
    with pytest.raises(ValueError, match="same shape"):
        repeatability_number([np.ones(10), np.ones(11)])
    with pytest.raises(ValueError, match="sample rate"):
        repeatability_number([np.ones(100), np.ones(100)], band=(0.0, 10.0))
    with pytest.raises(ValueError, match="fs/2"):
        repeatability_number([np.ones(100), np.ones(100)], fs=100.0, band=(0.0, 60.0))
