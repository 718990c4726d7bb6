"""Issue 34 item 4 "Honest notes": a percentage never rounds onto or across the threshold its
sentence states (:func:`vrig.percent.percent`), and the identification's extrapolation note
names the model the fit chose (after a structure search: the chosen candidate, not the
configured order) and is given only for a fitted model that is polynomial."""

from __future__ import annotations

import numpy as np
import pytest

from identification import InverseModel, NarxSearch
from vrig.percent import EXTRA_DECIMALS, percent
from vrig.reconstruction.engine import _describe, _extrapolation_note
from vrig.reconstruction.methods import InverseNarx
from vrig.timehistory import TimeHistory

# -- the helper, against hand-made values


def test_a_ratio_below_the_threshold_never_prints_as_it():
    assert percent(0.996, threshold=1.0) == "99.6 %"  # f"{99.6:.0f}" is "100"
    assert percent(0.9996, threshold=1.0) == "99.96 %"
    assert percent(0.99996, threshold=1.0, decimals=1) == "99.996 %"
    assert percent(1 - 1e-9, threshold=1.0) == "< 100 %"  # more than EXTRA_DECIMALS would need
    assert EXTRA_DECIMALS == 2


def test_a_ratio_above_the_threshold_never_prints_as_it():
    assert percent(1.004, threshold=1.0) == "100.4 %"  # f"{100.4:.0f}" is "100"
    assert percent(1 + 1e-9, threshold=1.0) == "> 100 %"
    assert percent(0.9504, threshold=0.95) == "95.04 %"  # f"{95.04:.0f}" is "95"
    assert percent(1e-5, threshold=0.0, decimals=1) == "0.001 %"  # a sample beyond: not "0.0 %"
    assert percent(1e-9, threshold=0.0, decimals=1) == "> 0 %"


def test_the_threshold_itself_and_values_far_from_it_print_plainly():
    assert percent(1.0, threshold=1.0) == "100 %"
    assert percent(1.0, threshold=1.0, decimals=1) == "100.0 %"
    assert percent(0.0, threshold=0.0, decimals=1) == "0.0 %"
    assert percent(0.42, threshold=1.0) == "42 %"
    assert percent(1.5, threshold=1.0, decimals=1) == "150.0 %"
    assert percent(0.123456, threshold=0.123456) == "12.3456 %"  # equal: the threshold itself
    assert percent(float("nan"), threshold=1.0) == "nan %"
    for bad in (-1, 1.5, True):
        with pytest.raises(ValueError, match="decimals must be a whole number"):
            percent(0.5, threshold=1.0, decimals=bad)
    with pytest.raises(ValueError, match="threshold must be a finite fraction"):
        percent(0.5, threshold=float("inf"))


def test_every_rounding_lands_on_the_ratios_side_of_the_threshold():
    """A sweep across 100 %: the printed number (or the < / > bound) is on the value's side."""
    for r in np.linspace(0.99, 1.01, 2001):
        text = percent(float(r), threshold=1.0)
        value = 100 * float(r)
        if text.startswith(("<", ">")):
            assert (text[0] == "<") == (value < 100)
            continue
        shown = float(text.removesuffix(" %"))
        assert np.sign(shown - 100) == np.sign(value - 100), (r, text)


# -- the extrapolation note names the fitted model


def _records(polynomial: bool, n: int = 600, seed: int = 0):
    """A response record and the drive that produced it through a known inverse: the drive is
    ``y(t) - 0.5 y(t-1)`` (+ ``0.3 y(t)^2`` when ``polynomial``) of the response, exactly."""
    y = np.random.default_rng(seed).standard_normal(n)
    u = y - 0.5 * np.r_[0.0, y[:-1]] + (0.3 * y**2 if polynomial else 0.0)
    u = u - u.mean()
    return u[:, None], y[:, None]


def _searched(degrees, *, polynomial: bool) -> InverseNarx:
    """An ``InverseNarx(order=4, degree=2, search=True)`` whose fitted inverse came from a
    search over the one structure order 3 / ``degrees`` (the chosen candidate is known)."""
    method = InverseNarx(order=4, degree=2, search=True, lead=0)
    u, y = _records(polynomial)
    search = NarxSearch(
        None,  # no budget: a cold numba cache (compiling the kernels) must not skip the candidate
        orders=[3],
        degrees=degrees,
        kinds=["input-polynomial"],
        focus=["prediction"],
        selection=["frols"],
        options={"constant": False},
    )
    method.inverse = InverseModel(search, lead=0).fit(u, y)
    return method


def test_the_note_names_the_structure_the_search_chose_not_the_configured_one():
    method = _searched([2], polynomial=True)
    chosen = method.inverse.search_.best_result_.candidate
    assert (chosen.order, chosen.degree) == (3, 2)  # the one structure searched
    note = _extrapolation_note(method, [0.996, 1.2], ["F", "x"])
    assert "order 3, degree 2" in note and "chosen by the structure search" in note
    assert "NARX(4" not in note and "order 4" not in note  # the configured order
    assert "99.6 % of the desired response's peak (F)" in note and "100 %" not in note
    # before the fit the method is a search, not NARX(4, degree 2)
    assert _describe(InverseNarx(order=4, degree=2, search=True)) == (
        "NARX structure search (degree up to 2)"
    )


def test_no_polynomial_note_when_the_fitted_model_is_linear():
    # the search chose (here: could only choose) a linear candidate: a linear inverse
    linear = _searched([1], polynomial=True)
    assert linear.inverse.search_.best_result_.candidate.degree == 1
    assert _extrapolation_note(linear, [0.5], ["F"]) is None
    # a degree-2 NARX whose term selection kept no product (the drive is linear in the
    # response, so FROLS's two terms are y(t) and y(t-1)): linear as fitted
    u, y = _records(polynomial=False)
    drive, response = TimeHistory(u, 100.0, ["d"]), TimeHistory(y, 100.0, ["F"])
    method = InverseNarx(order=2, degree=2, lead=0, n_terms=2)
    method.identify(drive, response)
    assert method.inverse.model.term_names() == [["F(t)", "F(t-1)"]]
    assert _extrapolation_note(method, [0.5], ["F"]) is None
    # the same configuration on a drive with a y(t)^2 part keeps a product: polynomial
    u, y = _records(polynomial=True)
    method = InverseNarx(order=2, degree=2, lead=0, n_terms=3)
    method.identify(TimeHistory(u, 100.0, ["d"]), TimeHistory(y, 100.0, ["F"]))
    note = _extrapolation_note(method, [0.5], ["F"])
    assert note is not None and "NARX(2, degree 2)" in note and "50 %" in note


# -- the range check says "beyond" and prints a number beyond


def test_the_range_check_never_prints_a_peak_beyond_the_range_as_100_percent():
    """A desired response whose one sample in 100 000 lies 0.04 % beyond the transducer range
    (±2 mm): the row EXCEEDS, so neither its "of range" (100.04 %, not the old "100.0 %") nor
    its "samples beyond" (0.001 %, not "0.0 %") may read as at or within the range; a peak
    0.04 % inside the range is not printed as 100.0 % either."""
    from types import SimpleNamespace

    from vrig.desired.range_report import range_report

    x = np.zeros(100_000)
    x[10] = 2.0008  # [mm]
    rig = SimpleNamespace(outputs=[SimpleNamespace(name="x", unit="mm", full_scale=2.0)])
    report = range_report(rig, TimeHistory(x[:, None], 1000.0, ["x"], ["mm"]))
    row = report.rows[0]
    assert row.exceeds and row.fraction_beyond == 1e-5
    assert "100.04 %" in report.table() and "0.001 %  EXCEEDS" in report.table()
    assert "100.04 % of the transducer range" in row.describe()
    assert "0.001 % of the samples lie beyond it" in row.describe()
    x[10] = 1.9992  # 0.04 % inside
    inside = range_report(rig, TimeHistory(x[:, None], 1000.0, ["x"], ["mm"]))
    assert not inside.rows[0].exceeds and "99.96 %" in inside.table()
    assert "0.0 %" in inside.table()  # no sample beyond: exactly 0
