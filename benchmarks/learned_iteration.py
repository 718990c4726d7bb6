"""Learned drive-iteration strategies against the classic fixed gain (issue 5).

For each rig (shock-absorber, elastomeric-damper), on the ``fast`` environment
(``gymnasium.make("vrig/<Rig>-v1", fast=True)``: reduced-fidelity rig, 4 s pseudo-field
targets, the rig's default tolerance, budget 10 iterations):

1. trains :class:`vrig.policies.BandRatioPolicy` (per-band gains from the observed band-error
   ratios, 7 parameters) by the cross-entropy method on the *training* targets (pseudo-field
   seeds 1..N);
2. evaluates fixed gain 0.5, 0.8, 1.0, the decreasing schedule, the per-band adaptive rule and
   the learned policy on *held-out* targets (pseudo-field seeds 100001.., never used in training),
   each with the same targets and rig-noise seeds (``--quick`` leaves the schedule out);
3. prints mean iterations-to-tolerance (an episode that never meets the tolerance counts as
   budget + 1), success rate and final η0, and the learned policy against the best fixed gain.

    python -m benchmarks.learned_iteration            # full: ~18 min on this busy 2-core box
    python -m benchmarks.learned_iteration --quick    # ~3 min (a smoke run: tiny training)
    python -m benchmarks.learned_iteration --timing   # 10-iteration episode times, fast/default

Episodes run in ``--workers`` processes (default 2), each with its own environment.

Results go to ``results/learned_iteration.json`` (git-ignored).
"""

from __future__ import annotations

import argparse
import json
import multiprocessing as mp
import time
from functools import partial
from pathlib import Path

import gymnasium as gym
import numpy as np

import vrig  # noqa: F401  (registers the environments)
from vrig.envs import ENV_IDS
from vrig.policies import (
    AdaptiveBandGain,
    BandRatioPolicy,
    DecreasingGain,
    FixedGain,
    cross_entropy_search,
    run_episode,
)

_RIG_IDS = {kwargs["rig"]: env_id for env_id, kwargs in ENV_IDS.items() if "rig" in kwargs}
RIGS = {rig: _RIG_IDS[rig] for rig in ("shock-absorber", "elastomeric-damper")}
"""Rig -> its gymnasium id (the side-car's, as registered: :data:`vrig.envs.ENV_IDS`)."""
HELD_OUT_BASE = 100_001
BUDGET = 10

_WORKER: dict = {}


def _make(env_id):
    return gym.make(env_id, fast=True, max_episode_steps=BUDGET)


def _init(env_id):
    """Process-pool initialiser: one environment per worker (model identified once each)."""
    _WORKER["env"] = _make(env_id)


def _policy(env, spec):
    kind, *arg = spec
    if kind == "fixed":
        return FixedGain(env, arg[0])
    if kind == "decreasing":
        return DecreasingGain(env)
    if kind == "adaptive":
        return AdaptiveBandGain(env)
    return BandRatioPolicy(env, np.asarray(arg[0]))


def _episode(job):
    """One episode of a policy spec on one target: (iterations to tolerance, success, final
    mean η0, reason). Target seed s: pseudo-field seed s, rig-noise seed s."""
    spec, seed = job
    env = _WORKER["env"]
    r = run_episode(env, _policy(env, spec), options={"field_seed": seed, "run_seed": seed})
    return r.iterations_to_tolerance(BUDGET), r.success, float(np.mean(r.final_eta0)), r.reason


def _score(rows, tolerance):
    """Training objective: mean iterations-to-tolerance, plus a small term for the final η0
    (relative to the tolerance) that breaks ties, plus 5 per trip."""
    its = np.mean([r[0] for r in rows])
    fin = np.mean([r[2] / tolerance for r in rows])
    trips = np.mean([r[3] in ("limit", "unstable") for r in rows])
    return float(its + 0.25 * fin + 5.0 * trips)


def _summary(rows):
    its = np.array([r[0] for r in rows], float)
    fin = np.array([r[2] for r in rows])
    return {
        "mean_iterations": float(its.mean()),
        "success_rate": float(np.mean([r[1] for r in rows])),
        "mean_final_eta0": float(fin.mean()),
        "max_final_eta0": float(fin.max()),
        "trips": int(sum(r[3] in ("limit", "unstable") for r in rows)),
    }


def run_rig(rig, env_id, args):
    env = _make(env_id)
    tol = env.unwrapped.task.tolerance
    train_seeds = list(range(1, args.train + 1))
    held_out = list(range(HELD_OUT_BASE, HELD_OUT_BASE + args.held_out))
    t0 = time.perf_counter()
    if args.workers > 1:
        pool = mp.get_context("spawn").Pool(args.workers, initializer=_init, initargs=(env_id,))
        pmap = partial(pool.map, chunksize=1)
    else:
        pool, pmap = None, map
        _init(env_id)
    try:

        def generation(_objective, candidates):
            jobs = [(("learned", tuple(c)), s) for c in candidates for s in train_seeds]
            out = list(pmap(_episode, jobs))
            k = len(train_seeds)
            return [_score(out[i * k : (i + 1) * k], tol) for i in range(len(candidates))]

        def report(gen, best, score):
            print(
                f"  [{rig}] generation {gen + 1}/{args.generations}: best objective "
                f"{score:.3f} (params {np.round(best, 2).tolist()}), "
                f"{time.perf_counter() - t0:.0f} s",
                flush=True,
            )

        n = BandRatioPolicy.n_params(env)
        mean = BandRatioPolicy.initial(env, gain=1.0)
        std = np.r_[np.full(n - 3, 0.25), 0.5, 0.3, 0.1]
        best, best_score, _history = cross_entropy_search(
            lambda p: generation(None, [p])[0],
            mean,
            std,
            generations=args.generations,
            population=args.population,
            elite=max(2, args.population // 4),
            seed=0,
            callback=report,
            map_fn=generation,
        )
        train_s = time.perf_counter() - t0
        specs = {
            "fixed 0.5": ("fixed", 0.5),
            "fixed 0.8": ("fixed", 0.8),
            "fixed 1": ("fixed", 1.0),
            "decreasing": ("decreasing",),
            "adaptive per band": ("adaptive",),
            "learned (CEM)": ("learned", tuple(best)),
        }
        if args.quick:
            del specs["decreasing"]
        t1 = time.perf_counter()
        jobs = [(spec, s) for spec in specs.values() for s in held_out]
        out = list(pmap(_episode, jobs))
        k = len(held_out)
        rows = {name: _summary(out[i * k : (i + 1) * k]) for i, name in enumerate(specs)}
        eval_s = time.perf_counter() - t1
    finally:
        if pool is not None:
            pool.close()
            pool.join()
    fixed = {k: v for k, v in rows.items() if k.startswith("fixed")}
    best_fixed = min(
        fixed, key=lambda k: (fixed[k]["mean_iterations"], fixed[k]["mean_final_eta0"])
    )
    learned = rows["learned (CEM)"]
    reduction = 1.0 - learned["mean_iterations"] / fixed[best_fixed]["mean_iterations"]
    env.close()
    return {
        "rig": rig,
        "env": env_id,
        "tolerance_percent": tol,
        "budget": BUDGET,
        "segment_s": env.unwrapped.physics.seconds,
        "train_seeds": train_seeds,
        "held_out_seeds": held_out,
        "learned_params": best.tolist(),
        "train_objective": best_score,
        "table": rows,
        "best_fixed": best_fixed,
        "iteration_reduction": reduction,
        "target_met": bool(
            reduction >= 0.25
            and learned["mean_final_eta0"] <= fixed[best_fixed]["mean_final_eta0"] + 1e-12
        ),
        "train_s": train_s,
        "eval_s": eval_s,
    }


def _print(res):
    print(
        f"\n{res['rig']} ({res['env']}, fast, {res['segment_s']:g} s targets, tolerance "
        f"{res['tolerance_percent']:g} % η0, budget {res['budget']}; "
        f"{len(res['held_out_seeds'])} held-out targets)"
    )
    print(
        f"{'policy':<24} {'iterations':>10} {'success':>8} {'final η0':>9} {'max η0':>8} {'trips':>5}"
    )
    for name, r in res["table"].items():
        print(
            f"{name:<24} {r['mean_iterations']:>10.2f} {100 * r['success_rate']:>7.0f}% "
            f"{r['mean_final_eta0']:>8.3f}% {r['max_final_eta0']:>7.3f}% {r['trips']:>5d}"
        )
    print(
        f"learned vs best fixed ({res['best_fixed']}): {100 * res['iteration_reduction']:+.1f} % "
        f"fewer iterations; target (>= 25 % fewer at equal or lower final η0) "
        f"{'MET' if res['target_met'] else 'MISSED'}; training {res['train_s']:.0f} s, "
        f"evaluation {res['eval_s']:.0f} s"
    )


def episode_times(rigs=("shock-absorber", "elastomeric-damper", "shaker"), repeats=3):
    """Wall time of a 10-iteration episode (reset with IT00 + 10 steps at gain 0.8, tolerance
    out of reach, inverse model already identified), fast and default, per SISO rig."""
    out = {}
    for rig in rigs:
        for label, kw in (("fast", {"fast": True}), ("default", {})):
            env = gym.make("vrig/DriveIteration-v1", rig=rig, tolerance=1e-9, **kw)
            env.reset(seed=0)  # identifies the model (cached) and warms up
            times = []
            for r in range(repeats):
                t = time.perf_counter()
                env.reset(seed=r + 1)
                for _ in range(10):
                    env.step(np.full(env.action_space.shape, 0.8))
                times.append(time.perf_counter() - t)
            env.close()
            out[f"{rig} {label}"] = {"min_s": min(times), "median_s": float(np.median(times))}
            print(
                f"  {rig:<20} {label:<8} 10-iteration episode: min {min(times):.2f} s, "
                f"median {np.median(times):.2f} s",
                flush=True,
            )
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="small training budget (a few minutes)")
    ap.add_argument("--rigs", nargs="+", default=list(RIGS), choices=list(RIGS))
    ap.add_argument("--train", type=int, help="training targets (default 10, quick 4)")
    ap.add_argument("--held-out", type=int, help="held-out targets (default 30, quick 20)")
    ap.add_argument("--generations", type=int, help="CEM generations (default 6, quick 2)")
    ap.add_argument("--population", type=int, help="CEM population (default 10, quick 6)")
    ap.add_argument("--workers", type=int, default=2, help="processes (default 2)")
    ap.add_argument(
        "--timing", action="store_true", help="only time 10-iteration episodes (fast, default)"
    )
    ap.add_argument("--output", default="results/learned_iteration.json")
    args = ap.parse_args(argv)
    quick = args.quick
    if args.timing:
        print("episode wall time (min / median of 3; this machine is shared, so noisy):")
        episode_times()
        return
    args.train = args.train or (4 if quick else 10)
    args.held_out = args.held_out or (20 if quick else 30)
    args.generations = args.generations or (2 if quick else 6)
    args.population = args.population or (6 if quick else 10)
    t0 = time.perf_counter()
    results = []
    for rig in args.rigs:
        res = run_rig(rig, RIGS[rig], args)
        _print(res)
        results.append(res)
    wall = time.perf_counter() - t0
    print(f"\nwall time {wall:.0f} s")
    out = Path(args.output)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps({"quick": quick, "wall_s": wall, "rigs": results}, indent=2))
    print(f"written {out}")


if __name__ == "__main__":
    main()
