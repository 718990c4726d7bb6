"""Statistics of every rig's service records (field twins, issue 22), beside its pseudo-field record.

    python -m benchmarks.field_records [--seconds 30] [--seed 0]

For every shipped rig with a service scenario (``vrig.field_scenarios``) and each scenario: the field
twin's record over the scenario's default road (``vrig.field_record``) and, beside it, the rig's own
pseudo-field record (``vrig.pseudo_field``), per response channel after the simulation band's
pre-processing (de-trend, DC removal, band-limit: what the reconstruction takes as DESRES): RMS, peak,
crest factor (peak / RMS), excess kurtosis (0 for a Gaussian record), and the peak as a fraction of
the rig's transducer range. A Gaussian record of a few thousand samples has a crest factor of about
3.5-4 and an excess kurtosis within about ±0.1; service records with discrete events (a ditch, a
bump, pavé) sit clearly above.
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from scipy.stats import kurtosis


def channel_statistics(record, rig, band) -> list[dict]:
    """Per channel of ``record`` after the simulation band's pre-processing: RMS, peak, crest
    factor, excess kurtosis and the peak as a fraction of the rig's transducer range."""
    from vrig.processing import gprepro

    x = np.asarray(gprepro(record, band).data)
    out = []
    for j, o in enumerate(rig.outputs):
        rms = float(np.sqrt(np.mean(x[:, j] ** 2)))
        peak = float(np.abs(x[:, j]).max())
        out.append({
            "channel": o.name, "unit": o.unit, "rms": rms, "peak": peak,
            "crest": peak / rms if rms > 0 else float("nan"),
            "kurtosis": float(kurtosis(x[:, j])), "of_range": peak / o.full_scale,
        })  # fmt: skip
    return out


def _lines(label: str, stats: list[dict]) -> list[str]:
    return [
        f"  {label:<22} {s['channel']:<20} {s['rms']:>10.4g} {s['peak']:>10.4g} {s['unit']:<11}"
        f" {s['crest']:>6.2f} {s['kurtosis']:>8.2f} {100 * s['of_range']:>7.1f} %"
        for s in stats
    ]


def main(argv=None) -> int:
    import vrig
    from vrig.desired.kinds import desired_response
    from vrig.reconstruction.defaults import default_band

    ap = argparse.ArgumentParser(prog="python -m benchmarks.field_records",
                                 description=__doc__.split("\n")[0])  # fmt: skip
    ap.add_argument("--seconds", type=float, default=30.0, help="record length [s] (default 30)")
    ap.add_argument("--seed", type=int, default=0, help="road / drive seed (default 0)")
    args = ap.parse_args(argv)
    print(f"{'':2}{'record':<22} {'channel':<20} {'rms':>10} {'peak':>10} {'unit':<11} "
          f"{'crest':>6} {'kurtosis':>8} {'of range':>9}")  # fmt: skip
    for name in vrig.list_rigs():
        scenarios = vrig.field_scenarios(name)
        if not scenarios:
            continue
        rig = vrig.load_rig(name)
        band = default_band(rig)
        print(f"{name} (band {band[0]:g}-{band[1]:g} Hz)")
        for target in ["pseudo-field"] + [f"field:{s}" for s in scenarios]:
            t0 = time.perf_counter()
            record = desired_response(rig, target, args.seconds, seed=args.seed)[0]
            took = time.perf_counter() - t0
            for line in _lines(target, channel_statistics(record, rig, band)):
                print(line)
            print(f"  {'':<22} ({args.seconds:g} s record made in {took:.1f} s)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
