"""Ecosystem conventions (issue 15, deliverable 7): nonlinear_benchmarks' ``Input_output_data``
adapters, ``TimeHistory`` to and from pandas, sample-index slicing of ``TimeHistory``, and the
optional packages imported lazily."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from identification import (
    IdentificationError,
    Narx,
    from_input_output_data,
    to_input_output_data,
)
from vrig import TimeHistory

ROOT = Path(__file__).resolve().parents[1]


def _record(n=1000, fs=512.0):
    rng = np.random.default_rng(0)
    return TimeHistory(rng.standard_normal((n, 3)), fs, ["x", "F", "a"], ["m", "N", "m/s^2"])


# ---------------------------------------------------------------- nonlinear_benchmarks
def _duck(u, y, sampling_time, n_init=None):
    """What nonlinear_benchmarks' Input_output_data holds (utilities.py of the package)."""
    return SimpleNamespace(
        u=u, y=y, sampling_time=sampling_time, name="test",
        state_initialization_window_length=n_init,
    )


def test_from_input_output_data_duck_typed():
    rng = np.random.default_rng(1)
    u, y = rng.standard_normal(300), rng.standard_normal(300)
    got_u, got_y, fs = from_input_output_data(_duck(u, y, 0.25, 50))
    np.testing.assert_array_equal(got_u, u)
    np.testing.assert_array_equal(got_y, y)
    assert fs == 4.0  # Hz, from a 0.25 s sampling time
    assert from_input_output_data(_duck(u, y, None))[2] is None  # discrete time


@pytest.mark.parametrize(
    ("obj", "match"),
    [
        (SimpleNamespace(u=np.zeros(3), y=np.zeros(3)), "no sampling_time"),
        (_duck(np.zeros(3), np.zeros(4), 1.0), "one length"),
        (_duck(np.zeros(3), np.zeros(3), -1.0), "> 0 seconds"),
        (_duck(np.zeros(3), np.zeros(3), "1 ms"), "number of seconds"),
        (_duck(["a", "b"], np.zeros(2), 1.0), "numeric"),
    ],
)
def test_from_input_output_data_refuses_bad_objects(obj, match):
    with pytest.raises(IdentificationError, match=match):
        from_input_output_data(obj)


def test_input_output_data_round_trip_with_the_real_class():
    nb = pytest.importorskip("nonlinear_benchmarks")
    rng = np.random.default_rng(2)
    u, y = rng.standard_normal((400, 2)), rng.standard_normal(400)
    data = to_input_output_data(u, y, 1 / 610.35, name="sb", state_initialization_window_length=50)
    assert isinstance(data, nb.Input_output_data)
    assert data.state_initialization_window_length == 50 and data.name == "sb"
    u2, y2, fs = from_input_output_data(data)
    np.testing.assert_array_equal(u2, u)
    np.testing.assert_array_equal(y2, y)
    assert fs == pytest.approx(610.35, rel=4e-16)  # one rounding each way
    # the package's own slicing keeps working on what we made
    assert len(data[:100]) == 100


def test_a_benchmark_style_initialisation_window_on_input_output_data():
    # the nonlinear_benchmarks workflow: simulate the test record from its first n outputs
    rng = np.random.default_rng(3)
    u = rng.standard_normal(600)
    y = np.zeros(600)
    for t in range(1, 600):
        y[t] = 0.8 * y[t - 1] + u[t - 1]
    model = Narx(na=1, nb=1, nk=1, degree=1).fit(u, y)
    u2, y2, _ = from_input_output_data(_duck(u, y, 1e-3, 50))
    y_sim = model.simulate(u2, y0=y2[:50])
    np.testing.assert_allclose(y_sim[:, 0], y, rtol=0, atol=1e-10)


def test_to_input_output_data_says_which_extra_when_missing(monkeypatch):
    monkeypatch.setitem(sys.modules, "nonlinear_benchmarks", None)  # import fails
    with pytest.raises(ImportError, match=r"vrig\[interop\]"):
        to_input_output_data(np.zeros(3), np.zeros(3), 1.0)


# ---------------------------------------------------------------- pandas
def test_pandas_round_trip_is_exact():
    pytest.importorskip("pandas")
    th = _record(fs=1000.0 / 3.0)  # fs with no short binary expansion
    df = th.to_pandas()
    assert list(df.columns) == ["x", "F", "a"]
    assert df.index.name == "time [s]"
    np.testing.assert_allclose(df.index.to_numpy(), np.arange(1000) * 0.003, rtol=1e-15, atol=0)
    assert df.attrs["units"] == {"x": "m", "F": "N", "a": "m/s^2"}
    back = TimeHistory.from_pandas(df)
    np.testing.assert_array_equal(back.data, th.data)
    assert back.fs == th.fs
    assert back.names == th.names and back.units == th.units
    df.iloc[0, 0] = 99.0  # the frame is a copy: the record stays as it was
    assert th.data[0, 0] != 99.0


def test_from_pandas_infers_the_rate_from_the_index():
    pd = pytest.importorskip("pandas")
    data = np.arange(20.0).reshape(10, 2)
    df = pd.DataFrame(data, index=0.5 + np.arange(10) / 200.0, columns=["p", "q"])
    th = TimeHistory.from_pandas(df)  # no attrs: fs from the spacing, start time dropped
    assert th.fs == pytest.approx(200.0, rel=1e-12)
    assert th.units == ("-", "-") and th.names == ("p", "q")
    stamps = pd.date_range("2024-01-01", periods=10, freq="1ms")
    assert TimeHistory.from_pandas(pd.DataFrame(data, index=stamps)).fs == pytest.approx(1000.0)
    rounded = pd.DataFrame(data, index=np.round(np.arange(10) / 3000.0, 6))  # µs stamps
    assert TimeHistory.from_pandas(rounded).fs == pytest.approx(3000.0, rel=1e-5)
    series = pd.Series(np.ones(4), index=np.arange(4) * 0.1, name="s")
    assert TimeHistory.from_pandas(series).names == ("s",)


def test_from_pandas_refuses_a_non_uniform_index():
    pd = pytest.importorskip("pandas")
    t = np.arange(11) / 100.0
    df = pd.DataFrame(np.zeros((10, 1)), index=np.delete(t, 5))  # one sample missing
    with pytest.raises(ValueError, match="not uniform"):
        TimeHistory.from_pandas(df)
    with pytest.raises(ValueError, match="not uniform"):
        TimeHistory.from_pandas(pd.DataFrame(np.zeros((10, 1)), index=t[:10]), fs=50.0)


def test_from_pandas_range_index_needs_fs():
    pd = pytest.importorskip("pandas")
    df = pd.DataFrame({"a": np.ones(5)})
    with pytest.raises(ValueError, match="RangeIndex"):
        TimeHistory.from_pandas(df)
    assert TimeHistory.from_pandas(df, fs=100.0).fs == 100.0


def test_from_pandas_refuses_bad_columns_and_units():
    pd = pytest.importorskip("pandas")
    df = pd.DataFrame({"a": ["x", "y"]}, index=[0.0, 0.1])
    with pytest.raises(ValueError, match="numeric"):
        TimeHistory.from_pandas(df)
    df = pd.DataFrame({"a": [1.0, 2.0]}, index=[0.0, 0.1])
    df.attrs["units"] = ["m", "N"]
    with pytest.raises(ValueError, match="2 units for 1 columns"):
        TimeHistory.from_pandas(df)
    df.attrs["units"] = ["m"]
    assert TimeHistory.from_pandas(df).units == ("m",)


def test_optional_packages_are_imported_lazily():
    code = (
        "import sys, identification, vrig, vrig.timehistory, identification.interop\n"
        "bad = [m for m in ('pandas', 'nonlinear_benchmarks') if m in sys.modules]\n"
        "print(bad)\n"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, check=True,
        env={"PYTHONPATH": str(ROOT), "PATH": "/usr/bin:/bin"},
    )
    assert out.stdout.strip() == "[]"


def test_to_pandas_says_which_extra_when_missing(monkeypatch):
    monkeypatch.setitem(sys.modules, "pandas", None)
    with pytest.raises(ImportError, match=r"vrig\[pandas\]"):
        _record().to_pandas()


# ---------------------------------------------------------------- sample slicing
def test_slices_select_samples_and_names_select_channels():
    th = _record()
    part = th[100:200]
    np.testing.assert_array_equal(part.data, th.data[100:200])
    assert part.fs == th.fs and part.names == th.names and part.units == th.units
    np.testing.assert_array_equal(th[-10:].data, th.data[-10:])
    assert th["F"].names == ("F",) and th[["a", "x"]].names == ("a", "x")
    assert th[1].names == ("F",)  # an integer still picks a channel
    assert th[[0, 2]].names == ("x", "a")
    both = th[100:200, "F"]
    assert both.names == ("F",) and both.units == ("N",)
    np.testing.assert_array_equal(both.data[:, 0], th.data[100:200, 1])


def test_a_step_divides_the_sample_rate():
    th = _record(fs=512.0)
    half = th[::2]
    assert half.fs == 256.0 and half.n_samples == 500
    np.testing.assert_array_equal(half.data, th.data[::2])
    assert half.duration == th.duration  # the same span of time, every other sample
    assert th[10:20:5].fs == 512.0 / 5


def test_bad_sample_slices_are_refused():
    th = _record()
    with pytest.raises(ValueError, match="reverse time"):
        th[::-1]
    with pytest.raises(ValueError, match="select nothing"):
        th[500:500]
    with pytest.raises(KeyError, match="sample slice, channels"):
        th["F", 1:2]
