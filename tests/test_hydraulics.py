"""Servo-hydraulic actuator: tracking FRF against the linearised loop, flow saturation, interlocks."""

from __future__ import annotations

from pathlib import Path

import control
import numpy as np
import pytest
from scipy import signal

import vrig
from identification import band_limited_noise

TEST_RIG = Path(__file__).parent / "data" / "servo_mass.xml"
M_TABLE, C_PISTON = 20.0 + 0.5, 200.0  # table mass + piston armature [kg], piston damping [N s/m]
K2, C2, M2 = 4e5, 300.0, 5.0  # the sprung mass above the table


def _linear_loop(h):
    """Closed displacement loop linearised about rest, from the documented parameters.

    Valve: second order; flow Q = Q_max x_v; oil column s p = (4 beta / V) (Q - A s x);
    load: table + sprung mass impedance; controller PI with delta-P feedback.
    """
    s = control.tf("s")
    kh = 4 * h.bulk_modulus / h.oil_volume
    z = M_TABLE * s**2 + C_PISTON * s + (C2 * s + K2) * M2 * s**2 / (M2 * s**2 + C2 * s + K2)
    den = s * (z + h.area**2 * kh)
    wv = 2 * np.pi * h.valve_frequency
    valve = wv**2 / (s**2 + 2 * h.valve_damping * wv * s + wv**2)
    inner = control.feedback(
        h.max_flow * valve, h.pressure_feedback * kh * z / den / h.supply_pressure
    )
    return control.feedback((h.kp + h.ki / s) * inner * h.area * kh / den, 1)


@pytest.fixture(scope="module")
def tracking():
    rig = vrig.load_rig(TEST_RIG)
    drive = 0.0002 * band_limited_noise(30000, 1, cutoff=250 / 500, seed=3)
    lvdt = rig.run(drive, seed=0).channel("table_lvdt")
    f, pxy = signal.csd(drive[:, 0], lvdt, fs=rig.fs, nperseg=2048)
    _, pxx = signal.welch(drive[:, 0], fs=rig.fs, nperseg=2048)
    model = _linear_loop(rig.input_defs[0].hydraulic)
    aa = rig.description.anti_alias.response(f, rig.fs, rig.fs * rig.decimation)
    return f, pxy / pxx, model(2j * np.pi * np.maximum(f, 1e-3)) * aa


def test_tracking_frf_matches_the_linearised_servo_loop(tracking):
    f, measured, model = tracking
    band = (f >= 1) & (f <= 30)
    gain_db = 20 * np.log10(np.abs(measured[band]) / np.abs(model[band]))
    phase = np.degrees(np.angle(measured[band] / model[band]))
    assert np.max(np.abs(gain_db)) < 1.0
    assert np.max(np.abs(phase)) < 5.0


def test_tracking_bandwidth_rolls_off_as_documented(tracking):
    f, measured, model = tracking
    loop = np.abs(model)  # includes the anti-alias filter, as the measurement does
    f3 = f[np.argmax((f > 5) & (loop < 10 ** (-3 / 20)))]
    # vrig/rigs/hydraulics.py documents ~150 Hz for the default actuator with ~25 kg moving mass
    assert 120 < f3 < 190
    i = np.argmin(np.abs(f - f3))
    assert 20 * np.log10(abs(measured[i])) == pytest.approx(-3.0, abs=1.5)
    assert 20 * np.log10(abs(measured[np.argmin(np.abs(f - 2))])) == pytest.approx(0.0, abs=0.5)


def test_flow_saturation_limits_velocity_and_trips_the_following_error_interlock():
    rig = vrig.load_rig(TEST_RIG)
    h = rig.input_defs[0].hydraulic
    fs = rig.fs
    # a 20 Hz sine of 6 mm demands 0.75 m/s peak, above the valve's 0.525 m/s no-load limit:
    # the actuator can follow only ~0.525 / (2 pi 20) = 4.2 mm, a following error of ~2 mm
    t = np.arange(int(0.5 * fs)) / fs
    demand = 0.006 * np.sin(2 * np.pi * 20 * t)
    assert 0.006 * 2 * np.pi * 20 > h.velocity_limit
    tight = vrig.load_rig(TEST_RIG, error_limit=0.001)
    with pytest.raises(vrig.RigLimitError, match="following error") as err:
        tight.run(demand, seed=0)
    assert err.value.kind == "following error"
    assert abs(err.value.value) > 0.001
    # with a generous error interlock the actuator saturates instead: a 10 mm, 20 Hz demand
    # (1.26 m/s) becomes a flow-limited, triangle-like motion: the speed sits near Q_max / A
    # for most of each half cycle (the orifice law and the oil spring let an overrunning
    # inertial load exceed it briefly), and the amplitude falls well short of the demand
    loose = vrig.load_rig(TEST_RIG, error_limit=0.05)
    demand = 0.010 * np.sin(2 * np.pi * 20 * t)
    x = loose.run(demand, seed=0).channel("table_lvdt")[int(0.1 * fs) :]
    speed = np.abs(np.gradient(x) * fs)
    assert np.median(speed) == pytest.approx(h.velocity_limit, rel=0.25)
    amplitude = (x.max() - x.min()) / 2
    assert amplitude < 0.85 * 0.010
