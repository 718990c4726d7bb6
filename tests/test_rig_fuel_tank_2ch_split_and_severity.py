"""fuel-tank-2ch (issue 23): the resonance at the split as a calibrated observable, and the
severity axis of the tank's progressive rubber buffers and snubbers.

Truth used here:

* the resonance estimator (:func:`vrig.spectra.frf_resonance`) against linear filters of known
  natural frequency: single modes discretised by zero-order hold (their poles are exactly the
  continuous ones, ``z = exp(s T)``), read within the estimator's line spacing;
* the buffers' force law against MuJoCo's compiled model: the side-car's documented
  coefficients (per buffer ``k d + k2 d² + k3 d³`` on the deflection ``d`` from the free
  length, two buffers per tendon; a snubber ``k_s`` per buffer beyond ±10 mm) times the
  severity, against the passive generalised force MuJoCo computes at imposed tank positions;
* the static sag of the progressive buffers (the root of the force law under the tank's weight)
  and the small-amplitude modes it sets (the tangent stiffness at the sag in the README's bounce
  and pitch formulas): the linearised twin's resonance lies between them;
* linearity by definition: at severity 0 the rig's specimen is linear, so doubling a noise-free
  drive doubles the response within the servo-hydraulics' own small non-linearity, which the
  as-loaded twin exceeds several times over.
"""

from __future__ import annotations

import json

import mujoco
import numpy as np
import pytest
from scipy import signal

import vrig
from vrig.rigs import rig_path
from vrig.signals import random_drive, triangular_psd
from vrig.spectra import frf_resonance

NAME = "fuel-tank-2ch"
SPEC = json.loads(rig_path(NAME).read_text())
PARAMS = {k: p["value"] for k, p in SPEC["parameters"].items()}
A = 0.33  # buffer spacing [m] (README)
CLEARANCE = 0.010  # snubber clearance [m] (README)
TANK_MASS, I_PIVOT = 97.0, 6.29 + 97.0 * 0.121**2  # kg; kg m² about the buffer-plane centre
CG_HEIGHT, G = 0.121, 9.81  # m above the buffer plane; m/s²

# ----------------------------------------------------------------- the resonance estimator

FS, NPERSEG = 250.0, 1024


def _mode(f_n, zeta, x):
    """``x`` through one mode ``w²/(s² + 2 ζ w s + w²)`` (zero-order hold at FS)."""
    w = 2 * np.pi * f_n
    b, a, _ = signal.cont2discrete(([w**2], [1.0, 2 * zeta * w, w**2]), 1 / FS, method="zoh")
    return signal.lfilter(np.ravel(b), a, x)


@pytest.mark.parametrize(("f_n", "zeta"), [(12.0, 0.05), (7.3, 0.02), (30.0, 0.03)])
def test_the_resonance_of_one_mode_is_its_natural_frequency(f_n, zeta):
    x = np.random.default_rng(0).standard_normal(round(120 * FS))
    f = frf_resonance(x, _mode(f_n, zeta, x), fs=FS, nperseg=NPERSEG, band=(1.0, 100.0))
    assert f.shape == (1,)
    assert abs(f[0] - f_n) <= FS / NPERSEG  # within the line spacing


def test_each_channel_reads_its_own_direct_frf():
    """2 x 2: mode 9 Hz on channel 0, 15 Hz on channel 1, each also driven by the other drive
    through a weaker mode at the other frequency (uncorrelated drives): each direct FRF keeps
    its own mode."""
    rng = np.random.default_rng(1)
    x = rng.standard_normal((round(120 * FS), 2))
    y = np.c_[
        _mode(9.0, 0.03, x[:, 0]) + 0.3 * _mode(15.0, 0.03, x[:, 1]),
        _mode(15.0, 0.03, x[:, 1]) + 0.3 * _mode(9.0, 0.03, x[:, 0]),
    ]
    f = frf_resonance(x, y, fs=FS, nperseg=NPERSEG, band=(1.0, 100.0))
    np.testing.assert_allclose(f, [9.0, 15.0], atol=FS / NPERSEG)


def test_two_modes_of_equal_height_give_a_resonance_between_them():
    """Two modes 10 and 13 Hz of equal peak height (gain w²: both peak at 1 / 2ζ): the resonance
    lies between them, where the argmax of the noisy estimate could sit on either."""
    x = np.random.default_rng(2).standard_normal(round(120 * FS))
    y = _mode(10.0, 0.04, x) + _mode(13.0, 0.04, x)
    (f,) = frf_resonance(x, y, fs=FS, nperseg=NPERSEG, band=(1.0, 100.0))
    assert 10.0 + FS / NPERSEG < f < 13.0 - FS / NPERSEG


def test_the_resonance_estimator_refuses_bad_input():
    x = np.random.default_rng(3).standard_normal((2048, 2))
    with pytest.raises(ValueError, match="as many responses as drives"):
        frf_resonance(x, x[:, :1], fs=FS, nperseg=256, band=(1.0, 40.0))
    with pytest.raises(ValueError, match="band"):
        frf_resonance(x, x, fs=FS, nperseg=256, band=(1.0, 200.0))
    with pytest.raises(ValueError, match="band"):
        frf_resonance(x, x, fs=FS, nperseg=256, band=(40.0, 1.0))
    with pytest.raises(ValueError, match="fewer than 3 lines"):
        frf_resonance(x, x, fs=FS, nperseg=256, band=(10.0, 10.5))
    for level in (0.0, 1.0, np.nan):
        with pytest.raises(ValueError, match="level"):
            frf_resonance(x, x, fs=FS, nperseg=256, band=(1.0, 40.0), level=level)
    with pytest.raises(ValueError, match="nperseg"):
        frf_resonance(x, x, fs=FS, nperseg=4096, band=(1.0, 40.0))


# ------------------------------------------------------------- the buffers' force law


def _pair_tension(d, s, values):
    """The force [N] of one buffer tendon (two buffers and their two snubbers) at deflection
    ``d`` [m] from the free length, severity ``s``: the documented law, written out."""
    k, k2, k3 = (values[n] for n in ("buffer_stiffness", "buffer_quadratic_stiffness",
                                      "buffer_cubic_stiffness"))  # fmt: skip
    buffer = k * d + s * (k2 * d**2 + k3 * d**3)
    beyond = np.sign(d) * max(abs(d) - CLEARANCE, 0.0)
    return -2.0 * (buffer + s * values["snubber_stiffness"] * beyond)


@pytest.mark.parametrize("severity", [0.0, 1.0, 2.0])
def test_the_compiled_buffers_follow_the_documented_law_times_the_severity(severity):
    """Tank bounce z and pitch θ imposed (everything else at rest): the generalised passive
    forces are the two tendons' forces through their coefficients (fore d = z - a θ, aft
    d = z + a θ), with the progressive terms and the snubbers scaled by the severity."""
    rig = vrig.load_rig(NAME, variant="mild", severity=severity)
    assert rig.severity == severity
    m = rig.model
    d = mujoco.MjData(m)
    bounce, pitch = m.joint("tank_bounce"), m.joint("tank_pitch")
    for z, theta in [(-0.014, 0.0), (-0.0105, 0.0), (-0.006, 0.01), (0.0, 0.0), (0.003, -0.02),
                     (0.012, 0.0), (0.0, 0.04)]:  # fmt: skip
        d.qpos[:] = 0.0
        d.qvel[:] = 0.0
        d.qpos[bounce.qposadr[0]], d.qpos[pitch.qposadr[0]] = z, theta
        mujoco.mj_forward(m, d)
        fore, aft = (_pair_tension(z + c * theta, severity, PARAMS) for c in (-A, A))
        np.testing.assert_allclose(
            [d.qfrc_passive[bounce.dofadr[0]], d.qfrc_passive[pitch.dofadr[0]]],
            [fore + aft, -A * fore + A * aft],
            rtol=1e-9,
            atol=1e-6,
        )


def test_severity_scales_the_progressive_terms_and_the_snubbers_only():
    one = vrig.load_rig(NAME, variant="mild", severity=1.0).parameters
    for s in (0.0, 0.5, 2.0):
        scaled = vrig.load_rig(NAME, variant="mild", severity=s).parameters
        for name, value in one.items():
            law = SPEC["severity"]["scales"].get(name)
            assert scaled[name] == pytest.approx(value * s if law else value), name
    assert set(SPEC["severity"]["scales"]) == {
        "buffer_quadratic_stiffness", "buffer_cubic_stiffness", "snubber_stiffness"
    }  # fmt: skip


def _sag(values):
    """The static deflection of each buffer [m], the root of k d + k2 d² + k3 d³ = -m g / 4
    nearest zero, and the tangent stiffness there [N/m]."""
    k, k2, k3 = (values[n] for n in ("buffer_stiffness", "buffer_quadratic_stiffness",
                                      "buffer_cubic_stiffness"))  # fmt: skip
    roots = np.roots([k3, k2, k, TANK_MASS * G / 4])
    real = roots[np.abs(roots.imag) < 1e-12].real
    d = float(real[np.argmin(np.abs(real))])
    return d, k + 2 * k2 * d + 3 * k3 * d**2


def _linear_modes_hz(k_tangent):
    """Bounce and pitch [Hz] on buffers of tangent stiffness ``k_tangent`` (README formulas)."""
    f_bounce = np.sqrt(4 * k_tangent / TANK_MASS) / (2 * np.pi)
    k_pitch = 4 * k_tangent * A**2 - TANK_MASS * G * CG_HEIGHT
    return f_bounce, np.sqrt(k_pitch / I_PIVOT) / (2 * np.pi)


def test_the_progressive_buffers_sag_less_and_stiffen_at_the_sag():
    """The tank settles where the law carries its weight: less sag than the linear buffer's
    m g / 4 k and a tangent stiffness above k (the neo-Hookean rubber is stiffer in
    compression); in the compiled model the buffers' force balances the tank's weight there."""
    sag, k_t = _sag(PARAMS)
    linear = -TANK_MASS * G / (4 * PARAMS["buffer_stiffness"])
    assert linear < sag < 0 and k_t > PARAMS["buffer_stiffness"]
    m = vrig.load_rig(NAME, variant="mild").model
    d = mujoco.MjData(m)
    bounce = m.joint("tank_bounce")
    d.qpos[bounce.qposadr[0]] = sag
    mujoco.mj_forward(m, d)
    dof = bounce.dofadr[0]
    assert d.qfrc_bias[dof] == pytest.approx(TANK_MASS * G, rel=1e-9)  # the tank's weight
    assert d.qfrc_passive[dof] == pytest.approx(d.qfrc_bias[dof], rel=1e-9)


# ------------------------------------------------------------------ the twin's physics


def _homogeneity_error(severity):
    """||y(2x) - 2 y(x)|| / ||2 y(x)|| of the noise-free rig (mild: snubbers present) to a
    1-40 Hz random drive of 0.6 mm rms per actuator (the tank reaches its snubbers at s = 1)."""
    rig = vrig.load_rig(NAME, variant="mild", severity=severity, valve_noise=0.0, acc_noise=0.0)
    n = round(6.0 * rig.fs)
    x = random_drive(triangular_psd((1.0, 40.0)), n, rig.fs, channels=2, rms=6e-4, seed=4,
                     names=[c.name for c in rig.inputs], unit="m")  # fmt: skip
    fade = np.minimum(1.0, np.arange(n) / (0.5 * rig.fs))[:, None]
    x = x.with_data(x.data * fade)
    one = rig.run(x, seed=1).data
    two = rig.run(x.with_data(2 * x.data), seed=1).data
    keep = slice(round(1.0 * rig.fs), None)
    return np.linalg.norm(two[keep] - 2 * one[keep]) / np.linalg.norm(2 * one[keep])


def test_severity_zero_is_linear_and_the_loaded_twin_is_not():
    """Superposition (homogeneity) on the twin: within the servo-hydraulics' own 2 % at s = 0
    (linear buffers, no snubbers), broken several times over at s = 1 (progressive buffers and
    snubbers) and more at s = 2."""
    e0, e1, e2 = (_homogeneity_error(s) for s in (0.0, 1.0, 2.0))
    assert e0 < 0.02, e0
    assert e1 > 5 * e0 and e2 > e1, (e0, e1, e2)


def test_the_linearised_twins_resonance_lies_between_its_bounce_and_pitch():
    """benchmarks.calibrate's observable on the linearised twin (s = 0: linear buffers k, no
    snubbers): each channel's resonance between the analytic bounce and pitch modes."""
    from benchmarks.calibrate import resonance_channels

    f_bounce, f_pitch = _linear_modes_hz(PARAMS["buffer_stiffness"])
    res = resonance_channels(vrig.load_rig(NAME, seed=0, variant="mild", severity=0.0), NAME)
    assert set(res) == {"fore_acc", "aft_acc"}
    for channel, f in res.items():
        assert f_bounce < f < f_pitch, (channel, f, f_bounce, f_pitch)


def test_the_thesis_twin_has_its_resonance_at_the_split():
    """The committed calibration (benchmarks.calibrate --check): Fig. 3.9's resonance at the
    text's 12 Hz split within ±1 Hz on both channels, with every calibrated value inside its
    documented range."""
    from benchmarks.calibrate import CALIBRATIONS, resonance_channels

    res_cal = CALIBRATIONS[NAME]["resonance"]
    rig = vrig.load_rig(NAME, seed=0)
    assert rig.variant == "thesis"
    for name, value in rig.description.variants["thesis"].values.items():
        assert rig.description.parameters[name].check(value) == value
    for channel, f in resonance_channels(rig, NAME).items():
        assert abs(f - res_cal["target_hz"]) <= res_cal["tolerance_hz"], (channel, f)
