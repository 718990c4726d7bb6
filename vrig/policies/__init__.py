"""Drive-iteration policies for the ``vrig/`` gymnasium environments, and a gradient-free trainer.

One concept per module:

* :mod:`vrig.policies.gains` - the policies (the gains of each iteration): :class:`Policy`,
  :class:`FixedGain`, :class:`DecreasingGain`, :class:`AdaptiveBandGain`, the secant step of
  the observed response-change ratio :class:`SecantBandGain` and the learned
  :class:`BandRatioPolicy`;
* :mod:`vrig.policies.episodes` - :func:`run_episode` plays one episode and returns an
  :class:`EpisodeResult`;
* :mod:`vrig.policies.search` - :func:`cross_entropy_search`, the optimiser that trains the
  learned policy (``benchmarks/learned_iteration.py``).

Every public name is importable from here (``from vrig.policies import BandRatioPolicy,
cross_entropy_search, run_episode``).
"""

from __future__ import annotations

from .episodes import EpisodeResult, run_episode
from .gains import (
    AdaptiveBandGain,
    BandRatioPolicy,
    DecreasingGain,
    FixedGain,
    Policy,
    SecantBandGain,
)
from .search import cross_entropy_search

__all__ = [
    "AdaptiveBandGain",
    "BandRatioPolicy",
    "DecreasingGain",
    "EpisodeResult",
    "FixedGain",
    "Policy",
    "SecantBandGain",
    "cross_entropy_search",
    "run_episode",
]
