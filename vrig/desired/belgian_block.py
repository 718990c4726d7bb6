"""Real service records as desired responses: the Belgian-block road record on fuel-tank-7ch.

The record (``rpc3-samples/acc_Belgium_road(half)_20Kph_Pass02_DATA7.rsp`` of the public data
folder, ``SOURCE.md`` beside it) is a real vehicle road-load measurement: six vertical wheel/axle
accelerations in g (left and right, front, middle and rear axle) at 256 Hz, 300 s of a Belgian
pavé at 20 km/h (the vehicle is on the blocks from about 4 s to 280 s). Read in place, never
copied: :func:`external_data_root` finds the folder.

:func:`belgian_block_desired` makes it the desired response of fuel-tank-7ch's four vertical
accelerations (F2D, :func:`vrig.desired.f2d.f2d`):

* **channels**: the record's LF, RF, LR and RR wheel accelerations -> ``LF_vertical_acc``,
  ``RF_vertical_acc``, ``LR_vertical_acc``, ``RR_vertical_acc`` (the rig's frame corners, where
  its vertical links, the stand-ins of the suspension, attach); the middle axle (LM, RM) has no
  counterpart on the rig and is dropped;
* **the lateral and longitudinal responses** are left free: the record measures vertical motion
  only, so it says nothing about them, and a zero desired response is no answer (η0 of a zero
  target is a ratio of round-off: :meth:`vrig.reconstruction.DriveIteration.check_desired`
  refuses it, and holding the frame still sideways is not what the vehicle did on the road,
  where roll makes lateral acceleration at the brackets). The reconstruction runs on the rig
  seen through its four vertical accelerometers (:func:`belgian_block_rig`, a
  :class:`vrig.rigs.OutputSubset`): all seven actuators drive, four responses are controlled
  and scored (an under-determined inverse: 7 drives from 4 responses);
* **units, rate, band**: g -> m/s² (9.80665), 256 -> 250 Hz (``resample_poly`` 125/128), the
  rig's band (1-40 Hz) with de-trend and DC removal;
* **level** (``scale="auto"``, :func:`vrig.desired.reachability.scale_to_limits`): one common factor for the
  four channels (their ratios are the vehicle's), the largest ``<= 1`` for which the best
  linear drive (:func:`vrig.desired.reachability.check_target`, one identification run) needs at most half
  of every actuator's stroke, full scale and velocity limit, and the target at most half of
  every transducer range. Why: at its own level the record (2.4 g RMS, 14 g peak of wheel-hub
  acceleration, mostly at 5-20 Hz) needs about 2 m/s of actuator velocity where the rig's
  actuators make 0.525 m/s; the transducer range (50 g) is not what limits it, so a rule "peak at
  half the range" would scale the record *up* into the actuators' limits. The half is headroom
  for the iterations' overshoot, for the estimate, and for the following-error and force
  interlocks no drive estimate predicts.
"""

from __future__ import annotations

import os
from pathlib import Path

from ..timehistory import TimeHistory
from .f2d import f2d
from .reachability import check_target, scale_to_limits

__all__ = [
    "BELGIAN_BLOCK_CHANNELS",
    "BELGIAN_BLOCK_FILE",
    "ENV_VAR",
    "belgian_block_desired",
    "belgian_block_path",
    "belgian_block_record",
    "belgian_block_rig",
    "external_data_root",
]

ENV_VAR = "VRIG_EXTERNAL_DATA"
"""Environment variable naming the public data folder (wins over the search)."""

BELGIAN_BLOCK_FILE = "rpc3-samples/acc_Belgium_road(half)_20Kph_Pass02_DATA7.rsp"
"""The record's path inside the public data folder."""

BELGIAN_BLOCK_CHANNELS = {
    "LF_vertical_acc": "WFT1@LF_Z_Acceler.RN_1",
    "RF_vertical_acc": "WFT1@RF_Z_Acceler.RN_1",
    "LR_vertical_acc": "WFT2@LR_Z_Acceler.RN_1",
    "RR_vertical_acc": "WFT2@RR_Z_Acceler.RN_1",
}
"""fuel-tank-7ch response -> the record's channel (front and rear axle; the middle one dropped)."""

_G = 9.80665  # m/s^2 per g
_RECORD_S = 300.0


def external_data_root() -> Path:
    """The public data folder: ``$VRIG_EXTERNAL_DATA`` if set, else the first
    ``shared/external-data`` beside the repository or one of the folders above it (a git
    worktree may sit deeper than the main checkout), else ``<repo>/../shared/external-data``
    (which may not exist).

    Returns
    -------
    Path
    """
    env = os.environ.get(ENV_VAR)
    if env:
        return Path(env)
    repo = Path(__file__).resolve().parents[1]
    for folder in repo.parents:
        candidate = folder / "shared" / "external-data"
        if candidate.is_dir():
            return candidate
    return repo.parent / "shared" / "external-data"


def belgian_block_path(path=None) -> Path:
    """The Belgian-block record file; :class:`FileNotFoundError` naming the folder when absent.

    Parameters
    ----------
    path : str or Path, optional
        The file (default: :data:`BELGIAN_BLOCK_FILE` in :func:`external_data_root`).

    Returns
    -------
    Path
    """
    p = Path(path) if path is not None else external_data_root() / BELGIAN_BLOCK_FILE
    if not p.is_file():
        raise FileNotFoundError(
            f"the Belgian-block road record {p.name} is not in {p.parent} (set {ENV_VAR} to the "
            "public data folder that holds rpc3-samples/, or pass path=)"
        )
    return p


def belgian_block_record(path=None) -> TimeHistory:
    """The raw record: six wheel/axle accelerations [g] at 256 Hz, 300 s (FIELD).

    Parameters
    ----------
    path : str or Path, optional
        The file (default :func:`belgian_block_path`).

    Returns
    -------
    TimeHistory
    """
    from ..io import read_rpc3

    return read_rpc3(belgian_block_path(path))


def belgian_block_rig(rig):
    """fuel-tank-7ch as the Belgian record drives it: its four vertical accelerometers
    controlled, all seven actuators driving (:class:`vrig.rigs.OutputSubset`).

    Parameters
    ----------
    rig : Rig
        fuel-tank-7ch (any fidelity or variant), or already such a view (returned as it is).

    Returns
    -------
    Rig
    """
    from ..rigs import OutputSubset

    names = list(BELGIAN_BLOCK_CHANNELS)
    if [c.name for c in rig.outputs] == names:
        return rig
    missing = [n for n in names if n not in [c.name for c in rig.outputs]]
    if missing:
        raise ValueError(
            f"rig {rig.name!r} has no response {missing}: the Belgian-block record is a desired "
            "response of fuel-tank-7ch's vertical accelerations"
        )
    return OutputSubset(rig, names)


def belgian_block_desired(
    rig,
    path=None,
    *,
    seconds: float = 60.0,
    start: float = 5.0,
    scale="auto",
    drive_fraction: float = 0.5,
    id_drive: TimeHistory | None = None,
    id_response: TimeHistory | None = None,
    seed: int = 0,
) -> TimeHistory:
    """The Belgian-block record as the desired response of fuel-tank-7ch's four vertical
    accelerations (the module documentation gives every F2D step and the scaling rule).

    Parameters
    ----------
    rig : Rig
        fuel-tank-7ch or :func:`belgian_block_rig` of it (the desired response has the four
        vertical channels either way: reconstruct it on :func:`belgian_block_rig`).
    path : str or Path, optional
        The record (default :func:`belgian_block_path`).
    seconds : float
        Length of the window [s].
    start : float
        Start of the window in the record [s] (default 5: the vehicle is on the blocks).
    scale : "auto" or float
        ``"auto"``: the module's rule (an identification run of the rig unless ``id_drive``
        and ``id_response`` are given); a number: that factor on the record's own level in
        m/s² (1: the measured level).
    drive_fraction : float
        The rule's fraction of every actuator limit the best linear drive may use, in (0, 1].
    id_drive, id_response : TimeHistory, optional
        Identification records of :func:`belgian_block_rig` (``scale="auto"``); default: one
        run of ``seconds`` (:func:`vrig.desired.reachability.check_target`).
    seed : int
        Seed of that identification run.

    Returns
    -------
    TimeHistory
        DESRES: ``LF_vertical_acc``, ``RF_vertical_acc``, ``LR_vertical_acc``,
        ``RR_vertical_acc`` [m/s²] at the rig's rate.

    Raises
    ------
    FileNotFoundError
        The record is not there.
    ValueError
        A window outside the record, a bad scale, a rig without the four vertical responses.
    """
    view = belgian_block_rig(rig)
    if not (0 <= start and seconds > 0 and start + seconds <= _RECORD_S):
        raise ValueError(
            f"the window [{start:g}, {start + seconds:g}) s must lie in the record's "
            f"0-{_RECORD_S:g} s"
        )
    record = belgian_block_record(path).window(start, start + seconds)
    physical = f2d(record, view, channels=BELGIAN_BLOCK_CHANNELS, scale=_G)
    if isinstance(scale, str):
        if scale != "auto":
            raise ValueError(f"scale must be 'auto' or a factor, got {scale!r}")
        check = check_target(view, physical, seed=seed, id_drive=id_drive, id_response=id_response)
        factor = scale_to_limits(view, physical, check, drive_fraction=drive_fraction).factor
    else:
        factor = float(scale)
        if not (factor > 0 and factor < float("inf")):
            raise ValueError(f"scale must be a finite factor > 0, got {scale!r}")
    return physical.with_data(physical.data * factor)
