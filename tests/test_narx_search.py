"""NarxSearch: structure and option search by free-run validation (issue 24).

Truths used: a known generating NARX (its terms), a constructed system whose least-squares cubic
model passes its own 1.5x stability check and still diverges on a held-out block (checked here
first, so the test cannot pass vacuously), and the search's documented contract (never returns
a model that diverges on a validation block or a stress input; the budget bounds the wall time).
"""

from __future__ import annotations

import time
import warnings

import numpy as np
import pytest

from identification import (
    IdentificationError,
    InsufficientDataError,
    Narx,
    NarxSearch,
    SimulationDivergedError,
    band_limited_noise,
    metrics,
)


def _problem_a(n: int, seed: int, noise: float = 0.05):
    """y(t) = 0.2 y(t-1) + 0.1 y(t-1) x(t-1) + 0.9 x(t-2), output noise ``noise`` x RMS."""
    rng = np.random.default_rng(seed)
    x = rng.uniform(-1, 1, n)
    y = np.zeros(n)
    for t in range(2, n):
        y[t] = 0.2 * y[t - 1] + 0.1 * y[t - 1] * x[t - 1] + 0.9 * x[t - 2]
    return x, y, y + noise * y.std() * rng.standard_normal(n)


GENERATING_TERMS = {"y1(t-1)", "y1(t-1)*u1(t-1)", "u1(t-2)"}


def _saturating(u):
    """A second-order system with a tanh input non-linearity: a cubic polynomial model fits it
    at small amplitude and extrapolates badly at large amplitude."""
    y = np.zeros_like(u)
    for t in range(2, len(u)):
        y[t] = 1.2 * y[t - 1] - 0.5 * y[t - 2] + 0.4 * np.tanh(0.5 * u[t - 1])
    return y


@pytest.fixture(scope="module")
def known_narx_search():
    x, _, yn = _problem_a(3000, seed=0)
    grid = dict(orders=(1, 2, 3), degrees=(1, 2), kinds=("full",))
    return NarxSearch(budget=None, **grid).fit(x, yn), grid


def test_finds_the_generating_structure(known_narx_search):
    search, _ = known_narx_search
    assert set(search.best_.term_names()[0]) == GENERATING_TERMS
    assert search.best_result_.status == "ok"
    assert search.refit_ == "whole record"


def test_free_run_beats_every_single_option_fit(known_narx_search):
    """On a fresh record, against the noise-free output: the search's model is at least as good
    as each single-option fit of the generating structure and of a generous guess."""
    search, _ = known_narx_search
    xv, yv, _ = _problem_a(3000, seed=1)
    _, _, yn = _problem_a(3000, seed=0)
    xi = _problem_a(3000, seed=0)[0]

    def err(model):
        try:
            return float(metrics.rrse(yv[4:], model.simulate(xv, y0=yv[:4])[4:])[0])
        except SimulationDivergedError:
            return np.inf

    mine = err(search.best_)
    others = {}
    for order, degree in ((2, 2), (3, 2)):
        for opts in (
            {},
            {"selection": "frols", "criterion": "bic"},
            {"selection": "simulation"},
            {"focus": "simulation"},
        ):
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                try:
                    m = Narx(order=order, degree=degree, **opts).fit(xi, yn)
                except IdentificationError:
                    continue
            others[(order, degree, tuple(opts.items()))] = err(m)
    assert others, "no single-option fit to compare with"
    assert mine <= min(others.values()) * (1 + 1e-3), (mine, others)
    assert mine < 0.02  # the generating terms: only parameter noise is left


def test_never_returns_a_model_that_diverges_on_a_held_out_block():
    n = 4000
    u = band_limited_noise(n, cutoff=0.3, seed=0)[:, 0]
    u[3000:] *= 3.0  # the held-out quarter is driven harder
    y = _saturating(u) + 0.01 * np.random.default_rng(0).standard_normal(n)
    # the premise: the least-squares cubic model passes its own 1.5x check, and diverges there
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ls = Narx(order=2, degree=3).fit(u[:3000], y[:3000])
    assert ls.stability_["margin"] is True
    with pytest.raises(SimulationDivergedError):
        ls.simulate(u[3000:], y0=y[3000:3002])
    search = NarxSearch(
        budget=None,
        orders=(2,),
        degrees=(1, 2, 3),
        kinds=("full",),
        focus=("prediction",),
        selection=("all",),
        n_blocks=1,
    ).fit(u, y)
    row = next(r for r in search.results_ if r.candidate.structure[:2] == (2, 3))
    assert row.status == "rejected" and "validation block" in row.reason
    assert search.best_result_.candidate.degree < 3
    sim = search.best_.simulate(u[3000:], y0=y[3000:3002])  # bounded: no exception
    assert np.all(np.isfinite(sim))


def test_mimo_non_square():
    """Two inputs, one output; then one input, two outputs: per-output scores, right shapes."""
    n = 2500
    u = band_limited_noise(n, 2, cutoff=0.4, seed=3)
    y = np.zeros((n, 2))
    for t in range(1, n):
        y[t, 0] = 0.5 * y[t - 1, 0] + u[t - 1, 0] + 0.3 * u[t - 1, 1] ** 2
        y[t, 1] = 0.3 * y[t - 1, 1] + 0.2 * y[t - 1, 0] + u[t - 1, 1]
    grid = dict(budget=None, orders=(1, 2), degrees=(1, 2), kinds=("full",), selection=("all",))
    s = NarxSearch(**grid, focus=("prediction",)).fit(u, y[:, :1], output_names=["f"])
    assert s.best_.n_inputs_ == 2 and s.best_.n_outputs_ == 1
    assert s.best_.output_names_ == ("f",)
    assert s.best_result_.score < 0.01  # noise-free, the structure is in the grid
    s2 = NarxSearch(**grid, focus=("prediction",)).fit(u[:, 0], y)
    assert s2.best_.n_outputs_ == 2 and s2.best_result_.scores.shape == (2,)


def test_deterministic_under_a_seed():
    x, _, yn = _problem_a(2000, seed=4)
    grid = dict(budget=None, orders=(1, 2), degrees=(1, 2), kinds=("full",), seed=7)
    a = NarxSearch(**grid).fit(x, yn)
    b = NarxSearch(**grid).fit(x, yn)
    assert [r.candidate for r in a.results_] == [r.candidate for r in b.results_]
    assert [r.score for r in a.results_] == [r.score for r in b.results_]
    assert np.array_equal(np.concatenate(a.best_.coef_), np.concatenate(b.best_.coef_))


@pytest.mark.slow  # a wall-time check: not in the default (CI) run, whose box is shared
def test_budget_is_respected():
    """A grid far larger than the budget: the wall time stays within 20 % of the budget (one
    candidate at most overruns its prediction) and candidates are skipped for the budget."""
    x, _, yn = _problem_a(6000, seed=5)
    budget = 12.0
    t0 = time.perf_counter()
    s = NarxSearch(budget=budget, orders=(1, 2, 3, 4, 6, 8), degrees=(1, 2, 3)).fit(x, yn)
    wall = time.perf_counter() - t0
    assert wall <= 1.2 * budget, s.report()
    assert any(r.status == "skipped" and "budget" in r.reason for r in s.results_)
    assert s.search_time_ <= wall


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"budget": 0}, "budget"),
        ({"budget": -5.0}, "budget"),
        ({"budget": float("inf")}, "budget"),
        ({"orders": ()}, "orders is empty"),
        ({"degrees": []}, "degrees is empty"),
        ({"kinds": ()}, "kinds is empty"),
        ({"focus": ()}, "focus is empty"),
        ({"selection": ("lasso",)}, "selection values"),
        ({"degrees": (0,)}, "degrees must be integers >= 1"),
        ({"holdout": 0.9}, "holdout"),
        ({"folds": 0}, "folds"),
        ({"folds": "many"}, "folds"),
        ({"baselines": "yes"}, "baselines"),
        ({"options": {"degree": 2}}, "searched"),
        ({"init_window": 2, "orders": (4,)}, "init_window"),
        ({"n_terms": ()}, "n_terms is empty"),
        ({"n_terms": (0,)}, "n_terms must be integers >= 1"),
        ({"options": {"n_terms": 5}}, "searched"),
        ({"orders": ((2, ()),)}, "per-input lags"),
    ],
)
def test_bad_arguments_are_refused_clearly(kwargs, match):
    with pytest.raises(IdentificationError, match=match):
        NarxSearch(**kwargs)


def test_record_too_short_for_the_validation_blocks():
    x, _, yn = _problem_a(80, seed=6)
    with pytest.raises(InsufficientDataError, match="too short for the validation"):
        NarxSearch(orders=(8,), degrees=(1,)).fit(x, yn)


def test_report_lists_every_candidate_with_its_fate(known_narx_search):
    search, _ = known_narx_search
    text = search.report()
    assert text.splitlines()[0].startswith("NarxSearch:")
    assert len(text.splitlines()) == len(search.results_) + 2
    assert "order 2, degree 2 full" in text
    with pytest.raises(IdentificationError, match="not fitted"):
        NarxSearch().report()


def test_report_after_a_search_that_found_no_model_says_why():
    """The error points to report(): it must work then, and it says why each candidate failed."""
    x, _, yn = _problem_a(600, seed=6)
    search = NarxSearch(budget=None, orders=(2,), degrees=(1,), focus=("prediction",),
                        selection=("all",), baselines=False).fit(x, yn)  # fmt: skip
    assert hasattr(search, "best_")
    search.max_terms = 2  # refitted with too small a limit: the old model must not survive
    with pytest.raises(IdentificationError, match="see results_ / report"):
        search.fit(x, yn)
    text = search.report()
    assert "no model chosen" in text
    # order 2, degree 1, one input: 4 lagged terms + constant > max_terms = 2
    assert "over max_terms (2)" in text
    assert not hasattr(search, "best_")


def test_a_structure_too_big_for_all_terms_is_ranked_by_frols_and_refined():
    """focus=("simulation",) with a structure over max_terms: stage 1 cannot fit it with all
    terms, so FROLS least squares ranks it and stage 2 refines it (before: no candidate)."""
    x, _, yn = _problem_a(1500, seed=9)
    search = NarxSearch(budget=None, orders=(2,), degrees=(2,), kinds=("full",),
                        focus=("simulation",), selection=("frols",), max_terms=4).fit(x, yn)  # fmt: skip
    fates = {r.candidate.options: r.status for r in search.results_}
    assert fates[("prediction", "all")] == "skipped"  # 1 + 4 + 10 = 15 terms > 4
    assert fates[("simulation", "frols")] == "ok"
    terms = set(search.best_.term_names()[0])
    assert GENERATING_TERMS <= terms, terms  # the generating terms are found


def test_the_constant_term_is_a_candidate_by_default():
    """A known NARX with an offset term (a transducer zero): the default search keeps the
    constant and recovers it; ``options={"constant": False}`` leaves it out."""
    x, y, _ = _problem_a(2000, seed=11, noise=0.0)
    offset = 0.3 / (1 - 0.2)  # y(t) = ... + 0.3: the constant 0.3 in the generating equation
    yo = np.zeros_like(y)
    for t in range(2, y.size):
        yo[t] = 0.2 * yo[t - 1] + 0.1 * yo[t - 1] * x[t - 1] + 0.9 * x[t - 2] + 0.3
    assert abs(yo.mean() - offset) < 0.1  # the premise: a record with a clear mean
    grid = dict(budget=None, orders=(2,), degrees=(2,), kinds=("full",),
                focus=("prediction",), selection=("frols",), baselines=False)  # fmt: skip
    model = NarxSearch(**grid).fit(x, yo).best_
    names = list(model.term_names()[0])
    assert "1" in names
    np.testing.assert_allclose(model.coef_[0][names.index("1")], 0.3, atol=1e-6)
    # without it, the offset must come from the lagged terms: none of this structure's fits
    # then runs bounded on every stress input (the search says so rather than guess)
    without = NarxSearch(**grid, options={"constant": False})
    with pytest.raises(IdentificationError, match="no candidate"):
        without.fit(x, yo)
    assert all(r.status == "rejected" for r in without.results_)


def test_a_fit_past_its_deadline_stops_iterating_and_says_so():
    """Narx.fit(deadline=...): a deadline already past stops the simulation-error refinement
    before its first iteration (the least-squares start is kept, the contract still holds)."""
    x, _, yn = _problem_a(2000, seed=8)
    late = Narx(order=2, degree=2, focus="simulation").fit(x, yn, deadline=time.perf_counter())
    assert late.timed_out_ and late.refinement_.timed_out
    assert late.refinement_.iterations == 0
    assert late.stability_["input"] is True
    free = Narx(order=2, degree=2, focus="simulation").fit(x, yn)
    assert not free.timed_out_ and free.refinement_.iterations > 0


def test_sized_frols_paths_are_candidates_and_ties_go_to_the_fewest_terms():
    """FROLS at 3 terms on data of a 3-term NARX: its free run ties the larger fits, so the
    3-term path is chosen, and its terms are the generating ones; a size at or above the
    structure's candidate count is the all-terms fit and is not fitted again."""
    x, _, yn = _problem_a(3000, seed=3)
    search = NarxSearch(
        budget=None, orders=(2,), degrees=(2,), kinds=("full",), focus=("prediction",),
        selection=("all", "frols"), n_terms=(3, 8, 10_000),
    ).fit(x, yn)  # fmt: skip
    rows = {r.candidate.n_terms: r for r in search.results_ if r.candidate.selection == "frols"}
    assert rows[3].status == rows[8].status == "ok"
    assert rows[3].n_terms == 3 and rows[8].n_terms == 8
    assert rows[10_000].status == "skipped" and "all-terms fit" in rows[10_000].reason
    assert search.best_result_.n_terms == 3  # the 3-term path (or BIC's baseline, also 3)
    assert set(search.best_.term_names()[0]) == GENERATING_TERMS


def test_per_input_lags_reach_a_late_input():
    """y(t) = 0.5 y(t-1) + u1(t-1) + 0.8 u2(t-5): order 1 cannot see u2(t-5), the per-input
    order (1, (1, 5)) can, and the search picks it with a near-perfect free run."""
    rng = np.random.default_rng(4)
    u = rng.standard_normal((2000, 2))
    y = np.zeros(2000)
    for t in range(5, 2000):
        y[t] = 0.5 * y[t - 1] + u[t - 1, 0] + 0.8 * u[t - 5, 1]
    search = NarxSearch(
        budget=None, orders=(1, (1, (1, 5))), degrees=(1,), focus=("prediction",),
        selection=("all",), init_window=5,
    ).fit(u, y)  # fmt: skip
    assert search.best_result_.candidate.order == (1, (1, 5))
    assert search.best_result_.score < 1e-6
    assert "u2(t-5)" in search.best_.term_names()[0]  # per-input lags reach it (either convention)
    text = NarxSearch(budget=None, orders=((1, (1, 5)),), degrees=(1,), focus=("prediction",),
                      selection=("all",), init_window=5, baselines=False).fit(u, y)  # fmt: skip
    assert "u lags 0..1/0..5" in text.best_result_.candidate.label()
    with pytest.raises(IdentificationError, match="per-input lags, but u has 2 inputs"):
        NarxSearch(budget=None, orders=((1, (1, 2, 3)),), degrees=(1,)).fit(u, y)


def test_stage_one_leaves_time_for_stage_two(monkeypatch):
    """Stage 1 spends at most its share of the budget (here none: only its first candidate);
    stage 2 then refines what was ranked, and the stage-1 candidates left over are still tried
    afterwards while time is left."""
    import identification.narx_search as ns

    monkeypatch.setattr(ns, "_STAGE1_SHARE", 0.0)
    x, _, yn = _problem_a(1500, seed=11)
    search = NarxSearch(budget=600, orders=(1, 2), degrees=(1, 2), kinds=("full",)).fit(x, yn)
    cheap = [r.candidate.options in {("prediction", "all"), ("prediction", "frols")}
             for r in search.results_ if r.origin != "widening"]  # fmt: skip
    assert cheap[0] and not cheap[1]  # one least-squares fit, then stage 2
    # every structure's LS and FROLS fits still tried, and per order the baselines without
    # the current input (ARX, FROLS of degree 1 and 2)
    assert sum(cheap) == 2 * 4 + 2 * 3


# --------------------------------------------------------------- issue 34: checked, predictive
def _nrmse_free_run(model, u, y, init: int) -> float:
    """Free-run NRMSE of ``model`` over ``u, y`` from its first ``init`` measured outputs."""
    sim = model.simulate(u, y0=y[:init])
    return float(np.mean(metrics.nrmse(y[init:], sim[init:])))


def test_a_whole_record_refit_that_runs_away_is_caught():
    """The issue's case, constructed: a closed-loop record of an open-loop unstable integrating
    process (ball on a beam), the structure the issue's search chose (order 4, degree 3
    input-polynomial, simulation focus, all terms). Its refit on the whole record is checked
    first, independently: a free run over its own training record far worse than the output's
    spread. The search must return the model it validated instead, and say so."""
    from identification.synthetic import ball_and_beam

    rec = ball_and_beam(1000, seed=7)
    u, y = rec.u[:500], rec.y[:500]
    grid = dict(orders=(4,), degrees=(3,), kinds=("input-polynomial",), focus=("simulation",),
                selection=("all",))  # fmt: skip
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        refit = Narx(na=4, nb=5, nk=0, degree=3, kind="input-polynomial", focus="simulation",
                     constant=True).fit(u, y)  # fmt: skip
    assert _nrmse_free_run(refit, u, y, 4) > 5.0  # the premise: the refit runs away
    search = NarxSearch(budget=None, folds=1, baselines=False, **grid).fit(u, y)
    assert search.refit_.startswith("training-part model kept")
    assert search.refit_ in search.report()
    assert _nrmse_free_run(search.best_, u, y, 4) < 2.0


def test_closed_loop_unstable_integrator_gives_a_bounded_held_out_free_run():
    """Ball on a beam in closed loop (a double integrator from angle to position): trained on
    the first half, the chosen model's free run over the second half (from its first 50
    measured outputs) stays within 1.5 standard deviations of the measured position (before
    issue 34 this record's chosen model ran away to 32x)."""
    from identification.synthetic import ball_and_beam

    rec = ball_and_beam(1000, seed=3)
    u, y = rec.u, rec.y
    search = NarxSearch(budget=None, orders=(2, 4, 8), degrees=(1, 2),
                        kinds=("input-polynomial",)).fit(u[:500], y[:500])  # fmt: skip
    assert search.n_folds_ == 4  # a short record: k-fold in time
    assert search.best_result_.block_scores.size == 4 * search.n_blocks
    assert _nrmse_free_run(search.best_, u[500:], y[500:], 50) < 1.5


def test_linear_baselines_are_always_in_the_field():
    """A linear second-order process searched with a cubic grid only: the ARX and linear
    output-error baselines are tried anyway, and the linear model (the truth) wins."""
    from scipy import signal as sig

    rng = np.random.default_rng(5)
    u = rng.standard_normal(3000)
    y = sig.lfilter([0.0, 0.5, 0.3], [1.0, -1.2, 0.5], u) + 0.02 * rng.standard_normal(3000)
    search = NarxSearch(budget=None, orders=(2,), degrees=(3,), kinds=("full",)).fit(u, y)
    base = [r for r in search.results_ if r.origin == "baseline"]
    assert {r.candidate.options for r in base if r.candidate.degree == 1} >= {
        ("prediction", "all"), ("simulation", "all")}  # fmt: skip
    assert any(r.candidate.selection == "frols" for r in base)
    assert search.best_result_.candidate.degree == 1
    linear = min(r.score for r in search.results_ if r.candidate.degree == 1 and r.status == "ok")
    assert search.best_result_.score <= linear
    only = NarxSearch(budget=None, orders=(2,), degrees=(3,), kinds=("full",), baselines=False)
    assert all(r.candidate.degree == 3 for r in only.fit(u, y).results_)


def test_time_left_widens_the_search_past_the_grid():
    """The grid holds order 1 only, which cannot see x(t-2) of the 3-term NARX; with time left
    the search widens to its neighbours (within the measured initial window) and finds the
    generating terms."""
    x, _, yn = _problem_a(3000, seed=2)
    search = NarxSearch(budget=60, orders=(1,), degrees=(2,), kinds=("full",), init_window=3,
                        focus=("prediction",), selection=("frols",)).fit(x, yn)  # fmt: skip
    widened = [r for r in search.results_ if r.origin == "widening"]
    assert widened and search.best_result_.origin == "widening"
    assert set(search.best_.term_names()[0]) == GENERATING_TERMS
    assert "from widening" in search.report().splitlines()[0]
