"""Per-rig simulation context of the compiled MuJoCo callbacks (issue 14, deliverable 3).

The servo-hydraulic control callback and the air-spring passive/sensor callbacks look their
context up by the mjData they are called with: two rigs run interleaved (even one inside
another's run, and in two threads) give each one's single-rig result bit for bit, and a user's
own callback is chained for the user's model while a rig runs and is back after.
"""

from __future__ import annotations

import ctypes
import sys
import threading

import mujoco
import numpy as np
import pytest

import vrig
from identification import band_limited_noise
from vrig.rigs import gas_spring, hydraulics

GENERIC = ctypes.CFUNCTYPE(None, ctypes.c_void_p, ctypes.c_void_p)
USER_XML = """<mujoco><option gravity="0 0 0"/><worldbody><body><joint name="j" type="slide"/><geom size=".1" mass="1"/>
</body></worldbody><actuator><motor joint="j"/></actuator></mujoco>"""


@pytest.fixture(autouse=True)
def no_user_callbacks():
    """Every test starts and ends with MuJoCo's hooks empty (as a fresh process has them)."""
    for name in ("control", "passive", "sensor"):
        getattr(mujoco, f"set_mjcb_{name}")(None)
    yield
    for name in ("control", "passive", "sensor"):
        getattr(mujoco, f"set_mjcb_{name}")(None)


def drive(rig, seconds, seed, fraction=0.03):
    """A band-limited random drive in the rig's band at ``fraction`` of full scale."""
    cutoff = min(max(rig.bandwidth[1], 5.0), 0.4 * rig.fs) / (rig.fs / 2)
    d = band_limited_noise(int(seconds * rig.fs), len(rig.inputs), cutoff=cutoff, seed=seed)
    return d * fraction * np.array([c.full_scale for c in rig.inputs])


def alone(name, drives):
    """Each drive's response on a fresh rig run on its own (seeds 1, 2, ...)."""
    rig = vrig.load_rig(name, seed=0)
    return [rig.run(x, seed=k + 1, chunk_seconds=0.25).data for k, x in enumerate(drives)]


def during_each_chunk(rig, action):
    """Make ``rig`` call ``action()`` after each chunk of its runs (its context live)."""
    check = rig._check_stability

    def hooked(g0, raw):
        check(g0, raw)
        action()

    rig._check_stability = hooked


@pytest.fixture(scope="module")
def drives():
    a, b = vrig.load_rig("shock-absorber"), vrig.load_rig("pneumatic-trailer")
    return [drive(a, 1.0, s) for s in (1, 2)], [drive(b, 1.0, s) for s in (3, 4)]


def test_two_rigs_interleaved_give_each_ones_single_rig_result_bit_for_bit(drives):
    da, db = drives
    ref_a, ref_b = alone("shock-absorber", da), alone("pneumatic-trailer", db)
    a = vrig.load_rig("shock-absorber", seed=0)
    b = vrig.load_rig("pneumatic-trailer", seed=0)
    out_b = []
    # rig B runs whole inside rig A's run, between A's chunks (A's context stays live)
    during_each_chunk(a, lambda: out_b.append(b.run(db[len(out_b)], seed=len(out_b) + 1,
                                                    chunk_seconds=0.25).data)
                      if len(out_b) < len(db) else None)  # fmt: skip
    out_a = [a.run(x, seed=k + 1, chunk_seconds=0.25).data for k, x in enumerate(da)]
    assert len(out_b) == 2
    for got, ref in zip(out_a + out_b, ref_a + ref_b, strict=True):
        assert np.array_equal(got, ref)
    # and nothing of either rig is left registered once they are done
    assert not hydraulics.CONTROL.installed and not gas_spring.PASSIVE.installed
    assert mujoco.get_mjcb_control() is None and mujoco.get_mjcb_passive() is None


def test_a_users_c_callbacks_are_chained_for_their_model_during_a_run_and_intact_after():
    m = mujoco.MjModel.from_xml_string(USER_XML)
    d = mujoco.MjData(m)
    calls = {"control": 0, "passive": 0}
    mine = d._address

    def counter(kind):
        def cb(model_ptr, data_ptr):
            if data_ptr == mine:  # only ever called for the user's own model
                calls[kind] += 1
            else:
                calls[kind] = -(10**9)
        return GENERIC(cb)

    control, passive = counter("control"), counter("passive")
    # (loading a rig compiles and analyses its model with MuJoCo's hooks as they are: load
    # first, then install the user's callbacks)
    rig = vrig.load_rig("pneumatic-trailer", seed=0)  # hydraulics and a gas spring
    x = drive(rig, 0.5, 5)
    ref = alone("pneumatic-trailer", [x])[0]
    mujoco.set_mjcb_control(control)
    mujoco.set_mjcb_passive(passive)
    during_each_chunk(rig, lambda: mujoco.mj_step(m, d, 3))  # the user's model, rig live
    y = rig.run(x, seed=1, chunk_seconds=0.25).data
    assert np.array_equal(y, ref)  # the user's stepping does not disturb the rig
    # called only for the user's model (never for the rig's), 3 steps after each chunk
    assert calls["control"] >= 3 * 2 and calls["control"] % 3 == 0
    assert calls["passive"] == calls["control"]
    before = dict(calls)
    assert mujoco.get_mjcb_control() is control and mujoco.get_mjcb_passive() is passive
    mujoco.mj_step(m, d, 5)
    assert calls == {"control": before["control"] + 5, "passive": before["passive"] + 5}


def test_a_users_python_callback_is_restored_after_a_run_and_fires_for_their_model():
    m = mujoco.MjModel.from_xml_string(USER_XML)
    d = mujoco.MjData(m)
    calls = []

    def user(model, data):
        calls.append(data.time)
        data.ctrl[0] = 1.0  # the user's controller: a constant force

    rig = vrig.load_rig("shock-absorber", seed=0)
    x = drive(rig, 0.5, 6)
    ref = alone("shock-absorber", [x])[0]
    mujoco.set_mjcb_control(user)
    y = rig.run(x, seed=1, chunk_seconds=0.25).data
    assert np.array_equal(y, ref)
    assert calls == []  # never called for the rig's model
    assert mujoco.get_mjcb_control() is user
    mujoco.mj_step(m, d, 4)
    assert len(calls) == 4
    # the force reached the 1 kg body: v = F t / m after 4 steps of 2 ms
    assert d.qvel[0] == pytest.approx(4 * m.opt.timestep * 1.0 / 1.0, rel=1e-12)


def test_a_model_stepped_while_a_rig_is_live_without_user_callbacks_is_left_alone():
    m = mujoco.MjModel.from_xml_string(USER_XML)
    d = mujoco.MjData(m)
    rig = vrig.load_rig("shock-absorber", seed=0)
    x = drive(rig, 0.5, 7)
    ref = alone("shock-absorber", [x])[0]
    seen = []
    during_each_chunk(rig, lambda: (mujoco.mj_step(m, d, 2), seen.append(d.ctrl.copy())))
    assert np.array_equal(rig.run(x, seed=1, chunk_seconds=0.25).data, ref)
    # the servo callback did not write a force into the other model's controls
    assert len(seen) >= 2 and all(np.all(c == 0.0) for c in seen)
    assert d.qvel[0] == 0.0


def test_two_rigs_in_two_threads_give_their_single_rig_results_bit_for_bit(drives):
    # mujoco.rollout (MuJoCo 4.0, one MjData) holds the GIL while it steps: the two threads
    # take turns chunk by chunk (short chunks, a short switch interval: many turns), each
    # chunk seeing its own rig's context
    da, db = drives
    ref_a, ref_b = alone("shock-absorber", da), alone("pneumatic-trailer", db)
    rigs = {"a": vrig.load_rig("shock-absorber", seed=0),
            "b": vrig.load_rig("pneumatic-trailer", seed=0)}  # fmt: skip
    out, errors = {}, []

    def work(key, xs):
        try:
            out[key] = [rigs[key].run(x, seed=k + 1, chunk_seconds=0.02).data
                        for k, x in enumerate(xs)]  # fmt: skip
        except Exception as exc:  # pragma: no cover - reported below
            errors.append(exc)

    threads = [threading.Thread(target=work, args=("a", da)),
               threading.Thread(target=work, args=("b", db))]  # fmt: skip
    interval = sys.getswitchinterval()
    sys.setswitchinterval(1e-5)
    try:
        for t in threads:
            t.start()
        for t in threads:
            t.join()
    finally:
        sys.setswitchinterval(interval)
    assert not errors
    for got, ref in zip(out["a"] + out["b"], ref_a + ref_b, strict=True):
        assert np.array_equal(got, ref)
    assert mujoco.get_mjcb_control() is None


def test_the_context_layout_is_named():
    # the compiled callbacks address parameters by name: every HydraulicActuator field that
    # the law uses has its own record field, and a record carries the documented values
    act = hydraulics.HydraulicActuator()
    r = act.record(1e-4, (1, 2, 3, 4, 5))
    assert r["area"] == act.area and r["supply_pressure"] == act.supply_pressure
    assert r["valve_omega"] == pytest.approx(2 * np.pi * act.valve_frequency)
    assert r["oil_gain"] == pytest.approx(4 * act.bulk_modulus / act.oil_volume)
    assert r["period"] == 2 and r["controller_dt"] == pytest.approx(2e-4)  # 5 kHz at 10 kHz
    assert (r["i_cmd"], r["i_noise"], r["i_force"], r["qpos"], r["dof"]) == (1, 2, 3, 4, 5)
    s = gas_spring.AirSpring("s", "t", 0.3, 3e5, 5e-3, 0.02, -0.05)
    g = s.record(2, 7)
    assert (g["tendon"], g["sensor"]) == (2, 7)
    assert g["p0"] == 3e5 + s.ambient_pressure and g["area_slope"] == -0.05


def test_a_rig_loads_with_a_users_callbacks_installed_and_leaves_them_uncalled_and_intact():
    """MuJoCo's compiler runs a model once with whatever callbacks are installed: a user's Python
    ``mjcb_control`` made ``load_rig`` fail ("Python exception raised") and a C callback ran on the
    rig's model. Loading suspends them; they are in place afterwards and fire for the user."""
    m = mujoco.MjModel.from_xml_string(USER_XML)
    d = mujoco.MjData(m)
    seen = {"python": 0, "c_foreign": 0, "c_mine": 0}
    mine = d._address

    def user(model, data):
        seen["python"] += 1

    def c_passive(model_ptr, data_ptr):
        seen["c_mine" if data_ptr == mine else "c_foreign"] += 1

    passive = GENERIC(c_passive)
    mujoco.set_mjcb_control(user)
    mujoco.set_mjcb_passive(passive)
    rig = vrig.load_rig("pneumatic-trailer", seed=0)  # hydraulics and a gas spring
    assert seen == {"python": 0, "c_foreign": 0, "c_mine": 0}
    assert mujoco.get_mjcb_control() is user and mujoco.get_mjcb_passive() is passive
    x = drive(rig, 0.25, 7)
    mujoco.set_mjcb_control(None)
    mujoco.set_mjcb_passive(None)
    ref = alone("pneumatic-trailer", [x])[0]  # the rig loaded and run without user callbacks
    mujoco.set_mjcb_control(user)
    mujoco.set_mjcb_passive(passive)
    assert np.array_equal(rig.run(x, seed=1, chunk_seconds=0.25).data, ref)
    assert seen["c_foreign"] == 0 and seen["python"] == 0
    mujoco.mj_step(m, d, 3)
    assert seen == {"python": 3, "c_foreign": 0, "c_mine": 3}
