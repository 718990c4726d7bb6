"""The result of a reconstruction: every iteration played, its scores and why it stopped."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..timehistory import TimeHistory
from .settings import IterationSettings

__all__ = ["STOP_KINDS", "ReconstructionResult", "best_iteration"]

STOP_KINDS = (
    "completed",
    "converged",
    "interlock",
    "refused",
    "diverged",
    "unstable",
    "model",
    "law",
    "failed",
    "interrupted",
)
"""The values of :attr:`ReconstructionResult.stop_kind`, the machine-readable stop reason:

``completed``  every iteration asked for was played
``converged``  stopped early because the iteration met its tolerance
``interlock``  a drive tripped an interlock of the rig (stroke, force, following error, range)
``refused``    a drive beyond the drives' full scale was refused before it was sent
``diverged``   η0 grew beyond ``divergence`` x the best, the inverse model diverged on a
               response, or the drive update was not finite
``unstable``   the rig's simulation became unstable (a MuJoCo warning or a non-finite state)
``model``      the inverse model could not be (re-)fitted (e.g. an unstable model)
``law``        a user's control law raised (:class:`~vrig.errors.ControlLawError`: the law's
               file and line are in ``stopped``)
``failed``     any other error
``interrupted`` Ctrl-C (``SIGINT``): :func:`vrig.reconstruct` raises
               :class:`~vrig.ReconstructionInterrupted` with the iterations played

``""`` while a reconstruction is running.
"""


@dataclass
class ReconstructionResult:
    """Everything a reconstruction produced (QanTiM names).

    Attributes
    ----------
    desired : TimeHistory
        DESRES: the desired response after processing (GPREPRO over ``bandwidth``).
    method : Method
        The identified method (its inverse model) the drives were computed with.
    bandwidth : (low, high) Hz
        The simulation band.
    errors : ndarray (n_iterations_run + 1, n_outputs)
        η0 [%] (eq. 5-28) of ITxxRES against DESRES, IT00 first.
    rms_errors : ndarray, same shape
        RMS error [%] of ITxxRES against DESRES (means removed).
    damage_ratio : ndarray, same shape
        Rainflow pseudo-damage of ITxxRES over that of DESRES (S-N slope 5).
    drives, responses, raw_responses : list of TimeHistory
        ITxxDRV, ITxxRES (processed) and RITxxRES (raw) per iteration.
    best_iteration : int
        The iteration kept (:func:`best_iteration`): the smallest mean η0 among the iterations
        where no channel's η0 exceeds its IT00 value (IT00 itself always qualifies), so a better
        mean bought by making one channel worse than the model's first drive is never the one
        kept (a test engineer signs off per channel: a channel worse than IT00 means the
        iteration damaged what the inverse model got right). ``final_drive``/``final_response``
        are its records. ``-1`` when no iteration was played (the result of a
        :class:`~vrig.ReconstructionError`).
    id_drive, id_response : TimeHistory or None
        IDDRV and IDRES (raw); ``None`` when the identification drive could not be played.
    stopped : str
        Why the loop stopped before the last iteration ("" when it ran them all).
    stop_kind : str
        The same, machine-readable: one of :data:`STOP_KINDS` (``"completed"`` when it ran them
        all); for a failure before IT00 (:class:`~vrig.ReconstructionError`) the kind of the
        error that stopped the identification, the fit or IT00.
    error : BaseException or None
        The exception that stopped the loop (None when it completed or diverged; the
        :class:`KeyboardInterrupt` of a Ctrl-C).
    rejected_name, rejected_drive : str, TimeHistory or None
        The drive that was refused before it was sent (``"REFUSEDxx"``, ``"REFUSEDID"`` for the
        identification drive) or that tripped the rig (``"TRIPPEDxx"``, ``"TRIPPEDID"``), when
        the loop stopped on one; ``""``/``None`` otherwise.
    decimation, gain, strategy, seed : int, ndarray, str, int
        The model decimation used, the gain per drive channel, the strategy and the
        identification seed (``settings.id_seed``).
    settings : IterationSettings
        Everything the reconstruction was run with, every default resolved
        (:func:`vrig.reconstruction.defaults.resolve`).
    resolved : dict
        Each value the defaults resolver filled in and where it came from,
        ``{name: {"value": ..., "source": ...}}`` (:meth:`vrig.reconstruction.defaults.
        ResolvedSettings.record`: the source ``"caller"``, the side-car's method or rig block, or
        ``"built-in"``); ``summary.json`` keeps it as ``resolved``.
    identification : dict or None
        Which identification level was used and why (``DriveIteration.id_report``: the mode,
        default or matched to the target, the drive level in % of full scale, the
        identification response's RMS and peak over DESRES's per channel, and for a matched
        identification the probe and every level played); ``None`` when the identification
        drive could not be played.
    updates : list of dict
        What the update rule (``settings.update``, :mod:`~vrig.reconstruction.updates`) did,
        one entry per event (start, each observed iteration, each correction); ``[]`` for
        ``update="none"``. With ``"reidentify"`` ``method`` stays the model identified before
        IT00 (the refits are described here).
    """

    desired: TimeHistory
    id_drive: TimeHistory | None
    id_response: TimeHistory | None
    method: object
    bandwidth: tuple[float, float]
    errors: np.ndarray
    rms_errors: np.ndarray
    damage_ratio: np.ndarray
    drives: list = field(default_factory=list)
    responses: list = field(default_factory=list)
    raw_responses: list = field(default_factory=list)
    best_iteration: int = 0
    stopped: str = ""
    decimation: int = 1
    gain: np.ndarray | None = None
    strategy: str = "fixed"
    seed: int = 0
    settings: IterationSettings | None = None
    resolved: dict = field(default_factory=dict)
    error: BaseException | None = None
    rejected_name: str = ""
    rejected_drive: TimeHistory | None = None
    stop_kind: str = ""
    identification: dict | None = None
    updates: list = field(default_factory=list)

    @property
    def final_drive(self) -> TimeHistory:
        """The drive of the best iteration (FINDRV01); ``ValueError`` when none was played."""
        return self.drives[self._best()]

    @property
    def final_response(self) -> TimeHistory:
        """The processed response of the best iteration (FINRES01); ``ValueError`` when none was
        played."""
        return self.responses[self._best()]

    def _best(self) -> int:
        if not self.drives or not 0 <= self.best_iteration < len(self.drives):
            raise ValueError(f"no iteration was played ({self.stopped or 'empty result'})")
        return self.best_iteration

    def table(self) -> str:
        """Per-iteration, per-channel η0 table."""
        names = self.desired.names
        head = f"{'iteration':>9} " + " ".join(f"{n[:14]:>14}" for n in names) + f" {'mean':>8}"
        rows = [head]
        for i, e in enumerate(self.errors):
            mark = " *" if i == self.best_iteration else ""
            rows.append(
                f"{f'IT{i:02d}':>9} "
                + " ".join(f"{v:>13.2f}%" for v in e)
                + f" {e.mean():>7.2f}%{mark}"
            )
        return "\n".join(rows)


def best_iteration(errors) -> int:
    """The iteration a reconstruction keeps: the smallest mean η0 among the iterations where no
    channel's η0 exceeds its IT00 value; IT00 itself always qualifies.

    A NaN η0 disqualifies its iteration (IT00 is then kept unless a later iteration has finite
    values that are all <= IT00's; a NaN at IT00 compares as +inf). Ties go to the earliest
    iteration.

    Parameters
    ----------
    errors : array_like (n_iterations_run + 1, n_outputs)
        η0 [%] per iteration (IT00 first) and channel.

    Returns
    -------
    int
        The index of the iteration (0 = IT00); -1 for an empty ``errors``.
    """
    e = np.asarray(errors, dtype=float)
    if e.ndim != 2:
        raise ValueError(f"errors must be (iterations, channels), got shape {e.shape}")
    if e.shape[0] == 0:
        return -1
    first = np.where(np.isnan(e[0]), np.inf, e[0])
    ok = np.all(e <= first, axis=1)  # NaN compares False: disqualified
    ok[0] = True
    means = np.where(ok, np.nan_to_num(e.mean(axis=1), nan=np.inf), np.inf)
    return int(np.argmin(means))
