"""Playing one episode of a drive-iteration policy: :func:`run_episode` -> :class:`EpisodeResult`.

The runner the baselines and the learned policy are compared with (``tests/test_policies.py``,
``benchmarks/learned_iteration.py``): ``env.reset``, then the policy's action each step until the
episode terminates (tolerance met, a trip) or is truncated (the iteration budget of the
``TimeLimit`` wrapper, ``gymnasium.make(..., max_episode_steps=n)``: reason ``"budget"``).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

__all__ = ["EpisodeResult", "run_episode"]


@dataclass
class EpisodeResult:
    """One episode of :func:`run_episode`.

    Attributes
    ----------
    iterations : int
        Steps played (iterations after IT00).
    success : bool
        True when the tolerance was met.
    mean_eta0 : list of float
        Mean η0 over the response channels per iteration, IT00 first, in %.
    final_eta0 : ndarray (n_outputs,) or None
        η0 per response channel at the end, in %.
    total_reward : float
        Sum of the step rewards.
    reason : str
        Why the episode ended: the env's ``info["reason"]`` (``"tolerance"``, ``"limit"``,
        ``"unstable"``), or ``"budget"`` when the ``TimeLimit`` wrapper truncated it.
    """

    iterations: int
    success: bool
    mean_eta0: list = field(default_factory=list)
    final_eta0: np.ndarray | None = None
    total_reward: float = 0.0
    reason: str = ""

    def iterations_to_tolerance(self, budget: int) -> int:
        """Iterations after IT00 until the tolerance was met; ``budget + 1`` if never.

        Parameters
        ----------
        budget : int
            The episode's iteration budget (returned plus one when the tolerance was never met).
        """
        return self.iterations if self.success else budget + 1


def run_episode(env, policy, *, seed=None, options=None) -> EpisodeResult:
    """Play one episode of ``policy`` on ``env``.

    Parameters
    ----------
    env : gymnasium.Env
        A :class:`vrig.envs.DriveIterationEnv` (or a wrapper of one); its action layout sets the
        shape of the actions. The episode's budget is its ``TimeLimit`` (the env itself never
        truncates: an env without one runs until it terminates).
    policy : Policy
        The policy (reset after ``env.reset``, then called with each observation).
    seed : int, optional
        Seed of ``env.reset``.
    options : dict, optional
        Options of ``env.reset``.
    """
    obs, info = env.reset(seed=seed, options=options)
    policy.reset()
    res = EpisodeResult(0, bool(info["success"]), [info["mean_eta0"]], info["eta0"])
    done = False
    while not done:
        obs, reward, terminated, truncated, info = env.step(policy(obs))
        res.iterations += 1
        res.total_reward += float(reward)
        res.mean_eta0.append(info["mean_eta0"])
        res.final_eta0, res.success, res.reason = (
            info["eta0"],
            bool(info["success"]),
            "budget" if truncated and not terminated else info["reason"],
        )
        done = terminated or truncated
    return res
