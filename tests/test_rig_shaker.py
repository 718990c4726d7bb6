"""The electro-dynamic shaker rig (models/shaker): a near-linear SDOF reference rig.

The truth the tests compare against is computed here from the documented parameters
(models/shaker/shaker.rig.json, README): the armature is a mass on a spring driven by a force
K_f * V, so the drive-voltage-to-shaft-acceleration FRF is

    H(w) = K_f (-w^2) / (k - m w^2 + j c w)  x  accelerometer high-pass  x  anti-alias filter
           x  linear interpolation of the drive from fs to the physics rate

(the documented drive path of vrig.rigs.MujocoRig).
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy import signal

import vrig
from identification import band_limited_noise
from vrig.repeatability import repeatability_number, signal_to_noise
from vrig.rigs.daq import transducer_response

FS = 500.0
BAND = 80.0  # test band [Hz] (reference text Sec. 3.1.1)


@pytest.fixture(scope="module")
def rig():
    return vrig.load_rig("shaker", seed=0)


def _drive(rig, seconds, rms, seed):
    """Band-limited (0-80 Hz) random amplifier voltage of the given RMS [V]."""
    n = round(seconds * rig.fs)
    return rms * band_limited_noise(n, 1, cutoff=BAND / (rig.fs / 2), seed=seed)


def _param(rig, name):
    return float(rig.description.parameters[name].value)


def _analytic_frf(rig, f):
    """Voltage -> measured acceleration FRF from the documented parameters."""
    m = _param(rig, "moving_mass")
    k = _param(rig, "suspension_stiffness")
    c = _param(rig, "suspension_damping")
    kf = _param(rig, "force_constant")
    w = 2 * np.pi * np.asarray(f, float)
    mech = kf * (-(w**2)) / (k - m * w**2 + 1j * c * w)
    physics_rate = 1.0 / rig.timestep
    hp = transducer_response(rig.output_defs[0].transducer, f, physics_rate)
    aa = rig.description.anti_alias.response(f, rig.fs, physics_rate)
    # linear interpolation fs -> physics rate: triangle kernel, zero phase
    interp = (np.sinc(f / rig.fs) / np.sinc(f / physics_rate)) ** 2
    return mech * hp * aa * interp


def test_random_drive_runs_with_the_documented_channels(rig):
    assert rig.fs == FS
    assert rig.bandwidth == (0.0, BAND)
    assert [c.name for c in rig.inputs] == ["amplifier_voltage"]
    assert [c.unit for c in rig.inputs] == ["V"]
    assert rig.inputs[0].kind == "direct"
    u = _drive(rig, 2.0, 0.5, seed=1)
    y = rig.run(u)
    assert y.data.shape == (1000, 1)
    assert list(y.names) == ["shaft_acc"]
    assert list(y.units) == ["m/s^2"]
    assert np.all(np.isfinite(y.data))
    assert 5.0 < y.data.std() < 200.0


def test_documented_suspension_resonance():
    """README: suspension resonance sqrt(k/m)/2pi = 31.8 Hz, zeta = 0.06 (from the parameters)."""
    r = vrig.load_rig("shaker")
    m, k, c = (_param(r, p) for p in ("moving_mass", "suspension_stiffness", "suspension_damping"))
    assert np.sqrt(k / m) / (2 * np.pi) == pytest.approx(31.8, abs=0.05)
    assert c / (2 * np.sqrt(k * m)) == pytest.approx(0.06, abs=1e-3)
    # the compiled model carries the documented values
    assert r.model.body_subtreemass[r.model.body("armature").id] == pytest.approx(m)
    assert r.model.jnt_stiffness[0] == pytest.approx(k)
    assert r.model.dof_damping[0] == pytest.approx(c)
    assert r.model.actuator_gear[0, 0] == pytest.approx(_param(r, "force_constant"))


def test_h1_frf_matches_the_analytic_linear_model(rig):
    """(a) H1 from 40 s of random drive within 1 dB and 5 degrees of the analytic model, 10-80 Hz."""
    u = _drive(rig, 40.0, 0.6, seed=11)
    y = rig.run(u, seed=12).data[:, 0]
    nper = round(4 * rig.fs)  # 0.25 Hz lines, 19 averages
    f, puu = signal.welch(u[:, 0], rig.fs, nperseg=nper)
    _, puy = signal.csd(u[:, 0], y, rig.fs, nperseg=nper)
    sel = (f >= 10.0) & (f <= BAND)
    ratio = (puy[sel] / puu[sel]) / _analytic_frf(rig, f[sel])
    err_db = 20 * np.log10(np.abs(ratio))
    err_deg = np.degrees(np.angle(ratio))
    assert np.abs(err_db).max() < 1.0, f"max magnitude error {np.abs(err_db).max():.2f} dB"
    assert np.abs(err_deg).max() < 5.0, f"max phase error {np.abs(err_deg).max():.2f} deg"
    # the resonance peak of the estimate sits at the documented suspension resonance
    h1 = np.abs(puy / puu)
    f_peak = f[sel][np.argmax(h1[sel])]
    assert f_peak == pytest.approx(31.8, abs=0.5)


def test_superposition(rig):
    """(b) response to 2u = 2 x response to u, within the noise (same noise streams: seed)."""
    u = _drive(rig, 5.0, 0.4, seed=21)
    y1 = rig.run(u, seed=5).data[:, 0]
    y2 = rig.run(2 * u, seed=5).data[:, 0]
    y0 = rig.run(0 * u, seed=5).data[:, 0]  # the same noise alone (amplifier, sensor, mains)
    noise = y0.std()
    assert 0.02 < noise < 0.5  # documented noise floor + 0.1 m/s^2 mains hum
    # y(2u) - 2 y(u) is the (negated) noise of one run: at the noise level, far below the signal
    assert (y2 - 2 * y1).std() < 1.5 * noise
    assert (y2 - 2 * y1).std() < 1e-2 * y1.std()
    # with the noise removed exactly (y0 carries the same streams) the rest is quantisation:
    # three 16-bit samples over +-490 m/s^2, each rounded to half an LSB
    lsb = 2 * rig.outputs[0].full_scale / 2**16
    assert np.abs(y2 - 2 * y1 + y0).max() <= 1.5 * lsb + 1e-9


def test_five_run_repeatability():
    """(c) 5 runs of the same drive with different noise streams: repeatability >= 99.5 %;
    the mains pickup makes 50 Hz the least repeatable line in the band (text Sec. 3.1.1)."""
    r = vrig.load_rig("shaker", seed=3)
    u = _drive(r, 10.0, 0.5, seed=31)
    runs = [r.run(u) for _ in range(5)]
    rep = repeatability_number(runs)[0]
    assert 99.5 <= rep < 100.0, rep
    f, snr = signal_to_noise(runs, r.fs, nperseg=500)
    snr = snr[:, 0]
    at50 = snr[f == 50.0][0]
    neighbours = snr[((f >= 20) & (f <= 40)) | ((f >= 60) & (f <= 80))]
    assert at50 < np.median(neighbours) - 10.0
    # without the hum the 50 Hz line is as repeatable as its neighbours
    quiet = vrig.load_rig("shaker", seed=3, mains_pickup=0.0)
    runs_q = [quiet.run(u) for _ in range(5)]
    _, snr_q = signal_to_noise(runs_q, r.fs, nperseg=500)
    assert snr_q[f == 50.0, 0][0] > at50 + 10.0


def test_interlocks():
    r = vrig.load_rig("shaker", seed=0)
    t = np.arange(1000) / r.fs
    with pytest.raises(vrig.RigLimitError, match="drive"):
        r.run(10.5 * np.sin(2 * np.pi * 20 * t))  # beyond the amplifier's +-10 V
    # full-scale sine at the suspension resonance: the accelerometer range trips
    with pytest.raises(vrig.RigLimitError, match="transducer range"):
        r.run(10.0 * np.sin(2 * np.pi * 31.8 * t))
    # full-scale sine below resonance: 10 V -> 100 N -> 10.3 mm at 5 Hz, inside the 12.7 mm stroke;
    # the acceleration amplitude follows the SDOF model and the 2 Hz high-pass
    t = np.arange(1500) / r.fs
    y = r.run(10.0 * np.sin(2 * np.pi * 5.0 * t)).data[500:, 0]
    m, k, kf = (_param(r, p) for p in ("moving_mass", "suspension_stiffness", "force_constant"))
    w = 2 * np.pi * 5.0
    assert kf * 10.0 / (k - m * w**2) < _param(r, "stroke")
    expected = kf * 10.0 * w**2 / abs(k - m * w**2)
    expected *= abs(transducer_response(r.output_defs[0].transducer, [5.0], 1 / r.timestep)[0])
    expected *= abs(r.description.anti_alias.response([5.0], r.fs, 1 / r.timestep)[0])
    tt = t[500:]
    basis = np.c_[np.sin(w * tt), np.cos(w * tt)]
    amp = np.hypot(*np.linalg.lstsq(basis, y, rcond=None)[0])
    assert amp == pytest.approx(expected, rel=0.02)
