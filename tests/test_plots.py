"""Figures: the right axes and lines, desired red and achieved blue, PNGs written."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest
from matplotlib.colors import to_rgba
from matplotlib.figure import Figure

from vrig import ChannelSpec, TimeHistory
from vrig.plots import (
    drive_vs_limits,
    error_vs_iteration,
    overlay,
    psd_compare,
    repeatability_plot,
    save_reconstruction_plots,
)

FS = 200.0


def _records(n_channels=2, n=2000, seed=0):
    rng = np.random.default_rng(seed)
    names = [f"load{k + 1}" for k in range(n_channels)]
    t = np.arange(n)[:, None] / FS
    freqs = rng.uniform(1.0, 15.0, (4, n_channels))
    x = sum(np.sin(2 * np.pi * f * t + k) for k, f in enumerate(freqs))
    desired = TimeHistory(x, FS, names, ["N"] * n_channels)
    achieved = desired.with_data(0.95 * x + 0.05 * np.sin(2 * np.pi * 3.0 * t))
    return desired, achieved


def _result(n_channels=2, iterations=3):
    desired, achieved = _records(n_channels)
    drive = TimeHistory(0.01 * np.sin(np.arange(2000) / 20.0), FS, ["disp"], ["m"])
    errors = np.array(
        [[20.0 / (i + 1) + k for k in range(n_channels)] for i in range(iterations + 1)]
    )
    return SimpleNamespace(
        desired=desired,
        final_response=achieved,
        final_drive=drive,
        errors=errors,
        best_iteration=iterations,
        bandwidth=(0.0, 20.0),
    )


def _colors(ax):
    return [to_rgba(line.get_color()) for line in ax.get_lines()]


def test_overlay_desired_red_achieved_blue_one_axes_per_channel():
    desired, achieved = _records(3)
    fig = overlay(desired, achieved, errors=[1.0, 2.0, 3.0], title="t")
    assert isinstance(fig, Figure)
    assert len(fig.axes) == 3
    for k, ax in enumerate(fig.axes):
        assert len(ax.get_lines()) == 2
        assert _colors(ax) == [to_rgba("red"), to_rgba("blue")]
        assert ax.get_ylabel() == f"load{k + 1} [N]"
        np.testing.assert_array_equal(ax.get_lines()[0].get_ydata(), desired.data[:, k])
        assert "η0" in ax.get_title()
    assert fig.axes[-1].get_xlabel() == "time [s]"


def test_overlay_window_and_mismatch():
    desired, achieved = _records(1)
    fig = overlay(desired, achieved, window=(1.0, 2.0))
    t = fig.axes[0].get_lines()[0].get_xdata()
    assert t.min() >= 1.0 and t.max() < 2.0
    with pytest.raises(ValueError, match="channels"):
        overlay(desired, _records(2)[1])
    with pytest.raises(ValueError, match="Hz"):
        overlay(desired, TimeHistory(achieved.data, 100.0))
    with pytest.raises(ValueError, match="no samples"):
        overlay(desired, achieved, window=(100.0, 200.0))


def test_psd_compare_log_scale_with_units():
    desired, achieved = _records(2)
    fig = psd_compare(desired, achieved, band=(0.0, 20.0))
    assert len(fig.axes) == 2
    for ax in fig.axes:
        assert ax.get_yscale() == "log"
        assert _colors(ax) == [to_rgba("red"), to_rgba("blue")]
        assert "N²/Hz" in ax.get_ylabel()
        assert ax.get_xlim()[1] == pytest.approx(40.0)
    assert fig.axes[-1].get_xlabel() == "frequency [Hz]"


def test_error_vs_iteration_marks_the_best():
    res = _result(n_channels=2, iterations=3)
    fig = error_vs_iteration(res)
    (ax,) = fig.axes
    lines = ax.get_lines()
    assert len(lines) == 2 + 1 + 1  # two channels, the mean, the best-iteration marker
    np.testing.assert_array_equal(lines[0].get_ydata(), res.errors[:, 0])
    assert list(lines[-1].get_xdata()) == [3, 3]
    assert "best IT03" in lines[-1].get_label()
    assert ax.get_ylabel() == "η0 [%]" and ax.get_xlabel() == "iteration"
    single = error_vs_iteration(_result(n_channels=1, iterations=2))
    assert len(single.axes[0].get_lines()) == 2  # no mean line for one channel


def test_drive_vs_limits_draws_full_scale_lines():
    drive = TimeHistory(
        np.column_stack([np.linspace(-1, 1, 100), np.zeros(100)]), FS, ["a", "b"], ["m", "V"]
    )
    specs = (ChannelSpec("b", "V", 10.0, "direct"), ChannelSpec("a", "m", 2.0, "hydraulic"))
    fig = drive_vs_limits(drive, specs)  # matched by name
    assert len(fig.axes) == 2
    for ax, full in zip(fig.axes, (2.0, 10.0), strict=True):
        lines = ax.get_lines()
        assert len(lines) == 3
        assert list(lines[1].get_ydata()) == [full, full]
        assert list(lines[2].get_ydata()) == [-full, -full]
    assert fig.axes[0].get_ylabel() == "a [m]"
    assert "50.0 % of full scale" in fig.axes[0].get_title()
    with pytest.raises(ValueError, match="drives"):
        drive_vs_limits(drive, specs[:1])


def test_repeatability_plot_has_two_axes():
    f = np.linspace(0, 100, 51)
    rf = np.full((51, 2), 99.0)
    snr = np.full((51, 2), 40.0)
    fig = repeatability_plot(f, rf, snr, ["x", "y"], band=(0.0, 30.0))
    assert len(fig.axes) == 2
    assert all(len(ax.get_lines()) == 2 for ax in fig.axes)
    assert fig.axes[0].get_ylabel() == "R_f(f) [%]" and fig.axes[1].get_ylabel() == "SNR [dB]"


def test_save_reconstruction_plots_writes_pngs(tmp_path):
    res = _result()
    rig = SimpleNamespace(inputs=(ChannelSpec("disp", "m", 0.05, "hydraulic"),))
    paths = save_reconstruction_plots(res, tmp_path / "plots", rig=rig, dpi=40)
    names = [p.name for p in paths]
    assert names == [
        "overlay.png",
        "overlay_zoom.png",
        "psd.png",
        "error_vs_iteration.png",
        "drive_vs_limits.png",
    ]
    for p in paths:
        assert p.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert len(save_reconstruction_plots(res, tmp_path / "norig", dpi=40)) == 4
