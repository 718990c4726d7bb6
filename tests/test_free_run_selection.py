"""Fast free-run selection (SEMP): the compiled scorer against the exhaustive reference, known
generating systems, the term-table free run against the compiled plan, and the size estimate."""

from __future__ import annotations

import time

import numpy as np
import pytest

import identification.free_run_selection as frs
from identification import IdentificationError, Narx, band_limited_noise, regression_matrix
from identification._semp import _term_tables
from identification._semp_kernels import score_groups, subset_free_run
from identification.free_run_selection import (
    MIN_SHORTLIST,
    screening,
    selection_estimate,
    simulation_selection,
)
from identification.simulation import compile_plan, simulate_plan
from identification.structure import ChannelStructure

A_TERMS = {"u1(t-2)", "y1(t-1)", "y1(t-1)*u1(t-1)"}  # y = 0.2 y1 + 0.1 y1 u1 + 0.9 u2


def _system_a(n: int, seed: int, noise: float) -> tuple[np.ndarray, np.ndarray]:
    """``y(t) = 0.2 y(t-1) + 0.1 y(t-1) x(t-1) + 0.9 x(t-2)``, ``x ~ U(-1, 1)``, written out
    sample by sample; ``noise`` x the output RMS added after the recursion (output error)."""
    rng = np.random.default_rng(seed)
    x = rng.uniform(-1.0, 1.0, n)
    y = np.zeros(n)
    for t in range(2, n):
        y[t] = 0.2 * y[t - 1] + 0.1 * y[t - 1] * x[t - 1] + 0.9 * x[t - 2]
    y += noise * np.sqrt(np.mean(y**2)) * rng.standard_normal(n)
    return x[:, None], y[:, None]


def _system_2x1(n: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """A sparse 2-output, 1-input NARX with cross terms, 5 % output noise per channel:
    ``y1(t) = 0.5 y1(t-1) + 0.8 u(t-1) + 0.2 y2(t-1) u(t-1)``,
    ``y2(t) = 0.3 y2(t-1) + 0.6 u(t-2) - 0.1 y1(t-1)^2``."""
    rng = np.random.default_rng(seed)
    u = rng.uniform(-1.0, 1.0, n)
    y = np.zeros((n, 2))
    for t in range(2, n):
        y[t, 0] = 0.5 * y[t - 1, 0] + 0.8 * u[t - 1] + 0.2 * y[t - 1, 1] * u[t - 1]
        y[t, 1] = 0.3 * y[t - 1, 1] + 0.6 * u[t - 2] - 0.1 * y[t - 1, 0] ** 2
    y += 0.05 * np.sqrt(np.mean(y**2, axis=0)) * rng.standard_normal(y.shape)
    return u[:, None], y


def _candidates(**structure) -> ChannelStructure:
    """The SISO candidate structure ``Narx(**structure)`` builds (one input, one output)."""
    model = Narx(**structure)
    model.n_inputs_, model.n_outputs_ = 1, 1
    return model._structure(1, 1, np.ones(2))[0]


def _candidates_2x1() -> ChannelStructure:
    """The candidate structure of ``Narx(order=2, degree=2)`` with two outputs, one input."""
    model = Narx(order=2, degree=2)
    model.n_inputs_, model.n_outputs_ = 1, 2
    return model._structure(2, 1, np.ones(3))[0]


def _steps(path) -> list[list[int]]:
    return [[int(i) for i in s] for s in path.steps]


_A_NAMES = _candidates(na=4, nb=5, nk=1, degree=3, constant=True).term_names(["y1"], ["u1"])


# ------------------------------------------------------------------ known generating systems
def test_the_fast_path_selects_the_generating_terms_of_a_known_narx_among_220():
    u, y = _system_a(3000, seed=1, noise=0.05)
    model = Narx(na=4, nb=5, nk=1, degree=3, constant=True, selection="simulation").fit(u, y)
    path = model.selection_paths_[0]
    assert path.screened is None  # small: every candidate scored
    # the first three forward steps take exactly the generating terms; the size criterion
    # keeps them (it may add a term whose free-run gain is at the noise level)
    assert {_A_NAMES[int(i)] for i in path.steps[2]} == A_TERMS
    assert A_TERMS <= set(model.term_names()[0])
    coef = dict(zip(model.term_names()[0], model.coef_[0], strict=True))
    np.testing.assert_allclose(
        [coef["y1(t-1)"], coef["y1(t-1)*u1(t-1)"], coef["u1(t-2)"]], [0.2, 0.1, 0.9], atol=0.02
    )


def test_a_shortlist_of_ten_candidates_per_step_keeps_the_exhaustive_model():
    u, y = _system_a(2000, seed=2, noise=0.05)
    structure = dict(na=4, nb=5, nk=1, degree=3, constant=True, selection="simulation")
    with screening(10):
        screened = Narx(**structure).fit(u, y)
    with screening(None):
        reference = Narx(**structure).fit(u, y)
    path, ref = screened.selection_paths_[0], reference.selection_paths_[0]
    assert path.screened == 10
    # the same steps up to the one the criterion keeps (later steps gain at the noise level,
    # where the shortlist may miss the exhaustive choice), hence the same model
    assert path.chosen == ref.chosen
    assert _steps(path)[: path.chosen + 1] == _steps(ref)[: ref.chosen + 1]
    assert set(screened.term_names()[0]) == set(reference.term_names()[0])
    assert {_A_NAMES[int(i)] for i in path.steps[2]} == A_TERMS


def test_fast_and_exhaustive_selection_take_the_same_path_on_a_siso_problem():
    u, y = _system_a(2000, seed=3, noise=0.05)
    structure = dict(na=2, nb=3, nk=1, degree=2, constant=True, selection="simulation")
    fast = Narx(**structure).fit(u, y)
    with screening(None):
        reference = Narx(**structure).fit(u, y)
    pf, pr = fast.selection_paths_[0], reference.selection_paths_[0]
    assert _steps(pf) == _steps(pr)
    assert pf.chosen == pr.chosen
    np.testing.assert_allclose(pf.mse, pr.mse, rtol=1e-8)
    assert set(fast.term_names()[0]) == set(reference.term_names()[0]) == A_TERMS


def test_fast_and_exhaustive_selection_take_the_same_path_on_a_two_output_problem():
    u, y = _system_2x1(2000, seed=4)
    structure = dict(order=2, degree=2, selection="simulation")
    fast = Narx(**structure).fit(u, y)
    with screening(None):
        reference = Narx(**structure).fit(u, y)
    for k in range(2):
        assert _steps(fast.selection_paths_[k]) == _steps(reference.selection_paths_[k])
        np.testing.assert_allclose(
            fast.selection_paths_[k].mse, reference.selection_paths_[k].mse, rtol=1e-8
        )
    true = ({"y1(t-1)", "u1(t-1)", "y2(t-1)*u1(t-1)"}, {"y2(t-1)", "u1(t-2)", "y1(t-1)*y1(t-1)"})
    names = _candidates_2x1().term_names(["y1", "y2"], ["u1"])
    for k in range(2):  # a step holds exactly the generating terms (channel 2: once pruning
        # dropped y1(t-1), a stand-in for y2(t-1) taken first); the criterion keeps them
        steps = [{names[i] for i in s} for s in fast.selection_paths_[k].steps]
        assert true[k] in steps
        assert true[k] <= set(fast.term_names()[k])


def test_the_path_does_not_depend_on_the_number_of_scoring_threads():
    u, y = _system_a(2000, seed=5, noise=0.1)
    ch = _candidates(na=3, nb=3, nk=1, degree=3, constant=True)
    start = ch.max_lag
    X = regression_matrix(u, y, ch, start)
    paths = [
        simulation_selection(X, ch, 0, u, y, start, workers=w, criterion=None) for w in (1, 2, 3)
    ]
    assert _steps(paths[0]) == _steps(paths[1]) == _steps(paths[2])
    assert np.array_equal(paths[0].mse, paths[1].mse) and np.array_equal(paths[0].mse, paths[2].mse)


def test_no_forward_step_starts_after_the_deadline():
    """The size estimate is nominal (a loaded machine runs slower): with a deadline already
    past the path makes its first step and no other; without one it goes on."""
    u, y = _system_a(2000, seed=5, noise=0.1)
    ch = _candidates(na=3, nb=3, nk=1, degree=3, constant=True)
    start = ch.max_lag
    X = regression_matrix(u, y, ch, start)
    late = simulation_selection(X, ch, 0, u, y, start, deadline=time.perf_counter())
    free = simulation_selection(X, ch, 0, u, y, start)
    assert len(late.steps) == 1 and len(free.steps) > 1
    assert np.array_equal(late.steps[0], free.steps[0])

# ------------------------------------------------------------------ the term-table free run
def _structure_with_functions() -> ChannelStructure:
    """A single-output view: own output lags 1, 2 (and |y(t-1)|), input 1 lags 0, 1 (and a dead
    zone of u1(t-1)), input 2 lag 1; cubic terms mixing all of them."""
    regs = [(0, 1), (0, 2), (0, 1), (1, 0), (1, 1), (1, 1), (2, 1)]
    functions = [0, 0, 1, 0, 0, 2, 0]  # identity, identity, abs, ..., deadzone
    breakpoints = [0, 0, 0, 0, 0, 0.3, 0]
    terms = [
        (0, 0, 1), (0, 0, 2), (0, 0, 3), (0, 0, 4), (0, 0, 5), (0, 0, 6), (0, 0, 7),
        (0, 1, 4), (0, 3, 5), (1, 2, 7), (4, 5, 6), (0, 4, 7), (1, 1, 4), (0, 0, 0),
        (2, 3, 6),
    ]  # fmt: skip
    return ChannelStructure(
        np.array(regs), np.array(terms), functions=np.array(functions),
        breakpoints=np.array(breakpoints, dtype=float),
    )  # fmt: skip


def test_the_term_table_free_run_matches_the_compiled_plan():
    siso = _structure_with_functions()
    rng = np.random.default_rng(6)
    n, start = 3000, siso.max_lag
    inputs = band_limited_noise(n, 2, cutoff=0.4, seed=rng)
    yk = rng.standard_normal(n)  # the measured output: its first samples start the free run
    X = regression_matrix(inputs, yk[:, None], siso, start)
    tables = _term_tables(siso, inputs, yk, start)
    sel = np.array([0, 2, 3, 5, 7, 8, 9, 11, 12, 13, 14], dtype=np.int64)
    coef = 0.15 * rng.uniform(-1.0, 1.0, sel.size)
    sub = ChannelStructure(
        siso.regressors, siso.terms[sel], functions=siso.functions, breakpoints=siso.breakpoints
    )
    plan = compile_plan((sub,), (coef,), 1, 2)
    ref = simulate_plan(plan, inputs, yk[:start, None], np.array([np.inf]), ("y",))[:, 0]
    assert np.all(np.isfinite(ref)) and np.std(ref[start:]) > 0.1
    y = yk.copy()
    target = yk[start:]
    sse = subset_free_run(
        y, start, X, tables[6], *tables[:6], sel, coef, target, np.inf, np.inf
    )
    np.testing.assert_allclose(y, ref, rtol=0, atol=1e-12 * np.max(np.abs(ref)))
    assert sse == pytest.approx(float(np.sum((target - ref[start:]) ** 2)), rel=1e-10)


def test_lockstep_groups_score_every_subset_as_its_own_free_run():
    siso = _structure_with_functions()
    rng = np.random.default_rng(8)
    n, start = 2000, siso.max_lag
    inputs = band_limited_noise(n, 2, cutoff=0.4, seed=rng)
    yk = rng.standard_normal(n)
    X = regression_matrix(inputs, yk[:, None], siso, start)
    tables = _term_tables(siso, inputs, yk, start)
    run = (yk, start, X, tables[6], *tables[:6])
    S = np.array([0, 3, 8], dtype=np.int64)  # y(t-1), u1(t), y(t-1)*u1(t-1)*dz(u1(t-1))
    own = np.array([t for t in range(siso.n_terms) if t not in S] * 2, dtype=np.int64)
    coefs = 0.15 * rng.uniform(-1.0, 1.0, (own.size, S.size + 1))  # 24 subsets: 16 + 8
    ptr = np.array([0, 16, own.size], dtype=np.int64)
    for terms in (own, np.full(own.size, -1, dtype=np.int64)):  # forward step, pruning
        out = np.full(own.size, np.nan)
        groups = np.arange(2, dtype=np.int64)
        score_groups(*run, S, terms, coefs, ptr, groups, yk[start:], 1e6, np.array([np.inf]),
                     False, out)  # fmt: skip
        for c in range(own.size):
            sel = np.append(S, terms[c]) if terms[c] >= 0 else S
            alone = subset_free_run(yk.copy(), *run[1:], sel, coefs[c, : sel.size], yk[start:],
                                    1e6, np.inf)  # fmt: skip
            assert np.isfinite(alone)
            assert out[c] == pytest.approx(alone, rel=1e-12)


def test_the_term_table_free_run_stops_at_the_bound_and_at_the_cap():
    siso = _structure_with_functions()
    rng = np.random.default_rng(7)
    n, start = 500, siso.max_lag
    inputs = band_limited_noise(n, 2, cutoff=0.4, seed=rng)
    yk = rng.standard_normal(n)
    X = regression_matrix(inputs, yk[:, None], siso, start)
    tables = _term_tables(siso, inputs, yk, start)
    sel = np.array([0, 3], dtype=np.int64)  # y(t) = 1.5 y(t-1) + u1(t): grows without limit
    run = (yk.copy(), start, X, tables[6], *tables[:6], sel, np.array([1.5, 1.0]), yk[start:])
    assert subset_free_run(*run, 1e6, np.inf) == np.inf
    assert subset_free_run(*run, np.inf, 1.0) == np.inf  # squared error beyond the cap


# ------------------------------------------------------------------ size estimate and budget
def test_the_estimate_counts_the_forward_runs_the_pruning_runs_and_the_gram_rows():
    # M = 3 candidates, 2 steps: step 1 scores 3 one-term models, no pruning (3); step 2 scores
    # 2 two-term models and prunes one one-term model (2 * 2 + 1): 8 subset-terms per sample;
    # the least squares read the 1000 x 3 matrix 2 + 2 times (2 Gram rows, norms, X'y)
    from identification._semp import GRAM_RATE, TERM_RATE

    gram = 4 * 1000 * 3 / GRAM_RATE
    assert selection_estimate(1000, 3, 2, cost=1.0) == pytest.approx(8 * 1000 / TERM_RATE + gram)
    assert selection_estimate(1000, 3, 2, cost=2.0, shortlist=1) == pytest.approx(
        2.0 * 1000 * (1 + 2 + 1) / TERM_RATE + gram
    )


def test_a_large_selection_is_refused_with_the_estimate_and_what_to_change(monkeypatch):
    u, y = _system_a(1500, seed=8, noise=0.05)
    monkeypatch.setattr(frs, "SELECTION_BUDGET_S", 1e-6)
    with pytest.raises(IdentificationError) as info:
        Narx(na=4, nb=5, nk=1, degree=3, constant=True, selection="simulation").fit(u, y)
    msg = str(info.value)
    assert "1,495 samples x 220 candidate terms x up to 40 steps" in msg  # 1500 - max lag 5
    for phrase in ("estimated", "budget", "n_terms", "selection='frols'", "SELECTION_BUDGET_S"):
        assert phrase in msg


def test_past_the_budget_the_forward_steps_are_screened_to_a_shortlist_that_fits():
    u, y = _system_a(2000, seed=9, noise=0.05)
    ch = _candidates(na=4, nb=5, nk=1, degree=3, constant=True)
    start = ch.max_lag
    X = regression_matrix(u, y, ch, start)
    n, M = X.shape
    own = np.concatenate([[False], ch.regressors[:, 0] == 0])  # factor -> is an output lag
    cost = 1.0 + float(np.mean(own[ch.terms].sum(axis=1)))  # 1 + mean output factors per term
    budget = selection_estimate(n, M, 40, cost) / 4
    path = simulation_selection(X, ch, 0, u, y, start, budget=budget)
    assert MIN_SHORTLIST <= path.screened < M
    assert selection_estimate(n, M, 40, cost, path.screened) <= budget
    assert selection_estimate(n, M, 40, cost, path.screened + 1) > budget
    assert {_A_NAMES[int(i)] for i in path.steps[2]} == A_TERMS
    assert A_TERMS <= {_A_NAMES[int(i)] for i in path.selected}


def test_the_output_channels_share_the_budget():
    u, y = _system_2x1(2000, seed=11)
    ch = _candidates_2x1()
    start = ch.max_lag
    X = regression_matrix(u, y, ch, start)
    n, M = X.shape
    own = np.concatenate([[False], ch.regressors[:, 0] == 0])  # channel 1's own output lags
    cost = 1.0 + float(np.mean(own[ch.terms].sum(axis=1)))
    full = selection_estimate(n, M, min(M, 40), cost)
    least = selection_estimate(n, M, min(M, 40), cost, MIN_SHORTLIST)
    budget = full + least  # the whole path fits it, but not half of it: channel 1's share
    path = simulation_selection(X, ch, 0, u, y, start, budget=budget)
    assert path.screened is not None
    assert selection_estimate(n, M, min(M, 40), cost, path.screened) <= budget / 2


def test_a_seven_by_seven_order_five_selection_is_beyond_the_default_budget():
    # 7 outputs x lags 1..5 and 7 inputs x lags 0..5: 77 regressors, quadratic with constant:
    # C(79, 2) = 3081 candidates per channel; 20,000 samples, a 40-term path
    M = 79 * 78 // 2
    assert selection_estimate(20_000, M, 40) > frs.SELECTION_BUDGET_S


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"screen": "fast"}, "screen must be 'auto', None or a number"),
        ({"screen": 0}, "screen must be 'auto', None or a number"),
        ({"screen": True}, "screen must be 'auto', None or a number"),
        ({"budget": 0.0}, "budget must be > 0"),
        ({"budget": -1.0}, "budget must be > 0"),
        ({"workers": 0}, "workers must be None or a number >= 1"),
        ({"workers": 1.5}, "workers must be None or a number >= 1"),
    ],
)
def test_bad_screen_and_budget_are_refused(kwargs, match):
    u, y = _system_a(300, seed=10, noise=0.05)
    ch = _candidates(na=1, nb=2, nk=1, degree=1)
    X = regression_matrix(u, y, ch, ch.max_lag)
    with pytest.raises(IdentificationError, match=match):
        simulation_selection(X, ch, 0, u, y, ch.max_lag, **kwargs)


def test_screening_refuses_a_bad_screen():
    with pytest.raises(IdentificationError, match="screen must be"):
        with screening("fast"):
            pass
