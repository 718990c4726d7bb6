"""Radiator rig: linear modes against the documented eigen-analysis, play (rattle above 1 g),
interlocks. Documented values: models/radiator/README.md; each physics test runs on the
datasheet-typical ``mild`` set and on the calibrated ``thesis`` variant (the rig's default, issue
12: twice the mount plays). The plays do not enter the linear modes (gravity closes them at rest)
nor the 1 g lift-off threshold; the modes follow from the variant's documented stiffnesses."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import signal

import vrig
from identification import band_limited_noise

FS = 1250  # DAQ rate [Hz]
# --- documented parameters (models/radiator/README.md) -----------------------------------------
M_RAD, I_PITCH = 15.0, 0.80  # radiator with coolant [kg], pitch inertia about its CoM [kg m^2]
C_LOW, H_PINS, E_X = 0.33, 0.70, 0.06  # CoM above bottom pin, pin spacing, pin line behind CoM [m]
X_ACC = -0.06  # top-tank accelerometer fore-aft position relative to the CoM [m]
M_PISTON, C_PISTON = 0.5, 200.0  # piston armature [kg], piston viscous damping [N s/m]
# closed-loop modes stated in the README [Hz]: bounce, pitch, frame on the oil column
README_MODES = {"bounce": 70.0, "pitch": 151.2, "oil_column": 171.0}
WIDE_BAND = (0.0, 200.0)  # the band of the wide-band (identification) test [Hz]
NO_PLAY = {"radial_play": 0.0, "vertical_play": 0.0}
VARIANTS = ["mild", "thesis"]


def _linear_model(p, h):
    """Closed-loop linearisation about rest from the documented parameters.

    States: frame z, radiator x, z, pitch (relative to the frame), their velocities, load
    pressure, spool position and velocity, integral of the error. Mounts: two rows, linear
    (play closed by gravity); actuator: PI + delta-P, second-order valve, orifice flow gain at the
    static load pressure, oil-column compliance with leakage."""
    mf = p["frame_mass"] + M_PISTON
    mass = np.array(
        [[mf + M_RAD, 0, M_RAD, 0], [0, M_RAD, 0, 0], [M_RAD, 0, M_RAD, 0], [0, 0, 0, I_PITCH]]
    )
    k = np.zeros((4, 4))
    c = np.zeros((4, 4))
    c[0, 0] = C_PISTON
    kr, ka = 2 * p["mount_radial_stiffness"], 2 * p["mount_axial_stiffness"]
    cr, ca = 2 * p["mount_radial_damping"], 2 * p["mount_axial_damping"]
    for kk, cc, j in [
        (kr, cr, [0, 1, 0, -C_LOW]),  # bottom pins, fore-aft
        (ka, ca, [0, 0, 1, E_X]),  # bottom pins, vertical
        (kr, cr, [0, 1, 0, H_PINS - C_LOW]),  # top pins, fore-aft
    ]:
        j = np.array(j, float)
        k += kk * np.outer(j, j)
        c += cc * np.outer(j, j)
    kh = 4 * h.bulk_modulus / h.oil_volume
    p_static = (mf + M_RAD) * 9.81 / h.area
    kq = h.max_flow * np.sqrt((h.supply_pressure - p_static) / h.supply_pressure)
    wv = 2 * np.pi * h.valve_frequency
    a = np.zeros((12, 12))
    mi = np.linalg.inv(mass)
    a[0:4, 4:8] = np.eye(4)
    a[4:8, 0:4] = -mi @ k
    a[4:8, 4:8] = -mi @ c
    a[4:8, 8] = mi @ np.array([h.area, 0, 0, 0])
    a[8, 9], a[8, 4], a[8, 8] = kh * kq, -kh * h.area, -kh * h.leakage
    a[9, 10] = 1.0
    a[10, 0] = -(wv**2) * h.kp
    a[10, 4] = -(wv**2) * h.kd
    a[10, 8] = -(wv**2) * h.pressure_feedback / h.supply_pressure
    a[10, 9], a[10, 10], a[10, 11] = -(wv**2), -2 * h.valve_damping * wv, wv**2 * h.ki
    a[11, 0] = -1.0
    b = np.zeros(12)
    b[10], b[11] = wv**2 * h.kp, 1.0
    return a, b


def _modes(a):
    """Closed-loop oscillatory modes: (frequency [Hz], damping ratio, mode shape of q)."""
    w, v = np.linalg.eig(a)
    keep = w.imag > 1.0
    order = np.argsort(np.abs(w[keep]))
    return (
        np.abs(w[keep][order]) / (2 * np.pi),
        -w[keep][order].real / np.abs(w[keep][order]),
        v[:4, keep][:, order],
    )


def _peaks(f, mag, lo, hi, rel_prominence=0.05):
    """Local maxima in [lo, hi] Hz standing out by ``rel_prominence`` of their height."""
    sel = (f >= lo) & (f <= hi)
    idx, props = signal.find_peaks(mag[sel], prominence=0.0)
    keep = props["prominences"] > rel_prominence * mag[sel][idx]
    return f[sel][idx[keep]]


def test_loads_and_runs_two_seconds_of_random_drive():
    rig = vrig.load_rig("radiator", seed=0)
    assert [c.name for c in rig.inputs] == ["actuator_disp"]
    assert [c.name for c in rig.outputs] == ["base_acc", "toptank_acc"]
    assert [c.unit for c in rig.outputs] == ["m/s^2", "m/s^2"]
    assert rig.fs == FS and rig.bandwidth == (2.0, 30.0)
    drive = 0.0003 * band_limited_noise(2 * FS, 1, cutoff=30 / (FS / 2), seed=1)
    out = rig.run(drive, seed=0)
    assert out.data.shape == (2 * FS, 2)
    assert out.names == ("base_acc", "toptank_acc") and out.units == ("m/s^2", "m/s^2")
    assert np.all(np.isfinite(out.data))
    # the accelerometers see the drive; AC coupled, they carry no gravity offset once the
    # 1 Hz high-pass has settled (the DAQ starts its filter at rest: skip the first second)
    assert np.all(out.data.std(axis=0) > 0.5)
    assert np.all(np.abs(out.data[FS:].mean(axis=0)) < 0.5)


@pytest.mark.parametrize("variant", VARIANTS)
def test_documented_modes_follow_from_the_documented_parameters(variant):
    rig = vrig.load_rig("radiator", variant=variant)
    assert rig.variant == variant
    a, _ = _linear_model(rig.parameters, rig.input_defs[0].hydraulic)
    f, zeta, shapes = _modes(a)
    assert np.all(zeta > 0.02)  # the closed loop is stable and every mode damped
    for name, f_doc in README_MODES.items():
        assert np.min(np.abs(f - f_doc)) < 0.005 * f_doc, (name, f)
        assert WIDE_BAND[0] < f_doc < WIDE_BAND[1]
    # mode shapes: bounce = radiator vertical, pitch = rotation (0.35 m lever), oil column =
    # the frame moving
    lever = np.array([1, 1, 1, 0.35])
    shape = {
        n: np.abs(shapes[:, np.argmin(np.abs(f - fd))]) * lever for n, fd in README_MODES.items()
    }
    assert np.argmax(shape["bounce"]) == 2
    assert np.argmax(shape["pitch"]) == 3
    assert shape["oil_column"][0] > 0.5 * shape["oil_column"].max()


@pytest.fixture(scope="module")
def wide_band_frfs():
    """H1 FRFs from a 0-225 Hz random drive (50 um rms), mount play taken up (linear mounts)."""
    # the modes are measured here: without the controller's 1/f noise (62 um rms on `thesis`,
    # issue 23), which a 50 um rms drive would not stand out of below 40 Hz
    rig = vrig.load_rig("radiator", seed=0, control_noise=0.0, **NO_PLAY)
    fs = rig.fs
    u = 5e-5 * band_limited_noise(int(20 * fs), 1, cutoff=225 / (fs / 2), seed=1)[:, 0]
    y = rig.run(u, seed=2).data
    kw = dict(fs=fs, nperseg=1250)
    f, puu = signal.welch(u, **kw)
    _, pub = signal.csd(u, y[:, 0], **kw)
    _, put = signal.csd(u, y[:, 1], **kw)
    _, pbt = signal.csd(y[:, 0], y[:, 1], **kw)
    _, pbb = signal.welch(y[:, 0], **kw)
    _, coh = signal.coherence(u, y[:, 1], **kw)
    return f, pub / puu, put / puu, pbt / pbb, coh


def test_wide_band_frf_peaks_sit_at_the_documented_modes(wide_band_frfs):
    f, h_base, h_top, _transmissibility, coh = wide_band_frfs
    band = (f > 40) & (f < 200)
    assert np.median(coh[band]) > 0.9
    w2 = (2 * np.pi * np.maximum(f, 1.0)) ** 2
    # bounce: the dominant peak of the top-tank displacement FRF (acceleration / omega^2)
    bounce = _peaks(f, np.abs(h_top) / w2, 40, 120)
    # oil column: the frame resonance, a peak of the base acceleration per drive displacement
    oil = _peaks(f, np.abs(h_base), 120, 200)
    # pitch (151 Hz) is no peak of the vertical channels: the doughnuts' radial contact damping
    # (loss factor 0.25, issue 23) damps it by 19 %; its frequency is checked by the eigen-analysis
    # and its contribution by the FRF against the linear model (the tests next to this one)
    for name, found in [("bounce", bounce), ("oil_column", oil)]:
        f_doc = README_MODES[name]
        assert found.size, name
        err = np.min(np.abs(found - f_doc)) / f_doc
        assert err < 0.05, (name, found, f_doc)
    # no other resonance in the top-tank FRF below the wide-band limit than bounce and
    # pitch/oil column
    top = _peaks(f, np.abs(h_top) / w2, 40, 200)
    for fp in top:
        assert min(abs(fp - fd) / fd for fd in README_MODES.values()) < 0.08, top


def test_measured_frf_matches_the_linear_model(wide_band_frfs):
    f, h_base, h_top, *_ = wide_band_frfs
    rig = vrig.load_rig("radiator", **NO_PLAY)
    a, b = _linear_model(rig.parameters, rig.input_defs[0].hydraulic)
    aa = rig.description.anti_alias.response(f, rig.fs, rig.fs * rig.decimation)
    band = (f > 5) & (f < 190)
    s = 2j * np.pi * f[band]
    x = np.array([np.linalg.solve(si * np.eye(12) - a, b) for si in s])
    base = s**2 * x[:, 0] * aa[band]
    top = s**2 * (x[:, 0] + x[:, 2] - X_ACC * x[:, 3]) * aa[band]
    for measured, model in [(h_base[band], base), (h_top[band], top)]:
        ratio = np.abs(measured) / np.abs(model)
        assert np.median(np.abs(20 * np.log10(ratio))) < 1.0
        assert np.percentile(np.abs(20 * np.log10(ratio)), 90) < 2.5


def _rattle_ratio(g_level, variant):
    """High-frequency (> 100 Hz) top-tank energy with the play of ``variant`` / without, for a
    20 Hz sine whose base acceleration is ``g_level`` g."""
    fs = FS
    t = np.arange(3 * fs) / fs
    w = 2 * np.pi * 20.0
    drive = g_level * 9.81 / w**2 * np.sin(w * t)
    hf = []
    for kw in ({}, NO_PLAY):  # the threshold's physics: without the controller's 1/f noise,
        # whose own acceleration would lift the pins off now and then near 1 g (issue 23)
        y = (
            vrig.load_rig("radiator", variant=variant, control_noise=0.0, **kw)
            .run(drive, seed=1)
            .channel("toptank_acc")[fs:]
        )
        f, p = signal.welch(y, fs=fs, nperseg=625)
        hf.append(p[f > 100].sum())
    return hf[0] / hf[1]


@pytest.mark.parametrize("variant", VARIANTS)
def test_play_opens_when_the_radiator_acceleration_exceeds_one_g(variant):
    # gravity closes the vertical play and, through the CoM offset, preloads the fore-aft play in
    # proportion to (g + a): below 1 g the mounts stay engaged (no rattle), whatever the play ...
    assert _rattle_ratio(0.8, variant) < 1.5
    # ... above 1 g the pins lift off and hit their stops: broadband impact content
    assert _rattle_ratio(1.25, variant) > 20.0


@pytest.mark.parametrize("variant", VARIANTS)
def test_drive_beyond_the_valve_capability_trips_an_interlock(variant):
    rig = vrig.load_rig("radiator", variant=variant)
    t = np.arange(FS) / rig.fs
    # 60 Hz, 5 mm: 1.9 m/s demanded against the valve's 0.53 m/s
    with pytest.raises(vrig.RigLimitError):
        rig.run(0.005 * np.sin(2 * np.pi * 60 * t), seed=0)
    with pytest.raises(vrig.RigLimitError, match="drive"):
        rig.run(np.full(100, 0.05))
