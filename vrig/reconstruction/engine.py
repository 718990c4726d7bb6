"""The drive-iteration engine: one reconstruction, step by step (§1.3, App. G).

:class:`DriveIteration` identifies the inverse model (IDDRV -> rig -> IDRES), computes the first
drive (IT00DRV = inverse(DESRES)), plays drives on the rig and computes the corrections; the loop
that strings these together is :func:`vrig.reconstruct` (:mod:`.iteration`), and the gymnasium
environments drive the same engine a step at a time.
"""

from __future__ import annotations

import numpy as np
from scipy import signal
from scipy.signal import windows

from identification.errors import SimulationDivergedError

from ..errors import RigLimitError, SimulationInstabilityError
from ..percent import percent
from ..processing import band_gains, check_band, decimate, gprepro, identification_band
from ..progress import status
from ..rigs.limits import check_drive_limits
from ..timehistory import TimeHistory
from .defaults import BUILT_IN, CALLER, DEFAULT_ID_RMS_FRACTION
from .defaults import resolved as resolve_settings
from .id_drive import identification_run
from .matching import identify_matched, level_ratios
from .methods import make_method
from .protocol import ObservingMethod
from .scores import pseudo_damages, scores
from .settings import IterationSettings
from .updates import make_update

__all__ = ["DriveIteration", "play_batch"]

_PLAY_ERRORS = (RigLimitError, SimulationInstabilityError, SimulationDivergedError)
"""What :func:`play_batch` returns in a drive's slot (what :meth:`DriveIteration.play` raises
for a drive the rig refuses, trips on or cannot simulate)."""


def _check_drive(rig, drive: np.ndarray, what: str) -> None:
    check_drive_limits(rig.inputs, drive, fs=rig.fs, what=what)


def _check_id_rms(id_rms, full: np.ndarray) -> np.ndarray:
    """Identification drive RMS per channel: finite, > 0 and at most the full scale."""
    rms = np.asarray(id_rms, float)
    try:
        rms = np.broadcast_to(rms, full.shape)
    except ValueError:
        raise ValueError(
            f"id_rms must be one value or one per drive channel ({full.size}), got {id_rms!r}"
        ) from None
    if not np.all(np.isfinite(rms) & (rms > 0) & (rms <= full)):
        raise ValueError(
            f"id_rms must be finite, > 0 and <= each drive's full scale {full.tolist()}, "
            f"got {rms.tolist()}"
        )
    return rms


def _check_content(desired: TimeHistory, desres: TimeHistory, band) -> None:
    """See :meth:`DriveIteration.check_desired`."""
    scale = np.abs(desired.data).max(axis=0)
    rms = np.sqrt(np.mean(desres.data**2, axis=0))
    empty = ~(rms > 1e-9 * scale)
    if empty.any():
        k = int(np.argmax(empty))
        raise ValueError(
            f"desired channel {desired.names[k]!r} has no content in the simulation band "
            f"{band[0]:g}-{band[1]:g} Hz after de-trending and DC removal (RMS {rms[k]:.3g} "
            f"against a peak of {scale[k]:.3g}): a constant or out-of-band record cannot be "
            "reconstructed"
        )


def _describe(method) -> str:
    """``"ARX(4)"``, ``"NARX(4, degree 2)"``, ``"FRF"``, ... for status lines: the method as
    configured (a searched NARX: ``"NARX structure search (degree up to 2)"``); the model a fit
    chose is :func:`_fitted_structure`'s."""
    name = str(getattr(method, "name", type(method).__name__)).upper()
    order, degree = getattr(method, "order", None), getattr(method, "degree", None)
    if getattr(method, "search", False) is True:
        return f"{name} structure search" + (f" (degree up to {degree})" if degree else "")
    if order is None:
        return name
    return f"{name}({order}" + (f", degree {degree}" if degree else "") + ")"


def _fitted_structure(method) -> str:
    """The structure of the model ``method``'s last fit chose: after a structure search the
    chosen candidate (``"NARX order 3, degree 2 input-polynomial, LS, FROLS, chosen by the
    structure search"``), else the method as configured (:func:`_describe`; its fit has that
    structure); a split names its bands'."""
    low, high = getattr(method, "low", None), getattr(method, "high", None)
    if low is not None and high is not None:
        return f"low band {_fitted_structure(low)}, high band {_fitted_structure(high)}"
    search = getattr(getattr(method, "inverse", None), "search_", None)
    if search is None:
        return _describe(method)
    chosen = search.best_result_.candidate
    name = "NARX" if chosen.degree > 1 else "ARX"
    return f"{name} {chosen.label()}, chosen by the structure search"


def _term_degree(model) -> int:
    """The largest number of non-constant factors of any term of a fitted Narx / Arx (1: a
    linear model, whatever degree its structure allowed: a term selection may keep no product)."""
    return max(
        (int(np.max(np.count_nonzero(ch.terms, axis=1), initial=0)) for ch in model.channels_),
        default=0,
    )


def _fitted_degree(method) -> int:
    """The polynomial degree of ``method``'s fitted inverse: the largest term degree of its
    model (an error-signal model's two parts), so a search that chose a linear candidate, or a
    term selection that kept no product, gives 1; a method without a fitted polynomial model
    (FRF, before a fit, another kind of method object) its configured ``degree`` (none: 1)."""
    model = getattr(getattr(method, "inverse", None), "model", None)
    parts = [getattr(model, "linear", None), getattr(model, "nonlinear", None)]
    parts = [p for p in (parts if parts[0] is not None else [model]) if p is not None]
    if parts and all(hasattr(p, "channels_") for p in parts):
        return max(_term_degree(p) for p in parts)
    return int(getattr(method, "degree", None) or 1)


def _is_polynomial(method) -> bool:
    """Whether ``method``'s fitted inverse (or a band's of a split) is polynomial: a term of
    degree >= 2 (:func:`_fitted_degree`; a linear inverse extrapolates linearly)."""
    parts = [getattr(method, "low", None), getattr(method, "high", None), method]
    return any(_fitted_degree(p) > 1 for p in parts if p is not None)


def _extrapolation_note(method, peak_ratio, names) -> str | None:
    """The note of a polynomial inverse identified on responses that peak below DESRES's:
    the inverse is then evaluated outside the amplitude range it was fitted on, where its
    polynomial terms extrapolate (a quadratic term at 3x the range is 9x), and its drive can
    overshoot - the user's-rig NARX of issue 25 stopped at IT01 on a drive beyond full scale
    for it, where the linear inverses ran (their extrapolation is linear). None otherwise.
    ``method`` is the fitted one: the note names the structure the fit chose
    (:func:`_fitted_structure`) and the peak ratio is never printed as 100 % (:func:`percent`)."""
    ratio = np.asarray(peak_ratio, dtype=float)
    if not _is_polynomial(method) or not np.all(np.isfinite(ratio)) or ratio.min() >= 1.0:
        return None
    k = int(np.argmin(ratio))
    return (
        f"note: the polynomial inverse ({_fitted_structure(method)}) is identified on responses "
        f"that peak at {percent(ratio[k], threshold=1.0)} of the desired response's peak "
        f"({names[k]}): beyond that its polynomial extrapolates and its drive may overshoot; "
        "identify matched to the target (id_match=True, vrig reconstruct --id-match) or at a "
        "higher id_rms"
    )


def _level_reason(source: str) -> str:
    """Why the identification drive has its level, from where the resolver took ``id_rms``."""
    if source == CALLER:
        return "the given id_rms"
    if source == BUILT_IN:
        return f"the default level ({100 * DEFAULT_ID_RMS_FRACTION:g} % of full scale rms)"
    return f"the rig's own level ({source}.id_rms)"


class DriveIteration:
    """One reconstruction, step by step: the engine of :func:`reconstruct` and of the gymnasium
    environments (so a policy's fixed gain reproduces ``reconstruct`` exactly).

    >>> it = DriveIteration(rig, desired, method="arx", seed=0)   # doctest: +SKIP
    >>> it.identify()                             # IDDRV -> IDRES -> model   # doctest: +SKIP
    >>> drive = it.first_drive()                  # IT00DRV = inverse(DESRES) # doctest: +SKIP
    >>> drv, raw, res, (eta0, rms, damage) = it.play(drive, 0)  # RIT00RES, IT00RES # doctest: +SKIP
    >>> drive = it.next_drive(drive, res, gain=0.8)  # IT01DRV                # doctest: +SKIP

    ``play`` raises :class:`~vrig.RigLimitError` for a drive beyond the rig's limits *before*
    sending it, or when the rig trips. A drive that was refused or tripped the rig (in ``play``
    or ``identify``) is kept in ``rejected`` as ``("REFUSEDxx" | "TRIPPEDxx", drive)`` (``xx``
    the iteration, ``ID`` for the identification drive) until the next drive is played; a drive
    that is not finite is refused but not kept.

    Parameters
    ----------
    rig : Rig
        The rig (:class:`~vrig.rigs.Rig` protocol).
    desired : TimeHistory
        The desired response (DESRES before processing), the rig's outputs at ``rig.fs``.
    settings : IterationSettings or ResolvedSettings, optional
        The iteration's settings (default: the defaults), resolved here by the one resolver
        (:func:`vrig.reconstruction.defaults.resolve`: the caller's values, then the rig
        side-car's, then the built-in defaults; kept in :attr:`resolved`, the filled-in settings
        in :attr:`settings`); settings resolved already (a ``ResolvedSettings``) are used as they
        are. The engine uses the identification ones and ``id_seed`` / ``run_seed``, the loop's
        (gain, iterations, ...) are :func:`reconstruct`'s.
    **options
        Settings by name applied on top of ``settings`` (see :meth:`IterationSettings.build`).
    """

    def __init__(
        self,
        rig,
        desired: TimeHistory,
        settings: IterationSettings | None = None,
        **options,
    ):
        if not isinstance(desired, TimeHistory):
            raise TypeError("desired must be a vrig.TimeHistory")
        if desired.fs != rig.fs:
            raise ValueError(f"desired is sampled at {desired.fs:g} Hz, the rig at {rig.fs:g} Hz")
        if desired.n_channels != len(rig.outputs):
            raise ValueError(
                f"desired has {desired.n_channels} channels, the rig {len(rig.outputs)} responses"
            )
        resolved = resolve_settings(rig, settings, **options)  # the one resolver
        self.resolved = resolved
        s = self.settings = resolved.settings
        self.rig = rig
        self.band = check_band(s.bandwidth, rig.fs, "bandwidth")
        self.id_band = identification_band(self.band, fs=rig.fs)
        self.method = resolved.method
        self.decimation = (
            max(1, int(rig.fs // (8 * self.id_band[1]))) if s.decimation is None else s.decimation
        )
        self.taper = float(s.taper)
        self.n_inputs = len(rig.inputs)
        full = np.array([c.full_scale for c in rig.inputs])
        self.id_rms = _check_id_rms(s.id_rms, full)  # resolved: never None here
        self.id_psd = s.id_psd
        self.id_samples = round((s.id_duration or desired.duration) * rig.fs)
        self.desres = gprepro(desired, self.band)
        self._desired = desired
        self.n = self.desres.n_samples
        self.names = [c.name for c in rig.inputs]
        self.names_out = [c.name for c in rig.outputs]
        self.units = [c.unit for c in rig.inputs]
        self.id_drive: TimeHistory | None = None
        self.id_response: TimeHistory | None = None
        self.target: np.ndarray | None = None
        self.rejected: tuple[str, TimeHistory] | None = None
        self.id_matching = None  # MatchedIdentification of an id_match identification
        self.id_report: dict | None = None  # which identification level was used and why
        self.updater = make_update(s.update, s.update_options)  # None: update="none"

    # -- resampling between the rig rate and the model rate
    def down(self, th: TimeHistory) -> TimeHistory:
        """A record at the model rate (``fs / decimation``, zero-phase anti-alias filter).

        Parameters
        ----------
        th : TimeHistory
            A record at the rig rate.

        Returns
        -------
        TimeHistory
        """
        return decimate(th, self.decimation)

    def up(self, x: np.ndarray) -> np.ndarray:
        """Samples at the model rate interpolated back to the rig rate (``n`` samples).

        Parameters
        ----------
        x : ndarray (n_model_samples, n_channels)
            A drive at the model rate.

        Returns
        -------
        ndarray (n, n_channels)
        """
        if self.decimation == 1:
            return x
        return signal.resample_poly(x, self.decimation, 1, axis=0)[: self.n]

    def identify(self) -> None:
        """IDDRV -> IDRES -> inverse model (after :meth:`check_length`).

        Default: IDDRV from ``id_psd`` (triangular over the identification band) at ``id_rms``
        (5 % of full scale), the RMS halved (up to ten times: 1/1024) while the rig refuses or
        trips on it (a level set from the drives' full scales knows nothing of the responses'
        ranges: a user's rig may take only a small fraction of it, as vrig.desired.pseudo_field.pseudo_field
        says). With ``id_match`` the drive is matched to DESRES's spectrum and amplitude range
        (:func:`~vrig.reconstruction.matching.identify_matched`; what it did is kept in
        ``id_matching``). Either way ``id_report`` says which level was used and why, and how
        the identification response's RMS and peak compare with DESRES's; a default
        identification of a polynomial inverse whose responses peak below DESRES's adds an
        ``"extrapolation"`` note (the inverse will be used beyond its fitted range)."""
        self.check_length()
        if self.settings.id_match:
            iddrv, idres, self.id_matching = identify_matched(self)
            self.id_report = self.id_matching.summary()
            status(f"identification matched to the target: {self.id_report['reason']}")
        else:
            iddrv, idres = self._identify_default()
        self.id_drive, self.id_response = iddrv, idres
        self._fit(iddrv, idres)
        if not self.settings.id_match:  # after the fit: the note names the model it chose
            note = _extrapolation_note(self.method, self.id_report["peak_ratio"], self.names_out)
            if note:
                self.id_report["extrapolation"] = note
                status(note)

    def _identify_default(self) -> tuple[TimeHistory, TimeHistory]:
        """The default IDDRV and IDRES (see :meth:`identify`; the one identification drive,
        :func:`~vrig.reconstruction.id_drive.identification_run`); fills ``id_report``."""
        rig, seed = self.rig, self.settings.id_seed
        run = identification_run(
            rig, self.band, self.id_samples, self.id_rms, seed=seed, psd=self.id_psd,
            send=lambda drive: self._send(drive, "ID", "the identification drive", seed),
        )  # fmt: skip
        iddrv, idres, rms, attempt, last_trip = (
            run.drive, run.response, run.rms, run.halvings, run.last_trip,
        )  # fmt: skip
        self.id_report = {
            "mode": "default",
            "rms_percent": (100 * rms / [c.full_scale for c in rig.inputs]).tolist(),
            **level_ratios(self.desres, gprepro(idres, self.band)),
            "reason": _level_reason(self.resolved.sources.get("id_rms", CALLER)),
        }
        if attempt:
            self.id_report["reason"] += f", halved {attempt}x after interlock trips ({last_trip})"
        return iddrv, idres

    def reidentify(self, drive: TimeHistory, raw: TimeHistory) -> None:
        """Adaptive strategy: re-fit the inverse from the latest drive / raw response pair.

        Parameters
        ----------
        drive : TimeHistory
            The drive last played (ITxxDRV).
        raw : TimeHistory
            The rig's raw response to it (RITxxRES).
        """
        self._fit(drive, raw)

    def _fit(self, drive: TimeHistory, response: TimeHistory) -> None:
        status(f"fitting the inverse model: {_describe(self.method)} ...")
        self.method.identify(
            self.down(gprepro(drive, self.id_band)), self.down(gprepro(response, self.id_band))
        )
        self.target = self._inverse(self.desres, "DESRES")

    def _inverse(self, response: TimeHistory, what: str) -> np.ndarray:
        """The method's drive for ``response`` at the model rate; a non-finite value raises
        :class:`~identification.SimulationDivergedError` (as a diverging free run does)."""
        x = np.asarray(self.method.drive(self.down(response)), dtype=float)
        bad = ~np.isfinite(x)
        if bad.any():
            i, j = np.argwhere(bad)[0]
            raise SimulationDivergedError(
                j, f"{self.names[j]} (inverse of {what})", i, x[i, j], np.inf
            )
        return x

    def use_identified(self, method, id_drive: TimeHistory, id_response: TimeHistory) -> None:
        """Take an already identified method (e.g. a cached inverse model, identified by
        :meth:`identify` on the same rig, band and settings) instead of identifying again.

        Parameters
        ----------
        method : Method
            The identified method.
        id_drive, id_response : TimeHistory
            The identification records it was identified from (IDDRV, IDRES).
        """
        self.method = make_method(method)
        self.id_drive, self.id_response = id_drive, id_response
        self.target = self._inverse(self.desres, "DESRES")

    def shape(self, x: np.ndarray) -> np.ndarray:
        """A drive (or drive correction) as it may be sent: band-limited to the identification
        band (zero-phase, as every other record: what the model does outside the band it was
        identified in is drift, not information) and tapered to zero over the first and last
        ``taper`` seconds (the rig starts and ends at rest; a step at the start would trip the
        following-error interlock).

        Parameters
        ----------
        x : ndarray (n, n_inputs)
            A drive or correction at the rig rate, in the drives' units.

        Returns
        -------
        ndarray (n, n_inputs)
        """
        th = TimeHistory(x, self.rig.fs, self.names, self.units)
        y = np.array(gprepro(th, self.id_band, detrend=False).data)
        m = min(round(self.taper * self.rig.fs), self.n // 4)
        if m > 0:
            ramp = windows.hann(2 * m + 1)[:m]  # the rising half of a raised cosine
            y[:m] *= ramp[:, None]
            y[self.n - m :] *= ramp[::-1, None]
        return y

    def check_desired(self) -> None:
        """Raise ``ValueError`` when a desired channel has nothing to reproduce in the band
        (constant, a pure trend or out of band): its η0 would be a ratio of round-off
        (2.3e14 % for a constant record), or when the identification record is too short for
        the method (:meth:`check_length`). Called by :meth:`first_drive` and, before the
        identification, by :func:`reconstruct`; identifying alone needs no desired content."""
        self.check_length()
        _check_content(self._desired, self.desres, self.band)

    def check_length(self) -> None:
        """Raise ``ValueError`` before anything is played when the identification record is
        shorter than the method needs.

        The rule: the identification record (``id_duration``, by default the desired record's
        length) at the model rate ``fs / decimation`` must hold the method's ``min_samples``
        (a method without one: no check): a time-domain inverse needs its delay estimate
        (``max_lead +`` :data:`~vrig.reconstruction.methods.DELAY_SAMPLES`, 128 samples at the
        default lead search) and one sample per term of its largest channel after its lags;
        the H1 inverse :data:`~vrig.reconstruction.methods.FRF_MIN_SAMPLES`; split spectra the
        larger of its two bands'. The model's own fit checks the rest (e.g. a term selection).
        """
        need_fn = getattr(self.method, "min_samples", None)
        if need_fn is None:
            return
        need = int(need_fn(self.n_inputs, len(self.rig.outputs)))
        have = -(-self.id_samples // self.decimation)
        if have >= need:
            return
        fs_model = self.rig.fs / self.decimation
        where = (
            f"id_duration {self.settings.id_duration:g} s"
            if self.settings.id_duration is not None
            else f"the desired record's {self._desired.duration:g} s"
        )
        raise ValueError(
            f"the identification record ({where}) is {have} samples at the model rate "
            f"{fs_model:g} Hz, but the {_describe(self.method)} inverse needs at least {need} "
            f"({need / fs_model:.3g} s): give a longer desired record (or id_duration), a "
            "lower order, or a method needing fewer samples (frf)"
        )

    def first_drive(self) -> np.ndarray:
        """IT00DRV = inverse(DESRES), band-limited and tapered (:meth:`shape`), at the rig rate."""
        if self.target is None:
            raise RuntimeError("identify() first")
        self.check_desired()
        if self.updater is not None:  # the update rule starts from the identification
            self.updater.start(self)
        return self.shape(self.up(self.target))

    def play(self, drive: np.ndarray, iteration: int):
        """Check and send ``drive`` (ITxxDRV); returns (drive, raw, processed, (η0, rms, damage)).

        Raises RigLimitError (nothing is sent when the drive itself is beyond the limits).

        Parameters
        ----------
        drive : ndarray (n, n_inputs) or TimeHistory
            The drive, at the rig rate.
        iteration : int
            Its iteration number xx (names the records; the rig run is seeded with
            ``run_seed + 1 + xx``).

        Returns
        -------
        drive, raw, processed : TimeHistory
            ITxxDRV, RITxxRES and ITxxRES (GPREPRO over the simulation band).
        scores : (eta0, rms_error, damage_ratio)
            Per response channel (:func:`~vrig.reconstruction.scores.scores`).
        """
        tag, what, run_seed = self._play_names(iteration)
        drv, raw = self._send(drive, tag, what, run_seed)
        return self._processed(drv, raw)

    def _play_names(self, iteration: int) -> tuple[str, str, int]:
        """(tag ``xx``, record name ``ITxxDRV``, rig run seed ``run_seed + 1 + xx``)."""
        return (
            f"{iteration:02d}",
            f"IT{iteration:02d}DRV",
            self.settings.rig_run_seed + 1 + iteration,
        )

    def _processed(self, drv: TimeHistory, raw: TimeHistory):
        """(ITxxDRV, RITxxRES, ITxxRES, scores) of a played drive (see :meth:`play`); the
        update rule, if any, observes the pair."""
        if self.updater is not None:
            self.updater.observe(self, drv, raw)
        res = gprepro(raw, self.band)
        if isinstance(self.method, ObservingMethod):  # e.g. a Rattlesnake law's last signals
            self.method.observe(self.down(drv), self.down(res))
        return drv, raw, res, scores(self.desres, res, desired_damage=self._desired_damage())

    def _desired_damage(self) -> np.ndarray:
        """``pseudo_damages(self.desres)``, computed once per desired response (every iteration
        is scored against it)."""
        kept = getattr(self, "_damage_of", None)
        if kept is None or kept[0] is not self.desres:  # TimeHistory data are read-only
            kept = self._damage_of = (self.desres, pseudo_damages(self.desres))
        return kept[1]

    def _send(self, drive, tag: str, what: str, seed: int):
        """Check ``drive`` (TimeHistory or array) against the limits and play it; returns
        (drive as TimeHistory, raw response). A refused drive or one that trips the rig (an
        interlock, an unstable simulation) is kept in ``rejected`` before the error goes on."""
        drv = self._checked(drive, tag, what)
        try:
            raw = self.rig.run(drv, seed=seed)
        except (RigLimitError, SimulationInstabilityError):
            self.rejected = (f"TRIPPED{tag}", drv)
            raise
        return drv, raw

    def _checked(self, drive, tag: str, what: str) -> TimeHistory:
        """``drive`` as a TimeHistory once checked against the limits (the first half of
        :meth:`_send`: ``rejected`` cleared, a refused finite drive kept as ``REFUSEDxx``)."""
        self.rejected = None
        data = drive.data if isinstance(drive, TimeHistory) else np.asarray(drive, dtype=float)
        drv = None
        if np.all(np.isfinite(data)):
            drv = drive if isinstance(drive, TimeHistory) else self._th(data)
        try:
            _check_drive(self.rig, data, what)
        except RigLimitError:
            self.rejected = None if drv is None else (f"REFUSED{tag}", drv)
            raise
        return drv

    def _th(self, data: np.ndarray) -> TimeHistory:
        return TimeHistory(data, self.rig.fs, self.names, self.units)

    @property
    def update_log(self) -> list:
        """What the update rule did (one dict per event, :mod:`.updates`); ``[]`` without one."""
        return [] if self.updater is None else self.updater.log

    def correction(self, response: TimeHistory) -> np.ndarray:
        """The un-scaled update for ITxxRES: the update rule's (``settings.update``,
        :mod:`.updates`), else :meth:`base_correction`.

        Parameters
        ----------
        response : TimeHistory
            The processed response of the last iteration (ITxxRES).

        Returns
        -------
        ndarray (n, n_inputs)
        """
        if self.updater is not None:
            return self.updater.correction(self, response)
        return self.base_correction(response)

    def base_correction(self, response: TimeHistory) -> np.ndarray:
        """``inverse(DESRES) - inverse(ITxxRES)`` at the rig rate (the un-scaled update),
        band-limited and tapered like the drive (:meth:`shape`).

        Parameters
        ----------
        response : TimeHistory
            The processed response of the last iteration (ITxxRES).

        Returns
        -------
        ndarray (n, n_inputs)
        """
        return self.shape(self.up(self.target - self._inverse(response, "the response")))

    def next_drive(self, drive: np.ndarray, response: TimeHistory, gain, edges=None) -> np.ndarray:
        """``ITn+1DRV = ITnDRV + gain * (inverse(DESRES) - inverse(ITnRES))``.

        With complex per-band gains ``g * exp(1j * phi)`` the correction's band is scaled by
        ``g`` and its phase advanced by ``phi`` rad (:func:`~vrig.processing.band_gains`; a
        pure delay of the band's content when ``phi < 0``), then tapered again like the drive
        (:meth:`shape`: the phase shift spreads the correction a little into the tapered ends,
        and the rig starts and ends at rest). Complex gains with all phases 0 are the real
        gains, bit for bit.

        Parameters
        ----------
        drive : ndarray (n, n_inputs)
            ITnDRV.
        response : TimeHistory
            ITnRES (processed).
        gain : float, sequence or ndarray (n_inputs, n_bands)
            A scalar, one value per drive channel, or one per channel and band (real, or
            complex: magnitude and phase per channel and band).
        edges : sequence of float, optional
            Band edges [Hz] of per-band gains (see :func:`~vrig.processing.band_gains`).

        Returns
        -------
        ndarray (n, n_inputs)
            ITn+1DRV.
        """
        corr = self.correction(response)
        g = np.asarray(gain)
        if np.iscomplexobj(g) and np.any(g.imag):
            if g.ndim != 2 or edges is None:
                raise ValueError(
                    "complex (phase-shifting) gains must be per channel and band (n_inputs, "
                    f"n_bands) with the band edges, got shape {g.shape}"
                )
            return drive + self._taper(band_gains(corr, self.rig.fs, g, edges))
        g = np.asarray(g.real if np.iscomplexobj(g) else g, dtype=float)
        if g.ndim == 2:
            if edges is None:
                raise ValueError("per-band gains need the band edges")
            return drive + band_gains(corr, self.rig.fs, g, edges)
        return drive + np.broadcast_to(g, (self.n_inputs,)) * corr

    def _taper(self, y: np.ndarray) -> np.ndarray:
        """``y`` tapered to zero over its first and last ``taper`` seconds (the ramp of
        :meth:`shape`, without the band limit)."""
        m = min(round(self.taper * self.rig.fs), self.n // 4)
        if m > 0:
            ramp = windows.hann(2 * m + 1)[:m]
            y = y.copy()
            y[:m] *= ramp[:, None]
            y[self.n - m :] *= ramp[::-1, None]
        return y


def play_batch(engines, drives, iterations, *, threads: int | None = None) -> list:
    """:meth:`DriveIteration.play` of many engines on one rig, their rig runs in one batch
    (:func:`vrig.rigs.run_batch`: across threads on a MuJoCo rig).

    Each engine (its own desired response and run seed) plays one drive; slot ``i`` is what
    ``engines[i].play(drives[i], iterations[i])`` returns, bit for bit, or the exception it
    raises (:class:`~vrig.RigLimitError`, :class:`~vrig.errors.SimulationInstabilityError`,
    :class:`~identification.SimulationDivergedError`), with the same ``rejected`` bookkeeping
    (``REFUSEDxx`` / ``TRIPPEDxx``) on each engine. Any other error (e.g. a drive of the wrong
    shape) is raised, the first one's (lowest index), once every drive has been played.
    When no two engines share an engine, method or update rule object, each play's
    processing and scores run in the rig's worker thread as soon as its run ends (beside the
    other runs: :meth:`vrig.rigs.MujocoRig.run_batch`'s ``then``); else in drive order after
    the batch. The results are the same either way.

    Parameters
    ----------
    engines : sequence of DriveIteration
        The engines, all on the same rig object.
    drives : sequence of ndarray (n, n_inputs) or TimeHistory
        One drive per engine, at the rig rate.
    iterations : int or sequence of int
        Each drive's iteration number xx (one for all, or one per engine).
    threads : int, optional
        Worker threads of the rig's batch (see :meth:`vrig.rigs.MujocoRig.run_batch`).

    Returns
    -------
    list of tuple or Exception
        Per engine, ``(drive, raw, processed, (eta0, rms_error, damage_ratio))`` as
        :meth:`DriveIteration.play` returns, or the exception in its slot.
    """
    from ..rigs import run_batch

    engines, drives = list(engines), list(drives)
    its = [iterations] * len(engines) if np.ndim(iterations) == 0 else list(iterations)
    if not len(drives) == len(its) == len(engines):
        raise ValueError(
            f"play_batch needs one drive and one iteration per engine ({len(engines)}), got "
            f"{len(drives)} drives and {len(its)} iterations"
        )
    if engines and any(e.rig is not engines[0].rig for e in engines):
        raise ValueError("play_batch: every engine must play on the same rig object")
    out: list = [None] * len(engines)
    sent, names = [], []
    for i, (engine, drive, it) in enumerate(zip(engines, drives, its, strict=True)):
        tag, what, seed = engine._play_names(it)
        try:
            sent.append((i, engine._checked(drive, tag, what), seed))
            names.append(tag)
        except _PLAY_ERRORS as exc:
            out[i] = exc
        except Exception as exc:  # raised below, in drive order
            out[i] = _Raise(exc)
    if sent:
        # each engine on its own: its processing and scores run in the rig's worker thread
        # right after its run, beside the other runs (shared state: in order, after all)
        alone = _unshared(engines)
        then = (lambda k, raw: _Processed(engines[sent[k][0]], sent[k][1], raw)) if alone else None
        raws = run_batch(engines[0].rig, [d for _, d, _ in sent], seeds=[s for *_, s in sent],
                         threads=threads, return_exceptions=True, then=then)  # fmt: skip
        for (i, drv, _), tag, raw in zip(sent, names, raws, strict=True):
            if isinstance(raw, (RigLimitError, SimulationInstabilityError)):
                engines[i].rejected = (f"TRIPPED{tag}", drv)
                out[i] = raw
            elif isinstance(raw, BaseException):
                out[i] = _Raise(raw)
            else:
                done = raw if alone else _Processed(engines[i], drv, raw)
                out[i] = done.outcome
    first = next((r for r in out if isinstance(r, _Raise)), None)
    if first is not None:
        raise first.error
    return out


def _unshared(engines) -> bool:
    """Whether no two engines share what processing a play changes (the engine, its method,
    its update rule): then each engine's plays can be processed in any thread."""
    held = [id(x) for e in engines for x in (e, e.method, e.updater) if x is not None]
    return len(set(held)) == len(held)


class _Raise:
    """An error of :func:`play_batch` that is raised, not returned in its slot."""

    def __init__(self, error: BaseException):
        self.error = error


class _Processed:
    """:meth:`DriveIteration._processed` of a played drive, its outcome for :func:`play_batch`'s
    slot: the play tuple, the play error (returned in the slot) or any other error (raised,
    in drive order, as :class:`_Raise`). Never raises itself: a run's errors and the
    processing's stay apart."""

    def __init__(self, engine, drv: TimeHistory, raw: TimeHistory):
        try:
            self.outcome = engine._processed(drv, raw)
        except _PLAY_ERRORS as exc:
            self.outcome = exc
        except Exception as exc:
            self.outcome = _Raise(exc)
