"""ARX/NARX models against known generating systems: exact recovery, free run, persistence."""

from __future__ import annotations

import control
import numpy as np
import pytest
from scipy import signal

from identification import (
    Arx,
    ErrorSignalModel,
    Narx,
    SimulationDivergedError,
    band_limited_noise,
    metrics,
    random_narx,
    regression_matrix,
)
from identification.solvers import SOLVERS

STABLE = ["qr", "householder", "mgs", "cgs", "svd"]


def _max_rel_coef_error(fitted, truth):
    return max(
        np.max(np.abs(a - b)) / np.max(np.abs(b))
        for a, b in zip(fitted.coef_, truth.coef_, strict=True)
    )


@pytest.mark.parametrize("solver", STABLE)
def test_noise_free_cubic_mimo_narx_is_recovered_exactly(cubic_2x2, solver):
    truth, u, y = cubic_2x2
    assert truth.n_terms_.tolist() == [285, 285]  # 2x2, order 2, cubic: C(10 + 3, 3) - 1
    fitted = Narx(order=2, degree=3, solver=solver).fit(u, y)
    assert _max_rel_coef_error(fitted, truth) < 1e-8
    np.testing.assert_allclose(fitted.simulate(u), y, rtol=0, atol=1e-8 * np.abs(y).max())


def test_normal_equations_agree_on_a_well_conditioned_case():
    truth = random_narx(2, 2, 2, 1, seed=3)  # linear: a well-conditioned regression
    u = band_limited_noise(3000, 2, cutoff=0.8, seed=4)
    y = truth.simulate(u)
    fitted = Narx(order=2, degree=1, solver="normal").fit(u, y)
    assert _max_rel_coef_error(fitted, truth) < 1e-6
    np.testing.assert_allclose(fitted.simulate(u), y, rtol=0, atol=1e-6 * np.abs(y).max())


def test_one_step_prediction_is_exact_on_noise_free_data(cubic_2x2):
    truth, u, y = cubic_2x2
    pred = truth.predict(u, y)
    np.testing.assert_allclose(pred, y, rtol=0, atol=1e-10 * np.abs(y).max())


def test_free_run_with_initial_conditions_matches_recursion_written_out():
    # y(t) = 0.5 y(t-1) - 0.2 y(t-2) + u(t) + 0.3 u(t-1) + 0.1 y(t-1)^2 - 0.05 u(t) y(t-1)
    rng = np.random.default_rng(0)
    N = 500
    u = 0.5 * rng.standard_normal(N)
    y = np.zeros(N)
    y[:2] = [0.3, -0.1]
    for t in range(2, N):
        y[t] = (
            0.5 * y[t - 1]
            - 0.2 * y[t - 2]
            + u[t]
            + 0.3 * u[t - 1]
            + 0.1 * y[t - 1] ** 2
            - 0.05 * u[t] * y[t - 1]
        )
    m = Narx(na=2, nb=2, nk=0, degree=2).fit(u, y)
    np.testing.assert_allclose(m.simulate(u, y0=y[:2]), y[:, None], atol=1e-10)
    names = m.term_names()[0]
    coef = dict(zip(names, m.coef_[0], strict=True))
    assert coef["y1(t-1)"] == pytest.approx(0.5, abs=1e-10)
    assert coef["y1(t-1)*y1(t-1)"] == pytest.approx(0.1, abs=1e-10)
    assert coef["y1(t-1)*u1(t)"] == pytest.approx(-0.05, abs=1e-10)
    assert coef["y1(t-2)*u1(t-1)"] == pytest.approx(0.0, abs=1e-10)


@pytest.mark.parametrize("ny,nu", [(3, 1), (1, 3), (3, 2)])
def test_non_square_systems(ny, nu):
    truth = random_narx(ny, nu, 2, 2, seed=ny * 10 + nu)
    u = band_limited_noise(2500, nu, cutoff=0.3, seed=5)
    y = truth.simulate(u)
    fitted = Narx(order=2, degree=2).fit(u, y)
    assert fitted.simulate(u).shape == (2500, ny)
    assert _max_rel_coef_error(fitted, truth) < 1e-8


def test_per_channel_orders_and_degrees():
    truth = random_narx(2, 1, [1, 3], [2, 1], seed=21)
    assert truth.n_terms_.tolist() == [
        # channel 1: order 1, quadratic: R = 2*1 + 1*2 = 4 -> C(6, 2) - 1 = 14
        # channel 2: order 3, linear: R = 2*3 + 1*4
        14,
        2 * 3 + 1 * 4,
    ]
    u = band_limited_noise(2000, 1, cutoff=0.3, seed=22)
    y = truth.simulate(u)
    fitted = Narx(order=[1, 3], degree=[2, 1]).fit(u, y)
    assert _max_rel_coef_error(fitted, truth) < 1e-8


def test_cross_coupled_outputs_feed_each_other():
    # y1 depends on y2's past and vice versa: a free run must use the simulated outputs
    rng = np.random.default_rng(3)
    N = 800
    u = rng.standard_normal((N, 1))
    y = np.zeros((N, 2))
    for t in range(1, N):
        y[t, 0] = 0.4 * y[t - 1, 0] + 0.3 * y[t - 1, 1] + u[t, 0]
        y[t, 1] = (
            -0.2 * y[t - 1, 0]
            + 0.5 * y[t - 1, 1]
            + 0.1 * y[t - 1, 0] * y[t - 1, 1]
            + 0.5 * u[t - 1, 0]
        )
    m = Narx(order=1, degree=2).fit(u, y)
    np.testing.assert_allclose(m.simulate(u, y0=y[:1]), y, atol=1e-10)


def test_save_load_round_trip_is_exact(tmp_path, cubic_2x2):
    _, u, y = cubic_2x2
    m = Narx(order=2, degree=3).fit(u, y, input_names=["force", "disp"], output_names=["a", "b"])
    path = m.save(tmp_path / "model")
    assert path.suffix == ".npz"
    loaded = Narx.load(path)
    assert all(np.array_equal(a, b) for a, b in zip(m.coef_, loaded.coef_, strict=True))
    assert loaded.term_names() == m.term_names()
    assert "a(t-1)*force(t)" in loaded.term_names()[0]
    assert np.array_equal(m.simulate(u[:500]), loaded.simulate(u[:500]))


def test_arx_save_load_keeps_class(tmp_path):
    u = band_limited_noise(500, 2, seed=1)
    y = band_limited_noise(500, 1, seed=2)
    m = Arx(order=3).fit(u, y)
    loaded = Narx.load(m.save(tmp_path / "arx.npz"))
    assert type(loaded) is Arx
    assert np.array_equal(loaded.simulate(u), m.simulate(u))


def test_term_names_are_human_readable():
    u = band_limited_noise(400, 2, seed=1)
    y = band_limited_noise(400, 1, seed=2)
    names = Narx(order=1, degree=2).fit(u, y).term_names()[0]
    assert "y1(t-1)*u2(t)" in names
    assert "u1(t-1)*u1(t-1)" in names


def test_arx_state_space_equals_simulation_3x2():
    rng = np.random.default_rng(8)
    truth = random_narx(3, 2, 3, 1, seed=8)
    u = band_limited_noise(1500, 2, cutoff=0.4, seed=9)
    y = truth.simulate(u) + 1e-3 * rng.standard_normal((1500, 3))
    m = Arx(order=3).fit(u, y)
    sys = m.to_statespace(dt=0.01)
    assert isinstance(sys, control.StateSpace)
    assert (sys.ninputs, sys.noutputs) == (2, 3)
    t = np.arange(1500) * 0.01
    resp = control.forced_response(sys, T=t, U=u.T)
    np.testing.assert_allclose(resp.outputs.T, m.simulate(u), rtol=0, atol=1e-9)


def test_statespace_with_selected_terms_and_different_orders():
    u = band_limited_noise(1200, 2, seed=3)
    truth = random_narx(2, 2, [2, 4], 1, seed=4)
    y = truth.simulate(u) + 1e-3 * np.random.default_rng(5).standard_normal((1200, 2))
    m = Arx(order=[2, 4], n_terms=10).fit(u, y)  # forward selection: terms in selection order
    assert m.n_terms_.tolist() == [10, 10]
    resp = control.forced_response(m.to_statespace(), T=np.arange(1200), U=u.T)
    np.testing.assert_allclose(resp.outputs.T, m.simulate(u), atol=1e-9)


def test_divergence_raises_naming_channel_and_sample():
    # an unstable AR(1), pole 1.5: y(t) = 1.5 y(t-1) + u(t)
    rng = np.random.default_rng(0)
    u = rng.standard_normal(200)
    y = signal.lfilter([1.0], [1.0, -1.5], u)
    m = Arx(na=1, nb=1).fit(u[:40], y[:40])
    bound = 1e6
    with pytest.raises(SimulationDivergedError) as err:
        m.simulate(u, bound=bound)
    first = int(np.argmax(np.abs(y) > bound))  # independent: the true recursion's first exceedance
    assert err.value.channel == 0
    assert err.value.channel_name == "y1"
    assert err.value.sample == first
    assert "sample" in str(err.value) and "'y1'" in str(err.value)


def test_divergence_to_non_finite_is_caught_even_without_bound():
    u = np.random.default_rng(1).standard_normal(30)
    m = Arx(na=1, nb=1).fit(u, signal.lfilter([1.0], [1.0, -2.0], u))  # pole at 2
    with pytest.raises(SimulationDivergedError, match="not finite") as err:
        m.simulate(np.ones(5000), bound=np.inf)
    assert 1000 < err.value.sample < 1100  # 2**t overflows float64 near t = 1024


def test_forward_regression_finds_the_true_sparse_structure():
    rng = np.random.default_rng(5)
    N = 3000
    x = rng.uniform(-1, 1, N)
    y = np.zeros(N)
    for t in range(2, N):
        y[t] = 0.2 * y[t - 1] + 0.1 * y[t - 1] * x[t - 1] + 0.9 * x[t - 2]
    m = Narx(na=2, nb=2, nk=1, degree=2, constant=True, n_terms=3).fit(x, y)
    names = m.term_names()[0]
    assert set(names) == {"y1(t-1)", "y1(t-1)*u1(t-1)", "u1(t-2)"}
    coef = dict(zip(names, m.coef_[0], strict=True))
    assert coef["u1(t-2)"] == pytest.approx(0.9, abs=1e-10)
    assert coef["y1(t-1)*u1(t-1)"] == pytest.approx(0.1, abs=1e-10)
    assert m.err_[0].sum() == pytest.approx(1.0, abs=1e-10)
    # ERR tolerance stops early with the same terms
    m2 = Narx(na=2, nb=2, nk=1, degree=2, constant=True, err_tol=1e-8).fit(x, y)
    assert set(m2.term_names()[0]) == set(names)


def test_purely_quadratic_model_recovers_its_generator():
    rng = np.random.default_rng(6)
    N = 1500
    u = rng.uniform(-1, 1, N)
    y = np.zeros(N)
    for t in range(1, N):
        y[t] = (
            0.1
            + 0.6 * y[t - 1]
            + 0.5 * u[t]
            - 0.2 * u[t - 1]
            + 0.3 * u[t - 1] ** 2
            - 0.1 * y[t - 1] ** 2
        )
    m = Narx(order=1, degree=2, kind="pure", constant=True).fit(u, y)
    coef = dict(zip(m.term_names()[0], m.coef_[0], strict=True))
    assert coef["1"] == pytest.approx(0.1, abs=1e-10)
    assert coef["u1(t-1)*u1(t-1)"] == pytest.approx(0.3, abs=1e-10)
    assert coef["y1(t-1)*y1(t-1)"] == pytest.approx(-0.1, abs=1e-10)


def test_quasi_static_model_recovers_a_static_nonlinearity():
    rng = np.random.default_rng(7)
    N = 1500
    u = rng.uniform(-1, 1, (N, 2))
    y = np.zeros(N)
    for t in range(2, N):
        y[t] = (
            0.5 * y[t - 1]
            - 0.1 * y[t - 2]
            + u[t, 0]
            + 0.2 * u[t - 1, 1]
            + 0.4 * u[t, 0] ** 2
            - 0.3 * u[t, 1] ** 2
        )
    m = Narx(order=2, degree=2, kind="quasi-static").fit(u, y)
    coef = dict(zip(m.term_names()[0], m.coef_[0], strict=True))
    assert coef["u1(t)*u1(t)"] == pytest.approx(0.4, abs=1e-10)
    assert coef["u2(t)*u2(t)"] == pytest.approx(-0.3, abs=1e-10)
    np.testing.assert_allclose(m.simulate(u, y0=y[:2, None]), y[:, None], atol=1e-9)


def test_error_signal_model_improves_on_its_linear_part():
    # Hammerstein system (static quadratic, then linear dynamics): a linear ARX leaves a
    # non-linear error that the NARX error model captures. The reference text reports
    # ARX(3) 67 % -> ARX(3) + NARX(2, quadratic) error model 35 % on the elastomeric damper.
    u = band_limited_noise(6000, 1, cutoff=0.3, seed=9)[:, 0]
    y = signal.lfilter([0.2, 0.1], [1.0, -1.2, 0.5], u + 0.5 * u**2)
    lin = Arx(order=2).fit(u[:4000], y[:4000])
    esm = ErrorSignalModel(Arx(order=2), Narx(order=2, degree=2)).fit(u[:4000], y[:4000])
    e_lin = metrics.qantim_fit_dc(y[4000:], lin.simulate(u[4000:])[:, 0])
    e_esm = metrics.qantim_fit_dc(y[4000:], esm.simulate(u[4000:])[:, 0])
    assert e_esm < 0.6 * e_lin


def test_error_signal_model_is_linear_plus_narx_of_the_linear_error():
    u = band_limited_noise(3000, 1, cutoff=0.3, seed=1)
    y = signal.lfilter([0.3], [1.0, -0.6], u[:, 0] + 0.2 * u[:, 0] ** 3)
    esm = ErrorSignalModel(Arx(order=2), Narx(order=1, degree=3)).fit(u, y)
    lin = Arx(order=2).fit(u, y)
    nl = Narx(order=1, degree=3).fit(u, y[:, None] - lin.simulate(u))
    np.testing.assert_allclose(esm.simulate(u), lin.simulate(u) + nl.simulate(u), atol=1e-12)


def test_random_narx_is_deterministic_and_bounded():
    a = random_narx(2, 1, 3, 2, seed=42)
    b = random_narx(2, 1, 3, 2, seed=42)
    assert all(np.array_equal(x, y) for x, y in zip(a.coef_, b.coef_, strict=True))
    for seed in range(5):
        out = a.simulate(band_limited_noise(20_000, 1, cutoff=0.3, seed=seed))
        assert np.all(np.isfinite(out))
        assert np.abs(out).max() < a.bound_.max()


def test_all_solvers_registered():
    assert set(SOLVERS) == {"qr", "householder", "mgs", "cgs", "svd", "normal"}


def test_shared_factorisation_equals_a_separate_least_squares_solve(cubic_2x2):
    _, u, y = cubic_2x2
    both = Narx(order=2, degree=2).fit(u, y)
    # channel 0 alone, with both outputs as regressors, is the same least-squares problem
    X = regression_matrix(u, y, both.channels_[0], both.max_lag_)
    ref, *_ = np.linalg.lstsq(X, y[both.max_lag_ :, 0], rcond=None)
    np.testing.assert_allclose(both.coef_[0], ref, rtol=1e-7, atol=1e-9)
