"""Every shipped rig has one gymnasium id (``vrig/<Name>-v2``, from its side-car), and the env of
an id takes the rig's own defaults from the side-car: the method (``gym.method``), its options and
identification level (``methods.METHOD``) and the band, unless the caller passes them.

Every expected value is read from the side-car JSON files themselves (plain ``json``, not
:mod:`vrig.rigs.spec`), never copied from the code's output."""

from __future__ import annotations

import json
import re
import warnings
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import vrig
from vrig.envs import ENV_IDS

MODELS = Path(__file__).resolve().parents[1] / "models"
GENERIC_ID = "vrig/DriveIteration-v2"
SLOW_RIGS = {"fuel-tank-7ch"}  # check_env > 30 s (7 drives x 7 responses)

# the side-car's method fields -> the method's keyword (``vrig reconstruct`` builds them so:
# error-signal's ``order`` is its linear ARX order, vrig.cli._method)
OPTION_NAMES = {
    "arx": {"order": "order"},
    "narx": {"order": "order", "degree": "degree", "focus": "focus"},
    "error-signal": {"order": "linear_order", "degree": "degree", "focus": "focus"},
    "split": {"split_hz": "split_hz"},
    "frf": {},
}


def _side_cars() -> dict:
    """Every shipped side-car, parsed with plain ``json``: {rig name: dict}."""
    return {
        p.parent.name: json.loads(p.read_text())
        for p in sorted(MODELS.glob("*/*.rig.json"))
        if p.name == f"{p.parent.name}.rig.json"
    }


CARS = _side_cars()


def _gym(name: str) -> dict:
    return CARS[name]["reconstruction"]["gym"]


def _param(name: str):
    return pytest.param(name, marks=[pytest.mark.slow] if name in SLOW_RIGS else [])


def _unsupported() -> list:
    return [
        (name, method, m["unsupported"])
        for name, d in CARS.items()
        for method, m in d.get("reconstruction", {}).get("methods", {}).items()
        if "unsupported" in m
    ]


# ---------------------------------------------------------------------------------------------
# one id per rig, -v2, from the side-car
# ---------------------------------------------------------------------------------------------
def test_every_shipped_rig_has_exactly_one_v2_id():
    assert sorted(CARS) == sorted(vrig.list_rigs())
    ids = {name: _gym(name)["id"] for name in CARS}  # KeyError: a rig without an id
    assert len(set(ids.values())) == len(ids)
    for name, env_id in ids.items():
        assert re.fullmatch(r"vrig/[A-Z][A-Za-z0-9]*-v2", env_id), env_id
        spec = gym.spec(env_id)
        assert spec.kwargs["rig"] == name and spec.max_episode_steps == 10
        assert spec.kwargs.get("method") == _gym(name).get("method")
    registered = {k for k in gym.registry if k.startswith("vrig/")}
    assert registered == {GENERIC_ID, *ids.values()}
    assert set(ENV_IDS) == registered


@pytest.mark.parametrize("old_version", ["-v0", "-v1"])
@pytest.mark.parametrize("env_id", sorted(ENV_IDS))
def test_the_old_ids_tell_the_user_to_use_v2(env_id, old_version):
    old = env_id.replace("-v2", old_version)
    with pytest.raises(gym.error.DeprecatedEnv, match=re.escape(f"use `{env_id}`")):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", DeprecationWarning)
            gym.make(old)


@pytest.mark.parametrize("name", [_param(n) for n in sorted(CARS)])
def test_check_env_passes_for_every_rig_id(name):
    env = gym.make(_gym(name)["id"], fast=True, seconds=2.0)
    with warnings.catch_warnings():
        # the gains are not a [-1, 1] box on purpose (gain 0.8 means 0.8): that advice only
        warnings.filterwarnings("ignore", message=".*symmetric and normalized.*")
        check_env(env.unwrapped)
    env.close()


def test_check_env_passes_for_the_generic_id():
    env = gym.make(GENERIC_ID, rig="shaker", fast=True, seconds=2.0)
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message=".*symmetric and normalized.*")
        check_env(env.unwrapped)
    env.close()


# ---------------------------------------------------------------------------------------------
# the rig's own defaults: method, options, identification level, band, tolerance
# ---------------------------------------------------------------------------------------------
def _expected_settings(name: str, method: str) -> tuple[dict, tuple | None]:
    """The method options and identification RMS [drive units] the side-car asks for (the
    built-in 5 % of full scale where it names none)."""
    block = CARS[name].get("reconstruction", {})
    m = block.get("methods", {}).get(method, {})
    options = {OPTION_NAMES[method][k]: v for k, v in m.items() if k in OPTION_NAMES[method]}
    level = m.get("id_rms", block.get("id_rms", 0.05))  # the documented built-in: 5 %
    return options, tuple(level * c["full_scale"] for c in CARS[name]["inputs"])


@pytest.mark.parametrize("name", sorted(CARS))
def test_the_env_of_an_id_takes_the_side_cars_method_options_band_and_tolerance(name):
    env = gym.make(_gym(name)["id"], fast=True).unwrapped
    s = env.physics.settings
    method = _gym(name).get("method", "arx")
    assert s.method == method
    options, id_rms = _expected_settings(name, method)
    for key, value in options.items():
        assert s.method_options[key] == value, key
    np.testing.assert_allclose(s.id_rms, id_rms, rtol=1e-12)
    block = CARS[name]["reconstruction"]
    band = block.get("band", CARS[name].get("bandwidth_hz", [0.0, CARS[name]["fs"] / 4]))
    assert env.physics.band == tuple(band)
    assert env.task.tolerance == _gym(name)["tolerance"]
    env.close()


def test_split_on_a_rig_without_a_split_frequency_uses_the_commands_default():
    # the shock absorber's side-car names no split: vrig reconstruct's default, the geometric
    # mean of the band, or a quarter of its upper edge when the band starts at 0 Hz
    assert "split" not in CARS["shock-absorber"]["reconstruction"].get("methods", {})
    env = gym.make("vrig/ShockAbsorber-v2", method="split", fast=True).unwrapped
    lo, hi = env.physics.band
    want = np.sqrt(lo * hi) if lo > 0 else hi / 4
    assert env.physics.settings.method_options["split_hz"] == pytest.approx(want)
    env.close()


def test_what_the_caller_passes_wins_over_the_side_car():
    m = CARS["motorcycle-rear"]["reconstruction"]["methods"]["narx"]
    assert m["order"] != 3 and m["focus"] == "simulation"
    env = gym.make(
        _gym("motorcycle-rear")["id"],
        fast=True,
        method="narx",
        method_options={"order": 3},
        id_rms=0.002,
        bandwidth=(1.0, 20.0),
    ).unwrapped
    s = env.physics.settings
    assert s.method == "narx"
    assert s.method_options["order"] == 3  # given
    assert s.method_options["focus"] == "simulation"  # not given: the side-car's
    assert s.id_rms == 0.002 and env.physics.band == (1.0, 20.0)
    env.close()


IT00_BEYOND_FULL_SCALE = {("light-truck-front", "narx"), ("light-truck-front", "error-signal")}


def _one_line_warning(record, reason: str) -> None:
    """Exactly one ``UserWarning`` among ``record``, on one line, quoting ``reason``."""
    mine = [w for w in record if issubclass(w.category, UserWarning) and reason in str(w.message)]
    assert len(mine) == 1, [str(w.message) for w in record]
    text = str(mine[0].message)
    assert "\n" not in text and f'"{reason}"' in text and "running it anyway" in text


@pytest.mark.parametrize("name,method,reason", _unsupported())
def test_an_unsupported_method_warns_quoting_the_side_car_and_the_env_steps(name, method, reason):
    # a benchmark lets a user see a method do badly: the side-car's text is a one-line warning,
    # the env is made with the method and its side-car options, and an episode is played
    with warnings.catch_warnings(record=True) as record:
        warnings.simplefilter("always")
        env = gym.make(_gym(name)["id"], method=method, fast=True, seconds=2.0)
    _one_line_warning(record, reason)
    s = env.unwrapped.physics.settings
    assert s.method == method
    options, id_rms = _expected_settings(name, method)
    for key, value in options.items():
        assert s.method_options[key] == value, key
    np.testing.assert_allclose(s.id_rms, id_rms, rtol=1e-12)
    try:
        obs, _ = env.reset(seed=0)
    except vrig.errors.RigLimitError as exc:
        # only a drive check may stop it: the light truck's NARX inverses ask IT00DRV for a
        # little more than the Fy full scale (their side-car descriptions: "IT00DRV is refused")
        assert (name, method) in IT00_BEYOND_FULL_SCALE, exc
        assert "before the drive was sent" in str(exc)
    else:
        assert env.observation_space.contains(obs)
        obs, reward, terminated, truncated, _ = env.step(env.action_space.sample())
        assert np.isfinite(reward) and isinstance(terminated, bool) and not truncated
    env.close()
    with warnings.catch_warnings(record=True) as record:
        warnings.simplefilter("always")
        gym.make(GENERIC_ID, rig=name, method=method, fast=True, seconds=2.0).close()
    _one_line_warning(record, reason)


def test_the_shipped_side_cars_mark_the_reference_texts_failures():
    # the reference text's failures (Table 3.4: full-spectrum models of the fuel tank; Table 6.7:
    # ARX of the trailer's strain): they warn, and the id must not default to them
    assert {("fuel-tank-2ch", m) for m in ("arx", "narx", "frf")} <= {
        (n, m) for n, m, _ in _unsupported()
    }
    assert ("pneumatic-trailer", "arx") in {(n, m) for n, m, _ in _unsupported()}
    for name, method, _ in _unsupported():
        assert _gym(name).get("method", "arx") != method, name
