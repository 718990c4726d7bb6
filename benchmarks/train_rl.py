"""A standard RL baseline for learned drive iteration: Stable-Baselines3 SAC (or PPO), CPU (issue 16).

Trains an SB3 agent (``MultiInputPolicy`` on the env's ``Dict`` observation, the env's own
reward) on the ``fast`` environment of a rig (``gymnasium.make(<the rig's id in
vrig.envs.ENV_IDS>, fast=True, max_episode_steps=10)``) for a wall-clock budget, then saves

* ``results/rl/<rig>-<algo>.zip`` - the model (``SAC.load`` / ``PPO.load``; scored by
  ``python -m benchmarks.learned_iteration`` through :class:`benchmarks.learned_iteration.SB3Policy`);
* ``results/rl/<rig>-<algo>.json`` - settings, steps, episodes, wall time [s], steps/s and the
  training curve (one point per progress line).

Both are written atomically (``vrig.files.atomic_write``). ::

    pip install torch==2.13.0 "stable-baselines3>=2.3"     # this machine (a CPU build on disk)
    python -m benchmarks.train_rl --rig shock-absorber      # SAC, 25 min
    python -m benchmarks.train_rl --rig elastomeric-damper --algo ppo --minutes 10 --n-envs 2

**Training targets never overlap the held-out ones.** Every reset of a training env goes
through :class:`TrainingTargets`, which draws the pseudo-field seed (and the rig-noise seed)
itself, from ``[TRAIN_SEED_LOW, TRAIN_SEED_HIGH)`` = [1, 100000), and passes them as
``options={"field_seed": ..., "run_seed": ...}``; the env's own redraw (a drawn target whose
IT00 drive trips the rig, drawn from [0, 2**31)) is never used: a target that trips is redrawn
by the wrapper from the same range. The held-out targets of ``learned_iteration.py`` start at
``HELD_OUT_BASE`` = 100001.

**Why SAC by default.** A fast SISO step costs 0.1-0.4 s of rig simulation (idle vs busy
2-core box) and a reset ~1 s more (the new pseudo-field target), so a 25 min budget is a few
thousand env steps: an off-policy learner that re-uses every transition (SAC: one gradient step
per env step from a replay buffer) fits that budget; on-policy PPO discards each rollout after a
few epochs. In a 5 min trial on the shock absorber (``--minutes 5``, both at once; figures in
``benchmarks/README.md``) SAC's mean return over the last 20 episodes was +2.71 at 7.9
iterations per episode, PPO's +1.95 at 9.95. The gains' ``Box`` [0, 2] suits SAC's squashed
Gaussian (PPO's Gaussian is clipped at the bounds: at its initial mean 0 half of its gains are
clipped to 0).

Progress lines every ``--progress`` s (default 20): steps, episodes, steps/s, mean return and
mean iterations (episode length) over the last 20 episodes. ``--minutes`` stops training
cleanly at the budget (a callback) and saves. SAC's training return on this env rises, then
falls (on the shock absorber: a peak after ~500-1500 steps, then towards "never at tolerance";
``benchmarks/README.md``), so by default the saved policy is the one at the best rolling mean
training return over 20 episodes (``--keep best``; training targets only, so no held-out
information is used), ``--keep final`` saves the last one.
"""

from __future__ import annotations

import argparse
import io
import json
import time
from pathlib import Path

import gymnasium as gym
import numpy as np

import vrig  # noqa: F401  (registers the environments)
from benchmarks.learned_iteration import BUDGET, HELD_OUT_BASE, env_id_of, env_kwargs_of
from vrig.errors import RigLimitError
from vrig.files import atomic_write

__all__ = [
    "ALGOS",
    "TRAIN_SEED_HIGH",
    "TRAIN_SEED_LOW",
    "TrainingTargets",
    "main",
    "make_env",
    "make_vec_env",
    "model_path",
    "train",
]

TRAIN_SEED_LOW = 1
TRAIN_SEED_HIGH = 100_000
"""Training pseudo-field (and rig-noise) seeds are drawn from ``[TRAIN_SEED_LOW,
TRAIN_SEED_HIGH)``: below ``HELD_OUT_BASE`` (100001), the first held-out seed."""
assert TRAIN_SEED_HIGH <= HELD_OUT_BASE
ALGOS = ("sac", "ppo")
RESULTS = Path("results/rl")
TARGET_REDRAWS = 8
"""How often :class:`TrainingTargets` redraws a training target whose IT00 drive trips."""


class TrainingTargets(gym.Wrapper):
    """Resets on training targets only: pseudo-field and rig-noise seeds drawn by the wrapper
    from ``[low, high)`` and passed as ``options`` (never the env's own draw).

    ``reset(seed=s)`` seeds the wrapper's generator (Gymnasium's rule: once, then ``None``); a
    target whose IT00 drive trips the rig (:class:`vrig.RigLimitError`) is redrawn from the same
    range up to :data:`TARGET_REDRAWS` times. ``options`` other than ``None`` are refused (they
    could name a held-out target).

    Parameters
    ----------
    env : gymnasium.Env
        A drive-iteration env (``vrig.envs.DriveIterationEnv`` or a wrapper of one).
    low, high : int
        The training seed range ``[low, high)``; ``high`` must not exceed ``HELD_OUT_BASE``.
    """

    def __init__(self, env, low: int = TRAIN_SEED_LOW, high: int = TRAIN_SEED_HIGH):
        super().__init__(env)
        if not (0 <= low < high <= HELD_OUT_BASE):
            raise ValueError(
                f"training seeds [low, high) must satisfy 0 <= low < high <= {HELD_OUT_BASE} "
                f"(the first held-out seed), got [{low}, {high})"
            )
        self.low, self.high = int(low), int(high)
        self._rng = np.random.default_rng()

    def reset(self, *, seed=None, options=None):
        """Reset on a training target drawn from ``[low, high)``.

        Parameters
        ----------
        seed : int, optional
            Seeds the wrapper's generator of training targets.
        options : None
            Must be ``None`` (the wrapper chooses the target).
        """
        if options:
            raise ValueError(f"TrainingTargets chooses the target itself; got options {options}")
        if seed is not None:
            self._rng = np.random.default_rng(seed)
        for attempt in range(TARGET_REDRAWS + 1):
            field, run = (int(s) for s in self._rng.integers(self.low, self.high, size=2))
            try:
                return self.env.reset(options={"field_seed": field, "run_seed": run})
            except RigLimitError:
                if attempt == TARGET_REDRAWS:
                    raise
        raise AssertionError("unreachable")  # pragma: no cover


def make_env(rig: str, *, fast: bool = True, **env_kwargs):
    """One training env of ``rig``: its registered id (looked up in ``vrig.envs.ENV_IDS``),
    the iteration budget as ``max_episode_steps`` (``TimeLimit`` truncates), wrapped in
    :class:`TrainingTargets`.

    Parameters
    ----------
    rig : str
        Rig name with a registered gymnasium id.
    fast : bool
        The reduced-fidelity env (4 s targets).
    **env_kwargs
        Further ``gymnasium.make`` keywords (e.g. ``seconds``, ``action_mode``); the rig's
        :data:`benchmarks.learned_iteration.FAST_TOLERANCE` unless ``tolerance`` is given.
    """
    kwargs = {**env_kwargs_of(rig), **env_kwargs}  # the benchmark's fast tolerance, if any
    env = gym.make(env_id_of(rig), fast=fast, max_episode_steps=BUDGET, **kwargs)
    return TrainingTargets(env)


def make_vec_env(rig: str, n_envs: int = 1, seed: int = 0, *, subproc: bool = False, **env_kwargs):
    """The SB3 vector env of ``n_envs`` training envs (``DummyVecEnv``: one process;
    ``SubprocVecEnv`` with ``subproc``), each in a ``Monitor`` (episode returns and lengths),
    seeded ``seed + i``. The one place that builds training envs (a batched vector env can
    replace it).

    Parameters
    ----------
    rig : str
        Rig name with a registered gymnasium id.
    n_envs : int
        Number of envs.
    seed : int
        Seed of the first env's target generator (env i gets ``seed + i``).
    subproc : bool
        One process per env instead of all in this one.
    **env_kwargs
        Passed to :func:`make_env`.
    """
    from stable_baselines3.common.monitor import Monitor
    from stable_baselines3.common.vec_env import DummyVecEnv, SubprocVecEnv

    if not isinstance(n_envs, int) or n_envs < 1:
        raise ValueError(f"n_envs must be a positive integer, got {n_envs!r}")
    fns = [_EnvFactory(rig, env_kwargs, Monitor) for _ in range(n_envs)]
    venv = (SubprocVecEnv if subproc and n_envs > 1 else DummyVecEnv)(fns)
    venv.seed(seed)
    return venv


class _EnvFactory:
    """Picklable env constructor (``SubprocVecEnv`` sends it to its processes)."""

    def __init__(self, rig, env_kwargs, monitor):
        self.rig, self.env_kwargs, self.monitor = rig, env_kwargs, monitor

    def __call__(self):
        return self.monitor(make_env(self.rig, **self.env_kwargs))


def model_path(rig: str, algo: str, out: Path = RESULTS) -> Path:
    """Where the model of ``rig`` trained with ``algo`` is saved: ``<out>/<rig>-<algo>.zip``.

    Parameters
    ----------
    rig : str
        Rig name.
    algo : {"sac", "ppo"}
        The algorithm.
    out : Path
        Results folder.
    """
    return Path(out) / f"{rig}-{algo}.zip"


BEST_WINDOW = 20
"""Episodes in the rolling mean training return by which the best policy is kept."""


def _budget_callback(seconds: float, progress: float, t0: float, curve: list, log):
    """An SB3 callback: stops at ``t0 + seconds`` (wall clock), every ``progress`` s logs and
    appends a curve point (steps, episodes, wall s, steps/s, mean return, mean iterations), and
    keeps a copy of the policy's parameters at the best rolling mean training return over
    :data:`BEST_WINDOW` episodes (``best``: steps, mean return, parameters)."""
    import copy

    from stable_baselines3.common.callbacks import BaseCallback

    class _Budget(BaseCallback):
        def __init__(self):
            super().__init__()
            self.episodes, self.last = 0, time.perf_counter()
            self.best = {"steps": None, "mean_return": -np.inf, "params": None}

        def _keep_best(self, ended: int) -> None:
            eps = list(self.model.ep_info_buffer)[-BEST_WINDOW:]
            if ended and len(eps) == BEST_WINDOW:
                ret = float(np.mean([e["r"] for e in eps]))
                if ret > self.best["mean_return"]:
                    params = copy.deepcopy(self.model.policy.state_dict())
                    self.best = {"steps": self.num_timesteps, "mean_return": ret, "params": params}

        def _on_step(self) -> bool:
            infos = self.locals.get("infos", [])
            ended = sum("episode" in i for i in infos)
            self.episodes += ended
            self._keep_best(ended)
            now = time.perf_counter()
            if now - self.last >= progress:
                self.last = now
                self.point(now)
            return now - t0 < seconds

        def point(self, now):
            eps = list(self.model.ep_info_buffer)[-20:]
            ret = float(np.mean([e["r"] for e in eps])) if eps else float("nan")
            its = float(np.mean([e["l"] for e in eps])) if eps else float("nan")
            p = {
                "steps": int(self.num_timesteps),
                "episodes": self.episodes,
                "wall_s": round(now - t0, 1),
                "steps_per_s": self.num_timesteps / max(now - t0, 1e-9),
                "mean_return": ret,
                "mean_iterations": its,
            }
            curve.append(p)
            log(
                f"  {p['wall_s']:6.0f} s  {p['steps']:6d} steps  {p['episodes']:5d} episodes  "
                f"{p['steps_per_s']:5.1f} steps/s  mean return {ret:+.3f}  "
                f"mean iterations {its:.2f}"
            )

    return _Budget()


def _print(line: str) -> None:
    print(line, flush=True)


def _model(algo: str, venv, seed: int, overrides: dict):
    from stable_baselines3 import PPO, SAC

    # gamma 0.95: 10-step episodes. SAC: one gradient step per env step (the env is the cost);
    # entropy coefficient auto-tuned from 0.1: from SB3's 1.0 (rewards here are ~0.3 a step) a
    # 20 min run on the shock absorber fell from a mean return of +2.7 to +0.9 (never at
    # tolerance), from 0.1 it kept rising (benchmarks/README.md)
    kw = {
        "sac": {
            "learning_starts": 200, "buffer_size": 100_000, "batch_size": 128,
            "ent_coef": "auto_0.1",
        },
        "ppo": {"n_steps": max(64, 256 // venv.num_envs), "batch_size": 64},
    }[algo]
    kw = {"gamma": 0.95, **kw, **overrides}
    return {"sac": SAC, "ppo": PPO}[algo](
        "MultiInputPolicy", venv, seed=seed, device="cpu", verbose=0, **kw
    )


def train(
    rig: str,
    algo: str = "sac",
    *,
    minutes: float = 25.0,
    n_envs: int = 1,
    seed: int = 0,
    max_steps: int | None = None,
    out: Path = RESULTS,
    progress: float = 20.0,
    subproc: bool = False,
    env_kwargs: dict | None = None,
    algo_kwargs: dict | None = None,
    keep: str = "best",
    log=None,
) -> dict:
    """Train an SB3 agent on the fast env of ``rig`` and save it (model zip + JSON).

    Parameters
    ----------
    rig : str
        Rig name with a registered gymnasium id (``vrig.envs.ENV_IDS``).
    algo : {"sac", "ppo"}
        The algorithm.
    minutes : float
        Wall-clock budget [min], counted from the call (env construction and the inverse-model
        identification included); training stops at the first env step past it.
    n_envs : int
        Training envs (see :func:`make_vec_env`).
    seed : int
        Seed of the agent and of the training-target generators.
    max_steps : int, optional
        Also stop after this many env steps (default: the budget alone decides).
    out : Path
        Results folder (``<out>/<rig>-<algo>.zip`` and ``.json``).
    progress : float
        Seconds between progress lines.
    subproc : bool
        One process per env (``SubprocVecEnv``).
    env_kwargs : dict, optional
        Further ``gymnasium.make`` keywords of the training envs.
    algo_kwargs : dict, optional
        Keywords of the SB3 algorithm overriding this script's (e.g. ``learning_starts``).
    keep : {"best", "final"}
        Which policy is saved: the one at the best rolling mean training return over
        :data:`BEST_WINDOW` episodes (training targets only; the final one when fewer episodes
        ended), or the final one.
    log : callable, optional
        Where progress lines go (default: ``print``, flushed).

    Returns
    -------
    dict
        The record written to ``<out>/<rig>-<algo>.json``.
    """
    import torch

    if algo not in ALGOS:
        raise ValueError(f"algo must be one of {ALGOS}, got {algo!r}")
    if keep not in ("best", "final"):
        raise ValueError(f"keep must be 'best' or 'final', got {keep!r}")
    if not (np.isfinite(minutes) and minutes > 0):
        raise ValueError(f"minutes must be a positive number, got {minutes!r}")
    env_id_of(rig)  # a clear error for a rig without an id, before anything is built
    log = log or _print
    torch.set_num_threads(1)
    t0 = time.perf_counter()
    venv = make_vec_env(rig, n_envs, seed, subproc=subproc, **(env_kwargs or {}))
    model = _model(algo, venv, seed, algo_kwargs or {})
    curve: list = []
    cb = _budget_callback(60.0 * minutes, progress, t0, curve, log)
    total = max_steps if max_steps is not None else 10**9
    model.learn(total_timesteps=total, callback=cb)
    wall = time.perf_counter() - t0
    cb.point(time.perf_counter())
    final_steps = int(model.num_timesteps)
    if keep == "best" and cb.best["params"] is not None:
        model.policy.load_state_dict(cb.best["params"])
    venv.close()
    path = model_path(rig, algo, out)
    path.parent.mkdir(parents=True, exist_ok=True)
    buf = io.BytesIO()
    model.save(buf)
    with atomic_write(path, "wb") as f:
        f.write(buf.getvalue())
    record = {
        "rig": rig,
        "env": env_id_of(rig),
        "algo": algo,
        "policy": "MultiInputPolicy",
        "fast": True,
        "budget_iterations": BUDGET,
        "n_envs": n_envs,
        "seed": seed,
        "minutes_budget": minutes,
        "max_steps": max_steps,
        "algo_kwargs": algo_kwargs or {},
        "env_kwargs": env_kwargs or {},
        "train_seed_range": [TRAIN_SEED_LOW, TRAIN_SEED_HIGH],
        "held_out_base": HELD_OUT_BASE,
        "steps": final_steps,
        "kept": keep if cb.best["params"] is not None else "final",
        "best_steps": cb.best["steps"],
        "best_mean_return": None if cb.best["params"] is None else cb.best["mean_return"],
        "episodes": curve[-1]["episodes"],
        "wall_s": wall,
        "steps_per_s": final_steps / wall,
        "torch_threads": torch.get_num_threads(),
        "model": str(path),
        "curve": curve,
    }
    with atomic_write(path.with_suffix(".json"), "w") as f:
        f.write(json.dumps(record, indent=1) + "\n")
    log(
        f"{rig} {algo}: {record['steps']} steps, {record['episodes']} episodes in {wall:.0f} s "
        f"({record['steps_per_s']:.1f} steps/s) -> {path}"
    )
    return record


def main(argv=None):
    """Command line: ``python -m benchmarks.train_rl --rig RIG [--algo sac|ppo] [--minutes M]``.

    Parameters
    ----------
    argv : list of str, optional
        Arguments (default ``sys.argv[1:]``).
    """
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--rig", default="shock-absorber", help="rig with a gym id (vrig.envs.ENV_IDS)")
    ap.add_argument("--algo", choices=ALGOS, default="sac", help="default sac")
    ap.add_argument("--minutes", type=float, default=25.0, help="wall-clock budget [min]")
    ap.add_argument("--n-envs", type=int, default=1, help="training envs (default 1)")
    ap.add_argument("--subproc", action="store_true", help="one process per env")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument(
        "--keep", choices=("best", "final"), default="best",
        help="save the policy at the best rolling training return (default) or the final one",
    )  # fmt: skip
    ap.add_argument("--max-steps", type=int, help="also stop after this many env steps")
    ap.add_argument("--progress", type=float, default=20.0, help="seconds between progress lines")
    ap.add_argument("--out", type=Path, default=RESULTS, help="results folder (default results/rl)")
    args = ap.parse_args(argv)
    try:
        import stable_baselines3  # noqa: F401
    except ImportError:
        ap.exit(
            2,
            "train_rl needs Stable-Baselines3: pip install torch --index-url "
            "https://download.pytorch.org/whl/cpu && pip install 'stable-baselines3>=2.3'\n",
        )
    try:
        env_id_of(args.rig)
    except ValueError as exc:
        ap.error(str(exc))
    train(
        args.rig,
        args.algo,
        minutes=args.minutes,
        n_envs=args.n_envs,
        seed=args.seed,
        max_steps=args.max_steps,
        out=args.out,
        progress=args.progress,
        subproc=args.subproc,
        keep=args.keep,
    )


if __name__ == "__main__":
    main()
