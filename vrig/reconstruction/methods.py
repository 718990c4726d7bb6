"""Reconstruction methods: how a drive is computed from a (desired) response.

Every method has the same small interface (:class:`vrig.reconstruction.protocol.Method`):

* ``identify(iddrv, idres)`` — fit the inverse of the rig from processed identification records;
* ``drive(response)`` — the drive the inverse model predicts for a response record;
* ``describe()`` — one line saying what was fitted.

Optional capabilities (protocols in :mod:`vrig.reconstruction.protocol`): ``model_size()``
(every method here) and ``fitted_lead()``/``set_lead()`` (the time-domain inverses and split
spectra: :class:`~vrig.reconstruction.protocol.InverseModelMethod`).

The iteration (:func:`vrig.reconstruction.reconstruct`) computes ``IT00DRV = drive(DESRES)`` and
corrects with ``ITn+1DRV = ITnDRV + gain * (drive(DESRES) - drive(ITnRES))``, which for a
linear inverse equals ``gain * drive(DESRES - ITnRES)`` and stays meaningful for a non-linear one.

Methods: :class:`InverseArx` (QanTiM), :class:`InverseNarx`, :class:`InverseErrorSignal` (an
inverse ARX plus a NARX model of its drive error, §5.5.4), :class:`SplitSpectra` (two bands,
each its own inverse model) and :class:`InverseFrf` (H1 estimate, inverse by truncated SVD /
Tikhonov per frequency line: the MTS RPC / Simcenter TWR baseline).
"""

from __future__ import annotations

import inspect
from collections.abc import Mapping

import numpy as np

from identification import Arx, ErrorSignalModel, InverseModel, Narx, NarxSearch

from ..processing import band_split
from ..spectra import frf_filter, frf_h1
from ..timehistory import TimeHistory
from .protocol import InverseModelMethod, SavableMethod, SizedMethod

__all__ = [
    "DELAY_SAMPLES",
    "FRF_MIN_SAMPLES",
    "METHODS",
    "InverseArx",
    "InverseErrorSignal",
    "InverseFrf",
    "InverseNarx",
    "SplitSpectra",
    "make_method",
]


DELAY_SAMPLES = 96
"""Samples (model rate) :func:`identification.estimate_delay` needs beyond ``max_lead``: it fits
ARX(4) models at every candidate delay and needs more than ``max_lead + 4 + 1 + 10 (2 x 4 + 1)``
samples."""

FRF_MIN_SAMPLES = 32
"""Samples (model rate) the H1 estimate of :class:`InverseFrf` needs at least: four Welch
segments of at least 8 samples."""


def _structure_samples(model, n_outputs: int, n_inputs: int, lead: int = 0) -> int:
    """The samples a least-squares fit of ``model`` (an Arx / Narx, or an ErrorSignalModel's
    two parts) needs at ``lead``: one per term of its largest channel after the lead and the
    largest lag (:meth:`identification.Narx.term_count`, before any term selection)."""
    parts = [model.linear, model.nonlinear] if isinstance(model, ErrorSignalModel) else [model]
    if isinstance(model, NarxSearch):
        parts = [model.lead_model()]  # the candidates check their own sizes
    return max(
        lead + p.max_lag(n_outputs, n_inputs) + int(np.max(p.term_count(n_outputs, n_inputs)))
        for p in parts
    )


class _InverseTimeDomain:
    """An inverse ARX/NARX model with a lead for rig delay."""

    name = "time-domain"

    def _model(self):  # pragma: no cover - abstract
        raise NotImplementedError

    def __init__(self, *, lead="auto", max_lead: int = 32, responses=None, max_radius=0.995):
        if lead != "auto" and not _is_count(lead):
            raise ValueError(f"lead must be 'auto' or a number of samples >= 0, got {lead!r}")
        if not _is_count(max_lead):
            raise ValueError(f"max_lead must be a number of samples >= 0, got {max_lead!r}")
        if max_radius is not None and not (
            isinstance(max_radius, (int, float, np.number)) and 0 < max_radius <= 1
        ):
            raise ValueError(f"max_radius must lie in (0, 1] or be None, got {max_radius!r}")
        self.lead = lead
        self.max_lead = max_lead
        self.responses = _names(responses, "responses")
        self.max_radius = max_radius

    def _select(self, th: TimeHistory) -> TimeHistory:
        return th if self.responses is None else th[self.responses]

    def identify(self, iddrv: TimeHistory, idres: TimeHistory) -> None:
        lead = (
            self.lead if self.lead == "auto" or not hasattr(self, "inverse") else self.inverse.lead_
        )
        idres = self._select(idres)
        self.inverse = InverseModel(
            self._model(), lead=lead, max_lead=self.max_lead, max_radius=self.max_radius
        ).fit(iddrv.data, idres.data, drive_names=iddrv.names, response_names=idres.names)

    def drive(self, response: TimeHistory) -> np.ndarray:
        # a desired (or iteration) response is a band-pass filtered cut-out, not a record that
        # starts from rest: the inverse's free run starts from a mirrored, faded-in history
        # (InverseModel.simulate run_in) instead of a zero past, whose step at sample 0 gives a
        # non-linear inverse a start-up transient longer than the drive taper
        # bound: the model's own free-run bound (1000 x the identification drive's peak): an
        # inverse that diverges on the response is reported as such (SimulationDivergedError),
        # not passed on as a huge finite drive for the rig's drive limit to refuse
        return self.inverse.simulate(self._select(response).data, run_in="auto")

    def fitted_lead(self) -> int | None:
        """The lead [samples] the last :meth:`identify` chose; None before one."""
        inverse = getattr(self, "inverse", None)
        return None if inverse is None else int(inverse.lead_)

    def min_samples(self, n_drives: int, n_responses: int) -> int:
        """The shortest identification record [samples at the model rate] this inverse can be
        identified from: with ``lead="auto"`` the delay estimate's ``max_lead +``
        :data:`DELAY_SAMPLES`, and (any lead) one sample per term of the inverse's largest drive
        channel after its largest lag and the lead (for ``"auto"``: lead 0, the shortest tried).

        Parameters
        ----------
        n_drives, n_responses : int
            Numbers of drive and response channels of the rig (the inverse maps responses to
            drives; ``responses`` restricts the latter).
        """
        n_in = n_responses if self.responses is None else len(self.responses)
        if self.lead == "auto":
            need = self.max_lead + DELAY_SAMPLES
            return max(need, _structure_samples(self._model(), n_drives, n_in))
        return max(2 * self.lead + 1, _structure_samples(self._model(), n_drives, n_in, self.lead))

    def set_lead(self, lead) -> None:
        """Fix the lead for the next :meth:`identify`: samples >= 0 (0: a causal model, no lead
        search) or ``"auto"``; None leaves it as it is."""
        if lead is None:
            return
        if lead != "auto" and not _is_count(lead):
            raise ValueError(f"lead must be 'auto' or a number of samples >= 0, got {lead!r}")
        self.lead = lead

    def model_size(self) -> int | None:
        """Number of model terms over all drive channels; None before :meth:`identify`."""
        inverse = getattr(self, "inverse", None)
        return None if inverse is None else int(np.sum(inverse.model.n_terms_))

    _OPTIONS: tuple[str, ...] = ()

    def options(self) -> dict:
        """The method's options (``order``, ``degree``, ...), as given."""
        return {k: getattr(self, k) for k in self._OPTIONS}

    def search_report(self) -> str | None:
        """The structure search's table (:meth:`identification.NarxSearch.report`) when the
        inverse was searched, else None."""
        search = getattr(getattr(self, "inverse", None), "search_", None)
        return None if search is None else search.report()

    def fitted_models(self) -> dict:
        """``{"model": InverseModel}`` after :meth:`identify`, ``{}`` before."""
        inverse = getattr(self, "inverse", None)
        return {} if inverse is None else {"model": inverse}

    def describe(self) -> str:
        m = self.inverse.model
        src = "" if self.responses is None else f" from {self.responses}"
        remedy = getattr(m, "stability_", {}).get("remedy")
        search = getattr(self.inverse, "search_", None)
        found = ""
        if search is not None:
            found = (
                f", searched: {search.best_result_.candidate.label()} of "
                f"{len(search.results_)} candidates in {search.search_time_:.0f} s"
            )
        return (
            f"{self.name}: {type(m).__name__} {m.n_terms_.tolist()} terms, "
            f"lead {self.inverse.lead_}{src}{found}" + (f" ({remedy})" if remedy else "")
        )


class InverseArx(_InverseTimeDomain):
    """Time-domain inverse ARX model (the QanTiM method, full-order structure eq. 4-15).

    Parameters
    ----------
    order : int, optional
        Full-order ARX order of the inverse (output lags 1..order, input lags 0..order).
    **kw
        Options of every time-domain inverse: ``lead`` (``"auto"``, default, or a number of
        samples >= 0), ``max_lead`` (samples, default 32), ``responses`` (the response channel
        names the inverse uses; default all) and ``max_radius`` (pole radius limit, default 0.995;
        None: none); see :class:`identification.InverseModel`.
    """

    name = "arx"
    _OPTIONS = ("order",)

    def __init__(self, order: int = 4, **kw):
        super().__init__(**kw)
        self.order = order
        self._model()  # validate the order now, not at identification

    def _model(self):
        return Arx(order=self.order)


class InverseNarx(_InverseTimeDomain):
    """Time-domain inverse polynomial NARX model (any order/degree).

    ``kind``: ``"input-polynomial"`` (default: every monomial of the *response* regressors, the
    past drives linear), ``"full"`` (the text's condensed NARX, eq. 5-3: products of past drives
    too), ``"pure"`` (purely quadratic, eq. 5-24) or ``"quasi-static"`` (eq. 5-25).

    Why the default departs from the text: an inverse model runs free (its past drives are fed
    back), and products of past drives give it polynomial feedback that escapes to infinity on
    the virtual rigs for every order tried (tables in ``benchmarks/thesis_tables.py``). With the
    past drives linear, the recursion is a linear filter of a polynomial of the responses: its
    poles are known and kept inside the unit circle (``max_radius``), so a bounded response
    always gives a bounded drive.

    ``focus="simulation"`` refines the least-squares inverse on its free-run (output-error)
    error (:class:`identification.Narx`): what makes the text's full condensed NARX inverse
    (``kind="full"``) usable at all, since its least-squares fit diverges in free run.
    ``selection="simulation"`` chooses the terms by free-run error (SEMP; ``n_terms`` caps,
    ``criterion`` sizes), which keeps only the output-feedback terms that simulate well.
    ``functions`` adds non-polynomial terms of the responses (e.g. ``[("saturation", "auto")]``:
    a rig with free play needs a jump in its inverse, which a saturation with a small
    breakpoint approximates; see :class:`identification.Narx`).

    ``stability_margin`` (default 3): the model's stability contract checks its free run at
    this many times the identification response (:class:`identification.Narx`; the simulation
    focus drops non-linear drive feedback that is not bounded there). An inverse runs on the
    *desired* response, which at the default identification level (5 % of full scale) is about
    twice the identification response (the elastomeric damper's pseudo-field: 1.9-2.1x in RMS
    and peak): a model checked only to Narx's default 1.5x can be bounded on its record and
    diverge on the desired response (a bilinear drive x response feedback whose pole moves with
    the response amplitude).

    Parameters
    ----------
    order : int, optional
        Full-order model order of the inverse (samples).
    degree : int, optional
        Polynomial degree (1: linear).
    kind : {"input-polynomial", "full", "pure", "quasi-static"}, optional
        Term set (see above).
    focus : {"prediction", "simulation"}, optional
        Fit the one-step error (least squares) or refine on the free-run error.
    selection : {"frols", "simulation"}, optional
        How terms are chosen when ``n_terms`` or ``criterion`` is given.
    n_terms : int, optional
        Most terms per drive channel.
    criterion : {"aic", "aicc", "bic", "fpe", "press"}, optional
        Term-count criterion along the selection path.
    functions : sequence, optional
        Non-polynomial terms of the responses (see :class:`identification.Narx`).
    function_sources : {"inputs", "outputs", "all"}, optional
        Which regressors get the function terms (the inverse's inputs are the responses).
    stability_margin : float, optional
        Multiple of the identification response the free run is checked at (see above).
    search : bool, optional
        Search the inverse's structure and fitting options by free-run validation
        (:class:`identification.NarxSearch`) instead of fitting the one given: orders
        :data:`SEARCH_ORDERS` up to twice ``order``, degrees 1 .. ``degree``, both term kinds
        above, least squares and simulation focus, all/FROLS/SEMP terms, within ``budget``.
        ``kind``, ``focus``, ``selection``, ``n_terms`` and ``criterion`` are then searched,
        not used. Like the fitted inverse, the searched one has no constant term.
    budget : float, optional
        Seconds the search may take (``search=True``; default 60).
    **kw
        Options of every time-domain inverse: ``lead`` (``"auto"``, default, or a number of
        samples >= 0), ``max_lead`` (samples, default 32), ``responses`` (the response channel
        names the inverse uses; default all) and ``max_radius`` (pole radius limit, default 0.995;
        None: none); see :class:`identification.InverseModel`.
    """

    name = "narx"
    _OPTIONS = ("order", "degree", "kind", "focus", "selection", "n_terms", "search", "budget")
    #: orders the search tries (those up to twice ``order``)
    SEARCH_ORDERS = (1, 2, 3, 4, 6, 8, 12)

    def __init__(
        self,
        order: int = 4,
        degree: int = 2,
        *,
        kind: str = "input-polynomial",
        focus: str = "prediction",
        selection: str = "frols",
        n_terms: int | None = None,
        criterion: str | None = None,
        functions=None,
        function_sources: str = "inputs",
        stability_margin: float = 3.0,
        search: bool = False,
        budget: float = 60.0,
        **kw,
    ):
        super().__init__(**kw)
        if not isinstance(search, bool):
            raise ValueError(f"search must be True or False, got {search!r}")
        self.search, self.budget = search, budget
        self.order, self.degree, self.kind, self.focus = order, degree, kind, focus
        self.stability_margin = stability_margin
        self.selection, self.n_terms, self.criterion = selection, n_terms, criterion
        self.functions, self.function_sources = functions, function_sources
        self._model()  # validate the options now, not at identification

    def _model(self):
        if self.search:
            return NarxSearch(
                self.budget,
                orders=[n for n in self.SEARCH_ORDERS if n <= max(2 * self.order, 1)],
                degrees=range(1, self.degree + 1),
                kinds=("input-polynomial", "full"),
                functions=[None, self.functions] if self.functions else None,
                # the fitted inverse's model class: no constant term (NarxSearch's default has
                # one); the searched and the fitted inverse differ in structure and fit only
                options={"stability_margin": self.stability_margin, "constant": False},
            )
        return Narx(
            order=self.order,
            degree=self.degree,
            kind=self.kind,
            focus=self.focus,
            selection=self.selection,
            n_terms=self.n_terms,
            criterion=self.criterion,
            functions=self.functions,
            function_sources=self.function_sources,
            stability_margin=self.stability_margin,
        )


class InverseErrorSignal(_InverseTimeDomain):
    """Inverse non-linear error-signal model (§5.5.4, Table 6.5): an inverse ARX
    (``linear_order``) plus a NARX (``nonlinear_order``, ``degree``) of the drive error the ARX
    leaves, fitted from the response to it (:class:`identification.ErrorSignalModel` inside
    :class:`identification.InverseModel`: same lead, run-in and pole contraction as the other
    time-domain inverses; ``max_radius`` applies to both parts).

    ``kind`` (default ``"input-polynomial"``) is the error NARX's term set; the default keeps
    the past drive errors linear for the reason :class:`InverseNarx` gives (the inverse runs
    free, and products of past drives make its free run escape); ``"full"`` is the text's
    condensed NARX. ``stability_margin`` (default 3) as for :class:`InverseNarx`.

    Parameters
    ----------
    linear_order : int, optional
        Order of the inverse ARX.
    nonlinear_order : int, optional
        Order of the error NARX.
    degree : int, optional
        Polynomial degree of the error NARX.
    kind : {"input-polynomial", "full", "pure", "quasi-static"}, optional
        Term set of the error NARX (see above).
    focus : {"prediction", "simulation"}, optional
        Fit of the error NARX: one-step error or free-run error.
    stability_margin : float, optional
        Multiple of the identification response the free run is checked at.
    **kw
        Options of every time-domain inverse: ``lead`` (``"auto"``, default, or a number of
        samples >= 0), ``max_lead`` (samples, default 32), ``responses`` (the response channel
        names the inverse uses; default all) and ``max_radius`` (pole radius limit, default 0.995;
        None: none); see :class:`identification.InverseModel`.
    """

    name = "error-signal"
    _OPTIONS = ("linear_order", "nonlinear_order", "degree", "kind", "focus")

    def __init__(
        self,
        linear_order: int = 3,
        nonlinear_order: int = 2,
        degree: int = 2,
        *,
        kind: str = "input-polynomial",
        focus: str = "prediction",
        stability_margin: float = 3.0,
        **kw,
    ):
        super().__init__(**kw)
        self.linear_order, self.nonlinear_order, self.degree = linear_order, nonlinear_order, degree
        self.kind, self.focus, self.stability_margin = kind, focus, stability_margin
        self._model()  # validate the options now, not at identification

    def _model(self):
        return ErrorSignalModel(
            Arx(order=self.linear_order),
            Narx(
                order=self.nonlinear_order,
                degree=self.degree,
                kind=self.kind,
                focus=self.focus,
                stability_margin=self.stability_margin,
            ),
        )


class SplitSpectra:
    """Split-spectra modelling (§3.2, §5.5.3): one inverse model per band, drives superposed.

    ``low`` and ``high`` are methods (e.g. a non-linear low band and a linear high band); the
    identification and response records are split at ``split_hz`` with complementary zero-phase
    filters (:func:`vrig.processing.band_split`, which is the split of the forward
    :class:`identification.SplitSpectraModel`). The forward model object itself is not reused:
    each band here is a reconstruction *method* (an inverse with its own lead, run-in and
    response channel selection, working on TimeHistories), not a forward Narx the model object
    holds, so the two share the splitting function rather than the model. ``low_responses`` / ``high_responses`` (response channel names) let each band's
    inverse use its own transducers: the multiple-transducer split spectra of §3.2.2 (the
    motorcycle's coil-spring strain gauge below the split, its spindle accelerometer above).

    Parameters
    ----------
    split_hz : float
        Split frequency in Hz.
    low, high : method or None, optional
        The band methods (objects with ``identify`` and ``drive``); default
        ``InverseArx(4)`` for each.
    low_responses, high_responses : sequence of str, optional
        Response channel names each band's inverse uses (default all).
    """

    name = "split"

    def __init__(
        self, split_hz: float, low=None, high=None, *, low_responses=None, high_responses=None
    ):
        if not (isinstance(split_hz, (int, float, np.number)) and 0 < split_hz < np.inf):
            raise ValueError(f"split_hz must be a finite frequency > 0 Hz, got {split_hz!r}")
        self.split_hz = split_hz
        self.low = low or InverseArx()
        self.high = high or InverseArx()
        self.low_responses = _names(low_responses, "low_responses")
        self.high_responses = _names(high_responses, "high_responses")

    @staticmethod
    def _select(th: TimeHistory, names):
        return th if names is None else th[names]

    def identify(self, iddrv: TimeHistory, idres: TimeHistory) -> None:
        """Split both records at ``split_hz`` and identify each band's method on its band.

        Parameters
        ----------
        iddrv : TimeHistory
            Identification drive record.
        idres : TimeHistory
            The response measured for it (same length and sample rate).
        """
        d_lo, d_hi = band_split(iddrv, self.split_hz)
        r_lo, r_hi = band_split(idres, self.split_hz)
        self.low.identify(d_lo, self._select(r_lo, self.low_responses))
        self.high.identify(d_hi, self._select(r_hi, self.high_responses))

    def drive(self, response: TimeHistory) -> np.ndarray:
        """The sum of the band methods' drives for the two bands of ``response``.

        Parameters
        ----------
        response : TimeHistory
            The response (desired, or an iteration's correction target) to compute a drive for.
        """
        r_lo, r_hi = band_split(response, self.split_hz)
        return self.low.drive(self._select(r_lo, self.low_responses)) + self.high.drive(
            self._select(r_hi, self.high_responses)
        )

    def fitted_lead(self) -> dict:
        """``{"low": lead, "high": lead}`` of the bands (a band without a lead: None)."""
        return {
            part: band.fitted_lead() if isinstance(band, InverseModelMethod) else None
            for part, band in (("low", self.low), ("high", self.high))
        }

    def set_lead(self, lead) -> None:
        """Fix the bands' leads for the next :meth:`identify`: one value for both bands or
        ``{"low": ..., "high": ...}`` (as :meth:`fitted_lead` returns); a band without a lead
        (e.g. :class:`InverseFrf`) is left alone.

        Parameters
        ----------
        lead : int, str or mapping
            One lead for both bands (samples >= 0 or ``"auto"``) or
            ``{"low": ..., "high": ...}``.
        """
        parts = lead if isinstance(lead, Mapping) else {"low": lead, "high": lead}
        unknown = set(parts) - {"low", "high"}
        if unknown:
            raise ValueError(f"split spectra has bands 'low' and 'high', not {sorted(unknown)}")
        for part, value in parts.items():
            band = getattr(self, part)
            if isinstance(band, InverseModelMethod):
                band.set_lead(value)

    def min_samples(self, n_drives: int, n_responses: int) -> int:
        """The shortest identification record [samples at the model rate]: the larger of the
        two band methods' (a band method without ``min_samples``: 0).

        Parameters
        ----------
        n_drives, n_responses : int
            Numbers of drive and response channels of the rig.
        """
        need = 0
        for band, names in ((self.low, self.low_responses), (self.high, self.high_responses)):
            if hasattr(band, "min_samples"):
                n_resp = n_responses if names is None else len(names)
                need = max(need, band.min_samples(n_drives, n_resp))
        return need

    def model_size(self) -> int | None:
        """Sum of the bands' model sizes; None if either band's is unknown."""
        sizes = [
            b.model_size() if isinstance(b, SizedMethod) else None for b in (self.low, self.high)
        ]
        return None if None in sizes else int(sum(sizes))

    def options(self) -> dict:
        """``split_hz`` and the two band methods (``low``, ``high``)."""
        return {"split_hz": self.split_hz, "low": self.low, "high": self.high}

    def fitted_models(self) -> dict:
        """The bands' fitted models, ``model_low`` / ``model_high`` (``{}`` before
        :meth:`identify`, or for bands whose methods have no model files)."""
        return {
            f"{stem}_{part}": model
            for part, band in (("low", self.low), ("high", self.high))
            if isinstance(band, SavableMethod)
            for stem, model in band.fitted_models().items()
        }

    def describe(self) -> str:
        """One line: the split frequency and each band's method description."""
        lo = "" if self.low_responses is None else f" from {self.low_responses}"
        hi = "" if self.high_responses is None else f" from {self.high_responses}"
        return (
            f"split at {self.split_hz:g} Hz: low [{self.low.describe()}{lo}], "
            f"high [{self.high.describe()}{hi}]"
        )


def _is_count(v) -> bool:
    """A non-negative integer (not a bool)."""
    return isinstance(v, (int, np.integer)) and not isinstance(v, bool) and v >= 0


def _names(names, what):
    if names is None:
        return None
    if isinstance(names, str):
        return [names]
    names = list(names)
    if not names or not all(isinstance(n, str) for n in names):
        raise ValueError(f"{what} must be response channel names, got {names!r}")
    return names


class InverseFrf:
    """Frequency-domain inverse (RPC/TWR baseline): H1 estimate and a regularised inverse.

    ``H(f) = S_yu(f) S_uu(f)^-1`` from Welch cross-spectra of the identification records
    (:func:`vrig.spectra.frf_h1` with ``regularisation="line"``: ``S_uu`` inverted wherever it
    is numerically non-singular, the estimate the method's figures were made with); the
    inverse per frequency line is the truncated-SVD pseudo-inverse (singular values below
    ``rcond`` of the largest dropped) with Tikhonov damping ``tikhonov * s_max``. The drive for a
    response is ``irfft(H^-1(f) R(f))`` on the record's own frequency grid (H^-1 interpolated).

    Parameters
    ----------
    nperseg : int, optional
        Welch segment length in samples (frequency resolution ``fs / nperseg`` Hz).
    rcond : float, optional
        Relative singular value below which a direction of H is dropped.
    tikhonov : float, optional
        Tikhonov damping as a fraction of the largest singular value.
    """

    name = "frf"

    def __init__(self, *, nperseg: int = 512, rcond: float = 1e-3, tikhonov: float = 1e-3):
        if not (_is_count(nperseg) and nperseg >= 8):
            raise ValueError(f"nperseg must be an integer >= 8, got {nperseg!r}")
        if not (isinstance(rcond, (int, float, np.number)) and 0 <= rcond < 1):
            raise ValueError(
                f"rcond must be a relative singular-value threshold in [0, 1), got {rcond!r}"
            )
        if not (isinstance(tikhonov, (int, float, np.number)) and 0 <= tikhonov < np.inf):
            raise ValueError(f"tikhonov must be a finite number >= 0, got {tikhonov!r}")
        self.nperseg, self.rcond, self.tikhonov = nperseg, rcond, tikhonov

    def identify(self, iddrv: TimeHistory, idres: TimeHistory) -> None:
        """Estimate the H1 FRF matrix from the identification records and invert it per line.

        Parameters
        ----------
        iddrv : TimeHistory
            Identification drive record.
        idres : TimeHistory
            The response measured for it (same length and sample rate).
        """
        fs = iddrv.fs
        nperseg = min(self.nperseg, iddrv.n_samples // 4)
        h1 = frf_h1(iddrv.data, idres.data, fs=fs, nperseg=nperseg, regularisation="line")
        self.set_frf(h1.f, h1.frf, fs)
        self.coherence = h1.coherence

    def set_frf(self, f: np.ndarray, H: np.ndarray, fs: float) -> None:
        """Take the FRF matrix ``H`` (drive -> response) and invert it per line, by the
        truncated-SVD / Tikhonov pseudo-inverse of the class docstring (``rcond``,
        ``tikhonov``); :meth:`identify` calls it with its H1 estimate, the ``"frf"`` update
        (:mod:`vrig.reconstruction.updates`) with its iteration-updated one.

        Parameters
        ----------
        f : ndarray (F,)
            Frequency lines [Hz].
        H : ndarray (F, n_responses, n_drives), complex
            The FRF per line (response unit per drive unit).
        fs : float
            Sample rate [Hz] of the records the drive is computed for.
        """
        U, s, Vh = np.linalg.svd(H, full_matrices=False)
        keep = s >= self.rcond * s[:, :1]
        lam = self.tikhonov * s[:, :1]
        sinv = np.where(keep, s / (s**2 + lam**2), 0.0)
        self.Hinv = np.einsum("fji,fj,fkj->fik", Vh.conj(), sinv, U.conj())  # (F, nu, ny)
        self.f, self.H, self.fs = f, H, fs

    def min_samples(self, n_drives: int, n_responses: int) -> int:
        """The shortest identification record [samples at the model rate]:
        :data:`FRF_MIN_SAMPLES` (four Welch segments of 8 samples).

        Parameters
        ----------
        n_drives, n_responses : int
            Numbers of drive and response channels of the rig (not used).
        """
        return FRF_MIN_SAMPLES

    def drive(self, response: TimeHistory) -> np.ndarray:
        """Drive for a response: the record is zero-padded to twice its length (no circular
        wrap-around of the inverse's impulse response) and the DC line is left out.

        Parameters
        ----------
        response : TimeHistory
            The response (desired, or an iteration's correction target) to compute a drive for.
        """
        return frf_filter(self.Hinv, self.f, self.fs, response.data, dc=False)

    def describe(self) -> str:
        """One line: the number of frequency lines and the inverse used."""
        return f"frf: H1 with {self.f.size} lines, truncated-SVD/Tikhonov inverse"

    def options(self) -> dict:
        """``nperseg``, ``rcond``, ``tikhonov``."""
        return {"nperseg": self.nperseg, "rcond": self.rcond, "tikhonov": self.tikhonov}

    def fitted_models(self) -> dict:
        """``{}``: the inverse FRF has no model file (its size is in :meth:`model_size`)."""
        return {}

    def model_size(self) -> int | None:
        """Real numbers in the inverse FRF matrices (2 per complex entry); None before
        :meth:`identify`."""
        hinv = getattr(self, "Hinv", None)
        return None if hinv is None else int(2 * np.asarray(hinv).size)


METHODS = {
    "arx": InverseArx,
    "narx": InverseNarx,
    "error-signal": InverseErrorSignal,
    "split": SplitSpectra,
    "frf": InverseFrf,
}


def make_method(method, **options):
    """A method object from a name (``"arx"``, ``"narx"``, ``"error-signal"``, ``"split"``,
    ``"frf"``) and options,
    or the given object if it already has ``identify`` and ``drive``.

    Parameters
    ----------
    method : str or method object
        A name of :data:`METHODS` or an object with ``identify`` and ``drive``.
    **options
        Keyword arguments of the named method's class (none for an object).
    """
    if hasattr(method, "identify") and hasattr(method, "drive"):
        if options:
            raise ValueError("options are only for methods given by name")
        return method
    try:
        cls = METHODS[method]
    except (KeyError, TypeError):
        raise ValueError(f"unknown method {method!r}; choose one of {sorted(METHODS)}") from None
    params = inspect.signature(cls).parameters
    if not any(p.kind is p.VAR_KEYWORD for p in params.values()):
        unknown = sorted(set(options) - set(params))
        if unknown:
            takes = [n for n, p in params.items() if p.kind not in (p.VAR_POSITIONAL,)]
            raise ValueError(
                f"method {method!r} takes no option {', '.join(map(repr, unknown))}; its options: "
                f"{', '.join(takes) or 'none'}"
            )
    missing = [
        n for n, p in params.items()
        if p.default is p.empty and p.kind in (p.POSITIONAL_OR_KEYWORD, p.KEYWORD_ONLY)
        and n not in options
    ]  # fmt: skip
    if missing:  # e.g. split without split_hz (vrig.reconstruct fills it from the rig's band)
        raise ValueError(f"method {method!r} needs the option(s) {', '.join(missing)}")
    try:
        return cls(**options)
    except TypeError as exc:  # an option the class's base does not take either
        if "keyword argument" not in str(exc):
            raise
        raise ValueError(f"method {method!r}: {exc}") from None
