"""Field twins (vrig.service): the rigs' specimens in service, driven by roads (issue 22)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.stats import kurtosis

import vrig
from vrig.errors import RigModelError
from vrig.service import field_record, field_scenarios, field_twin, road_drive, scenario
from vrig.service.scenario import read_scenarios

SCENARIOS = [
    ("shock-absorber", "rough-road"),
    ("elastomeric-damper", "slow-ditch"),
    ("motorcycle-rear", "rough-road"),
    ("radiator", "truck-front"),
    ("fuel-tank-2ch", "chassis-road"),
    ("fuel-tank-7ch", "chassis-road"),
]


@pytest.fixture(scope="module")
def rigs():
    return {}


def _rig(rigs, name):
    if name not in rigs:
        rigs[name] = vrig.load_rig(name)
    return rigs[name]


@pytest.mark.parametrize("rig_name, name", SCENARIOS)
def test_every_scenario_records_the_rigs_channels_reproducibly(rigs, rig_name, name):
    rig = _rig(rigs, rig_name)
    assert name in field_scenarios(rig)
    a = field_record(rig, name, 6.0, seed=3)
    b = field_record(rig, name, 6.0, seed=3)
    c = field_record(rig, name, 6.0, seed=4)
    assert a.fs == rig.fs and a.n_samples == round(6.0 * rig.fs)
    assert list(a.names) == [o.name for o in rig.outputs]
    assert list(a.units) == [o.unit for o in rig.outputs]
    assert np.all(np.isfinite(a.data))
    np.testing.assert_array_equal(a.data, b.data)  # bit for bit under a seed
    assert not np.array_equal(a.data, c.data)
    swing = np.ptp(np.asarray(a.data), axis=0)
    noise = np.array([o.transducer.noise_rms for o in rig.output_defs])
    assert np.all(swing > 20 * noise)  # the road moves every channel far beyond its noise


def test_the_slow_ditch_damper_load_is_not_gaussian(rigs):
    """The text's Table 6.3 target (§6.1.1): a slow ditch, large slow events on a rough track."""
    rig = _rig(rigs, "elastomeric-damper")
    x = np.asarray(field_record(rig, "slow-ditch", 30.0, seed=0).data[:, 0])
    x = x - x.mean()
    crest = np.abs(x).max() / x.std()
    # a Gaussian record of 7,500 samples: excess kurtosis ~0 (+-0.06), crest factor ~3.8
    assert kurtosis(x) > 1.0 or crest > 5.0, (kurtosis(x), crest)


def test_the_cab_mount_carries_the_cab_in_service(rigs):
    """Static equilibrium: at rest the load cell carries the cab corner and the crosshead above
    the mount (their masses read from the compiled model), which the rig's mount never does."""
    import mujoco

    rig = _rig(rigs, "elastomeric-damper")
    twin = field_twin(rig, "slow-ditch")
    m = twin.model
    above = sum(
        m.body_mass[mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, b)] for b in ("sprung", "crosshead")
    )
    still = vrig.TimeHistory(np.zeros((250, 1)), rig.fs, ["road"], ["m"])
    load = np.asarray(twin.run(still, seed=0).data[:, 0]).mean()
    assert load == pytest.approx(above * 9.81, rel=5e-3)
    assert np.asarray(rig.run(np.zeros((250, 1)), seed=0).data).mean() == pytest.approx(0, abs=50)


def test_a_rear_axle_meets_the_road_later():
    sc = scenario("fuel-tank-2ch", "chassis-road")
    rear = next(w for w in sc.wheels if w.name == "rear")
    road = road_drive(sc, 250.0, 10.0, speed_kmh=35.0, road_class="C", seed=1)
    front, back = np.asarray(road.channel("front")), np.asarray(road.channel("rear"))
    lag = rear.offset / (35.0 / 3.6) * 250  # 3.5 m at 35 km/h: 90 samples
    assert lag == pytest.approx(90.0)
    mid = slice(500, 2000)  # away from the fades
    shifted = slice(mid.start - 90, mid.stop - 90)
    gap = back[mid] - front[shifted]  # the same road; each column's own mean removed
    assert np.std(gap) < 1e-3 * np.std(front[mid])


def test_the_twin_keeps_the_rigs_specimen_parameters():
    """A parameter override of the rig reaches its field twin (the same specimen, not a copy)."""
    # mild: the linear dashpot, realised as the joint's damping (thesis: the valve law)
    stiff = vrig.load_rig("shock-absorber", variant="mild", damping=20000.0)
    twin = field_twin(stiff, "rough-road")
    assert twin.parameters["damping"] == 20000.0
    assert twin.model.dof_damping[twin.model.joint("damper").dofadr[0]] == 20000.0


def test_manoeuvre_pulses_reach_the_inertial_loads():
    sc = scenario("fuel-tank-7ch", "chassis-road")
    drive = road_drive(sc, 250.0, 20.0, speed_kmh=50.0, road_class="C", seed=0)
    lateral = np.asarray(drive.channel("lateral_front"))
    brake = np.asarray(drive.channel("longitudinal"))
    assert lateral.max() == pytest.approx(3.0, rel=1e-9)
    assert brake.min() == pytest.approx(-4.0, rel=1e-9)
    assert drive.units[drive.index("lateral_front")] == "m/s^2"


@pytest.mark.parametrize(
    "call, match",
    [
        (lambda: field_record("shock-absorber", "nope", 5.0), "no service scenario 'nope'"),
        (lambda: field_record("shock-absorber", "rough-road", 5.0, road_class="Z"), "class"),
        (lambda: field_record("shock-absorber", "rough-road", 5.0, speed_kmh=0), "speed_kmh"),
        (lambda: field_record("shock-absorber", "rough-road", 5.0, speed_kmh=-3), "speed_kmh"),
        (lambda: field_record("shock-absorber", "rough-road", 1.0), "seconds"),
        (lambda: field_record("shock-absorber", "rough-road", float("nan")), "seconds"),
    ],
)
def test_bad_input_is_one_clear_error(call, match):
    with pytest.raises(ValueError, match=match):
        call()


def test_a_rig_without_scenarios_has_none():
    assert field_scenarios("shaker") == []
    with pytest.raises(ValueError, match="its targets are pseudo-field"):
        vrig.desired.kinds.parse_target(vrig.load_rig("shaker"), "field")


@pytest.mark.parametrize(
    "raw, match",
    [
        ({"s": {"wheels": [{"drive": "nope"}]}}, "unknown drive"),
        ({"s": {"wheels": []}}, "at least one wheel or load"),
        ({"s": {"wheels": [{"drive": "d", "tyre": {"stiffness": -1}}]}}, "stiffness"),
        (
            {"s": {"wheels": [{"drive": "d", "tyre": None, "axle": {"mass": 1, "stiffness": 1}}]}},
            "axle needs a tyre",
        ),
        ({"s": {"wheels": [{"drive": "d"}, {"drive": "d"}]}}, "more than one"),
    ],
)
def test_bad_scenarios_are_refused_by_name(raw, match):
    with pytest.raises(RigModelError, match=match):
        read_scenarios(raw, ["d"])
