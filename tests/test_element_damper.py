"""Hydraulic damper element (vrig.rigs.damper): the bleed / knee / blow-off force-velocity law.

Truth: the law as documented in the module and the side-cars (per stroke direction
``|F| = c |u|`` up to the knee ``v_k``, then ``c v_k + β c (|u| - v_k)``), written out here
independently, and the coefficients the hand-written MJCF files had before the dampers moved to
the side-cars (shock absorber 12 kN s/m both ways, motorcycle 4000 / 10400 N s/m, trailer 4750
/ 14250 N s/m, light truck 6500 N s/m). The specimen is isolated in the rig's own model: only
the damper's joint moves, kinematically, along a sine; the force is what MuJoCo applies to it
(the damper's actuators plus the joint's own damping; the seal friction is a constraint force,
not part of the law)."""

from __future__ import annotations

import copy
import json

import mujoco
import numpy as np
import pytest

import vrig
from vrig.errors import RigModelError, RigParameterError
from vrig.rigs import damper, rig_path
from vrig.rigs.damper import Damper, realise

PEAKS = [0.05, 0.1, 0.3, 0.6, 1.0]  # documented test velocities [m/s], both directions
SPEC = json.loads(rig_path("shock-absorber").read_text())


def _analytic(u, c_comp, c_reb, beta_comp, beta_reb, knee_comp, knee_reb):
    """The documented law, damper force [N] (positive in rebound) at extension velocity u."""
    if u >= 0:
        c, beta, knee, sign = c_reb, beta_reb, knee_reb, 1.0
    else:
        c, beta, knee, sign = c_comp, beta_comp, knee_comp, -1.0
    s = abs(u)
    return sign * (c * s if s <= knee else c * knee + beta * c * (s - knee))


def _digressive():
    """The thesis variant's documented damper-law parameters, from the side-car."""
    p = SPEC["variants"]["thesis"]["parameters"]
    c = p["damping"]
    return dict(
        c_comp=c, c_reb=c * p["rebound_ratio"],
        beta_comp=p["blowoff_ratio_compression"], beta_reb=p["blowoff_ratio_rebound"],
        knee_comp=p["knee_velocity_compression"], knee_reb=p["knee_velocity_rebound"],
    )  # fmt: skip


def _damper_forces(model, dof, actuators, velocities):
    """Generalised force on ``dof`` from the damper (``actuators`` plus the dof's own
    damping) while only that dof moves with each of ``velocities`` [m/s]. The tendons' damping
    (e.g. the load cell's, which spans the damper joint) is switched off on a copy."""
    model = copy.copy(model)
    model.tendon_damping[:] = 0.0
    data = mujoco.MjData(model)
    out = []
    for v in velocities:
        data.qvel[:] = 0.0
        data.qvel[dof] = v
        mujoco.mj_forward(model, data)
        f = data.qfrc_damper[dof] + sum(
            data.actuator_force[a] * _moment(data, a, dof) for a in actuators
        )
        out.append(f)
    return np.array(out)


def _moment(data, a, dof):
    """d(actuator length)/d(qpos of dof) for actuator ``a`` (sparse moment storage)."""
    start, n = data.moment_rowadr[a], data.moment_rownnz[a]
    cols = data.moment_colind[start : start + n]
    vals = data.actuator_moment[start : start + n]
    hit = np.flatnonzero(cols == dof)
    return float(vals[hit[0]]) if hit.size else 0.0


def _sine_peaks(model, dof, actuators, peak, *, cycles=2, samples=200):
    """Kinematic sine run of the damper joint at ``peak`` velocity [m/s] (1 Hz): the largest
    rebound and compression forces the damper applies (extension = positive joint velocity)."""
    t = np.arange(cycles * samples) / samples
    v = peak * np.cos(2 * np.pi * t)
    f = _damper_forces(model, dof, actuators, v)
    return f.min(), f.max()  # rebound resisted by a negative force, compression by a positive


def _specimen(rig):
    """(model, damper dof, damper actuator ids) of the shock-absorber rig."""
    m = rig.model
    dof = int(m.jnt_dofadr[m.joint("damper").id])
    acts = [i for i in range(m.nu) if m.actuator(i).name.startswith("damper_")]
    return m, dof, acts


@pytest.fixture(scope="module")
def digressive():
    """The shock-absorber rig, thesis variant (its asymmetric, digressive damper law)."""
    return vrig.load_rig("shock-absorber", variant="thesis")


def test_the_element_law_is_the_documented_one():
    law = _digressive()
    d = Damper("d", joint="j", damping=law["c_comp"], rebound_ratio=law["c_reb"] / law["c_comp"],
               blowoff_ratio_compression=law["beta_comp"], blowoff_ratio_rebound=law["beta_reb"],
               knee_velocity_compression=law["knee_comp"], knee_velocity_rebound=law["knee_reb"])  # fmt: skip
    u = np.array([-1.0, -0.6, -0.3, -0.15, -0.1, -0.05, 0.0, 0.05, 0.1, 0.15, 0.3, 0.6, 1.0])
    expected = [_analytic(x, **law) for x in u]
    np.testing.assert_allclose(d.force_at(u), expected, rtol=1e-12, atol=1e-9)
    # the variant's documented figures at 0.52 m/s: 1.7 kN compression, 5.0 kN rebound
    assert d.force_at(-0.52) == pytest.approx(-1677.0, abs=1.0)
    assert d.force_at(0.52) == pytest.approx(5031.0, abs=1.0)
    # on the joint: opposing the velocity, mirrored by extension = -1
    assert d.generalised_force_at(0.3) == pytest.approx(-_analytic(0.3, **law))
    mirrored = Damper("d", tendon="t", extension=-1, damping=d.damping, rebound_ratio=d.rebound_ratio,
                      blowoff_ratio_compression=d.blowoff_ratio_compression,
                      blowoff_ratio_rebound=d.blowoff_ratio_rebound,
                      knee_velocity_compression=d.knee_velocity_compression,
                      knee_velocity_rebound=d.knee_velocity_rebound)  # fmt: skip
    assert mirrored.generalised_force_at(0.3) == pytest.approx(
        _analytic(-0.3, **law)
    )  # compression
    assert mirrored.generalised_force_at(-0.3) == pytest.approx(_analytic(0.3, **law))  # rebound


@pytest.mark.parametrize("peak", PEAKS)
def test_digressive_sine_runs_match_the_law_within_2_percent(digressive, peak):
    m, dof, acts = _specimen(digressive)
    assert len(acts) == 4  # slope + bleed actuator per stroke direction
    rebound, compression = _sine_peaks(m, dof, acts, peak)
    law = _digressive()
    assert -rebound == pytest.approx(_analytic(peak, **law), rel=0.02)
    assert compression == pytest.approx(-_analytic(-peak, **law), rel=0.02)


def test_digressive_variant_is_asymmetric_and_has_a_knee(digressive):
    m, dof, acts = _specimen(digressive)
    law = _digressive()
    v = np.array([0.05, 0.1, 0.3, 0.6, 1.0])
    reb = -_damper_forces(m, dof, acts, v)
    comp = _damper_forces(m, dof, acts, -v)
    ratio = reb / comp
    assert np.all(ratio > 2.0)  # rebound several times compression at every speed
    assert ratio[0] == pytest.approx(law["c_reb"] / law["c_comp"], rel=0.02)
    # digressive: the slope beyond the knee is the blow-off fraction of the bleed slope
    for f, c, beta in (
        (reb, law["c_reb"], law["beta_reb"]),
        (comp, law["c_comp"], law["beta_comp"]),
    ):
        low = (f[1] - f[0]) / (v[1] - v[0])
        high = (f[4] - f[3]) / (v[4] - v[3])
        assert low == pytest.approx(c, rel=0.02)
        assert high == pytest.approx(beta * c, rel=0.02)
        assert high < 0.5 * low


@pytest.mark.parametrize("variant", ["mild"])
def test_the_default_damper_is_the_linear_12_kNs_per_m_dashpot(variant):
    """The datasheet-typical set keeps the old linear dashpot (the thesis twin has the valve
    law since issue 23: see the tests above)."""
    rig = vrig.load_rig("shock-absorber", variant=variant)
    m, dof, acts = _specimen(rig)
    assert acts == [] and m.nu == 3  # no actuator added: the hand-written model
    assert m.dof_damping[dof] == 12000.0
    assert m.dof_frictionloss[dof] == 60.0  # seal friction unchanged
    f = _damper_forces(m, dof, acts, np.array(PEAKS + [-p for p in PEAKS]))
    np.testing.assert_allclose(f, -12000.0 * np.array(PEAKS + [-p for p in PEAKS]), rtol=1e-12)
    assert rig.variant == variant


@pytest.mark.parametrize(
    "rig_name, compression, rebound, extension",
    [("motorcycle-rear", 4000.0, 10400.0, -1), ("pneumatic-trailer", 4750.0, 14250.0, 1)],
)
def test_bilinear_dampers_keep_their_hand_written_actuators(
    rig_name, compression, rebound, extension
):
    m = vrig.load_rig(rig_name, variant="mild").model  # the default is now digressive
    comp, reb = m.actuator("damper_compression"), m.actuator("damper_rebound")
    assert comp.id < reb.id and reb.id == m.nu - 1  # last, in the MJCF's order
    np.testing.assert_array_equal(comp.biasprm[:3], [0.0, 0.0, -compression])
    np.testing.assert_array_equal(reb.biasprm[:3], [0.0, 0.0, -rebound])
    # compression = shortening: tendon velocity -extension; each force range one-sided
    sign = -extension
    np.testing.assert_array_equal(sorted(comp.forcerange), sorted([0.0, -sign * 1e6]))
    np.testing.assert_array_equal(sorted(reb.forcerange), sorted([0.0, sign * 1e6]))
    assert m.tendon_damping[m.tendon("shock").id] == 0.0
    assert not any(m.actuator(i).name.endswith("_bleed") for i in range(m.nu))


def test_light_truck_mild_damper_stays_the_tendons_own_damping():
    m = vrig.load_rig("light-truck-front", variant="mild").model
    assert m.tendon_damping[m.tendon("damper").id] == 6500.0
    assert not any(m.actuator(i).name.startswith("damper_") for i in range(m.nu))
    m2 = vrig.load_rig("light-truck-front", variant="mild", damping=5000.0).model
    assert m2.tendon_damping[m2.tendon("damper").id] == 5000.0


def test_parameters_reach_the_law():
    rig = vrig.load_rig("shock-absorber", variant="mild", rebound_ratio=2.0)
    m, dof, acts = _specimen(rig)
    assert len(acts) == 2 and m.dof_damping[dof] == 0.0  # asymmetric, no knee: two slopes
    f = _damper_forces(m, dof, acts, np.array([0.2, -0.2]))
    np.testing.assert_allclose(f, [-24000.0 * 0.2, 12000.0 * 0.2], rtol=1e-12)


_STANDALONE = """<mujoco><option timestep="0.001" integrator="implicitfast"/><worldbody>
<site name="a"/><body pos="0 0 0.5"><joint name="j" type="slide" axis="0 0 1"/>
<geom size="0.05" mass="1"/><site name="b"/></body></worldbody>
<tendon><spatial name="len"><site site="a"/><site site="b"/></spatial>
<fixed name="comp"><joint joint="j" coef="-1"/></fixed></tendon></mujoco>"""


@pytest.mark.parametrize("tendon, extension", [("len", 1), ("comp", -1)])
def test_a_tendon_damper_in_a_test_model(tendon, extension):
    law = _digressive()
    d = Damper("shock", tendon=tendon, extension=extension, damping=law["c_comp"],
               rebound_ratio=law["c_reb"] / law["c_comp"],
               blowoff_ratio_compression=law["beta_comp"], blowoff_ratio_rebound=law["beta_reb"],
               knee_velocity_compression=law["knee_comp"], knee_velocity_rebound=law["knee_reb"])  # fmt: skip
    spec = mujoco.MjSpec.from_string(_STANDALONE)
    realise(spec, d)
    m = spec.compile()
    acts = list(range(m.nu))
    for peak in PEAKS:  # the body moves up = the damper lengthens (rebound) for both tendons
        rebound, compression = _sine_peaks(m, 0, acts, peak)
        assert -rebound == pytest.approx(_analytic(peak, **law), rel=0.02)
        assert compression == pytest.approx(-_analytic(-peak, **law), rel=0.02)
    with pytest.raises(ValueError, match="already has an actuator"):
        realise(spec, d)


def test_bad_dampers_are_refused():
    with pytest.raises(ValueError, match="exactly one of joint and tendon"):
        Damper("d", damping=1.0)
    with pytest.raises(ValueError, match="exactly one of joint and tendon"):
        Damper("d", joint="j", tendon="t", damping=1.0)
    with pytest.raises(RigParameterError, match="damping"):
        Damper("d", joint="j", damping=-1.0)
    with pytest.raises(RigParameterError, match="knee_velocity_rebound"):
        Damper("d", joint="j", damping=1.0, knee_velocity_rebound=-0.1)  # 0: open from rest
    with pytest.raises(ValueError, match="extension"):
        Damper("d", joint="j", damping=1.0, extension=2)
    with pytest.raises(ValueError, match="realisation"):
        Damper("d", joint="j", damping=1.0, realisation="callback")
    with pytest.raises(RigParameterError):
        Damper("d", joint="j", damping=1.0).replace(stiffness=3.0)
    spec = mujoco.MjSpec.from_string(_STANDALONE)
    with pytest.raises(ValueError, match="no joint 'nope'"):
        realise(spec, Damper("d", joint="nope", damping=1.0))
    with pytest.raises(RigParameterError, match="rebound_ratio"):
        vrig.load_rig("shock-absorber", variant="mild", rebound_ratio=0.5)


def test_a_side_car_with_an_unknown_damper_joint_is_a_model_error(tmp_path):
    raw = json.loads(rig_path("shock-absorber").read_text())
    raw["dampers"][0]["joint"] = "nope"
    raw["mjcf"] = str(rig_path("shock-absorber").parent / raw["mjcf"])
    path = tmp_path / "shock-absorber.rig.json"
    path.write_text(json.dumps(raw))
    with pytest.raises(RigModelError, match="no joint 'nope'"):
        vrig.load_rig(path)


# --- series compliance (a spring k_s in series with the valves: a Maxwell element) ------------
_HEAVY = """<mujoco><option timestep="0.0002" integrator="implicitfast" gravity="0 0 0"/>
<worldbody><body><joint name="j" type="slide" axis="0 0 1" stiffness="{k}"/>
<geom size="0.05" mass="{m}"/></body></worldbody></mujoco>"""


def _heavy_run(dmp, *, hz, velocity, seconds):
    """A 1e9 kg body oscillating on its own spring at ``hz`` with peak ``velocity`` [m/s] (the
    damper's force cannot slow it): (damper force on the joint [N], joint position [m]) per step,
    the force computed from that position (before the step)."""
    mass = 1e9
    w = 2 * np.pi * hz
    spec = mujoco.MjSpec.from_string(_HEAVY.format(k=mass * w * w if hz else 0.0, m=mass))
    realise(spec, dmp)
    m = spec.compile()
    records = damper.bind(m, [dmp])
    d = mujoco.MjData(m)
    d.qvel[0] = velocity
    n = round(seconds / m.opt.timestep)
    f, v = np.empty(n), np.empty(n)
    damper.install(m, d, records)
    try:
        assert damper.ACT_DYN.installed
        for k in range(n):
            v[k] = d.qpos[0]  # the state the step's force is computed from
            mujoco.mj_step(m, d)
            f[k] = d.actuator_force[0]
    finally:
        damper.uninstall(d)
    assert not damper.ACT_DYN.installed
    return f, v


def test_the_inverse_law_is_the_documented_one():
    law = _digressive()
    d = Damper("d", joint="j", damping=law["c_comp"], rebound_ratio=law["c_reb"] / law["c_comp"],
               blowoff_ratio_compression=law["beta_comp"], blowoff_ratio_rebound=law["beta_reb"],
               knee_velocity_compression=law["knee_comp"], knee_velocity_rebound=law["knee_reb"])  # fmt: skip
    u = np.array([-1.0, -0.3, -0.15, -0.05, 0.0, 0.05, 0.15, 0.3, 1.0])
    forces = np.array([_analytic(x, **law) for x in u])
    np.testing.assert_allclose(d.velocity_at(forces), u, rtol=1e-12, atol=1e-15)


@pytest.mark.parametrize("hz", [2.0, 10.0])
@pytest.mark.parametrize("c", [6000.0, 18000.0])
def test_series_compliance_is_a_maxwell_element(hz, c):
    """A linear law with k_s in series: after the transient the force amplitude is
    c V / sqrt(1 + (w tau)^2), tau = c / k_s, and it lags (a loop: force at zero velocity)."""
    k_s, v_peak = 6e6, 0.1
    dmp = Damper("d", joint="j", damping=c, series_stiffness=k_s)
    f, q = _heavy_run(dmp, hz=hz, velocity=v_peak, seconds=1.0)
    half = len(f) // 2
    wt = 2 * np.pi * hz * c / k_s
    amplitude = c * v_peak / np.sqrt(1 + wt**2)
    assert np.abs(f[half:]).max() == pytest.approx(amplitude, rel=0.02)
    # the loop: the force's component in phase with the displacement (the part at zero
    # velocity) is amplitude * sin(lag), lag = atan(w tau), by least squares at w
    t = np.arange(len(f))[half:] * 0.0002
    basis = np.column_stack([np.sin(2 * np.pi * hz * t), np.cos(2 * np.pi * hz * t)])
    (qs, qc), (fs, fc) = (np.linalg.lstsq(basis, y[half:], rcond=None)[0] for y in (q, f))
    in_phase = (fs * qs + fc * qc) / np.hypot(qs, qc)
    assert -in_phase == pytest.approx(amplitude * np.sin(np.arctan(wt)), rel=0.02)


@pytest.mark.parametrize("velocity", [0.1, -0.1, 0.6, -0.6])
def test_series_compliance_settles_on_the_law_at_constant_velocity(velocity):
    law = _digressive()
    k_s = 6e6
    d = Damper("d", joint="j", damping=law["c_comp"], rebound_ratio=law["c_reb"] / law["c_comp"],
               blowoff_ratio_compression=law["beta_comp"], blowoff_ratio_rebound=law["beta_reb"],
               knee_velocity_compression=law["knee_comp"], knee_velocity_rebound=law["knee_reb"],
               series_stiffness=k_s)  # fmt: skip
    f, _ = _heavy_run(d, hz=0.0, velocity=velocity, seconds=0.05)  # tau <= 18000 / 6e6 = 3 ms
    assert f[-1] == pytest.approx(-_analytic(velocity, **law), rel=0.02)
    if abs(velocity) < law["knee_comp"]:  # inside the bleed: a first-order rise, tau = c / k_s
        c = law["c_reb"] if velocity > 0 else law["c_comp"]
        tau = c / k_s
        at_tau = f[round(tau / 0.0002)]  # f[k]: the force at t = k dt (before step k)
        assert at_tau == pytest.approx(-_analytic(velocity, **law) * (1 - np.exp(-1)), rel=0.03)


def test_series_compliance_in_the_rig():
    rig = vrig.load_rig("shock-absorber", variant="thesis", series_stiffness=6e6)
    m = rig.model
    assert m.actuator("damper_compliance").id == m.nu - 1 and m.na == 1
    assert not any(m.actuator(i).name.endswith("_bleed") for i in range(m.nu))
    x = np.zeros((500, 1))
    x[:, 0] = 0.004 * np.sin(2 * np.pi * 3.0 * np.arange(500) / rig.fs)
    y = rig.run(x, seed=0)
    assert np.all(np.isfinite(y.data)) and np.abs(y.data).max() > 100.0
    assert not damper.ACT_DYN.installed  # registered for the run only
    # a stiffer series spring brings the rig closer to the memoryless law (k_s -> infinity)
    stiff = vrig.load_rig("shock-absorber", variant="thesis", series_stiffness=2e7)
    rigid = vrig.load_rig("shock-absorber", variant="thesis").run(x, seed=0).data
    gap_soft = np.sqrt(np.mean((y.data - rigid) ** 2))
    gap_stiff = np.sqrt(np.mean((stiff.run(x, seed=0).data - rigid) ** 2))
    assert 0 < gap_stiff < gap_soft
    with pytest.raises(ValueError, match="every slope"):
        Damper("d", joint="j", damping=0.0, series_stiffness=1e6)


# --- the vehicle rigs' dampers in their own models (issue 23) -----------------------------------
# Truth: the side-cars' documented values (each parameter's value, overridden by the variant's),
# read as JSON, through the law written out above (_analytic). The specimen is stroked
# kinematically in the rig's own compiled model: one joint moves along a sine, everything else is
# frozen, so only the damper's own dynamics run (the series-compliance node, advanced by vrig's
# callback exactly as MuJoCo's explicit step advances an activation). The force is the one the
# damper puts on its tendon: its actuators' plus the tendon's own damping.
VEHICLES = {  # rig: (joint that strokes the damper, the damper's tendon)
    "motorcycle-rear": ("swingarm", "shock"),
    "pneumatic-trailer": ("swingarm", "shock"),
    "light-truck-front": ("lcaf_vertical", "damper"),
}
STROKE_HZ = 2.0  # slow beside the compliance lags (omega tau <= 0.04): the peaks sit on the law


def _documented(rig_name, variant):
    """(law kwargs for _analytic, extension, series stiffness [N/m]) of the rig's damper in
    ``variant``, from its side-car."""
    raw = json.loads(rig_path(rig_name).read_text())
    v = {k: p["value"] for k, p in raw["parameters"].items()}
    if variant != "mild":
        v.update(raw["variants"][variant]["parameters"])
    if "compression_damping" in v:  # motorcycle, trailer: both bleeds set directly
        c_comp, c_reb = v["compression_damping"], v["rebound_damping"]
    else:  # light truck: compression bleed and the rebound ratio
        c_comp, c_reb = v["damping"], v["damping"] * v["rebound_ratio"]
    law = dict(
        c_comp=c_comp, c_reb=c_reb,
        beta_comp=v["blowoff_ratio_compression"], beta_reb=v["blowoff_ratio_rebound"],
        knee_comp=v["knee_velocity_compression"], knee_reb=v["knee_velocity_rebound"],
    )  # fmt: skip
    return law, raw["dampers"][0]["extension"], v["series_stiffness"]


def _stroke(rig, joint, tendon, peak, *, cycles=2):
    """Kinematic sine of ``joint`` whose damper-tendon velocity peaks near ``peak`` [m/s]
    (STROKE_HZ, starting at the reference pose at full speed): (tendon velocity [m/s], damper
    force on the tendon [N]) per physics step of the last cycle."""
    m = rig.model
    d = mujoco.MjData(m)
    ten, jnt = m.tendon(tendon).id, m.joint(joint)
    dof, adr = int(jnt.dofadr[0]), int(jnt.qposadr[0])
    acts = [i for i in range(m.nu) if m.actuator(i).name.startswith("damper_")]
    nodes = [int(m.actuator_actadr[i]) for i in acts if m.actuator(i).name.endswith("_compliance")]
    d.qvel[dof] = 1.0
    mujoco.mj_forward(m, d)
    w = 2 * np.pi * STROKE_HZ
    amp = peak / (w * abs(d.ten_velocity[ten]))  # joint amplitude for the peak tendon speed
    dt = m.opt.timestep
    n = round(cycles / STROKE_HZ / dt)
    velocity, force = np.empty(n), np.empty(n)
    mujoco.mj_resetData(m, d)
    q0 = d.qpos[adr]
    damper.install(m, d, rig._damper_bound)
    try:
        for k in range(n):
            d.qpos[adr] = q0 + amp * np.sin(w * k * dt)
            d.qvel[dof] = amp * w * np.cos(w * k * dt)
            mujoco.mj_fwdPosition(m, d)
            mujoco.mj_fwdVelocity(m, d)
            mujoco.mj_fwdActuation(m, d)
            velocity[k] = d.ten_velocity[ten]
            force[k] = d.actuator_force[acts].sum() - m.tendon_damping[ten] * velocity[k]
            d.act[nodes] += dt * d.act_dot[nodes]  # MuJoCo's explicit step of the activation
    finally:
        damper.uninstall(d)
    last = slice(n - round(1 / STROKE_HZ / dt), n)
    return velocity[last], force[last]


def _peak_forces(rig_name, variant, peaks):
    """(rebound, compression) damper force magnitudes [N] and the extension speeds [m/s] at
    which they were reached, per peak speed, from the rig's kinematic sine runs."""
    rig = vrig.load_rig(rig_name, variant=variant)
    joint, tendon = VEHICLES[rig_name]
    ext = _documented(rig_name, rig.variant)[1]
    out = []
    for peak in peaks:
        v, f = _stroke(rig, joint, tendon, peak)
        u, fu = ext * v, -ext * f  # extension speed; damper force, positive in rebound
        out.append((fu.max(), -fu.min(), u.max(), -u.min()))
    return np.array(out).T


@pytest.mark.parametrize("variant", ["digressive", "mild"])
@pytest.mark.parametrize("rig_name", list(VEHICLES))
def test_vehicle_damper_sine_runs_match_the_documented_law_within_2_percent(rig_name, variant):
    law = _documented(rig_name, variant)[0]
    reb, comp, u_reb, u_comp = _peak_forces(rig_name, variant, PEAKS)
    # the runs reach the documented test velocities, both directions
    np.testing.assert_allclose(u_reb, PEAKS, rtol=0.03)
    np.testing.assert_allclose(u_comp, PEAKS, rtol=0.03)
    expected_reb = [_analytic(u, **law) for u in u_reb]
    expected_comp = [-_analytic(-u, **law) for u in u_comp]
    np.testing.assert_allclose(reb, expected_reb, rtol=0.02)
    np.testing.assert_allclose(comp, expected_comp, rtol=0.02)


def _slopes(f, u, i, j):
    return (f[j] - f[i]) / (u[j] - u[i])


@pytest.mark.parametrize("rig_name", list(VEHICLES))
def test_vehicle_default_damper_is_asymmetric_digressive_and_compliant(rig_name):
    rig = vrig.load_rig(rig_name)
    # the real damper is the default (the motorcycle's "thesis": digressive + Table 3.2's noise)
    assert rig.variant == ("thesis" if rig_name == "motorcycle-rear" else "digressive")
    law, _ext, k_s = _documented(rig_name, "digressive")
    m = rig.model
    act = m.actuator("damper_compliance")  # the whole law in series with the oil's compliance
    assert m.actuator_gainprm[act.id][0] == k_s > 0
    assert m.tendon_damping[m.tendon(VEHICLES[rig_name][1]).id] == 0.0
    reb, comp, u_reb, u_comp = _peak_forces(rig_name, None, PEAKS)
    assert np.all(reb / comp > 2.0)  # rebound several times compression at every speed
    assert reb[0] / comp[0] == pytest.approx(law["c_reb"] / law["c_comp"], rel=0.02)
    # bleed below the knee (0.05 and 0.1 m/s lie at or below every rig's knee), blow-off above
    for f, u, c, beta, knee in (
        (reb, u_reb, law["c_reb"], law["beta_reb"], law["knee_reb"]),
        (comp, u_comp, law["c_comp"], law["beta_comp"], law["knee_comp"]),
    ):
        assert 0.1 <= knee <= 0.3 and beta < 0.5  # datasheet-typical knee, digressive valve
        assert _slopes(f, u, 0, 1) == pytest.approx(c, rel=0.02)
        assert _slopes(f, u, 3, 4) == pytest.approx(beta * c, rel=0.02)


@pytest.mark.parametrize("rig_name", list(VEHICLES))
def test_vehicle_mild_damper_is_the_old_linear_or_bilinear_dashpot(rig_name):
    """The variant mild: no knee, no compliance; the hand-written coefficients (the module's
    docstring), one slope per stroke direction."""
    c_comp, c_reb = {
        "motorcycle-rear": (4000.0, 10400.0),
        "pneumatic-trailer": (4750.0, 14250.0),
        "light-truck-front": (6500.0, 6500.0),
    }[rig_name]
    m = vrig.load_rig(rig_name, variant="mild").model
    assert m.na == 0 and not any(m.actuator(i).name.endswith("_bleed") for i in range(m.nu))
    reb, comp, u_reb, u_comp = _peak_forces(rig_name, "mild", [0.05, 1.0])
    np.testing.assert_allclose(reb / u_reb, c_reb, rtol=1e-6)
    np.testing.assert_allclose(comp / u_comp, c_comp, rtol=1e-6)
