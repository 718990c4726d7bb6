"""Error measures: QanTiM fit value (eq. 5-27), DC-corrected η0 (eq. 5-28) and the usual others."""

from __future__ import annotations

import numpy as np
import pytest

from identification import IdentificationError, metrics


def test_qantim_fit_value_eq_5_27_by_hand():
    y = np.array([1.0, -2.0, 3.0, -4.0])
    yhat = np.array([1.5, -2.0, 2.0, -4.0])
    # sum|e| = 0.5 + 0 + 1 + 0 = 1.5 ; sum|y| = 10
    assert metrics.qantim_fit(y, yhat) == pytest.approx(15.0)


def test_dc_corrected_fit_eq_5_28_by_hand():
    y = np.array([11.0, 8.0, 13.0, 6.0])  # mean 9.5 -> y0 = [1.5, -1.5, 3.5, -3.5], sum|y0| = 10
    yhat = np.array([1.0, -2.0, 4.0, -3.0])  # mean 0 -> e0 = [0.5, 0.5, -0.5, -0.5], sum = 2
    assert metrics.qantim_fit_dc(y, yhat) == pytest.approx(20.0)
    # eq. 5-27 is fooled by the DC offset, eq. 5-28 is not
    assert metrics.qantim_fit(y + 100, yhat + 100) < metrics.qantim_fit_dc(y + 100, yhat + 100)


def test_dc_corrected_fit_ignores_offsets_on_either_record(rng):
    y = rng.standard_normal((500, 3))
    yhat = y + 0.1 * rng.standard_normal((500, 3))
    base = metrics.qantim_fit_dc(y, yhat)
    assert base.shape == (3,)
    np.testing.assert_allclose(metrics.qantim_fit_dc(y + 5.0, yhat - 2.0), base, rtol=1e-12)


def test_perfect_and_zero_estimates():
    y = np.sin(np.linspace(0, 20, 400))
    assert metrics.qantim_fit_dc(y, y) == 0.0
    assert metrics.fit_percent(y, y) == pytest.approx(100.0)
    assert metrics.qantim_fit(y, np.zeros_like(y)) == pytest.approx(100.0)
    assert metrics.rrse(y, np.full_like(y, y.mean())) == pytest.approx(1.0)
    assert metrics.fit_percent(y, np.full_like(y, y.mean())) == pytest.approx(0.0)


def test_rms_nrmse_rmse_by_hand():
    y = np.array([1.0, -1.0, 1.0, -1.0])
    yhat = np.array([0.0, -1.0, 1.0, -1.0])
    assert metrics.rmse(y, yhat) == pytest.approx(0.5)
    assert metrics.nrmse(y, yhat) == pytest.approx(0.5)  # std(y) = 1
    assert metrics.nrmse(y, yhat, norm="range") == pytest.approx(0.25)
    # means: y 0, yhat -0.25 -> e0 = [0.75, -0.25, -0.25, -0.25]: rms = sqrt(0.75)/2
    assert metrics.rms_error_percent(y, yhat) == pytest.approx(100 * np.sqrt(0.75) / 2)


def test_single_channel_as_vector_or_column():
    y = np.arange(10.0)
    assert metrics.qantim_fit_dc(y, y[:, None] * 0.9).shape == (1,)


def test_metric_bad_input():
    with pytest.raises(IdentificationError, match="same shape"):
        metrics.qantim_fit(np.ones(5), np.ones(6))
    with pytest.raises(IdentificationError, match="constant"):
        metrics.qantim_fit_dc(np.ones(5), np.arange(5.0))
    with pytest.raises(IdentificationError, match="NaN"):
        metrics.rmse(np.array([1.0, np.nan]), np.ones(2))
    with pytest.raises(IdentificationError, match="norm"):
        metrics.nrmse(np.arange(3.0), np.arange(3.0), norm="max")
