"""Forward split-spectra model (§5.5.3, §6.3): one model per frequency band, outputs summed.

Inputs and outputs are split at ``split_hz`` into a low and a high band by a complementary
zero-phase filter (:func:`band_split`); one model is fitted per band (the text's linear-non-linear
split: a static quadratic NARX below, an ARX above) and the simulation is the sum of the two band
simulations. The low band can run at its own, lower sample rate (§3.5, the "localised sampling
rate": a constant ratio between sampling rate and signal frequency).
"""

from __future__ import annotations

import copy
import math

import numpy as np
from scipy import signal

from ._composite import load_composite, save_composite
from ._validation import as_signal, check_same_length, check_steps_ahead
from .errors import IdentificationError, InsufficientDataError, SimulationDivergedError
from .models import Arx, Narx

__all__ = ["SplitSpectraModel", "band_split", "split_filter"]

LOW_RATE_RATIO = 10.0
"""``decimate_low=True``: the low band's sample rate is at least this many times ``split_hz``."""

UPSAMPLE_WINDOW = ("kaiser", 14.0)
"""Window of the polyphase FIR that brings the low band back to ``fs``. Scipy's default
(``("kaiser", 5.0)``) has a passband ripple of about 1e-3; with beta 14 a sinusoid at up to a
tenth of the low rate is interpolated within 5e-7 of its amplitude (measured for factors 2, 5
and 10 at 0.01, 0.05 and 0.1 of the low rate)."""


def _check_split(split_hz, fs) -> tuple[float, float]:
    if not (isinstance(fs, (int, float, np.number)) and 0 < fs < np.inf):
        raise IdentificationError(f"fs must be a finite sample rate > 0 Hz, got {fs!r}")
    if not (isinstance(split_hz, (int, float, np.number)) and 0 < split_hz < fs / 2):
        raise IdentificationError(
            f"split_hz must lie in (0, fs/2 = {fs / 2:g}) Hz, got {split_hz!r}"
        )
    return float(split_hz), float(fs)


def split_filter(split_hz: float, fs: float, order: int = 4) -> np.ndarray:
    """Second-order sections of the split's Butterworth low-pass (``order`` poles, -3 dB at
    ``split_hz`` for one pass; applied forward and backward, -6 dB and ``2 * order`` poles).

    Parameters
    ----------
    split_hz : float
        Split (-3 dB per pass) frequency in Hz, in (0, fs/2).
    fs : float
        Sample rate in Hz.
    order : int, optional
        Poles of the low-pass (per pass).
    """
    split_hz, fs = _check_split(split_hz, fs)
    if not isinstance(order, (int, np.integer)) or isinstance(order, bool) or order < 1:
        raise IdentificationError(f"filter order must be a positive integer, got {order!r}")
    return signal.butter(int(order), split_hz, btype="lowpass", fs=fs, output="sos")


def _padlen(sos: np.ndarray) -> int:
    """``scipy.signal.sosfiltfilt``'s default edge padding, in samples."""
    zeros = min(int((sos[:, 2] == 0).sum()), int((sos[:, 5] == 0).sum()))
    return 3 * (2 * sos.shape[0] + 1 - zeros)


def band_split(x, split_hz: float, fs: float, *, order: int = 4) -> tuple[np.ndarray, np.ndarray]:
    """Split records ``x`` (N, channels) or (N,) at ``split_hz`` into complementary bands.

    ``low`` is ``x`` through a Butterworth low-pass of ``order`` poles applied forward and
    backward (:func:`scipy.signal.sosfiltfilt`, odd extension at the ends): zero phase, so the
    bands stay aligned in time with each other and with the record. ``high = x - low``.

    Why complementary: ``low + high == x`` exactly (to round-off), so nothing of the record is
    lost or counted twice where the bands overlap around ``split_hz``: a model per band summed
    reproduces the whole record when each band model is exact, and a linear system split this
    way is the sum of its band responses. Two separately designed filters (a low-pass and a
    high-pass) would leave a notch or a bump at the crossover.

    Parameters
    ----------
    x : array_like, shape (N, channels) or (N,)
        Records sampled at ``fs``.
    split_hz : float
        Split frequency in Hz, in (0, fs/2).
    fs : float
        Sample rate in Hz.
    order : int, optional
        Poles of the Butterworth low-pass (per pass).

    Raises
    ------
    IdentificationError
        ``split_hz`` outside (0, fs/2), a bad filter order, NaN/inf in ``x``.
    InsufficientDataError
        A record no longer than the filter's edge padding (``3 * (2 * n_sections + 1)``
        samples: 15 for order 4).
    """
    sos = split_filter(split_hz, fs, order)
    x = np.asarray(x, dtype=np.float64)
    if x.ndim not in (1, 2):
        raise IdentificationError(f"x must have shape (N,) or (N, channels), got {x.shape}")
    if not np.all(np.isfinite(x)):
        raise IdentificationError("x contains NaN or inf")
    pad = _padlen(sos)
    if x.shape[0] <= pad:
        raise InsufficientDataError(
            f"a record of {x.shape[0]} samples is too short for the order-{order} split filter "
            f"(its zero-phase edge padding needs more than {pad} samples)"
        )
    low = signal.sosfiltfilt(sos, x, axis=0)
    return low, x - low


def _factor(decimate_low, fs: float, split_hz: float) -> int:
    if decimate_low is True:
        return max(1, math.floor(fs / (LOW_RATE_RATIO * split_hz)))
    if decimate_low is False or decimate_low is None:
        return 1
    if isinstance(decimate_low, (int, np.integer)) and decimate_low >= 1:
        q = int(decimate_low)
        if fs / q <= 2 * split_hz:
            raise IdentificationError(
                f"decimate_low={q}: the low band's rate {fs / q:g} Hz must exceed twice the split "
                f"frequency ({2 * split_hz:g} Hz), else the low band aliases; at most "
                f"{math.ceil(fs / (2 * split_hz)) - 1}"
            )
        return q
    raise IdentificationError(
        f"decimate_low must be True, False or a decimation factor >= 1, got {decimate_low!r}"
    )


class SplitSpectraModel:
    """Forward split-spectra (linear-non-linear) model, MIMO and non-square (§5.5.3, §6.3).

    Inputs and outputs are split at ``split_hz`` by :func:`band_split` (complementary zero-phase
    Butterworth split, ``filter_order`` poles: the text's 4th-order digital filter of §6.3.1);
    ``low`` is fitted to the low bands, ``high`` to the high bands, and :meth:`simulate` sums
    the two band simulations.

    Parameters
    ----------
    split_hz : float
        Split frequency in Hz, in (0, fs/2).
    fs : float
        Sample rate of the records in Hz.
    low, high : Narx or Arx (unfitted)
        The band models; default the text's Table 6.9 pair: ``Narx(order=0, degree=2)`` (static
        quadratic) below and ``Arx(order=2)`` above. They are copied into the fitted model
        (``low_``, ``high_``), the given objects are left untouched.
    filter_order : int
        Poles of the split's Butterworth low-pass (per pass).
    decimate_low : bool or int
        The low band's own sample rate (§3.5): ``False`` (default, the text's practice in
        §6.3) fits it at ``fs``; an integer ``q`` fits it at ``fs / q``; ``True`` picks the
        largest ``q`` with ``fs / q >= 10 * split_hz`` (``LOW_RATE_RATIO``). The low band is
        decimated by taking every q-th sample of the split's low band, which the split filter
        has already band-limited: content that folds back below ``split_hz`` lies above
        ``fs / q - split_hz`` (at least 9 x ``split_hz`` with ``True``), where the zero-phase
        Butterworth passes at most ``1 / (1 + 9 ** (2 * filter_order))`` (2.3e-8 for order 4).
        The low model's lags count low-rate samples. On simulation its output is brought back
        to ``fs`` by polyphase FIR interpolation (:func:`scipy.signal.resample_poly`, Kaiser
        window beta 14 (``UPSAMPLE_WINDOW``), zero phase, ends extended by a fitted line):
        within 5e-7 of the amplitude for content up to a tenth of the low rate.

    Attributes
    ----------
    low_, high_ : the fitted band models
    factor_ : int, the low band's decimation factor (1: none)
    n_inputs_, n_outputs_, input_names_, output_names_, max_lag_ (samples at ``fs``)
    """

    def __init__(
        self,
        split_hz: float,
        fs: float,
        low: Narx | None = None,
        high: Narx | None = None,
        *,
        filter_order: int = 4,
        decimate_low: bool | int = False,
    ):
        self.split_hz, self.fs = _check_split(split_hz, fs)
        split_filter(self.split_hz, self.fs, filter_order)  # validates the order
        self.filter_order = int(filter_order)
        self.low = Narx(order=0, degree=2) if low is None else low
        self.high = Arx(order=2) if high is None else high
        for name, m in (("low", self.low), ("high", self.high)):
            if not isinstance(m, Narx):
                raise IdentificationError(
                    f"{name} must be an Arx/Narx instance, got {type(m).__name__}"
                )
        self.factor = _factor(decimate_low, self.fs, self.split_hz)
        self.decimate_low = decimate_low

    # ------------------------------------------------------------------ bands
    def split(self, x) -> tuple[np.ndarray, np.ndarray]:
        """The low and high bands of records ``x`` (N, channels) at this model's split.

        Parameters
        ----------
        x : array_like, shape (N, channels) or (N,)
            Records sampled at ``fs``.
        """
        return band_split(x, self.split_hz, self.fs, order=self.filter_order)

    def _down(self, x: np.ndarray) -> np.ndarray:
        return x[:: self.factor] if self.factor > 1 else x

    def _up(self, x: np.ndarray, n: int) -> np.ndarray:
        if self.factor == 1:
            return x
        up = signal.resample_poly(
            x, self.factor, 1, axis=0, window=UPSAMPLE_WINDOW, padtype="line"
        )
        return up[:n]

    # ------------------------------------------------------------------ fit / use
    def fit(self, u, y, *, input_names=None, output_names=None):
        """Split ``u`` (N, nu) and ``y`` (N, ny) at ``split_hz`` and fit one model per band.

        Parameters
        ----------
        u : array_like, shape (N, nu) or (N,)
            Identification input record, in its physical units (time on axis 0).
        y : array_like, shape (N, ny) or (N,)
            Identification output record, same N, in its physical units.
        input_names, output_names : sequence of str, optional
            Channel names (default ``u1, u2, ...``, ``y1, y2, ...``), kept in the model.
        """
        u = as_signal(u, "u")
        y = as_signal(y, "y")
        check_same_length(u, y, "u", "y")
        u_lo, u_hi = self.split(u)
        y_lo, y_hi = self.split(y)
        n_low = math.ceil(u.shape[0] / self.factor)
        if n_low < 2:
            raise InsufficientDataError(
                f"the low band decimated by {self.factor} keeps {n_low} samples; record too short"
            )
        names = {"input_names": input_names, "output_names": output_names}
        low, high = copy.deepcopy(self.low), copy.deepcopy(self.high)
        low.fit(self._down(u_lo), self._down(y_lo), **names)
        high.fit(u_hi, y_hi, **names)
        self._install(low, high)
        return self

    def _install(self, low: Narx, high: Narx) -> None:
        self.low_, self.high_ = low, high
        self.factor_ = self.factor
        self.n_inputs_, self.n_outputs_ = high.n_inputs_, high.n_outputs_
        self.input_names_, self.output_names_ = high.input_names_, high.output_names_
        self.max_lag_ = max(low.max_lag_ * self.factor, high.max_lag_)
        self.n_terms_ = low.n_terms_ + high.n_terms_

    def _check_fitted(self):
        if not hasattr(self, "low_"):
            raise IdentificationError("this SplitSpectraModel is not fitted yet; call fit(u, y)")

    def _input(self, u) -> tuple[np.ndarray, np.ndarray, int]:
        self._check_fitted()
        u = as_signal(u, "u")
        if u.shape[1] != self.n_inputs_:
            raise IdentificationError(
                f"u has {u.shape[1]} channels, but the model was fitted with {self.n_inputs_} "
                f"inputs {self.input_names_}"
            )
        u_lo, u_hi = self.split(u)
        return u_lo, u_hi, u.shape[0]

    def simulate(self, u, *, bound=None) -> np.ndarray:
        """Free run (N, ny): the low model's simulation of the low band of ``u`` (at its own
        rate, brought back to ``fs``) plus the high model's of the high band, each from a zero
        past. ``bound`` (per output channel, default each band model's own ``bound_``) limits
        each band's free run.

        Parameters
        ----------
        u : array_like, shape (N, nu) or (N,)
            Input record at ``fs``.
        bound : float or array_like of shape (ny,), optional
            Free-run magnitude bound per output channel, in the output's units, for each band.

        Raises
        ------
        SimulationDivergedError
            when a band's free run leaves its bound (names the channel, sample and band).
        """
        u_lo, u_hi, n = self._input(u)
        kw = {"bound": bound}
        y_lo = self._band("low", self.low_.simulate, (self._down(u_lo),), kw, self.factor_)
        y_hi = self._band("high", self.high_.simulate, (u_hi,), kw, 1)
        return self._up(y_lo, n) + y_hi

    @staticmethod
    def _band(band: str, run, args: tuple, kwargs: dict, factor: int) -> np.ndarray:
        """``run(*args, **kwargs)`` (a band model's simulate or predict), a divergence
        re-raised with its sample counted at ``fs`` and the band named."""
        try:
            return run(*args, **kwargs)
        except SimulationDivergedError as exc:  # the sample counted at fs
            what = "free run" if exc.kind == "free-run simulation" else exc.kind
            raise SimulationDivergedError(
                exc.channel,
                exc.channel_name,
                exc.sample * factor,
                exc.value,
                exc.bound,
                f"{band}-band {what}",
            ) from None

    def predict(self, u, y, *, steps_ahead: int | None = 1, bound=None) -> np.ndarray:
        """Prediction (N, ny): each band model's prediction from the measured band of ``u``
        and ``y`` (the low band at its own rate, interpolated back to ``fs``), summed.

        ``steps_ahead`` (SysIdentPy's meaning, see :meth:`Narx.predict
        <identification.Narx.predict>`; the default, 1, is not SysIdentPy's): ``1`` one step
        ahead (the low band one low-rate step); ``k`` k steps ahead (the low band
        ``ceil(k / factor_)`` low-rate steps, i.e. at least k samples at ``fs``); ``None`` each
        band's free run from the first ``max_lag_`` samples of its measured band. The bands of
        ``y`` need the whole record, so that free run has no :meth:`simulate` counterpart
        (``simulate`` starts both bands from a zero past). ``bound``: for the free runs, as
        for :meth:`simulate`.

        Parameters
        ----------
        u : array_like, shape (N, nu) or (N,)
            Measured input record.
        y : array_like, shape (N, ny) or (N,)
            Measured output record, same N (its past values are the regressors).
        steps_ahead : int or None
            ``1`` (default) one step ahead, ``k`` k steps ahead, ``None`` a free run.
        bound : float, optional
            Free-run bound, as for :meth:`simulate`.

        Raises
        ------
        SimulationDivergedError
            when a band's prediction is not finite or its free run leaves ``bound`` (the sample
            counted at ``fs``).
        """
        steps = check_steps_ahead(steps_ahead)
        u_lo, u_hi, n = self._input(u)
        y = as_signal(y, "y", n_channels=self.n_outputs_)
        check_same_length(u_lo, y, "u", "y")
        y_lo, y_hi = self.split(y)
        if steps == 1:
            p_lo = self.low_.predict(self._down(u_lo), self._down(y_lo))
            return self._up(p_lo, n) + self.high_.predict(u_hi, y_hi)
        low_steps = None if steps is None else -(-steps // self.factor_)
        kw = {"bound": bound}
        p_lo = self._band(
            "low", self.low_.predict, (self._down(u_lo), self._down(y_lo)),
            {"steps_ahead": low_steps, **kw}, self.factor_,
        )
        p_hi = self._band("high", self.high_.predict, (u_hi, y_hi), {"steps_ahead": steps, **kw}, 1)
        return self._up(p_lo, n) + p_hi

    def describe(self) -> str:
        """One-line summary: split frequency (Hz), filter order, each band model's rate and
        summary."""
        self._check_fitted()
        rate = self.fs / self.factor_
        return (
            f"SplitSpectraModel at {self.split_hz:g} Hz (order-{self.filter_order} zero-phase "
            f"Butterworth split): low band at {rate:g} Hz [{self.low_.describe()}]; "
            f"high band at {self.fs:g} Hz [{self.high_.describe()}]"
        )

    # ------------------------------------------------------------------ persistence
    def _params(self) -> dict:
        return {
            "split_hz": self.split_hz,
            "fs": self.fs,
            "filter_order": self.filter_order,
            "decimate_low": self.factor,
        }

    def save(self, path):
        """Save the fitted model to one ``.npz`` model file (atomic; exact round trip: the
        loaded model simulates bit for bit the same); returns the path.

        Parameters
        ----------
        path : str or os.PathLike
            Target file; ``.npz`` is appended when the name has another suffix or none.
        """
        self._check_fitted()
        return save_composite(
            path, "SplitSpectraModel", self._params(), {"low": self.low_, "high": self.high_}
        )

    @classmethod
    def load(cls, path):
        """Load a model written by :meth:`save` (checked like :meth:`Narx.load
        <identification.Narx.load>`; raises :class:`~identification.ModelFileError`).

        Parameters
        ----------
        path : str or os.PathLike
            A file written by :meth:`save` (``.npz`` appended when missing).
        """
        from .errors import ModelFileError

        params, parts = load_composite(path, "SplitSpectraModel", ("low", "high"))
        try:
            model = cls(
                params["split_hz"],
                params["fs"],
                parts["low"],
                parts["high"],
                filter_order=params["filter_order"],
                decimate_low=params["decimate_low"],
            )
            low, high = parts["low"], parts["high"]
            if (low.n_inputs_, low.n_outputs_) != (high.n_inputs_, high.n_outputs_):
                raise IdentificationError("the band models have different channel counts")
        except (KeyError, TypeError, IdentificationError) as exc:
            raise ModelFileError(path, f"{type(exc).__name__}: {exc}") from None
        model._install(low, high)
        return model

    def __repr__(self) -> str:
        return (
            f"SplitSpectraModel(split_hz={self.split_hz!r}, fs={self.fs!r}, low={self.low!r}, "
            f"high={self.high!r}, filter_order={self.filter_order}, "
            f"decimate_low={self.decimate_low!r})"
        )
