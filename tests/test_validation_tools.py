"""Model-validation tools: information criteria, PRESS and Billings' correlation tests.

Every expected value is computed independently in the test (by hand formulas, brute-force
refits or ``np.corrcoef`` of shifted arrays) or follows from the generating system.
"""

from __future__ import annotations

import math
from statistics import NormalDist

import numpy as np
import pytest
from matplotlib.figure import Figure
from scipy.signal import lfilter

from identification.errors import IdentificationError
from identification.validation import (
    CORRELATION_TESTS,
    correlation_tests,
    criterion_value,
    information_criteria,
    press,
)

# ----------------------------------------------------------------------------------------------
# information criteria
# ----------------------------------------------------------------------------------------------


def test_information_criteria_siso_by_hand():
    e = [0.3, -1.2, 0.8, 0.05, -0.4, 1.1, -0.7, 0.2, 0.6, -0.9, 0.15, -0.25]
    n, p = len(e), 3
    v = sum(x * x for x in e) / n
    ic = information_criteria(np.array(e), p)
    aic = n * math.log(v) + 2 * p
    assert ic.n_samples == n and ic.n_params == p
    assert ic.sigma2 == pytest.approx(v, rel=1e-14)
    assert ic.aic == pytest.approx(aic, rel=1e-12)
    assert ic.aicc == pytest.approx(aic + 2 * p * (p + 1) / (n - p - 1), rel=1e-12)
    assert ic.bic == pytest.approx(n * math.log(v) + p * math.log(n), rel=1e-12)
    assert ic.fpe == pytest.approx(v * (n + p) / (n - p), rel=1e-12)
    # a single column given as (N, 1) is the same record
    assert information_criteria(np.array(e)[:, None], p) == ic


def test_information_criteria_mimo_uses_determinant():
    rng = np.random.default_rng(3)
    z = rng.standard_normal((15, 2))
    E = np.column_stack([z[:, 0], 0.9 * z[:, 0] + 0.3 * z[:, 1]])  # strongly correlated channels
    n, p = 15, 4
    saa, sbb, sab = (E[:, 0] ** 2).sum(), (E[:, 1] ** 2).sum(), (E[:, 0] * E[:, 1]).sum()
    v = (saa * sbb - sab * sab) / n**2  # 2x2 determinant written out
    ic = information_criteria(E, p)
    assert ic.sigma2 == pytest.approx(v, rel=1e-12)
    assert ic.aic == pytest.approx(n * math.log(v) + 2 * p, rel=1e-12)
    assert ic.bic == pytest.approx(n * math.log(v) + p * math.log(n), rel=1e-12)
    # not the product of the per-channel mean squares: the correlation between channels counts
    assert ic.sigma2 < 0.5 * (saa / n) * (sbb / n)


def test_fpe_formula_and_its_aic_equivalence():
    rng = np.random.default_rng(5)
    e = rng.standard_normal(4000)
    n, p = e.size, 10
    v = np.dot(e, e) / n
    ic = information_criteria(e, p)
    assert ic.fpe == pytest.approx(v * (1 + p / n) / (1 - p / n), rel=1e-12)
    # Akaike: N ln FPE = N ln V + N ln((N + p)/(N - p)) = AIC + O(p^3 / N^2)
    assert n * math.log(ic.fpe) == pytest.approx(ic.aic, abs=1e-3)


def test_criterion_value_by_name():
    e = np.array([0.5, -0.1, 0.3, -0.8, 0.2, 0.9, -0.4, 0.1])
    n, p = e.size, 2
    v = np.mean(e**2)
    expected = {
        "aic": n * math.log(v) + 2 * p,
        "aicc": n * math.log(v) + 2 * p + 2 * p * (p + 1) / (n - p - 1),
        "bic": n * math.log(v) + p * math.log(n),
        "fpe": v * (n + p) / (n - p),
    }
    for name, value in expected.items():
        assert criterion_value(name, e, p) == pytest.approx(value, rel=1e-12)
    assert criterion_value("BIC", e, p) == pytest.approx(expected["bic"], rel=1e-12)


def _arx_residuals(y, u, order, start):
    """Residuals of an ARX(order, order) fitted by lstsq on samples start..N-1."""
    n = y.size
    cols = [y[start - k : n - k] for k in range(1, order + 1)]
    cols += [u[start - k : n - k] for k in range(1, order + 1)]
    X = np.column_stack(cols)
    theta = np.linalg.lstsq(X, y[start:], rcond=None)[0]
    return y[start:] - X @ theta


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_bic_picks_the_true_arx_order(seed):
    rng = np.random.default_rng(seed)
    n = 2000
    u = rng.standard_normal(n)
    w = 0.3 * rng.standard_normal(n)
    # ARX(2): y(t) = 1.5 y(t-1) - 0.7 y(t-2) + u(t-1) + 0.5 u(t-2) + w(t)
    y = lfilter([1.0], [1.0, -1.5, 0.7], lfilter([0.0, 1.0, 0.5], [1.0], u) + w)
    orders = range(1, 7)
    bic = [criterion_value("bic", _arx_residuals(y, u, k, 6), 2 * k) for k in orders]
    assert orders[int(np.argmin(bic))] == 2
    assert bic[0] - bic[1] > 100  # order 1 is clearly too small


# ----------------------------------------------------------------------------------------------
# PRESS
# ----------------------------------------------------------------------------------------------


def _brute_force_loo(X, Y):
    Y2 = Y.reshape(Y.shape[0], -1)
    out = np.empty_like(Y2)
    for i in range(X.shape[0]):
        keep = np.arange(X.shape[0]) != i
        theta = np.linalg.lstsq(X[keep], Y2[keep], rcond=None)[0]
        out[i] = Y2[i] - X[i] @ theta
    return out.reshape(Y.shape)


@pytest.mark.parametrize("k", [None, 3])
def test_press_equals_brute_force_leave_one_out(k):
    rng = np.random.default_rng(7)
    X = rng.standard_normal((30, 5))
    shape = (30,) if k is None else (30, k)
    y = X @ rng.standard_normal(5 if k is None else (5, k)) + rng.standard_normal(shape)
    res = press(X, y)
    loo = _brute_force_loo(X, y)
    np.testing.assert_allclose(res.loo_residuals, loo, rtol=1e-10, atol=0)
    np.testing.assert_allclose(res.press, (loo**2).sum(axis=0), rtol=1e-10, atol=0)
    if k is None:
        assert isinstance(res.press, float)
    assert res.leverage.sum() == pytest.approx(np.linalg.matrix_rank(X), rel=1e-12)
    assert res.rank == 5


def test_press_rank_deficient_columns():
    rng = np.random.default_rng(8)
    A = rng.standard_normal((25, 4))
    X = np.column_stack([A, A[:, 0] - 2.0 * A[:, 2]])  # column 4 is dependent
    y = A @ np.array([1.0, -0.5, 0.2, 0.0]) + 0.1 * rng.standard_normal(25)
    res = press(X, y)
    assert np.linalg.matrix_rank(X) == 4
    assert res.rank == 4
    assert res.leverage.sum() == pytest.approx(4.0, rel=1e-12)
    np.testing.assert_allclose(res.loo_residuals, _brute_force_loo(X, y), rtol=1e-10, atol=0)


def test_press_unit_leverage_is_reported():
    rng = np.random.default_rng(9)
    X = rng.standard_normal((20, 3))
    X = np.column_stack([X, np.eye(20)[:, 6]])  # a regressor non-zero only at sample 6
    with pytest.raises(IdentificationError, match=r"sample\(s\) \[6\] have leverage 1"):
        press(X, rng.standard_normal(20))


# ----------------------------------------------------------------------------------------------
# correlation tests
# ----------------------------------------------------------------------------------------------


def test_white_residuals_independent_of_white_input_pass():
    rng = np.random.default_rng(2024)
    res = correlation_tests(rng.standard_normal(5000), rng.standard_normal(5000))
    assert res.band == pytest.approx(1.959964 / math.sqrt(5000), rel=1e-6)
    assert res.all_passed, res.table()


def test_false_alarm_rate_is_close_to_nominal():
    # uncorrelated residuals: each test should fail about (at most) 5 % of the time
    n_runs = 60
    fails = dict.fromkeys(CORRELATION_TESTS, 0)
    for seed in range(n_runs):
        rng = np.random.default_rng(1000 + seed)
        res = correlation_tests(rng.standard_normal(1000), rng.standard_normal(1000))
        for name in CORRELATION_TESTS:
            fails[name] += not bool(np.all(res.passed[name]))
    assert max(fails.values()) <= 0.15 * n_runs, fails
    assert sum(fails.values()) >= 3, fails  # the tests are not vacuously lenient either


def _allowed_count(n_lags, alpha):
    """Smallest k with P(Binomial(n_lags, alpha) > k) <= alpha / 2, at least 1."""
    cdf = 0.0
    for k in range(n_lags + 1):
        cdf += math.comb(n_lags, k) * alpha**k * (1 - alpha) ** (n_lags - k)
        if cdf >= 1 - alpha / 2 - 1e-12:
            return max(1, k)
    return n_lags


@pytest.mark.parametrize("confidence", [0.95, 0.9])
def test_pass_rule_as_documented(confidence):
    rng = np.random.default_rng(21)
    n, max_lag = 3000, 15
    u = rng.standard_normal(n)
    w = lfilter([1.0], [1.0, -0.1], rng.standard_normal(n))
    e = w + 0.06 * np.r_[0.0, 0.0, u[:-2]] + 0.03 * np.r_[0.0, u[:-1] ** 2]
    res = correlation_tests(u, e, max_lag=max_lag, confidence=confidence)
    alpha = 1 - confidence
    z = NormalDist().inv_cdf(1 - alpha / 2)
    assert res.band == pytest.approx(z / math.sqrt(n), rel=1e-12)
    for name in CORRELATION_TESTS:
        phi = getattr(res, name)
        n_lags = phi.shape[-1]
        assert n_lags == (max_lag if name in ("phi_ee", "phi_e_eu") else 2 * max_lag + 1)
        outside = (np.abs(phi) > res.band).sum(axis=-1)
        allowed = _allowed_count(n_lags, alpha)
        limit = NormalDist().inv_cdf(1 - alpha / (4 * n_lags)) / math.sqrt(n)
        np.testing.assert_array_equal(res.n_outside[name], outside)
        assert np.all(res.n_allowed[name] == allowed)
        assert res.limit[name] == pytest.approx(limit, rel=1e-9)
        expected = (outside <= allowed) & (np.abs(phi).max(axis=-1) <= limit)
        np.testing.assert_array_equal(res.passed[name], expected)


def test_pass_rule_both_parts_decide():
    # at a low confidence level both parts of the rule are often decisive on their own
    only_count = only_peak = 0
    for seed in range(20):
        rng = np.random.default_rng(seed)
        u, e = rng.standard_normal(500), rng.standard_normal(500)
        res = correlation_tests(u, e, max_lag=15, confidence=0.5)
        for name in CORRELATION_TESTS:
            phi = np.abs(getattr(res, name))
            too_many = (phi > res.band).sum(axis=-1) > res.n_allowed[name]
            too_big = phi.max(axis=-1) > res.limit[name]
            np.testing.assert_array_equal(res.passed[name], ~too_many & ~too_big)
            only_count += int(np.sum(too_many & ~too_big))
            only_peak += int(np.sum(~too_many & too_big))
    assert only_count > 0 and only_peak > 0


def test_coloured_residuals_fail_phi_ee():
    rng = np.random.default_rng(11)
    u = rng.standard_normal(5000)
    e = lfilter([1.0], [1.0, -0.6], rng.standard_normal(5000))
    res = correlation_tests(u, e)
    assert not res.passed["phi_ee"][0]
    assert res.phi_ee[0, 0] == pytest.approx(0.6, abs=0.05)  # AR(1) autocorrelation at lag 1


def test_single_large_autocorrelation_fails_phi_ee():
    # MA(1): only lag 1 is outside the band, but it is far outside
    rng = np.random.default_rng(12)
    w = rng.standard_normal(5001)
    e = w[1:] + 0.5 * w[:-1]
    res = correlation_tests(rng.standard_normal(5000), e)
    assert res.n_outside["phi_ee"][0] <= res.n_allowed["phi_ee"][0]  # the count rule alone
    assert not res.passed["phi_ee"][0]
    assert res.phi_ee[0, 0] == pytest.approx(0.5 / 1.25, abs=0.05)


def test_unmodelled_quadratic_term_fails_u2_tests_not_phi_ue():
    rng = np.random.default_rng(13)
    n = 5000
    u = rng.standard_normal(n)
    u1 = np.r_[0.0, u[:-1]]  # u(t-1)
    u2 = np.r_[0.0, 0.0, u[:-2]]  # u(t-2)
    y = u1 + 0.5 * u1**2 + 0.1 * rng.standard_normal(n)
    X = np.column_stack([np.ones(n), u1, u2])  # linear model of the quadratic system
    e = y - X @ np.linalg.lstsq(X, y, rcond=None)[0]
    res = correlation_tests(u, e)
    assert res.passed["phi_ue"][0, 0], res.table()
    assert not (res.passed["phi_u2e"][0, 0] and res.passed["phi_u2e2"][0, 0])
    assert res.lags[np.argmax(np.abs(res.phi_u2e[0, 0]))] == 1


def test_missing_input_lag_fails_phi_ue_at_that_lag():
    rng = np.random.default_rng(14)
    u = rng.standard_normal(5000)
    e = rng.standard_normal(5000) + 0.4 * np.r_[0.0, 0.0, u[:-2]]  # contains u(t-2)
    res = correlation_tests(u, e)
    assert not res.passed["phi_ue"][0, 0]
    assert res.lags[np.argmax(np.abs(res.phi_ue[0, 0]))] == 2
    assert res.phi_ue[0, 0, res.lags == 2][0] == pytest.approx(0.4 / math.sqrt(1.16), abs=0.04)


def test_bilinear_noise_term_fails_phi_e_eu():
    rng = np.random.default_rng(15)
    u = rng.standard_normal(5001)
    w = rng.standard_normal(5001)
    e = w[1:] + 0.5 * w[:-1] * u[:-1]  # e(t) = w(t) + 0.5 w(t-1) u(t-1)
    res = correlation_tests(u[1:], e)
    assert not res.passed["phi_e_eu"][0, 0]
    assert res.lags_positive[np.argmax(np.abs(res.phi_e_eu[0, 0]))] == 1


def _shifted_corr(a, b, tau):
    """np.corrcoef of a(t) and b(t + tau) over their overlap."""
    n = a.size
    if tau >= 0:
        return np.corrcoef(a[: n - tau], b[tau:])[0, 1]
    return np.corrcoef(a[-tau:], b[: n + tau])[0, 1]


def test_correlations_match_corrcoef_of_shifted_arrays():
    rng = np.random.default_rng(16)
    n = 800
    u = 0.3 + rng.standard_normal(n)
    w = lfilter([1.0], [1.0, -0.5], rng.standard_normal(n))
    e = w + 0.4 * np.r_[0.0, u[:-1]] + 0.3 * np.r_[0.0, 0.0, u[:-2] ** 2]
    res = correlation_tests(u, e, max_lag=10)
    lag = {int(t): k for k, t in enumerate(res.lags)}
    for tau in (-7, -1, 0, 2, 10):
        k = lag[tau]
        assert res.phi_ue[0, 0, k] == pytest.approx(_shifted_corr(u, e, tau), abs=1e-10)
        assert res.phi_u2e[0, 0, k] == pytest.approx(_shifted_corr(u**2, e, tau), abs=1e-10)
        assert res.phi_u2e2[0, 0, k] == pytest.approx(_shifted_corr(u**2, e**2, tau), abs=1e-10)
    for k in (1, 3, 10):
        assert res.phi_ee[0, k - 1] == pytest.approx(_shifted_corr(e, e, k), abs=1e-10)
        # phi_e(eu): e(t) against e(t-k) u(t-k)
        assert res.phi_e_eu[0, 0, k - 1] == pytest.approx(
            np.corrcoef(e[k:], (e * u)[: n - k])[0, 1], abs=1e-10
        )


def test_mimo_pairs_are_tested_separately():
    rng = np.random.default_rng(17)
    n = 4000
    u = rng.standard_normal((n, 2))
    e = rng.standard_normal((n, 3))
    e[:, 0] += 0.5 * np.r_[0.0, u[:-1, 1]]  # residual 0 contains input 1 at lag 1
    res = correlation_tests(u, e, max_lag=8)
    assert res.phi_ee.shape == (3, 8)
    for name in ("phi_ue", "phi_u2e", "phi_u2e2"):
        assert getattr(res, name).shape == (3, 2, 17)
    assert res.phi_e_eu.shape == (3, 2, 8)
    assert res.passed["phi_ee"].shape == (3,)
    assert res.passed["phi_ue"].shape == (3, 2)
    at_lag1 = res.phi_ue[:, :, res.lags == 1][..., 0]
    assert at_lag1[0, 1] == pytest.approx(0.5 / math.sqrt(1.25), abs=0.05)
    others = np.delete(at_lag1.ravel(), 1)
    assert np.all(np.abs(others) < 4 / math.sqrt(n))
    assert not res.passed["phi_ue"][0, 1]
    assert not res.all_passed


def test_binary_input_makes_u2_tests_vacuous():
    rng = np.random.default_rng(18)
    u = np.where(rng.standard_normal(2000) > 0, 1.0, -1.0)
    res = correlation_tests(u, rng.standard_normal(2000))
    assert np.all(np.isnan(res.phi_u2e)) and np.all(np.isnan(res.phi_u2e2))
    assert res.passed["phi_u2e"][0, 0] and res.passed["phi_u2e2"][0, 0]
    assert np.all(np.isfinite(res.phi_ue))
    assert "n/a" in res.table()


def test_table_and_plot():
    rng = np.random.default_rng(19)
    u = rng.standard_normal((3000, 2))
    e = rng.standard_normal(3000) + 0.5 * np.r_[0.0, u[:-1, 0]]
    res = correlation_tests(u, e, max_lag=5, confidence=0.99)
    assert res.band == pytest.approx(2.575829 / math.sqrt(3000), rel=1e-6)
    text = res.table(input_names=["force", "disp"])
    fail_rows = [r for r in text.splitlines() if r.rstrip().endswith("FAIL")]
    assert any(r.startswith("phi_ue") and "e1/force" in r for r in fail_rows)
    assert len(text.splitlines()) == 2 + 1 + 2 * 4  # title, header, phi_ee once, 4 per input
    fig = res.plot()
    assert isinstance(fig, Figure)
    assert len(fig.axes) == 10
    band_lines = [ln for ln in fig.axes[1].get_lines() if ln.get_linestyle() == "--"]
    assert sorted(float(ln.get_ydata()[0]) for ln in band_lines) == pytest.approx(
        [-res.band, res.band]
    )
    with pytest.raises(IdentificationError, match="needs 10 axes"):
        res.plot(axes=fig.axes[:4])


# ----------------------------------------------------------------------------------------------
# bad input
# ----------------------------------------------------------------------------------------------


def test_information_criteria_rejects_wrong_shape():
    with pytest.raises(IdentificationError, match="residuals must be 1-D"):
        information_criteria(np.zeros((10, 2, 2)), 1)


def test_information_criteria_rejects_nan():
    e = np.ones(20)
    e[4] = np.nan
    with pytest.raises(IdentificationError, match="residuals contains NaN"):
        information_criteria(e, 1)


def test_information_criteria_rejects_too_few_samples():
    with pytest.raises(IdentificationError, match=r"N = 6, n_params = 5; N must be > 6"):
        information_criteria(np.arange(1.0, 7.0), 5)


@pytest.mark.parametrize("p", [-1, 2.0, True, None])
def test_information_criteria_rejects_bad_n_params(p):
    with pytest.raises(IdentificationError, match="n_params must be"):
        information_criteria(np.arange(1.0, 30.0), p)


def test_information_criteria_rejects_exact_fit():
    with pytest.raises(IdentificationError, match="det"):
        information_criteria(np.zeros(30), 2)
    E = np.random.default_rng(0).standard_normal((30, 1))
    with pytest.raises(IdentificationError, match="linearly dependent"):
        information_criteria(np.hstack([E, 2 * E]), 2)


def test_criterion_value_rejects_unknown_name():
    with pytest.raises(IdentificationError, match=r"one of \('aic', 'aicc', 'bic', 'fpe'\)"):
        criterion_value("hqc", np.arange(1.0, 30.0), 2)


def test_press_rejects_wrong_shape():
    with pytest.raises(IdentificationError, match="X must be 1-D"):
        press(np.zeros((10, 2, 2)), np.zeros(10))


def test_press_rejects_nan():
    X = np.random.default_rng(0).standard_normal((10, 2))
    y = np.ones(10)
    y[3] = np.nan
    with pytest.raises(IdentificationError, match="y contains NaN"):
        press(X, y)


def test_press_rejects_length_mismatch():
    with pytest.raises(IdentificationError, match="X has 10 samples but y has 9"):
        press(np.random.default_rng(0).standard_normal((10, 2)), np.ones(9))


def test_press_rejects_too_few_samples():
    X = np.random.default_rng(0).standard_normal((3, 3))
    with pytest.raises(IdentificationError, match="leverage 1"):
        press(X, np.ones(3))


@pytest.mark.parametrize("rtol", [-1e-3, 1.0, "tiny"])
def test_press_rejects_bad_rtol(rtol):
    X = np.random.default_rng(0).standard_normal((10, 2))
    with pytest.raises(IdentificationError, match="rtol must be"):
        press(X, np.ones(10), rtol=rtol)


def test_correlation_tests_reject_wrong_shape():
    with pytest.raises(IdentificationError, match="u must be 1-D"):
        correlation_tests(np.zeros((100, 1, 1)), np.zeros(100))


def test_correlation_tests_reject_nan():
    rng = np.random.default_rng(0)
    e = rng.standard_normal(200)
    e[50] = np.nan
    with pytest.raises(IdentificationError, match="e contains NaN"):
        correlation_tests(rng.standard_normal(200), e)


def test_correlation_tests_reject_length_mismatch():
    rng = np.random.default_rng(0)
    with pytest.raises(IdentificationError, match="u has 200 samples but e has 199"):
        correlation_tests(rng.standard_normal(200), rng.standard_normal(199))


def test_correlation_tests_reject_too_short_record():
    rng = np.random.default_rng(0)
    with pytest.raises(IdentificationError, match=r"N = 50 samples.*<= N / 4 = 12"):
        correlation_tests(rng.standard_normal(50), rng.standard_normal(50), max_lag=20)


@pytest.mark.parametrize("max_lag", [0, -3, 2.5, True, None])
def test_correlation_tests_reject_bad_max_lag(max_lag):
    rng = np.random.default_rng(0)
    with pytest.raises(IdentificationError, match="max_lag must be a positive integer"):
        correlation_tests(rng.standard_normal(200), rng.standard_normal(200), max_lag=max_lag)


@pytest.mark.parametrize("confidence", [0.0, 1.0, 1.5, -0.2, float("nan"), "0.95", True])
def test_correlation_tests_reject_bad_confidence(confidence):
    rng = np.random.default_rng(0)
    with pytest.raises(IdentificationError, match="confidence must be a number"):
        correlation_tests(rng.standard_normal(200), rng.standard_normal(200), 5, confidence)


def test_correlation_tests_reject_constant_signals():
    rng = np.random.default_rng(0)
    with pytest.raises(IdentificationError, match="u channel 1 is constant"):
        correlation_tests(
            np.column_stack([rng.standard_normal(200), np.ones(200)]), rng.standard_normal(200)
        )
    with pytest.raises(IdentificationError, match="e channel 0 is constant"):
        correlation_tests(rng.standard_normal(200), np.zeros(200))
