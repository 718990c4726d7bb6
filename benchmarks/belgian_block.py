"""The Belgian-block road record reconstructed on fuel-tank-7ch (issue 22, deliverable 4a).

A real road-load measurement (``vrig.desired.belgian_block``: six wheel accelerations, 256 Hz, 300 s of Belgian
pavé at 20 km/h) becomes the desired response of fuel-tank-7ch's four vertical accelerations by
the documented F2D and scaling rule (:func:`vrig.desired.belgian_block.belgian_block_desired`), and
:func:`vrig.reconstruct` plays it on the rig at its default settings (fidelity full, the default
variant, method ARX, every other value resolved as ``vrig reconstruct`` resolves it:
:func:`vrig.reconstruction.defaults.resolve`; the identification drive halved until the rig
accepts it). Prints the reachability check at the record's own level and at the scaled level,
the scaling rule's factor and what set it, the iteration table, IT00 and the best η0 per
channel, whether an interlock tripped (which limit, on which channel), and the lateral and
longitudinal responses (not controlled) under the best drive played on the whole rig. Writes
``results/belgian_block.json`` atomically (``results/`` is git-ignored).

    python -m benchmarks.belgian_block [--seconds 60] [--iterations 5] [--start 5]
                                       [--drive-fraction 0.5] [--seed 0]

Skips with a message (exit 0) when the public data folder is absent.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

import vrig
from vrig.desired.belgian_block import belgian_block_desired, belgian_block_path, belgian_block_rig
from vrig.desired.reachability import check_target, scale_to_limits
from vrig.files import atomic_write
from vrig.reconstruction.defaults import default_band, resolve
from vrig.reconstruction.id_drive import identification_run


def _targets(view, seconds: float, start: float, seed: int, drive_fraction: float):
    """The record at its own level, its check, the rule's factor, the scaled target and its
    check (one identification run, the one reconstruct makes with the same seed)."""
    band = default_band(view)
    physical = belgian_block_desired(view, seconds=seconds, start=start, scale=1.0)
    level = resolve(view, method="arx", bandwidth=band).settings.id_rms  # reconstruct's own
    run = identification_run(view, band, round(seconds * view.fs), level, seed=seed)
    iddrv, idres = run.drive, run.response
    own = check_target(view, physical, id_drive=iddrv, id_response=idres)
    rule = scale_to_limits(view, physical, own, drive_fraction=drive_fraction)
    desired = physical.with_data(physical.data * rule.factor)
    scaled = check_target(view, desired, id_drive=iddrv, id_response=idres)
    return desired, own, rule, scaled


def _play(view, desired, args):
    """(result or None, error text): the reconstruction at the rig's defaults (resolved as
    every door resolves them: :func:`vrig.reconstruction.defaults.resolve`)."""
    try:
        result = vrig.reconstruct(
            view,
            desired,
            method="arx",
            iterations=args.iterations,
            seed=args.seed,
            progress=True,
        )
    except vrig.ReconstructionError as exc:
        return exc.result, f"{exc.stage}: {exc}"
    return result, ""


def _horizontals(rig, result, seed: int) -> dict:
    """RMS and peak of the uncontrolled responses under the best drive on the whole rig."""
    if result is None or result.best_iteration < 0:
        return {}
    try:
        full = rig.run(result.final_drive, seed=seed + 999)
    except vrig.RigLimitError as exc:
        return {"error": str(exc)}
    names = [c.name for c in rig.outputs if not c.name.startswith(("LF", "RF", "LR", "RR"))]
    data = full[names].data - full[names].data.mean(axis=0)
    return {
        n: {"rms": float(data[:, k].std()), "peak": float(np.abs(data[:, k]).max())}
        for k, n in enumerate(names)
    }


def _report(result, error: str) -> dict:
    """IT00, best, stop and interlock of a reconstruction (or of one that failed before IT00)."""
    errors = np.asarray(result.errors) if result is not None else np.zeros((0, 0))
    played = errors.shape[0] > 0
    kind = getattr(result, "stop_kind", "") if result is not None else ""
    return {
        "channels": list(result.desired.names) if result is not None else [],
        "it00_eta0_percent": errors[0].tolist() if played else None,
        "best_iteration": int(result.best_iteration) if played else None,
        "best_eta0_percent": errors[result.best_iteration].tolist() if played else None,
        "iterations_run": int(errors.shape[0] - 1) if played else -1,
        "stop_kind": kind or None,
        "stopped": (result.stopped if result is not None else "") or None,
        "interlock": kind in ("interlock", "refused") or bool(error),
        "rejected": getattr(result, "rejected_name", "") or None,
        "error": error or (str(result.error) if getattr(result, "error", None) else None),
    }


def _print(rule, own, scaled, result, report, horizontals) -> None:
    print("\nthe record at its own level (g -> m/s^2):\n" + own.table())
    print(f"\nscaling rule: {rule.describe()}\n\nthe desired response:\n" + scaled.table())
    if result is not None and report["it00_eta0_percent"] is not None:
        print("\n" + result.table())
        for name, a, b in zip(
            report["channels"],
            report["it00_eta0_percent"],
            report["best_eta0_percent"],
            strict=True,
        ):
            print(
                f"{name:<16}  IT00 η0 {a:6.2f} %   best (IT{report['best_iteration']:02d}) "
                f"{b:6.2f} %"
            )
    print(
        f"\ninterlock tripped: {'yes' if report['interlock'] else 'no'}"
        + (f" ({report['rejected']}: {report['error']})" if report["interlock"] else "")
    )
    print(f"stopped: {report['stopped'] or 'after all iterations'}")
    for name, v in horizontals.items():
        text = v if isinstance(v, str) else f"RMS {v['rms']:.3g} m/s^2, peak {v['peak']:.3g} m/s^2"
        print(f"not controlled: {name:<18} {text}")


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--seconds", type=float, default=60.0, help="window length [s] (default 60)")
    p.add_argument("--start", type=float, default=5.0, help="window start in the record [s]")
    iterations = vrig.IterationSettings.iterations  # vrig reconstruct's
    p.add_argument("--iterations", type=int, default=iterations,
                   help=f"iterations after IT00 (default {iterations})")  # fmt: skip
    p.add_argument(
        "--drive-fraction",
        type=float,
        default=0.5,
        help="scaling rule: fraction of every actuator limit (default 0.5)",
    )
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--output", default="results/belgian_block.json")
    args = p.parse_args(argv)
    try:
        belgian_block_path()
    except FileNotFoundError as exc:
        print(f"Belgian-block benchmark skipped: {exc}")
        return 0
    t0 = time.perf_counter()
    rig = vrig.load_rig("fuel-tank-7ch", seed=args.seed)
    view = belgian_block_rig(rig)
    desired, own, rule, scaled = _targets(
        view, args.seconds, args.start, args.seed, args.drive_fraction
    )
    result, error = _play(view, desired, args)
    report = _report(result, error)
    horizontals = _horizontals(rig, result, args.seed)
    _print(rule, own, scaled, result, report, horizontals)
    record = {
        "benchmark": "belgian_block",
        "rig": rig.name,
        "variant": rig.variant,
        "fidelity": "full",
        "settings": {
            "seconds": args.seconds,
            "start": args.start,
            "iterations": args.iterations,
            "seed": args.seed,
            "resolved": None if result is None else result.resolved,
            "drive_fraction": args.drive_fraction,
        },
        "scale": {"factor": rule.factor, "binding": rule.binding, "rule": rule.describe()},
        "check_own_level": own.to_dict(),
        "check": scaled.to_dict(),
        "reconstruction": report,
        "uncontrolled_responses": horizontals,
        "wall_s": time.perf_counter() - t0,
    }
    out = Path(args.output)
    out.parent.mkdir(parents=True, exist_ok=True)
    with atomic_write(out, "w", encoding="utf-8") as f:
        f.write(json.dumps(record, indent=2) + "\n")
    print(f"\nresults written to {out} ({record['wall_s']:.0f} s)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
