"""Identification matched to the target (§3.3-3.4; issue 22): ``IterationSettings(id_match=True)``.

The default identification drive is a triangular-PSD random drive at 5 % of full scale RMS: a
model identified from it has never seen the amplitudes or the spectrum of a large, slow,
non-Gaussian service target (a slow ditch), and extrapolates. The reference text's rule is that
the identification band and spectrum follow the desired response (§3.3: rig-specific drive PSDs;
§3.4: the same band for every record). The matched identification of
:class:`~vrig.reconstruction.DriveIteration` therefore

1. plays a short broadband **probe** (triangular PSD over the identification band, at the
   default level ``id_rms``) and estimates the rig's FRF from it (H1, :func:`vrig.spectra.frf_h1`);
2. **shapes** the drive PSD the target needs, ``G_xx = H^+ G_yy H^+^H`` from DESRES's spectral
   matrix (:func:`vrig.spectra.matched_drive_psd`: diagonal, smoothed over 3 lines, band-limited
   to the identification band, floored at :data:`FLOOR` of its peak so that every line of the
   band is still excited);
3. sets the **level** so that each identification response (processed like DESRES) reaches the
   target's RMS, its peak and its *half-energy amplitude* (:func:`half_energy_amplitude`: half
   the record's energy lies above it): a Gaussian drive at the target's RMS never reaches the
   peaks of a non-Gaussian target, and one that merely touches them spends too little time at
   the amplitudes a slow large event lives at (the elastomeric damper's slow-ditch-like target
   of ``benchmarks.matched_identification``, fast fidelity, 30 s, identification seeds 0-2:
   matching RMS and peak alone left ARX(6) IT00 at 56-97 %, matching the half-energy amplitude
   too 47-57 %; on a Gaussian target the three criteria coincide). The level is raised until the response's largest shortfall over the
   channels and statistics is made good (within :data:`LEVEL_TOLERANCE`), in at most
   :data:`MAX_PLAYS` identification runs (a secant on the level in log-log, which follows a
   progressive or softening specimen);
4. checks every level against the drives' **full scale** before it is played (the drive's peak
   is kept at or below :data:`PEAK_MARGIN` of full scale: a target that needs more is reported,
   not played) and a level that trips an interlock is halved (up to three times: the matched
   level is measured, near the target's; the default identification halves up to ten times)
   and never exceeded again.

The identification run kept is the one whose response came closest to the target's level;
:class:`MatchedIdentification` records the probe, the FRF, the target and drive PSDs, every
level played and why the kept one was chosen (``DriveIteration.id_matching``; its
:meth:`~MatchedIdentification.summary` goes to ``summary.json``).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..errors import RigLimitError
from ..percent import percent
from ..processing import gprepro
from ..progress import status
from ..signals import random_drive, triangular_psd
from ..spectra import frf_h1, matched_drive_psd, psd_function, spectral_matrix
from ..timehistory import TimeHistory
from .id_drive import identification_run

__all__ = [
    "FLOOR",
    "LEVEL_TOLERANCE",
    "MAX_PLAYS",
    "PEAK_MARGIN",
    "RESOLUTION_HZ",
    "MatchedIdentification",
    "half_energy_amplitude",
    "identify_matched",
    "level_ratios",
]

RESOLUTION_HZ = 0.25
"""Line spacing of the probe's FRF and the target's PSD [Hz] (Welch segments of 4 s; shorter
when the desired record has fewer than four such segments)."""
PROBE_SEGMENTS = 5
"""The probe lasts this many Welch segments (nine half-overlapping averages): 20 s at 0.25 Hz."""
FLOOR = 0.01
"""Lowest drive PSD inside the identification band, as a fraction of its peak (20 dB down: 10 %
of the peak amplitude density), so that no line of the band goes unexcited."""
LEVEL_TOLERANCE = 0.15
"""The level is settled when the response's largest shortfall ratio is within 15 % of 1."""
MAX_PLAYS = 4
"""Most identification runs spent on the level (trips included)."""
LEVEL_STATISTICS = ("rms_ratio", "peak_ratio", "half_energy_ratio")
"""The statistics of the identification response that must reach the target's."""
PEAK_MARGIN = 0.95
"""The matched drive's peak stays at or below this fraction of each drive's full scale."""
_MAX_HALVINGS = 3  # full, 1/2, 1/4, 1/8 of a tripping level
_PROBE_SEED, _DRIVE_SEED = 1, 2  # streams of np.random.default_rng([id_seed, stream])


@dataclass
class MatchedIdentification:
    """What a matched identification did (``DriveIteration.id_matching``).

    Attributes
    ----------
    probe_drive, probe_response : TimeHistory
        The broadband probe and the rig's raw response to it.
    frequencies : ndarray (n_freq,)
        Spectral lines [Hz] of the FRF and the PSDs.
    frf : ndarray (n_freq, n_outputs, n_inputs), complex
        The rig's H1 FRF estimated from the probe.
    target_psd : ndarray (n_freq, n_outputs)
        DESRES's auto-PSDs [(response unit)²/Hz].
    drive_psd : ndarray (n_freq, n_inputs)
        The shaped drive PSD [(drive unit)²/Hz] at the linear match (its level before scaling).
    plays : list of dict
        Every level tried: ``scale`` (of the linear match), ``rms_percent`` and
        ``peak_percent`` of full scale per drive, and either ``rms_ratio`` / ``peak_ratio`` (the
        processed response's RMS and peak over DESRES's, per response channel) or ``tripped``
        (the interlock's message).
    kept : int
        Index in ``plays`` of the identification run kept (IDDRV / IDRES).
    reason : str
        Why that level: reached the target, capped by full scale, halved after a trip, or the
        closest after :data:`MAX_PLAYS` runs.
    """

    probe_drive: TimeHistory
    probe_response: TimeHistory
    frequencies: np.ndarray
    frf: np.ndarray
    target_psd: np.ndarray
    drive_psd: np.ndarray
    plays: list = field(default_factory=list)
    kept: int = -1
    reason: str = ""

    def summary(self) -> dict:
        """A JSON-friendly account (no time histories): probe, band, floor, every level played,
        the level kept and why.

        Returns
        -------
        dict
        """
        f, p = self.frequencies, self.drive_psd
        df = f[1] - f[0] if f.size > 1 else 0.0
        probe = self.probe_drive
        return {
            "mode": "matched",
            "probe": {
                "seconds": probe.duration,
                "rms": np.sqrt(np.mean(probe.data**2, axis=0)).tolist(),
            },
            "resolution_hz": float(df),
            "floor": FLOOR,
            "drive_psd_peak_hz": f[np.argmax(p, axis=0)].tolist(),
            "linear_match_rms": np.sqrt(p.sum(axis=0) * df).tolist(),
            "plays": self.plays,
            "kept": self.kept,
            **{k: v for k, v in self.plays[self.kept].items() if k != "scale"},
            "reason": self.reason,
        }


def half_energy_amplitude(x) -> np.ndarray:
    """The amplitude that splits a record's energy in half, per channel: half of ``sum(x**2)``
    comes from samples with ``|x|`` above it (1.54 sigma for a Gaussian record; close to the
    events' level for a record whose energy sits in a few large events).

    Parameters
    ----------
    x : ndarray (n, n_channels)
        Samples (time on axis 0), means removed.

    Returns
    -------
    ndarray (n_channels,)
    """
    a = np.sort(np.abs(np.asarray(x, dtype=float)), axis=0)
    energy = np.cumsum(a**2, axis=0)
    i = np.argmax(energy >= 0.5 * energy[-1], axis=0)
    return a[i, np.arange(a.shape[1])]


def level_ratios(desres: TimeHistory, response: TimeHistory) -> dict:
    """A processed response's level over the target's, per channel: RMS, peak and half-energy
    amplitude (:func:`half_energy_amplitude`).

    Parameters
    ----------
    desres : TimeHistory
        The target (DESRES, processed).
    response : TimeHistory
        A response processed the same way.

    Returns
    -------
    dict
        ``rms_ratio``, ``peak_ratio``, ``half_energy_ratio``: lists (one value per channel).
    """
    t, r = desres.data, response.data
    return {
        "rms_ratio": (np.sqrt(np.mean(r**2, axis=0) / np.mean(t**2, axis=0))).tolist(),
        "peak_ratio": (np.abs(r).max(axis=0) / np.abs(t).max(axis=0)).tolist(),
        "half_energy_ratio": (half_energy_amplitude(r) / half_energy_amplitude(t)).tolist(),
    }


def identify_matched(engine) -> tuple[TimeHistory, TimeHistory, MatchedIdentification]:
    """Probe, shape and level the identification drive of ``engine`` (see the module docstring).

    Parameters
    ----------
    engine : DriveIteration
        The engine (its rig, DESRES, bands, ``id_rms`` as the probe level, ``id_seed``).

    Returns
    -------
    iddrv, idres : TimeHistory
        The identification run kept.
    record : MatchedIdentification

    Raises
    ------
    RigLimitError
        The probe trips the rig even at 1/8 of its level, or every matched level tripped.
    """
    rig = engine.rig
    nperseg = max(64, min(round(rig.fs / RESOLUTION_HZ), engine.desres.n_samples // 4))
    probe, probe_res = _probe(engine, nperseg)
    band = engine.id_band
    x = gprepro(probe, band).data
    y = gprepro(probe_res, band).data
    h1 = frf_h1(x, y, fs=rig.fs, nperseg=nperseg)
    f, frf = h1.f, h1.frf
    _, target = spectral_matrix(engine.desres.data, fs=rig.fs, nperseg=nperseg)
    mask = (f > 0) & (f >= band[0]) & (f <= band[1])
    psd = matched_drive_psd(frf, target, mask=mask, floor=FLOOR)
    dead = ~(psd.max(axis=0) > 0)
    if dead.any():  # a drive no response needs (H's column ~ 0): excite it as the probe did
        tri = triangular_psd((max(band[0], 0.0), band[1]))(f)
        psd[:, dead] = tri[:, None] * engine.id_rms[dead] ** 2 / (tri.sum() * (f[1] - f[0]))
    record = MatchedIdentification(
        probe, probe_res, f, frf, np.real(np.einsum("fii->fi", target)), psd
    )
    rms = np.sqrt(psd.sum(axis=0) * (f[1] - f[0]))
    unit = random_drive(
        psd_function(f, psd),
        engine.id_samples,
        rig.fs,
        channels=engine.n_inputs,
        rms=rms,
        seed=np.random.default_rng([engine.settings.id_seed, _DRIVE_SEED]),
        names=engine.names,
        unit=rig.inputs[0].unit,
    )
    iddrv, idres = _level(engine, unit, record)
    return iddrv, idres, record


def _probe(engine, nperseg: int) -> tuple[TimeHistory, TimeHistory]:
    """The broadband probe (the identification drive, :func:`~vrig.reconstruction.id_drive.
    identification_run`, over the identification band at ``engine.id_rms``, halved while the rig
    trips on it) and the rig's raw response."""
    seed = engine.settings.id_seed
    run = identification_run(
        engine.rig, engine.band, PROBE_SEGMENTS * nperseg, engine.id_rms,
        seed=[seed, _PROBE_SEED], attempts=_MAX_HALVINGS + 1, label="matched probe",
        send=lambda drive: engine._send(drive, "ID", "the identification probe", seed),
    )  # fmt: skip
    return run.drive, run.response


def _percent(x, rig) -> np.ndarray:
    return 100 * np.asarray(x) / [c.full_scale for c in rig.inputs]


def _level(engine, unit: TimeHistory, record: MatchedIdentification):
    """Scale ``unit`` (the shaped drive at the linear match) until the response reaches the
    target's RMS, peak and half-energy amplitude; returns the run kept and fills ``record.plays``, ``kept``, ``reason``."""
    rig = engine.rig
    full = np.array([c.full_scale for c in rig.inputs])
    peak = np.abs(unit.data).max(axis=0)
    cap = float(np.min(PEAK_MARGIN * full / peak))  # the largest scale full scale allows
    limit = f"the drives' full scale ({100 * PEAK_MARGIN:g} % peak)"
    scale, runs, notes, outcome = min(1.0, cap), {}, [], ""
    if cap < 1:  # said before anything is played
        notes.append(
            f"the linear match needs {percent(np.max(peak / full), threshold=PEAK_MARGIN)} of "
            f"full scale peak: held at {100 * PEAK_MARGIN:g} %"
        )
    for _ in range(MAX_PLAYS):
        play = {
            "scale": scale,
            "rms_percent": _percent(scale * np.sqrt(np.mean(unit.data**2, axis=0)), rig).tolist(),
            "peak_percent": _percent(scale * peak, rig).tolist(),
        }
        record.plays.append(play)
        status(
            f"identifying (matched): IDDRV {unit.duration:g} s at "
            f"{max(play['rms_percent']):.3g} % of full scale rms (peak "
            f"{max(play['peak_percent']):.3g} %) -> {rig.name}"
        )
        try:
            drv, raw = engine._send(unit.data * scale, "ID", "the identification drive",
                                    engine.settings.id_seed)  # fmt: skip
        except RigLimitError as exc:
            play["tripped"] = str(exc)
            if sum("tripped" in p for p in record.plays) > _MAX_HALVINGS:
                raise  # MAX_PLAYS = _MAX_HALVINGS + 1: no run without a trip at all
            notes.append(f"halved after an interlock trip at {max(play['rms_percent']):.3g} % "
                         f"of full scale rms ({exc})")  # fmt: skip
            cap, scale, limit = scale / 2, scale / 2, "half the level that tripped"
            continue
        play.update(level_ratios(engine.desres, gprepro(raw, engine.band)))
        runs[len(record.plays) - 1] = (drv, raw)
        need = _shortfall(play)
        if abs(need - 1) <= LEVEL_TOLERANCE:
            outcome = "the response reached the target's RMS, peak and half-energy amplitude"
            outcome += f" (held at {limit})" if scale >= cap else ""
            break
        if need > 1 and scale >= cap:
            outcome = (
                f"held at {limit}: the response stays {need:.2g}x below the target's RMS, "
                f"peak or half-energy amplitude (the target needs about {need * max(play['peak_percent']):.3g} % of "
                "full scale peak)"
            )
            break
        scale = min(cap, _next_scale(record.plays, runs, scale, need))
    else:
        outcome = f"the closest of {MAX_PLAYS} levels (the level did not settle)"
    record.kept = min(runs, key=lambda i: abs(np.log(_shortfall(record.plays[i]))))
    record.reason = "; ".join([*notes, outcome or "the closest level played"])
    return runs[record.kept]


def _shortfall(play: dict) -> float:
    """The factor by which the response falls short of the target (> 1) or exceeds it (< 1) in
    its worst channel and statistic (:data:`LEVEL_STATISTICS`)."""
    ratios = np.array([play[k] for k in LEVEL_STATISTICS])
    return float(np.max(1 / ratios))


def _next_scale(plays: list, runs: dict, scale: float, need: float) -> float:
    """The next level: ``scale * need**(1/g)`` with ``g`` the response's growth exponent with
    the level between the last two runs played (1 for a single run; kept in [0.5, 2]), the step
    kept within a factor 4."""
    played = [plays[i] for i in sorted(runs)]
    g = 1.0
    if len(played) >= 2:
        (a, b) = played[-2:]
        ds = np.log(b["scale"] / a["scale"])
        if abs(ds) > 1e-9:
            g = float(np.clip(np.log(_shortfall(a) / _shortfall(b)) / ds, 0.5, 2.0))
    return scale * float(np.clip(need ** (1 / g), 0.25, 4.0))
