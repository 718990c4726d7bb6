"""Throughput of batched rig runs (issue 16, deliverable 2): rig runs and drive-iterations per
minute, one after another against ``rig.run_batch`` / ``play_batch`` across threads.

A rig run is ``rig.run(drive)`` of a 4 s band-limited random drive (fast fidelity); a
drive-iteration is one :meth:`DriveIteration.play <vrig.reconstruction.engine.DriveIteration.
play>` (check, rig run, processing, scores), each engine with its own desired response. Rigs:
the shock absorber (SISO) and fuel-tank-7ch (7 drives). For each rig and batch size (8, 16) the
batch is played one after another (``single``) and batched with 2 and 4 threads; every batched
result is checked bit for bit against the single one (``identical``). Figures are per wall
minute on this machine (``os.cpu_count()`` and the load average are printed: threads beyond the
free cores only share them).

The gym section (``--env``, on by default) counts drive iterations per minute of the gymnasium
environments (fast, 4 s targets, gain 0.8 every step, the tolerance out of reach so every
episode runs its ``max_episode_steps=10`` iterations and resets: a reset makes a new pseudo-field
target, rig runs too, plays IT00 and counts as an iteration): one env, and ``num_envs`` envs as
gymnasium's ``SyncVectorEnv``, as vrig's batched :class:`~vrig.envs.DriveIterationVectorEnv`
with each resetting sub-env making its target in turn (``batch_targets=False``, as before issue
26) and with the targets of all resetting sub-envs in one batch (the default,
``gymnasium.make_vec``'s for a vrig id). The modes of a rig run one after another in one
process, so their ratios (``x one env``, ``x serial targets``) are the figures to compare on a
shared box; beside the wall-clock rate each row has the CPU time per iteration of the process and
of the calling thread (the serial part: with ``T`` threads on free cores an iteration takes about
``main + (cpu - main) / T``), and of MuJoCo's rollouts alone in every thread (``physics``: the
floor no change outside MuJoCo can lower; ``2 cores at best`` is ``60 s / (physics / 2)``, the
rate if two cores did nothing but step the physics).

    python -m benchmarks.rig_batch [--quick] [--rigs shock-absorber fuel-tank-7ch] [--no-env]
"""

from __future__ import annotations

import argparse
import os
import threading
import time

import numpy as np

import vrig
from identification import band_limited_noise
from vrig.reconstruction.engine import DriveIteration, play_batch

SECONDS = 4.0
EPISODE_STEPS = 10  # the gym section's episodes: a reset (new target, IT00) every 11th step


def _fraction(rig) -> float:
    """The largest of 3 / 1 / 0.5 % of full scale (rms) at which four trial drives run without
    an interlock trip (fuel-tank-7ch trips its force interlock at 3 %)."""
    for fraction in (0.03, 0.01, 0.005):
        out = rig.run_batch([_drive(rig, s, fraction) for s in range(4)], return_exceptions=True)
        if not any(isinstance(r, Exception) for r in out):
            return fraction
    raise RuntimeError(f"{rig.name}: even a 0.5 % drive trips an interlock")


def _drive(rig, seed: int, fraction: float = 0.03) -> np.ndarray:
    """A band-limited random drive in the rig's band at ``fraction`` of full scale (rms)."""
    cutoff = min(max(rig.bandwidth[1], 5.0), 0.4 * rig.fs) / (rig.fs / 2)
    d = band_limited_noise(int(SECONDS * rig.fs), len(rig.inputs), cutoff=cutoff, seed=seed)
    return d * fraction * np.array([c.full_scale for c in rig.inputs])


def _per_minute(count: int, seconds: float) -> float:
    return 60.0 * count / seconds


def _timed(fn):
    t0 = time.perf_counter()
    out = fn()
    return out, time.perf_counter() - t0


def _runs(rig, xs, threads_list) -> list[tuple[str, float, bool]]:
    """(mode, rig runs per minute, identical to single) for one batch of drives."""
    seeds = list(range(1, len(xs) + 1))
    ref, wall = _timed(lambda: [rig.run(x, seed=s).data for x, s in zip(xs, seeds, strict=True)])
    rows = [("single", _per_minute(len(xs), wall), True)]
    for threads in threads_list:
        got, wall = _timed(lambda t=threads: rig.run_batch(xs, seeds=seeds, threads=t))
        same = all(np.array_equal(g.data, r) for g, r in zip(got, ref, strict=True))
        rows.append((f"batch {threads} threads", _per_minute(len(xs), wall), same))
    return rows


def _plays(rig, xs, threads_list, fraction) -> list[tuple[str, float, bool]]:
    """(mode, drive-iterations per minute, identical to single) for one batch of engines."""
    name = rig.name
    engines = []
    for k in range(len(xs)):  # each its own desired response: a response of a twin rig
        desired = vrig.load_rig(name, seed=50 + k, fidelity="fast").run(_drive(rig, 60 + k, fraction))
        engines.append(DriveIteration(rig, desired, run_seed=100 + k))
    ref, wall = _timed(lambda: [e.play(x, 1) for e, x in zip(engines, xs, strict=True)])
    rows = [("single", _per_minute(len(xs), wall), True)]
    for threads in threads_list:
        got, wall = _timed(lambda t=threads: play_batch(engines, xs, 1, threads=t))
        same = all(
            np.array_equal(g[2].data, r[2].data) and np.array_equal(g[3][0], r[3][0])
            for g, r in zip(got, ref, strict=True)
        )
        rows.append((f"batch {threads} threads", _per_minute(len(xs), wall), same))
    return rows


class _PhysicsClock:
    """Counts the CPU time [s] spent inside ``mujoco.rollout`` by every thread of the rigs
    (:mod:`vrig.rigs.mujoco_rig` calls it through its module attribute ``rollout``, replaced
    here by a timing proxy while the clock is installed)."""

    def __init__(self):
        import vrig.rigs.mujoco_rig as mujoco_rig

        self._module, self._real = mujoco_rig, mujoco_rig.rollout
        self._lock, self.seconds = threading.Lock(), 0.0

    def rollout(self, *args, **kwargs):
        """``mujoco.rollout.rollout``, timed (CPU time of the calling thread)."""
        t0 = time.thread_time()
        try:
            return self._real.rollout(*args, **kwargs)
        finally:
            with self._lock:
                self.seconds += time.thread_time() - t0

    def __enter__(self):
        self._module.rollout = self
        return self

    def __exit__(self, *exc):
        self._module.rollout = self._real


def _env_rate(env, n: int, steps: int) -> tuple[float, float, float, float]:
    """Drive iterations per minute of ``steps`` vector steps of ``env`` (n sub-envs) after a reset
    (the first reset, identification included, is not timed; the autoresets of the timed steps
    are: a new target and its IT00 play, one iteration), and the CPU time per iteration [ms] of
    the process (every thread), of the calling thread alone (the part no worker thread shares:
    on a loaded box these say more than the wall clock) and of the MuJoCo rollouts (every
    thread)."""
    env.reset(seed=0)
    action = np.full(env.action_space.shape, 0.8)
    with _PhysicsClock() as physics:
        t0, cpu0, main0 = time.perf_counter(), time.process_time(), time.thread_time()
        for _ in range(steps):
            env.step(action)
        wall, cpu, main = (time.perf_counter() - t0, time.process_time() - cpu0,
                           time.thread_time() - main0)  # fmt: skip
    k = 1e3 / (n * steps)
    return _per_minute(n * steps, wall), k * cpu, k * main, k * physics.seconds


def env_throughput(rig: str, n: int, steps: int) -> list[tuple[str, float, float, float, float]]:
    """(mode, drive iterations per minute, CPU ms per iteration, calling-thread CPU ms per
    iteration, MuJoCo rollout CPU ms per iteration) of one env and of ``n`` envs: sync, batched
    with the targets made in turn, batched with the targets batched (episodes of 10
    iterations)."""
    import gymnasium as gym

    from vrig.envs import ENV_IDS

    env_id = next(i for i, kw in ENV_IDS.items() if kw.get("rig") == rig)
    kw = {"fast": True, "tolerance": 1e-9, "max_episode_steps": EPISODE_STEPS}
    rows = []
    for label, make in (
        ("one env", lambda: gym.make_vec(env_id, 1, vectorization_mode="sync", **kw)),
        (f"sync x{n}", lambda: gym.make_vec(env_id, n, vectorization_mode="sync", **kw)),
        (
            f"batched x{n}, serial targets",
            lambda: gym.make_vec(env_id, n, batch_targets=False, **kw),
        ),
        (f"batched x{n}", lambda: gym.make_vec(env_id, n, **kw)),
    ):
        env = make()
        try:
            k = env.num_envs
            cycles = max(1, round(steps / (k * (EPISODE_STEPS + 1))))  # whole episodes:
            rows.append((label, *_env_rate(env, k, cycles * (EPISODE_STEPS + 1))))  # resets too
        finally:
            env.close()
    return rows


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--quick", action="store_true", help="batch size 8, 2 threads only")
    p.add_argument("--rigs", nargs="+", default=["shock-absorber", "fuel-tank-7ch"])
    p.add_argument("--no-env", action="store_true", help="leave out the gym section")
    p.add_argument("--no-rig", action="store_true", help="leave out the rig / engine section")
    args = p.parse_args(argv)
    sizes, threads = ([8], [2]) if args.quick else ([8, 16], [2, 4])
    print(f"rig batch throughput: {SECONDS:g} s drives, fast fidelity, "
          f"os.cpu_count() = {os.cpu_count()}, load average {os.getloadavg()[0]:.1f} "
          "(a shared, loaded box gives the threads no free core)")  # fmt: skip
    header = f"{'rig':<16} {'batch':>5}  {'mode':<18} {'runs/min':>9} {'iter/min':>9}  identical"
    print(header)
    print("-" * len(header))
    for name in [] if args.no_rig else args.rigs:
        rig = vrig.load_rig(name, seed=0, fidelity="fast")
        fraction = _fraction(rig)  # also compiles the callbacks and makes the clones
        for size in sizes:
            xs = [_drive(rig, s, fraction) for s in range(size)]
            runs = _runs(rig, xs, threads)
            plays = _plays(rig, xs, threads, fraction)
            for (mode, rpm, same_r), (_, ipm, same_p) in zip(runs, plays, strict=True):
                same = "yes" if same_r and same_p else "NO"
                print(f"{name:<16} {size:>5}  {mode:<18} {rpm:>9.0f} {ipm:>9.0f}  {same}")
    if not args.no_env:
        n, steps = (4, 44) if args.quick else (8, 176)
        print(f"\ngym drive iterations per minute (fast, 4 s targets, {n} envs, gain 0.8, "
              f"episodes of {EPISODE_STEPS} iterations, load average "
              f"{os.getloadavg()[0]:.1f}):")  # fmt: skip
        for name in args.rigs:
            base = serial = None
            for label, rate, cpu, main, physics in env_throughput(name, n, steps):
                base = base or rate
                serial = rate if "serial targets" in label else serial
                ratio = f"x{rate / serial:.2f} serial targets" if serial and rate != serial else ""
                print(f"{name:<16} {label:<28} {rate:>7.0f} iterations/min  cpu {cpu:5.1f} "
                      f"ms/it, main thread {main:5.1f} ms/it, physics {physics:5.1f} ms/it "
                      f"(2 cores at best {60e3 / (physics / 2):5.0f}/min)  x{rate / base:.2f} "
                      f"one env  {ratio}", flush=True)  # fmt: skip
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
