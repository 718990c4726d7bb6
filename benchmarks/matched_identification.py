"""Identification matched to the target (issue 22, deliverable 5): IT00 η0 at the default, the
rig's side-car and the matched identification level.

    python -m benchmarks.matched_identification [--quick] [--fidelity full|fast]
                                                [--seeds 0 1 2] [--seconds 30]
    python -m benchmarks.matched_identification --rig elastomeric-damper --desired FILE

For each target the inverse models are identified three ways and IT00 (``iterations=0``) is
played: the **default** identification (triangular random drive at 5 % of full scale RMS, what
``vrig.reconstruct`` does unless told), the rig **side-car**'s level where its reconstruction
block sets one (``id_rms``; ``vrig reconstruct`` uses it), and the **matched** one
(``id_match=True``: :mod:`vrig.reconstruction.matching`). Printed per target: its statistics
(RMS, crest factor, kurtosis of DESRES), and per method and identification the mean IT00 η0
[%] over the seeds (min-max in brackets), or the failure, with the identification level used
(% of full scale RMS) and the identification response's peak over the target's.

Targets (``--desired`` replaces them with one record of the given rig):

- ``pseudo-field``: the rig's response to a triangular-PSD drive at 10 % of full scale
  (:func:`vrig.desired.pseudo_field.pseudo_field`, seed :data:`TARGET_SEED`: a seed different from the
  identification seeds, so that no identification drive shares the target drive's random
  phases), on the shock absorber and the elastomeric damper;
- ``slow-ditch``: the damper's response to :func:`slow_ditch_drive`, two large slow half-cosine
  events on a small random background (a stand-in for the text's §6.1.1 slow-ditch field load
  until field-twin records replace it: pass one with ``--desired``).

Methods: ARX at the order of the rig side-car's ``reconstruction.methods.arx.order``, else the
text's table for the rig (damper 6, Table 6.3; shock absorber 4, Table 6.16); vrig's default NARX
(order 4, degree 2, input-polynomial, least squares); the text's NARX (order 4, degree 2, full
condensed terms, simulation focus, Table 6.3).
"""

from __future__ import annotations

import argparse
import time
from collections.abc import Callable

import numpy as np

from benchmarks.method_factories import inverse_arx, inverse_narx
from vrig.reference_figures import figure

__all__ = [
    "TARGET_SEED",
    "identification_levels",
    "methods_for",
    "run_target",
    "slow_ditch_drive",
    "target_statistics",
]

TARGET_SEED = 11
"""Seed of the constructed targets' random drives (the identification seeds are 0, 1, 2)."""
TEXT_ARX_ORDER = {
    f.rig: f.order
    for f in map(figure, ("table-6.3/qantim-6-inverse", "table-6.16/qantim-4-inverse/IT00"))
}
"""The ARX order of the text's table for a rig (Tables 6.3 and 6.16, :mod:`vrig.reference_figures`)
when its side-car sets none."""


def slow_ditch_drive(
    rig,
    seconds: float = 30.0,
    *,
    event_times=None,
    event_signs=(-1.0, 1.0),
    event_seconds: float = 2.5,
    event_fraction: float = 0.25,
    background_fraction: float = 0.03,
    seed: int = TARGET_SEED,
):
    """A slow-ditch-like drive: large slow half-cosine events on a small random background.

    Each event is ``sign * event_fraction * full_scale * cos(pi (t - t_c) / event_seconds)`` for
    ``|t - t_c| <= event_seconds / 2`` (a half cosine: zero at both ends, its peak at ``t_c``);
    the first goes one way and the second the other, so both sides of an asymmetric specimen are
    loaded. The background is a triangular-PSD random drive over the rig's test band at
    ``background_fraction`` of full scale RMS, faded in and out over 1 s. Every drive channel gets
    the same shape (independent backgrounds).

    Parameters
    ----------
    rig : Rig
        The rig (its drives' full scale, ``fs`` and ``bandwidth``).
    seconds : float
        Record length [s].
    event_times : sequence of float, optional
        Event centres [s] (default: at 30 % and 70 % of the record).
    event_signs : sequence of float
        Event directions (+1, -1), one per event.
    event_seconds : float
        Duration of each event [s].
    event_fraction : float
        Event peak as a fraction of full scale.
    background_fraction : float
        Background RMS as a fraction of full scale.
    seed : int
        Seed of the background.

    Returns
    -------
    TimeHistory
        The drive (DESDRV), at ``rig.fs``.
    """
    from scipy.signal.windows import tukey

    import vrig
    from vrig.signals import random_drive, triangular_psd

    if event_times is None:
        event_times = (0.3 * seconds, 0.7 * seconds)
    if len(event_times) != len(event_signs):
        raise ValueError("give one sign per event")
    fs = rig.fs
    n = round(seconds * fs)
    t = np.arange(n) / fs
    full = np.array([c.full_scale for c in rig.inputs])
    bg = random_drive(triangular_psd(tuple(rig.bandwidth)), n, fs, channels=full.size,
                      rms=background_fraction * full, seed=seed).data  # fmt: skip
    bg = (bg - bg.mean(axis=0)) * tukey(n, min(1.0, 2.0 / seconds))[:, None]
    events = np.zeros(n)
    for tc, sign in zip(event_times, event_signs, strict=True):
        m = np.abs(t - tc) <= event_seconds / 2
        events[m] += sign * np.cos(np.pi * (t[m] - tc) / event_seconds)
    data = bg + event_fraction * events[:, None] * full
    return vrig.TimeHistory(data, fs, [c.name for c in rig.inputs], [c.unit for c in rig.inputs])


def target_statistics(rig, desired, band=None) -> dict:
    """RMS, peak, crest factor, kurtosis and half-energy amplitude over peak of DESRES (the desired record processed over the
    simulation band), per channel.

    Parameters
    ----------
    rig : Rig
        The rig (its default band).
    desired : TimeHistory
        The desired response.
    band : (float, float), optional
        Simulation band [Hz] (default: the rig's).

    Returns
    -------
    dict of ndarray
    """
    from vrig.processing import gprepro
    from vrig.reconstruction.defaults import default_band
    from vrig.reconstruction.matching import half_energy_amplitude

    y = gprepro(desired, band or default_band(rig)).data
    rms = np.sqrt(np.mean(y**2, axis=0))
    peak = np.abs(y).max(axis=0)
    kurt = np.mean(y**4, axis=0) / rms**4
    half = half_energy_amplitude(y) / peak
    return {"rms": rms, "peak": peak, "crest": peak / rms, "kurtosis": kurt,
            "half_energy_over_peak": half}  # fmt: skip


def methods_for(rig) -> list[tuple[str, str, Callable]]:
    """(label, side-car method name, factory) of the methods compared on ``rig``.

    Parameters
    ----------
    rig : Rig
        The rig (its side-car's method defaults).

    Returns
    -------
    list of tuple
    """
    stem = rig.name.split("/")[-1].removesuffix(".xml")
    order = rig.defaults.method("arx").order or TEXT_ARX_ORDER.get(stem, 4)
    m = rig.defaults.method("narx")
    no, nd = m.order or 4, m.degree or 2
    return [
        (f"ARX({order})", "arx", inverse_arx(order)),
        (f"NARX({no},{nd}) least squares", "narx", inverse_narx(no, nd)),
        (
            f"NARX({no},{nd}) full, simulation focus",
            "narx",
            inverse_narx(no, nd, kind="full", focus="simulation"),
        ),
    ]


def identification_levels(rig, method_name: str) -> dict:
    """The identification settings compared: ``default``, ``side-car`` (only where the rig's
    side-car sets an ``id_rms`` for the method) and ``matched``.

    Parameters
    ----------
    rig : Rig
        The rig.
    method_name : str
        ``"arx"`` or ``"narx"`` (the side-car's method block).

    Returns
    -------
    dict
        label -> settings (``reconstruct`` keywords).
    """
    d = rig.defaults
    m = d.method(method_name)
    level = m.id_rms if m.id_rms is not None else d.id_rms
    out = {"default": {}}
    if level is not None:
        out[f"side-car {100 * level:g} %"] = {
            "id_rms": tuple(level * c.full_scale for c in rig.inputs)
        }
    out["matched"] = {"id_match": True}
    return out


def _it00(rig, desired, factory, options: dict, seed: int):
    """(mean IT00 η0 or a failure string, identification report, seconds)."""
    import vrig

    t0 = time.perf_counter()
    try:
        res = vrig.reconstruct(rig, desired, method=factory(), iterations=0, seed=seed, **options)
    except vrig.ReconstructionError as exc:
        kind = exc.result.stop_kind
        return f"{exc.stage}: {kind}", exc.result.identification, time.perf_counter() - t0
    return float(res.errors[0].mean()), res.identification, time.perf_counter() - t0


def run_target(rig, desired, *, seeds=(0, 1, 2), log=print) -> list[dict]:
    """IT00 η0 of every method at every identification level on one target.

    Parameters
    ----------
    rig : Rig
        The rig.
    desired : TimeHistory
        The desired response (the rig's outputs at ``rig.fs``).
    seeds : sequence of int
        Identification (and run) seeds; each cell is their mean.
    log : callable
        Where progress lines go.

    Returns
    -------
    list of dict
        One row per method and level: ``method``, ``level``, ``eta0`` (per seed: a float or
        a failure string), ``id_rms_percent`` and ``id_peak_ratio`` (per seed, the largest over
        the channels), ``reason`` (of the first seed).
    """
    rows = []
    for label, name, factory in methods_for(rig):
        for level, options in identification_levels(rig, name).items():
            row = {"method": label, "level": level, "eta0": [], "id_rms_percent": [],
                   "id_peak_ratio": [], "id_half_energy_ratio": [], "reason": ""}  # fmt: skip
            for seed in seeds:
                eta, report, dt = _it00(rig, desired, factory, options, seed)
                row["eta0"].append(eta)
                if report:
                    row["id_rms_percent"].append(max(report["rms_percent"]))
                    row["id_peak_ratio"].append(max(report["peak_ratio"]))
                    row["id_half_energy_ratio"].append(max(report["half_energy_ratio"]))
                    row["reason"] = row["reason"] or report["reason"]
                shown = f"{eta:.1f} %" if isinstance(eta, float) else eta
                log(f"    {label}, {level}, seed {seed}: IT00 η0 {shown} ({dt:.0f} s)")
            rows.append(row)
    return rows


def _cell(values) -> str:
    ok = [v for v in values if isinstance(v, float)]
    bad = [v for v in values if not isinstance(v, float)]
    if not ok:
        return f"failed ({bad[0]})"
    text = f"{np.mean(ok):6.1f}" + (f" [{min(ok):.1f}-{max(ok):.1f}]" if len(ok) > 1 else "")
    return text + (f", {len(bad)} failed ({bad[0]})" if bad else "")


def report(title: str, stats: dict, rows: list[dict]) -> str:
    """One target's table as text.

    Parameters
    ----------
    title : str
        The target's heading.
    stats : dict
        :func:`target_statistics` of the target.
    rows : list of dict
        :func:`run_target`'s rows.

    Returns
    -------
    str
    """

    def values(key):
        return ", ".join(f"{v:.3g}" for v in stats[key])

    lines = [
        title,
        f"  DESRES: rms {values('rms')}; crest factor {values('crest')}; kurtosis "
        f"{values('kurtosis')} (Gaussian: 3); half-energy amplitude / peak "
        f"{values('half_energy_over_peak')} (Gaussian: ~0.35)",
        f"  {'method':<36} {'identification':<15} {'IT00 η0 [%] mean [min-max]':<30} "
        f"{'ID rms':>7} {'ID/target: peak':>15} {'half-energy':>11}",
    ]
    for r in rows:
        rms, pk, he = (
            f"{np.mean(r[k]):.3g}" if r[k] else "-"
            for k in ("id_rms_percent", "id_peak_ratio", "id_half_energy_ratio")
        )
        lines.append(
            f"  {r['method']:<36} {r['level']:<15} {_cell(r['eta0']):<30} {rms + ' %':>7} "
            f"{pk:>15} {he:>11}"
        )
    lines += [
        f"  matched level (first seed): {r['reason']}" for r in rows if r["level"] == "matched"
    ][:1]
    return "\n".join(lines)


def _targets(args, log):
    """(title, rig, desired) of every target of the run."""
    import vrig
    from vrig.desired.pseudo_field import pseudo_field
    from vrig.reconstruction.defaults import default_band

    if args.desired is not None:
        rig = vrig.load_rig(args.rig, fidelity=args.fidelity)
        desired = vrig.io.read(args.desired)
        if args.seconds is not None:
            desired = desired.window(0.0, args.seconds)
        yield f"{args.desired} on {rig.name}", rig, desired
        return
    seconds = args.seconds or (20.0 if args.quick else 30.0)
    for name in args.rigs:
        rig = vrig.load_rig(name, fidelity=args.fidelity)
        log(f"{name}: pseudo-field target, {seconds:g} s, seed {TARGET_SEED}")
        _, desired = pseudo_field(rig, default_band(rig), seconds, seed=TARGET_SEED)
        yield f"{name} ({rig.variant}): pseudo-field, {seconds:g} s", rig, desired
    if args.no_ditch:
        return
    rig = vrig.load_rig("elastomeric-damper", fidelity=args.fidelity)
    drive = slow_ditch_drive(rig, seconds)
    desired = rig.run(drive, seed=TARGET_SEED + 10_000)
    yield (
        f"elastomeric-damper ({rig.variant}): slow-ditch-like, {seconds:g} s (two 2.5 s "
        "half-cosine events at 25 % of full scale, 3 % rms background)",
        rig,
        desired,
    )


def main(argv=None) -> int:
    """Command line: run the targets, print the tables.

    Parameters
    ----------
    argv : list of str, optional
        Arguments (default ``sys.argv[1:]``).

    Returns
    -------
    int
        Exit status.
    """
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--quick", action="store_true", help="20 s records, seeds 0 and 1")
    p.add_argument("--fidelity", choices=("full", "fast"), default="full")
    p.add_argument("--seeds", type=int, nargs="+", default=None)
    p.add_argument("--seconds", type=float, default=None, help="record length [s]")
    p.add_argument("--desired", default=None, help="a desired record (any vrig.io format)")
    p.add_argument("--rig", default="elastomeric-damper", help="the rig of --desired")
    p.add_argument(
        "--rigs",
        nargs="+",
        default=["shock-absorber", "elastomeric-damper"],
        help="rigs of the pseudo-field targets",
    )
    p.add_argument("--no-ditch", action="store_true", help="skip the slow-ditch-like target")
    args = p.parse_args(argv)
    seeds = args.seeds or ((0, 1) if args.quick else (0, 1, 2))
    t0 = time.perf_counter()
    parts = []
    for title, rig, desired in _targets(args, print):
        print(title, flush=True)
        rows = run_target(rig, desired, seeds=seeds)
        parts.append(report(title, target_statistics(rig, desired), rows))
    print()
    print(
        f"IT00 η0 (eq. 5-28) of DESRES, fidelity {args.fidelity}, identification seeds "
        f"{', '.join(map(str, seeds))}; python -m benchmarks.matched_identification "
        f"({time.perf_counter() - t0:.0f} s)\n"
    )
    print("\n\n".join(parts))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
