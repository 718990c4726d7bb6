"""``vrig repeatability``: play one random drive several times; the repeatability number of
§3.1 (Tables 3.1-3.3), R_f and SNR per channel (:mod:`vrig.repeatability`), with a plot."""

from __future__ import annotations

import contextlib
from pathlib import Path

import numpy as np

from ..desired.pseudo_field import pseudo_field
from ..job import CLI_NAMES, check_writable, hold_results_folder
from .common import (
    _UsageError,
    add_band_argument,
    add_rig_argument,
    add_seed_argument,
    check_seconds,
    check_seed,
    load_rig,
    simulation_band,
)


def _add_parser(sub, epilog: str) -> None:
    """Add the `repeatability` subcommand."""
    rep = sub.add_parser(
        "repeatability",
        help="play one random drive several times: the repeatability number of §3.1 (in the drive "
        "band), R_f and SNR per channel",
        epilog=epilog,
    )
    add_rig_argument(rep)
    rep.add_argument("--runs", type=int, default=5, help="number of runs (default 5, as §3.1)")
    rep.add_argument("--seconds", type=float, default=20.0, help="drive length (default 20 s)")
    add_band_argument(
        rep,
        "drive band [Hz] (default: the band of the text's repeatability test of the rig "
        "where the side-car gives one, else as for reconstruct)",
    )
    add_seed_argument(rep)
    rep.add_argument("--out", help="folder of the plot (default ./results/<rig>-repeatability)")


def _run(args) -> int:
    """``vrig repeatability``, holding the lock of ``--out`` from its checks to the end."""
    with contextlib.ExitStack() as hold:  # the plot folder's lock, from the checks to the end
        return _repeatability(args, hold)


def _repeatability(args, hold: contextlib.ExitStack) -> int:
    """``vrig repeatability``; ``hold`` keeps the lock of ``--out``."""
    from ..plots import repeatability_plot, save_figure
    from ..progress import bar
    from ..repeatability import repeatability_function, repeatability_number, signal_to_noise

    if not 2 <= args.runs <= 50:
        raise _UsageError(f"--runs must be 2..50 (the text uses 5), got {args.runs}")
    check_seconds(args.seconds)
    check_seed(args.seed)
    rig = load_rig(args.rig, seed=args.seed)
    text = getattr(getattr(rig, "description", None), "repeatability", None) or {}
    band = simulation_band(rig, text["band"] if args.band is None and text else args.band)
    out = Path(args.out) if args.out else Path("results") / f"{Path(rig.name).stem}-repeatability"
    if out.exists() and not out.is_dir():
        raise _UsageError(f"--out {out} is a file, not a folder")
    check_writable(out, CLI_NAMES)  # before the runs, not after them
    hold_results_folder(hold, out, CLI_NAMES)  # one writer per folder: refused before its runs

    drive, first = pseudo_field(rig, band, args.seconds, seed=args.seed)
    rms = np.sqrt(np.mean(drive.data**2, axis=0)) / [c.full_scale for c in rig.inputs]
    print(f"rig    {rig.name}: {rig.description.title}")
    print(
        f"drive  {args.seconds:g} s random, triangular PSD {band[0]:g}-{band[1]:g} Hz, "
        f"{100 * rms.max():.3g} % of full scale rms, played {args.runs} times"
    )
    runs = [first]  # run 1 of the bar: pseudo_field played the drive once already
    with bar(args.runs, desc=f"{rig.name}: runs", unit="run", initial=1) as runs_bar:
        for k in range(1, args.runs):
            runs.append(rig.run(drive, seed=args.seed + 10_000 + k))
            runs_bar.update(1)
    number = repeatability_number(runs, fs=rig.fs, band=band)  # the text's (Tables 3.1-3.3)
    full = repeatability_number(runs)  # the recorded band, up to the anti-alias filter
    nperseg = int(min(drive.n_samples // 4, 2 ** np.ceil(np.log2(2 * rig.fs))))
    f, rf = repeatability_function(runs, rig.fs, nperseg=nperseg)
    _, snr = signal_to_noise(runs, rig.fs, nperseg=nperseg)
    inband = (f >= band[0]) & (f <= band[1]) & (f > 0)
    names = runs[0].names
    width = max(len(n) for n in names)
    print(
        f"\nrepeatability number (reference text §3.1, Tables 3.1-3.3): 100 - mean eta0 (eq. 5-28) "
        f"of each run against the mean response, responses in the drive band {band[0]:g}-"
        f"{band[1]:g} Hz; full band: the same over everything up to the anti-alias filter"
    )
    numbers = text.get("numbers", {}) if tuple(band) == tuple(text.get("band", ())) else {}
    if numbers:
        print(f"text   {text['table']} in the same band: its number per channel (last column)")
    print(
        f"{'channel':<{width}}  repeatability  full band  R_f in band (mean)  "
        "SNR in band: mean   min" + ("   text" if numbers else "")
    )
    for k, name in enumerate(names):
        quoted = f"  {numbers[name]:>6.2f}%" if name in numbers else ""
        print(
            f"{name:<{width}}  {number[k]:>12.2f}%  {full[k]:>8.2f}%  "
            f"{np.nanmean(rf[inband, k]):>17.1f}%  "
            f"{np.mean(snr[inband, k]):>15.1f} dB {np.min(snr[inband, k]):>5.1f} dB" + quoted
        )
    out.mkdir(parents=True, exist_ok=True)
    fig = repeatability_plot(
        f,
        rf,
        snr,
        names,
        band=band,
        title=f"{rig.name}: repeatability of {args.runs} runs of one drive",
    )
    path = save_figure(fig, out / "repeatability.png", dpi=110)
    print(f"\nplot   {path}")
    return 0
