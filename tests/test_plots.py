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
    worst_error_window,
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


def _captured(monkeypatch, res, rig):
    """``{file name: figure}`` that save_reconstruction_plots would write."""
    import vrig.plots as plots

    figures = {}

    def fake_save(fig, path, *, dpi=110):
        figures[path.name] = fig
        return path

    monkeypatch.setattr(plots, "save_figure", fake_save)
    plots.save_reconstruction_plots(res, "unused-folder-never-written", rig=rig)
    return figures


def _injected_pair(n=4000, at=700, at_loud=3000):
    """Two channels of very different scale (1000 N and 0.01 m/s²) tracked with a small error
    everywhere, plus two injected error bursts of 0.2 s: on the small channel at sample ``at``
    (0.5 x its desired RMS) and on the large channel at ``at_loud`` (10 N absolute, far more than
    the first burst in absolute terms but only 0.01 x that channel's RMS)."""
    rng = np.random.default_rng(3)
    t = np.arange(n) / FS
    x = np.column_stack(
        [1000 * np.sin(2 * np.pi * 2.0 * t), 0.01 * np.sin(2 * np.pi * 7.0 * t + 1.0)]
    )
    rms = np.sqrt(np.mean(x**2, axis=0))
    y = x + 0.001 * rms * rng.standard_normal(x.shape)
    burst = int(0.2 * FS)
    y[at : at + burst, 1] += 0.5 * rms[1]
    y[at_loud : at_loud + burst, 0] += 10.0
    desired = TimeHistory(x, FS, ["load", "accel"], ["N", "m/s²"])
    return desired, desired.with_data(y)


def test_worst_error_window_finds_the_injected_error_normalised_per_channel():
    desired, achieved = _injected_pair(at=700)
    t0, t1 = worst_error_window(desired, achieved, width=1.0)
    assert t1 - t0 == pytest.approx(1.0)
    # the whole 0.2 s burst at 3.5-3.7 s lies in the window, not the louder-in-newtons one
    assert t0 <= 700 / FS and (700 + 40) / FS <= t1
    # a record shorter than the window: all of it
    short = TimeHistory(desired.data[:100], FS, desired.names, desired.units)
    assert worst_error_window(short, short.with_data(short.data + 1.0)) == (0.0, 0.5)
    with pytest.raises(ValueError, match="width"):
        worst_error_window(desired, achieved, width=0.0)


def test_zoom_plot_shows_the_worst_error_second_and_says_so(monkeypatch):
    desired, achieved = _injected_pair(at=700)  # 3.5 s of a 20 s record: far from the middle
    res = _result()
    res.desired, res.final_response = desired, achieved
    figures = _captured(monkeypatch, res, rig=None)
    zoom = figures["overlay_zoom.png"]
    t = zoom.axes[0].get_lines()[0].get_xdata()
    assert t.min() <= 700 / FS <= t.max()
    assert t.max() - t.min() == pytest.approx(1.0, abs=2 / FS)
    assert f"zoom: {t.min():.1f}-{t.min() + 1:.1f} s, worst error" in zoom.get_suptitle()
    # the whole-record overlay shades the same window
    (span,) = figures["overlay.png"].axes[0].patches
    assert span.get_x() == pytest.approx(t.min())


def test_overlay_and_psd_draw_desired_on_top_of_achieved():
    desired, achieved = _records(2)
    figures = (
        overlay(desired, achieved),
        overlay(desired, achieved, window=(1.0, 2.0)),
        psd_compare(desired, achieved),
    )
    for fig in figures:
        for ax in fig.axes:
            des, ach = ax.get_lines()
            assert to_rgba(des.get_color()) == to_rgba("red")
            assert des.get_zorder() > ach.get_zorder()
            assert des.get_linewidth() < ach.get_linewidth()  # the blue band shows around it


def test_small_drive_is_drawn_between_its_limits_with_an_inset_scaled_to_it():
    """The figure is named after the limits: they are drawn whatever the drive's size (issue 25:
    a final drive at 17 % of full scale was shown with "full scale off axis" and no limit); a
    drive below a third of them also gets an inset scaled to its own peak."""
    full = 0.05
    x = 0.01 * full * np.sin(np.arange(2000) / 20.0)  # 1 % of full scale
    drive = TimeHistory(x, FS, ["disp"], ["m"])
    fig = drive_vs_limits(drive, (ChannelSpec("disp", "m", full, "hydraulic"),))
    (ax,) = fig.axes  # the inset is a child of the axes, not a figure axes
    assert sorted(line.get_ydata()[0] for line in ax.get_lines()[1:]) == [-full, full]
    assert ax.get_ylim()[1] > full and ax.get_ylim()[0] < -full and not ax.texts
    (inset,) = ax.child_axes
    np.testing.assert_array_equal(inset.get_lines()[0].get_ydata(), x)
    peak = np.abs(x).max()
    lo, hi = inset.get_ylim()
    assert peak < hi <= 3 * peak and -3 * peak <= lo < -peak
    # at half of full scale: the lines inside the axes, no inset needed
    fig = drive_vs_limits(drive.with_data(50 * x), (ChannelSpec("disp", "m", full, "hydraulic"),))
    (ax,) = fig.axes
    assert sorted(line.get_ydata()[0] for line in ax.get_lines()[1:]) == [-full, full]
    assert ax.get_ylim()[1] > full and ax.get_ylim()[0] < -full and not ax.child_axes


def test_overlay_error_trace_beneath_each_channel():
    """``error=True``: beneath each channel an axes with desired - achieved on its own scale and
    its RMS in % of the desired RMS (means removed) in the legend; the saved whole-record and
    zoom overlays have it."""
    from identification.metrics import rms_error_percent

    desired, achieved = _records(2)
    fig = overlay(desired, achieved, error=True)
    assert len(fig.axes) == 4
    for k in range(2):
        ax, err = fig.axes[2 * k], fig.axes[2 * k + 1]
        assert len(ax.get_lines()) == 2  # desired, achieved
        line = err.get_lines()[0]
        e = desired.data[:, k] - achieved.data[:, k]
        np.testing.assert_allclose(line.get_ydata(), e)
        assert to_rgba(line.get_color()) == to_rgba("black")
        rms = rms_error_percent(desired.data[:, k], achieved.data[:, k])
        assert f"RMS {rms:.3g} % of desired" in line.get_label()
        lo, hi = err.get_ylim()
        assert np.abs(e).max() < hi < 1.5 * np.abs(e).max() and lo == -hi  # scaled to the error
        assert err.get_ylabel() == "error [N]"
    assert fig.axes[-1].get_xlabel() == "time [s]"


def test_saved_overlays_carry_the_error_trace(monkeypatch):
    figures = _captured(monkeypatch, _result(n_channels=2), rig=None)
    for name in ("overlay.png", "overlay_zoom.png"):
        axes = figures[name].axes
        assert len(axes) == 4 and axes[1].get_ylabel() == "error [N]", name


def test_error_vs_iteration_log_axis_reads_plain_numbers():
    """η0 from 31.35 to 2.75 % spans more than a decade: a log axis, labelled 3, 5, 10, 20,
    30 - not matplotlib's "3 × 10^1"."""
    res = _result(n_channels=1, iterations=5)
    res.errors = np.array([[31.35], [12.0], [6.1], [4.2], [3.3], [2.75]])
    res.best_iteration = 5
    (ax,) = error_vs_iteration(res).axes
    assert ax.get_yscale() == "log"
    lo, hi = ax.get_ylim()
    ticks = [v for v in ax.yaxis.get_major_locator()() if lo <= v <= hi]
    labels = ax.yaxis.get_major_formatter().format_ticks(ticks)
    assert labels == ["3", "5", "10", "20", "30"], labels
    assert ax.yaxis.get_minor_formatter()(30.0) == ""  # no "3 × 10^1" minor label


def _rejected(name, error, x):
    res = _result()
    res.errors = np.empty((0, 2))  # nothing played: only the rejected-drive figure
    res.rejected_name, res.rejected_drive = name, TimeHistory(x, FS, ["disp"], ["m"])
    res.error, res.stopped = error, f"IT02: {error}"
    return res


def test_tripped_drive_marks_the_interlock_that_tripped(monkeypatch):
    from vrig.errors import RigLimitError

    rig = SimpleNamespace(inputs=(ChannelSpec("disp", "m", 0.05, "hydraulic"),))
    x = 0.04 * np.sin(np.arange(2000) / 20.0)
    trip = RigLimitError("stroke", "disp", 1.5, 0.0751, 0.075, "m")
    (fig,) = _captured(monkeypatch, _rejected("TRIPPED02", trip, x), rig).values()
    (ax,) = fig.axes
    levels = sorted(line.get_ydata()[0] for line in ax.get_lines()[1:] if line.get_xdata()[0] == 0)
    assert levels == [-0.075, -0.05, 0.05, 0.075]  # full scale and the stroke limit
    assert any(list(line.get_xdata()) == [1.5, 1.5] for line in ax.get_lines())  # trip time
    assert "stroke interlock" in ax.get_title() and "0.075 m limit" in ax.get_title()
    assert ax.get_ylim()[1] > 0.075
    # an interlock on a response channel: the trip time is still marked
    trip = RigLimitError("transducer range", "damper_load", 0.7, 1.2e4, 1e4, "N")
    (fig,) = _captured(monkeypatch, _rejected("TRIPPED02", trip, x), rig).values()
    assert any(list(line.get_xdata()) == [0.7, 0.7] for line in fig.axes[0].get_lines())


def test_refused_drive_marks_the_samples_beyond_full_scale(monkeypatch):
    from vrig.errors import RigLimitError

    rig = SimpleNamespace(inputs=(ChannelSpec("disp", "m", 0.05, "hydraulic"),))
    x = 0.04 * np.sin(np.arange(2000) / 20.0)
    x[1000] = 0.06  # the one sample beyond the full scale
    refused = RigLimitError("drive", "disp", float("nan"), 0.06, 0.05, "m")
    figures = _captured(monkeypatch, _rejected("REFUSED02", refused, x), rig)
    (ax,) = figures["refused_drive_vs_limits.png"].axes
    (marks,) = [line for line in ax.get_lines() if line.get_marker() == "x"]
    assert list(marks.get_xdata()) == [1000 / FS] and list(marks.get_ydata()) == [0.06]
    assert ax.get_ylim()[1] > 0.06  # the sample beyond the full scale is inside the axes
    assert "drive interlock" in ax.get_title()


def test_plain_log_ticks_over_many_decades():
    from vrig.plots import plain_log_ticks

    fig = Figure()
    ax = fig.add_subplot()
    ax.semilogy([0, 1], [0.01, 1e4])
    ax.set_ylim(0.01, 1e4)
    plain_log_ticks(ax.yaxis)
    ticks = [v for v in ax.yaxis.get_major_locator()() if 0.01 <= v <= 1e4]
    labels = ax.yaxis.get_major_formatter().format_ticks(ticks)
    assert labels == ["0.01", "0.1", "1", "10", "100", "1000", "10000"], labels
