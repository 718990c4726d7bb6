"""A rig's own defaults live in its side-car (``"reconstruction"``: band, gain, gym id and
tolerance): parsed and checked there, exposed as ``rig.defaults``, read by
:func:`vrig.reconstruction.defaults.default_band`, the gymnasium registration and the env's tolerance.

Every expected value here is read from the side-car JSON files themselves (independently of
:mod:`vrig.rigs.spec`), never copied from the code."""

from __future__ import annotations

import json
from pathlib import Path

import gymnasium as gym
import pytest

import vrig
from vrig.envs import ENV_IDS, FALLBACK_TOLERANCE, DriveIterationEnv
from vrig.reconstruction.defaults import default_band
from vrig.rigs import ChannelSpec, FileRig, OutputSubset, RigDefaults
from vrig.rigs.spec import MethodDefaults, read_defaults

MODELS = Path(__file__).resolve().parents[1] / "models"
GENERIC_ID = "vrig/DriveIteration-v2"


def _side_cars() -> dict:
    """Every shipped side-car, parsed with plain ``json``: {rig name: dict}."""
    return {
        p.parent.name: json.loads(p.read_text())
        for p in sorted(MODELS.glob("*/*.rig.json"))
        if p.name == f"{p.parent.name}.rig.json"
    }


def _user_side_car(tmp_path, rig: str, edit) -> Path:
    """A copy of a shipped side-car (same MJCF), changed by ``edit(dict)``."""
    path = vrig.rig_path(rig)
    d = json.loads(path.read_text())
    d["mjcf"] = str((path.parent / d["mjcf"]).resolve())
    edit(d)
    out = tmp_path / f"{rig}-copy.rig.json"
    out.write_text(json.dumps(d))
    return out


# ---------------------------------------------------------------------------------------------
# parsed from the side-car, the same for every variant, severity and override
# ---------------------------------------------------------------------------------------------
@pytest.mark.parametrize("name", sorted(_side_cars()))
def test_rig_defaults_are_the_side_cars_values(name):
    block = _side_cars()[name].get("reconstruction", {})
    gym_block = block.get("gym", {})
    methods = {
        method: MethodDefaults(**{k: v for k, v in m.items()})
        for method, m in block.get("methods", {}).items()
    }
    want = RigDefaults(
        band=None if "band" not in block else tuple(block["band"]),
        gain=block.get("gain"),
        gym_id=gym_block.get("id"),
        gym_method=gym_block.get("method"),
        gym_gain=gym_block.get("gain"),
        tolerance=gym_block.get("tolerance"),
        id_rms=block.get("id_rms"),
        methods=methods,
    )
    rig = vrig.load_rig(name)
    assert rig.defaults == want
    assert rig.description.defaults == want
    assert read_defaults(vrig.rig_path(name)) == want  # the cheap reader of the registration


def test_the_shipped_side_cars_name_the_documented_defaults():
    cars = _side_cars()
    assert cars["shaker"]["reconstruction"]["band"] == [10.0, 60.0]
    assert cars["elastomeric-damper"]["reconstruction"]["gain"] == 0.5
    tolerances = {
        n: d["reconstruction"]["gym"]["tolerance"]
        for n, d in cars.items()
        if "gym" in d.get("reconstruction", {})
    }
    assert tolerances == {
        "shock-absorber": 6.1,  # issue 23: the run-to-run variation (1.7 before)
        "elastomeric-damper": 0.65,  # issue 23: the Maxwell chain in thesis
        "shaker": 0.5,
        "radiator": 5.6,  # issue 23: the controller noise
        "light-truck-front": 4.6,  # issue 23: measured on the digressive damper (4.1 on mild)
        "motorcycle-rear": 10.0,  # thesis: digressive + noise (7.6 without, 6.4 on mild)
        "pneumatic-trailer": 38.0,  # (6.8 on mild: frf converges slowly on the digressive shock)
        "fuel-tank-2ch": 8.5,  # issue 23: the two-observable thesis twin (22 before)
        "fuel-tank-7ch": 14.0,
    }


@pytest.mark.parametrize("name", ["elastomeric-damper", "shock-absorber", "radiator", "shaker"])
def test_variant_severity_and_overrides_do_not_change_the_defaults(name):
    base = vrig.load_rig(name)
    d = base.description
    param = sorted(k for k, p in d.parameters.items() if not isinstance(p.value, str))[0]
    others = [
        vrig.load_rig(name, variant="mild"),
        vrig.load_rig(name, fidelity="fast", seed=3),
        vrig.load_rig(name, **{param: d.parameters[param].value}),
    ]
    if d.severity is not None:
        others.append(vrig.load_rig(name, severity=0.5))
    for rig in others:
        assert rig.defaults == base.defaults


# ---------------------------------------------------------------------------------------------
# checked when the side-car is read: a clear error naming the file and the key
# ---------------------------------------------------------------------------------------------
@pytest.mark.parametrize(
    "block,key",
    [
        ({"description": "x", "band": [60.0, 10.0]}, "reconstruction.band"),  # low >= high
        ({"description": "x", "band": [10.0, 300.0]}, "reconstruction.band"),  # > fs/2 = 250 Hz
        ({"description": "x", "band": [10.0]}, "reconstruction.band"),
        ({"description": "x", "band": [-1.0, 10.0]}, r"reconstruction.band\[0\]"),
        ({"band": [10.0, 60.0]}, "description"),  # a band says why
        ({"gym": {"id": "Shaker", "tolerance": 1.0, "description": "x"}}, "reconstruction.gym.id"),
        ({"gym": {"id": "vrig/X-v2", "tolerance": 0.0, "description": "x"}}, "tolerance"),
        ({"gym": {"id": "vrig/X-v2", "description": "x"}}, "tolerance"),
        ({"gym": {"id": "vrig/X-v2", "tolerance": 1.0, "description": "x", "tol": 1}}, "tol"),
        (
            {"gym": {"id": "vrig/X-v2", "method": "ARX", "tolerance": 1.0, "description": "x"}},
            "reconstruction.gym.method",
        ),
        (
            {"gym": {"id": "vrig/X-v2", "gain": 2.5, "tolerance": 1.0, "description": "x"}},
            "reconstruction.gym.gain",
        ),
        (  # the env's default method cannot be one the side-car marks unsupported
            {
                "methods": {"narx": {"description": "x", "unsupported": "the text says so"}},
                "gym": {"id": "vrig/X-v2", "method": "narx", "tolerance": 1.0, "description": "x"},
            },
            "reconstruction.gym.method",
        ),
    ],
)
def test_a_bad_side_car_default_is_refused_naming_the_file(tmp_path, block, key):
    bad = _user_side_car(tmp_path, "shaker", lambda d: d.__setitem__("reconstruction", block))
    for read in (vrig.load_rig, read_defaults):
        with pytest.raises(vrig.RigParameterError, match=key) as info:
            read(bad)
        assert str(bad) in str(info.value)


def test_a_band_outside_nyquist_names_the_allowed_range(tmp_path):
    bad = _user_side_car(
        tmp_path, "shaker", lambda d: d["reconstruction"].__setitem__("band", [10.0, 300.0])
    )
    with pytest.raises(vrig.RigParameterError) as info:
        vrig.load_rig(bad)
    assert info.value.key == "reconstruction.band"
    assert "fs/2 = 250 Hz" in str(info.value)  # the shaker's fs is 500 Hz


# ---------------------------------------------------------------------------------------------
# default_band: the side-car's band, else the test band
# ---------------------------------------------------------------------------------------------
def test_default_band_of_the_shaker_is_its_side_cars_band():
    documented = tuple(json.loads(vrig.rig_path("shaker").read_text())["reconstruction"]["band"])
    rig = vrig.load_rig("shaker")
    assert default_band(rig) == documented
    assert default_band(rig) != tuple(rig.bandwidth)  # it differs from the 0-80 Hz test band


def test_default_band_follows_the_side_car_not_the_rig_name(tmp_path):
    """A user side-car named like a shipped rig gets its own side-car's band."""
    no_band = _user_side_car(tmp_path, "shaker", lambda d: d["reconstruction"].pop("band"))
    rig = vrig.load_rig(no_band)
    assert rig.name == "shaker" and default_band(rig) == tuple(rig.bandwidth)

    def narrow(d):
        d["reconstruction"] = {"description": "a narrower band", "band": [1.0, 5.0]}

    rig = vrig.load_rig(_user_side_car(tmp_path, "shock-absorber", narrow))
    assert default_band(rig) == (1.0, 5.0)


@pytest.mark.parametrize(
    "name", sorted(n for n, d in _side_cars().items() if "band" not in d.get("reconstruction", {}))
)
def test_default_band_without_a_side_car_band_is_the_test_band(name):
    rig = vrig.load_rig(name)
    assert default_band(rig) == tuple(_side_cars()[name].get("bandwidth_hz"))


def test_a_user_rig_without_a_side_car_falls_back_to_its_test_band(tmp_path):
    """Only a rig built from a side-car has defaults: a user's rig object named like a shipped
    rig gets its own test band and the global tolerance."""
    ch_in = ChannelSpec("amplifier_voltage", "V", 10.0, "direct")
    ch_out = ChannelSpec("shaft_acc", "m/s^2", 490.0, "accelerometer")
    rig = FileRig(tmp_path, [ch_in], [ch_out], 500.0, lambda p: p, bandwidth=(0.0, 80.0))
    rig.name = "shaker"
    assert not hasattr(rig, "defaults")
    assert default_band(rig) == (0.0, 80.0)
    env = DriveIterationEnv(rig)
    assert env.task.tolerance == FALLBACK_TOLERANCE == 2.0
    assert env.physics.band == (0.0, 80.0)


def test_an_output_subset_has_no_side_car_defaults():
    """The side-car's defaults were set on the whole rig's responses: a subset gets the global
    ones (the test band), as before the defaults moved into the side-cars."""
    rig = vrig.load_rig("shaker")
    sub = OutputSubset(rig, [rig.outputs[0].name])
    assert sub.defaults is None
    assert default_band(sub) == tuple(rig.bandwidth)


# ---------------------------------------------------------------------------------------------
# gymnasium: the registered ids and the env tolerances are the side-cars'
# ---------------------------------------------------------------------------------------------
def test_the_registered_ids_are_those_the_side_cars_declare():
    declared = {
        d["reconstruction"]["gym"]["id"]: {
            "rig": name,
            **({"method": d["reconstruction"]["gym"]["method"]}
               if "method" in d["reconstruction"]["gym"] else {}),
        }
        for name, d in _side_cars().items()
        if "gym" in d.get("reconstruction", {})
    }
    assert ENV_IDS == {GENERIC_ID: {}, **declared}
    registered = {k for k in gym.registry if k.startswith("vrig/")}
    assert registered == {GENERIC_ID, *declared}
    for env_id, kwargs in declared.items():
        spec = gym.spec(env_id)
        assert spec.kwargs == kwargs and spec.max_episode_steps == 10
    assert gym.spec(GENERIC_ID).kwargs == {}


def test_the_env_tolerance_is_the_side_cars(tmp_path):
    documented = json.loads(vrig.rig_path("shaker").read_text())["reconstruction"]["gym"]
    env = gym.make(documented["id"], fast=True)
    assert env.unwrapped.task.tolerance == documented["tolerance"]
    env.close()
    # the side-car's tolerance, also for a user side-car and under vrig/DriveIteration-v2
    user = _user_side_car(
        tmp_path,
        "shock-absorber",
        lambda d: d["reconstruction"]["gym"].__setitem__("tolerance", 7.5),
    )
    env = gym.make(GENERIC_ID, rig=vrig.load_rig(user), fast=True)
    assert env.unwrapped.task.tolerance == 7.5
    env.close()
    # a rig whose side-car names none (every shipped rig names one): the global fallback
    user = _user_side_car(
        tmp_path, "motorcycle-rear", lambda d: d["reconstruction"].pop("gym")
    )
    env = gym.make(GENERIC_ID, rig=vrig.load_rig(user), method="frf", fast=True)
    assert env.unwrapped.task.tolerance == FALLBACK_TOLERANCE
    env.close()
