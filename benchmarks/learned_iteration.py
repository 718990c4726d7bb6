"""Learned and model-updating drive iteration against the classic fixed gain (issues 5, 16, 26).

For each rig (default :data:`DEFAULT_RIGS`: shock-absorber, elastomeric-damper, fuel-tank-2ch,
fuel-tank-7ch; ``--rigs`` takes any rig in ``vrig.envs.ENV_IDS``) and each target kind
(``--targets``, default both :data:`TARGET_KINDS`: pseudo-field records and the rig's service
records, ``target="field"``: its first scenario of :func:`vrig.service.field_scenarios`, each
seed a new road), on the ``fast`` environment (``gymnasium.make(<the rig's id>, fast=True,
max_episode_steps=10, target=...)``: reduced-fidelity rig, 4 s targets, the rig's fast-env
tolerance :data:`FAST_TOLERANCE`, budget 10 iterations):

1. trains :class:`vrig.policies.BandRatioPolicy` (per-band gains from the observed band-error
   ratios, 7 parameters) by the cross-entropy method on the *training* targets of that kind
   (seeds 1..N; starting from the rig's side-car gain, else 1.0), and its phase-aware variant
   on the ``action_mode="complex"`` env (a learned phase per band besides the gains, 11
   parameters: "learned (CEM, phase)"; ``--no-phase`` or ``--quick`` leave it out);
2. evaluates fixed gain 0.5, 0.8, 1.0, the decreasing schedule, the per-band adaptive rule, the
   per-band secant step of the observed response-change ratio (:class:`vrig.policies.SecantBandGain`,
   "secant gain (observed)"), the learned policy, every Stable-Baselines3 model trained for the rig
   (``results/rl/<rig>-sac.zip`` / ``-ppo.zip`` from ``python -m benchmarks.train_rl``, through
   :class:`SB3Policy`; without one the table says how to train it; a model trained on the v1
   observation must be retrained) and - when :class:`vrig.IterationSettings` has the
   ``update`` field - one row per model-updating method ``update <method>``
   (:data:`UPDATE_METHODS`, played by :func:`play_update` as :func:`vrig.reconstruct` with the
   env's settings, desired record, run seed, tolerance and budget, at the rig's own gain
   :func:`rule_gain`; without the field a one-line note says the rows are left out) on
   ``--held-out`` (default 20) *held-out* targets (seeds 100001.., never used in training:
   CEM trains on 1..N, ``train_rl`` on [1, 100000); a seed whose IT00 drive trips the rig,
   whatever the policy, is left out and the next one taken: :func:`playable_targets`), each
   with the same targets and rig-noise seeds (``--quick`` leaves the schedule out);
3. prints mean iterations-to-tolerance (an episode that never meets the tolerance counts as
   budget + 1), success rate, mean and max final η0 and trips, and the best learned or
   model-updating method against the best fixed gain (:func:`compare`): target >= 25 % fewer
   iterations at equal or lower mean final η0, on every rig; where neither ever met the
   tolerance (an unreachable service record) the final η0 at the budget is compared instead
   (>= 25 % lower) and the line says so. "final η0" is the mean over the response channels;
   the tolerance applies to every channel.

    python -m benchmarks.learned_iteration            # full (see below for the time)
    python -m benchmarks.learned_iteration --quick    # a smoke run: tiny CEM, 3 held-out targets
    python -m benchmarks.learned_iteration --timing   # 10-iteration episode times, fast/default

``--quick`` trains CEM on 2 targets for 1 generation of 4 and scores 3 held-out targets per
rig and target kind (no phase variant, no schedule): a smoke run of every code path, not a
result. Episodes run in ``--workers`` processes (default 2), each with its own environment.

Times on the shared 2-core box (issue 5/16 runs, pseudo-field only): the two SISO rigs took
~18 min in full; ``--quick`` then (4 training targets, 2 generations of 6, 20 held-out) took
1.5 min (shock absorber) and 2.5 min (damper). Issue 26 (four rigs x two target kinds, with the
four update-method rows; the box shared with other jobs, load average 2-4 on its 2 cores):
``--quick`` took 391 s (272 s on the quiet box after the throughput work, its last line); ``--held-out 20 --train 4 --generations 2
--population 6 --no-phase`` took 1092 s (1.5-4.5 min per rig and target kind, the seven-channel
tank the slowest). The full default run
(CEM on 10 targets, 6 generations of 10, and its phase variant) was not timed: its CEM plays
1200 training episodes per rig and target kind against the latter's 48.

Results go to ``results/learned_iteration.json`` (git-ignored; written atomically), with a
``policies`` list (policy, rig - ``rig:<scenario>`` on field targets -, target, mean
iterations, success rate, final η0, trips, held-out n) that the benchmark runner's report shows
as its "Policies" leaderboard.
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

import vrig  # registers the environments; vrig.reconstruct plays the update rows
from vrig.envs import ENV_IDS
from vrig.errors import ReconstructionError, RigLimitError
from vrig.files import atomic_write
from vrig.policies import (
    AdaptiveBandGain,
    BandRatioPolicy,
    DecreasingGain,
    EpisodeResult,
    FixedGain,
    Policy,
    SecantBandGain,
    cross_entropy_search,
    run_episode,
)
from vrig.reconstruction import IterationSettings

RIG_IDS = {kwargs["rig"]: env_id for env_id, kwargs in ENV_IDS.items() if "rig" in kwargs}
"""Rig -> its gymnasium id (the side-car's, as registered: :data:`vrig.envs.ENV_IDS`)."""
MIMO_RIG = "fuel-tank-2ch" if "fuel-tank-2ch" in RIG_IDS else "light-truck-front"
"""The multi-channel rig scored by default: the two-channel fuel tank once it has an id."""
DEFAULT_RIGS = ("shock-absorber", "elastomeric-damper", "fuel-tank-2ch", "fuel-tank-7ch")
"""The rigs scored by default (issue 26): the two SISO rigs and the two fuel tanks."""
TARGET_KINDS = ("pseudo-field", "field")
"""The target kinds scored by default: pseudo-field records and the rig's service records
(``target="field"``: its first scenario of :func:`vrig.service.field_scenarios`)."""
UPDATE_METHODS = ("frf", "secant", "reidentify", "ilc")
"""The model-updating iteration methods (``IterationSettings(update=...)``, issue 26) scored as
rows ``update <method>`` when the settings have that field (:func:`update_methods`)."""
FAST_TOLERANCE = {
    "shock-absorber": 5.2,
    "elastomeric-damper": 1.4,
    "fuel-tank-2ch": 17.0,
    "fuel-tank-7ch": 6.5,
}
"""η0 tolerance [%, every channel] of each scored rig's *fast* env, by the rule of :mod:`vrig.envs`.

The side-car tolerances were measured by the rule on the full-fidelity env (20 s targets); this
benchmark runs the fast env (reduced fidelity, 4 s targets), where the same rule - the largest
max-channel η0 at IT07 over ``reset(seed=0..2)`` at the rule's fixed gain (:func:`rule_gain`),
rounded up to two significant figures - gives other figures. Re-measured in issue 26 on the
current twins (the issue-16 figures, 1.1 / 1.6 / 1.9 %, predate the controller noise of issue
23, and no policy met 1.1 % on the shock absorber any more): shock absorber (gain 0.8) 5.14 /
3.96 / 4.85 % -> 5.2 % (side-car 6.1 %); elastomeric damper (gain 0.5) 1.31 / 0.93 / 1.12 % ->
1.4 % (side-car 0.65 %); two-channel fuel tank (split, gain 0.3, its ``gym.gain``) 10.25 /
16.79 / 11.31 % -> 17 % (side-car 8.5 %, measured at full fidelity; at 0.8 the fast env trips
on seed 1 at IT01, 6.07 / 3.60 % on seeds 0 and 2); seven-channel fuel tank (frf, gain 0.5)
6.48 / 3.02 / 3.08 % -> 6.5 % (side-car 14 %, the full-fidelity stall level). The same
tolerance applies to the rig's field targets, which may never reach it (a service record is
not reachable by construction). ``--side-car-tolerance`` scores with the side-car tolerances
instead."""


def env_kwargs_of(rig: str, *, side_car_tolerance: bool = False) -> dict:
    """The ``gymnasium.make`` keywords of ``rig``'s fast env beyond the id's (its
    :data:`FAST_TOLERANCE`, if any).

    Parameters
    ----------
    rig : str
        Rig name.
    side_car_tolerance : bool
        Keep the side-car tolerance (``--side-car-tolerance``): no keyword then.
    """
    if rig not in FAST_TOLERANCE or side_car_tolerance:
        return {}
    return {"tolerance": FAST_TOLERANCE[rig]}


def env_id_of(rig: str) -> str:
    """The registered gymnasium id of ``rig`` (:data:`vrig.envs.ENV_IDS`).

    Parameters
    ----------
    rig : str
        Rig name.
    """
    try:
        return RIG_IDS[rig]
    except KeyError:
        raise ValueError(
            f"rig {rig!r} has no gymnasium id; rigs with one: {', '.join(sorted(RIG_IDS))}"
        ) from None

HELD_OUT_BASE = 100_001
"""First held-out pseudo-field seed (training targets stay below: CEM 1..N,
``benchmarks.train_rl`` [1, 100000))."""
BUDGET = 10
RL_DIR = Path("results/rl")
"""Where ``benchmarks.train_rl`` saves its models (``<rig>-<algo>.zip``)."""
TARGET = 0.25
"""Iteration reduction of the best learned policy against the best fixed gain aimed at on the
SISO rigs (issue 16); on the MIMO rig the aim is any reduction."""

_WORKER: dict = {}


class SB3Policy(Policy):
    """A trained Stable-Baselines3 model as a :class:`vrig.policies.Policy`: the action is
    ``model.predict(obs, deterministic=True)``, clipped to the env's action space.

    Parameters
    ----------
    env : gymnasium.Env
        The drive-iteration env the policy acts on; its observation and action spaces must be
        the model's (same keys and shapes), else ``ValueError``.
    model : stable_baselines3.common.base_class.BaseAlgorithm
        The trained model.
    name : str
        Row label.
    """

    def __init__(self, env, model, name: str = "SB3"):
        super().__init__(env)
        obs_space, act_space = env.observation_space, env.action_space
        mine = {k: v.shape for k, v in obs_space.spaces.items()}
        theirs = {k: v.shape for k, v in getattr(model.observation_space, "spaces", {}).items()}
        if mine != theirs or model.action_space.shape != act_space.shape:
            raise ValueError(
                f"the SB3 model was trained on observations {theirs} and actions "
                f"{model.action_space.shape}; this env has {mine} and {act_space.shape}"
            )
        self.model, self.name = model, name
        self._low, self._high = act_space.low, act_space.high

    @classmethod
    def load(cls, env, path):
        """Load ``<rig>-<algo>.zip`` (``algo`` ``sac`` or ``ppo``, from the name) for ``env``.

        Parameters
        ----------
        env : gymnasium.Env
            The drive-iteration env the policy acts on.
        path : str or Path
            The model file written by ``benchmarks.train_rl``.
        """
        import stable_baselines3 as sb3
        import torch

        torch.set_num_threads(1)
        path = Path(path)
        algo = path.stem.rsplit("-", 1)[-1].upper()
        if algo not in ("SAC", "PPO"):
            raise ValueError(f"{path}: the name must end in -sac.zip or -ppo.zip")
        model = getattr(sb3, algo).load(path, device="cpu")
        return cls(env, model, name=f"SB3 {algo}")

    def __call__(self, obs):
        action, _ = self.model.predict(obs, deterministic=True)
        return np.clip(np.asarray(action, dtype=np.float64).ravel(), self._low, self._high)

    def gains(self, obs):
        """The model's gains for this observation (the action without a re-identify flag).

        Parameters
        ----------
        obs : dict of str to ndarray
            The environment's observation.
        """
        return self(obs)[: self.layout.n_gains]

    def reidentify(self, obs) -> bool:
        """The model's re-identify flag (False when the action has none).

        Parameters
        ----------
        obs : dict of str to ndarray
            The environment's observation.
        """
        return bool(self.layout.reidentify and self(obs)[-1] >= 0.5)


def sb3_models(rig: str, folder=RL_DIR) -> list[Path]:
    """The trained SB3 models of ``rig`` in ``folder`` (``<rig>-sac.zip``, ``<rig>-ppo.zip``).

    Parameters
    ----------
    rig : str
        Rig name.
    folder : str or Path
        Where ``benchmarks.train_rl`` saved them.
    """
    return sorted(p for p in Path(folder).glob(f"{rig}-*.zip") if p.stem[len(rig) + 1 :].isalpha())


def _make(env_id, side_car_tolerance=False, target="pseudo-field", **kwargs):
    # TimeLimit owns truncation: the budget is max_episode_steps
    rig = ENV_IDS[env_id].get("rig")
    extra = env_kwargs_of(rig, side_car_tolerance=side_car_tolerance)
    return gym.make(env_id, fast=True, max_episode_steps=BUDGET, target=target, **extra, **kwargs)


def _env(spec):
    """The worker's env for a policy spec: the ``"complex"``-mode env (made on first use; the
    same rig, targets and cached inverse model) for the phase-aware CEM policy, else the
    ``"bands"`` env."""
    if spec[0] != "learned-complex":
        return _WORKER["env"]
    if "env_complex" not in _WORKER:
        _WORKER["env_complex"] = _make(
            _WORKER["env_id"], _WORKER["side_car_tolerance"], _WORKER["target"],
            action_mode="complex",
        )  # fmt: skip
    return _WORKER["env_complex"]


def _init(env_id, side_car_tolerance=False, target="pseudo-field"):
    """Process-pool initialiser: one environment per worker (model identified once each)."""
    _WORKER.clear()
    _WORKER["side_car_tolerance"] = side_car_tolerance
    _WORKER["env_id"] = env_id
    _WORKER["target"] = target
    _WORKER["env"] = _make(env_id, side_car_tolerance, target)


def _policy(env, spec):
    kind, *arg = spec
    if kind == "fixed":
        return FixedGain(env, arg[0])
    if kind == "decreasing":
        return DecreasingGain(env)
    if kind == "adaptive":
        return AdaptiveBandGain(env)
    if kind == "secant":
        return SecantBandGain(env)
    if kind == "sb3":
        key = ("sb3", arg[0])
        if key not in _WORKER:
            _WORKER[key] = SB3Policy.load(env, arg[0])
        return _WORKER[key]
    return BandRatioPolicy(env, np.asarray(arg[0]))


def update_methods() -> tuple[str, ...]:
    """The model-updating methods to score: :data:`UPDATE_METHODS` when
    :class:`vrig.IterationSettings` has the ``update`` field (issue 26), else none."""
    return UPDATE_METHODS if "update" in IterationSettings.field_names() else ()


def rule_gain(rig) -> float:
    """The rig's own iteration gain, as the tolerance rule of :mod:`vrig.envs` takes it: the
    side-car's ``gym.gain``, else its gym method's gain, else the rig's ``gain``, else 0.8.

    Parameters
    ----------
    rig : Rig
        The rig (one without side-car defaults gives 0.8).
    """
    d = getattr(rig, "defaults", None)
    if d is None:
        return 0.8
    method = d.methods.get(d.gym_method or "arx")
    for gain in (d.gym_gain, getattr(method, "gain", None), d.gain):
        if gain is not None:
            return float(gain)
    return 0.8


_STOP_REASONS = {"converged": "tolerance", "completed": "budget", "refused": "limit",
                 "interlock": "limit", "unstable": "unstable", "diverged": "unstable"}  # fmt: skip
""":func:`vrig.reconstruct`'s ``stop_kind`` -> the env's episode reason."""


def play_update(env, update, *, field_seed, run_seed, gain=None, reconstruct=None):
    """One episode of the model-updating method ``update`` on ``env``'s target ``field_seed``,
    played as :func:`vrig.reconstruct` with ``IterationSettings(update=update)``.

    The same episode as the env's (the same rig, identification settings - hence the same
    initial inverse model - desired record, run seed, tolerance and budget): the settings are
    the env's physics' (``env.unwrapped.physics.settings``) with ``run_seed``, ``gain``,
    ``iterations`` = the budget (:data:`BUDGET`), ``tolerance`` = the env's and no divergence
    stop (an env episode has none); ``update`` None leaves the field out (then the episode is
    the env's fixed-gain one, record for record).

    Parameters
    ----------
    env : gymnasium.Env
        A drive-iteration env (or a wrapper of one): its physics, target and tolerance.
    update : str or None
        The ``update`` setting (``"frf"``, ``"secant"``, ...), or None for the plain update.
    field_seed, run_seed : int
        The target's seed and the run seed, as the env's reset options.
    gain : float, optional
        The iteration gain (default: the rig's own, :func:`rule_gain`).
    reconstruct : callable, optional
        The reconstruction to run (default :func:`vrig.reconstruct`; a test passes a fake).

    Returns
    -------
    EpisodeResult
        ``reason`` as the env's (``"tolerance"``, ``"budget"``, ``"limit"``, ``"unstable"``);
        ``total_reward`` NaN (no reward: not an env episode).
    """
    ph = env.unwrapped.physics
    settings = ph.settings.replace(
        run_seed=int(run_seed), iterations=BUDGET, tolerance=env.unwrapped.task.tolerance,
        gain=rule_gain(ph.rig) if gain is None else float(gain), strategy="fixed",
        divergence=np.inf,
    )  # fmt: skip
    if update is not None:
        settings = settings.replace(update=update)
    try:
        result = (reconstruct or vrig.reconstruct)(ph.rig, ph.target_record(field_seed), settings)
    except ReconstructionError as exc:  # IT00 refused or tripped: nothing iterated
        result = exc.result
    errors = np.asarray(result.errors, dtype=float)
    reason = _STOP_REASONS.get(result.stop_kind, "unstable")
    played = max(len(errors) - 1, 0) + (reason in ("limit", "unstable"))
    return EpisodeResult(
        iterations=played,
        success=reason == "tolerance",
        mean_eta0=[float(e) for e in errors.mean(axis=1)],
        final_eta0=errors[-1] if len(errors) else None,
        total_reward=float("nan"),
        reason=reason,
    )


def _episode(job):
    """One episode of a policy spec on one target: (iterations to tolerance, success, final
    mean η0, reason). Target seed s: pseudo-field (or road) seed s, rig-noise seed s."""
    spec, seed = job
    env = _env(spec)
    if spec[0] == "update":
        r = play_update(env, spec[1], field_seed=seed, run_seed=seed)
    else:
        r = run_episode(env, _policy(env, spec), options={"field_seed": seed, "run_seed": seed})
    final = float(np.mean(r.final_eta0)) if r.final_eta0 is not None else float("nan")
    return r.iterations_to_tolerance(BUDGET), r.success, final, r.reason


def _playable(seed) -> bool:
    """Whether target ``seed``'s IT00 drive plays (the same for every policy: IT00 is
    inverse(DESRES)); a RigLimitError there is the answer False."""
    try:
        _WORKER["env"].reset(options={"field_seed": seed, "run_seed": seed})
    except RigLimitError:
        return False
    return True


def playable_targets(pmap, first: int, n: int, limit: int | None = None):
    """The first ``n`` target seeds from ``first`` upward whose IT00 drive plays, and the
    seeds left out (their IT00 drive trips the rig or exceeds its full scale: the linear inverse
    overshoots a hardening rig, on the calibrated damper about 1 target in 24).

    Parameters
    ----------
    pmap : callable
        ``pmap(fn, seeds)`` (the worker pool's map, or ``map`` in this process).
    first : int
        First seed.
    n : int
        Targets wanted.
    limit : int, optional
        Seeds from ``first`` that may be tried (default ``first + 10 * n``); fewer playable
        targets raise ``RuntimeError``.
    """
    limit = first + 10 * n if limit is None else limit
    seeds, skipped, nxt = [], [], first
    while len(seeds) < n:
        batch = list(range(nxt, min(nxt + n - len(seeds), limit)))
        if not batch:
            raise RuntimeError(f"fewer than {n} playable targets in seeds {first}..{limit - 1}")
        nxt += len(batch)
        for seed, ok in zip(batch, pmap(_playable, batch), strict=True):
            (seeds if ok else skipped).append(seed)
    return seeds, skipped


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
        "held_out": len(rows),
    }


def _train_cem(rig, env, tol, pmap, args, t0, train_seeds, kind="learned"):
    """CEM training of :class:`BandRatioPolicy` on the training targets (``kind``
    ``"learned"``: gains per band; ``"learned-complex"``: gains and phases per band, on the
    ``"complex"``-mode env ``env``); returns (best parameters, best objective)."""

    def generation(_objective, candidates):
        jobs = [((kind, tuple(c)), s) for c in candidates for s in train_seeds]
        out = list(pmap(_episode, jobs))
        k = len(train_seeds)
        return [_score(out[i * k : (i + 1) * k], tol) for i in range(len(candidates))]

    def report(gen, best, score):
        print(
            f"  [{rig}{' complex' if kind != 'learned' else ''}] generation {gen + 1}/{args.generations}: best objective "
            f"{score:.3f} (params {np.round(best, 2).tolist()}), "
            f"{time.perf_counter() - t0:.0f} s",
            flush=True,
        )

    n = BandRatioPolicy.n_params(env)
    nb = env.unwrapped.layout.n_bands
    # start at the rig's own iteration gain (its side-car's: 0.5 on the hardening damper, where
    # 0.8 and 1.0 diverge), else 1.0; phases (complex mode) 0
    gain = getattr(getattr(env.unwrapped.physics.rig, "defaults", None), "gain", None) or 1.0
    mean = BandRatioPolicy.initial(env, gain=gain)
    std = np.r_[np.full(nb, 0.25), 0.5, 0.3, 0.1, np.full(n - nb - 3, 0.3)]
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
    return best, best_score


def _specs(rig, best, args, best_complex=None):
    """The policies scored on the held-out targets, and the SB3 rows that are missing."""
    specs = {
        "fixed 0.5": ("fixed", 0.5),
        "fixed 0.8": ("fixed", 0.8),
        "fixed 1": ("fixed", 1.0),
        "decreasing": ("decreasing",),
        "adaptive per band": ("adaptive",),
        "secant gain (observed)": ("secant",),
        "learned (CEM)": ("learned", tuple(best)),
    }
    if best_complex is not None:
        specs["learned (CEM, phase)"] = ("learned-complex", tuple(best_complex))
    if args.quick:
        del specs["decreasing"]
    models = sb3_models(rig, args.rl_dir) if _has_sb3() else []
    for path in models:
        specs[f"SB3 {path.stem.rsplit('-', 1)[-1].upper()}"] = ("sb3", str(path))
    missing = []
    if not models:
        why = "" if _has_sb3() else " (pip install 'stable-baselines3>=2.3')"
        missing.append(f"SB3: not trained (run python -m benchmarks.train_rl --rig {rig}){why}")
    for update in update_methods():
        specs[f"update {update}"] = ("update", update)
    if not update_methods():
        missing.append(
            "update methods: vrig.IterationSettings has no 'update' field in this build: "
            "their rows are left out"
        )
    return specs, "; ".join(missing) or None


def _has_sb3() -> bool:
    import importlib.util

    return importlib.util.find_spec("stable_baselines3") is not None


CHALLENGERS = ("learned", "SB3", "update", "secant")
"""Row-name prefixes of the learned and model-updating methods compared with the fixed gains
(``secant gain (observed)``: :class:`vrig.policies.SecantBandGain`, the per-band secant step of
the env's observed response-change ratio, a model update through the gains)."""


def compare(rows: dict) -> dict:
    """The best learned or model-updating method against the best fixed gain.

    Best = fewest mean iterations to tolerance, then lowest mean final η0. Target (issue 26, on
    every rig): >= :data:`TARGET` (25 %) fewer iterations at equal or lower mean final η0. When
    neither best ever met the tolerance (success rate 0 for both: an unreachable target, e.g.
    a service record), the iterations say nothing (both budget + 1): the comparison is then
    on the mean final η0 at the budget, target >= 25 % lower (``basis`` says which).

    Parameters
    ----------
    rows : dict
        Policy name -> summary (``mean_iterations``, ``mean_final_eta0``, ``success_rate``);
        fixed gains are named ``fixed ...``, the challengers ``learned ...``, ``SB3 ...`` or
        ``update ...`` or ``secant ...`` (:data:`CHALLENGERS`).

    Returns
    -------
    dict
        ``best_fixed``, ``best_learned`` (the best challenger), ``basis`` (``"iterations"`` or
        ``"final η0"``), ``iteration_reduction`` and ``eta0_reduction`` (fractions, > 0: the
        challenger is better), ``goal`` (the target in words) and ``target_met``.
    """

    def best(names):
        key = lambda k: (rows[k]["mean_iterations"], rows[k]["mean_final_eta0"])  # noqa: E731
        return min(names, key=key)

    best_fixed = best([k for k in rows if k.startswith("fixed")])
    best_learned = best([k for k in rows if k.startswith(CHALLENGERS)])
    f, lrn = rows[best_fixed], rows[best_learned]
    reduction = 1.0 - lrn["mean_iterations"] / f["mean_iterations"]
    eta_reduction = 1.0 - lrn["mean_final_eta0"] / f["mean_final_eta0"]
    unreached = f.get("success_rate", 1.0) == 0 and lrn.get("success_rate", 1.0) == 0
    if unreached:
        met = eta_reduction >= TARGET
        goal = f">= {100 * TARGET:.0f} % lower final η0 (the tolerance was never met)"
    else:
        met = lrn["mean_final_eta0"] <= f["mean_final_eta0"] + 1e-12 and reduction >= TARGET
        goal = f">= {100 * TARGET:.0f} % fewer iterations at equal or lower final η0"
    return {
        "best_fixed": best_fixed,
        "best_learned": best_learned,
        "basis": "final η0" if unreached else "iterations",
        "iteration_reduction": reduction,
        "eta0_reduction": eta_reduction,
        "goal": goal,
        "target_met": bool(met),
    }


def run_rig(rig, env_id, args, target="pseudo-field"):
    """Train CEM on ``rig``'s ``target`` records, then score every policy on held-out ones.

    Parameters
    ----------
    rig : str
        Rig name.
    env_id : str
        Its registered gymnasium id.
    args : argparse.Namespace
        The command line (``train``, ``held_out``, ``generations``, ``population``,
        ``workers``, ``quick``, ``rl_dir``).
    target : str
        The env's ``target`` (:data:`TARGET_KINDS`: ``"pseudo-field"`` or ``"field"``, or
        ``"field:<scenario>"``); training and held-out seeds are its records' seeds.
    """
    side_car = getattr(args, "side_car_tolerance", False)
    env = _make(env_id, side_car, target)
    tol = env.unwrapped.task.tolerance
    t0 = time.perf_counter()
    if args.workers > 1:
        pool = mp.get_context("spawn").Pool(
            args.workers, initializer=_init, initargs=(env_id, side_car, target)
        )
        pmap = partial(pool.map, chunksize=1)
    else:
        pool, pmap = None, map
        _init(env_id, side_car, target)
    try:
        train_seeds, train_skipped = playable_targets(pmap, 1, args.train, HELD_OUT_BASE)
        held_out, skipped = playable_targets(pmap, HELD_OUT_BASE, args.held_out)
        best, best_score = _train_cem(rig, env, tol, pmap, args, t0, train_seeds)
        best_c = score_c = None
        if getattr(args, "phase", False):
            env_c = _make(env_id, side_car, target, action_mode="complex")
            best_c, score_c = _train_cem(
                rig, env_c, tol, pmap, args, t0, train_seeds, kind="learned-complex"
            )
            env_c.close()
        train_s = time.perf_counter() - t0
        specs, missing = _specs(rig, best, args, best_c)
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
    n_inputs = env.unwrapped.physics.n_inputs
    env.close()
    return {
        "rig": rig,
        "env": env_id,
        "target": env.unwrapped.physics.target,
        "n_inputs": n_inputs,
        "tolerance_percent": tol,
        "tolerance_source": "side-car" if side_car or rig not in FAST_TOLERANCE else "fast rule",
        "budget": BUDGET,
        "segment_s": env.unwrapped.physics.seconds,
        "train_seeds": train_seeds,
        "train_seeds_left_out": train_skipped,
        "held_out_seeds": held_out,
        "held_out_left_out": skipped,
        "learned_params": best.tolist(),
        "train_objective": best_score,
        "learned_phase_params": None if best_c is None else best_c.tolist(),
        "train_objective_phase": score_c,
        "table": rows,
        "sb3_missing": missing,
        **compare(rows),
        "train_s": train_s,
        "eval_s": eval_s,
    }


def rig_label(res: dict) -> str:
    """``rig``, or ``rig:<scenario>`` for a result on a field target (the benchmark runner's
    label: :func:`benchmarks.runner.report.rig_label`), so the two target kinds of a rig are
    two columns of the runner's "Policies" table.

    Parameters
    ----------
    res : dict
        A :func:`run_rig` result (``rig``, and ``target`` when it has one).
    """
    target = res.get("target", "pseudo-field")
    return res["rig"] if target == "pseudo-field" else f"{res['rig']}:{target.partition(':')[2]}"


def policy_records(results: list[dict]) -> list[dict]:
    """One record per policy, rig and target kind, for the benchmark runner's "Policies"
    section (``rig`` is :func:`rig_label`'s).

    Parameters
    ----------
    results : list of dict
        :func:`run_rig` results.
    """
    return [
        {
            "policy": name,
            "rig": rig_label(res),
            "target": res.get("target", "pseudo-field"),
            **{k: r[k] for k in ("mean_iterations", "success_rate", "mean_final_eta0")},
            **{k: r[k] for k in ("max_final_eta0", "trips", "held_out")},
            "budget": res["budget"],
            "tolerance_percent": res["tolerance_percent"],
        }
        for res in results
        for name, r in res["table"].items()
    ]


def _print(res):
    print(
        f"\n{res['rig']} on {res.get('target', 'pseudo-field')} targets ({res['env']}, fast, "
        f"{res['segment_s']:g} s targets, tolerance "
        f"{res['tolerance_percent']:g} % η0 on every channel, budget {res['budget']}; "
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
    if res["sb3_missing"]:
        print(res["sb3_missing"])
    if res["held_out_left_out"]:
        print(
            f"held-out seeds left out (their IT00 drive trips the rig, whatever the policy): "
            f"{res['held_out_left_out']}"
        )
    print(
        f"best learned or model-updating ({res['best_learned']}) vs best fixed "
        f"({res['best_fixed']}): {100 * res['iteration_reduction']:+.1f} % fewer iterations, "
        f"{100 * res['eta0_reduction']:+.1f} % lower final η0; compared on {res['basis']}; "
        f"target ({res['goal']}) {'MET' if res['target_met'] else 'MISSED'}; CEM training "
        f"{res['train_s']:.0f} s, evaluation {res['eval_s']:.0f} s"
    )


def episode_times(rigs=("shock-absorber", "elastomeric-damper", "shaker"), repeats=3):
    """Wall time of a 10-iteration episode (reset with IT00 + up to 10 steps at gain 0.8,
    tolerance out of reach, inverse model already identified), fast and default, per SISO rig.
    An episode that ends early (an interlock trip or a diverging drive ends it) is timed as far
    as it went and the iterations it played are printed beside the time."""
    out = {}
    for rig in rigs:
        for label, kw in (("fast", {"fast": True}), ("default", {})):
            env = gym.make("vrig/DriveIteration-v2", rig=rig, tolerance=1e-9,
                           max_episode_steps=10, **kw)  # fmt: skip
            env.reset(seed=0)  # identifies the model (cached) and warms up
            times, played = [], []
            for r in range(repeats):
                t = time.perf_counter()
                env.reset(seed=r + 1)
                steps, ended = 0, False
                while steps < 10 and not ended:
                    *_, terminated, truncated, _ = env.step(np.full(env.action_space.shape, 0.8))
                    steps, ended = steps + 1, terminated or truncated
                times.append(time.perf_counter() - t)
                played.append(steps)
            env.close()
            out[f"{rig} {label}"] = {"min_s": min(times), "median_s": float(np.median(times)),
                                     "iterations": played}  # fmt: skip
            print(
                f"  {rig:<20} {label:<8} 10-iteration episode: min {min(times):.2f} s, "
                f"median {np.median(times):.2f} s (iterations played: "
                f"{', '.join(map(str, played))})",
                flush=True,
            )
    return out


def main(argv=None):
    """Command line (see the module docstring).

    Parameters
    ----------
    argv : list of str, optional
        Arguments (default ``sys.argv[1:]``).
    """
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="small training budget (a few minutes)")
    ap.add_argument(
        "--side-car-tolerance", action="store_true",
        help="score with the side-car tolerances (measured at full fidelity), not FAST_TOLERANCE",
    )  # fmt: skip
    ap.add_argument(
        "--no-phase", dest="phase", action="store_false",
        help="leave out the phase-aware CEM policy (complex action mode)",
    )  # fmt: skip
    ap.add_argument(
        "--rigs", nargs="+", default=list(DEFAULT_RIGS), choices=sorted(RIG_IDS),
        help=f"rigs with a gym id (default {' '.join(DEFAULT_RIGS)})",
    )  # fmt: skip
    ap.add_argument(
        "--targets", nargs="+", default=list(TARGET_KINDS), choices=TARGET_KINDS,
        help="target kinds scored (default: pseudo-field field)",
    )  # fmt: skip
    ap.add_argument("--train", type=int, help="CEM training targets (default 10, quick 2)")
    ap.add_argument("--held-out", type=int, help="held-out targets (default 20, quick 3)")
    ap.add_argument("--generations", type=int, help="CEM generations (default 6, quick 1)")
    ap.add_argument("--population", type=int, help="CEM population (default 10, quick 4)")
    ap.add_argument("--workers", type=int, default=2, help="processes (default 2)")
    ap.add_argument("--rl-dir", type=Path, default=RL_DIR, help="SB3 models (default results/rl)")
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
    args.held_out = args.held_out if args.held_out is not None else (3 if quick else 20)
    if args.held_out < 1:
        ap.error(f"--held-out must be at least 1, got {args.held_out}")
    args.train = args.train or (2 if quick else 10)
    args.generations = args.generations or (1 if quick else 6)
    args.population = args.population or (4 if quick else 10)
    args.phase = args.phase and not quick
    t0 = time.perf_counter()
    results = []
    for rig in args.rigs:
        for target in args.targets:
            res = run_rig(rig, RIG_IDS[rig], args, target)
            _print(res)
            results.append(res)
    wall = time.perf_counter() - t0
    print(f"\nwall time {wall:.0f} s")
    out = Path(args.output)
    out.parent.mkdir(parents=True, exist_ok=True)
    doc = {"quick": quick, "wall_s": wall, "rigs": results, "policies": policy_records(results)}
    with atomic_write(out, "w") as f:
        f.write(json.dumps(doc, indent=2) + "\n")
    print(f"written {out}")


if __name__ == "__main__":
    main()
