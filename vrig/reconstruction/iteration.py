"""The drive-iteration loop (§1.3, App. G): identify, invert, play, correct.

IDDRV (random, triangular PSD over the identification band) → rig → IDRES → GPREPRO (one
simulation bandwidth for every record) → inverse model → IT00DRV = inverse(DESRES) → rig →
RIT00RES → GPREPRO → IT00RES → error → ``ITn+1DRV = ITnDRV + gain (inverse(DESRES) -
inverse(ITnRES))`` → ...

Every drive is checked against the rig's full scale before it is sent; a diverging iteration
(η0 grows by ``divergence`` over the best so far) stops, and the best drive is kept.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import rainflow
from scipy import signal
from tqdm.auto import tqdm

from identification import metrics

from ..errors import RigLimitError
from ..processing import decimate, gprepro, identification_band
from ..rigs.spec import check_drive_limits
from ..signals import random_drive, triangular_psd
from ..timehistory import TimeHistory
from .methods import make_method

__all__ = ["ReconstructionResult", "pseudo_damage", "reconstruct"]


def pseudo_damage(x: np.ndarray, *, slope: float = 5.0) -> float:
    """Rainflow pseudo-damage ``sum n_i S_i^slope`` of a record (ranges S_i, counts n_i)."""
    return float(
        sum(count * rng**slope for rng, _mean, count, _i, _j in rainflow.extract_cycles(x))
    )


@dataclass
class ReconstructionResult:
    """Everything a reconstruction produced (QanTiM names).

    Attributes
    ----------
    errors : ndarray (n_iterations_run + 1, n_outputs)
        η0 [%] (eq. 5-28) of ITxxRES against DESRES, IT00 first.
    rms_errors : ndarray, same shape
        RMS error [%] of ITxxRES against DESRES (means removed).
    damage_ratio : ndarray, same shape
        Rainflow pseudo-damage of ITxxRES over that of DESRES (S-N slope 5).
    drives, responses, raw_responses : list of TimeHistory
        ITxxDRV, ITxxRES (processed) and RITxxRES (raw) per iteration.
    best_iteration : int
        Iteration with the smallest mean η0; ``final_drive``/``final_response`` are its records.
    """

    desired: TimeHistory
    id_drive: TimeHistory
    id_response: TimeHistory
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

    @property
    def final_drive(self) -> TimeHistory:
        return self.drives[self.best_iteration]

    @property
    def final_response(self) -> TimeHistory:
        return self.responses[self.best_iteration]

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


def _scores(desired: TimeHistory, response: TimeHistory):
    eta0 = metrics.qantim_fit_dc(desired.data, response.data)
    rms = metrics.rms_error_percent(desired.data, response.data)
    dmg = np.array(
        [
            pseudo_damage(response.data[:, k]) / max(pseudo_damage(desired.data[:, k]), 1e-300)
            for k in range(desired.n_channels)
        ]
    )
    return eta0, rms, dmg


def _check_drive(rig, drive: np.ndarray, what: str) -> None:
    check_drive_limits(rig.inputs, drive, fs=rig.fs, what=what)


def reconstruct(
    rig,
    desired: TimeHistory,
    *,
    method="arx",
    iterations: int = 8,
    gain=0.8,
    bandwidth: tuple[float, float] | None = None,
    strategy: str = "fixed",
    id_duration: float | None = None,
    id_rms: float | None = None,
    divergence: float = 1.5,
    min_increase: float = 1.0,
    decimation: int | None = None,
    seed: int = 0,
    progress: bool = False,
    **method_options,
) -> ReconstructionResult:
    """Reproduce ``desired`` on ``rig`` by drive iteration.

    Parameters
    ----------
    rig : Rig
        Anything with ``inputs``, ``outputs``, ``fs`` and ``run(drive, seed=None)``.
    desired : TimeHistory
        The desired response (DESRES before processing), the rig's outputs at ``rig.fs``.
    method : str or method object
        ``"arx"``, ``"narx"``, ``"split"``, ``"frf"`` (options such as ``order``, ``degree``,
        ``split_hz`` go to the method) or an object with ``identify``/``drive``.
    iterations : int
        Number of correction iterations after IT00.
    gain : float or sequence (one per drive channel)
        Iteration gain.
    bandwidth : (low, high) Hz
        Simulation bandwidth applied to every record (default: the rig's test band).
    strategy : {"fixed", "adaptive"}
        ``"adaptive"`` re-identifies the inverse from the latest drive/response pair each time.
    id_duration, id_rms : float
        Identification drive length [s] (default: the desired record's) and RMS per channel
        (default: 5 % of full scale, halved until the rig accepts it).
    divergence, min_increase : float
        Stop when the mean η0 exceeds ``divergence`` times the best so far and by more than
        ``min_increase`` percentage points (so scatter at the noise floor is not divergence).
    decimation : int, optional
        Models work at ``fs / decimation`` (zero-phase decimation of the processed records; the
        drives are interpolated back to fs before they are sent). Default: the largest integer
        keeping at least 8 samples per period of the identification band's upper edge: a record
        sampled far above its band makes the lagged regressors nearly collinear (Table 5.1).
    seed : int
        Seeds the identification drive and every rig run (reproducible).
    """
    if not isinstance(desired, TimeHistory):
        raise TypeError("desired must be a vrig.TimeHistory")
    if desired.fs != rig.fs:
        raise ValueError(f"desired is sampled at {desired.fs:g} Hz, the rig at {rig.fs:g} Hz")
    if desired.n_channels != len(rig.outputs):
        raise ValueError(
            f"desired has {desired.n_channels} channels, the rig {len(rig.outputs)} responses"
        )
    if strategy not in ("fixed", "adaptive"):
        raise ValueError(f"strategy must be 'fixed' or 'adaptive', got {strategy!r}")
    if not isinstance(iterations, int) or iterations < 0:
        raise ValueError(f"iterations must be a non-negative integer, got {iterations!r}")
    n_in = len(rig.inputs)
    gain = np.broadcast_to(np.asarray(gain, dtype=float), (n_in,))
    if np.any(gain <= 0) or np.any(gain > 2):
        raise ValueError(f"gain must lie in (0, 2], got {gain}")
    band = tuple(bandwidth) if bandwidth is not None else tuple(rig.bandwidth)
    id_band = identification_band(band, fs=rig.fs)
    method = make_method(method, **method_options)
    if decimation is None:
        decimation = max(1, int(rig.fs // (8 * id_band[1])))
    if not isinstance(decimation, int) or decimation < 1:
        raise ValueError(f"decimation must be a positive integer, got {decimation!r}")

    def down(th: TimeHistory) -> TimeHistory:
        return decimate(th, decimation)

    def up(x: np.ndarray, n: int) -> np.ndarray:
        return x if decimation == 1 else signal.resample_poly(x, decimation, 1, axis=0)[:n]

    # identification
    n_id = round((id_duration or desired.duration) * rig.fs)
    full = np.array([c.full_scale for c in rig.inputs])
    rms = np.broadcast_to(np.asarray(id_rms if id_rms is not None else 0.05 * full, float), (n_in,))
    shape = triangular_psd((max(id_band[0], 0.0), id_band[1]))
    for _attempt in range(4):
        iddrv = random_drive(
            shape,
            n_id,
            rig.fs,
            channels=n_in,
            rms=rms,
            seed=seed,
            names=[c.name for c in rig.inputs],
            unit=rig.inputs[0].unit,
        )
        try:
            _check_drive(rig, iddrv.data, "the identification drive")
            idres = rig.run(iddrv, seed=seed)
            break
        except RigLimitError as exc:  # halve the amplitude and try again
            rms, last_trip = rms / 2, exc
    else:
        raise last_trip  # even at 1/8 of the amplitude the identification drive trips
    method.identify(down(gprepro(iddrv, id_band)), down(gprepro(idres, id_band)))

    desres = gprepro(desired, band)
    n = desres.n_samples
    target = method.drive(down(desres))
    drive = up(target, n)
    result = ReconstructionResult(
        desired=desres,
        id_drive=iddrv,
        id_response=idres,
        method=method,
        bandwidth=band,
        errors=np.empty((0, desired.n_channels)),
        rms_errors=np.empty((0, desired.n_channels)),
        damage_ratio=np.empty((0, desired.n_channels)),
    )
    errs, rmss, dmgs = [], [], []
    names = [c.name for c in rig.inputs]
    units = [c.unit for c in rig.inputs]
    failure: Exception | None = None
    bar = tqdm(
        total=iterations + 1, desc=f"{rig.name}: iterations", disable=not progress, leave=False
    )
    for it in range(iterations + 1):
        try:
            _check_drive(rig, drive, f"IT{it:02d}DRV")
        except RigLimitError as exc:
            result.stopped, failure = f"IT{it:02d}: {exc}", exc
            break
        drv = TimeHistory(drive, rig.fs, names, units)
        try:
            raw = rig.run(drv, seed=seed + 1 + it)
        except RigLimitError as exc:
            result.stopped, failure = f"IT{it:02d}: {exc}", exc
            break
        res = gprepro(raw, band)
        e, r, d = _scores(desres, res)
        result.drives.append(drv)
        result.raw_responses.append(raw)
        result.responses.append(res)
        errs.append(e)
        rmss.append(r)
        dmgs.append(d)
        bar.update(1)
        means = [x.mean() for x in errs]
        if means[-1] > divergence * min(means) and means[-1] - min(means) > min_increase:
            result.stopped = (
                f"IT{it:02d}: diverging (mean η0 {means[-1]:.1f} % > {divergence} x best)"
            )
            break
        if it == iterations:
            break
        if strategy == "adaptive":
            method.identify(down(gprepro(drv, id_band)), down(gprepro(raw, id_band)))
            target = method.drive(down(desres))
        drive = drive + gain * up(target - method.drive(down(res)), n)
    bar.close()
    if not errs:  # IT00 itself could not be played: report why
        raise failure
    result.errors, result.rms_errors, result.damage_ratio = (
        np.array(errs),
        np.array(rmss),
        np.array(dmgs),
    )
    result.best_iteration = int(np.argmin(result.errors.mean(axis=1)))
    return result
