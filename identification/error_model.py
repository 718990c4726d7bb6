"""Non-linear error-signal model (Section 5.5.4): linear ARX plus a NARX model of its error."""

from __future__ import annotations

import numpy as np

from ._composite import load_composite, save_composite
from ._validation import (
    as_signal,
    check_initial_outputs,
    check_same_length,
    check_steps_ahead,
)
from .errors import IdentificationError, ModelFileError, SimulationDivergedError
from .models import Arx, Narx

__all__ = ["ErrorSignalModel"]


class ErrorSignalModel:
    """Linear ARX model of the system plus a NARX model of the linear model's free-run error.

    The linear model is identified first; its simulation error ``e = y - y_lin`` is assumed to
    be the non-linear part of the system and is identified from the same input with ``nonlinear``
    (Figure 5.3). The model output is ``y_lin + e_hat``. MIMO and non-square like its parts
    (each output channel's error is modelled from all inputs and all past errors).

    It has the interface :class:`~identification.InverseModel` uses from its model, so
    ``InverseModel(ErrorSignalModel(...))`` is an inverse error-signal model (response in,
    drive out): :meth:`fit` with ``input_names``/``output_names``, :meth:`simulate` with ``y0``
    and ``bound``, ``max_lag_``, ``n_inputs_``/``n_outputs_``, ``max_radius`` (handed to both
    parts: each contracts its own poles when linear in its past outputs), ``contraction_``,
    ``stability_``, ``n_terms_`` and :meth:`describe`.

    Parameters
    ----------
    linear : Arx, default ``Arx(order=3)``
        The (unfitted) linear model of the system.
    nonlinear : Narx, default ``Narx(order=2, degree=2)``
        The (unfitted) model of the linear model's free-run error. Together the text's
        Table 6.5 pair (ARX(3) and a quadratic NARX(2) of the error).
    max_radius : float, optional
        Pole radius limit given to both parts at :meth:`fit` (see :class:`Narx`); None keeps
        the parts' own setting.

    Attributes
    ----------
    max_lag_ : int, the larger of the two parts' largest lags
    n_terms_ : ndarray, terms per output channel (both parts)
    contraction_ : float, the stronger (smaller) of the two parts' pole contractions (1: none)
    stability_ : dict, the two parts' stability contracts: ``"input"``, ``"margin"`` (True when
        both are bounded), ``"remedy"`` (what was done to either, or None), and the parts'
        own dicts under ``"linear"`` and ``"nonlinear"``. The parts run in parallel (the
        error model never sees the linear model's output), so the sum is bounded when both
        are.
    """

    def __init__(
        self, linear: Arx | None = None, nonlinear: Narx | None = None, *, max_radius=None
    ):
        self.linear = Arx(order=3) if linear is None else linear
        self.nonlinear = Narx(order=2, degree=2) if nonlinear is None else nonlinear
        for name, m in (("linear", self.linear), ("nonlinear", self.nonlinear)):
            if not isinstance(m, Narx):
                raise IdentificationError(
                    f"{name} must be an Arx/Narx instance, got {type(m).__name__}"
                )
        if max_radius is not None and not 0 < max_radius <= 1:
            raise IdentificationError(
                f"max_radius must lie in (0, 1] or be None, got {max_radius!r}"
            )
        self.max_radius = max_radius

    def fit(self, u, y, *, input_names=None, output_names=None):
        """Fit the linear model to ``(u, y)``, then the non-linear one to ``(u, y - y_lin)``
        (``y_lin``: the linear model's free run from a zero past); returns self.

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
        if self.max_radius is not None:
            self.linear.max_radius = self.max_radius
            self.nonlinear.max_radius = self.max_radius
        names = {"input_names": input_names, "output_names": output_names}
        self.linear.fit(u, y, **names)
        self.nonlinear.fit(u, y - self.linear.simulate(u), **names)
        self._install()
        return self

    def _install(self) -> None:
        lin, nl = self.linear, self.nonlinear
        self.n_inputs_, self.n_outputs_ = lin.n_inputs_, lin.n_outputs_
        self.input_names_, self.output_names_ = lin.input_names_, lin.output_names_
        self.max_lag_ = max(lin.max_lag_, nl.max_lag_)
        self.n_terms_ = lin.n_terms_ + nl.n_terms_
        self.bound_ = lin.bound_
        self.contraction_ = min(getattr(lin, "contraction_", 1.0), getattr(nl, "contraction_", 1.0))
        s_lin = getattr(lin, "stability_", None) or {}
        s_nl = getattr(nl, "stability_", None) or {}

        def both(key):
            a, b = s_lin.get(key), s_nl.get(key)
            return None if a is None or b is None else bool(a and b)

        remedies = [f"{n}: {s['remedy']}" for n, s in (("linear", s_lin), ("error", s_nl))
                    if s.get("remedy")]
        self.stability_ = {
            "input": both("input"),
            "margin": both("margin"),
            "remedy": "; ".join(remedies) or None,
            "linear": s_lin,
            "nonlinear": s_nl,
        }

    def _check_fitted(self):
        if not hasattr(self, "max_lag_"):
            raise IdentificationError("this ErrorSignalModel is not fitted yet; call fit(u, y)")

    def is_output_affine(self) -> bool:
        """True when both parts are linear in their past outputs."""
        self._check_fitted()
        return self.linear.is_output_affine() and self.nonlinear.is_output_affine()

    def simulate(self, u, y0=None, *, bound=None) -> np.ndarray:
        """Free run (N, ny): linear simulation plus simulated error signal.

        ``y0`` (L, ny), L >= ``max_lag_``, optional: an initialisation window of measured
        outputs, as for :meth:`Narx.simulate <identification.Narx.simulate>` (its last
        ``max_lag_`` samples are the initial state; bit for bit the same as
        ``simulate(u[L - max_lag_:], y0=y0[-max_lag_:])`` after the first ``L - max_lag_``
        samples). The linear part starts from them, the error part from a zero error (the
        linear model taken as exact at the start); the first ``L`` samples of the result are
        ``y0``. Default: zero past.
        ``bound`` (per output channel): limits each part's free run and their sum; default
        each part's own ``bound_``, and the linear part's for the sum.

        Parameters
        ----------
        u : array_like, shape (N, nu) or (N,)
            Input record.
        y0 : array_like, shape (max_lag_, ny), optional
            Measured initial outputs (see above); default a zero past.
        bound : float or array_like of shape (ny,), optional
            Free-run magnitude bound per output channel, in the output's units, handed to both parts
            (default each part's own ``bound_``).

        Raises
        ------
        SimulationDivergedError
            when a part or the sum leaves its bound.
        """
        self._check_fitted()
        u = as_signal(u, "u", n_channels=self.n_inputs_)
        if y0 is None:
            out = self.linear.simulate(u, bound=bound) + self.nonlinear.simulate(u, bound=bound)
        else:
            y0 = check_initial_outputs(y0, u, self.max_lag_, self.n_outputs_)
            shift = y0.shape[0] - self.max_lag_  # samples of y0 before the initial state
            e0 = np.zeros((shift + self.nonlinear.max_lag_, self.n_outputs_))
            out = self.linear.simulate(
                u, y0=y0[: shift + self.linear.max_lag_], bound=bound
            ) + self.nonlinear.simulate(u, y0=e0, bound=bound)
            out[: y0.shape[0]] = y0
        limit = self.bound_ if bound is None else np.broadcast_to(bound, (self.n_outputs_,))
        bad = ~(np.abs(out) <= limit)
        if bad.any():
            t, k = np.argwhere(bad)[0]
            raise SimulationDivergedError(
                k, self.output_names_[k], t, out[t, k], float(limit[k]),
                "free-run simulation (linear + error model)",
            )
        return out

    def predict(self, u, y, *, steps_ahead: int | None = 1, bound=None) -> np.ndarray:
        """Prediction (N, ny) from measured inputs and outputs (SysIdentPy's ``steps_ahead``;
        the default, 1, is not SysIdentPy's: see :meth:`Narx.predict
        <identification.Narx.predict>`).

        ``steps_ahead=1`` (default) or ``k``: the linear part's free run from a zero past
        (the signal the error model was fitted against) plus the error model's one-step or
        k-step prediction (:meth:`Narx.predict <identification.Narx.predict>`) of the measured
        error ``y - y_lin``. ``None``: the free run from the first ``max_lag_`` measured
        outputs, exactly ``simulate(u, y0=y[:max_lag_])``; unlike a single-part model, a very
        large ``k`` is not that free run (its linear part starts from a zero past).
        ``bound``: as for :meth:`simulate` (free runs only).

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
        """
        self._check_fitted()
        steps = check_steps_ahead(steps_ahead)
        if steps is None:
            y = as_signal(y, "y", n_channels=self.n_outputs_)
            u = as_signal(u, "u", n_channels=self.n_inputs_)
            check_same_length(u, y, "u", "y")
            if u.shape[0] <= self.max_lag_:
                raise IdentificationError(
                    f"need more than max_lag_ = {self.max_lag_} samples to predict"
                )
            return self.simulate(u, y0=y[: self.max_lag_], bound=bound)
        y_lin = self.linear.simulate(u)
        if steps == 1:
            return y_lin + self.nonlinear.predict(u, as_signal(y, "y") - y_lin)
        err = as_signal(y, "y") - y_lin
        return y_lin + self.nonlinear.predict(u, err, steps_ahead=steps, bound=bound)

    def describe(self) -> str:
        """Summary of the two fitted parts (their :meth:`Narx.describe` texts in brackets)."""
        self._check_fitted()
        return (
            f"ErrorSignalModel: linear [{self.linear.describe()}]; "
            f"error [{self.nonlinear.describe()}]"
        )

    # ------------------------------------------------------------------ persistence
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
            path,
            "ErrorSignalModel",
            {"max_radius": self.max_radius},
            {"linear": self.linear, "nonlinear": self.nonlinear},
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
        params, parts = load_composite(path, "ErrorSignalModel", ("linear", "nonlinear"))
        lin, nl = parts["linear"], parts["nonlinear"]
        try:
            if (lin.n_inputs_, lin.n_outputs_) != (nl.n_inputs_, nl.n_outputs_):
                raise IdentificationError("the two parts have different channel counts")
            model = cls(lin, nl, max_radius=params.get("max_radius"))
        except (TypeError, IdentificationError) as exc:
            raise ModelFileError(path, f"{type(exc).__name__}: {exc}") from None
        model._install()
        return model

    def __repr__(self) -> str:
        return f"ErrorSignalModel(linear={self.linear!r}, nonlinear={self.nonlinear!r})"
