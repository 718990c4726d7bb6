"""Reachability of a desired response on a rig (the reference text's §2.3.2, "physically
unrealisable desired response data", made measurable), and the one rule that scales a target to
what the rig can play.

* :func:`check_target` says, per response channel, which fraction of the target no drive of the
  rig can reach, and per drive channel the peak drive (and velocity) the target would need
  against the actuator's limits. It needs one identification run of the rig (random drive over
  the identification band, the kind :func:`vrig.reconstruct` plays) or the records of one
  (:func:`vrig.reconstruction.id_drive.identification_run`, the reconstruction's own).
* :func:`scale_to_limits` is the one documented rule that scales a too-severe (or any) target
  down to what the rig can play.

Reachability (:func:`check_target`)
-----------------------------------
Per spectral line ``f`` of the simulation band (Welch estimates, Hann window, 50 % overlap):
``S_xx`` (drives), ``S_yx`` and ``S_yy`` (responses) of the identification run, ``G`` of the
target (DESRES). The rig's FRF is the H1 estimate ``H = S_yx S_xx^-1``; its coherent output
spectrum ``S_c = S_yx S_xx^-1 S_xy``; the multiple coherence of response ``j`` with all the
drives ``γ²_j = S_c,jj / S_yy,jj`` (:func:`multiple_coherence`); the noise spectrum (what no
linear function of the drives explains: noise, non-linear distortion) ``S_n = S_yy - S_c``.

*Usable drive directions.* A response whose multiple coherence at ``f`` is not significant
(below the level a response independent of the drives exceeds with 1 % probability: Beta(m,
K - m) for ``K`` averages and ``m`` drives) is not driven there: its row of ``H`` is set to
zero. With ``S_xx = C C^H`` and ``S_n = N N^H``, the SVD of the noise-whitened FRF
``N^-1 H C = U Σ V^H`` gives the drive directions ``C v_k`` and the ratio ``σ_k²`` of coherent
to incoherent power of their response; a direction is usable where its coherence
``σ_k² / (1 + σ_k²)`` is significant by the same level. ``D`` holds the usable directions: the
rig reaches nothing along the others (a response the drives do not move, an orthogonal load
path, two responses no drive separates). Low but significant coherence (noise, a non-linear
rig) does not make a target unreachable: that is what *incoherent* reports.

*The best linear drive* ``x = B y`` minimises the target error weighted per channel by
``1 / s_j²`` (``s_j``: the target's RMS in the band, at least the identification run's noise RMS;
so every channel's *relative* error counts alike, as η0 does):
``B = D (W^½ H D)^+ W^½``, ``W = diag(1 / s_j²)``; it reaches ``A y`` with ``A = H B``.

*Unreachable fraction* of response channel ``j``: the residual of the best linear drive, as a
fraction of the target's variance in the band::

    unreachable_j = Σ_f [(I - A) G (I - A)^H]_jj / Σ_f G_jj

0 for any target of a rig with as many usable drive directions as responses (a square rig with a
well-conditioned FRF reaches every target, also one with mutually independent channels); on a
rig with fewer drives than responses the target must keep the rig's ratios between its channels,
and the part that does not is unreachable, shared between the channels by the weighting
(``sqrt(unreachable_j)`` is about the smallest RMS error fraction a linear drive leaves on
channel ``j``); a response the drives do not move is unreachable whatever its target.

*Incoherent fraction*: ``Σ_f (1 - γ²_j) G_jj / Σ_f G_jj``, the rig's lack of coherence (noise,
non-linearity: §2.3.1.5) at the frequencies the target has its energy at; reported beside it.
The estimate is linear: target content a non-linear rig makes at frequencies where it has no
significant linear part (intermodulation, rectification) counts as unreachable, though the
(non-linear) drive that made it exists.

*Needed drive*: ``B`` interpolated onto the target's own spectral lines and applied to its
spectrum gives the best linear drive in time (and its velocity ``jω x``); its peak is compared
with the drive's full scale and stroke (the smaller) and, for a displacement drive [m], the
actuator's velocity limit. An estimate: the following-error and force interlocks, which depend
on the rig's internals, are not predicted.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..processing import check_band, gprepro
from ..reconstruction.defaults import default_band
from ..spectra import frf_from_spectra, interpolate_lines, spectral_matrix
from ..timehistory import TimeHistory
from ._checks import _check_th
from .range_report import _columns, _pct, range_report

__all__ = [
    "ChannelReach",
    "DriveNeed",
    "TargetCheck",
    "TargetScale",
    "check_target",
    "multiple_coherence",
    "scale_to_limits",
]

_MIN_LINES = 8  # spectral lines in the band a reachability estimate needs at least
_WANT_LINES = 16  # ... and the resolution it asks for when the record is long enough
_MIN_AVERAGES = 16  # Welch segments (also at least 4 per drive channel)
_FALSE_ALARM = 0.01  # a response independent of the drives is taken as driven this often
_DEFINITION = (
    "unreachable: residual of the best linear drive (usable drive directions of the "
    "identification run, relative-error weighting) as a fraction of the target's variance in "
    "the band; incoherent: sum_f (1 - gamma^2_j) P_target_j / sum_f P_target_j (vrig.desired.reachability)"
)


# ------------------------------------------------------------------------------ spectra
# (the one spectral core: vrig.spectra's Welch matrix and H1; the reachability's H1 is the
# unregularised "solve": a line whose drives' matrix is singular is not driven - its coherence is
# NaN in multiple_coherence, and its H is left out of the usable directions in _lines)
def _averages(n: int, nperseg: int) -> int:
    return (n - nperseg) // (nperseg - nperseg // 2) + 1 if n >= nperseg else 0


def multiple_coherence(x, y, fs: float, *, nperseg: int = 256):
    """Multiple coherence of each response with all the drives, per frequency (Welch).

    ``γ²_j(f) = S_yx S_xx^-1 S_xy / S_yy`` (the ``j``-th diagonal element): the fraction of
    response ``j``'s power at ``f`` that a linear function of all the drives explains (1 for a
    noise-free linear system; ``S / (S + N)`` for a linear system with independent output noise
    ``N``).

    Parameters
    ----------
    x : array_like (n_samples, n_drives)
        The drives (time on axis 0).
    y : array_like (n_samples, n_responses)
        The responses.
    fs : float
        Sample rate [Hz].
    nperseg : int
        Welch segment length (Hann window, 50 % overlap, mean removed per segment).

    Returns
    -------
    f : ndarray (n_lines,)
        Frequencies [Hz].
    gamma2 : ndarray (n_lines, n_responses)
        Multiple coherence in [0, 1] (NaN where the drives have no power).
    """
    x, y = np.asarray(x, float), np.asarray(y, float)
    x, y = (v[:, None] if v.ndim == 1 else v for v in (x, y))
    if x.shape[0] != y.shape[0]:
        raise ValueError(f"x has {x.shape[0]} samples, y {y.shape[0]}")
    if not (isinstance(nperseg, (int, np.integer)) and 2 <= nperseg <= x.shape[0]):
        raise ValueError(f"nperseg must be an integer in 2..{x.shape[0]} samples, got {nperseg!r}")
    m = x.shape[1]
    f, S = spectral_matrix(np.hstack([x, y]), fs=fs, nperseg=nperseg)
    Sxx, Syx, Syy = S[:, :m, :m], S[:, m:, :m], S[:, m:, m:]
    ok = np.linalg.matrix_rank(Sxx) == m
    gamma2 = np.full((f.size, y.shape[1]), np.nan)
    if ok.any():
        est = frf_from_spectra(f[ok], Sxx[ok], Syx[ok], Syy[ok], regularisation="solve")
        gamma2[ok] = est.coherence
    return f, gamma2


def _sqrt_psd(S: np.ndarray, floor: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(R, R^-1)`` with ``R R^H = S`` per line, eigenvalues held at or above ``floor``."""
    lam, Q = np.linalg.eigh(S)
    lam = np.maximum(lam, floor[:, None])
    root = np.sqrt(lam)
    return Q * root[:, None, :], np.conj(np.swapaxes(Q, -1, -2)) / root[:, :, None]


@dataclass(frozen=True)
class _Lines:
    """The reachability estimate on the band's spectral lines (module documentation)."""

    f: np.ndarray  # (F,) lines in the band [Hz]
    B: np.ndarray  # (F, m, n) best linear drive per unit target
    A: np.ndarray  # (F, n, n) reached response per unit target
    gamma2: np.ndarray  # (F, n) multiple coherence of each response with all the drives
    noise: np.ndarray  # (F, n) noise PSD of the identification run
    directions: np.ndarray  # (F,) usable drive directions


def _hermitian(S: np.ndarray) -> np.ndarray:
    return np.conj(np.swapaxes(S, -1, -2))


def _significant(m: int, averages: int) -> float:
    """The coherence a response independent of ``m`` drives exceeds with 1 % probability.

    The multiple coherence estimated from ``K`` independent averages of Gaussian records is
    Beta(m, K - m) distributed when the response is independent of the drives; 50 %-overlapped
    Hann segments count as ``K / 1.06`` independent ones (their variance reduction)."""
    from scipy.stats import beta

    k = averages / 1.06
    return float(beta.ppf(1 - _FALSE_ALARM, m, max(k - m, 1.0)))


def _usable(H, Sxx, Sn, syy, level: float) -> tuple[np.ndarray, np.ndarray]:
    """Drive directions ``D`` (F, m, m; unusable columns zero) and their count per line: a
    direction is usable where its coherence ``σ² / (1 + σ²)`` is significant (``level``)."""
    m = Sxx.shape[-1]
    C, _ = _sqrt_psd(Sxx, 1e-12 * np.trace(Sxx, axis1=1, axis2=2).real / m)
    _, Ninv = _sqrt_psd(Sn, 1e-10 * syy.max(axis=1))
    _, sv, Vh = np.linalg.svd(Ninv @ H @ C, full_matrices=False)
    usable = sv**2 >= level / (1 - level)
    D = np.zeros(Sxx.shape, dtype=complex)
    D[:, :, : sv.shape[1]] = (C @ _hermitian(Vh)) * usable[:, None, :]
    return D, usable.sum(axis=1)


def _lines(drive, response, fs: float, nperseg: int, band, target_rms) -> _Lines:
    """The identification run's spectra on the band's lines and the best linear drive."""
    m = drive.shape[1]
    level = _significant(m, _averages(drive.shape[0], nperseg))
    f, S = spectral_matrix(np.hstack([drive, response]), fs=fs, nperseg=nperseg)
    keep = (f >= band[0]) & (f <= band[1]) & (f > 0)
    f, S = f[keep], S[keep]
    Sxx, Sxy, Syx, Syy = S[:, :m, :m], S[:, :m, m:], S[:, m:, :m], S[:, m:, m:]
    est = frf_from_spectra(f, Sxx, Syx, Syy, regularisation="solve")
    H, gamma2 = est.frf, est.coherence
    Sc = H @ Sxy
    syy = np.diagonal(Syy, axis1=1, axis2=2).real
    Sn = Syy - Sc
    Sn = 0.5 * (Sn + _hermitian(Sn))
    noise = np.clip(np.diagonal(Sn, axis1=1, axis2=2).real, 0.0, None)
    H = H * (gamma2 >= level)[:, :, None]  # not significantly coherent: not driven at f
    D, count = _usable(H, Sxx, Sn, syy, level)
    noise_rms = np.sqrt(noise.sum(axis=0) * fs / nperseg)
    w = 1.0 / np.maximum(np.maximum(target_rms, noise_rms), np.finfo(float).tiny)  # W^1/2
    pinv = np.linalg.pinv(w[None, :, None] * (H @ D), rcond=1e-10)
    B = D @ pinv * w[None, None, :]
    return _Lines(f, B, H @ B, gamma2, noise, count)


def _needed_drive(lines: _Lines, target: np.ndarray, fs: float, band):
    """Peak of the best linear drive for ``target`` and of its velocity, per drive channel."""
    n = target.shape[0]
    Y = np.fft.rfft(target, axis=0)
    ff = np.fft.rfftfreq(n, 1.0 / fs)
    inband = (ff >= band[0]) & (ff <= band[1]) & (ff > 0)
    X = np.zeros((ff.size, lines.B.shape[1]), dtype=complex)
    X[inband] = np.einsum("fmn,fn->fm", interpolate_lines(lines.B, lines.f, ff[inband]), Y[inband])
    x = np.fft.irfft(X, n, axis=0)
    v = np.fft.irfft(X * (2j * np.pi * ff)[:, None], n, axis=0)
    return np.abs(x).max(axis=0), np.abs(v).max(axis=0)


# ------------------------------------------------------------------------------ the result
@dataclass(frozen=True)
class ChannelReach:
    """How much of one response channel's target the rig can reach (:func:`check_target`).

    Attributes
    ----------
    name, unit : str
        The response channel and its unit.
    target_rms : float
        RMS of the target in the band [unit].
    unreachable : float
        Fraction of the target's variance the best linear drive leaves (0 .. 1; NaN for a
        target without content in the band).
    incoherent : float
        The target-weighted lack of coherence ``Σ (1 - γ²) P / Σ P`` of the channel (0 .. 1).
    """

    name: str
    unit: str
    target_rms: float
    unreachable: float
    incoherent: float


@dataclass(frozen=True)
class DriveNeed:
    """The best linear drive of a target on one drive channel against its limits.

    Attributes
    ----------
    name, unit : str
        The drive channel and its unit.
    needed_peak : float
        Peak of the estimated drive [unit].
    limit : float
        The smaller of the drive's full scale and its actuator stroke [unit].
    limit_kind : str
        ``"full scale"`` or ``"stroke"``: which one ``limit`` is.
    fraction_of_limit : float
        ``needed_peak / limit`` (> 1: beyond it).
    needed_peak_velocity : float or None
        Peak velocity of the estimated drive [unit/s] (displacement drives with a velocity
        limit only).
    velocity_limit : float or None
        The actuator's velocity limit [unit/s].
    fraction_of_velocity_limit : float or None
        ``needed_peak_velocity / velocity_limit``.
    """

    name: str
    unit: str
    needed_peak: float
    limit: float
    limit_kind: str
    fraction_of_limit: float
    needed_peak_velocity: float | None = None
    velocity_limit: float | None = None
    fraction_of_velocity_limit: float | None = None

    @property
    def worst_fraction(self) -> float:
        """The larger of the two fractions of limit."""
        return max(self.fraction_of_limit, self.fraction_of_velocity_limit or 0.0)


def _json(value):
    """Floats as JSON numbers (NaN and inf as None), tuples as lists, recursively."""
    if isinstance(value, dict):
        return {k: _json(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_json(v) for v in value]
    if isinstance(value, (float, np.floating)):
        return float(value) if math.isfinite(value) else None
    if isinstance(value, np.integer):
        return int(value)
    return value


@dataclass(frozen=True)
class TargetCheck:
    """Reachability of a desired response on a rig (:func:`check_target`; the definitions are
    the module's documentation).

    Attributes
    ----------
    rig : str
        The rig's name.
    band : (float, float)
        The band [Hz] the estimate covers.
    channels : tuple of ChannelReach
        Per response channel: target RMS, unreachable and incoherent fractions.
    drives : tuple of DriveNeed
        Per drive channel: the best linear drive's peak (and velocity) against the limits.
    id_level : tuple of float
        RMS of the identification drive as a fraction of each drive's full scale.
    id_seconds : float
        Length of the identification records [s].
    resolution_hz : float
        Spacing of the spectral lines [Hz].
    averages : int
        Welch segments averaged (of the shorter of target and identification records).
    directions : (int, int)
        Fewest and most usable drive directions over the band's lines.
    """

    rig: str
    band: tuple[float, float]
    channels: tuple[ChannelReach, ...]
    drives: tuple[DriveNeed, ...]
    id_level: tuple[float, ...]
    id_seconds: float
    resolution_hz: float
    averages: int
    directions: tuple[int, int]

    @property
    def unreachable(self) -> np.ndarray:
        """The unreachable fraction per response channel."""
        return np.array([c.unreachable for c in self.channels])

    @property
    def worst_drive_fraction(self) -> float:
        """The largest fraction of a drive limit (stroke or full scale, velocity) needed."""
        return max((d.worst_fraction for d in self.drives), default=0.0)

    def table(self) -> str:
        """The check as a text table: responses, then drives."""
        lo, hi = self.band
        d0, d1 = self.directions
        rows = [["response", "target RMS", "unreachable", "incoherent"]]
        rows += [
            [c.name, f"{c.target_rms:.4g} {c.unit}", _pct(c.unreachable), _pct(c.incoherent)]
            for c in self.channels
        ]
        drives = [
            [
                "drive",
                "needed peak",
                "limit",
                "of limit",
                "needed velocity",
                "velocity limit",
                "of limit",
            ]
        ]
        for d in self.drives:
            vel = (
                ["-", "-", "-"]
                if d.velocity_limit is None
                else [
                    f"{d.needed_peak_velocity:.4g} {d.unit}/s",
                    f"{d.velocity_limit:.4g} {d.unit}/s",
                    _pct(d.fraction_of_velocity_limit, 1.0),
                ]
            )
            drives.append(
                [
                    d.name,
                    f"{d.needed_peak:.4g} {d.unit}",
                    f"{d.limit:.4g} {d.unit} ({d.limit_kind})",
                    _pct(d.fraction_of_limit, 1.0),
                    *vel,
                ]
            )
        return "\n".join(
            [
                f"target check on {self.rig}, band {lo:g}-{hi:g} Hz (vrig.desired.reachability)",
                f"identification {self.id_seconds:g} s at {100 * max(self.id_level):.3g} % of full "
                f"scale RMS; {self.averages} averages, {self.resolution_hz:.3g} Hz lines; {d0}-{d1} "
                f"usable drive directions ({len(self.drives)} drives, {len(self.channels)} responses)",
                "",
                *_columns(rows),
                "",
                *_columns(drives),
            ]
        )

    def __str__(self) -> str:
        return self.table()

    def to_dict(self) -> dict:
        """The check as JSON-able data (NaN as None), with the definitions in one line."""
        return _json(
            {
                "definition": _DEFINITION,
                "rig": self.rig,
                "band_hz": self.band,
                "id_level": self.id_level,
                "id_seconds": self.id_seconds,
                "resolution_hz": self.resolution_hz,
                "averages": self.averages,
                "usable_directions": self.directions,
                "channels": [vars(c) for c in self.channels],
                "drives": [vars(d) for d in self.drives],
                "worst_drive_fraction": self.worst_drive_fraction,
            }
        )


# ------------------------------------------------------------------------------ check_target
def _ordered_target(rig, desired: TimeHistory) -> TimeHistory:
    """``desired`` with the rig's response channels, in its order (by name, else by position)."""
    _check_th(desired, "desired")
    names = [c.name for c in rig.outputs]
    if abs(desired.fs - rig.fs) > 1e-9 * rig.fs:
        raise ValueError(
            f"the target is sampled at {desired.fs:g} Hz but rig {rig.name!r} runs at "
            f"{rig.fs:g} Hz: resample it first (vrig.desired.f2d.f2d)"
        )
    if desired.n_channels != len(names):
        raise ValueError(
            f"the target has {desired.n_channels} channels {list(desired.names)} but rig "
            f"{rig.name!r} has {len(names)} responses {names}"
        )
    if set(desired.names) == set(names):
        desired = desired[names]
    return TimeHistory(desired.data, rig.fs, names, [c.unit for c in rig.outputs])


def _id_pair(rig, id_drive, id_response, n: int, band, id_rms, seed: int):
    """The identification records: given (checked) or made by the one identification drive
    (:func:`vrig.reconstruction.id_drive.identification_run`, at ``vrig reconstruct``'s level
    unless ``id_rms`` is given: :func:`vrig.reconstruction.defaults.resolve`)."""
    if (id_drive is None) != (id_response is None):
        raise ValueError("give both id_drive and id_response, or neither")
    if id_drive is None:
        from ..reconstruction.defaults import resolve
        from ..reconstruction.id_drive import identification_run

        if id_rms is None:
            id_rms = resolve(rig, bandwidth=band).settings.id_rms
        run = identification_run(rig, band, n, id_rms, seed=seed)
        return run.drive, run.response
    for th, what, chans in (
        (id_drive, "id_drive", rig.inputs),
        (id_response, "id_response", rig.outputs),
    ):
        _check_th(th, what)
        if th.n_channels != len(chans) or abs(th.fs - rig.fs) > 1e-9 * rig.fs:
            raise ValueError(
                f"{what} must have the rig's {len(chans)} channels at {rig.fs:g} Hz, got "
                f"{th.n_channels} at {th.fs:g} Hz"
            )
    if id_drive.n_samples != id_response.n_samples:
        raise ValueError(
            f"id_drive has {id_drive.n_samples} samples, id_response {id_response.n_samples}"
        )
    return id_drive, id_response


def _segment(n: int, fs: float, band, m: int) -> tuple[int, int]:
    """Welch segment length and the averages it gives for records of ``n`` samples."""
    k_min = max(_MIN_AVERAGES, 4 * m)
    width = band[1] - band[0]
    want = 2 ** math.ceil(math.log2(_WANT_LINES * fs / width))
    least = 2 ** math.ceil(math.log2(_MIN_LINES * fs / width))
    fit = 2 ** math.floor(math.log2(max(2 * n / (k_min + 1), 1)))
    nperseg = min(want, fit)
    if nperseg < max(least, 8):
        need = (k_min + 1) * max(least, 8) / 2 / fs
        raise ValueError(
            f"the target and identification records ({n / fs:.3g} s) are too short for the "
            f"spectral estimate: {_MIN_LINES} lines in the {band[0]:g}-{band[1]:g} Hz band and "
            f"{k_min} averages need at least {need:.3g} s"
        )
    return nperseg, _averages(n, nperseg)


def _drive_needs(rig, peak, vpeak) -> tuple[DriveNeed, ...]:
    out = []
    for c, p, v in zip(rig.inputs, peak, vpeak, strict=True):
        stroke = c.limits.get("stroke")
        limit, kind = (
            (stroke, "stroke") if stroke and stroke < c.full_scale else (c.full_scale, "full scale")
        )
        vlim = c.limits.get("velocity") if c.unit == "m" else None
        out.append(
            DriveNeed(
                c.name,
                c.unit,
                float(p),
                float(limit),
                kind,
                float(p / limit),
                None if vlim is None else float(v),
                vlim,
                None if vlim is None else float(v / vlim),
            )
        )
    return tuple(out)


def check_target(
    rig,
    desired: TimeHistory,
    *,
    band=None,
    seconds: float | None = None,
    id_rms=None,
    seed: int = 0,
    id_drive: TimeHistory | None = None,
    id_response: TimeHistory | None = None,
) -> TargetCheck:
    """How much of ``desired`` the rig can reach, and the drive it would need (§2.3.2).

    Per response channel the fraction of the target no drive can reach (the residual of the
    best linear drive) and the rig's target-weighted incoherence; per drive channel the peak of
    that drive (and of its velocity) against the actuator's limits. The definitions are the
    module's documentation (:mod:`vrig.desired.reachability`). The target is processed as a reconstruction
    processes it (:func:`vrig.processing.gprepro` over ``band``).

    Parameters
    ----------
    rig : Rig
        The rig (``inputs``, ``outputs``, ``fs``, ``run``).
    desired : TimeHistory
        The desired response: the rig's response channels (by name, else by position) at
        ``rig.fs``.
    band : (float, float), optional
        Simulation band [Hz] (default :func:`vrig.reconstruction.defaults.default_band`).
    seconds : float, optional
        Length of the identification run [s] (default: the target's length, as a
        reconstruction identifies). Not used with ``id_drive`` / ``id_response``.
    id_rms : float or sequence of float, optional
        Identification drive RMS per drive channel in its unit (default: ``vrig
        reconstruct``'s level, :func:`vrig.reconstruction.defaults.resolve`).
    seed : int
        Seed of the identification drive and run.
    id_drive, id_response : TimeHistory, optional
        The records of an identification run already made on this rig (e.g. a reconstruction's
        IDDRV and raw IDRES): no rig run then.

    Returns
    -------
    TargetCheck

    Raises
    ------
    ValueError
        A target with other channels than the rig's responses or another sample rate, records
        too short for the spectral estimate (at least 8 lines in the band and 16 Welch averages,
        4 per drive channel), a bad band.
    """
    target = _ordered_target(rig, desired)
    band = check_band(default_band(rig) if band is None else band, rig.fs)
    n_id = target.n_samples if seconds is None else round(seconds * rig.fs)
    m = len(rig.inputs)
    _segment(min(target.n_samples, n_id), rig.fs, band, m)  # before any rig run
    drive, response = _id_pair(rig, id_drive, id_response, n_id, band, id_rms, seed)
    nperseg, averages = _segment(min(target.n_samples, drive.n_samples), rig.fs, band, m)
    desres = gprepro(target, band)
    f, G = spectral_matrix(desres.data, fs=rig.fs, nperseg=nperseg)
    keep = (f >= band[0]) & (f <= band[1]) & (f > 0)
    G = G[keep]
    g = np.diagonal(G, axis1=1, axis2=2).real
    rms = np.sqrt(g.sum(axis=0) * rig.fs / nperseg)
    lines = _lines(drive.data, response.data, rig.fs, nperseg, band, rms)
    eye = np.eye(len(rig.outputs))
    R = (eye - lines.A) @ G @ _hermitian(eye - lines.A)
    with np.errstate(invalid="ignore", divide="ignore"):
        unreachable = np.diagonal(R, axis1=1, axis2=2).real.sum(axis=0) / g.sum(axis=0)
        incoherent = ((1 - lines.gamma2) * g).sum(axis=0) / g.sum(axis=0)
    peak, vpeak = _needed_drive(lines, desres.data, rig.fs, band)
    full = np.array([c.full_scale for c in rig.inputs])
    return TargetCheck(
        rig=str(rig.name),
        band=band,
        channels=tuple(
            ChannelReach(c.name, c.unit, float(r), float(u), float(i))
            for c, r, u, i in zip(rig.outputs, rms, unreachable, incoherent, strict=True)
        ),
        drives=_drive_needs(rig, peak, vpeak),
        id_level=tuple(float(v) for v in np.sqrt(np.mean(drive.data**2, axis=0)) / full),
        id_seconds=drive.duration,
        resolution_hz=rig.fs / nperseg,
        averages=averages,
        directions=(int(lines.directions.min()), int(lines.directions.max())),
    )


# ------------------------------------------------------------------------------ scaling rule
@dataclass(frozen=True)
class TargetScale:
    """The factor :func:`scale_to_limits` scales a target by, and what set it.

    Attributes
    ----------
    factor : float
        The common factor for every channel (ratios between channels stay).
    binding : str
        What set it: ``"the target's own level"`` (1: not scaled), ``"transducer range of
        <response>"``, ``"<stroke|full scale|velocity limit> of <drive>"``.
    drive_fraction, range_fraction : float
        The rule's fractions of the drive limits and transducer ranges.
    """

    factor: float
    binding: str
    drive_fraction: float
    range_fraction: float

    def describe(self) -> str:
        """The rule and its result in one line."""
        return (
            f"scaled by {self.factor:.4g} (set by the {self.binding}): the best linear drive "
            f"within {100 * self.drive_fraction:g} % of every drive limit, the target within "
            f"{100 * self.range_fraction:g} % of every transducer range, never scaled up"
        )


def scale_to_limits(
    rig,
    desired: TimeHistory,
    check: TargetCheck,
    *,
    drive_fraction: float = 0.5,
    range_fraction: float = 0.5,
) -> TargetScale:
    """One common factor that brings a target within the rig's limits with headroom.

    The factor is the largest ``s <= 1`` for which the best linear drive of ``s * desired``
    (``check``, linear in the target) peaks at no more than ``drive_fraction`` of each drive's
    stroke or full scale and of its velocity limit, and ``s * desired`` at no more than
    ``range_fraction`` of each transducer range. A target is never scaled up (its own level is
    the physical one); one factor for all channels keeps their ratios (a field record's
    physics). The headroom (default half) is for the iterations, which overshoot, for the
    estimate's error, and for the following-error and force interlocks no drive estimate
    predicts.

    Parameters
    ----------
    rig : Rig
        The rig.
    desired : TimeHistory
        The target at its own level (the rig's response channels).
    check : TargetCheck
        :func:`check_target` of ``desired`` on ``rig``.
    drive_fraction : float
        Fraction of each drive limit the best linear drive may use, in (0, 1].
    range_fraction : float
        Fraction of each transducer range the target may use, in (0, 1].

    Returns
    -------
    TargetScale
    """
    for name, v in (("drive_fraction", drive_fraction), ("range_fraction", range_fraction)):
        if not (isinstance(v, (int, float)) and 0 < v <= 1):
            raise ValueError(f"{name} must lie in (0, 1], got {v!r}")
    found = [(1.0, "the target's own level")]
    found += [
        (range_fraction / r.peak_fraction, f"transducer range of {r.name}")
        for r in range_report(rig, desired).rows
        if r.peak > 0
    ]
    for d in check.drives:
        if d.fraction_of_limit > 0:
            found.append((drive_fraction / d.fraction_of_limit, f"{d.limit_kind} of {d.name}"))
        if d.fraction_of_velocity_limit:
            found.append(
                (drive_fraction / d.fraction_of_velocity_limit, f"velocity limit of {d.name}")
            )
    factor, binding = min(found, key=lambda item: item[0])
    return TargetScale(float(factor), binding, float(drive_fraction), float(range_fraction))
