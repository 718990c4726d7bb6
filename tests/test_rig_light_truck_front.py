"""Light-truck front suspension (SLA double wishbone driven by six wheel forces/moments): the wheel
rate and ride frequency follow the README's derivation from the documented hardpoints, masses and
rates (an independent rigid-link kinematic model, not MuJoCo); the upper ball-joint force against
the vertical wheel load is non-linear over the documented travel (geometry only: the bumper and the
rebound stop are not reached); a lateral load moves the vertical bushing forces. Documented values:
models/light-truck-front/README.md."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest
from scipy.optimize import brentq

import vrig
from vrig.rigs import damper

NAME = "light-truck-front"
G = 9.81
# --- documented hardpoints [m], vehicle axes x forward, y outward, z up (README "Hardpoints") -----
P = {
    "LF": (0.16, 0.37, -0.10), "LR": (-0.20, 0.37, -0.075), "LBJ": (0.005, 0.78, -0.13),
    "UF": (0.11, 0.45, 0.235), "UR": (-0.15, 0.45, 0.25), "UBJ": (-0.02, 0.72, 0.20),
    "W": (0.0, 0.86, 0.0), "TO": (-0.15, 0.74, -0.03), "TI": (-0.16, 0.40, -0.02),
    "SL": (0.0, 0.62, -0.095), "SU": (0.0, 0.56, 0.33),
}  # fmt: skip
P = {k: np.array(v, dtype=float) for k, v in P.items()}
# --- documented masses, rates (README "Parameters") ----------------------------------------------
K_SPRING, L_FREE = 100_000.0, 0.50697  # coil spring [N/m], free length [m]
KT_LCA, KT_UCA = 2 * 355.0, 2 * 115.5  # arm pivot torsion: 2 bushings x k_t [N m/rad]
F0 = 5400.0  # static corner load [N]
M_LCA, M_UCA, M_STUD, M_KNUCKLE = 4.0, 1.8, 0.3, 62.0  # moving with the arm rotation [kg]
M_EYES = 2 * 1.0 + 2 * 0.6  # bushing eyes (sleeves): translate only with the bushings [kg]
I_LCA, I_UCA = np.diag([0.06, 0.035, 0.09]), np.diag([0.012, 0.008, 0.018])  # [kg m^2]
I_KNUCKLE = np.diag([1.7, 0.5, 1.7])
CM_LCA = (P["LF"] + P["LR"] + P["LBJ"]) / 3
CM_UCA = (P["UF"] + P["UR"] + P["UBJ"]) / 3
CM_KNUCKLE = np.array([0.0, 0.833, 0.0])
K_TYRE = 300_000.0  # LT245/75R16 radial rate [N/m]
M_SPRUNG = F0 / G - (M_KNUCKLE + M_LCA + M_UCA + M_STUD + M_EYES)  # quarter-car sprung mass [kg]
README_WHEEL_RATE = 44_060.0  # [N/m]
README_RIDE_HZ = 1.423  # 2-DOF quarter car, undamped [Hz]
TRAVEL = (-0.076, 0.060)  # documented travel before the rebound stop / bumper [m]


# --- independent rigid-link kinematics of the corner ---------------------------------------------
def _rot(axis, angle):
    a = axis / np.linalg.norm(axis)
    k = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    return np.eye(3) + np.sin(angle) * k + (1 - np.cos(angle)) * k @ k


def _on_arm(front, rear, point, angle):
    return front + _rot(front - rear, angle) @ (point - front)


def _pose(tl):
    """Rigid arms and knuckle for the lower-arm rotation ``tl`` [rad] about its pivot axis: the
    upper arm closes |UBJ - LBJ| (the kingpin), the tie rod fixes the rotation about the kingpin."""
    lbj = _on_arm(P["LF"], P["LR"], P["LBJ"], tl)
    kingpin = np.linalg.norm(P["UBJ"] - P["LBJ"])
    tu = brentq(
        lambda a: np.linalg.norm(_on_arm(P["UF"], P["UR"], P["UBJ"], a) - lbj) - kingpin, -0.8, 0.8
    )
    ubj = _on_arm(P["UF"], P["UR"], P["UBJ"], tu)
    e0 = (P["UBJ"] - P["LBJ"]) / kingpin
    e1 = (ubj - lbj) / np.linalg.norm(ubj - lbj)
    v = np.cross(e0, e1)
    r0 = _rot(v, np.arctan2(np.linalg.norm(v), e0 @ e1)) if np.linalg.norm(v) > 1e-14 else np.eye(3)
    tie_rod = np.linalg.norm(P["TO"] - P["TI"])

    def knuckle(psi):
        r = _rot(e1, psi) @ r0
        return r, lambda p: lbj + r @ (p - P["LBJ"])

    psi = brentq(lambda s: np.linalg.norm(knuckle(s)[1](P["TO"]) - P["TI"]) - tie_rod, -0.5, 0.5)
    r, move = knuckle(psi)
    return {"tl": tl, "tu": tu, "ubj": ubj, "R": r, "move": move,
            "SL": _on_arm(P["LF"], P["LR"], P["SL"], tl)}  # fmt: skip


def _potential(tl):
    """Spring, pivot-torsion and gravity energy of the rigid mechanism [J]."""
    p = _pose(tl)
    length = np.linalg.norm(p["SL"] - P["SU"])
    heights = [
        _on_arm(P["LF"], P["LR"], CM_LCA, tl)[2],
        _on_arm(P["UF"], P["UR"], CM_UCA, p["tu"])[2],
        p["ubj"][2],
        p["move"](CM_KNUCKLE)[2],
    ]
    return (
        0.5 * K_SPRING * (length - L_FREE) ** 2
        + 0.5 * KT_LCA * tl**2
        + 0.5 * KT_UCA * p["tu"] ** 2
        + G * np.dot([M_LCA, M_UCA, M_STUD, M_KNUCKLE], heights)
    )


def _wheel_load(tl, h=1e-5):
    """Spindle-frame vertical force [N] that holds the mechanism at ``tl`` (virtual work)."""
    dv = (_potential(tl + h) - _potential(tl - h)) / (2 * h)
    dw = (_pose(tl + h)["move"](P["W"]) - _pose(tl - h)["move"](P["W"])) / (2 * h)
    return dv / (_pose(tl)["R"][:, 2] @ dw)


def _wheel_rate(h=0.002):
    z = [_pose(t)["move"](P["W"])[2] for t in (-h, h)]
    return (_wheel_load(h) - _wheel_load(-h)) / (z[1] - z[0])


def _unsprung_mass(h=1e-5):
    """Effective mass at the wheel centre [kg]: kinetic energy of the arms, stud and knuckle per
    unit vertical wheel-centre velocity."""
    a, b = _pose(h), _pose(-h)
    dz = a["move"](P["W"])[2] - b["move"](P["W"])[2]
    m = M_KNUCKLE * np.sum(((a["move"](CM_KNUCKLE) - b["move"](CM_KNUCKLE)) / dz) ** 2)
    rel = a["R"] @ b["R"].T
    omega = np.array([rel[2, 1] - rel[1, 2], rel[0, 2] - rel[2, 0], rel[1, 0] - rel[0, 1]]) / 2 / dz
    m += omega @ I_KNUCKLE @ omega
    m += M_STUD * np.sum(((a["ubj"] - b["ubj"]) / dz) ** 2)
    for front, rear, cm, mass, inertia, key in (
        (P["LF"], P["LR"], CM_LCA, M_LCA, I_LCA, "tl"),
        (P["UF"], P["UR"], CM_UCA, M_UCA, I_UCA, "tu"),
    ):
        move = (_on_arm(front, rear, cm, a[key]) - _on_arm(front, rear, cm, b[key])) / dz
        axis = (front - rear) / np.linalg.norm(front - rear)
        m += mass * move @ move + ((a[key] - b[key]) / dz) ** 2 * axis @ inertia @ axis
    return m


def _ride_frequency():
    """Undamped bounce frequency [Hz] of the 2-DOF quarter car: sprung mass on the wheel rate,
    effective unsprung mass on the tyre."""
    kw, mu = _wheel_rate(), _unsprung_mass()
    mass = np.diag([M_SPRUNG, mu])
    stiff = np.array([[kw, -kw], [-kw, kw + K_TYRE]])
    w2 = np.linalg.eigvals(np.linalg.solve(mass, stiff)).real
    return np.sqrt(w2.min()) / (2 * np.pi)


# --- the rig, held quasi-statically --------------------------------------------------------------
@pytest.fixture(scope="module")
def rig():
    return vrig.load_rig(NAME)


def _static(rig, ctrl, seconds=2.5):
    """Sensor readings of ``rig`` after ``seconds`` under constant wheel forces (settled: the
    corner mode is damped at zeta ~ 0.7), vrig's damper callback registered (the default
    damper's series-compliance node: it carries no static load once settled)."""
    model = rig.model
    data = mujoco.MjData(model)
    data.ctrl[: len(ctrl)] = ctrl  # the six wheel forces; the damper's actuator takes none
    damper.install(model, data, rig._damper_bound)
    try:
        mujoco.mj_step(model, data, nstep=round(seconds / model.opt.timestep))
    finally:
        damper.uninstall(data)
    assert not data.warning.number.any()
    return {
        s: data.sensor(s).data.copy()
        for s in ("wheel_centre", "ubj_force", "ucaf_force", "ucar_force", "lcaf_force",
                  "lcar_force", "coilover_length")
    }  # fmt: skip


def _fz(value):
    return np.array([0.0, 0.0, value, 0.0, 0.0, 0.0])


def test_channels_and_a_clean_random_run(rig):
    assert [c.name for c in rig.inputs] == ["Fx", "Fy", "Fz", "Mx", "My", "Mz"]
    assert [c.name for c in rig.outputs] == [
        "ucaf_vertical", "ucaf_lateral", "ucar_vertical", "ucar_lateral",
        "lcaf_vertical", "lcaf_lateral", "lcar_vertical", "lcar_lateral",
        "lca_angle", "ubj_longitudinal",
    ]  # fmt: skip
    assert rig.fs == 200 and rig.bandwidth == (0.0, 25.0)
    rng = np.random.default_rng(0)
    full = np.array([c.full_scale for c in rig.inputs])
    y = rig.run(0.05 * full * rng.standard_normal((400, 6)), seed=0)
    assert np.all(np.isfinite(y.data)) and np.all(y.data.std(axis=0) > 0)


def test_readme_derivation_is_the_documented_one():
    # the README's numbers follow from the documented hardpoints, masses and rates
    assert _wheel_load(0.0) == pytest.approx(F0, rel=0.002)  # static equilibrium at design
    assert _wheel_rate() == pytest.approx(README_WHEEL_RATE, rel=0.005)
    assert _ride_frequency() == pytest.approx(README_RIDE_HZ, rel=0.005)


def test_wheel_rate_within_5_percent_of_the_derivation(rig):
    base = _static(rig, _fz(0.0))
    assert base["wheel_centre"][2] == pytest.approx(0.0, abs=0.002)  # rides at the design pose
    rates = []
    for df in (-300.0, 300.0):
        dz = _static(rig, _fz(df))["wheel_centre"][2] - base["wheel_centre"][2]
        rates.append(df / dz)
    assert np.mean(rates) == pytest.approx(_wheel_rate(), rel=0.05)


def test_ride_frequency_within_5_percent_of_the_derivation(rig):
    """Quarter-car probe: the frame (sprung mass) free to bounce on a vertical guide, the wheel
    centre on the tyre spring to the ground, the Fz bias and the damper removed."""
    spec = mujoco.MjSpec.from_file(str(rig.description.mjcf))
    frame = spec.body("frame")
    frame.add_joint(name="bounce", type=mujoco.mjtJoint.mjJNT_SLIDE, axis=[0, 0, 1])
    frame.mass, frame.inertia, frame.explicitinertial = M_SPRUNG, [50.0, 50.0, 50.0], True
    spec.worldbody.add_site(name="ground", pos=[0.0, 0.86, -0.38])
    tyre = spec.add_tendon(name="tyre", stiffness=[K_TYRE, 0, 0])
    tyre.springlength = [0.38 + F0 / K_TYRE] * 2
    tyre.wrap_site("spindle")
    tyre.wrap_site("ground")
    spec.actuator("Fz").biasprm[0] = 0.0
    spec.tendon("damper").damping[0] = 0.0
    model = spec.compile()
    data = mujoco.MjData(model)
    data.qvel[model.joint("bounce").dofadr[0]] = 0.05  # a bounce kick [m/s]
    dt = model.opt.timestep
    z = np.empty(round(8.0 / dt))
    for i in range(z.size):
        mujoco.mj_step(model, data)
        z[i] = data.qpos[model.joint("bounce").qposadr[0]]
    assert not data.warning.number.any()
    x = z - z.mean()
    up = np.flatnonzero((x[:-1] < 0) & (x[1:] >= 0))
    f = (up.size - 1) / ((up[-1] - up[0]) * dt)
    assert f == pytest.approx(_ride_frequency(), rel=0.05)


def test_ball_joint_force_against_vertical_load_is_geometrically_non_linear(rig):
    # quasi-static vertical loads about the static one; the documented travel ends before the
    # bumper (+64 mm) and the rebound stop (-79 mm): the non-linearity is the arms' geometry
    base = _static(rig, _fz(0.0))
    secant = {}
    for df in (-3500.0, -300.0, 300.0, 2600.0):
        s = _static(rig, _fz(df))
        dz = s["wheel_centre"][2] - base["wheel_centre"][2]
        assert TRAVEL[0] - 0.005 < dz < TRAVEL[1] + 0.005
        # neither end stop touched: the coil-over stays between the stops' engagement lengths
        assert 0.38921 < s["coilover_length"][0] < 0.47921
        secant[df] = (s["ubj_force"][0] - base["ubj_force"][0]) / df
    jounce = secant[2600.0] / secant[300.0]
    rebound = secant[-300.0] / secant[-3500.0]
    print(f"upper ball-joint longitudinal secant [N/N]: {secant}; full/small jounce {jounce:.2f}, "
          f"small/full rebound {rebound:.2f}")  # fmt: skip
    assert jounce >= 1.3 and rebound >= 1.3


def test_lateral_load_moves_the_vertical_bushing_forces(rig):
    base = _static(rig, np.zeros(6))
    fy = 3000.0
    s = _static(rig, np.array([0.0, fy, 0.0, 0.0, 0.0, 0.0]))
    for k in ("ucaf_force", "ucar_force", "lcaf_force", "lcar_force"):
        assert abs(s[k][2] - base[k][2]) > 0.01 * fy, k  # cross-coupling (jacking, arm angles)
