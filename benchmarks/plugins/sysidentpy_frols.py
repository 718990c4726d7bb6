"""Example plugin: an inverse polynomial NARX model selected by SysIdentPy's FROLS.

Registered as ``frols`` only when ``sysidentpy`` imports (``pip install -e .[bench]``); not part
of ``--quick`` (SysIdentPy's fit and free run are pure Python, so it is the slowest method).
One MISO model per drive channel (responses in, that drive out, both scaled to unit standard
deviation): ``ylag`` drive lags (default 1), ``xlag`` response lags (6), quadratic polynomial
basis, ``n_terms`` (12) terms chosen by FROLS (ERR), least squares; the responses are advanced
by the rig's delay (lead, as :class:`identification.InverseModel` does). Free run from zero
initial drives. (With 4 drive lags FROLS picks a nearly marginal autoregression whose free run
diverges on the damper rigs.)
"""

from __future__ import annotations

import numpy as np

from benchmarks.runner import register_method

try:
    from sysidentpy.basis_function import Polynomial
    from sysidentpy.model_structure_selection import FROLS
    from sysidentpy.parameter_estimation import LeastSquares
except ImportError:  # optional dependency: the method is simply not registered
    FROLS = None


class InverseFrols:
    """Inverse NARX by SysIdentPy FROLS (see the module docstring)."""

    def __init__(self, *, ylag: int = 1, xlag: int = 6, degree: int = 2, n_terms: int = 12):
        self.ylag, self.xlag, self.degree, self.n_terms = ylag, xlag, degree, n_terms

    def _shift(self, r):
        return np.concatenate([r[self.lead :], np.repeat(r[-1:], self.lead, axis=0)])

    def identify(self, iddrv, idres):
        from identification import estimate_delay

        d, r = iddrv.data, idres.data
        self.lead = estimate_delay(d, r, max_lag=16)
        # unit scaling: loads in N and strokes in m differ by 1e6, which ruins the ERR ranking
        self.x_scale = r.std(axis=0) + 1e-300
        self.y_scale = d.std(axis=0) + 1e-300
        x = self._shift(r) / self.x_scale
        d = d / self.y_scale
        n_in = r.shape[1]
        xlag = list(range(1, self.xlag + 1))
        self.models = []
        for j in range(d.shape[1]):
            m = FROLS(
                order_selection=False,
                n_terms=self.n_terms,
                ylag=self.ylag,
                xlag=xlag if n_in == 1 else [xlag] * n_in,
                basis_function=Polynomial(degree=self.degree),
                estimator=LeastSquares(),
            )
            m.fit(X=x, y=d[:, j : j + 1])
            self.models.append(m)

    def drive(self, response):
        x = self._shift(response.data) / self.x_scale
        y0 = np.zeros((x.shape[0], 1))
        cols = [m.predict(X=x, y=y0, steps_ahead=None)[: x.shape[0], 0] for m in self.models]
        out = np.column_stack(cols) * self.y_scale
        if not np.all(np.isfinite(out)):
            raise FloatingPointError("the FROLS model's free run diverged (inf/NaN)")
        return out

    def describe(self):
        return (
            f"SysIdentPy FROLS inverse NARX: {len(self.models)} MISO model(s), {self.n_terms} "
            f"terms each of ylag {self.ylag}, xlag {self.xlag}, degree {self.degree}; "
            f"lead {self.lead}"
        )

    def model_size(self):
        return int(sum(np.size(m.theta) for m in self.models))


if FROLS is not None:
    register_method(
        "frols",
        lambda rig, band: InverseFrols(),
        description="SysIdentPy FROLS inverse NARX (example plugin, needs sysidentpy)",
        quick=False,
        linear=False,
    )
