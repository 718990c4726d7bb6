# ---
# jupyter:
#   jupytext:
#     text_representation:
#       extension: .py
#       format_name: percent
#   kernelspec:
#     display_name: Python 3
#     language: python
#     name: python3
# ---

# %% [markdown]
# # Iteration policies in the gymnasium environment
#
# `import vrig` registers drive iteration as [gymnasium](https://gymnasium.farama.org)
# environments: one step is one iteration, and the **action is the iteration gain** — one per
# drive channel and frequency band. A *policy* decides the gains from what it observes (the
# error per band and how it changed). This tutorial compares the classic fixed gains with the
# adaptive rules of `vrig.policies` on the shock-absorber rig and trains a small learned policy
# by the cross-entropy method — without a GPU or a deep-learning library.
#
# It is deliberately small (the reduced-fidelity environment, `fast=True`: 4 s targets; a few
# targets; two generations of training) so that it runs in under a minute;
# `python -m benchmarks.learned_iteration` is the full-size comparison on held-out targets.

# %%
# %matplotlib inline
import time

import gymnasium as gym
import matplotlib.pyplot as plt
import numpy as np

import vrig  # noqa: F401  (registers the vrig/ environments)
from vrig.plots import plain_log_ticks
from vrig.policies import (
    AdaptiveBandGain,
    BandRatioPolicy,
    DecreasingGain,
    FixedGain,
    cross_entropy_search,
    run_episode,
)

t0 = time.perf_counter()
env = gym.make("vrig/ShockAbsorber-v2", fast=True)
obs, info = env.reset(seed=0)
print(f"environment ready in {time.perf_counter() - t0:.1f} s")
print("observation:", {k: v.shape for k, v in obs.items()})
print("action space:", env.action_space)
print("band edges [Hz]:", env.unwrapped.edges)
print(f"IT00 eta0 {info['eta0']} %, tolerance {env.unwrapped.task.tolerance} %")

# %% [markdown]
# The inverse model is identified once per environment (seeded by `model_seed`), so episodes are
# cheap: `reset()` draws a new pseudo-field desired response and plays IT00, each `step(gains)`
# plays one more iteration. The observation holds, per output and band, the log10 ratio of the
# band's RMS error to the desired response's (`band_error`), its change since the last iteration,
# the realised / predicted response-change ratio of the last correction (`change_ratio`,
# `change_phase`: what a model update uses), η0 and drive levels. The episode **terminates** when every channel's η0 is within the rig's
# tolerance and is **truncated** after 10 iterations (by gymnasium's `TimeLimit` wrapper:
# `max_episode_steps` of `gym.make`; the environment itself never truncates and
# `run_episode` reports the reason `"budget"`); the reward is the log reduction of the
# mean η0 (minus a small drive-energy penalty; −5 for a refused or tripping drive; +1 on the
# step that meets the tolerance).
#
# ## Baselines
#
# Evaluate each policy on the same few targets: `options={"field_seed": s, "run_seed": s}` fixes
# the desired response and the rig noise of an episode.

# %%
targets = [{"field_seed": s, "run_seed": s} for s in (101, 102, 103)]
policies = {
    "fixed 0.5": FixedGain(env, 0.5),
    "fixed 0.8": FixedGain(env, 0.8),
    "fixed 1.0": FixedGain(env, 1.0),
    "decreasing 1.2 x 0.85^n": DecreasingGain(env),
    "adaptive per band": AdaptiveBandGain(env),
}
results = {}
for name, policy in policies.items():
    runs = [run_episode(env, policy, options=o) for o in targets]
    results[name] = runs
    its = [r.iterations_to_tolerance(10) for r in runs]
    print(f"{name:26s} iterations to tolerance {its}  (mean {np.mean(its):.2f}; 11 = never)  "
          f"final mean eta0 {np.mean([r.mean_eta0[-1] for r in runs]):.2f} %")

# %%
fig, ax = plt.subplots(figsize=(8, 3.8))
for name, runs in results.items():
    ax.semilogy(runs[0].mean_eta0, "o-", ms=3, label=name)
ax.axhline(env.unwrapped.task.tolerance, color="k", ls="--", lw=1, label="tolerance")
ax.set_xlabel("iteration")
ax.set_ylabel("mean η0 [%]")
plain_log_ticks(ax.yaxis)  # 2, 5, 10 rather than "2 × 10^0"
ax.set_title(f"one target (field seed {targets[0]['field_seed']})", fontsize=10)
ax.legend(fontsize=8)
plt.show()

# %% [markdown]
# ## A learned policy
#
# `BandRatioPolicy` sets each band's gain from what it observes,
# `g_b = exp(θ_b + α·change_b + β·(error_b + 1) + γ·n)`: a band whose error grew gets less gain, a
# band still far from its target more. Its few parameters are found by the **cross-entropy
# method**: sample parameter vectors around a mean, keep the best few, refit the mean and spread,
# repeat. The cost is the mean number of iterations to tolerance on training targets (different
# from the evaluation targets above).

# %%
train = [{"field_seed": s, "run_seed": s} for s in (1, 2)]


def cost(params):
    runs = [run_episode(env, BandRatioPolicy(env, params), options=o) for o in train]
    return float(np.mean([r.iterations_to_tolerance(10) for r in runs]))


start = BandRatioPolicy.initial(env, gain=1.0)
t0 = time.perf_counter()
best, score, history = cross_entropy_search(cost, start, 0.3, generations=2, population=4, elite=2)
print(f"trained in {time.perf_counter() - t0:.0f} s: training cost {cost(start):.2f} -> {score:.2f} "
      f"iterations; history {history}")

learned = BandRatioPolicy(env, best)
runs = [run_episode(env, learned, options=o) for o in targets]
its = [r.iterations_to_tolerance(10) for r in runs]
print(f"{'learned (2 generations)':26s} iterations to tolerance {its}  (mean {np.mean(its):.2f})  "
      f"final mean eta0 {np.mean([r.mean_eta0[-1] for r in runs]):.2f} %")

# %% [markdown]
# With two generations on two training targets this is a demonstration of the mechanics, not a
# result: three evaluation targets cannot separate policies that differ by a fraction of an
# iteration. The README and `benchmarks/learned_iteration.py` give the full-size comparison (30
# held-out targets on each of the two SISO damper rigs; there the learned policy needs 12–14 %
# fewer iterations than the best fixed gain).
#
# Any gymnasium agent can be trained the same way — e.g. Stable-Baselines3 with
# `gymnasium.wrappers.FlattenObservation` around the environment (the `rl` extra installs it;
# not needed for anything here). `action_mode="channels"` or `"scalar"` makes the action one
# gain per drive channel or one gain in all; `action_mode="complex"` adds a phase per channel and
# band (in ±`phase_max` rad: the band's correction is advanced or delayed in phase, for an
# inverse model whose phase is off); `reidentify_action=True` lets the agent also decide
# when to re-fit the inverse model from the latest run.
