"""fuel-tank-7ch: the seven-channel full-chassis fuel-tank rig of Table 3.6.

The coupling figures are checked against a linear model built here from the geometry and
stiffnesses documented in models/fuel-tank-7ch/README.md (link attachment points, rubber-bushed
link stiffness, frame torsion and bending) and the actuators' documented servo parameters.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy import signal

import vrig
from identification import band_limited_noise

TABLE_3_6 = [  # (drive channel, response channel) in the order of Table 3.6
    ("LF_vertical", "LF_vertical_acc"),
    ("RF_vertical", "RF_vertical_acc"),
    ("LR_vertical", "LR_vertical_acc"),
    ("RR_vertical", "RR_vertical_acc"),
    ("front_lateral", "front_lateral_acc"),
    ("rear_lateral", "rear_lateral_acc"),
    ("longitudinal", "longitudinal_acc"),
]
INCH = 0.0254

# documented geometry (README.md): x forward, y left, z up [m]
K_VERTICAL_LINK, K_HORIZONTAL_LINK = 4.0e6, 3.0e6  # N/m
K_TORSION, K_BENDING = 4.0e5, 5.25e6  # N m/rad, frame halves about the split point
SPLIT = np.array([0.0, 0.0, 0.5])
Z, X, Y = (0, 0, 1), (1, 0, 0), (0, 1, 0)
LINKS = [  # attachment point, line of action, stiffness, frame half (F front, R rear)
    ((1.1, 0.45, 0.5), Z, K_VERTICAL_LINK, "F"),
    ((1.1, -0.45, 0.5), Z, K_VERTICAL_LINK, "F"),
    ((-1.1, 0.45, 0.5), Z, K_VERTICAL_LINK, "R"),
    ((-1.1, -0.45, 0.5), Z, K_VERTICAL_LINK, "R"),
    ((0.9, -0.45, 0.35), Y, K_HORIZONTAL_LINK, "F"),
    ((-0.9, -0.45, 0.35), Y, K_HORIZONTAL_LINK, "R"),
    ((1.2, 0.0, 0.35), X, K_HORIZONTAL_LINK, "F"),
]
ACCELEROMETERS = [  # position, sensing axis, frame half
    ((1.05, 0.45, 0.6), Z, "F"),
    ((1.05, -0.45, 0.6), Z, "F"),
    ((-1.05, 0.45, 0.6), Z, "R"),
    ((-1.05, -0.45, 0.6), Z, "R"),
    ((0.9, -0.42, 0.35), Y, "F"),
    ((-0.9, -0.42, 0.35), Y, "R"),
    ((1.17, 0.0, 0.35), X, "F"),
]


def _jacobian(point, half):
    """Small displacement of a frame point for q = [t(3), rotation(3) about SPLIT, torsion, bend]."""
    r = np.asarray(point) - SPLIT
    jac = np.zeros((3, 8))
    jac[:, :3] = np.eye(3)
    jac[:, 3:6] = [[0, r[2], -r[1]], [-r[2], 0, r[0]], [r[1], -r[0], 0]]  # theta x r
    if half == "R":
        jac[:, 6] = np.cross(X, r)
        jac[:, 7] = np.cross(Y, r)
    return jac


def _actuator_compliance(h, omega):
    """Quasi-static compliance of a displacement-controlled actuator (PI + delta-P, valve open
    loop) seen by a load force: the piston yields until the PI command balances the delta-P
    term and the flow into the oil column, piston motion and cross-port leakage."""
    jw = 1j * omega
    num = h.max_flow * h.pressure_feedback / (h.area * h.supply_pressure) + h.leakage / h.area
    num = num + h.oil_volume * jw / (4 * h.bulk_modulus * h.area)
    return num / (h.max_flow * (h.kp + h.ki / jw) + h.area * jw)


def _quasi_static_coupling(rig, drive, omega):
    """Accelerations of all 7 channels / that of the driven channel, frame + links + actuators
    as springs (inertia neglected: well below the first mode at 6.6 Hz)."""
    k = np.diag([0, 0, 0, 0, 0, 0, K_TORSION, K_BENDING]).astype(complex)
    gs, keff = [], []
    for (point, axis, k_link, half), d in zip(LINKS, rig.input_defs, strict=True):
        g = np.asarray(axis) @ _jacobian(point, half)
        ke = 1.0 / (1.0 / k_link + _actuator_compliance(d.hydraulic, omega))
        k += ke * np.outer(g, g)
        gs.append(g)
        keff.append(ke)
    q = np.linalg.solve(k, keff[drive] * gs[drive])
    out = np.array([np.asarray(a) @ _jacobian(p, h) @ q for p, a, h in ACCELEROMETERS])
    return out / out[drive]


@pytest.fixture(scope="module")
def rig():
    return vrig.load_rig("fuel-tank-7ch", seed=3)


def _ramped(x, fs, t_ramp=0.5):
    return x * np.minimum(np.arange(len(x)) / (t_ramp * fs), 1.0)[:, None]


def test_channel_table_is_table_3_6(rig):
    assert [c.name for c in rig.inputs] == [d for d, _ in TABLE_3_6]
    assert [c.name for c in rig.outputs] == [r for _, r in TABLE_3_6]
    for k, (drive, resp) in enumerate(zip(rig.inputs, rig.outputs, strict=True), start=1):
        assert drive.kind == "hydraulic"  # displacement control
        assert drive.unit == "m"
        assert drive.full_scale == pytest.approx(3 * INCH)
        assert drive.limits["stroke"] >= drive.full_scale
        assert resp.kind == "accelerometer"
        assert resp.unit == "m/s^2"
        assert drive.description.startswith(f"ch {k}:")
        assert resp.description.startswith(f"ch {k}:")


def test_load_and_run_random_drive(rig):
    fs = rig.fs
    x = _ramped(3e-4 * band_limited_noise(int(2 * fs), 7, cutoff=40 / (fs / 2), seed=1), fs)
    y = rig.run(x)
    assert y.data.shape == (int(2 * fs), 7)
    assert np.all(np.isfinite(y.data))
    assert list(y.names) == [r for _, r in TABLE_3_6]
    assert list(y.units) == ["m/s^2"] * 7
    assert np.all(y.data[int(1.0 * fs) :].std(axis=0) > 0.5)


def test_h1_cross_frfs_show_strong_coupling(rig):
    """H1 (7 x 7) from 20 s of uncorrelated random drives, 0.5 mm rms, 0-40 Hz.

    Median over 10-40 Hz of |H_ij| / |H_jj| (response i, drive j against the driven channel's
    own response): the corner-to-corner pairs through the frame's torsion and the rubber-bushed
    links, and the vertical-to-lateral pair through the frame roll on the bushes (lateral links
    act 0.15 m below the rails), lie within 20 dB; the longitudinal drive hardly reaches the
    corners (the vertical links over the 2.2 m base hold the pitch)."""
    fs = rig.fs
    n = int(20 * fs)
    x = _ramped(5e-4 * band_limited_noise(n, 7, cutoff=40 / (fs / 2), seed=21), fs)
    y = rig.run(x, seed=4).data
    skip = int(3 * fs)  # accelerometer AC-coupling transient at the record start
    xs, ys = x[skip:], y[skip:]
    f, sxx = signal.csd(xs[:, :, None], xs[:, None, :], fs=fs, nperseg=256, axis=0)
    _, sxy = signal.csd(xs[:, :, None], ys[:, None, :], fs=fs, nperseg=256, axis=0)
    h = np.transpose(np.linalg.solve(sxx, sxy), (0, 2, 1))  # H[f, response, drive]
    band = (f >= 10.0) & (f <= 40.0)

    def coupling_db(resp, drive):
        i, j = (
            [r for _, r in TABLE_3_6].index(resp),
            [d for d, _ in TABLE_3_6].index(drive),
        )
        return np.median(20 * np.log10(np.abs(h[band, i, j]) / np.abs(h[band, j, j])))

    strong = [
        ("LR_vertical_acc", "LF_vertical"),
        ("RR_vertical_acc", "RF_vertical"),
        ("front_lateral_acc", "LF_vertical"),
    ]
    for resp, drive in strong:
        assert coupling_db(resp, drive) > -20.0, (resp, drive)
    assert coupling_db("LF_vertical_acc", "longitudinal") < -20.0


def test_low_frequency_coupling_matches_frame_and_link_stiffness(rig):
    """A 2 Hz sine on the LF actuator: the other corners move through the frame's torsion and the
    compliance of the links and the (delta-P stabilised) actuators holding them; the in-plane
    motion is statically determinate (three links) and stays still."""
    fs = rig.fs
    f0, amp = 2.0, 0.01
    t = np.arange(int(10 * fs)) / fs
    x = np.zeros((len(t), 7))
    x[:, 0] = amp * np.sin(2 * np.pi * f0 * t) * np.minimum(t / 1.0, 1.0)
    y = rig.run(x, seed=2).data
    k0 = int(4 * fs)
    basis = np.c_[np.sin(2 * np.pi * f0 * t[k0:]), np.cos(2 * np.pi * f0 * t[k0:])]
    coef, *_ = np.linalg.lstsq(basis, y[k0:], rcond=None)
    phasor = coef[0] + 1j * coef[1]
    measured = np.real(phasor / phasor[0])
    expected = np.real(_quasi_static_coupling(rig, 0, 2 * np.pi * f0))
    # corners: RF and RR about 0.1, LR about 0.12 (frame warps against its torsion spring)
    np.testing.assert_allclose(measured[1:4], expected[1:4], rtol=0.1)
    assert 0.05 < abs(measured[1]) < 0.2
    # the driven corner follows its actuator: |a| ~ omega^2 x (AC coupling and 10 % elastic loss)
    gain = abs(phasor[0]) / (amp * (2 * np.pi * f0) ** 2)
    assert 0.8 < gain < 1.05
    # the front lateral link holds the frame sideways; its accelerometer tilts with the front
    # half's roll phi = (z_LF - z_RF) / 0.9 m and reads g phi (the sensor includes gravity):
    # a_lat / a_LF = g (1 - r_RF) / (0.9 m) / (-omega^2)
    tilt = 9.81 * (1 - measured[1]) / 0.9 / -((2 * np.pi * f0) ** 2)
    assert measured[4] == pytest.approx(tilt, rel=0.15)


def test_drive_beyond_the_servo_valve_trips_an_interlock(rig):
    fs = rig.fs
    x = _ramped(0.01 * band_limited_noise(int(3 * fs), 7, cutoff=40 / (fs / 2), seed=2), fs)
    with pytest.raises(vrig.RigLimitError):
        rig.run(x)


def test_drive_beyond_three_inches_is_refused(rig):
    x = np.zeros((100, 7))
    x[50, 6] = 3.1 * INCH
    with pytest.raises(vrig.RigLimitError):
        rig.run(x)
