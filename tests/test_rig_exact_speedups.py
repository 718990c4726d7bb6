"""Exact speedups of a rig run (issue 26, deliverable 4): what they skip changes nothing.

Truth used: MuJoCo's documented contact rule (two geoms collide only if the ``contype`` of one
and the ``conaffinity`` of the other share a bit, or an explicit ``<pair>`` names them), so a
model without such a pair forms no contact and its runs with collision detection switched off
equal the runs with it, bit for bit; a filter design depends on its arguments only, so a kept
design equals a fresh one, and no caller can change the kept one.
"""

from __future__ import annotations

import mujoco
import numpy as np
import pytest
from scipy import signal

import vrig
import vrig.rigs.mujoco_rig as mujoco_rig
from identification import band_limited_noise
from vrig.reconstruction.scores import pseudo_damages, scores
from vrig.rigs.daq import AntiAliasFilter, transducer_response
from vrig.rigs.mujoco_rig import collidable
from vrig.signals import flicker_sos

_CONTACT = int(mujoco.mjtDisableBit.mjDSBL_CONTACT)


def _model(geoms: str, extra: str = "") -> mujoco.MjModel:
    return mujoco.MjModel.from_xml_string(f"<mujoco><worldbody>{geoms}</worldbody>{extra}</mujoco>")


_FLOOR = '<geom name="floor" type="plane" size="1 1 0.1" contype="{}" conaffinity="{}"/>'
_BALL = (
    '<body pos="0 0 1"><freejoint/>'
    '<geom name="ball" size="0.1" contype="{}" conaffinity="{}"/></body>'
)


@pytest.mark.parametrize(
    ("floor", "ball", "expected"),
    [
        ((0, 0), (0, 0), False),  # every vrig rig's case
        ((1, 1), (1, 1), True),  # MuJoCo's defaults
        ((1, 0), (0, 1), True),  # the floor's type meets the ball's affinity
        ((0, 1), (1, 0), True),  # ... or the other way round
        ((2, 0), (0, 1), False),  # no shared bit either way
        ((1, 1), (0, 0), False),  # one collidable geom alone: nothing to meet
    ],
)
def test_the_contact_rule_is_mujocos_bitmask_over_pairs_of_geoms(floor, ball, expected):
    model = _model(_FLOOR.format(*floor) + _BALL.format(*ball))
    assert collidable(model) is expected
    # the rule agrees with MuJoCo itself: a ball dropped on the floor touches it or falls through
    data = mujoco.MjData(model)
    data.qpos[2] = 0.05  # the ball's centre below its radius: in contact if contact exists
    mujoco.mj_forward(model, data)
    assert (data.ncon > 0) is expected


def test_an_explicit_contact_pair_counts_whatever_the_bitmasks():
    geoms = _FLOOR.format(0, 0) + _BALL.format(0, 0)
    pair = '<contact><pair geom1="floor" geom2="ball"/></contact>'
    assert collidable(_model(geoms, pair))
    assert not collidable(_model(geoms))


def _drive(rig, seconds=1.0, seed=1):
    cutoff = min(max(rig.bandwidth[1], 5.0), 0.4 * rig.fs) / (rig.fs / 2)
    x = band_limited_noise(int(seconds * rig.fs), len(rig.inputs), cutoff=cutoff, seed=seed)
    return 0.005 * x * np.array([c.full_scale for c in rig.inputs])


@pytest.mark.parametrize("name", ["shock-absorber", "elastomeric-damper", "pneumatic-trailer"])
def test_a_rig_without_contacts_runs_bit_for_bit_as_with_collision_detection(name, monkeypatch):
    fast = vrig.load_rig(name, seed=0, fidelity="fast")
    assert fast.model.opt.disableflags & _CONTACT  # switched off at load: nothing collides
    with monkeypatch.context() as m:  # the same rig with collision detection on throughout
        m.setattr(mujoco_rig, "collidable", lambda model: True)
        searched = vrig.load_rig(name, seed=0, fidelity="fast")
    assert not searched.model.opt.disableflags & _CONTACT
    x = _drive(fast)
    assert np.array_equal(fast.run(x, seed=3).data, searched.run(x, seed=3).data)
    xs, seeds = [x, 0.5 * x, _drive(fast, seed=2)], [4, 5, 6]
    got = fast.run_batch(xs, seeds=seeds, threads=2)  # the clones of the data too
    ref = searched.run_batch(xs, seeds=seeds, threads=2)
    assert all(np.array_equal(g.data, r.data) for g, r in zip(got, ref, strict=True))


def test_a_rig_whose_geoms_can_meet_keeps_collision_detection():
    def collide(spec):  # two geoms of the damper that may touch by their bitmasks
        for geom in spec.worldbody.find_all(mujoco.mjtObj.mjOBJ_GEOM)[-2:]:
            geom.contype, geom.conaffinity = 1, 1

    rig = vrig.load_rig("shock-absorber", fidelity="fast")
    edited = vrig.rigs.MujocoRig(rig.description, fidelity="fast", spec_edit=collide)
    assert collidable(edited.model)
    assert not edited.model.opt.disableflags & _CONTACT


def test_the_flicker_design_is_kept_and_every_caller_gets_its_own_copy():
    sos, rms = flicker_sos(30.0, 3500.0)
    again, rms_again = flicker_sos(30.0, 3500.0)
    assert np.array_equal(sos, again) and rms == rms_again and sos is not again
    sos[:] = 0.0  # a caller that scribbles on its sections changes nobody else's
    third, _ = flicker_sos(30.0, 3500.0)
    assert np.array_equal(third, again)
    _, h = signal.sosfreqz(third, worN=[0.0], fs=3500.0)  # still the design: unit gain at DC
    assert abs(h[0]) == pytest.approx(1.0, rel=1e-9)
    with pytest.raises(ValueError, match="corner_hz"):
        flicker_sos(3000.0, 3500.0)


def test_the_daq_filter_designs_are_kept_and_copied():
    aa = AntiAliasFilter(order=6, cutoff=0.4)
    a, b = aa.sos(1000.0, 5000.0), aa.sos(1000.0, 5000.0)
    assert a is not b and np.array_equal(a, b)
    assert np.array_equal(a, signal.butter(6, 400.0, fs=5000.0, output="sos"))
    a[:] = 0.0
    assert np.array_equal(aa.sos(1000.0, 5000.0), b)
    t = vrig.rigs.daq.Transducer(kind="accelerometer", highpass_hz=0.5)
    _, hp = signal.sosfreqz(
        signal.butter(1, 0.5, btype="highpass", fs=5000.0, output="sos"), worN=[0.5], fs=5000.0
    )
    assert transducer_response(t, [0.5], 5000.0)[0] == hp[0]  # -3 dB at the corner


def test_scores_with_the_desired_damage_known_are_the_same_bit_for_bit():
    rng = np.random.default_rng(0)
    desired = vrig.TimeHistory(rng.standard_normal((2000, 3)), 500.0)
    response = vrig.TimeHistory(desired.data + 0.1 * rng.standard_normal((2000, 3)), 500.0)
    plain = scores(desired, response)
    kept = scores(desired, response, desired_damage=pseudo_damages(desired))
    assert all(np.array_equal(p, k) for p, k in zip(plain, kept, strict=True))
    with pytest.raises(ValueError, match="one value per channel"):
        scores(desired, response, desired_damage=np.ones(2))
