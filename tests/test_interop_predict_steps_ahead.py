"""SysIdentPy's ``predict(steps_ahead=None | 1 | k)`` and nonlinear_benchmarks' initialisation
windows ``simulate(u, y0=y[:50])`` (issue 15, deliverable 7).

Truth: a known second-order quadratic NARX written out as a recursion in the test (the fitted
model recovers its coefficients from noise-free data), SysIdentPy's own k-step predictor on
the same system (when installed), and the definitions (free run = ``simulate`` from the
measured start; a k-step window = a free run from the measured outputs before it).
"""

from __future__ import annotations

import numpy as np
import pytest

from identification import (
    Arx,
    ErrorSignalModel,
    IdentificationError,
    Narx,
    SimulationDivergedError,
    SplitSpectraModel,
    band_limited_noise,
    random_narx,
)

# y(t) = 0.5 y(t-1) - 0.2 y(t-2) + u(t-1) + 0.3 u(t-2) + 0.1 y(t-1)^2 - 0.05 u(t-1) y(t-1)
# (input lags from 1, so that SysIdentPy's xlag=2 describes the same system)


def _step(y1, y2, u1, u2):
    return 0.5 * y1 - 0.2 * y2 + u1 + 0.3 * u2 + 0.1 * y1**2 - 0.05 * u1 * y1


def _system(N=1200, seed=0):
    rng = np.random.default_rng(seed)
    u = 0.5 * rng.standard_normal(N)
    y = np.zeros(N)
    for t in range(2, N):
        y[t] = _step(y[t - 1], y[t - 2], u[t - 1], u[t - 2])
    return u, y


def _k_step_written_out(u, y, k, p=2):
    """SysIdentPy's k-step prediction of the system above, loop by loop: the first p samples
    are measured; windows of k samples from p on, each a free run from the measured outputs
    just before it."""
    N = len(u)
    out = np.array(y, dtype=float)
    for i in range(p, N, k):
        z = list(y[i - p : i])  # measured state
        for t in range(i, min(i + k, N)):
            z.append(_step(z[-1], z[-2], u[t - 1], u[t - 2]))
            out[t] = z[-1]
    return out


@pytest.fixture(scope="module")
def known():
    """The fitted model of the written-out system and a *noisy* measured record of it (noise
    makes one-step, k-step and free run differ)."""
    u, y = _system()
    model = Narx(na=2, nb=2, nk=1, degree=2).fit(u, y)
    coef = dict(zip(model.term_names()[0], model.coef_[0], strict=True))
    assert coef["y1(t-1)"] == pytest.approx(0.5, abs=1e-10)
    assert coef["y1(t-1)*u1(t-1)"] == pytest.approx(-0.05, abs=1e-10)
    u2, y2 = _system(N=900, seed=5)
    y_meas = y2 + 0.02 * np.random.default_rng(6).standard_normal(y2.size)
    return model, u2, y_meas


@pytest.mark.parametrize("k", [2, 3, 7, 64, 500])
def test_k_step_prediction_equals_the_recursion_written_out(known, k):
    model, u, y = known
    pred = model.predict(u, y, steps_ahead=k)
    truth = _k_step_written_out(u, y, k)
    np.testing.assert_allclose(pred[:, 0], truth, rtol=0, atol=1e-9)
    np.testing.assert_array_equal(pred[:2, 0], y[:2])  # the first max_lag samples: measured


def test_one_step_is_the_default_and_the_recursion_written_out(known):
    model, u, y = known
    truth = _k_step_written_out(u, y, 1)
    np.testing.assert_allclose(model.predict(u, y)[:, 0], truth, rtol=0, atol=1e-9)
    np.testing.assert_array_equal(model.predict(u, y), model.predict(u, y, steps_ahead=1))


def test_free_run_equals_simulate_bit_for_bit(known, cubic_2x2):
    model, u, y = known
    np.testing.assert_array_equal(
        model.predict(u, y, steps_ahead=None), model.simulate(u, y0=y[: model.max_lag_])
    )
    truth, u2, y2 = cubic_2x2
    y2 = y2 + 1e-3 * np.random.default_rng(2).standard_normal(y2.shape)
    np.testing.assert_array_equal(
        truth.predict(u2, y2, steps_ahead=None), truth.simulate(u2, y0=y2[: truth.max_lag_])
    )
    # and a horizon past the record's end is that free run too
    np.testing.assert_array_equal(
        truth.predict(u2, y2, steps_ahead=len(u2)), truth.predict(u2, y2, steps_ahead=None)
    )


@pytest.mark.parametrize("k", [2, 5, 2048, 2999])
def test_each_window_is_a_free_run_from_the_measured_outputs(cubic_2x2, k):
    # MIMO cubic; k = 2048 and 2999 take the one-simulate-per-window path, 2 and 5 the
    # compiled windowed kernel: both must give the free run's numbers bit for bit
    truth, u, y = cubic_2x2
    y = y + 1e-3 * np.random.default_rng(3).standard_normal(y.shape)
    p = truth.max_lag_
    ref = y.copy()
    for i in range(p, len(u), k):
        stop = min(i + k, len(u))
        ref[i:stop] = truth.simulate(u[i - p : stop], y0=y[i - p : i])[p:]
    np.testing.assert_array_equal(truth.predict(u, y, steps_ahead=k), ref)


def test_k_step_divergence_names_the_sample():
    u, y = _system(N=400)
    model = Narx(na=2, nb=2, nk=1, degree=2).fit(u, y)
    y_bad = y.copy()
    y_bad[200:202] = 1e3  # a measured state far outside: the next window's free run blows up
    with pytest.raises(SimulationDivergedError) as info:
        model.predict(u, y_bad, steps_ahead=4)
    assert info.value.kind == "k-step prediction"
    assert 202 <= info.value.sample < 206


@pytest.mark.parametrize("bad", [0, -3, True, 2.5, "1"])
def test_steps_ahead_must_be_none_or_a_positive_int(known, bad):
    model, u, y = known
    with pytest.raises(IdentificationError, match="steps_ahead must be None"):
        model.predict(u, y, steps_ahead=bad)


def test_steps_ahead_is_keyword_only(known):
    model, u, y = known
    with pytest.raises(TypeError):
        model.predict(u, y, 5)


def test_same_numbers_as_sysidentpy_steps_ahead(known):
    """SysIdentPy's own predictor, fed the same system: FROLS recovers the six terms from the
    noise-free record, then both libraries predict the noisy record k steps ahead."""
    sysidentpy = pytest.importorskip("sysidentpy")
    from sysidentpy.basis_function import Polynomial
    from sysidentpy.model_structure_selection import FROLS
    from sysidentpy.parameter_estimation import LeastSquares

    del sysidentpy
    u, y = _system()
    theirs = FROLS(
        xlag=2, ylag=2, basis_function=Polynomial(degree=2), n_terms=6,
        estimator=LeastSquares(), order_selection=False,
    ).fit(X=u[:, None], y=y[:, None])
    model, u2, y2 = known
    for k in (None, 1, 4, 25):
        ours = model.predict(u2, y2, steps_ahead=k)
        ref = theirs.predict(X=u2[:, None], y=y2[:, None], steps_ahead=k)
        np.testing.assert_allclose(ours[:, 0], ref[: len(u2), 0], rtol=0, atol=1e-8)


# ---------------------------------------------------------------- initialisation windows
def test_a_50_sample_window_is_its_last_max_lag_samples(known):
    model, u, y = known
    p = model.max_lag_
    out = model.simulate(u, y0=y[:50])
    np.testing.assert_array_equal(out[:50, 0], y[:50])
    np.testing.assert_array_equal(out[50 - p :], model.simulate(u[50 - p :], y0=y[50 - p : 50]))
    # and the written-out recursion started at sample 50 from y[48], y[49]
    z = list(y[48:50])
    for t in range(50, len(u)):
        z.append(_step(z[-1], z[-2], u[t - 1], u[t - 2]))
    np.testing.assert_allclose(out[50:, 0], z[2:], rtol=0, atol=1e-9)


def test_a_long_window_on_a_mimo_model_and_the_error_model(cubic_2x2):
    truth, u, y = cubic_2x2
    p = truth.max_lag_
    out = truth.simulate(u, y0=y[:50])
    np.testing.assert_array_equal(out[:50], y[:50])
    np.testing.assert_array_equal(out[50 - p :], truth.simulate(u[50 - p :], y0=y[50 - p : 50]))
    esm = ErrorSignalModel(Arx(order=3), Narx(order=1, degree=2)).fit(u, y)
    P = esm.max_lag_
    out = esm.simulate(u, y0=y[:50])
    np.testing.assert_array_equal(out[:50], y[:50])
    np.testing.assert_array_equal(out[50 - P :], esm.simulate(u[50 - P :], y0=y[50 - P : 50]))


def test_windows_shorter_than_max_lag_or_longer_than_u_are_refused(known):
    model, u, y = known
    with pytest.raises(IdentificationError, match="y0 must have shape"):
        model.simulate(u, y0=y[:1])
    with pytest.raises(IdentificationError, match="fewer than the 60 initial outputs"):
        model.simulate(u[:50], y0=y[:60])


def test_divergence_after_a_long_window_counts_samples_from_the_record_start():
    u, y = _system(N=400)
    model = Narx(na=2, nb=2, nk=1, degree=2).fit(u, y)
    y0 = y[:50].copy()
    y0[-2:] = 1e3
    with pytest.raises(SimulationDivergedError) as info:
        model.simulate(u, y0=y0)
    assert 50 <= info.value.sample < 60


# ---------------------------------------------------------------- composite models
@pytest.fixture(scope="module")
def mimo_noisy():
    truth = random_narx(2, 2, 2, 2, seed=7)
    u = band_limited_noise(2500, 2, cutoff=0.3, seed=8)
    y = truth.simulate(u)
    return u, y + 1e-3 * np.random.default_rng(9).standard_normal(y.shape)


def test_error_model_steps_ahead(mimo_noisy):
    u, y = mimo_noisy
    m = ErrorSignalModel(Arx(order=2), Narx(order=1, degree=2)).fit(u, y)
    np.testing.assert_array_equal(
        m.predict(u, y, steps_ahead=None), m.simulate(u, y0=y[: m.max_lag_])
    )
    y_lin = m.linear.simulate(u)
    for k in (1, 6):
        expected = y_lin + m.nonlinear.predict(u, y - y_lin, steps_ahead=k)
        np.testing.assert_array_equal(m.predict(u, y, steps_ahead=k), expected)


def test_split_spectra_steps_ahead_band_by_band():
    truth = random_narx(2, 2, 2, 1, seed=3)  # linear: each band is an ARX of its own
    u = band_limited_noise(3000, 2, cutoff=0.8, seed=4)
    y = truth.simulate(u) + 1e-4 * np.random.default_rng(5).standard_normal((3000, 2))
    m = SplitSpectraModel(0.2, 1.0, Arx(order=2), Arx(order=2)).fit(u, y)
    u_lo, u_hi = m.split(u)
    y_lo, y_hi = m.split(y)
    lo, hi = m.low_, m.high_
    free = lo.simulate(u_lo, y0=y_lo[: lo.max_lag_]) + hi.simulate(u_hi, y0=y_hi[: hi.max_lag_])
    np.testing.assert_array_equal(m.predict(u, y, steps_ahead=None), free)
    k_step = lo.predict(u_lo, y_lo, steps_ahead=8) + hi.predict(u_hi, y_hi, steps_ahead=8)
    np.testing.assert_array_equal(m.predict(u, y, steps_ahead=8), k_step)
    one = lo.predict(u_lo, y_lo) + hi.predict(u_hi, y_hi)
    np.testing.assert_array_equal(m.predict(u, y), one)


def test_split_spectra_decimated_low_band_steps_in_low_rate_samples(mimo_noisy):
    u, y = mimo_noisy
    m = SplitSpectraModel(
        0.02, 1.0, Narx(order=2, degree=2, kind="input-polynomial"), Arx(order=2), decimate_low=4
    )
    m.fit(u, y)
    u_lo, u_hi = m.split(u)
    y_lo, y_hi = m.split(y)
    low = m.low_.predict(u_lo[::4], y_lo[::4], steps_ahead=3)  # ceil(10 / 4) low-rate steps
    expected = m._up(low, len(u)) + m.high_.predict(u_hi, y_hi, steps_ahead=10)
    np.testing.assert_array_equal(m.predict(u, y, steps_ahead=10), expected)
