"""Simulation-accurate NARX: output-error refinement, its Jacobian, the stability contract and
free-run term selection, against known generating systems."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from scipy import signal

from identification import (
    IdentificationError,
    InverseModel,
    Narx,
    StabilityWarning,
    UnstableModelError,
    band_limited_noise,
    information_criteria,
    metrics,
    random_narx,
    regression_matrix,
)
from identification.free_run_selection import criterion_path
from identification.output_error import FlatModel, refine, simulation_error
from identification.selection import forward_regression

# y(t) = 1.5 y(t-1) - 0.7 y(t-2) + 0.5 u(t-1) + 0.3 u(t-2) + 0.1 u(t-1)^2 - 0.05 y(t-1) u(t-1)
TRUE_TERMS = {
    "y1(t-1)": 1.5,
    "y1(t-2)": -0.7,
    "u1(t-1)": 0.5,
    "u1(t-2)": 0.3,
    "u1(t-1)*u1(t-1)": 0.1,
    "y1(t-1)*u1(t-1)": -0.05,
}


def _true_system(u: np.ndarray) -> np.ndarray:
    """The generating NARX, written out sample by sample (independent of the package)."""
    y = np.zeros(u.size)
    for t in range(2, u.size):
        y[t] = (
            1.5 * y[t - 1]
            - 0.7 * y[t - 2]
            + 0.5 * u[t - 1]
            + 0.3 * u[t - 2]
            + 0.1 * u[t - 1] ** 2
            - 0.05 * y[t - 1] * u[t - 1]
        )
    return y


@pytest.fixture(scope="module")
def output_noise_data():
    """4,000 samples of the true system with 5 % (of the output RMS) noise added after the
    recursion: output error, not equation error."""
    u = band_limited_noise(4000, 1, cutoff=0.5, seed=1)[:, 0]
    clean = _true_system(u)
    rng = np.random.default_rng(0)
    y = clean + 0.05 * np.sqrt(np.mean(clean**2)) * rng.standard_normal(u.size)
    return u, y


def _coef(model, name):
    return dict(zip(model.term_names()[0], model.coef_[0], strict=True))[name]


def test_least_squares_is_biased_and_simulation_focus_recovers_the_generating_model(
    output_noise_data,
):
    u, y = output_noise_data
    structure = dict(na=2, nb=2, nk=1, degree=2)
    ls = Narx(**structure).fit(u, y)
    oe = Narx(**structure, focus="simulation").fit(u, y)
    # least squares: its own standard errors sigma^2 (X^T X)^-1 from the regression matrix
    X = regression_matrix(u[:, None], y[:, None], ls.channels_[0], ls.max_lag_)
    resid = y[ls.max_lag_ :] - X @ ls.coef_[0]
    cov = resid.var() * np.linalg.inv(X.T @ X)
    ls_std = dict(zip(ls.term_names()[0], np.sqrt(np.diag(cov)), strict=True))
    ls_dev = {n: abs(_coef(ls, n) - v) / ls_std[n] for n, v in TRUE_TERMS.items()}
    assert max(ls_dev.values()) > 10, ls_dev  # visibly biased: many standard errors off
    # simulation focus: every coefficient (true ones and the spurious ones, truth 0) within
    # three of its own standard errors of the generating value
    std = dict(zip(oe.term_names()[0], oe.coef_std_[0], strict=True))
    for name, value in zip(oe.term_names()[0], oe.coef_[0], strict=True):
        truth = TRUE_TERMS.get(name, 0.0)
        assert abs(value - truth) <= 3 * std[name], (name, value, truth, std[name])
    # free run on fresh data against the noise-free truth: at least 2x lower NRMSE
    u_new = band_limited_noise(4000, 1, cutoff=0.5, seed=7)[:, 0]
    truth = _true_system(u_new)
    e_ls = metrics.nrmse(truth, ls.simulate(u_new)[:, 0])
    e_oe = metrics.nrmse(truth, oe.simulate(u_new)[:, 0])
    assert e_oe * 2 <= e_ls, (e_oe, e_ls)
    assert oe.refinement_.cost < oe.refinement_.initial_cost


@pytest.mark.parametrize("horizon", [None, 37])
def test_sensitivity_jacobian_equals_finite_differences_on_a_mimo_cubic_model(horizon):
    truth = random_narx(2, 2, 2, 3, seed=11)  # cross-coupled 2x2 cubic, 285 terms per channel
    u = band_limited_noise(300, 2, cutoff=0.3, seed=12)
    y = truth.simulate(u) + 0.01 * np.random.default_rng(3).standard_normal((300, 2))
    flat = FlatModel.from_channels(truth.channels_, 2, 2)
    rng = np.random.default_rng(5)
    theta = np.concatenate(truth.coef_) * (1 + 1e-5 * rng.standard_normal(flat.n_params))
    assert simulation_error(flat, theta, u, y)[0] is not None
    w = np.array([1.0, 2.0])
    _e, J, _ = simulation_error(flat, theta, u, y, horizon=horizon, weight=w, jacobian=True)
    cols = rng.choice(flat.n_params, 16, replace=False)

    def central(j, h):
        tp, tm = theta.copy(), theta.copy()
        tp[j] += h
        tm[j] -= h
        ep = simulation_error(flat, tp, u, y, horizon=horizon, weight=w)[0]
        em = simulation_error(flat, tm, u, y, horizon=horizon, weight=w)[0]
        return -(ep - em) / (2 * h)  # e = w (y - yhat): d yhat / d theta = -d e / d theta

    for j in cols:
        h = 1e-5 * max(abs(theta[j]), 1.0)
        fd = (4 * central(j, h / 2) - central(j, h)) / 3  # Richardson: O(h^4)
        rel = np.linalg.norm(fd - J[:, j]) / np.linalg.norm(J[:, j])
        assert rel < 1e-6, (j, rel)


def _saturating_wiener(seed=4):
    """A Wiener system (linear filter, then tanh plus a linear part) with 5 % output noise:
    its least-squares cubic NARX diverges in free run on its own input (seed 4)."""
    u = band_limited_noise(3000, 1, cutoff=0.2, seed=seed)[:, 0]
    b, a = signal.butter(2, 0.1)
    x = 2 * signal.lfilter(b, a, u)
    y = np.tanh(x) + 0.3 * x
    y += 0.05 * y.std() * np.random.default_rng(seed).standard_normal(y.size)
    return u, y


def test_a_model_that_diverges_on_its_identification_input_is_never_returned():
    u, y = _saturating_wiener()
    with pytest.raises(UnstableModelError, match="focus='simulation'") as info:
        Narx(order=3, degree=3).fit(u, y)
    assert info.value.cause.sample < u.size  # the divergence it found on the record itself
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", StabilityWarning)
        model = Narx(order=3, degree=3, focus="simulation").fit(u, y)
    for y0 in (y[: model.max_lag_], None):  # bounded on its identification input
        sim = model.simulate(u, y0=y0)
        assert metrics.nrmse(y, sim[:, 0]) < 0.2
    assert model.stability_["input"] is True


def test_horizon_continuation_refines_a_diverging_least_squares_start():
    u, y = _saturating_wiener()
    ls = Narx(order=3, degree=3)
    ls.n_inputs_, ls.n_outputs_ = 1, 1
    ch = ls._structure(1, 1, np.ones(2))
    ls.max_lag_ = ch[0].max_lag
    channels, coefs, _ = ls._least_squares_fixed(u[:, None], y[:, None], ch)
    flat = FlatModel.from_channels(channels, 1, 1)
    theta0 = np.concatenate(coefs)
    assert simulation_error(flat, theta0, u[:, None], y[:, None])[0] is None  # LS diverges
    res = refine(flat, theta0, u[:, None], y[:, None], max_iter=10)
    assert res.initial_cost == np.inf and len(res.horizons) > 2
    assert res.horizons[-1] == u.size and np.isfinite(res.cost)
    e = simulation_error(flat, res.theta, u[:, None], y[:, None])[0]  # whole record, bounded
    assert e is not None and np.sqrt(np.mean(e**2)) < 0.2  # weighted: a fraction of std(y)


def test_the_remedy_drops_output_feedback_when_refinement_cannot_save_it():
    # white-noise 'output' unrelated to the input: a cubic NARX of it with products of past
    # outputs is wildly unstable and carries no information; the contract must still hold
    rng = np.random.default_rng(2)
    u = rng.standard_normal(1500)
    y = np.cumsum(rng.standard_normal(1500)) * 0.01 + rng.standard_normal(1500)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", StabilityWarning)
        try:
            model = Narx(order=2, degree=3, focus="simulation").fit(u, y)
        except UnstableModelError as exc:  # an honest refusal is allowed by the contract
            assert "Lower the order" in str(exc)
            return
    model.simulate(u, y0=y[: model.max_lag_])  # whatever it returned runs bounded


def test_stability_margin_warns_when_the_free_run_diverges_at_1_5x_the_input():
    # y(t) = 0.5 y(t-1) + 0.25 y(t-1)^2 + u(t-1): the fixed point y* = 2 - 2 sqrt(1 - u/...)
    # escapes once 0.5 y + 0.25 y^2 + u > y has no stable solution (u > 0.25 for constant u)
    u = 0.09 + 0.04 * band_limited_noise(2000, 1, cutoff=0.1, seed=3)[:, 0]
    y = np.zeros(u.size)
    for t in range(1, u.size):
        y[t] = 0.5 * y[t - 1] + 0.25 * y[t - 1] ** 2 + u[t - 1]
    big = 1.5 * u
    yb = np.zeros(u.size)
    with np.errstate(over="ignore", invalid="ignore"):
        for t in range(1, u.size):
            yb[t] = 0.5 * yb[t - 1] + 0.25 * yb[t - 1] ** 2 + big[t - 1]
    assert not np.all(np.isfinite(yb)) or np.abs(yb).max() > 1e3  # the truth escapes at 1.5x
    with pytest.warns(StabilityWarning, match="1.5x"):
        model = Narx(na=1, nb=1, nk=1, degree=2).fit(u, y)
    assert model.stability_ == {"input": True, "margin": False, "remedy": None}


def test_simulation_focus_inverse_model_recovers_the_drive_of_a_saturating_system():
    # drive band (0.08 of Nyquist) well inside the system's (0.3): the inverse is well posed
    u = band_limited_noise(3000, 1, cutoff=0.08, seed=9)[:, 0]
    b, a = signal.butter(2, 0.3)
    x = 2 * signal.lfilter(b, a, u)
    y = np.tanh(x) + 0.3 * x
    y += 0.02 * y.std() * np.random.default_rng(9).standard_normal(y.size)
    inv = InverseModel(Narx(order=3, degree=3, focus="simulation"), lead=1).fit(u, y)
    drive = inv.simulate(y, bound=np.inf)[:-1, 0]
    assert metrics.nrmse(u[:-1], drive) < 0.1
    linear = InverseModel(Narx(order=3, degree=1), lead=1).fit(u, y)
    assert metrics.nrmse(u[:-1], drive) < metrics.nrmse(u[:-1], linear.simulate(y)[:-1, 0])


def test_simulation_selection_finds_the_generating_terms_where_frols_adds_a_spurious_one(
    output_noise_data,
):
    u, y = output_noise_data
    candidates = dict(na=2, nb=2, nk=1, degree=3)  # 34 candidate terms
    semp = Narx(**candidates, selection="simulation").fit(u, y)
    assert set(semp.term_names()[0]) == set(TRUE_TERMS)
    assert semp.selection_paths_[0].criterion.size >= len(TRUE_TERMS)
    frols = Narx(**candidates, n_terms=14, criterion="bic").fit(u, y)
    assert set(frols.term_names()[0]) != set(TRUE_TERMS)  # one-step ERR is misled by the noise


def test_criterion_path_matches_refitting_every_frols_prefix(output_noise_data):
    u, y = output_noise_data
    model = Narx(na=2, nb=2, nk=1, degree=2)
    model.n_inputs_, model.n_outputs_ = 1, 1
    ch = model._structure(1, 1, np.ones(2))[0]
    X = regression_matrix(u[:, None], y[:, None], ch, ch.max_lag)
    target = y[ch.max_lag :]
    sel = forward_regression(X, target)
    for name in ("aic", "bic", "fpe"):
        brute = []
        for n in range(1, sel.selected.size + 1):
            cols = sel.selected[:n]
            coef, *_ = np.linalg.lstsq(X[:, cols], target, rcond=None)
            ic = information_criteria(target - X[:, cols] @ coef, n)
            brute.append(getattr(ic, name))
        assert criterion_path(X, target, sel.selected, sel.err, name) == int(np.argmin(brute)) + 1


def test_save_and_load_keep_the_new_options_and_standard_errors(tmp_path, output_noise_data):
    u, y = output_noise_data
    model = Narx(na=2, nb=2, nk=1, degree=2, focus="simulation", holdout=0.1, max_iter=20)
    model.fit(u, y)
    back = Narx.load(model.save(tmp_path / "oe"))
    assert (back.focus, back.holdout, back.max_iter) == ("simulation", 0.1, 20)
    for a, b in zip(model.coef_std_, back.coef_std_, strict=True):
        np.testing.assert_array_equal(a, b)
    np.testing.assert_array_equal(model.simulate(u), back.simulate(u))


@pytest.mark.parametrize(
    ("options", "message"),
    [
        ({"focus": "free-run"}, "focus must be 'prediction'"),
        ({"horizon": 0}, "horizon must be a positive number of samples"),
        ({"horizon": 2.5}, "horizon must be a positive number of samples"),
        ({"horizon": True}, "horizon must be a positive number of samples"),
        ({"max_iter": 0}, "max_iter must be a positive integer"),
        ({"stability_margin": 0.5}, "stability_margin must be a finite factor >= 1"),
        ({"stability_margin": float("nan")}, "stability_margin must be a finite factor >= 1"),
        ({"stability_margin": float("inf")}, "stability_margin must be a finite factor >= 1"),
        ({"holdout": 0.6}, "holdout must be a fraction in"),
        ({"holdout": -0.1}, "holdout must be a fraction in"),
        ({"selection": "ofr"}, "selection must be 'frols'"),
        ({"criterion": "mdl"}, "criterion must be one of"),
        ({"max_radius": 1.5}, "max_radius must lie in"),
    ],
)
def test_every_new_option_rejects_bad_input_clearly(options, message):
    with pytest.raises(IdentificationError, match=message):
        Narx(order=2, degree=2, **options)


def test_holdout_too_short_for_the_model_is_refused():
    u = band_limited_noise(300, 1, seed=1)[:, 0]
    y = _true_system(u)
    with pytest.raises(IdentificationError, match="holdout"):
        Narx(order=3, degree=3, focus="simulation", holdout=0.45).fit(u, y)


@pytest.mark.parametrize("kind", ["full", "pure", "quasi-static", "input-polynomial"])
def test_simulation_focus_lowers_the_free_run_error_for_every_term_kind(kind, output_noise_data):
    u, y = output_noise_data
    model = Narx(order=2, degree=2, kind=kind, focus="simulation", holdout=0.0, max_iter=20)
    model.fit(u, y)
    ref = model.refinement_
    assert ref.cost <= ref.initial_cost  # never worse than the least-squares start
    assert ref.history and ref.history[0] < ref.initial_cost  # and it did move
    ls = Narx(order=2, degree=2, kind=kind).fit(u, y)
    p = model.max_lag_
    err = [metrics.rmse(y[p:], m.simulate(u, y0=y[:p])[p:, 0]) for m in (ls, model)]
    assert err[1] < err[0]


def test_the_shock_absorber_full_narx_inverse_is_bounded_only_with_simulation_focus():
    """The reference text's full condensed cubic NARX inverse (Table 6.16) on the shock-absorber
    rig: its least-squares fit diverges on its own identification record; the simulation focus
    returns a model whose free run on that record is bounded (the contract), or refuses.

    On the datasheet-typical rig (``variant="mild"``, 1 mm of bush play; the figures below are
    its). On the calibrated default (``thesis``, 2.7 mm of play) the simulation-focus model's free
    run from a zero past diverges (SimulationDivergedError at sample 3): that rig's NARX rows are
    predictions, reported by benchmarks/thesis_tables.py."""
    import vrig
    from vrig.processing import gprepro
    from vrig.reconstruction.iteration import DriveIteration

    rig = vrig.load_rig("shock-absorber", seed=0, variant="mild")
    desired = vrig.TimeHistory(np.zeros((round(20 * rig.fs), 1)), rig.fs, ["damper_load"])
    it = DriveIteration(rig, desired, bandwidth=(0.0, 10.0), id_duration=20.0, seed=0)
    it.identify()
    drive = it.down(gprepro(it.id_drive, it.id_band)).data
    response = it.down(gprepro(it.id_response, it.id_band)).data
    lead = 3
    with pytest.raises(UnstableModelError):
        InverseModel(Narx(order=4, degree=3, kind="full"), lead=lead).fit(drive, response)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", StabilityWarning)
        inv = InverseModel(
            Narx(order=4, degree=3, kind="full", focus="simulation"), lead=lead
        ).fit(drive, response)
    model, n = inv.model, drive.shape[0]
    model.simulate(response[lead:])  # from a zero past: raises if it diverges
    sim = model.simulate(response[lead:], y0=drive[: model.max_lag_])
    assert metrics.qantim_fit_dc(drive[: n - lead], sim)[0] < 20  # ARX(4) inverse: 15 %


def test_free_run_residuals_of_the_simulation_fit_are_the_white_output_noise(output_noise_data):
    """The noise was added white to the output: a correct output-error model leaves exactly it,
    so every Billings-Voon test passes; the biased least-squares model fails them."""
    from identification import correlation_tests

    u, y = output_noise_data
    candidates = dict(na=2, nb=2, nk=1, degree=3)
    oe = Narx(**candidates, selection="simulation", focus="simulation").fit(u, y)
    ls = Narx(**candidates, n_terms=14, criterion="bic").fit(u, y)
    ok = correlation_tests(u, y - oe.simulate(u, y0=y[:2])[:, 0])
    bad = correlation_tests(u, y - ls.simulate(u, y0=y[:2])[:, 0])
    assert ok.all_passed, ok.table()
    assert not np.any([np.any(v) for v in bad.passed.values()]), bad.table()  # fails all five


def test_early_stopping_reports_which_step_it_kept(output_noise_data):
    u, y = output_noise_data
    model = Narx(na=2, nb=2, nk=1, degree=2, focus="simulation").fit(u, y)
    kept = model.refinement_.kept_step
    assert kept is not None and 1 <= kept <= len(model.refinement_.history)  # it did refine
    full = Narx(na=2, nb=2, nk=1, degree=2, focus="simulation", holdout=0.0).fit(u, y)
    assert full.refinement_.kept_step is None


def test_a_stable_linear_autoregression_is_not_refused_for_a_zero_past_transient():
    # y(t) = 1.6 y(t-1) - 0.8 y(t-2) + u(t-1): stable (|poles| = 0.89), underdamped; the record
    # sits at its level 250 (u = 50), a zero past starts at 0 and overshoots past the bound
    # (1.2 x max|y|) before it decays: a start-up transient, not a divergence
    from identification import SimulationDivergedError

    rng = np.random.default_rng(4)
    u = 50.0 + 0.1 * rng.standard_normal(3000)
    y = np.full(3000, 250.0)
    for t in range(2, 3000):
        y[t] = 1.6 * y[t - 1] - 0.8 * y[t - 2] + u[t - 1]
    y += 0.01 * rng.standard_normal(3000)
    model = Narx(na=2, nb=1, nk=1, degree=1, bound_factor=1.2).fit(u, y)
    assert model.pole_radius() < 0.95  # stable (true 0.894; a weakly excited estimate)
    assert model.stability_["input"] is True
    with pytest.raises(SimulationDivergedError):
        model.simulate(u)  # the transient does exceed the bound from a zero past
    model.simulate(u, y0=y[:2])  # and the record's own start runs bounded


def test_sensitivity_jacobian_with_non_polynomial_terms_on_inputs_and_outputs():
    """abs, dead zone, saturation and sign-square of inputs and of fed-back outputs: the
    kernel's derivative of each function (away from the kinks) against finite differences."""
    u = band_limited_noise(400, 1, cutoff=0.3, seed=2)[:, 0]
    y = np.zeros(400)
    for t in range(1, 400):  # a known model with a saturated output feedback
        y[t] = 0.6 * np.clip(y[t - 1], -0.4, 0.4) + 0.5 * u[t - 1] + 0.2 * abs(u[t - 1])
    functions = ["abs", "sign_square", ("deadzone", 0.3), ("saturation", 0.4)]
    model = Narx(na=1, nb=2, nk=0, degree=2, functions=functions, function_sources="all")
    model._fit_least_squares(u, y)
    flat = FlatModel.from_channels(model.channels_, 1, 1)
    assert flat.reg_fn.max() > 0  # the functions reach the kernel
    theta = np.concatenate(model.coef_)
    _e, J, _ = simulation_error(flat, theta, u[:, None], y[:, None], jacobian=True)
    for j in range(flat.n_params):
        h = 1e-6 * max(abs(theta[j]), 1.0)
        tp, tm = theta.copy(), theta.copy()
        tp[j] += h
        tm[j] -= h
        fd = -(
            simulation_error(flat, tp, u[:, None], y[:, None])[0]
            - simulation_error(flat, tm, u[:, None], y[:, None])[0]
        ) / (2 * h)
        assert np.linalg.norm(fd - J[:, j]) <= 1e-6 * max(np.linalg.norm(J[:, j]), 1e-12), j


def _rig_like_plant(d: np.ndarray) -> np.ndarray:
    """A linear 'damper on a servo actuator' (written out, independent of the package): the
    actuator lags the drive (pole 0.8), the load is stiffness plus a difference term. Its exact
    inverse is d(t) = d(t-1) / 3 + (y(t) - 0.8 y(t-1)) / 300 (pole 1/3: minimum phase)."""
    x = signal.lfilter([0.2], [1.0, -0.8], d)
    return 1000.0 * (1.5 * x - 0.5 * np.concatenate([[0.0], x[:-1]]))


def test_a_degree_2_simulation_focus_inverse_of_a_linear_rig_drives_a_cut_out_record():
    """Issue-12 follow-up: on the linearised damper the simulation-focus NARX inverse gave 57 %
    where ARX gave 5 %. Its drive was right everywhere but at the start: the desired response
    is a cut-out (it does not start from rest), a zero past makes sample 0 a step, and the
    degree-2 inverse's large cancelling products of response lags (an oversampled band) turn
    the step into a kick that its slow refined poles stretch past the drive taper. A free run
    from a mirrored, faded-in history (``run_in``) is what a cut-out record needs."""
    rng = np.random.default_rng(0)
    d_id = band_limited_noise(6000, 1, cutoff=0.2, seed=1)[:, 0]
    y_id = _rig_like_plant(d_id)
    y_id = y_id + 0.002 * y_id.std() * rng.standard_normal(y_id.size)  # transducer noise
    d_long = 2.0 * band_limited_noise(4000, 1, cutoff=0.1, seed=2)[:, 0]  # 2x the id level
    d_des, y_des = d_long[1000:], _rig_like_plant(d_long)[1000:]  # cut out: not at rest
    assert abs(y_des[0]) > y_des.std()  # the record starts far from zero
    inv = InverseModel(Narx(4, 2, kind="input-polynomial", focus="simulation"), lead=0).fit(
        d_id, y_id
    )
    assert inv.model.pole_radius() < 1.0  # a stable recursion: no divergence involved
    interior = slice(200, None)

    def error(d):
        return metrics.nrmse(d_des, d[:, 0]), metrics.nrmse(d_des[interior], d[interior, 0])

    whole0, inner0 = error(inv.simulate(y_des, run_in=0))
    whole, inner = error(inv.simulate(y_des, run_in="auto"))
    assert inner0 < 0.01 and inner < 0.01  # away from the start both are the drive
    assert whole0 > 10 * inner0  # the zero past's start-up kick dominates the whole record
    assert whole < 0.03  # the run-in start costs a little at the start, nothing like a kick
    with pytest.raises(IdentificationError, match="run_in"):
        inv.simulate(y_des, run_in=-1)
    with pytest.raises(IdentificationError, match="run_in"):
        inv.simulate(y_des, run_in="long")


def test_simulation_focus_of_a_degree_2_narx_on_a_linear_system_keeps_it_linear():
    """A KNOWN linear generating model with white output noise: the degree-2 simulation-focus
    fit must not simulate worse than its least-squares start (on the record and on fresh data,
    against the noise-free truth), must recover the linear coefficients within three of its
    standard errors and must leave every product term at zero within three standard errors."""
    truth = {"y1(t-1)": 1.5, "y1(t-2)": -0.7, "u1(t-1)": 0.5, "u1(t-2)": 0.3}

    def system(u):
        y = np.zeros(u.size)
        for t in range(2, u.size):
            y[t] = 1.5 * y[t - 1] - 0.7 * y[t - 2] + 0.5 * u[t - 1] + 0.3 * u[t - 2]
        return y

    u = band_limited_noise(4000, 1, cutoff=0.5, seed=3)[:, 0]
    clean = system(u)
    y = clean + 0.05 * clean.std() * np.random.default_rng(5).standard_normal(u.size)
    structure = dict(na=2, nb=2, nk=1, degree=2)
    ls = Narx(**structure).fit(u, y)
    oe = Narx(**structure, focus="simulation").fit(u, y)
    assert oe.refinement_.cost <= oe.refinement_.initial_cost
    u_new = band_limited_noise(4000, 1, cutoff=0.5, seed=8)[:, 0]
    for uu, yy in ((u, clean), (u_new, system(u_new))):
        e_ls = metrics.nrmse(yy, ls.simulate(uu)[:, 0])
        e_oe = metrics.nrmse(yy, oe.simulate(uu)[:, 0])
        assert e_oe <= e_ls, (e_oe, e_ls)
    std = dict(zip(oe.term_names()[0], oe.coef_std_[0], strict=True))
    for name, value in zip(oe.term_names()[0], oe.coef_[0], strict=True):
        assert abs(value - truth.get(name, 0.0)) <= 3 * std[name], (name, value, std[name])


def test_a_simulation_focus_too_large_for_memory_is_refused_before_anything_is_built(
    monkeypatch,
):
    """Issue 25: focus="simulation" on a 7 x 7 structure was refused (the output-error
    Jacobian over the memory budget) only after the regression matrix and the least-squares
    start were built (28 s, 1.16 GB). The Jacobian's size is known from the structure and the
    record length: (10000 - 2) x 7 residuals x 4655 parameters x 8 bytes = 2.6 GB > 2 GiB."""
    import identification.models as models
    from identification.budget import MEMORY_BUDGET_BYTES

    def never(*args, **kwargs):
        raise AssertionError("the regression matrix was built before the refusal")

    monkeypatch.setattr(models, "regression_matrix", never)
    rng = np.random.default_rng(0)
    u, y = rng.standard_normal((10_000, 7)), rng.standard_normal((10_000, 7))
    # 7 x 2 output lags + 7 x 3 input lags = 35 regressors: 35 + 35 * 36 / 2 = 665 terms
    n_bytes = (10_000 - 2) * 7 * (7 * 665) * 8
    assert n_bytes > MEMORY_BUDGET_BYTES
    with pytest.raises(IdentificationError, match="output-error Jacobian"):
        Narx(order=2, degree=2, focus="simulation").fit(u, y)
