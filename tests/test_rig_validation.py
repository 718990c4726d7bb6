"""Validated rig parameters (issue #11, item 7): the side-car's published JSON Schema, values and
overrides outside their range, and a fuzz test over mutated side-cars and overrides.

A bad value raises :class:`vrig.RigParameterError` (a :class:`vrig.RigModelError`, itself a
``ValueError``) naming the key and the allowed range; nothing else escapes ``load_rig``, and a
rig that loads runs a short drive to a finite response or stops with a documented rig error.
"""

from __future__ import annotations

import copy
import json
import math
import tomllib
from fnmatch import fnmatch
from pathlib import Path

import jsonschema
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import vrig
from vrig.errors import RigLimitError, RigModelError, RigParameterError, SimulationInstabilityError
from vrig.rigs import rig_path
from vrig.rigs.spec import read_description, schema_path

ROOT = Path(__file__).resolve().parents[1]
SIDE_CARS = sorted((ROOT / "models").glob("*/*.rig.json"))


def _shaker() -> dict:
    raw = json.loads(rig_path("shaker").read_text())
    raw["mjcf"] = str(rig_path("shaker").parent / raw["mjcf"])  # loadable from any folder
    return raw


def _write(tmp_path, raw, name="mutant.rig.json") -> Path:
    path = tmp_path / name
    path.write_text(json.dumps(raw))  # NaN / Infinity are written as JSON's NaN / Infinity
    return path


# ---------------------------------------------------------------------------------------------
# the published schema
# ---------------------------------------------------------------------------------------------
def test_the_schema_is_published_in_the_package_and_every_shipped_side_car_obeys_it():
    path = schema_path()
    assert path == ROOT / "models" / "rig.schema.json"
    pyproject = tomllib.loads((ROOT / "pyproject.toml").read_text())
    patterns = pyproject["tool"]["setuptools"]["package-data"]["vrig.models"]
    assert any(fnmatch("rig.schema.json", p) for p in patterns)  # shipped in the wheel
    assert any(d.startswith("jsonschema") for d in pyproject["project"]["dependencies"])
    schema = json.loads(path.read_text())
    jsonschema.Draft202012Validator.check_schema(schema)
    validator = jsonschema.Draft202012Validator(schema)
    assert len(SIDE_CARS) == len(vrig.list_rigs()) >= 7  # every shipped rig has a side-car
    for side_car in SIDE_CARS:
        errors = [e.message for e in validator.iter_errors(json.loads(side_car.read_text()))]
        assert errors == [], side_car.name


def test_every_numeric_parameter_of_a_shipped_rig_declares_its_range():
    for side_car in SIDE_CARS:
        for name, p in json.loads(side_car.read_text())["parameters"].items():
            if isinstance(p["value"], str):
                assert "enum" in p, (side_car.name, name)
                continue
            if name != "quadratic_stiffness":  # k2 may have either sign (the asymmetry)
                assert {"minimum", "exclusiveMinimum"} & set(p), (side_car.name, name)
            # issue 25: an upper bound too (damping=1e300 was accepted)
            assert {"maximum", "exclusiveMaximum"} & set(p), (side_car.name, name)


@pytest.mark.parametrize(
    ("rig", "name", "bound"),
    [
        ("shock-absorber", "damping", 100 * 12000.0),  # 100 x the documented value
        ("shock-absorber", "load_noise", 10000.0),  # the load cell's full scale [N]
        ("elastomeric-damper", "load_noise", 25000.0),
        ("light-truck-front", "damping", 100 * 6500.0),
    ],
)
def test_an_absurd_override_is_refused_with_the_documented_range(rig, name, bound):
    """The upper bounds follow models/README.md's rule (a noise: its channel's full scale;
    otherwise 100 x the documented value): the bound itself is accepted, 1e300 is refused."""
    p = read_description(rig_path(rig)).parameters[name]
    assert p.check(bound) == bound
    with pytest.raises(RigParameterError, match=name) as info:
        p.check(1e300)
    assert f"{bound:g}" in str(info.value)


# ---------------------------------------------------------------------------------------------
# side-car values
# ---------------------------------------------------------------------------------------------
def _set(*keys_and_value):
    *keys, value = keys_and_value

    def mutate(raw):
        node = raw
        for k in keys[:-1]:
            node = node[k]
        node[keys[-1]] = value

    return mutate


SIDE_CAR_CASES = {
    # case: (mutation, the key the message must name, the allowed range it must state)
    "misspelt transducer key": (
        _set("outputs", 0, "transducer", "noise_rmss", 0.5),
        "outputs[0].transducer",
        "'noise_rmss' was unexpected",
    ),
    "misspelt drive key": (
        _set("inputs", 0, "noise_rmss", 0.5),
        "inputs[0]",
        "allowed keys: actuator, control_noise_corner_hz, control_noise_rms, description, full_scale",
    ),
    "NaN full scale": (
        _set("outputs", 0, "full_scale", math.nan),
        "outputs[0].full_scale",
        "finite",
    ),
    "negative full scale": (
        _set("inputs", 0, "full_scale", -10.0),
        "inputs[0].full_scale",
        "a finite number > 0",
    ),
    "zero output range": (
        _set("outputs", 0, "full_scale", 0),
        "outputs[0].full_scale",
        "a finite number > 0",
    ),
    "reversed band": (
        _set("bandwidth_hz", [80.0, 10.0]),
        "bandwidth_hz",
        "0 <= low < high <= fs/2 = 250 Hz",
    ),
    "band beyond Nyquist": (
        _set("bandwidth_hz", [0.0, 400.0]),
        "bandwidth_hz",
        "high <= fs/2 = 250 Hz",
    ),
    "negative transducer noise": (
        _set("outputs", 0, "transducer", "noise_rms", -0.02),
        "outputs[0].transducer.noise_rms",
        "a finite number >= 0",
    ),
    "infinite drive noise": (
        _set("inputs", 0, "noise_rms", math.inf),
        "inputs[0].noise_rms",
        "finite",
    ),
    "parameter default outside its range": (
        _set("parameters", "moving_mass", "value", -0.25),
        "moving_mass",
        "a finite number in (0, 25] [kg]",  # 25: 100 x the documented 0.25 kg
    ),
    "huge settle time": (
        _set("settle_time", 1e300),
        "settle_time",
        "a finite number in [0, 60]",
    ),
    "anti-alias cutoff at Nyquist": (
        _set("anti_alias", "cutoff", 0.5),
        "anti_alias.cutoff",
        "a finite number in [0.05, 0.5)",
    ),
    "anti-alias cutoff far below Nyquist (a singular filter; found by the fuzz test)": (
        _set("anti_alias", "cutoff", 4e-10),
        "anti_alias.cutoff",
        "a finite number in [0.05, 0.5)",
    ),
}


@pytest.mark.parametrize("case", list(SIDE_CAR_CASES))
def test_a_bad_side_car_value_is_refused_naming_the_key_and_the_range(tmp_path, case):
    mutate, key, allowed = SIDE_CAR_CASES[case]
    raw = _shaker()
    mutate(raw)
    path = _write(tmp_path, raw)
    with pytest.raises(RigParameterError) as err:
        vrig.load_rig(path)
    msg = str(err.value)
    assert str(path) in msg and key in msg and allowed in msg
    assert key in err.value.key


OVERRIDE_CASES = [  # the upper bounds: models/README.md's rule (issue 25)
    ("shaker", "moving_mass", math.nan, "a finite number in (0, 25] [kg]"),
    ("shaker", "moving_mass", -0.25, "a finite number in (0, 25] [kg]"),
    ("shaker", "amplifier_noise", -0.001, "a finite number in [0, 10] [V rms]"),
    ("shaker", "suspension_stiffness", "stiff", "a finite number in [0, 1e+06] [N/m]"),
    ("shaker", "stroke", True, "a finite number in (0, 1.27] [m]"),
    ("shaker", "accelerometer_highpass", 400.0, "a finite number in [0, 250)"),
    ("shock-absorber", "valve_noise", 1.5, "a finite number in [0, 1]"),
    ("elastomeric-damper", "load_noise", math.inf, "a finite number in [0, 25000] [N rms]"),
    ("elastomeric-damper", "load_noise", 1e300, "a finite number in [0, 25000] [N rms]"),
    ("shock-absorber", "damping", 1e300, "a finite number in [0, 1.2e+06] [N s/m]"),
]


@pytest.mark.parametrize(("rig", "name", "value", "allowed"), OVERRIDE_CASES)
def test_a_bad_override_is_refused_naming_the_parameter_and_its_range(rig, name, value, allowed):
    with pytest.raises(RigParameterError) as err:
        vrig.load_rig(rig, **{name: value})
    assert name in str(err.value) and allowed in str(err.value)


def test_a_string_parameter_takes_only_its_listed_values_and_valid_overrides_still_apply():
    with pytest.raises(RigParameterError) as err:
        vrig.load_rig("shock-absorber", mounting="glued")  # today: a TypeError from MuJoCo
    assert "mounting" in str(err.value) and "one of 'rubber-bush', 'threaded'" in str(err.value)
    threaded = vrig.load_rig("shock-absorber", mounting="threaded")
    assert threaded.parameters["mounting"] == "threaded"
    assert threaded.model.eq_active0[0] == 1  # the threaded lock is on
    assert vrig.load_rig("shaker", moving_mass=0.5).parameters["moving_mass"] == 0.5


def test_seeds_must_be_non_negative_integers():
    with pytest.raises(ValueError, match="seed must be a non-negative integer, got -1"):
        vrig.load_rig("shaker", seed=-1)


# ---------------------------------------------------------------------------------------------
# fuzz: mutated side-cars and overrides
# ---------------------------------------------------------------------------------------------
_WEIRD = st.sampled_from(
    [math.nan, math.inf, -math.inf, -1.0, 0, -0.0, 1e300, -1e300, 10**30, 1e-300, "x", None,
     [], {}, True, [1.0, 2.0]]
)  # fmt: skip


def _paths(node, path=()):
    yield path
    if isinstance(node, dict):
        for k, v in node.items():
            yield from _paths(v, (*path, k))
    elif isinstance(node, list):
        for i, v in enumerate(node):
            yield from _paths(v, (*path, i))


def _mutate(raw: dict, data) -> None:
    """One random mutation: drop, add or misspell a key, or replace a value by a weird one."""
    path = data.draw(st.sampled_from([p for p in _paths(raw) if p]), label="path")
    parent = raw
    for k in path[:-1]:
        parent = parent[k]
    key = path[-1]
    op = data.draw(st.sampled_from(["drop", "add", "misspell", "replace", "scale"]), label="op")
    if op == "drop":
        del parent[key]
    elif op == "add" and isinstance(parent, dict):
        parent[data.draw(st.sampled_from(["noise_rmss", "fullscale", "gain", "bogus"]))] = 1.0
    elif op == "misspell" and isinstance(parent, dict):
        parent[f"{key}s"] = parent.pop(key)
    elif (
        op == "scale"
        and isinstance(parent[key], (int, float))
        and not isinstance(parent[key], bool)
    ):
        parent[key] = parent[key] * data.draw(st.sampled_from([-1.0, 0.0, 1e-9, 1e9, 1e300]))
    else:
        parent[key] = data.draw(_WEIRD, label="value")


def _run_short(rig) -> None:
    """A 0.2 s drive (at least 16 samples) at 5 % of full scale: a documented rig error or a
    finite response."""
    n = max(16, int(0.2 * rig.fs))
    t = np.arange(n) / rig.fs
    drive = np.column_stack(
        [0.05 * c.full_scale * np.sin(2 * np.pi * 0.05 * rig.fs * t) for c in rig.inputs]
    )
    try:
        out = rig.run(drive, seed=0)
    except (RigLimitError, SimulationInstabilityError):
        return
    assert np.all(np.isfinite(out.data))


@settings(
    max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(data=st.data(), n_mutations=st.integers(1, 2))
def test_fuzz_mutated_side_cars_load_cleanly_or_raise_a_rig_model_error(
    tmp_path, data, n_mutations
):
    raw = _shaker()
    for _ in range(n_mutations):
        if raw:
            _mutate(raw, data)
    path = _write(tmp_path, raw)
    try:
        rig = vrig.load_rig(path)
    except RigModelError as exc:  # RigParameterError included
        assert str(exc)
        return
    _run_short(rig)


_PARAMETERS = {
    rig: json.loads(rig_path(rig).read_text())["parameters"]
    for rig in ("shaker", "elastomeric-damper")
}


@settings(max_examples=50, deadline=None)
@given(
    rig=st.sampled_from(sorted(_PARAMETERS)),
    data=st.data(),
    value=st.one_of(
        st.floats(allow_nan=True, allow_infinity=True),
        st.integers(-(10**6), 10**6),
        st.sampled_from([None, True, "x", [1.0]]),
        st.sampled_from([1e-9, 0.5, 2.0, 1e6]),  # multiples of the default
    ),
)
def test_fuzz_overrides_load_cleanly_or_raise_a_rig_parameter_error(rig, data, value):
    name = data.draw(st.sampled_from([*sorted(_PARAMETERS[rig]), "moving_mas"]), label="name")
    default = _PARAMETERS[rig].get(name, {}).get("value")
    if isinstance(value, float) and value in (1e-9, 0.5, 2.0, 1e6) and isinstance(default, float):
        value = copy.copy(default) * value
    try:
        loaded = vrig.load_rig(rig, **{name: value})
    except RigParameterError as exc:
        assert name in str(exc)
        return
    except RigModelError as exc:  # e.g. MuJoCo refuses to compile, or the rig does not settle
        assert str(exc)
        return
    _run_short(loaded)
