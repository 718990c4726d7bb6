"""The gas-spring (air-spring) element (vrig.rigs.gas_spring) against the polytropic gas law
written out here independently: a mass on an air spring under gravity (static height, force and
pressure at any height, small-oscillation frequency from the analytic rate, Boyle's law)."""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest
from mujoco import rollout
from scipy.optimize import brentq

from vrig import RigParameterError
from vrig.rigs import gas_spring
from vrig.rigs.gas_spring import AirSpring

# a 2000 kg mass on a vertical guide, carried by an air spring from a ground plate (site
# "base", z = 0) to the mass (site "plate", z = 0.3 m in the model pose)
MJCF = """
<mujoco>
  <option timestep="0.0002" gravity="0 0 -9.81" integrator="implicitfast"/>
  <worldbody>
    <site name="base" pos="0 0 0"/>
    <body name="mass" pos="0 0 0.3">
      <joint name="z" type="slide" axis="0 0 1" damping="{damping}"/>
      <inertial pos="0 0 0" mass="2000" diaginertia="1 1 1"/>
      <site name="plate" pos="0 0 0"/>
    </body>
  </worldbody>
  <tendon><spatial name="air"><site site="base"/><site site="plate"/></spatial></tendon>
  <sensor>
    <user name="p" dim="1" needstage="pos" datatype="real"/>
    <tendonpos name="h" tendon="air"/>
  </sensor>
</mujoco>
"""
MASS, G = 2000.0, 9.81
# the documented law's parameters (SI)
H_D, P_D, V_D, A_D, SLOPE, N, P_A = 0.28, 3.0e5, 0.022, 0.0707, -0.05, 1.3, 101325.0


def law(h):
    """(gauge pressure [Pa], force [N], rate -dF/dh [N/m]) of the polytropic air spring:
    V = V_d + A_d (h - h_d) + A' (h - h_d)^2 / 2, A_e = dV/dh, p V^n = const."""
    d = h - H_D
    vol = V_D + A_D * d + 0.5 * SLOPE * d * d
    area = A_D + SLOPE * d
    p_abs = (P_D + P_A) * (V_D / vol) ** N
    force = (p_abs - P_A) * area
    rate = N * p_abs * area**2 / vol - (p_abs - P_A) * SLOPE
    return p_abs - P_A, force, rate


def spring(**kw):
    args = dict(name="air", tendon="air", sensor="p", design_height=H_D, design_pressure=P_D,
                volume=V_D, effective_area=A_D, area_slope=SLOPE, polytropic_index=N,
                ambient_pressure=P_A)  # fmt: skip
    return AirSpring(**{**args, **kw})


def model(damping=0.0):
    m = mujoco.MjModel.from_xml_string(MJCF.replace("{damping}", str(damping)))
    return m, mujoco.MjData(m)


def bound(m, s):
    t = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_TENDON, "air")
    return [(s, t, int(m.sensor_adr[0]))]


def simulate(m, d, z0, seconds, s):
    """Positions and sensors of a rollout from mass position z0 (joint coordinate)."""
    mujoco.mj_resetData(m, d)
    d.qpos[0] = z0
    state = np.empty(mujoco.mj_stateSize(m, mujoco.mjtState.mjSTATE_FULLPHYSICS))
    mujoco.mj_getState(m, d, state, mujoco.mjtState.mjSTATE_FULLPHYSICS)
    steps = round(seconds / m.opt.timestep)
    gas_spring.install(m, d, bound(m, s))
    try:
        st, sens = rollout.rollout(m, d, state[None], np.zeros((1, steps, 0)))
    finally:
        gas_spring.uninstall()
    return st[0, :, 1], sens[0]


def test_force_and_pressure_follow_the_polytropic_law_at_any_height():
    m, d = model()
    s = spring()
    t = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_TENDON, "air")
    for h in np.linspace(0.17, 0.40, 9):
        d.qpos[0] = h - 0.3
        mujoco.mj_forward(m, d)
        bare = d.qfrc_passive.copy()
        gas_spring.install(m, d, bound(m, s))
        try:
            mujoco.mj_forward(m, d)
        finally:
            gas_spring.uninstall()
        jac = np.zeros((m.ntendon, m.nv))
        mujoco.mju_sparse2dense(jac, d.ten_J, m.ten_J_rownnz, m.ten_J_rowadr, m.ten_J_colind)
        force = (d.qfrc_passive - bare)[0] / jac[t, 0]
        gauge, f_law, _ = law(h)
        assert d.sensordata[1] == pytest.approx(h, abs=1e-12)
        assert force == pytest.approx(f_law, rel=1e-9)
        assert d.sensordata[0] == pytest.approx(gauge, rel=1e-9)
        # and the element's own NumPy evaluation (used by the rig for its stability limit)
        assert s.force_at(h) == pytest.approx(f_law, rel=1e-12)
        assert s.rate_at(h) == pytest.approx(law(h)[2], rel=1e-12)


def test_boyle_isothermal_constant_area():
    s = spring(polytropic_index=1.0, area_slope=0.0)
    h = np.linspace(0.15, 0.45, 7)
    p_abs = s.pressure_at(h) + P_A
    vol = V_D + A_D * (h - H_D)
    np.testing.assert_allclose(p_abs * vol, (P_D + P_A) * V_D, rtol=1e-12)


def test_static_height_under_a_weight_and_small_oscillation_frequency():
    # static: the damped mass settles where the spring force carries its weight
    h_eq = brentq(lambda h: law(h)[1] - MASS * G, 0.1, 0.5)
    m, d = model(damping=2e4)
    z, sens = simulate(m, d, 0.0, 3.0, spring())
    assert 0.3 + z[-1] == pytest.approx(h_eq, abs=1e-6)
    assert sens[-1, 0] == pytest.approx(law(h_eq)[0], rel=1e-6)
    # dynamic: undamped small oscillation about it at sqrt(k / m), k = n p A^2 / V - p_g A'
    m, d = model(damping=0.0)
    z, _ = simulate(m, d, h_eq - 0.3 + 1e-4, 2.0, spring())
    x = z - (h_eq - 0.3)
    up = np.flatnonzero((x[:-1] < 0) & (x[1:] >= 0))
    period = (up[-1] - up[0]) / (len(up) - 1) * m.opt.timestep
    expected = math.sqrt(law(h_eq)[2] / MASS) / (2 * math.pi)
    assert 1 / period == pytest.approx(expected, rel=2e-3)


def test_large_oscillation_is_conservative_and_asymmetric():
    # undamped, 60 mm below the equilibrium: the gas energy is stored and returned (the
    # element is the derivative of its energy), and the hardening law makes the upper turning
    # point farther from the equilibrium than the lower one
    h_eq = brentq(lambda h: law(h)[1] - MASS * G, 0.1, 0.5)
    m, d = model(damping=0.0)
    z, _ = simulate(m, d, h_eq - 0.3 - 0.06, 1.5, spring())
    h = z + 0.3
    assert h.min() == pytest.approx(h_eq - 0.06, abs=2e-4)
    assert h.max() - h_eq > 0.06 + 0.005

    def energy(hh):  # gas work from h_eq to hh plus the potential energy of the weight
        grid = np.linspace(h_eq, hh, 2001)
        return -np.trapezoid(law(grid)[1], grid) + MASS * G * (hh - h_eq)

    assert energy(h.max()) == pytest.approx(energy(h.min()), rel=5e-3)


def test_the_callbacks_are_idle_when_not_installed():
    m, d = model()
    s = spring()
    gas_spring.install(m, d, bound(m, s))
    gas_spring.uninstall()
    d.qpos[0] = 0.0
    mujoco.mj_forward(m, d)
    assert d.qfrc_passive[0] == 0.0 and d.sensordata[0] == 0.0


@pytest.mark.parametrize(
    ("key", "value"),
    [("volume", 0.0), ("effective_area", -1.0), ("polytropic_index", 1.6),
     ("design_pressure", -2e5), ("design_height", float("nan"))],
)  # fmt: skip
def test_bad_parameters_are_refused_by_name(key, value):
    with pytest.raises(RigParameterError, match=key):
        spring(**{key: value})
