"""How the correction model learns from the iteration's data (``IterationSettings.update``).

Without an update (``update="none"``) the loop corrects with the inverse identified before IT00:
``ITn+1DRV = ITnDRV + gain (inverse(DESRES) - inverse(ITnRES))``. An update rule replaces the
bracket, the *correction*, by one that learns from the drives played and the responses measured:

``"frf"`` (:class:`FrfUpdate`)
    The correction is ``Hinv(f) E(f)``, ``E = DESRES - ITnRES``, with ``H`` the H1 estimate of
    the rig's FRF (drive -> response, per line, MIMO) from the identification record and every
    iteration record, their cross spectra accumulated with a forgetting factor ``forgetting``
    (each older record's weight multiplied by it at every new one; default 0.5; 0: the latest
    record alone, 1: all records equally), each record weighted by its length. A line whose
    multiple coherence (the smallest over the responses) falls below ``coherence`` (default 0.5)
    keeps its previous estimate (the coherence guard: lines the iteration drives do not excite,
    or where noise dominates, are not re-estimated). ``Hinv`` is :class:`~.methods.InverseFrf`'s
    truncated-SVD / Tikhonov pseudo-inverse (with the method's ``rcond`` / ``tikhonov`` when the
    method is ``"frf"``, else their defaults): the closed-loop adaptive update of the transfer
    function of commercial time waveform replication.
``"secant"`` (:class:`SecantUpdate`)
    The method's correction ``c`` is multiplied, per band ``b`` of ``n_bands`` log-spaced bands
    over the simulation band (:func:`vrig.spectra.band_edges`), by a matrix ``S_b`` (drive channels x
    drive channels; on a SISO rig 1 x 1, a complex gain), starting at the
    identity. After each iteration the realised change, seen through the model
    (``z = c_{n-1} - c_n``, the model's drive for the response change), is compared with the
    drive change actually played (``du = ITnDRV - ITn-1DRV``), and ``S_b`` gets the (multi-)secant
    Broyden update that makes ``S_b z(f) = du(f)`` hold in the least-squares sense over the
    band's lines with the smallest change of ``S_b``:
    ``S_b += [sum_f (du - S_b z) z^H] [sum_f z z^H]^+`` (the pseudo-inverse: directions the band's
    changes did not excite keep their value; one excited direction gives Broyden's rank-one
    update). SISO: ``S_b`` becomes the complex ratio of the drive change to the realised response
    change through the model, i.e. it divides out the ratio of realised to predicted response
    change. On an LTI rig whose FRF is the model's times a constant matrix per band, the update
    is exact after one pair whose changes span the drives. Safeguards: a band is skipped when
    its realised change carries less than ``min_change`` (default 1e-4) of the largest band's
    energy, or its drive change less than ``min_change`` of the drive's energy in the band (a
    change of less than 1 % RMS, e.g. once the error is at its floor, where what changes is no
    longer what the drive change caused); the step ``M = S_b,new S_b^-1`` has its singular
    values (SISO: the ratio's magnitude) clipped to ``[1 / clip, clip]`` (default 4), phase
    kept.
``"reidentify"`` (:class:`ReidentifyUpdate`)
    Before each correction the method is refitted on the identification record and the
    iteration records (drive ITxxDRV, raw response RITxxRES), each processed as the
    identification is (identification band, model rate), faded in and out over the drive taper
    (so the joins are at rest) and concatenated; ``records`` (default None: all) keeps only the
    most recent iteration records. The fit is made on a copy of the method: a fit that raises, or
    an inverse that diverges (or is not finite) on DESRES or on the response, keeps the previous
    model, and the log says so (the identification's stability contract: a model is only
    replaced by one that runs). A fit the identification library refuses for its memory budget
    (``identification.MemoryBudgetError``, raised before anything is allocated) is retried
    without the oldest iteration records, each drop logged: memory stays bounded however many
    iterations run.
``"ilc"`` (:class:`IlcUpdate`)
    Norm-optimal iterative learning control in the frequency domain (lifted form per line): with
    ``G`` the H1 estimate of the identification records, the correction is ``L(f) E(f)``,
    ``L = (G^H Q G + R)^-1 G^H Q``, the minimiser of ``|E - G du|_Q^2 + |du|_R^2`` on each line.
    ``Q`` is diagonal, weight ``q`` per response (default 1); ``R(f) = r rho(f) I`` is weighted
    per line, ``rho(f)`` the largest eigenvalue of ``G^H Q G`` at that line (``r`` relative,
    default 0.1), so every line converges at the same nominal rate (SISO: ``L = G^-1 / (1 + r)``,
    the error shrinks by ``r / (1 + r)`` per iteration when ``G`` is right). (A constant ``R``, the
    classical choice, leaves the lines where ``|G|`` is small almost unlearnt: the shock
    absorber's ``|G|^2`` spans three decades over its band.) ``L`` is 0 outside the
    identification band (no drive there, no estimate). With the true FRF ``G0``,
    ``E_n+1 = (I - gain G0 L) E_n`` per line, so the error's norm decreases monotonically when
    ``|I - gain G0(f) L(f)|_2 < 1`` on every line (SISO: ``|1 - gain G0 L| < 1``; for
    ``G0 = a G``: ``|1 - gain a / (1 + r)| < 1``; :meth:`IlcUpdate.contraction`); a larger ``r``
    buys robustness to a wrong ``G`` with slower convergence. The model is not updated from the
    iteration.

Every rule has the interface ``start(engine)`` (after the identification, from
:meth:`~vrig.reconstruction.DriveIteration.first_drive`), ``observe(engine, drive, raw)`` (each
played drive and its raw response, from :meth:`~vrig.reconstruction.DriveIteration.play` and
:func:`~vrig.reconstruction.play_batch`) and ``correction(engine, response) -> ndarray (n,
n_inputs)``, the un-scaled correction for ITnRES, band-limited and tapered as a drive
(:meth:`~vrig.reconstruction.DriveIteration.next_drive` scales it by the gain as before). What a
rule did is appended to its ``log`` (one dict per event; ``result.updates``, ``summary.json``'s
``updates``).
"""

from __future__ import annotations

import copy
import math
from collections.abc import Mapping

import numpy as np

from identification import MemoryBudgetError

from ..processing import gprepro
from ..spectra import band_edges, frf_filter, frf_from_spectra, spectral_matrix
from ..timehistory import TimeHistory
from .methods import InverseFrf

__all__ = [
    "DEFAULT_OPTIONS",
    "FrfUpdate",
    "IlcUpdate",
    "ReidentifyUpdate",
    "SecantUpdate",
    "check_update_options",
    "make_update",
]

DEFAULT_OPTIONS: dict[str, dict] = {
    "none": {},
    "frf": {"forgetting": 0.5, "coherence": 0.5, "nperseg": 512},
    "secant": {"n_bands": 8, "clip": 4.0, "min_change": 1e-4},
    "reidentify": {"records": None},
    "ilc": {"q": 1.0, "r": 0.1, "nperseg": 512},
}
"""Each update's options and their defaults (see the module docstring)."""


def _real(v) -> bool:
    return isinstance(v, (int, float, np.number)) and not isinstance(v, bool) and math.isfinite(v)


def _count(v) -> bool:
    return isinstance(v, (int, np.integer)) and not isinstance(v, bool)


def _check_q(v) -> bool:
    try:
        q = np.asarray(v, dtype=float)
    except (TypeError, ValueError):
        return False
    return q.ndim <= 1 and q.size > 0 and bool(np.all(np.isfinite(q) & (q > 0)))


_CHECKS = {
    "forgetting": (lambda v: _real(v) and 0 <= v <= 1, "a factor in [0, 1]"),
    "coherence": (lambda v: _real(v) and 0 <= v < 1, "a coherence threshold in [0, 1)"),
    "nperseg": (lambda v: _count(v) and v >= 8, "an integer >= 8 (Welch segment, samples)"),
    "n_bands": (lambda v: _count(v) and v >= 1, "a positive integer"),
    "clip": (lambda v: _real(v) and v > 1, "a finite factor > 1"),
    "min_change": (lambda v: _real(v) and 0 <= v < 1, "an energy fraction in [0, 1)"),
    "records": (lambda v: v is None or (_count(v) and v >= 1), "None (all) or an integer >= 1"),
    "q": (_check_q, "a weight > 0, or one per response channel"),
    "r": (lambda v: _real(v) and v > 0, "a finite relative weight > 0"),
}


def check_update_options(update: str, options: Mapping) -> dict:
    """The options of ``update`` with its defaults filled in; ``ValueError`` for an option the
    update does not take or a value out of range.

    Parameters
    ----------
    update : str
        One of :data:`~vrig.reconstruction.settings.UPDATES`.
    options : mapping
        Option name -> value (see :data:`DEFAULT_OPTIONS`).

    Returns
    -------
    dict
    """
    defaults = DEFAULT_OPTIONS[update]
    unknown = sorted(set(options) - set(defaults))
    if unknown:
        takes = ", ".join(defaults) or "none"
        raise ValueError(
            f"update {update!r} takes no option {', '.join(map(repr, unknown))}; its options: "
            f"{takes}"
        )
    for name, value in options.items():
        ok, what = _CHECKS[name]
        if not ok(value):
            raise ValueError(f"update option {name} must be {what}, got {value!r}")
    return {**defaults, **options}


def make_update(update: str, options: Mapping | None = None):
    """The rule object of ``update`` (None for ``"none"``).

    Parameters
    ----------
    update : str
        One of :data:`~vrig.reconstruction.settings.UPDATES`.
    options : mapping, optional
        Its options (:func:`check_update_options`).

    Returns
    -------
    FrfUpdate, SecantUpdate, ReidentifyUpdate, IlcUpdate or None
    """
    if update not in DEFAULT_OPTIONS:
        raise ValueError(f"update must be one of {', '.join(DEFAULT_OPTIONS)}, got {update!r}")
    opts = check_update_options(update, options or {})
    if update == "none":
        return None
    cls = {"frf": FrfUpdate, "secant": SecantUpdate, "reidentify": ReidentifyUpdate,
           "ilc": IlcUpdate}[update]  # fmt: skip
    return cls(**opts)


def _model_records(engine, drive: TimeHistory, response: TimeHistory):
    """A drive and its raw response as the identification sees them: the identification band
    (GPREPRO), at the model rate."""
    band = engine.id_band
    return engine.down(gprepro(drive, band)), engine.down(gprepro(response, band))


def _describe(method) -> str:
    """The method's one line (``describe()`` is optional for a method object)."""
    describe = getattr(method, "describe", None)
    return describe() if callable(describe) else type(method).__name__


def _error(engine, response: TimeHistory) -> TimeHistory:
    """``DESRES - ITnRES`` (processed, at the rig rate)."""
    return engine.desres.with_data(engine.desres.data - response.data)


class _Spectra:
    """Cross spectra of drive/response records, accumulated with a forgetting factor (each
    record weighted by its length in samples)."""

    def __init__(self, nperseg: int, forgetting: float):
        self.nperseg, self.forgetting = nperseg, forgetting
        self.suu = self.syu = self.syy = None

    def add(self, u: np.ndarray, y: np.ndarray, fs: float) -> None:
        self.f, suu = spectral_matrix(u, fs=fs, nperseg=self.nperseg)
        _, syu = spectral_matrix(y, u, fs=fs, nperseg=self.nperseg)
        _, syy = spectral_matrix(y, fs=fs, nperseg=self.nperseg)
        w = float(u.shape[0])
        if self.suu is None:
            self.suu, self.syu, self.syy = w * suu, w * syu, w * syy
            return
        lam = self.forgetting
        self.suu = lam * self.suu + w * suu
        self.syu = lam * self.syu + w * syu
        self.syy = lam * self.syy + w * syy

    def h1(self):
        """The H1 estimate and the multiple coherence of the accumulated spectra (``S_uu``
        inverted wherever numerically non-singular: ``regularisation="line"``, as the FRF
        method's estimate)."""
        h1 = frf_from_spectra(self.f, self.suu, self.syu, self.syy, regularisation="line")
        return h1.frf, h1.coherence


def _segment(engine, nperseg: int, id_samples: int) -> int:
    """The Welch segment: ``nperseg``, at most a quarter of the identification record and of an
    iteration record at the model rate (every record's spectra on one grid of lines)."""
    n_model = -(-engine.n // engine.decimation)
    return max(8, min(nperseg, id_samples // 4, n_model // 4))


class FrfUpdate:
    """The ``"frf"`` update: corrections through an H1 FRF updated from every record (see the
    module docstring).

    Parameters
    ----------
    forgetting : float
        Weight factor of the older records at each new one, in [0, 1].
    coherence : float
        Lines whose multiple coherence is below this keep their previous estimate.
    nperseg : int
        Welch segment length [samples at the model rate] (at most a quarter of a record).
    """

    name = "frf"

    def __init__(self, *, forgetting: float = 0.5, coherence: float = 0.5, nperseg: int = 512):
        self.forgetting, self.coherence, self.nperseg = forgetting, coherence, nperseg
        self.log: list[dict] = []

    def start(self, engine) -> None:
        """Estimate the FRF from the identification records (IDDRV, IDRES).

        Parameters
        ----------
        engine : DriveIteration
            The identified engine.
        """
        m = engine.method
        reg = {"rcond": m.rcond, "tikhonov": m.tikhonov} if isinstance(m, InverseFrf) else {}
        self.frf = InverseFrf(**reg)
        d, r = _model_records(engine, engine.id_drive, engine.id_response)
        self.spectra = _Spectra(_segment(engine, self.nperseg, d.n_samples), self.forgetting)
        self.spectra.add(d.data, r.data, d.fs)
        H, coh = self.spectra.h1()
        self.frf.set_frf(self.spectra.f, H, d.fs)
        self.log.clear()
        self.log.append({"rule": "frf", "event": "start", "lines": int(H.shape[0]),
                         "median_coherence": float(np.median(coh.min(axis=1)))})  # fmt: skip

    def observe(self, engine, drive: TimeHistory, raw: TimeHistory) -> None:
        """Add a played drive and its raw response to the estimate (coherence-guarded).

        Parameters
        ----------
        engine : DriveIteration
            The engine.
        drive, raw : TimeHistory
            ITxxDRV and RITxxRES.
        """
        d, r = _model_records(engine, drive, raw)
        self.spectra.add(d.data, r.data, d.fs)
        H, coh = self.spectra.h1()
        keep = coh.min(axis=1) >= self.coherence
        H = np.where(keep[:, None, None], H, self.frf.H)
        self.frf.set_frf(self.frf.f, H, self.frf.fs)
        self.log.append({"rule": "frf", "event": "observe", "lines_updated": int(keep.sum()),
                         "lines": int(keep.size),
                         "median_coherence": float(np.median(coh.min(axis=1)))})  # fmt: skip

    def correction(self, engine, response: TimeHistory) -> np.ndarray:
        """``Hinv(f) E(f)`` at the rig rate, band-limited and tapered like a drive.

        Parameters
        ----------
        engine : DriveIteration
            The engine.
        response : TimeHistory
            ITnRES (processed).

        Returns
        -------
        ndarray (n, n_inputs)
        """
        return engine.shape(engine.up(self.frf.drive(engine.down(_error(engine, response)))))


class SecantUpdate:
    """The ``"secant"`` update: a per-band Broyden update of the method's correction (see the
    module docstring).

    Parameters
    ----------
    n_bands : int
        Number of log-spaced bands over the simulation band.
    clip : float
        Singular values of one step's ratio ``S_new S^-1`` are clipped to ``[1 / clip, clip]``.
    min_change : float
        A band whose realised change holds less than this fraction of the largest band's energy,
        or whose drive change less than this fraction of the drive's energy in the band, is not
        updated.
    """

    name = "secant"

    def __init__(self, *, n_bands: int = 8, clip: float = 4.0, min_change: float = 1e-4):
        self.n_bands, self.clip, self.min_change = n_bands, clip, min_change
        self.log: list[dict] = []

    def start(self, engine) -> None:
        """Every band's matrix the identity (the method's correction as it is).

        Parameters
        ----------
        engine : DriveIteration
            The identified engine.
        """
        self.edges = band_edges(engine.band, self.n_bands)
        eye = np.eye(engine.n_inputs, dtype=complex)
        self.S = np.repeat(eye[None], self.n_bands, axis=0)
        self.drives: list[np.ndarray] = []
        self.base: np.ndarray | None = None
        self.log.clear()
        self.log.append({"rule": "secant", "event": "start", "edges_hz": self.edges.tolist()})

    def observe(self, engine, drive: TimeHistory, raw: TimeHistory) -> None:
        """Keep the drive (the last two make the drive change).

        Parameters
        ----------
        engine : DriveIteration
            The engine.
        drive, raw : TimeHistory
            ITxxDRV and RITxxRES.
        """
        self.drives = [*self.drives[-1:], np.array(drive.data)]

    def _bands(self, n_fft: int, fs: float) -> np.ndarray:
        f = np.fft.rfftfreq(n_fft, 1.0 / fs)
        return np.clip(np.searchsorted(self.edges, f, side="right") - 1, 0, self.n_bands - 1)

    def _step(self, b: int, Z: np.ndarray, DU: np.ndarray) -> bool:
        """Broyden step of band ``b`` from its lines ``Z`` (realised, through the model) and
        ``DU`` (drive change); returns whether the step was clipped."""
        S = self.S[b]
        residual = DU - Z @ S.T  # rows: lines; S z = du is the secant condition
        gram = Z.T @ Z.conj()  # sum over the lines of z z^H
        S_new = S + residual.T @ Z.conj() @ np.linalg.pinv(gram, rcond=1e-9, hermitian=True)
        U, s, Vh = np.linalg.svd(S_new @ np.linalg.inv(S))
        clipped = np.clip(s, 1 / self.clip, self.clip)
        self.S[b] = (U * clipped) @ Vh @ S
        return bool(np.any(clipped != s))

    def _update(self, fs: float, u: np.ndarray, du: np.ndarray, z: np.ndarray) -> None:
        n_fft = 2 * du.shape[0]
        U, DU, Z = (np.fft.rfft(x, n=n_fft, axis=0) for x in (u, du, z))
        band = self._bands(n_fft, fs)

        def per_band(X):
            return np.bincount(band, np.sum(np.abs(X) ** 2, axis=1), minlength=self.n_bands)

        energy, e_du, e_u = per_band(Z), per_band(DU), per_band(U)
        updated, clipped, skipped = [], [], []
        for b in range(self.n_bands):  # a few bands; the lines of each are vectorised
            small = not (energy[b] > self.min_change * energy.max())
            if small or not e_du[b] > self.min_change * e_u[b]:
                skipped.append(b)
                continue
            sel = band == b
            (clipped if self._step(b, Z[sel], DU[sel]) else updated).append(b)
        self.log.append({
            "rule": "secant", "event": "update", "bands_updated": updated,
            "bands_clipped": clipped, "bands_skipped": skipped,
            "scale": [float(np.linalg.norm(s, 2)) for s in self.S],
        })  # fmt: skip

    def correction(self, engine, response: TimeHistory) -> np.ndarray:
        """The method's correction with each band multiplied by its matrix, after the secant
        update from the last drive change (tapered again like a drive); while every matrix is the
        identity, the method's correction itself.

        Parameters
        ----------
        engine : DriveIteration
            The engine.
        response : TimeHistory
            ITnRES (processed).

        Returns
        -------
        ndarray (n, n_inputs)
        """
        base = engine.base_correction(response)
        if self.base is not None and len(self.drives) == 2:
            u, du = self.drives[1], self.drives[1] - self.drives[0]
            self._update(engine.rig.fs, u, du, self.base - base)
        self.base = base
        if np.array_equal(self.S, np.broadcast_to(np.eye(self.S.shape[1]), self.S.shape)):
            return base  # no band updated yet: the method's correction as it is
        n = base.shape[0]
        X = np.fft.rfft(base, n=2 * n, axis=0)
        M = self.S[self._bands(2 * n, engine.rig.fs)]
        return engine._taper(np.fft.irfft(np.einsum("fij,fj->fi", M, X), n=2 * n, axis=0)[:n])


class ReidentifyUpdate:
    """The ``"reidentify"`` update: the method refitted on the identification and iteration
    records before each correction, keeping the previous model when a fit fails or diverges
    (see the module docstring).

    Parameters
    ----------
    records : int or None
        The most recent iteration records used (None: all), besides the identification record.
    """

    name = "reidentify"

    def __init__(self, *, records: int | None = None):
        self.records = records
        self.log: list[dict] = []

    def start(self, engine) -> None:
        """Keep the identification records (processed as the identification does).

        Parameters
        ----------
        engine : DriveIteration
            The identified engine.
        """
        self.id_record = _model_records(engine, engine.id_drive, engine.id_response)
        self.recent: list = []
        self.fresh = False
        self.log.clear()
        self.log.append({"rule": "reidentify", "event": "start", "records": 1,
                         "model": _describe(engine.method)})  # fmt: skip

    def observe(self, engine, drive: TimeHistory, raw: TimeHistory) -> None:
        """Add a played drive and its raw response to the records the next fit uses.

        Parameters
        ----------
        engine : DriveIteration
            The engine.
        drive, raw : TimeHistory
            ITxxDRV and RITxxRES.
        """
        self.recent.append(_model_records(engine, drive, raw))
        if self.records is not None:
            del self.recent[: -self.records]
        self.fresh = True

    def _concatenated(self, engine) -> tuple[TimeHistory, TimeHistory]:
        """The records faded in and out over the taper and concatenated (joins at rest)."""
        pairs = [self.id_record, *self.recent]
        fs = pairs[0][0].fs
        parts: list[list[np.ndarray]] = [[], []]
        for pair in pairs:
            n = pair[0].n_samples
            m = min(round(engine.taper * fs), n // 4)
            w = np.ones(n)
            if m > 0:
                ramp = np.hanning(2 * m + 1)[:m]
                w[:m], w[n - m :] = ramp, ramp[::-1]
            for k in (0, 1):
                parts[k].append(pair[k].data * w[:, None])
        d, r = self.id_record
        return d.with_data(np.concatenate(parts[0])), r.with_data(np.concatenate(parts[1]))

    def _refit(self, engine) -> None:
        """Fit a copy of the method; keep it only when it runs on DESRES. A fit refused by the
        identification library's memory budget (``MemoryBudgetError``: nothing allocated) is
        retried without the oldest iteration records, each drop logged: memory stays bounded
        however many iterations run."""
        previous = engine.method, engine.target
        while True:
            try:
                new = copy.deepcopy(engine.method)
                new.identify(*self._concatenated(engine))
                engine.method = new
                engine.target = engine._inverse(engine.desres, "DESRES")
                break
            except Exception as exc:  # the stability contract: a model that fails is not used
                engine.method, engine.target = previous
                if not (isinstance(exc, MemoryBudgetError) and self.recent):
                    self._kept(exc)
                    return
                del self.recent[0]
                self.log.append({"rule": "reidentify", "event": "dropped oldest record",
                                 "reason": "memory budget", "records": 1 + len(self.recent)})  # fmt: skip
        samples = sum(p[0].n_samples for p in [self.id_record, *self.recent])
        self.log.append({"rule": "reidentify", "event": "refit",
                         "records": 1 + len(self.recent), "samples": int(samples),
                         "model": _describe(engine.method)})  # fmt: skip

    def _kept(self, exc: BaseException) -> None:
        self.log.append({"rule": "reidentify", "event": "kept previous model",
                         "reason": f"{type(exc).__name__}: {exc}"})  # fmt: skip

    def correction(self, engine, response: TimeHistory) -> np.ndarray:
        """The refitted method's correction ``inverse(DESRES) - inverse(ITnRES)``.

        Parameters
        ----------
        engine : DriveIteration
            The engine.
        response : TimeHistory
            ITnRES (processed).

        Returns
        -------
        ndarray (n, n_inputs)
        """
        previous = engine.method, engine.target
        if self.fresh:
            self._refit(engine)
            self.fresh = False
        if engine.method is previous[0]:
            return engine.base_correction(response)
        try:
            return engine.base_correction(response)
        except Exception as exc:  # diverges on the response: back to the previous model
            engine.method, engine.target = previous
            self._kept(exc)
            return engine.base_correction(response)


class IlcUpdate:
    """The ``"ilc"`` update: norm-optimal ILC with the identified forward FRF (see the module
    docstring).

    Parameters
    ----------
    q : float or sequence of float
        Error weight per response channel (``Q = diag(q)``).
    r : float
        Drive weight relative to each line's largest eigenvalue of ``G^H Q G``
        (``R(f) = r rho(f) I``).
    nperseg : int
        Welch segment length of the H1 estimate [samples at the model rate].
    """

    name = "ilc"

    def __init__(self, *, q=1.0, r: float = 0.1, nperseg: int = 512):
        self.q, self.r, self.nperseg = q, r, nperseg
        self.log: list[dict] = []

    def start(self, engine) -> None:
        """Estimate ``G`` (H1, identification records) and the learning filter ``L``.

        Parameters
        ----------
        engine : DriveIteration
            The identified engine.
        """
        d, r = _model_records(engine, engine.id_drive, engine.id_response)
        spectra = _Spectra(_segment(engine, self.nperseg, d.n_samples), 1.0)
        spectra.add(d.data, r.data, d.fs)
        G, _ = spectra.h1()
        try:
            q = np.broadcast_to(np.asarray(self.q, dtype=float), (G.shape[1],))
        except ValueError:
            raise ValueError(
                f"update option q must be one weight or one per response ({G.shape[1]}), got "
                f"{self.q!r}"
            ) from None
        GhQ = G.conj().transpose(0, 2, 1) * q[None, None, :]
        A = GhQ @ G
        rho = np.linalg.eigvalsh(A)[:, -1]  # per line
        lo, hi = engine.id_band
        inside = (spectra.f >= lo) & (spectra.f <= hi) & (rho > 0)
        eye = np.eye(G.shape[2])
        self.f, self.fs, self.G = spectra.f, d.fs, G
        self.L = np.zeros(GhQ.shape, dtype=complex)  # (F, n_in, n_out)
        R = self.r * rho[inside, None, None] * eye
        self.L[inside] = np.linalg.solve(A[inside] + R, GhQ[inside])
        self.log.clear()
        self.log.append({"rule": "ilc", "event": "start", "lines": int(inside.sum()),
                         "nominal_rate": self.r / (1 + self.r)})  # fmt: skip

    def contraction(self, G_true: np.ndarray, gain: float = 1.0) -> np.ndarray:
        """``|I - gain G_true(f) L(f)|_2`` per line: the error's norm decreases monotonically
        when this is below 1 on every line.

        Parameters
        ----------
        G_true : ndarray (F, n_responses, n_drives)
            The rig's FRF on the lines ``self.f`` [Hz].
        gain : float
            The iteration gain.

        Returns
        -------
        ndarray (F,)
        """
        eye = np.eye(G_true.shape[1])
        return np.linalg.norm(eye - gain * G_true @ self.L, ord=2, axis=(1, 2))

    def observe(self, engine, drive: TimeHistory, raw: TimeHistory) -> None:
        """Nothing is learnt from the iteration (the model stays the identified one).

        Parameters
        ----------
        engine : DriveIteration
            The engine.
        drive, raw : TimeHistory
            ITxxDRV and RITxxRES.
        """

    def correction(self, engine, response: TimeHistory) -> np.ndarray:
        """``L(f) E(f)`` at the rig rate, band-limited and tapered like a drive.

        Parameters
        ----------
        engine : DriveIteration
            The engine.
        response : TimeHistory
            ITnRES (processed).

        Returns
        -------
        ndarray (n, n_inputs)
        """
        error = engine.down(_error(engine, response))
        x = frf_filter(self.L, self.f, self.fs, error.data, dc=False)
        self.log.append({"rule": "ilc", "event": "correction",
                         "error_rms": np.sqrt(np.mean(error.data**2, axis=0)).tolist()})  # fmt: skip
        return engine.shape(engine.up(x))
