"""A gradient-free optimiser for policy parameters: the cross-entropy method.

:func:`cross_entropy_search` minimises any ``objective(params) -> float`` (the learned
:class:`~vrig.policies.gains.BandRatioPolicy` is trained with it in
``benchmarks/learned_iteration.py``); no GPU, no deep-learning library.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from .gains import _real_array

__all__ = ["cross_entropy_search"]


def cross_entropy_search(
    objective: Callable[[np.ndarray], float],
    mean,
    std,
    *,
    generations: int = 8,
    population: int = 12,
    elite: int = 3,
    seed: int = 0,
    callback: Callable[[int, np.ndarray, float], None] | None = None,
    map_fn: Callable = map,
):
    """Minimise ``objective(params)`` by the cross-entropy method.

    Each generation samples ``population`` parameter vectors from a diagonal Gaussian, keeps
    the ``elite`` best and refits the mean and standard deviation to them (the std is kept
    above 5 % of its initial value). The best vector ever evaluated is returned with its score.
    ``map_fn(objective, candidates)`` evaluates a generation (e.g. a process pool's ``map``; the
    objective must then be picklable).

    Parameters
    ----------
    objective : callable
        ``objective(params) -> float``, the score to minimise.
    mean, std : array_like
        Initial mean and standard deviation of the sampling distribution, one per parameter.
    generations : int, optional
        Number of generations.
    population : int, optional
        Parameter vectors sampled per generation.
    elite : int, optional
        Best vectors kept to refit the distribution.
    seed : int, optional
        Seed of the sampling.
    callback : callable, optional
        ``callback(generation, best_params, best_score)`` after each generation (the best
        vector so far and its score).
    map_fn : callable, optional
        ``map_fn(objective, candidates)`` evaluates a generation (default the built-in ``map``).

    Returns
    -------
    (best_params, best_score, history) : ndarray, float, list of (generation, mean score of the
    elite, best score so far)
    """
    rng = np.random.default_rng(seed)
    mean = _real_array(mean, "cross_entropy_search: mean").copy()
    std = np.broadcast_to(_real_array(std, "cross_entropy_search: std"), mean.shape).copy()
    std_min = 0.05 * std
    best, best_score, history = mean.copy(), float(objective(mean)), []
    for gen in range(generations):
        cands = mean + std * rng.standard_normal((population, mean.size))
        scores = np.array(list(map_fn(objective, list(cands))), dtype=float)
        order = np.argsort(scores, kind="stable")[:elite]
        if scores[order[0]] < best_score:
            best, best_score = cands[order[0]].copy(), float(scores[order[0]])
        mean = cands[order].mean(axis=0)
        std = np.maximum(cands[order].std(axis=0), std_min)
        history.append((gen, float(scores[order].mean()), best_score))
        if callback is not None:
            callback(gen, best, best_score)
    return best, best_score, history
