"""Error-signal model (§5.5.4) against known generating models: the static quadratic error is
recovered term by term, MIMO and non-square; exact save/load; use as an inverse model and as a
reconstruction method."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import signal

import vrig
from identification import (
    Arx,
    ErrorSignalModel,
    InverseModel,
    ModelFileError,
    Narx,
    band_limited_noise,
)

# FIR linear part (3 outputs x 2 inputs x lags 0..2) plus a static quadratic (u1^2, u1 u2, u2^2)
B = np.array(
    [
        [[0.5, 0.2, -0.1], [0.0, 0.3, 0.1]],
        [[0.1, -0.4, 0.2], [0.6, 0.0, 0.0]],
        [[-0.3, 0.0, 0.2], [0.2, 0.2, 0.2]],
    ]
)
Q = np.array([[0.4, 0.0, -0.2], [0.0, 0.3, 0.0], [-0.1, 0.2, 0.5]])


def _fir_plus_quadratic(u):
    lin = np.column_stack(
        [sum(signal.lfilter(B[k, j], [1.0], u[:, j]) for j in range(2)) for k in range(3)]
    )
    quad = np.column_stack([u[:, 0] ** 2, u[:, 0] * u[:, 1], u[:, 1] ** 2])
    return lin + quad @ Q.T


def _coef(model, k):
    return dict(zip(model.term_names()[k], model.coef_[k], strict=True))


@pytest.fixture(scope="module")
def mimo():
    u = band_limited_noise(6000, 2, cutoff=0.4, seed=11)
    return u, _fir_plus_quadratic(u)


def _esm():
    # FIR linear part (an ARX with na = 0) and a quadratic error NARX without error feedback:
    # the truth's error (B - B_hat) u + static quadratic needs no more, and past errors would
    # be (up to the tiny B - B_hat) copies of the quadratic terms: an ill-posed regression
    return ErrorSignalModel(Arx(na=0, nb=3), Narx(na=0, nb=3, degree=2))


def test_mimo_non_square_error_model_recovers_the_static_quadratic(mimo):
    # e = y - y_lin = (B - B_hat) u + Q [u1^2, u1 u2, u2^2]: the error model must hold the
    # static quadratic exactly, no other quadratic term, and its linear
    # terms must complete the linear model's estimate to the true FIR B
    u, y = mimo
    m = _esm().fit(u, y)
    assert (m.n_inputs_, m.n_outputs_) == (2, 3)
    for k in range(3):
        e = _coef(m.nonlinear, k)
        lin = _coef(m.linear, k)
        quad = {"u1(t)*u1(t)": Q[k, 0], "u1(t)*u2(t)": Q[k, 1], "u2(t)*u2(t)": Q[k, 2]}
        for name, value in e.items():
            if name in quad:
                assert value == pytest.approx(quad[name], abs=1e-8), (k, name)
            elif "*" in name:
                assert value == pytest.approx(0.0, abs=1e-8), (k, name)
        for j in range(2):
            for lag in range(3):
                name = f"u{j + 1}(t)" if lag == 0 else f"u{j + 1}(t-{lag})"
                assert lin[name] + e[name] == pytest.approx(B[k, j, lag], abs=1e-8)
    u_new = band_limited_noise(3000, 2, cutoff=0.4, seed=12)
    y_new = _fir_plus_quadratic(u_new)
    assert np.abs(m.simulate(u_new) - y_new).max() < 1e-8 * np.abs(y_new).max()


def test_siso_arx_plus_static_quadratic_error_has_the_predicted_coefficients():
    # y = (b/a) u + c u^2. With the fitted linear ARX(2) b_hat/a_hat, the error obeys
    # a a_hat e = (b a_hat - b_hat a) u + c a a_hat u^2: the error model's u(t-i)^2 coefficient
    # is c (a * a_hat)_i and its e(t-i) coefficient -(a * a_hat)_i (* : convolution)
    a, b, c = np.array([1.0, -1.1, 0.4]), np.array([0.3, 0.2, 0.1]), 0.25
    u = band_limited_noise(8000, 1, cutoff=0.3, seed=4)[:, 0]
    y = signal.lfilter(b, a, u) + c * u**2
    m = ErrorSignalModel(Arx(order=2), Narx(order=4, degree=2, kind="input-polynomial"))
    m.fit(u, y)
    lin = _coef(m.linear, 0)
    a_hat = np.array([1.0, -lin["y1(t-1)"], -lin["y1(t-2)"]])
    aa = np.convolve(a, a_hat)  # lags 0..4
    e = _coef(m.nonlinear, 0)
    for i in range(5):
        name = "u1(t)*u1(t)" if i == 0 else f"u1(t-{i})*u1(t-{i})"
        assert e[name] == pytest.approx(c * aa[i], abs=1e-8), name
        if i:
            assert e[f"y1(t-{i})"] == pytest.approx(-aa[i], abs=1e-8)
    assert np.abs(m.simulate(u)[:, 0] - y).max() < 1e-8 * np.abs(y).max()


def test_save_load_round_trip_is_exact(mimo, tmp_path):
    u, y = mimo
    y = y + 0.01 * np.random.default_rng(2).standard_normal(y.shape)
    m = ErrorSignalModel(Arx(order=3), Narx(order=2, degree=2)).fit(u, y)
    path = m.save(tmp_path / "esm")
    back = ErrorSignalModel.load(path)
    assert path.suffix == ".npz" and back.max_lag_ == m.max_lag_
    assert back.output_names_ == m.output_names_
    assert np.array_equal(back.n_terms_, m.n_terms_)
    u_new = band_limited_noise(2000, 2, cutoff=0.4, seed=3)
    assert np.array_equal(back.simulate(u_new), m.simulate(u_new))
    assert np.array_equal(back.predict(u, y), m.predict(u, y))
    with pytest.raises(ModelFileError, match="ErrorSignalModel"):
        Narx.load(path)
    with pytest.raises(ModelFileError, match="expected ErrorSignalModel"):
        ErrorSignalModel.load(m.linear.save(tmp_path / "linear.npz"))


def test_simulate_with_initial_outputs(mimo):
    u, y = mimo
    m = _esm().fit(u, y)
    y0 = y[: m.max_lag_]
    out = m.simulate(u, y0=y0)
    np.testing.assert_array_equal(out[: m.max_lag_], y0)
    assert np.abs(out - y).max() < 1e-8 * np.abs(y).max()  # the true start: still exact
    with pytest.raises(ValueError, match="y0 must have shape"):
        m.simulate(u, y0=y0[:1])


def test_error_signal_model_as_an_inverse_model():
    # the "rig" is known through its inverse: drive = FIR(response) + static quadratic of the
    # response, so the inverse error-signal model (response in, drive out) is exact
    r = band_limited_noise(6000, 2, cutoff=0.4, seed=21)
    d = _fir_plus_quadratic(r)  # 3 drives from 2 responses: non-square
    inv = InverseModel(_esm(), lead=0).fit(d, r, drive_names=["d1", "d2", "d3"])
    assert isinstance(inv.model, ErrorSignalModel) and inv.lead_ == 0
    assert inv.contraction_ == 1.0 and inv.model.stability_["input"] is True
    assert inv.model.output_names_ == ("d1", "d2", "d3")
    r_new = band_limited_noise(3000, 2, cutoff=0.4, seed=22)
    d_new = _fir_plus_quadratic(r_new)
    assert np.abs(inv.simulate(r_new) - d_new).max() < 1e-8 * np.abs(d_new).max()


def test_inverse_error_signal_reconstruction_method():
    from benchmarks.runner.registry import get_method
    from vrig.reconstruction import InverseErrorSignal, make_method
    from vrig.timehistory import TimeHistory

    # the inverse of a rig whose drive is an ARX(2) of the response plus c r^2: with the
    # linear ARX(2) fitted, the drive error needs an error NARX(4) (see the SISO test above),
    # so InverseErrorSignal(2, 4) is exact after its run-in transient (the drive starts from
    # a mirrored history, the truth from rest; the difference decays with poles of radius
    # sqrt(0.4) = 0.63 and sqrt of the fitted a_hat's, gone to round-off within 200 samples)
    a, b, c = np.array([1.0, -1.1, 0.4]), np.array([0.3, 0.2, 0.1]), 0.25
    r = band_limited_noise(8000, 1, cutoff=0.3, seed=31)[:, 0]
    d = signal.lfilter(b, a, r) + c * r**2
    method = InverseErrorSignal(2, 4, 2, lead=0, max_radius=None)
    method.identify(TimeHistory(d, 200.0), TimeHistory(r, 200.0))
    r_new = band_limited_noise(3000, 1, cutoff=0.3, seed=32)[:, 0]
    d_new = signal.lfilter(b, a, r_new) + c * r_new**2
    drive = method.drive(TimeHistory(r_new, 200.0))[:, 0]
    assert np.abs(drive - d_new)[200:].max() < 1e-8 * np.abs(d_new).max()
    assert "error-signal" in method.describe()
    assert isinstance(make_method("error-signal"), InverseErrorSignal)
    plugin = get_method("error-signal")
    assert plugin.linear is False
    rig = vrig.load_rig("shock-absorber", fidelity="fast")  # factory(rig, band): the rig's method
    assert isinstance(plugin.make(rig, (1.0, 10.0)), InverseErrorSignal)
