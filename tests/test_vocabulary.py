"""One method vocabulary (issue 26, deliverable 5): a method name and options, the rig side-car's
defaults and the band become a method in one place, :func:`vrig.reconstruction.method_spec`,
which the CLI, :func:`vrig.reconstruct`, the envs and the benchmark runner all use.

The truths: the documented built-in defaults (arx order 4, narx order 4 degree 2, error-signal
linear order 3, split at :func:`vrig.reconstruction.defaults.default_split_hz`), the side-car's values as written
in it, and the CLI's usage messages as ``vrig reconstruct --help`` states the ranges.
"""

from __future__ import annotations

from types import SimpleNamespace

import pytest

import vrig
from vrig.reconstruction import (
    InverseArx,
    InverseErrorSignal,
    InverseFrf,
    InverseNarx,
    MethodOptionError,
    SplitSpectra,
    method_spec,
)
from vrig.reconstruction.defaults import default_split_hz
from vrig.reconstruction.vocabulary import side_car_options
from vrig.rigs.spec import MethodDefaults, RigDefaults


def _rig(**methods):
    """A rig stand-in with a side-car's method defaults (only ``defaults`` is read)."""
    return SimpleNamespace(name="stub", defaults=RigDefaults(methods=methods))


# ---------------------------------------------------------------------------------------------
# built-in defaults
# ---------------------------------------------------------------------------------------------
def test_the_built_in_defaults():
    arx = method_spec("arx").method
    assert isinstance(arx, InverseArx) and arx.order == 4
    narx = method_spec("narx").method
    assert isinstance(narx, InverseNarx) and (narx.order, narx.degree) == (4, 2)
    assert narx.focus == "prediction" and narx.search is False
    es = method_spec("error-signal").method
    assert isinstance(es, InverseErrorSignal)
    assert (es.linear_order, es.nonlinear_order, es.degree) == (3, 2, 2)
    assert isinstance(method_spec("frf").method, InverseFrf)
    split = method_spec("split", band=(0.0, 40.0)).method
    assert isinstance(split, SplitSpectra) and split.split_hz == default_split_hz((0.0, 40.0))
    assert split.split_hz == 10.0  # a quarter of the upper edge of a band from 0 Hz
    assert all(type(b) is InverseArx and b.order == 4 for b in (split.low, split.high))


def test_descriptions_say_what_was_built():
    assert method_spec("arx", order=6).description == "arx order 6"
    assert method_spec("narx", degree=3).description == "narx order 4 degree 3"
    assert method_spec("narx", search=True, budget=5.0).description == (
        "narx searched by free-run validation (orders up to 8, degrees 1..2, budget 5 s)"
    )
    assert method_spec("split", band=(1.0, 100.0), degree=2).description == (
        "split spectra at 10 Hz (low narx degree 2 order 4, high arx order 4)"
    )
    assert method_spec("error-signal", focus="simulation").description == (
        "error-signal (arx order 3 + narx order 2 degree 2 of its drive error, simulation focus)"
    )
    assert method_spec("frf").description == "frf (H1, truncated-SVD/Tikhonov inverse)"


def test_a_method_class_option_passes_through_and_an_unknown_one_is_refused():
    narx = method_spec("narx", kind="full", lead=2).method
    assert narx.kind == "full" and narx.lead == 2
    assert method_spec("frf", nperseg=256).method.nperseg == 256
    with pytest.raises(ValueError, match="'frf' takes no option 'rcnd'"):
        method_spec("frf", rcnd=1e-3)
    with pytest.raises(ValueError, match="unknown method 'magic'"):
        method_spec("magic")


def test_a_method_object_is_taken_as_it_is():
    obj = InverseArx(2)
    assert method_spec(obj).method is obj
    with pytest.raises(ValueError, match="only for methods given by name"):
        method_spec(obj, order=3)


# ---------------------------------------------------------------------------------------------
# layers: given > side-car > built-in
# ---------------------------------------------------------------------------------------------
def test_given_wins_over_the_side_car_which_wins_over_the_built_in():
    rig = _rig(narx=MethodDefaults("why", order=3, degree=3, focus="simulation"))
    m = method_spec("narx", rig=rig).method
    assert (m.order, m.degree, m.focus) == (3, 3, "simulation")
    m = method_spec("narx", rig=rig, order=5).method
    assert (m.order, m.degree, m.focus) == (5, 3, "simulation")
    m = method_spec("narx", rig=rig, side_car=False).method  # as vrig.reconstruct builds it
    assert (m.order, m.degree, m.focus) == (4, 2, "prediction")


def test_a_side_car_option_the_method_does_not_take_is_left_out():
    rig = _rig(arx=MethodDefaults("why", order=5, focus="simulation"))
    assert method_spec("arx", rig=rig).method.order == 5  # focus: not an arx option
    assert side_car_options("arx", rig, (0.0, 10.0)) == {"order": 5}


def test_side_car_options_are_the_classes_keyword_arguments():
    rig = _rig(
        **{
            "error-signal": MethodDefaults("why", order=5, degree=3, focus="simulation"),
            "split": MethodDefaults("why", split_hz=7.0, order=3, degree=2),
        }
    )
    assert side_car_options("error-signal", rig, (0.0, 40.0)) == {
        "linear_order": 5,
        "degree": 3,
        "focus": "simulation",
    }
    split = side_car_options("split", rig, (0.0, 40.0))
    assert split["split_hz"] == 7.0
    assert type(split["low"]) is InverseNarx and (split["low"].order, split["low"].degree) == (3, 2)
    assert type(split["high"]) is InverseArx and split["high"].order == 3
    # no side-car split: the band's rule, always given (the env stores it in method_options)
    assert side_car_options("split", _rig(), (4.0, 100.0)) == {"split_hz": 20.0}
    assert side_car_options("frf", rig, (0.0, 40.0)) == {}


def test_the_split_frequency_is_the_side_cars_then_the_bands():
    rig = _rig(split=MethodDefaults("why", split_hz=12.0))
    assert method_spec("split", rig=rig, band=(0.0, 40.0)).method.split_hz == 12.0
    # vrig.reconstruct (side_car=False) keeps the rig's split too: default_split_hz's rule
    assert method_spec("split", rig=rig, band=(0.0, 40.0), side_car=False).method.split_hz == 12.0
    assert method_spec("split", band=(0.0, 40.0), split_hz=3.0).method.split_hz == 3.0
    with pytest.raises(ValueError, match="'split' needs split_hz"):
        method_spec("split")


# ---------------------------------------------------------------------------------------------
# applicability and ranges: one message in Python's words, one in the command line's
# ---------------------------------------------------------------------------------------------
@pytest.mark.parametrize(
    ("name", "options", "python", "cli"),
    [
        (
            "frf",
            {"order": 3},
            "order applies to",
            "--order applies to arx, narx and split, not frf",
        ),
        ("arx", {"degree": 2}, "degree applies to narx", "--degree applies to narx and split"),
        ("arx", {"split_hz": 3.0}, "split_hz applies to method 'split'", "--split-hz applies to"),
        ("arx", {"search": True}, "search applies to method 'narx'", "--search applies to"),
        ("narx", {"budget": 5.0}, "budget applies to search=True", "--budget applies to --search"),
        ("narx", {"search": True, "budget": 0.0}, "budget must be a positive", "--budget must be"),
        ("arx", {"order": 0}, "order must be 1..20, got 0", "--order must be 1..20, got 0"),
        ("arx", {"order": 21}, "order must be 1..20, got 21", "--order must be 1..20, got 21"),
        ("narx", {"degree": 6}, "degree must be 1..5, got 6", "--degree must be 1..5, got 6"),
        ("arx", {"focus": "simulation"}, "focus applies to narx and error-signal", "focus"),
    ],
)
def test_an_option_that_does_not_apply_or_is_out_of_range(name, options, python, cli):
    with pytest.raises(MethodOptionError, match=python) as err:
        method_spec(name, band=(0.0, 10.0), **options)
    assert isinstance(err.value, ValueError) and err.value.cli.startswith(cli)


def test_the_split_must_lie_inside_the_band():
    with pytest.raises(MethodOptionError) as err:
        method_spec("split", band=(0.0, 10.0), split_hz=20.0)
    assert str(err.value) == "split_hz must lie inside the band 0-10 Hz, got 20"
    assert err.value.cli == "--split-hz must lie inside the band 0-10 Hz, got 20"


def test_none_means_not_given():
    m = method_spec("narx", order=None, degree=None, split_hz=None, search=None, budget=None)
    assert (m.method.order, m.method.degree) == (4, 2)


# ---------------------------------------------------------------------------------------------
# every caller builds the same method
# ---------------------------------------------------------------------------------------------
def test_the_engine_builds_by_the_vocabulary():
    rig = vrig.load_rig("motorcycle-rear", fidelity="fast")
    desired = vrig.TimeHistory(
        __import__("numpy").zeros((2000, len(rig.outputs))), rig.fs, [c.name for c in rig.outputs]
    )
    engine = vrig.reconstruction.DriveIteration(rig, desired, method="narx", order=3)
    # vrig.reconstruct takes no side-car order/focus (only its split rule): given + built-in
    assert (engine.method.order, engine.method.degree, engine.method.focus) == (3, 2, "prediction")


def test_the_env_and_the_cli_build_the_same_method_from_the_side_car():
    from vrig.envs.physics import rig_settings

    rig = vrig.load_rig("motorcycle-rear", fidelity="fast")
    side = rig.defaults.method("narx")
    settings = rig_settings(rig, vrig.IterationSettings(method="narx"), (0.0, 40.0))
    env = vrig.reconstruction.make_method("narx", **settings.method_options)
    cli = method_spec("narx", rig=rig, band=(0.0, 40.0)).method
    for m in (env, cli):
        assert (m.order, m.focus) == (side.order, side.focus)
        assert m.degree == (side.degree or 2)


def test_the_runners_built_ins_are_the_vocabularys():
    from benchmarks.runner.registry import get_method

    arx = get_method("arx").factory()
    assert type(arx) is InverseArx and arx.order == 4
    narx = get_method("narx").factory()
    assert (narx.order, narx.degree, narx.kind) == (4, 2, "full")
    sim = get_method("narx-sim").factory()
    assert (sim.kind, sim.focus, sim.selection) == ("full", "simulation", "simulation")
    search = get_method("narx-search").factory()
    assert search.search is True and search.budget == 60.0
    es = get_method("error-signal").factory()
    assert (es.linear_order, es.nonlinear_order, es.degree) == (3, 2, 2)
    split = get_method("split").factory(None, (4.0, 100.0))
    assert split.split_hz == pytest.approx(20.0)  # the band's geometric mean
    assert isinstance(get_method("frf").factory(), InverseFrf)
