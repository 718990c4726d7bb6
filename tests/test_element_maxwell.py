"""Rate-dependent rubber (vrig.rigs.maxwell): a generalised Maxwell chain on a joint or tendon.

Truth, written out here independently of the module:

* one branch (spring ``k`` in series with a dashpot ``c = k τ``) under a harmonic displacement
  ``x e^{iωt}`` resists with the complex stiffness ``k iωτ / (1 + iωτ)`` (storage
  ``k (ωτ)² / (1 + (ωτ)²)``, loss ``k ωτ / (1 + (ωτ)²)``); parallel branches add;
* after a displacement step ``x_0`` the force relaxes as ``x_0 Σ k_i exp(-t / τ_i)``;
* on the rig, at a displacement amplitude below the first Iwan slip (0.15 mm), the mount is
  linear: the documented small-amplitude static stiffness ``k1 + 4 k_iwan`` (1 kN/mm), the
  viscous ``c`` and the chain in parallel; the documented ranges of filled natural rubber (Gent,
  *Engineering with Rubber*; Harris' *Shock and Vibration Handbook*, rubber isolators) put the
  dynamic stiffness at 1.2-1.6 x the static one over 5-30 Hz.

The element runs in a minimal model (a 1e9 kg body on its own spring, which the chain's force
cannot slow: the displacement is imposed) so the force is the chain's alone.
"""

from __future__ import annotations

import json

import mujoco
import numpy as np
import pytest

import vrig
from vrig.rigs import damper, maxwell, rig_path
from vrig.rigs.maxwell import MaxwellChain

DT = 0.0002  # s, the minimal model's timestep
_HEAVY = """<mujoco><option timestep="{dt}" integrator="implicitfast" gravity="0 0 0"/>
<worldbody><body><joint name="j" type="slide" axis="0 0 1" stiffness="{k}"/>
<geom size="0.05" mass="{m}"/></body></worldbody></mujoco>"""
SIDE_CAR = rig_path("elastomeric-damper")


def _branch_stiffness(k, tau, hz):
    """The documented complex stiffness of one branch [N/m]."""
    iwt = 1j * 2 * np.pi * hz * tau
    return k * iwt / (1 + iwt)


def _run_chain(chain, *, hz, amplitude, seconds, start=0.0):
    """Impose ``q = start + amplitude sin(2 pi hz t)`` (a 1e9 kg body on its own spring) on the
    chain's joint; returns (t [s], q [m], force of the chain on the joint [N]) per step, the
    force computed from the state before the step."""
    mass = 1e9
    w = 2 * np.pi * hz
    spec = mujoco.MjSpec.from_string(_HEAVY.format(dt=DT, k=mass * w * w, m=mass))
    maxwell.realise(spec, chain)
    m = spec.compile()
    records = damper.bind(m, chain.branches())
    d = mujoco.MjData(m)
    d.qpos[0], d.qvel[0] = start, amplitude * w
    n = round(seconds / DT)
    q, f = np.empty(n), np.empty(n)
    damper.install(m, d, records)
    try:
        for k in range(n):
            q[k] = d.qpos[0]
            mujoco.mj_step(m, d)
            f[k] = d.actuator_force.sum()  # the branches act on the joint with moment 1
    finally:
        damper.uninstall(d)
    return np.arange(n) * DT, q, f


def _phasor(t, y, hz):
    """Complex amplitude of ``y`` at ``hz`` (least squares with a constant), y ~ Re(Y e^{iωt})."""
    w = 2 * np.pi * hz
    basis = np.column_stack([np.cos(w * t), np.sin(w * t), np.ones_like(t)])
    a, b, _ = np.linalg.lstsq(basis, y, rcond=None)[0]
    return a - 1j * b


def _measured_stiffness(chain, hz, *, settle):
    """The chain's complex stiffness measured from an imposed sine: -F / X (phasors) over the
    last 2 s after ``settle`` seconds."""
    t, q, f = _run_chain(chain, hz=hz, amplitude=1e-3, seconds=settle + 2.0)
    keep = t >= settle
    return -_phasor(t[keep], f[keep], hz) / _phasor(t[keep], q[keep], hz)


@pytest.mark.parametrize("hz", [1.0, 5.0, 20.0])
def test_one_branch_has_the_analytic_complex_stiffness(hz):
    k, tau = 2e5, 0.05  # ωτ = 0.31, 1.6, 6.3
    chain = MaxwellChain("r", relaxation_time=(tau,), stiffness=(k,), joint="j")
    measured = _measured_stiffness(chain, hz, settle=10 * tau)
    truth = _branch_stiffness(k, tau, hz)
    assert measured.real == pytest.approx(truth.real, rel=0.02)  # storage
    assert measured.imag == pytest.approx(truth.imag, rel=0.02)  # loss
    np.testing.assert_allclose(chain.complex_stiffness(hz), truth, rtol=1e-12)


@pytest.mark.parametrize("hz", [2.0, 10.0])
def test_branches_add(hz):
    ks, taus = (1e5, 2e5, 3e5), (0.2, 0.02, 0.002)
    chain = MaxwellChain("r", relaxation_time=taus, stiffness=ks, joint="j")
    measured = _measured_stiffness(chain, hz, settle=2.0)
    truth = sum(_branch_stiffness(k, tau, hz) for k, tau in zip(ks, taus, strict=True))
    assert measured.real == pytest.approx(truth.real, rel=0.02)
    assert measured.imag == pytest.approx(truth.imag, rel=0.02)


def test_step_relaxation_is_the_prony_series():
    ks, taus = (1e5, 2e5, 3e5), (0.2, 0.02, 0.002)
    chain = MaxwellChain("r", relaxation_time=taus, stiffness=ks, joint="j")
    x0 = 1e-3  # a step of 1 mm at t = 0 (the body starts there, at rest: it stays)
    t, q, f = _run_chain(chain, hz=0.0, amplitude=0.0, seconds=1.0, start=x0)
    assert np.ptp(q) < 1e-4 * x0  # the 1e9 kg body barely moves
    truth = -x0 * sum(k * np.exp(-t / tau) for k, tau in zip(ks, taus, strict=True))
    early = t <= 0.6  # while the force is above 5e-3 of its initial value
    np.testing.assert_allclose(f[early], truth[early], rtol=0.01)
    np.testing.assert_allclose(chain.relaxation(t) * -x0, truth, rtol=1e-12)


def test_the_chain_checks_its_fields():
    with pytest.raises(ValueError, match="one per branch"):
        MaxwellChain("r", relaxation_time=(0.1, 0.01), stiffness=(1e5,), joint="j")
    with pytest.raises(ValueError, match="exactly one of joint and tendon"):
        MaxwellChain("r", relaxation_time=(0.1,))
    with pytest.raises(vrig.RigParameterError, match="relaxation_time"):
        MaxwellChain("r", relaxation_time=(0.0,), joint="j")
    with pytest.raises(vrig.RigParameterError, match="stiffness"):
        MaxwellChain("r", relaxation_time=(0.1,), stiffness=(-1.0,), joint="j")
    chain = MaxwellChain("r", relaxation_time=(0.1, 0.01), joint="j")
    assert chain.stiffness == (0.0, 0.0) and chain.branches() == ()
    with pytest.raises(IndexError, match="branch index 2"):
        chain.with_branch("stiffness", 2, 1e5)
    one = chain.with_branch("stiffness", 1, 1e5)
    (branch,) = one.branches()
    assert branch.name == "r_2" and branch.series_stiffness == 1e5
    assert branch.damping == pytest.approx(1e5 * 0.01)


# --- the elastomeric damper: mild unchanged, the chain in thesis (issue 23) -------------------
def _side_car(tmp_path, *, chain: bool, diagnostic: bool = False):
    """The shipped side-car (absolute MJCF path), without its Maxwell chain and parameters
    (``chain=False``: the side-car as it was before the element), with the mount's compression
    as an extra output (``diagnostic``)."""
    d = json.loads(SIDE_CAR.read_text())
    d["mjcf"] = str((SIDE_CAR.parent / d["mjcf"]).resolve())
    if not chain:
        del d["maxwell"], d["variants"]["thesis"]  # thesis carries the chain (issue 23)
        d["default_variant"] = "mild"
        for k in [k for k in d["parameters"] if k.startswith("maxwell_")]:
            del d["parameters"][k]
    if diagnostic:
        d["outputs"].append(
            {"name": "compression", "unit": "m", "full_scale": 0.05, "sensor": "mount_compression"}
        )
    path = tmp_path / f"elastomeric-damper-{chain:d}{diagnostic:d}.rig.json"
    path.write_text(json.dumps(d))
    return path


@pytest.mark.parametrize("variant", ["mild"])  # thesis carries the chain since issue 23
def test_the_existing_variants_are_unchanged_bit_for_bit(tmp_path, variant):
    rig = vrig.load_rig("elastomeric-damper", variant=variant, seed=0)
    before = vrig.load_rig(_side_car(tmp_path, chain=False), variant=variant, seed=0)
    assert rig.model.nu == before.model.nu and rig.model.na == before.model.na == 0
    assert all(v == 0.0 for k, v in rig.parameters.items() if k.startswith("maxwell_"))
    fs = rig.fs
    x = 0.002 * np.sin(2 * np.pi * 3.0 * np.arange(round(fs)) / fs)
    assert np.array_equal(rig.run(x, seed=0).data, before.run(x, seed=0).data)


def test_the_thesis_variant_carries_the_chain():
    rig = vrig.load_rig("elastomeric-damper", variant="thesis")
    assert all(rig.parameters[f"maxwell_stiffness_{i}"] > 0 for i in (1, 2, 3))
    names = [rig.model.actuator(i).name for i in range(rig.model.nu)]
    assert [n for n in names if n.startswith("rubber_")] == [
        "rubber_1_compliance", "rubber_2_compliance", "rubber_3_compliance",
    ]  # fmt: skip
    assert rig.model.na == 3
    one = vrig.load_rig("elastomeric-damper", variant="mild", maxwell_stiffness_2=1e5)
    assert one.model.na == 1 and one.model.actuator("rubber_2_compliance").gainprm[0] == 1e5


def _rig_stiffness(rig, hz, amplitude=5e-5):
    """|K| [N/m] of the mount from a sine of the actuator at ``hz``: load phasor over the mount
    compression phasor (both through the same DAQ chain), over the last 3 s of a 6 s run."""
    fs = rig.fs
    t = np.arange(round(6.0 * fs)) / fs
    y = rig.run(amplitude * np.sin(2 * np.pi * hz * t), seed=0)
    keep = t >= 3.0  # the slowest branch (0.5 s) has relaxed its start transient to 0.25 %
    load = y.data[keep, y.names.index("damper_load")]
    compression = y.data[keep, y.names.index("compression")]
    return _phasor(t[keep], load, hz) / _phasor(t[keep], compression, hz)


def _documented(name, variant):
    """A documented parameter of ``variant`` from the shipped side-car."""
    d = json.loads(SIDE_CAR.read_text())
    value = d["variants"].get(variant, {}).get("parameters", {}).get(name)
    return d["parameters"][name]["value"] if value is None else value


def test_dynamic_stiffness_rises_with_frequency_as_documented(tmp_path):
    """Sine runs at 1, 5, 20 Hz, 0.05 mm (below the first Iwan slip): the thesis mount is the
    static 1 kN/mm with its viscous loss (mild: no chain), the thesis one adds the chain and
    stiffens within the documented 1.2-1.6 x of static over 5-30 Hz."""
    path = _side_car(tmp_path, chain=True, diagnostic=True)
    quiet = dict(valve_noise=0.0, load_noise=0.0, seed=0)
    freqs = (1.0, 5.0, 20.0)
    static = _documented("linear_stiffness", "thesis") + 4 * _documented("iwan_stiffness", "thesis")
    c = _documented("viscous_damping", "thesis")
    ks = [_documented(f"maxwell_stiffness_{i}", "thesis") for i in (1, 2, 3)]
    taus = json.loads(SIDE_CAR.read_text())["maxwell"][0]["relaxation_time"]
    measured = {}
    for variant in ("mild", "thesis"):
        rig = vrig.load_rig(path, variant=variant, **quiet)
        measured[variant] = np.array([abs(_rig_stiffness(rig, hz)) for hz in freqs])
    w = 2 * np.pi * np.array(freqs)
    base = static + 1j * w * c
    chain = sum(_branch_stiffness(k, tau, np.array(freqs)) for k, tau in zip(ks, taus, strict=True))
    np.testing.assert_allclose(measured["mild"], np.abs(base), rtol=0.03)
    np.testing.assert_allclose(measured["thesis"], np.abs(base + chain), rtol=0.03)
    ratio = measured["thesis"] / static
    assert np.all(np.diff(ratio) > 0.05)  # rises with frequency
    assert np.all((ratio[1:] >= 1.2) & (ratio[1:] <= 1.6))  # 5 and 20 Hz: documented range
    assert measured["mild"][-1] / measured["mild"][0] < 1.03  # no rate dependence without it


def test_a_chain_on_a_missing_joint_is_refused_once_it_has_a_branch(tmp_path):
    d = json.loads(SIDE_CAR.read_text())
    d["mjcf"] = str((SIDE_CAR.parent / d["mjcf"]).resolve())
    d["maxwell"][0]["joint"] = "nope"
    path = tmp_path / "elastomeric-damper.rig.json"
    path.write_text(json.dumps(d))
    assert vrig.load_rig(path, variant="mild").model.na == 0  # no branch: nothing to place
    with pytest.raises(vrig.RigModelError, match="no joint 'nope'"):
        vrig.load_rig(path, variant="thesis")
