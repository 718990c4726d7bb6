"""Model-validation tools for (polynomial N)ARX identification (pure NumPy/SciPy).

* :func:`information_criteria` / :func:`criterion_value` — AIC, AICc, BIC and FPE of a fit from
  its residuals and its number of estimated parameters (model-size selection)
* :func:`press` — predicted residual sum of squares (leave-one-out residuals) of a
  linear-in-the-parameters least-squares fit, from one pivoted QR factorisation
* :func:`correlation_tests` — Billings & Voon's higher-order correlation tests of the residuals
  against the input, with the confidence band and a pass/fail verdict per test

References
----------
.. [Akaike69] H. Akaike, "Fitting autoregressive models for prediction", Ann. Inst. Statist.
   Math. 21 (1969) 243-247 (FPE).
.. [Akaike74] H. Akaike, "A new look at the statistical model identification", IEEE Trans.
   Automat. Control 19(6) (1974) 716-723 (AIC).
.. [Schwarz78] G. Schwarz, "Estimating the dimension of a model", Ann. Statist. 6(2) (1978)
   461-464 (BIC).
.. [HurvichTsai89] C. M. Hurvich, C.-L. Tsai, "Regression and time series model selection in
   small samples", Biometrika 76(2) (1989) 297-307 (AICc).
.. [Ljung99] L. Ljung, "System Identification: Theory for the User", 2nd ed., Prentice Hall
   1999, §16.4 (comparing model structures: AIC, FPE, BIC/MDL with V = det of the residual
   covariance for multi-output models).
.. [Allen74] D. M. Allen, "The relationship between variable selection and data augmentation
   and a method for prediction", Technometrics 16(1) (1974) 125-127 (PRESS).
.. [WeiBillings08] H.-L. Wei, S. A. Billings, "Model structure selection using an integrated
   forward orthogonal search algorithm assisted by squared correlation and mutual
   information", Int. J. Modelling, Identification and Control 3(4) (2008) 341-356 (PRESS /
   leave-one-out errors for NARX term selection; also used by the NonSysId package).
.. [BillingsVoon86] S. A. Billings, W. S. F. Voon, "Correlation based model validity tests
   for non-linear models", Int. J. Control 44(1) (1986) 235-244.
.. [BoxJenkins] G. E. P. Box, G. M. Jenkins, "Time Series Analysis: Forecasting and Control"
   (lags up to about N/4 for sample correlation functions).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import scipy.linalg
from scipy import stats
from scipy.fft import irfft, next_fast_len, rfft

from ._validation import as_signal, check_same_length
from .errors import IdentificationError

__all__ = [
    "CORRELATION_TESTS",
    "CRITERIA",
    "CorrelationTests",
    "InformationCriteria",
    "PressResult",
    "correlation_tests",
    "criterion_value",
    "information_criteria",
    "press",
]

CRITERIA = ("aic", "aicc", "bic", "fpe")
"""Names accepted by :func:`criterion_value`."""

CORRELATION_TESTS = ("phi_ee", "phi_ue", "phi_e_eu", "phi_u2e", "phi_u2e2")
"""Keys of :attr:`CorrelationTests.passed`, in the order of Billings & Voon (1986)."""

_LABELS = {
    "phi_ee": "phi_ee",
    "phi_ue": "phi_ue",
    "phi_e_eu": "phi_e(eu)",
    "phi_u2e": "phi_u2'e",
    "phi_u2e2": "phi_u2'e2",
}


# ----------------------------------------------------------------------------------------------
# information criteria
# ----------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class InformationCriteria:
    """Result of :func:`information_criteria` (smaller is better for every criterion).

    Attributes
    ----------
    aic, aicc, bic, fpe : float
        See :func:`information_criteria` for the exact formulas.
    n_samples : int
        N, the number of residual samples.
    n_params : int
        p, the number of estimated parameters (total over output channels).
    sigma2 : float
        V = det(E^T E / N): the mean squared residual for one output, the determinant of the
        (uncentred) residual covariance for several.
    """

    aic: float
    aicc: float
    bic: float
    fpe: float
    n_samples: int
    n_params: int
    sigma2: float


def _check_n_params(n_params, n_samples: int) -> int:
    if not isinstance(n_params, (int, np.integer)) or isinstance(n_params, bool):
        raise IdentificationError(
            f"n_params must be a non-negative integer (the number of estimated parameters), "
            f"got {n_params!r}"
        )
    p = int(n_params)
    if p < 0:
        raise IdentificationError(f"n_params must be >= 0, got {p}")
    if n_samples <= p + 1:
        raise IdentificationError(
            f"information criteria need more samples than parameters + 1: N = {n_samples}, "
            f"n_params = {p}; N must be > {p + 1} (AICc divides by N - p - 1, FPE by N - p)"
        )
    return p


def information_criteria(residuals, n_params: int) -> InformationCriteria:
    """AIC, AICc, BIC and FPE of a fitted model from its residuals.

    With N samples, p estimated parameters (total over all output channels) and residual
    matrix E (N, ny), V = det(E^T E / N) (Ljung's multi-output convention [Ljung99]_; for one
    output V = mean(e^2)) and, dropping the terms that do not depend on the model:

    * ``aic  = N ln V + 2 p``                      [Akaike74]_
    * ``aicc = aic + 2 p (p + 1) / (N - p - 1)``   [HurvichTsai89]_ (the single-output small-sample
      correction, applied with the total p also for several outputs)
    * ``bic  = N ln V + p ln N``                   [Schwarz78]_
    * ``fpe  = V (N + p) / (N - p)``               [Akaike69]_

    Ljung [Ljung99]_ §16.4 writes the same criteria divided by N; the ranking of models is the
    same. Compare criteria only between fits scored on the same N samples.

    Parameters
    ----------
    residuals : array (N,) or (N, ny)
        One-step-ahead prediction errors (time on axis 0).
    n_params : int
        Number of estimated parameters p >= 0; N must exceed p + 1.

    Returns
    -------
    InformationCriteria

    Raises
    ------
    IdentificationError
        Bad shape or non-finite residuals, N <= p + 1, or V = 0 (an exact fit, or residual
        channels that are linearly dependent), where the logarithm is undefined.
    """
    e = as_signal(residuals, "residuals")
    n = e.shape[0]
    p = _check_n_params(n_params, n)
    sign, logdet = np.linalg.slogdet(e.T @ e / n)
    if sign <= 0 or not np.isfinite(logdet):
        raise IdentificationError(
            "the residual covariance det(E^T E / N) is zero: the residuals are identically zero "
            "(an exact fit) or, for several outputs, linearly dependent across channels; "
            "information criteria need V > 0"
        )
    v = math.exp(logdet)
    aic = n * logdet + 2.0 * p
    return InformationCriteria(
        aic=float(aic),
        aicc=float(aic + 2.0 * p * (p + 1) / (n - p - 1)),
        bic=float(n * logdet + p * math.log(n)),
        fpe=float(v * (n + p) / (n - p)),
        n_samples=n,
        n_params=p,
        sigma2=float(v),
    )


def criterion_value(name: str, residuals, n_params: int) -> float:
    """One information criterion by name, for model-size selection (smaller is better).

    Parameters
    ----------
    name : {"aic", "aicc", "bic", "fpe"}
        Criterion; see :func:`information_criteria` for the formulas.
    residuals, n_params
        As for :func:`information_criteria`.
    """
    if not isinstance(name, str) or name.lower() not in CRITERIA:
        raise IdentificationError(f"criterion name must be one of {CRITERIA}, got {name!r}")
    return getattr(information_criteria(residuals, n_params), name.lower())


# ----------------------------------------------------------------------------------------------
# PRESS
# ----------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class PressResult:
    """Result of :func:`press`.

    Attributes
    ----------
    press : float or ndarray (k,)
        Sum of squared leave-one-out residuals, per output column (a float for 1-D ``y``).
    loo_residuals : ndarray (N,) or (N, k)
        Leave-one-out residuals ``e_i / (1 - h_ii)``: the error at sample i of the fit made
        without sample i.
    leverage : ndarray (N,)
        Hat-matrix diagonal h_ii in [0, 1); sums to ``rank``.
    residuals : ndarray (N,) or (N, k)
        Ordinary least-squares residuals ``e_i`` of the fit on all samples.
    rank : int
        Numerical rank of X used for the fit.
    """

    press: float | np.ndarray
    loo_residuals: np.ndarray
    leverage: np.ndarray
    residuals: np.ndarray
    rank: int


_UNIT_LEVERAGE_TOL = math.sqrt(np.finfo(np.float64).eps)


def press(X, y, *, rtol: float | None = None) -> PressResult:
    """Predicted residual sum of squares (PRESS) of the least-squares fit ``y ~ X theta``.

    The leave-one-out residual of sample i is ``e_i / (1 - h_ii)`` [Allen74]_, with e the
    ordinary residuals and h_ii the diagonal of the hat matrix H = X X^+, so no refit is needed.
    H is formed from a thin pivoted QR factorisation ``X P = Q R``: the numerical rank r is the
    number of diagonal entries with ``|R_kk| > rtol * |R_00|`` and ``h_ii = sum_k Q_ik^2`` over
    the first r columns of Q. Columns dependent to round-off are thereby dropped; the fitted
    values (the projection of y on the column space of X) are those of any least-squares
    solution, e.g. ``numpy.linalg.lstsq``. PRESS is the usual leave-one-out criterion for NARX
    term selection [WeiBillings08]_.

    Parameters
    ----------
    X : array (N, M)
        Regression matrix (a 1-D array is one regressor).
    y : array (N,) or (N, k)
        Target; each column is fitted separately on the same X.
    rtol : float, optional
        Relative rank tolerance; default ``max(N, M) * eps`` (as ``numpy.linalg.matrix_rank``).

    Returns
    -------
    PressResult

    Raises
    ------
    IdentificationError
        Bad shapes or non-finite values, or a sample with leverage 1 (``1 - h_ii <=
        sqrt(eps)``): it is fitted exactly by a direction only it supports (e.g. a regressor
        that is non-zero at that sample alone, or N not greater than the rank), so its
        leave-one-out residual is undefined.
    """
    Xa = as_signal(X, "X")
    Y = as_signal(y, "y")
    check_same_length(Xa, Y, "X", "y")
    n, m = Xa.shape
    if rtol is None:
        rtol = max(n, m) * np.finfo(np.float64).eps
    elif not (isinstance(rtol, (int, float, np.floating)) and 0.0 <= rtol < 1.0):
        raise IdentificationError(f"rtol must be a float in [0, 1), got {rtol!r}")
    q, r, _ = scipy.linalg.qr(Xa, mode="economic", pivoting=True)
    diag = np.abs(np.diag(r))
    rank = int(np.count_nonzero(diag > rtol * diag[0])) if diag[0] > 0 else 0
    q = q[:, :rank]
    resid = Y - q @ (q.T @ Y)
    lev = np.einsum("ij,ij->i", q, q)
    bad = np.flatnonzero(1.0 - lev <= _UNIT_LEVERAGE_TOL)
    if bad.size:
        raise IdentificationError(
            f"sample(s) {bad[:10].tolist()}{' ...' if bad.size > 10 else ''} have leverage 1 "
            f"(N = {n}, rank of X = {rank}): each is fitted exactly by a regressor direction "
            "only it supports, so its leave-one-out residual is undefined. Drop the regressor "
            "column(s) that are non-zero only at those samples, or use more samples than terms"
        )
    loo = resid / (1.0 - lev)[:, None]
    total = np.sum(loo**2, axis=0)
    one_d = np.ndim(y) == 1
    return PressResult(
        press=float(total[0]) if one_d else total,
        loo_residuals=loo[:, 0] if one_d else loo,
        leverage=lev,
        residuals=resid[:, 0] if one_d else resid,
        rank=rank,
    )


# ----------------------------------------------------------------------------------------------
# correlation tests
# ----------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class CorrelationTests:
    """Result of :func:`correlation_tests` (Billings & Voon 1986).

    Index ``[j, i]`` is output (residual) channel j and input channel i; the last axis is lag.
    ``phi_ab(tau)`` is the sample correlation coefficient of ``a(t)`` and ``b(t + tau)``, so a
    residual containing ``u(t - d)`` shows in ``phi_ue`` at ``tau = +d``.

    Attributes
    ----------
    max_lag, n_samples : int
        The largest lag tested (samples) and the record length the correlations used.
    confidence : float
        Confidence level of the band (e.g. 0.95).
    band : float
        Half-width of the confidence band, ``norm.ppf((1 + confidence) / 2) / sqrt(N)``.
    lags : ndarray (2 max_lag + 1,)
        ``-max_lag .. max_lag``: lag axis of ``phi_ue``, ``phi_u2e``, ``phi_u2e2``.
    lags_positive : ndarray (max_lag,)
        ``1 .. max_lag``: lag axis of ``phi_ee`` and ``phi_e_eu``.
    phi_ee : ndarray (ny, max_lag)
        Residual autocorrelation (lag 0 is 1 by definition and excluded).
    phi_ue : ndarray (ny, nu, 2 max_lag + 1)
        Input-residual cross-correlation.
    phi_e_eu : ndarray (ny, nu, max_lag)
        ``corr(e(t), e(t - k) u(t - k))`` at ``k = 1 .. max_lag``, i.e. Billings & Voon's
        ``phi_e(eu)(tau)`` with ``k = 1 + tau``, ``tau = 0 .. max_lag - 1``.
    phi_u2e, phi_u2e2 : ndarray (ny, nu, 2 max_lag + 1)
        ``phi_u2'e`` and ``phi_u2'e2``: correlation of ``u^2 - mean(u^2)`` with e and with e^2.
        NaN where ``u^2`` is constant (a binary input), for which these tests are vacuous.
    n_outside, n_allowed : dict of str -> ndarray of int
        Per test (keys :data:`CORRELATION_TESTS`): lags outside ``±band``, and the count allowed.
    limit : dict of str -> float
        Per test: the simultaneous bound no single lag may exceed.
    passed : dict of str -> ndarray of bool
        Per test: shape (ny,) for ``phi_ee``, (ny, nu) for the others. See
        :func:`correlation_tests` for the rule.
    """

    max_lag: int
    n_samples: int
    confidence: float
    band: float
    lags: np.ndarray
    lags_positive: np.ndarray
    phi_ee: np.ndarray
    phi_ue: np.ndarray
    phi_e_eu: np.ndarray
    phi_u2e: np.ndarray
    phi_u2e2: np.ndarray
    n_outside: dict = field(repr=False)
    n_allowed: dict = field(repr=False)
    limit: dict = field(repr=False)
    passed: dict = field(repr=False)

    @property
    def all_passed(self) -> bool:
        """True when every test passed for every (output, input) pair."""
        return all(bool(np.all(v)) for v in self.passed.values())

    def lags_of(self, name: str) -> np.ndarray:
        """Lag axis of the correlation function ``name`` (one of :data:`CORRELATION_TESTS`).

        Parameters
        ----------
        name : str
            One of :data:`CORRELATION_TESTS`.
        """
        if name not in CORRELATION_TESTS:
            raise IdentificationError(f"name must be one of {CORRELATION_TESTS}, got {name!r}")
        return self.lags_positive if name in ("phi_ee", "phi_e_eu") else self.lags

    def _pairs(self):
        ny, nu = self.phi_ue.shape[:2]
        for j in range(ny):
            for i in range(nu):
                for name in CORRELATION_TESTS:
                    idx = (j,) if name == "phi_ee" else (j, i)
                    if name == "phi_ee" and i > 0:
                        continue
                    yield j, i, name, idx

    def table(self, input_names=None, output_names=None) -> str:
        """Plain-text summary: one row per test and pair (max |phi|, lags outside, verdict).

        Parameters
        ----------
        input_names, output_names : sequence of str, optional
            Channel names for the rows (default ``u1, u2, ...`` and ``e1, e2, ...``).
        """
        ny, nu = self.phi_ue.shape[:2]
        unames = input_names or [f"u{i + 1}" for i in range(nu)]
        enames = output_names or [f"e{j + 1}" for j in range(ny)]
        rows = [
            f"correlation tests: N = {self.n_samples}, lags up to {self.max_lag}, "
            f"{100 * self.confidence:g} % band ±{self.band:.4f}",
            f"{'test':<10} {'pair':<12} {'max|phi|':>9} {'limit':>7} {'outside':>9} {'result':>6}",
        ]
        for j, i, name, idx in self._pairs():
            phi = getattr(self, name)[idx]
            pair = enames[j] if name == "phi_ee" else f"{enames[j]}/{unames[i]}"
            if np.all(np.isnan(phi)):
                peak, verdict = f"{'n/a':>9}", "n/a"
            else:
                peak = f"{np.nanmax(np.abs(phi)):>9.4f}"
                verdict = "pass" if self.passed[name][idx] else "FAIL"
            counts = f"{self.n_outside[name][idx]}/{self.n_allowed[name][idx]}"
            rows.append(
                f"{_LABELS[name]:<10} {pair:<12} {peak} {self.limit[name]:>7.4f} "
                f"{counts:>9} {verdict:>6}"
            )
        return "\n".join(rows)

    def plot(self, axes=None):
        """Draw every correlation function with the confidence band; return the figure.

        One row of five panels per (output, input) pair. ``axes`` (optional) is a sequence or
        array of at least ``5 * ny * nu`` matplotlib Axes, filled row by row.

        Parameters
        ----------
        axes : sequence or array of matplotlib Axes, optional
            At least ``5 * ny * nu`` Axes, filled row by row (default: a new figure).
        """
        from matplotlib.figure import Figure  # lazy: matplotlib is only needed for plotting

        ny, nu = self.phi_ue.shape[:2]
        n_rows = ny * nu
        if axes is None:
            fig = Figure(figsize=(15, 2.6 * n_rows), layout="constrained")
            axes = fig.subplots(n_rows, 5, squeeze=False)
        axes = np.asarray(axes, dtype=object).ravel()
        if axes.size < 5 * n_rows:
            raise IdentificationError(
                f"plot needs {5 * n_rows} axes (5 per output/input pair), got {axes.size}"
            )
        fig = axes[0].figure
        for row in range(n_rows):
            j, i = divmod(row, nu)
            for col, name in enumerate(CORRELATION_TESTS):
                ax = axes[5 * row + col]
                phi = getattr(self, name)[(j,) if name == "phi_ee" else (j, i)]
                ax.vlines(self.lags_of(name), 0.0, phi, color="C0")
                ax.plot(self.lags_of(name), phi, "o", color="C0", markersize=3)
                for s in (-1.0, 1.0):
                    ax.axhline(s * self.band, color="C3", linestyle="--", linewidth=1)
                ax.axhline(0.0, color="k", linewidth=0.5)
                ax.set_ylim(-1.0, 1.0)
                ax.set_title(f"{_LABELS[name]}  e{j + 1}/u{i + 1}", fontsize=9)
                ax.set_xlabel("lag")
        return fig


def _check_lag_confidence(max_lag, confidence, n: int) -> tuple[int, float]:
    if not isinstance(max_lag, (int, np.integer)) or isinstance(max_lag, bool) or max_lag < 1:
        raise IdentificationError(f"max_lag must be a positive integer, got {max_lag!r}")
    if 4 * int(max_lag) > n:
        raise IdentificationError(
            f"record too short for max_lag = {max_lag}: N = {n} samples, but max_lag must be "
            f"<= N / 4 = {n // 4} (lower max_lag or use a longer record)"
        )
    ok = isinstance(confidence, (int, float, np.floating)) and not isinstance(confidence, bool)
    if not ok or not 0.0 < confidence < 1.0:
        raise IdentificationError(
            f"confidence must be a number strictly between 0 and 1 (e.g. 0.95), got {confidence!r}"
        )
    return int(max_lag), float(confidence)


def _prepare(x: np.ndarray, nfft: int):
    """Centre one series; return what :func:`_corr` needs, or None if it is constant."""
    scale = float(np.sqrt(np.mean(x * x)))
    xc = x - x.mean()
    if not np.sqrt(np.mean(xc * xc)) > 1e-10 * scale:
        return None
    zero = np.zeros(1)
    return (
        xc,
        rfft(xc, nfft),
        np.concatenate((zero, np.cumsum(xc))),
        np.concatenate((zero, np.cumsum(xc * xc))),
    )


def _corr(pa, pb, lags: np.ndarray, nfft: int) -> np.ndarray:
    """Sample correlation coefficient of ``a(t)`` and ``b(t + tau)`` over their overlap.

    Equal to ``np.corrcoef`` of the two overlapping segments at each lag; the lagged sums come
    from one FFT cross-correlation (zero padding ``nfft >= N + max|lag|`` stops wrap-around)
    and the segment means and variances from cumulative sums.
    """
    if pa is None or pb is None:
        return np.full(lags.shape, np.nan)
    a, fa, ca, caa = pa
    _, fb, cb, cbb = pb
    n_total = a.size
    s_ab = irfft(np.conj(fa) * fb, nfft)[lags % nfft]
    pos, neg = np.maximum(lags, 0), np.maximum(-lags, 0)
    n = n_total - np.abs(lags)  # overlap: a[neg : N - pos] with b[pos : N - neg]
    sa, saa = ca[n_total - pos] - ca[neg], caa[n_total - pos] - caa[neg]
    sb, sbb = cb[n_total - neg] - cb[pos], cbb[n_total - neg] - cbb[pos]
    va, vb = saa - sa * sa / n, sbb - sb * sb / n
    tiny = 1e-20 * n
    ok = (va > tiny * caa[-1] / n_total) & (vb > tiny * cbb[-1] / n_total)
    with np.errstate(invalid="ignore", divide="ignore"):
        r = (s_ab - sa * sb / n) / np.sqrt(va * vb)
    return np.where(ok, np.clip(r, -1.0, 1.0), np.nan)


def _verdict(phi: np.ndarray, band: float, confidence: float):
    """Lags outside the band, the count allowed, the simultaneous limit, and pass/fail."""
    alpha = 1.0 - confidence
    n_lags = phi.shape[-1]
    finite = np.isfinite(phi)
    outside = np.sum(finite & (np.abs(np.nan_to_num(phi)) > band), axis=-1)
    allowed = max(1, int(stats.binom.ppf(1.0 - alpha / 2.0, n_lags, alpha)))
    z = stats.norm.ppf((1.0 + confidence) / 2.0)
    limit = band * stats.norm.ppf(1.0 - alpha / (4.0 * n_lags)) / z
    peak = np.max(np.abs(np.nan_to_num(phi)), axis=-1)
    passed = (outside <= allowed) & (peak <= limit)
    return outside, np.full(outside.shape, allowed), float(limit), passed


def correlation_tests(u, e, max_lag: int = 20, confidence: float = 0.95) -> CorrelationTests:
    """Billings & Voon's correlation-based validity tests of a (nonlinear) model's residuals.

    For an adequate model the residuals e are unpredictable from past inputs and residuals,
    so every function below is zero at every tested lag [BillingsVoon86]_:

    * ``phi_ee(tau)   = corr(e(t), e(t + tau))``,               tau = 1 .. max_lag
    * ``phi_ue(tau)   = corr(u(t), e(t + tau))``,               tau = -max_lag .. max_lag
    * ``phi_e_eu(k)   = corr(e(t), e(t - k) u(t - k))``,        k = 1 .. max_lag
      (Billings & Voon's ``phi_e(eu)(tau)`` with ``k = 1 + tau``)
    * ``phi_u2e(tau)  = corr(u^2(t) - mean(u^2), e(t + tau))``, tau = -max_lag .. max_lag
    * ``phi_u2e2(tau) = corr(u^2(t) - mean(u^2), e^2(t + tau))``, tau = -max_lag .. max_lag

    Each value is the sample correlation coefficient (means removed, divided by the product of
    the standard deviations) of the two series over their N - |tau| overlapping samples — the
    same as ``np.corrcoef(a[:N - tau], b[tau:])[0, 1]`` — so it lies in [-1, 1]. This differs
    from the full-record normalisation of Billings & Voon by O(|tau| / N). All functions are
    computed by FFT. For several inputs/outputs every (output, input) pair is tested
    separately; cross-correlations between residual channels (Billings & Zhu 1994) are not.

    **Pass rule.** With ``alpha = 1 - confidence``, the band ``±z / sqrt(N)``, ``z =
    norm.ppf(1 - alpha/2)``, and n tested lags, a function passes when both

    1. at most ``max(1, binom.ppf(1 - alpha/2, n, alpha))`` lags lie outside the band (for
       uncorrelated residuals each lag is outside with probability alpha), and
    2. no lag exceeds the simultaneous limit ``norm.ppf(1 - alpha / (4 n)) / sqrt(N)``
       (Bonferroni over the n lags), so a single large correlation is never excused by rule 1.

    Each rule has a false-alarm rate of at most alpha/2, so a function of uncorrelated
    residuals fails with probability at most about alpha (for N large). Lags where a function
    is undefined (NaN) count as inside; a function undefined at every lag passes vacuously.
    The band assumes the residuals are white; when they are not, ``phi_ee`` fails, and the
    other tests are then only indicative.

    Parameters
    ----------
    u : array (N,) or (N, nu)
        Input record.
    e : array (N,) or (N, ny)
        Residuals (one-step-ahead prediction errors), time-aligned with u.
    max_lag : int
        Largest lag tested, 1 <= max_lag <= N / 4 [BoxJenkins]_.
    confidence : float
        Confidence level of the band, in (0, 1).

    Returns
    -------
    CorrelationTests
    """
    u = as_signal(u, "u")
    e = as_signal(e, "e")
    check_same_length(u, e, "u", "e")
    n = e.shape[0]
    max_lag, confidence = _check_lag_confidence(max_lag, confidence, n)
    lags = np.arange(-max_lag, max_lag + 1)
    pos = np.arange(1, max_lag + 1)
    phis = _all_correlations(u, e, lags, pos)
    band = float(stats.norm.ppf((1.0 + confidence) / 2.0) / math.sqrt(n))
    verdicts = {k: _verdict(v, band, confidence) for k, v in phis.items()}
    return CorrelationTests(
        max_lag=max_lag,
        n_samples=n,
        confidence=confidence,
        band=band,
        lags=lags,
        lags_positive=pos,
        **phis,
        n_outside={k: v[0] for k, v in verdicts.items()},
        n_allowed={k: v[1] for k, v in verdicts.items()},
        limit={k: v[2] for k, v in verdicts.items()},
        passed={k: v[3] for k, v in verdicts.items()},
    )


def _prepared_channels(x: np.ndarray, name: str, nfft: int) -> list:
    out = []
    for k, c in enumerate(x.T):
        p = _prepare(c, nfft)
        if p is None:
            raise IdentificationError(
                f"{name} channel {k} is constant; correlation tests need a varying "
                f"{'input' if name == 'u' else 'residual (an all-zero residual is an exact fit)'}"
            )
        out.append(p)
    return out


def _all_correlations(u: np.ndarray, e: np.ndarray, lags: np.ndarray, pos: np.ndarray) -> dict:
    """The five correlation functions of every (output, input) pair, keyed as the tests."""
    nfft = next_fast_len(e.shape[0] + int(lags.max()), real=True)
    prep_u = _prepared_channels(u, "u", nfft)
    prep_e = _prepared_channels(e, "e", nfft)
    prep_u2 = [_prepare(c**2, nfft) for c in u.T]
    prep_e2 = [_prepare(c**2, nfft) for c in e.T]
    ny, nu = e.shape[1], u.shape[1]
    shape = (ny, nu, lags.size)
    phi_ue, phi_u2e, phi_u2e2 = np.empty(shape), np.empty(shape), np.empty(shape)
    phi_e_eu = np.empty((ny, nu, pos.size))
    for j in range(ny):
        for i in range(nu):
            phi_ue[j, i] = _corr(prep_u[i], prep_e[j], lags, nfft)
            phi_u2e[j, i] = _corr(prep_u2[i], prep_e[j], lags, nfft)
            phi_u2e2[j, i] = _corr(prep_u2[i], prep_e2[j], lags, nfft)
            # corr(e(t), (e u)(t - k)) is corr((e u)(t), e(t + k))
            prep_eu = _prepare(e[:, j] * u[:, i], nfft)
            phi_e_eu[j, i] = _corr(prep_eu, prep_e[j], pos, nfft)
    return dict(
        phi_ee=np.array([_corr(p, p, pos, nfft) for p in prep_e]),
        phi_ue=phi_ue,
        phi_e_eu=phi_e_eu,
        phi_u2e=phi_u2e,
        phi_u2e2=phi_u2e2,
    )
