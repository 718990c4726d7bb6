"""Motorcycle rear-wheel simulator: strain holds the low band, acceleration the high band; the
tyre lifts off; the measured FRFs follow the documented linear model. Documented values:
models/motorcycle-rear/README.md."""

from __future__ import annotations

import json

import numpy as np
import pytest
from scipy import signal

import vrig

FS = 500
# --- documented parameters (models/motorcycle-rear/README.md) ----------------------------------
M_PLATEN = 15.0 + 0.5  # platen + rod, piston armature [kg]
M_SPRUNG, M_ARM, M_WHEEL = 100.0, 6.0, 16.0  # [kg]
L_ARM, L_ARM_CG, I_ARM = 0.55, 0.275, 0.16  # swing arm length, CoM, inertia about CoM
LEVER = 2.0  # wheel travel / shock travel
K_SPRING = 104_000.0  # coil spring rate at the shaft [N/m]
R_FREE = 0.31  # tyre free radius [m]
C_PISTON, C_GUIDE = 200.0, 50.0  # piston and vertical-guide viscous damping [N s/m]
# coil spring: wire d, mean coil diameter D, active coils n; gauge at 45 deg on the wire
WIRE_D, COIL_D, COILS = 0.0115, 0.062, 7
README_BOUNCE_HOP = (2.55, 14.65)  # closed-loop modes with the mean damping [Hz]


def _strain_gain():
    """Microstrain per metre of spring compression: eps = tau / (2 G), tau = 8 F D K_w / (pi d^3),
    F = k delta, k = G d^4 / (8 D^3 n)  ->  eps / delta = d K_w / (2 pi D^2 n)."""
    c = COIL_D / WIRE_D
    wahl = (4 * c - 1) / (4 * c - 4) + 0.615 / c
    return WIRE_D * wahl / (2 * np.pi * COIL_D**2 * COILS) * 1e6


def _triangular_drive(n, rms, seed):
    """Random drive whose PSD falls linearly from 0 Hz to zero at 30 Hz (white noise shaped in
    the frequency domain by sqrt(PSD)), faded in over 0.5 s."""
    rng = np.random.default_rng(seed)
    f = np.fft.rfftfreq(n, 1 / FS)
    shape = np.sqrt(np.clip(1 - f / 30.0, 0.0, None))
    spec = shape * (rng.standard_normal(f.size) + 1j * rng.standard_normal(f.size))
    spec[0] = 0.0
    x = np.fft.irfft(spec, n)
    x *= rms / x.std()
    fade = np.minimum(1.0, np.arange(n) / (0.5 * FS))
    return x * 0.5 * (1 - np.cos(np.pi * fade))


def _linear_model(p, h):
    """Closed-loop linearisation about the static ride height with the mean shock damping.

    Coordinates: platen z, sprung-mass z, swing-arm angle; tyre engaged (linear); states add the
    velocities, load pressure, spool position/velocity and the PI integrator."""
    r = L_ARM / LEVER
    c_shock = 0.5 * (p["compression_damping"] + p["rebound_damping"])
    m12 = M_WHEEL * L_ARM + M_ARM * L_ARM_CG
    m22 = M_WHEEL * L_ARM**2 + M_ARM * L_ARM_CG**2 + I_ARM
    mass = np.array([[M_PLATEN, 0, 0], [0, M_SPRUNG + M_ARM + M_WHEEL, m12], [0, m12, m22]])
    tyre = np.array([1.0, -1.0, -L_ARM])
    shock = np.array([0.0, 0.0, r])
    k = p["tyre_stiffness"] * np.outer(tyre, tyre) + K_SPRING * np.outer(shock, shock)
    c = np.diag([C_PISTON, C_GUIDE, 0.0]) + c_shock * np.outer(shock, shock)
    kh = 4 * h.bulk_modulus / h.oil_volume
    p_static = (M_PLATEN + M_SPRUNG + M_ARM + M_WHEEL) * 9.81 / h.area
    kq = h.max_flow * np.sqrt((h.supply_pressure - p_static) / h.supply_pressure)
    wv = 2 * np.pi * h.valve_frequency
    a = np.zeros((10, 10))
    mi = np.linalg.inv(mass)
    a[0:3, 3:6] = np.eye(3)
    a[3:6, 0:3] = -mi @ k
    a[3:6, 3:6] = -mi @ c
    a[3:6, 6] = mi @ np.array([h.area, 0, 0])
    a[6, 7], a[6, 3], a[6, 6] = kh * kq, -kh * h.area, -kh * h.leakage
    a[7, 8] = 1.0
    a[8, 0] = -(wv**2) * h.kp
    a[8, 3] = -(wv**2) * h.kd
    a[8, 6] = -(wv**2) * h.pressure_feedback / h.supply_pressure
    a[8, 7], a[8, 8], a[8, 9] = -(wv**2), -2 * h.valve_damping * wv, wv**2 * h.ki
    a[9, 0] = -1.0
    b = np.zeros(10)
    b[8], b[9] = wv**2 * h.kp, 1.0
    return a, b


def test_loads_and_runs_two_seconds_of_random_drive():
    rig = vrig.load_rig("motorcycle-rear", seed=0)
    assert [c.name for c in rig.inputs] == ["actuator_disp"]
    assert [c.name for c in rig.outputs] == ["spindle_acc", "spring_strain"]
    assert [c.unit for c in rig.outputs] == ["m/s^2", "microstrain"]
    assert rig.fs == FS and rig.bandwidth == (0.0, 30.0)
    out = rig.run(_triangular_drive(2 * FS, 0.002, seed=1), seed=0)
    assert out.data.shape == (2 * FS, 2)
    assert out.names == ("spindle_acc", "spring_strain")
    assert np.all(np.isfinite(out.data))
    assert np.all(out.data.std(axis=0) > 0)


def test_strain_gauge_gain_follows_from_the_spring_geometry():
    rig = vrig.load_rig("motorcycle-rear")
    gain = rig.output_defs[1].transducer.gain
    assert gain == pytest.approx(_strain_gain(), rel=1e-3)
    # and the documented spring rate is that of the same coil: k = G d^4 / (8 D^3 n)
    assert 79.3e9 * WIRE_D**4 / (8 * COIL_D**3 * COILS) == pytest.approx(K_SPRING, rel=0.01)


def test_strain_holds_the_low_band_and_acceleration_the_high_band():
    rig = vrig.load_rig("motorcycle-rear", seed=0)
    y = rig.run(_triangular_drive(20 * FS, 0.004, seed=0), seed=1).data[FS:]
    f, p = signal.welch(y, fs=FS, nperseg=1024, axis=0)
    band = f <= 30.0
    low = band & (f < 8.0)
    strain_low = p[low, 1].sum() / p[band, 1].sum()
    acc_high = p[band & ~low, 0].sum() / p[band, 0].sum()
    assert strain_low > 0.5, strain_low  # reference text: strain holds energy DC-8 Hz
    assert acc_high > 0.5, acc_high  # ... acceleration 8-30 Hz
    assert acc_high > 0.9


@pytest.fixture(scope="module")
def tyre_probe(tmp_path_factory):
    """The shipped rig plus a raw tyre-length channel (axle to platen distance), as a user rig."""
    desc = json.loads(vrig.rig_path("motorcycle-rear").read_text())
    desc["mjcf"] = str(vrig.rig_path("motorcycle-rear").with_name("motorcycle-rear.xml"))
    desc["outputs"].append(
        {"name": "tyre_length", "unit": "m", "full_scale": 10.0, "sensor": "tyre_length"}
    )
    path = tmp_path_factory.mktemp("probe") / "motorcycle-probe.rig.json"
    path.write_text(json.dumps(desc))
    return path


def _drop(duration):
    """Platen raised 40 mm (1.5 s), held, then lowered to -30 mm in ``duration`` s (cosine)."""
    t = np.arange(4 * FS) / FS
    up = np.clip(t / 1.5, 0, 1)
    x = 0.04 * 0.5 * (1 - np.cos(np.pi * up))
    down = np.clip((t - 2.0) / duration, 0, 1)
    return t, x - 0.07 * 0.5 * (1 - np.cos(np.pi * down))


def test_tyre_lifts_off_the_platen_on_a_fast_drop_without_warnings(tyre_probe):
    rig = vrig.load_rig(tyre_probe, seed=0)
    k_tyre = rig.parameters["tyre_stiffness"]

    def tyre_force(duration):
        t, drive = _drop(duration)
        y = rig.run(drive, seed=0)  # raises on any MuJoCo warning or interlock
        force = k_tyre * np.clip(R_FREE - y.channel("tyre_length"), 0.0, None)
        return t, force

    # a 70 mm drop in 90 ms (1.2 m/s peak): the shock tops out and the wheel cannot follow
    t, force = tyre_force(0.09)
    after = t > 1.9
    static = (M_SPRUNG + M_ARM + M_WHEEL) * 9.81
    assert np.median(force[(t > 1.6) & (t < 1.9)]) == pytest.approx(static, rel=0.03)
    airborne = after & (force == 0.0)
    assert airborne.sum() / FS > 0.03  # off the platen for tens of milliseconds
    assert np.all(force[t > 3.0] > 0.5 * static)  # and lands again
    # the same drop done slowly: the wheel stays on the platen
    t, force = tyre_force(1.0)
    assert force[t > 1.9].min() > 0.3 * static


def test_measured_frf_matches_the_linear_model_with_symmetric_damping():
    # the mean of the documented compression and rebound damping makes the shock linear
    rig = vrig.load_rig("motorcycle-rear", compression_damping=7200.0, rebound_damping=7200.0)
    a, b = _linear_model(rig.parameters, rig.input_defs[0].hydraulic)
    w = np.linalg.eigvals(a)
    osc = w[w.imag > 0.1]
    f_modes = np.sort(np.abs(osc)) / (2 * np.pi)
    assert np.all(w.real < 0)
    for f_doc in README_BOUNCE_HOP:
        assert np.min(np.abs(f_modes - f_doc)) < 0.01 * f_doc, f_modes
    u = _triangular_drive(40 * FS, 0.002, seed=3)
    y = rig.run(u, seed=4).data
    kw = dict(fs=FS, nperseg=2048)
    f, puu = signal.welch(u, **kw)
    _, pua = signal.csd(u, y[:, 0], **kw)
    _, pus = signal.csd(u, y[:, 1], **kw)
    band = (f > 1.0) & (f < 28.0)
    s = 2j * np.pi * f[band]
    x = np.array([np.linalg.solve(si * np.eye(10) - a, b) for si in s])
    aa = rig.description.anti_alias.response(f[band], FS, FS * rig.decimation)
    hp = 1.0 / (1.0 + 2 * np.pi * 1.0 / s)  # the accelerometer's 1 Hz AC coupling
    acc = s**2 * (x[:, 1] + L_ARM * x[:, 2]) * aa * hp
    strain = _strain_gain() * (L_ARM / LEVER) * x[:, 2] * aa
    for measured, model in [(pua[band] / puu[band], acc), (pus[band] / puu[band], strain)]:
        err_db = np.abs(20 * np.log10(np.abs(measured) / np.abs(model)))
        assert np.median(err_db) < 0.5 and np.max(err_db) < 2.0, err_db.max()


def test_rebound_heavy_damping_packs_the_suspension_down():
    # rebound damping 2.6x compression: under vibration the shock extends more slowly than it
    # compresses, so its mean position sinks (mean spring compression > 0); symmetric: ~0
    drive = _triangular_drive(10 * FS, 0.004, seed=2)
    mean = {}
    for name, kw in [
        ("asym", {}),
        ("sym", dict(compression_damping=7200.0, rebound_damping=7200.0)),
    ]:
        y = vrig.load_rig("motorcycle-rear", seed=0, **kw).run(drive, seed=0)
        mean[name] = y.channel("spring_strain")[2 * FS :].mean()
    assert mean["asym"] > 100.0  # microstrain: > 1 mm mean shock compression
    assert abs(mean["sym"]) < 0.3 * mean["asym"]


def test_drive_beyond_the_valve_capability_trips_an_interlock():
    rig = vrig.load_rig("motorcycle-rear")
    t = np.arange(FS) / FS
    with pytest.raises(vrig.RigLimitError):  # 30 Hz, 20 mm: 3.8 m/s against 1.5 m/s
        rig.run(0.02 * np.sin(2 * np.pi * 30 * t) * np.minimum(1, t / 0.2), seed=0)
    with pytest.raises(vrig.RigLimitError, match="drive"):
        rig.run(np.full(10, 0.08))
