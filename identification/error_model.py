"""Non-linear error-signal model (Section 5.5.4): linear ARX plus a NARX model of its error."""

from __future__ import annotations

import numpy as np

from ._validation import as_signal, check_same_length
from .errors import IdentificationError
from .models import Arx, Narx

__all__ = ["ErrorSignalModel"]


class ErrorSignalModel:
    """Linear ARX model of the system plus a NARX model of the linear model's free-run error.

    The linear model is identified first; its simulation error ``e = y - y_lin`` is assumed to
    be the non-linear part of the system and is identified from the same input with ``nonlinear``
    (Figure 5.3). The model output is ``y_lin + e_hat``.

    Parameters
    ----------
    linear : Arx, default ``Arx(order=3)``
    nonlinear : Narx, default ``Narx(order=2, degree=2)``
    """

    def __init__(self, linear: Arx | None = None, nonlinear: Narx | None = None):
        self.linear = Arx(order=3) if linear is None else linear
        self.nonlinear = Narx(order=2, degree=2) if nonlinear is None else nonlinear
        for name, m in (("linear", self.linear), ("nonlinear", self.nonlinear)):
            if not isinstance(m, Narx):
                raise IdentificationError(
                    f"{name} must be an Arx/Narx instance, got {type(m).__name__}"
                )

    def fit(self, u, y):
        u = as_signal(u, "u")
        y = as_signal(y, "y")
        check_same_length(u, y, "u", "y")
        self.linear.fit(u, y)
        self.nonlinear.fit(u, y - self.linear.simulate(u))
        self.n_inputs_, self.n_outputs_ = u.shape[1], y.shape[1]
        return self

    def simulate(self, u) -> np.ndarray:
        """Free run: linear simulation plus simulated error signal."""
        return self.linear.simulate(u) + self.nonlinear.simulate(u)

    def predict(self, u, y) -> np.ndarray:
        """Linear free run plus one-step-ahead prediction of its error from the measured error."""
        y_lin = self.linear.simulate(u)
        return y_lin + self.nonlinear.predict(u, as_signal(y, "y") - y_lin)
