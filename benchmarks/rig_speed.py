"""Real-time factor of ``rig.run`` against a raw ``mujoco.rollout`` of the same MJCF.

For each rig: a 60 s band-limited random drive (within the rig's band and limits) is played with
``rig.run`` (servo callback + DAQ), and the same compiled model is rolled out with
``mujoco.rollout`` for the same number of physics steps, no callback, zero controls. Prints the
real-time factors (simulated seconds per wall second) and their ratio. Targets: ratio >= 0.5;
RTF >= 20 for single-input rigs and >= 5 for fuel-tank-7ch.

    python -m benchmarks.rig_speed [--seconds 60] [--rigs shock-absorber ...]
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import mujoco
import numpy as np
from mujoco import rollout

import vrig
from identification import band_limited_noise
from vrig.files import atomic_write


def _drive(rig, seconds, seed=0):
    """Band-limited random drive in the rig's band at half the largest of 10/5/2/1 % of full
    scale (rms) that a 5 s trial plays without an interlock trip."""
    hi = rig.bandwidth[1]
    cutoff = min(max(hi, 5.0), 0.4 * rig.fs) / (rig.fs / 2)
    d = band_limited_noise(int(seconds * rig.fs), len(rig.inputs), cutoff=cutoff, seed=seed)
    full = np.array([c.full_scale for c in rig.inputs])
    for fraction in (0.1, 0.05, 0.02, 0.01):
        try:
            rig.run(d[: int(5 * rig.fs)] * fraction * full, seed=0)
            return d * (fraction / 2) * full  # half of what 5 s passed: margin for the long run
        except vrig.RigLimitError:
            continue
    raise RuntimeError(f"{rig.name}: even a 1 % drive trips an interlock")


def measure(name: str, seconds: float) -> dict:
    rig = vrig.load_rig(name)
    drive = _drive(rig, seconds)
    t0 = time.perf_counter()
    rig.run(drive, seed=1)
    wall = time.perf_counter() - t0
    n_steps = round(seconds / rig.timestep)
    m, d = rig.model, mujoco.MjData(rig.model)
    state = np.empty(mujoco.mj_stateSize(m, mujoco.mjtState.mjSTATE_FULLPHYSICS))
    mujoco.mj_getState(m, d, state, mujoco.mjtState.mjSTATE_FULLPHYSICS)
    ctrl = np.zeros((1, n_steps, m.nu))
    rollout.rollout(m, d, state[None], ctrl[:, :1000])
    t0 = time.perf_counter()
    rollout.rollout(m, d, state[None], ctrl)
    raw = time.perf_counter() - t0
    return {
        "rig": name,
        "inputs": len(rig.inputs),
        "timestep_ms": rig.timestep * 1e3,
        "rtf_run": seconds / wall,
        "rtf_rollout": seconds / raw,
        "ratio": raw / wall,
    }


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--seconds", type=float, default=60.0)
    p.add_argument("--rigs", nargs="*", default=None)
    p.add_argument("--output", default="results/rig_speed.json")
    args = p.parse_args(argv)
    names = args.rigs or vrig.list_rigs()
    rows = []
    print(
        f"{'rig':<20} {'in':>3} {'dt ms':>6} {'RTF run':>9} {'RTF rollout':>12} {'ratio':>6}  targets"
    )
    for name in names:
        r = measure(name, args.seconds)
        # the targets: RTF >= 20 for single-input rigs, >= 5 for the 7-channel rig; other
        # multi-input rigs (fuel-tank-2ch) have no stated RTF target and are reported only
        target = 20.0 if r["inputs"] == 1 else 5.0 if r["inputs"] >= 7 else None
        ok = r["ratio"] >= 0.5 and (target is None or r["rtf_run"] >= target)
        rule = f"RTF >= {target:g}, " if target else "RTF reported, "
        print(
            f"{name:<20} {r['inputs']:>3} {r['timestep_ms']:>6.2f} {r['rtf_run']:>9.1f} "
            f"{r['rtf_rollout']:>12.1f} {r['ratio']:>6.2f}  {rule}ratio >= 0.5: "
            f"{'PASS' if ok else 'MISS'}"
        )
        rows.append({**r, "target_rtf": target, "pass": ok})
    out = Path(args.output)
    out.parent.mkdir(parents=True, exist_ok=True)
    with atomic_write(out, "w", encoding="utf-8") as f:
        f.write(json.dumps(rows, indent=2))
    print(f"results written to {out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
