"""The stability remedy keeps accuracy (issue 24, deliverable 4).

Truth: a known NARX with real non-linear output feedback, a cubic restoring term,

    y(t) = 0.8 y(t-1) - 0.3 y(t-1)^3 + u(t-1),

written out in this file, measured with 5 % output noise. Fitted as a full cubic NARX of order 2
with the simulation focus, the output-error model's free run is not bounded at the stability
margin, so the contract's remedy runs. Dropping every term that feeds past outputs back
non-linearly (the old remedy, reproduced independently as ``kind="input-polynomial"``: the same
term set, refitted and refined) removes the cubic restoring term the system has; the remedy must
keep a bounded model that validates at least as well, and on fresh data from the system this one
is more accurate. (Not every record of this system gives that: when no regrown or damped model is
bounded on the held-out probe inputs, the drop is kept and both are equal; on 36 remedied fits of
three such systems the remedy was kept on 23, never worse.)
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from identification import Narx, StabilityWarning, band_limited_noise, metrics
from identification.output_error import FlatModel, refine


def _system(u: np.ndarray) -> np.ndarray:
    y = np.zeros(u.size)
    for t in range(1, u.size):
        y[t] = 0.8 * y[t - 1] - 0.3 * y[t - 1] ** 3 + u[t - 1]
    return y


def _input(seed: int) -> np.ndarray:
    return 0.3 * band_limited_noise(3000, 1, cutoff=0.2, seed=seed)[:, 0]


def _as2d(fitted):
    u, y, _, _ = fitted
    return u[:, None], y[:, None]


@pytest.fixture(scope="module")
def fitted():
    u = _input(0)
    clean = _system(u)
    y = clean + 0.05 * clean.std() * np.random.default_rng(1).standard_normal(u.size)
    with warnings.catch_warnings():
        warnings.simplefilter("error", StabilityWarning)  # the contract holds: no warning
        model = Narx(order=2, degree=3, focus="simulation").fit(u, y)
        dropped = Narx(order=2, degree=3, kind="input-polynomial", focus="simulation").fit(u, y)
    return u, y, model, dropped


def test_the_case_is_fair_the_system_itself_is_bounded_at_the_margin():
    u = _input(0)
    big = _system(1.5 * u)
    assert np.all(np.isfinite(big)) and np.abs(big).max() < 10 * np.abs(_system(u)).max()


def test_the_remedy_ran_and_reports_every_remedy_tried(fitted):
    _, _, model, dropped = fitted
    assert dropped.stability_["remedy"] is None  # linear in its outputs, stable: no remedy
    tried = model.stability_["tried"]
    assert model.stability_["remedy"] and len(tried) >= 2
    assert sum(t["chosen"] for t in tried) == 1
    names = [t["remedy"] for t in tried]
    assert any(n.startswith("damp") for n in names) and names[-1].startswith("dropped")
    for t in tried:
        assert isinstance(t["bounded"], bool)
        assert np.isfinite(t["validation_error"]) == t["bounded"]
    chosen = next(t for t in tried if t["chosen"])
    assert chosen["remedy"] in model.stability_["remedy"] and chosen["remedy"] in model.describe()


def test_the_chosen_remedy_validates_at_least_as_well_as_the_drop(fitted):
    _, _, model, dropped = fitted
    tried = model.stability_["tried"]
    chosen = next(t for t in tried if t["chosen"])
    drop = tried[-1]
    assert chosen["bounded"] and drop["bounded"]
    assert chosen["validation_error"] <= drop["validation_error"]
    # the drop's figure is the independently fitted input-polynomial model's held-out error
    assert drop["validation_error"] == pytest.approx(dropped._validation_error(*_as2d(fitted)))


def test_the_returned_model_keeps_the_contract(fitted):
    u, y, model, _ = fitted
    assert model.stability_["input"] is True and model.stability_["margin"] is True
    for scale in (1.0, 1.5):
        for y0 in (None, y[: model.max_lag_]):
            out = model.simulate(scale * u, y0=y0)  # raises if it leaves bound_
            assert np.all(np.isfinite(out))


def test_on_fresh_data_the_remedy_is_more_accurate_than_the_drop(fitted):
    _, _, model, dropped = fitted
    u = _input(100)
    truth = _system(u)
    ours = metrics.nrmse(truth, model.simulate(u)[:, 0])
    theirs = metrics.nrmse(truth, dropped.simulate(u)[:, 0])
    assert ours < theirs


def test_a_constrained_refinement_never_leaves_the_feasible_set():
    """``refine(feasible=...)``: y(t) = 0.9 y(t-1) + u(t-1) with output noise; the constraint
    a_1 <= 0.8 excludes the unconstrained optimum (near 0.9). From a feasible start every
    accepted step, hence the result, satisfies it, and the cost still falls."""
    rng = np.random.default_rng(3)
    u = rng.standard_normal(2000)
    y = np.zeros(u.size)
    for t in range(1, u.size):
        y[t] = 0.9 * y[t - 1] + u[t - 1]
    y += 0.1 * y.std() * rng.standard_normal(u.size)
    model = Narx(na=1, nb=1, nk=1, degree=1).fit(u, y)
    assert model.term_names() == [["y1(t-1)", "u1(t-1)"]]
    flat = FlatModel.from_channels(model.channels_, 1, 1)
    start = np.array([0.5, 1.0])
    data = (u[:, None], y[:, None])
    free = refine(flat, start, *data, bound=model.bound_)
    assert free.theta[0] > 0.85
    seen = []

    def feasible(theta):
        seen.append(theta[0])
        return theta[0] <= 0.8

    res = refine(flat, start, *data, bound=model.bound_, feasible=feasible)
    assert res.theta[0] <= 0.8 and res.cost < res.initial_cost
    assert any(a > 0.8 for a in seen)  # infeasible trials were proposed, and refused


def test_the_probe_inputs_are_other_waveforms_of_the_same_spectrum():
    """Phase randomisation keeps each channel's mean and amplitude spectrum and the
    cross-spectra (one phase per frequency for all channels); the waveform changes."""
    from identification.models import _probe_inputs

    rng = np.random.default_rng(5)
    u = rng.standard_normal((1001, 2)) @ np.array([[1.0, 0.5], [0.0, 1.0]]) + [0.3, -1.0]
    probes = _probe_inputs(u, 1.5, n=2, seed=7)
    again = _probe_inputs(u, 1.5, n=2, seed=7)
    spec = np.fft.rfft(u - u.mean(axis=0), axis=0)
    for probe, same in zip(probes, again, strict=True):
        np.testing.assert_array_equal(probe, same)  # reproducible
        p = probe / 1.5
        np.testing.assert_allclose(p.mean(axis=0), u.mean(axis=0), atol=1e-12)
        ps = np.fft.rfft(p - p.mean(axis=0), axis=0)
        np.testing.assert_allclose(np.abs(ps), np.abs(spec), rtol=1e-9, atol=1e-9)
        cross = ps[:, 0] * np.conj(ps[:, 1])
        np.testing.assert_allclose(cross, spec[:, 0] * np.conj(spec[:, 1]), atol=1e-7)
        assert np.corrcoef(p[:, 0], u[:, 0])[0, 1] < 0.5  # another waveform


def test_with_nothing_held_out_the_remedies_are_compared_by_bic():
    """``holdout=0``: the whole-record error always favours the larger model, so the remedies
    are scored by BIC; the chosen one has the smallest among the bounded ones."""
    u = _input(0)
    clean = _system(u)
    y = clean + 0.05 * clean.std() * np.random.default_rng(1).standard_normal(u.size)
    with warnings.catch_warnings():
        warnings.simplefilter("error", StabilityWarning)
        model = Narx(order=2, degree=3, focus="simulation", holdout=0.0).fit(u, y)
    tried = model.stability_["tried"]
    bounded = [t for t in tried if t["bounded"]]
    assert bounded and all(np.isfinite(t["bic"]) for t in bounded)
    chosen = next(t for t in tried if t["chosen"])
    assert chosen["bic"] == min(t["bic"] for t in bounded)
    assert "by BIC" in model.stability_["remedy"]
