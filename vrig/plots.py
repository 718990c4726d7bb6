"""Figures of a reconstruction (matplotlib): desired in red, achieved in blue, as in the
reference text.

Every function builds and returns a :class:`matplotlib.figure.Figure` that is not registered with
``pyplot`` (no global figure state is touched, nothing needs closing; PNGs are rendered with the
Agg canvas): show one in a notebook by leaving it as the cell's value, or save it with
``fig.savefig(path)``.

* :func:`overlay` — desired vs achieved time histories, one axes per channel (and, with
  ``error=True``, their difference beneath each on its own scale: a long broadband record is a
  solid block of red and blue at any figure width, its error trace is not);
* :func:`psd_compare` — their PSDs (Welch, log scale);
* :func:`error_vs_iteration` — η0 per channel against the iteration, best iteration marked (a
  log axis, when the errors span more than a decade, labelled in plain numbers: 3, 5, 10, 20);
* :func:`drive_vs_limits` — a drive against the ± full-scale lines of the rig's drive channels
  (always drawn; a drive below a third of them gets an inset scaled to itself) and, for a drive
  that tripped the rig, the interlock that tripped;
* :func:`worst_error_window` — the second of a record with the largest desired-achieved error;
* :func:`repeatability_plot` — ``R_f(f)`` and the signal-to-noise ratio against frequency;
* :func:`save_reconstruction_plots` — the PNGs of a :class:`~vrig.reconstruction.ReconstructionResult`;
* :func:`save_figure` — ``fig.savefig`` that replaces the file atomically (:mod:`vrig.files`);
* :func:`plain_log_ticks` — plain-number tick labels on a log axis (also the benchmark plots').
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from textwrap import wrap

import numpy as np
from matplotlib.figure import Figure
from scipy import signal

from .files import atomic_write
from .percent import percent
from .timehistory import TimeHistory

__all__ = [
    "ACHIEVED_COLOR",
    "DESIRED_COLOR",
    "drive_vs_limits",
    "error_vs_iteration",
    "overlay",
    "plain_log_ticks",
    "psd_compare",
    "repeatability_plot",
    "save_figure",
    "save_reconstruction_plots",
    "worst_error_window",
]

DESIRED_COLOR = "red"
"""Colour of desired records (DESRES), as in the reference text's figures."""
ACHIEVED_COLOR = "blue"
"""Colour of achieved records (ITxxRES, FINRES)."""
_LIMIT_COLOR = "black"
_TRIP_COLOR = "darkorange"
_TRIP_FIELDS = ("kind", "channel", "time", "value", "limit", "unit")  # of a RigLimitError
_ERROR_COLOR = "black"
_LIMIT_SPAN = 3.0  # a drive whose peak is below 1/3 of its limits gets an inset scaled to it
_ROW_HEIGHT = 2.2
_WIDTH = 10.0


def _label(name: str, unit: str) -> str:
    return f"{name} [{unit}]"


def _psd_unit(unit: str) -> str:
    if unit in ("", "-"):
        return "1/Hz"
    return f"({unit})²/Hz" if any(c in unit for c in "/^*· ") else f"{unit}²/Hz"


def _check_pair(desired: TimeHistory, achieved: TimeHistory) -> None:
    for what, th in (("desired", desired), ("achieved", achieved)):
        if not isinstance(th, TimeHistory):
            raise TypeError(f"{what} must be a vrig.TimeHistory, got {type(th).__name__}")
    if desired.n_channels != achieved.n_channels:
        raise ValueError(
            f"desired has {desired.n_channels} channels but achieved has {achieved.n_channels}"
        )
    if desired.fs != achieved.fs:
        raise ValueError(
            f"desired is sampled at {desired.fs:g} Hz but achieved at {achieved.fs:g} Hz"
        )


def _rows(n: int, *, sharex: bool = True, height: float = _ROW_HEIGHT) -> tuple[Figure, list]:
    fig = Figure(figsize=(_WIDTH, 1.0 + height * n), layout="constrained")
    axes = fig.subplots(n, 1, sharex=sharex, squeeze=False)[:, 0]
    return fig, list(axes)


def _rows_with_error(n: int) -> tuple[Figure, list, list]:
    """``n`` channel axes, each with a half-height error axes beneath it (one shared time axis):
    ``(figure, channel axes, error axes)``; ``figure.axes`` alternates them."""
    fig = Figure(figsize=(_WIDTH, 1.0 + 1.5 * _ROW_HEIGHT * n), layout="constrained")
    axes = fig.subplots(2 * n, 1, sharex=True, squeeze=False, height_ratios=[2, 1] * n)[:, 0]
    return fig, list(axes[0::2]), list(axes[1::2])


def plain_log_ticks(axis) -> None:
    """Label a log-scaled axis in plain numbers (``3``, ``5``, ``10``, ``20``, ``0.5``) instead
    of matplotlib's ``3 × 10^1``: ticks at 1, 2, 3 and 5 per decade when the axis spans at most
    1.5 decades, at 1, 2 and 5 up to three decades, at the powers of ten (with unlabelled minor
    ticks) beyond.

    Parameters
    ----------
    axis : matplotlib.axis.Axis
        ``ax.yaxis`` or ``ax.xaxis`` of an axes whose scale on that axis is already ``"log"``.
    """
    from matplotlib.ticker import FuncFormatter, LogLocator, NullFormatter

    lo, hi = sorted(axis.get_view_interval())
    decades = np.log10(hi / lo) if lo > 0 and np.isfinite(hi / lo) else np.inf
    subs = (1.0, 2.0, 3.0, 5.0) if decades <= 1.5 else (1.0, 2.0, 5.0) if decades <= 3 else (1.0,)
    axis.set_major_locator(LogLocator(base=10, subs=subs))
    axis.set_major_formatter(FuncFormatter(lambda v, _pos: f"{v:g}"))
    axis.set_minor_formatter(NullFormatter())


def overlay(
    desired: TimeHistory,
    achieved: TimeHistory,
    *,
    window: tuple[float, float] | None = None,
    errors: Sequence[float] | None = None,
    labels: tuple[str, str] = ("desired", "achieved"),
    title: str | None = None,
    mark: tuple[float, float] | None = None,
    error: bool = False,
) -> Figure:
    """Desired (red) and achieved (blue) time histories, one axes per channel.

    The achieved line is wide and drawn first, the desired line thin and drawn on top of it
    (higher ``zorder``): when the two agree the red line runs inside the blue band and both stay
    visible, where they differ the blue band leaves the red line. Over a long broadband record
    the two fill a solid block at any figure width; ``error=True`` adds beneath each channel its
    error trace (desired - achieved, black) on an axes scaled to the error itself.

    Parameters
    ----------
    desired, achieved : TimeHistory
        Same sample rate and number of channels (matched by position; the axes are labelled with
        the desired record's names and units).
    window : (start, stop) seconds, optional
        Show only this part of the records (default: all of it).
    errors : sequence of float, optional
        η0 [%] per channel, written in each axes' title.
    labels : (str, str)
        Legend entries of the desired and the achieved record.
    title : str, optional
        Figure title.
    mark : (start, stop) seconds, optional
        Shade this interval in every axes (e.g. the window shown in a detail plot).
    error : bool, optional
        Add an error axes beneath each channel's axes (``fig.axes`` then alternates channel and
        error axes), with the RMS of the error in % of the desired RMS in its legend.

    Returns
    -------
    Figure
        ``n_channels`` axes, each with two lines: desired first (red, on top), achieved second
        (blue, beneath); with ``error=True`` each followed by an axes with one line, the error.
    """
    _check_pair(desired, achieved)
    if errors is not None and len(errors) != desired.n_channels:
        raise ValueError(f"{len(errors)} errors for {desired.n_channels} channels")
    n = min(desired.n_samples, achieved.n_samples)
    t = np.arange(n) / desired.fs
    sel = slice(None)
    if window is not None:
        t0, t1 = window
        if not 0 <= t0 < t1:
            raise ValueError(
                f"window must be (start, stop) seconds with 0 <= start < stop, got {window}"
            )
        sel = (t >= t0) & (t < t1)
        if not sel.any():
            raise ValueError(f"window {window} s holds no samples of the {t[-1]:g} s records")
    if error:
        fig, axes, error_axes = _rows_with_error(desired.n_channels)
    else:
        (fig, axes), error_axes = _rows(desired.n_channels), []
    for k, ax in enumerate(axes):
        ax.plot(
            t[sel],
            desired.data[:n, k][sel],
            color=DESIRED_COLOR,
            lw=0.7,
            zorder=3,
            label=labels[0],
        )
        ax.plot(
            t[sel],
            achieved.data[:n, k][sel],
            color=ACHIEVED_COLOR,
            lw=2.0,
            alpha=0.55,
            zorder=2,
            label=labels[1],
        )
        if mark is not None:
            ax.axvspan(*mark, color="gold", alpha=0.3, zorder=1, lw=0)
        ax.set_ylabel(_label(desired.names[k], desired.units[k]))
        ax.grid(True, alpha=0.3)
        if errors is not None:
            ax.set_title(f"{desired.names[k]}: η0 = {errors[k]:.2f} %", fontsize="medium")
    for k, ax in enumerate(error_axes):
        _error_axes(ax, t[sel], desired.data[:n, k][sel], achieved.data[:n, k][sel], mark)
        ax.set_ylabel(f"error [{desired.units[k]}]")
    axes[0].legend(loc="upper right", fontsize="small")
    (error_axes or axes)[-1].set_xlabel("time [s]")
    if title:
        fig.suptitle(title)
    return fig


def _error_axes(ax, t, desired, achieved, mark) -> None:
    """The error ``desired - achieved`` against time on ``ax``: scaled to itself (symmetric), its
    RMS in % of the desired RMS (means removed, as :func:`identification.metrics.rms_error_percent`)
    in the legend."""
    e = desired - achieved
    label = "error = desired - achieved"
    ok = np.isfinite(e)
    ref = float(np.std(desired[ok])) if ok.any() else 0.0
    if ref > 0:
        label += f" (RMS {100 * float(np.std(e[ok])) / ref:.3g} % of desired)"
    ax.plot(t, e, color=_ERROR_COLOR, lw=0.6, label=label)
    peak = float(np.abs(e[ok]).max()) if ok.any() else 0.0
    if peak > 0:
        ax.set_ylim(-1.15 * peak, 1.15 * peak)
    if mark is not None:
        ax.axvspan(*mark, color="gold", alpha=0.3, zorder=1, lw=0)
    ax.axhline(0.0, color="0.6", lw=0.6, zorder=0)
    ax.grid(True, alpha=0.3)
    ax.legend(loc="upper right", fontsize="small")


def worst_error_window(
    desired: TimeHistory, achieved: TimeHistory, *, width: float = 1.0
) -> tuple[float, float]:
    """The ``width``-second window of the records with the largest tracking error.

    The error of channel ``k`` is ``(desired_k - achieved_k) / rms(desired_k)`` (each channel
    normalised by its desired RMS, so that channels in N and in m/s² weigh alike); its square,
    averaged over the channels, is averaged over every window of ``width`` seconds (a sliding
    window, one sample apart) and the window with the largest mean — the largest RMS error — is
    returned. A channel whose desired record is all zero is normalised by its achieved RMS (or
    not at all when that is zero too); non-finite samples count as zero error.

    Parameters
    ----------
    desired, achieved : TimeHistory
        Same sample rate and number of channels (compared over the shorter record).
    width : float
        Window length [s], > 0; a record shorter than that gives the whole record.

    Returns
    -------
    (start, stop) : tuple of float
        Seconds from the start of the records, ``stop - start == width`` (sample-rounded).
    """
    _check_pair(desired, achieved)
    if not (np.isfinite(width) and width > 0):
        raise ValueError(f"width must be a positive number of seconds, got {width!r}")
    n = min(desired.n_samples, achieved.n_samples)
    fs = desired.fs
    w = max(1, round(width * fs))
    if n <= w:
        return 0.0, n / fs
    d, a = desired.data[:n], achieved.data[:n]
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        scale = np.sqrt(np.nanmean(d**2, axis=0))
        scale = np.where(scale > 0, scale, np.sqrt(np.nanmean(a**2, axis=0)))
        scale = np.where(np.isfinite(scale) & (scale > 0), scale, 1.0)
        e2 = np.mean(((d - a) / scale) ** 2, axis=1)
    e2 = np.where(np.isfinite(e2), e2, 0.0)
    c = np.concatenate(([0.0], np.cumsum(e2)))
    i0 = int(np.argmax(c[w:] - c[:-w]))  # start sample of the worst window
    return i0 / fs, (i0 + w) / fs


def psd_compare(
    desired: TimeHistory,
    achieved: TimeHistory,
    *,
    nperseg: int | None = None,
    band: tuple[float, float] | None = None,
    labels: tuple[str, str] = ("desired", "achieved"),
    title: str | None = None,
) -> Figure:
    """PSDs (Welch, log scale) of desired (red) and achieved (blue), one axes per channel.

    Parameters
    ----------
    desired, achieved : TimeHistory
        The two records to compare (same channels and sample rate).
    nperseg : int, optional
        Welch segment length (default: about 0.5 Hz resolution, at most the record length).
    band : (low, high) Hz, optional
        The simulation band: shaded, and the frequency axis ends at twice its upper edge.
    labels : tuple of str, optional
        Legend labels of the desired and achieved lines.
    title : str, optional
        Figure title.

    Returns
    -------
    Figure
        ``n_channels`` axes with two lines each: desired first (thin, on top), achieved second
        (a wide band beneath), as in :func:`overlay`.
    """
    _check_pair(desired, achieved)
    fs = desired.fs
    n = min(desired.n_samples, achieved.n_samples)
    if nperseg is None:
        nperseg = int(2 ** np.ceil(np.log2(2 * fs)))
    nperseg = max(8, min(int(nperseg), n))
    f, p_des = signal.welch(desired.data[:n], fs=fs, nperseg=nperseg, axis=0)
    _, p_ach = signal.welch(achieved.data[:n], fs=fs, nperseg=nperseg, axis=0)
    fmax = fs / 2 if band is None else min(fs / 2, 2 * band[1])
    keep = (f > 0) & (f <= fmax)
    fig, axes = _rows(desired.n_channels)
    for k, ax in enumerate(axes):
        ax.semilogy(
            f[keep],
            np.maximum(p_des[keep, k], 1e-300),
            color=DESIRED_COLOR,
            lw=0.8,
            zorder=3,
            label=labels[0],
        )
        ax.semilogy(
            f[keep],
            np.maximum(p_ach[keep, k], 1e-300),
            color=ACHIEVED_COLOR,
            lw=2.2,
            alpha=0.55,
            zorder=2,
            label=labels[1],
        )
        if band is not None:
            ax.axvspan(band[0], band[1], color="0.9", zorder=0)
        ax.set_ylabel(f"{desired.names[k]}\nPSD [{_psd_unit(desired.units[k])}]")
        ax.grid(True, which="both", alpha=0.3)
    axes[0].legend(loc="upper right", fontsize="small")
    axes[-1].set_xlabel("frequency [Hz]")
    axes[-1].set_xlim(0, fmax)
    if title:
        fig.suptitle(title)
    return fig


def error_vs_iteration(result, *, title: str | None = None) -> Figure:
    """η0 [%] per channel against the iteration number, the best iteration marked.

    Parameters
    ----------
    result : ReconstructionResult
        Uses ``errors`` (iterations + 1, n_outputs), ``best_iteration`` and ``desired.names``.
    title : str, optional
        Axes title (default: what is plotted).

    Returns
    -------
    Figure
        One axes: a line per channel, a dashed black mean line when there is more than one
        channel, and a grey vertical line at the best iteration (the last line).
    """
    errors = np.asarray(result.errors, dtype=float)
    if errors.ndim != 2 or errors.shape[0] == 0:
        raise ValueError(f"result.errors must be (iterations + 1, channels), got {errors.shape}")
    names = result.desired.names
    its = np.arange(errors.shape[0])
    fig = Figure(figsize=(8.0, 4.5), layout="constrained")
    ax = fig.add_subplot()
    for k in range(errors.shape[1]):
        ax.plot(its, errors[:, k], marker="o", label=names[k])
    if errors.shape[1] > 1:
        ax.plot(its, errors.mean(axis=1), "k--", marker="s", label="mean")
    best = int(result.best_iteration)
    ax.axvline(
        best, color="0.5", ls=":", lw=1.5, label=f"best IT{best:02d} ({errors[best].mean():.2f} %)"
    )
    finite = errors[np.isfinite(errors)]
    if finite.size and finite.min() > 0 and finite.max() / finite.min() > 10:
        ax.set_yscale("log")
        plain_log_ticks(ax.yaxis)
    ax.set_xlabel("iteration")
    ax.set_ylabel("η0 [%]")
    ax.set_xticks(its, [f"IT{i:02d}" for i in its])
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize="small")
    ax.set_title(title or "QanTiM error η0 (eq. 5-28) of ITxxRES against DESRES")
    return fig


def drive_vs_limits(
    drive: TimeHistory, rig_inputs, *, title: str | None = None, trip=None
) -> Figure:
    """A drive against the rig's limits.

    Each channel's axes show the drive between its ± full-scale lines (dashed black, always
    drawn: how much of the range the drive uses is what the figure is for). A drive whose peak
    is below a third of the outermost limit drawn would be a thin band there, so it also gets an
    inset (upper right) scaled to its own peak. A channel that is all zero is shown against its
    full scale. Samples beyond the full scale (a refused drive) are marked with black crosses.

    Parameters
    ----------
    drive : TimeHistory
        The drive to show, in the drive channels' units.
    rig_inputs : sequence of ChannelSpec
        ``rig.inputs``; matched to the drive's channels by name, else by position.
    title : str, optional
        Figure title.
    trip : RigLimitError, optional
        The interlock that tripped (or refused) this drive: its time is marked with a vertical
        orange line in every axes (when known), the channel it names gets the limit in its title,
        and a stroke limit on a drive channel of the same unit is drawn as ± orange lines too.

    Returns
    -------
    Figure
        One axes per drive channel: the drive (blue) first, then the limit lines; the inset of
        a small drive is a child of its axes (``ax.child_axes``), not in ``fig.axes``.
    """
    if not isinstance(drive, TimeHistory):
        raise TypeError(f"drive must be a vrig.TimeHistory, got {type(drive).__name__}")
    specs = _match_specs(drive, rig_inputs)
    fig, axes = _rows(drive.n_channels, height=1.4 * _ROW_HEIGHT)  # room for an inset
    for k, ax in enumerate(axes):
        _drive_axes(ax, drive, k, specs[k], trip)
    axes[-1].set_xlabel("time [s]")
    if title:
        fig.suptitle(title)
    return fig


def _drive_axes(ax, drive: TimeHistory, k: int, c, trip) -> None:
    """Channel ``k`` of ``drive`` against its spec ``c`` (and the interlock ``trip``, if any)."""
    t, x, unit = drive.time, drive.data[:, k], drive.units[k]
    ax.plot(t, x, color=ACHIEVED_COLOR, lw=0.8, label=drive.names[k])
    finite = x[np.isfinite(x)]
    peak = float(np.abs(finite).max()) if finite.size else 0.0
    title = (
        f"{drive.names[k]}: peak {peak:.4g} {unit} = "
        f"{percent(peak / c.full_scale, threshold=1.0, decimals=1)} of full scale "
        f"±{c.full_scale:g} {c.unit}"
    )
    limits = [(c.full_scale, c.unit, "full scale", _LIMIT_COLOR, "--")]
    ours = trip is not None and getattr(trip, "channel", None) == c.name
    if ours:
        title += (
            f"\n{trip.kind} interlock: {trip.value:.6g} {trip.unit} exceeds the "
            f"{trip.limit:.6g} {trip.unit} limit"
        )
        if trip.kind == "stroke" and trip.unit == c.unit:
            limits.append((trip.limit, c.unit, "stroke limit", _TRIP_COLOR, "-."))
    reach = _limit_lines(ax, limits)
    inset = 0 < peak < reach / _LIMIT_SPAN
    if inset:
        _drive_inset(ax, t, x, peak, unit)
    ax.set_title(title, fontsize="medium", color=_TRIP_COLOR if ours else "black")
    if trip is not None and np.isfinite(getattr(trip, "time", np.nan)):
        ax.axvline(trip.time, color=_TRIP_COLOR, lw=1.5, label=f"{trip.kind} trip")
    over = np.flatnonzero(~(np.abs(x) <= c.full_scale) & np.isfinite(x))
    if over.size:
        ax.plot(t[over], x[over], "x", color=_LIMIT_COLOR, ms=5, label="beyond full scale")
    top = 1.15 * max(reach, peak)  # a refused drive's samples beyond the limits stay visible
    ax.set_ylim(-top, top)
    ax.set_ylabel(_label(drive.names[k], unit))
    ax.grid(True, alpha=0.3)
    ax.legend(loc="lower right" if inset else "upper right", fontsize="small")


def _match_specs(drive: TimeHistory, rig_inputs) -> list:
    """The rig's drive channel specs in the drive's channel order (by name, else by position)."""
    specs = list(rig_inputs)
    by_name = {c.name: c for c in specs}
    if all(n in by_name for n in drive.names):
        return [by_name[n] for n in drive.names]
    if len(specs) != drive.n_channels:
        raise ValueError(
            f"the drive has {drive.n_channels} channels {list(drive.names)} but the rig has "
            f"{len(specs)} drives {[c.name for c in specs]}"
        )
    return specs


def _limit_lines(ax, limits) -> float:
    """Draw each ``±limit`` of ``limits`` ((limit, unit, what, colour, line style) tuples);
    return the largest (the level the axes must reach)."""
    for limit, unit, what, color, ls in limits:
        ax.axhline(limit, color=color, ls=ls, lw=1.0, label=f"± {what} ({limit:g} {unit})")
        ax.axhline(-limit, color=color, ls=ls, lw=1.0)
    return max(limit for limit, *_ in limits)


def _drive_inset(ax, t, x, peak: float, unit: str) -> None:
    """An inset in the upper right of ``ax`` (clear of a drive below a third of the limits, which
    stays inside the middle third of the axes; the legend goes to the lower right) showing the
    drive scaled to its own peak."""
    inset = ax.inset_axes([0.56, 0.64, 0.43, 0.33])
    inset.plot(t, x, color=ACHIEVED_COLOR, lw=0.5)
    inset.set_ylim(-1.45 * peak, 1.45 * peak)  # room for the label
    inset.set_xticks([])
    inset.tick_params(labelsize="x-small")
    inset.text(
        0.01, 0.97, f"scaled to its peak ±{peak:.3g} {unit}", transform=inset.transAxes,
        ha="left", va="top", fontsize="x-small",
    )  # fmt: skip
    inset.grid(True, alpha=0.3)


def repeatability_plot(
    f: np.ndarray,
    rf: np.ndarray,
    snr: np.ndarray,
    names: Sequence[str],
    *,
    band: tuple[float, float] | None = None,
    title: str | None = None,
) -> Figure:
    """Frequency-related repeatability ``R_f(f)`` [%] and signal-to-noise ratio [dB].

    Parameters
    ----------
    f : array (F,)
        Frequencies [Hz] (from :func:`vrig.repeatability.repeatability_function`).
    rf, snr : arrays (F, channels)
        ``R_f`` [%] and :func:`vrig.repeatability.signal_to_noise` [dB].
    names : sequence of str
        Channel names (legend).
    band : (low, high) Hz, optional
        Shaded; the frequency axis ends at twice its upper edge.
    title : str, optional
        Figure title.

    Returns
    -------
    Figure
        Two axes (R_f on top, SNR below), a line per channel in each.
    """
    f = np.asarray(f, dtype=float)
    rf = np.asarray(rf, dtype=float).reshape(f.size, -1)
    snr = np.asarray(snr, dtype=float).reshape(f.size, -1)
    if rf.shape != snr.shape or rf.shape[1] != len(names):
        raise ValueError(
            f"rf {rf.shape} and snr {snr.shape} must both be (F, {len(names)} channels)"
        )
    fmax = f[-1] if band is None else min(f[-1], 2 * band[1])
    fig, (ax_r, ax_s) = _rows(2)
    for k, name in enumerate(names):
        ax_r.plot(f, rf[:, k], lw=1.0, label=name)
        ax_s.plot(f, snr[:, k], lw=1.0, label=name)
    for ax in (ax_r, ax_s):
        if band is not None:
            ax.axvspan(band[0], band[1], color="0.9", zorder=0)
        ax.grid(True, alpha=0.3)
    ax_r.set_ylabel("R_f(f) [%]")
    ax_r.set_ylim(max(-100.0, np.nanmin(rf[f <= fmax]) - 5) if np.isfinite(rf).any() else 0, 102)
    ax_s.set_ylabel("SNR [dB]")
    ax_s.set_xlabel("frequency [Hz]")
    ax_s.set_xlim(0, fmax)
    ax_r.legend(fontsize="small")
    ax_r.set_title(title or "repeatability: PSD spread R_f(f) and repeatable/non-repeatable power")
    return fig


def save_reconstruction_plots(result, folder, rig=None, *, dpi: int = 110) -> list[Path]:
    """Write the PNGs of a reconstruction into ``folder`` (created if missing).

    Files: ``overlay.png`` (FINRES vs DESRES, whole record, the zoom window shaded, each channel's
    error trace beneath it), ``overlay_zoom.png`` (the second with the largest error,
    :func:`worst_error_window`; its title says which; with the error traces), ``psd.png``, ``error_vs_iteration.png`` and, when ``rig`` is given,
    ``drive_vs_limits.png`` (FINDRV against the rig's drive full scales). When the loop stopped on
    a drive that was refused or tripped the rig (``result.rejected_drive``) and ``rig`` is given,
    that drive is plotted against the limits too: ``refused_drive_vs_limits.png`` or
    ``tripped_drive_vs_limits.png``, with the interlock that tripped when ``result.error`` is a
    :class:`~vrig.errors.RigLimitError`. A result with no iteration played (from a
    :class:`~vrig.ReconstructionError`) gets only that plot. Existing files of these names are
    replaced.

    Parameters
    ----------
    result : ReconstructionResult
        The reconstruction (or the result carried by a :class:`~vrig.ReconstructionError`).
    folder : str or os.PathLike
        Where the PNGs go (created if missing).
    rig : rig, optional
        The rig whose drive full scales are plotted against the drives.
    dpi : int, optional
        Resolution of the PNGs, in dots per inch.

    Returns
    -------
    list of Path
        The files written.
    """
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    figures = _rejected_figure(result, rig)
    if len(np.asarray(result.errors)):  # at least one iteration played
        figures.update(_result_figures(result, rig))
    return [save_figure(fig, folder / name, dpi=dpi) for name, fig in figures.items()]


def _rejected_figure(result, rig) -> dict:
    """``{file name: figure}`` of the drive the loop stopped on (refused or tripped), if any."""
    drive = getattr(result, "rejected_drive", None)
    if drive is None or rig is None:
        return {}
    name = result.rejected_name
    kind = "refused" if name.startswith("REFUSED") else "tripped"
    verb = "was refused before it was sent" if kind == "refused" else "tripped the rig"
    error = getattr(result, "error", None)
    trip = error if all(hasattr(error, a) for a in _TRIP_FIELDS) else None
    return {
        f"{kind}_drive_vs_limits.png": drive_vs_limits(
            drive,
            rig.inputs,
            title="\n".join([f"{name}: the drive that {verb}", *wrap(result.stopped[:300], 110)]),
            trip=trip,
        )
    }


def _result_figures(result, rig) -> dict:
    """``{file name: figure}`` of a result with at least one iteration played."""
    best = int(result.best_iteration)
    desired, achieved = result.desired, result.final_response
    errors = np.asarray(result.errors)[best]
    labels = ("desired (DESRES)", f"achieved (IT{best:02d}RES = FINRES)")
    band = tuple(result.bandwidth) if result.bandwidth is not None else None
    zoom = worst_error_window(desired, achieved, width=1.0)
    where = f"zoom: {zoom[0]:.1f}-{zoom[1]:.1f} s, worst error"
    figures = {
        "overlay.png": overlay(
            desired,
            achieved,
            errors=errors,
            labels=labels,
            title=f"response reconstruction: best iteration IT{best:02d} (shaded: {where})",
            mark=zoom,
            error=True,
        ),
    }
    figures["overlay_zoom.png"] = overlay(
        desired,
        achieved,
        window=zoom,
        errors=errors,
        labels=labels,
        title=f"response reconstruction (detail): IT{best:02d}, {where}\n"
        "(the 1 s of largest RMS error, each channel normalised by its desired RMS)",
        error=True,
    )
    figures["psd.png"] = psd_compare(
        desired, achieved, band=band, labels=labels, title="PSD of desired and achieved response"
    )
    figures["error_vs_iteration.png"] = error_vs_iteration(result)
    if rig is not None:
        figures["drive_vs_limits.png"] = drive_vs_limits(
            result.final_drive,
            rig.inputs,
            title=f"final drive FINDRV (IT{best:02d}DRV) and the rig's limits",
        )
    return figures


def save_figure(fig: Figure, path, *, dpi: int = 110) -> Path:
    """Save ``fig`` to ``path`` atomically: an interrupted save leaves the previous file.

    Parameters
    ----------
    fig : Figure
        The matplotlib figure to save.
    path : str or Path
        The image file; its suffix gives the format (``.png``, ``.pdf``, ``.svg``...).
    dpi : int
        Resolution of raster formats, in dots per inch.

    Returns
    -------
    Path
        The written file.
    """
    path = Path(path)
    fmt = path.suffix[1:].lower() or None
    with atomic_write(path) as f:
        fig.savefig(f, format=fmt, dpi=dpi)
    return path
