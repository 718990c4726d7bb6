"""How an achieved response is scored against the desired one (per channel).

η0 (eq. 5-28, the QanTiM fit with the DC removed), the RMS error and the ratio of the rainflow
pseudo-damage (S-N slope 5) of the achieved response over that of the desired response.
"""

from __future__ import annotations

import numpy as np
import rainflow

from identification import metrics

from ..timehistory import TimeHistory

__all__ = ["DAMAGE_SLOPE", "pseudo_damage", "pseudo_damages", "scores"]

DAMAGE_SLOPE = 5.0
"""S-N (Basquin) slope of the pseudo-damage ratio the iterations report."""


def pseudo_damage(x: np.ndarray, *, slope: float = DAMAGE_SLOPE) -> float:
    """Rainflow pseudo-damage ``sum n_i S_i^slope`` of a record (ranges S_i, counts n_i).

    Parameters
    ----------
    x : ndarray (n_samples,)
        One channel of a record.
    slope : float
        S-N slope (Basquin exponent); 5 for the ratios the iterations report.

    Returns
    -------
    float
        The pseudo-damage, in (the record's unit)^slope.
    """
    return float(
        sum(count * rng**slope for rng, _mean, count, _i, _j in rainflow.extract_cycles(x))
    )


def pseudo_damages(th: TimeHistory) -> np.ndarray:
    """:func:`pseudo_damage` of every channel of ``th`` (slope :data:`DAMAGE_SLOPE`).

    Parameters
    ----------
    th : TimeHistory
        A record, e.g. a desired response scored against many achieved ones (its damages are
        then computed once: :func:`scores`' ``desired_damage``).

    Returns
    -------
    ndarray (n_channels,)
        The pseudo-damage per channel, in (the channel's unit)^slope.
    """
    return np.array([pseudo_damage(th.data[:, k]) for k in range(th.n_channels)])


def scores(desired: TimeHistory, response: TimeHistory, *, desired_damage=None):
    """η0 [%], RMS error [%] and pseudo-damage ratio of ``response`` against ``desired``.

    Parameters
    ----------
    desired, response : TimeHistory
        The processed desired response (DESRES) and an achieved one (ITxxRES), same channels.
    desired_damage : ndarray (n_channels,), optional
        ``pseudo_damages(desired)``, when it is known already (an engine scores every iteration
        against one desired response); default: computed here. The ratios are the same bit for
        bit either way.

    Returns
    -------
    eta0, rms_error, damage_ratio : ndarray (n_channels,)
        η0 (eq. 5-28) and RMS error of the difference in % of the desired response, and the
        pseudo-damage of ``response`` over that of ``desired`` (slope :data:`DAMAGE_SLOPE`).
    """
    eta0 = metrics.qantim_fit_dc(desired.data, response.data)
    rms = metrics.rms_error_percent(desired.data, response.data)
    if desired_damage is None:
        desired_damage = pseudo_damages(desired)
    elif np.shape(desired_damage) != (desired.n_channels,):
        raise ValueError(
            f"desired_damage must hold one value per channel ({desired.n_channels}), got shape "
            f"{np.shape(desired_damage)}"
        )
    dmg = np.array(
        [
            pseudo_damage(response.data[:, k]) / max(float(desired_damage[k]), 1e-300)
            for k in range(desired.n_channels)
        ]
    )
    return eta0, rms, dmg
