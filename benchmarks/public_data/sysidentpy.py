"""SysIdentPy 0.9.0 run in the same process (optional: only when it is importable)."""

from __future__ import annotations

import time
import warnings

import numpy as np

from .search import Candidate

SKIP_SYSIDENTPY = "skipped: sysidentpy not installed (pip install -e .[bench])"


class SysIdentPy:
    """SysIdentPy 0.9.0 FROLS + LeastSquares, polynomial basis (only when importable)."""

    def __init__(self) -> None:
        import sysidentpy
        from sysidentpy.basis_function import Polynomial
        from sysidentpy.model_structure_selection import FROLS
        from sysidentpy.parameter_estimation import LeastSquares

        self.version: str = getattr(sysidentpy, "__version__", "unknown")
        self._frols, self._poly, self._ls = FROLS, Polynomial, LeastSquares

    def fit(self, u, y, *, degree, ylag, xlag, **kw):
        u = np.asarray(u, dtype=float).reshape(len(y), -1)
        model = self._frols(
            ylag=ylag,
            xlag=xlag,
            basis_function=self._poly(degree=degree),
            estimator=self._ls(),
            **kw,
        )
        t0 = time.perf_counter()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            model.fit(X=u, y=np.asarray(y, dtype=float).reshape(-1, 1))
        return model, time.perf_counter() - t0

    @staticmethod
    def free_run(model, u, y, nk: int = 1) -> np.ndarray:
        """SysIdentPy free run (``steps_ahead=None``) from the first ``max_lag`` outputs.

        ``nk = 0``: a model fitted by :meth:`mirror` on inputs advanced by one sample.
        """
        u = advance(np.asarray(u, dtype=float).reshape(len(y), -1), 1 - nk)
        y = np.asarray(y, dtype=float).reshape(-1, 1)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            return np.asarray(model.predict(X=u, y=y[: model.max_lag])).ravel()

    @staticmethod
    def n_terms(model) -> int:
        return int(model.final_model.shape[0])

    def mirror(self, cand: Candidate, n_inputs: int, u, y):
        """FROLS with the same candidate set and number of terms as a vrig :class:`Candidate`.

        SysIdentPy's input lags start at 1; a candidate with ``nk = 0`` (current input) is
        mirrored by feeding it the inputs advanced by one sample (see :func:`advance`).
        """
        lags = list(range(1, cand.nb + 1))
        xlag = cand.nb if n_inputs == 1 else [lags] * n_inputs
        return self.fit(
            advance(u, 1 - cand.nk),
            y,
            degree=cand.degree,
            ylag=cand.na,
            xlag=xlag,
            n_terms=cand.n_terms,
            order_selection=False,
        )


def advance(u, k: int) -> np.ndarray:
    """Inputs advanced by ``k`` samples (``v[t] = u[t + k]``, the last value repeated at the end):
    lag j of ``v`` is lag ``j - k`` of ``u``. The padded samples only feed outputs past the end.
    """
    u = np.asarray(u, dtype=float)
    if k == 0:
        return u
    return np.concatenate([u[k:], np.repeat(u[-1:], k, axis=0)])


def get_sysidentpy() -> SysIdentPy | None:
    try:
        return SysIdentPy()
    except ImportError:
        return None
