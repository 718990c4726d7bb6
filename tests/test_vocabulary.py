"""One method vocabulary: a method name and options become a method in one place,
:func:`vrig.reconstruction.method_spec` (the defaults resolver, :mod:`vrig.reconstruction.defaults`,
gives it the rig side-car's options first: tests/test_defaults_resolver.py).

The truths: the documented built-in defaults (the method classes' signatures: arx order 4, narx
order 4 degree 2, error-signal linear order 3), and the CLI's usage messages as ``vrig reconstruct
--help`` states the ranges.
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
from vrig.reconstruction.vocabulary import side_car_vocabulary
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
    split = method_spec("split", band=(0.0, 40.0), split_hz=10.0).method
    assert isinstance(split, SplitSpectra) and split.split_hz == 10.0
    assert all(type(b) is InverseArx and b.order == 4 for b in (split.low, split.high))


def test_descriptions_say_what_was_built():
    assert method_spec("arx", order=6).description == "arx order 6"
    assert method_spec("narx", degree=3).description == "narx order 4 degree 3"
    assert method_spec("narx", search=True, budget=5.0).description == (
        "narx searched by free-run validation (orders up to 8, degrees 1..2, budget 5 s)"
    )
    assert method_spec("split", band=(1.0, 100.0), degree=2, split_hz=10.0).description == (
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
# the side-car's vocabulary options (applied by the resolver)
# ---------------------------------------------------------------------------------------------
def test_a_side_car_option_the_method_does_not_take_is_left_out():
    rig = _rig(arx=MethodDefaults("why", order=5, focus="simulation"))
    assert side_car_vocabulary("arx", rig) == {"order": 5}  # focus: not an arx option
    rig = _rig(split=MethodDefaults("why", split_hz=7.0, order=3, degree=2))
    assert side_car_vocabulary("split", rig) == {"split_hz": 7.0, "order": 3, "degree": 2}
    assert side_car_vocabulary("frf", rig) == {}
    assert side_car_vocabulary("arx", SimpleNamespace(name="no side-car")) == {}


def test_split_needs_its_frequency_and_builds_its_band_methods_from_order_and_degree():
    with pytest.raises(ValueError, match="'split' needs split_hz"):
        method_spec("split")
    split = method_spec("split", band=(0.0, 40.0), split_hz=7.0, order=3, degree=2).method
    assert type(split.low) is InverseNarx and (split.low.order, split.low.degree) == (3, 2)
    assert type(split.high) is InverseArx and split.high.order == 3


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
# the runner's built-ins are vrig reconstruct's methods
# ---------------------------------------------------------------------------------------------
def test_the_runners_built_ins_are_the_resolvers():
    from benchmarks.runner.registry import get_method
    from vrig.reconstruction.defaults import resolve

    rig = vrig.load_rig("motorcycle-rear", fidelity="fast")  # a side-car with narx options
    band = rig.bandwidth
    side = rig.defaults.method("narx")
    narx = get_method("narx").make(rig, band)
    assert (narx.order, narx.focus, narx.kind) == (side.order, side.focus, "full")
    cli = resolve(rig, method="narx", bandwidth=band).method
    assert (cli.order, cli.degree, cli.focus) == (narx.order, narx.degree, narx.focus)
    sim = get_method("narx-sim").make(rig, band)
    assert (sim.kind, sim.focus, sim.selection) == ("full", "simulation", "simulation")
    search = get_method("narx-search").make(rig, band)
    assert search.search is True and search.budget == 60.0
    es = get_method("error-signal").make(rig, band)
    assert type(es) is InverseErrorSignal
    split = get_method("split").make(rig, (4.0, 100.0))
    assert split.split_hz == resolve(rig, method="split", bandwidth=(4.0, 100.0)).method.split_hz
    assert isinstance(get_method("frf").make(rig, band), InverseFrf)
