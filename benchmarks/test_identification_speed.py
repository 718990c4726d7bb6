"""pytest-benchmark suite of the identification hot paths (kept out of the default test run).

Run with::

    pytest benchmarks/ --benchmark-only                       # timings table
    pytest benchmarks/ --benchmark-only --benchmark-autosave  # also save to .benchmarks/
    python -m benchmarks.compare_runs                         # latest two saved runs, > 20 %?

Problems are moderate so that the whole file runs in well under two minutes:

* SISO: SysIdentPy's classic cubic example system, 5,000 samples; candidate structure with
  3 output and 3 input lags, cubic, constant (84 terms).
* MIMO: a random stable 2 x 2 quadratic NARX system driven by band-limited noise, 5,000
  samples; full-order ``Narx(order=3, degree=2)`` (119 terms per channel).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pytest

from identification import (
    Narx,
    band_limited_noise,
    forward_regression,
    random_narx,
    regression_matrix,
)
from identification.solvers import SOLVERS

N_SAMPLES = 5_000
N_SIMULATE = 200_000
SISO_TERMS = 84
MIMO_TERMS = 119


@dataclass(frozen=True)
class Problem:
    """Identification data and a model fitted on it (numba kernels already compiled)."""

    u: np.ndarray
    y: np.ndarray
    model: Narx
    u_long: np.ndarray

    def fresh(self, **kwargs) -> Narx:
        return self.model.__class__(**{**self.params, **kwargs})

    @property
    def params(self) -> dict:
        m = self.model
        if m.order is not None:
            return {"order": m.order, "degree": m.degree, "constant": m.constant}
        return {"na": m.na, "nb": m.nb, "nk": m.nk, "degree": m.degree, "constant": m.constant}


def siso_data(n: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """``y(t) = 0.2 y(t-1) + 0.1 y(t-1) x(t-1) + 0.9 x(t-2) + e(t)``, x ~ U(-1, 1)."""
    rng = np.random.default_rng(seed)
    x = rng.uniform(-1.0, 1.0, n)
    e = rng.normal(0.0, 1e-3, n)
    y = np.zeros(n)
    for t in range(2, n):  # the true system
        y[t] = 0.2 * y[t - 1] + 0.1 * y[t - 1] * x[t - 1] + 0.9 * x[t - 2] + e[t]
    return x[:, None], y[:, None]


@pytest.fixture(scope="module")
def siso() -> Problem:
    u, y = siso_data(N_SAMPLES, seed=1)
    model = Narx(na=3, nb=3, nk=1, degree=3, constant=True).fit(u, y)
    assert model.n_terms_[0] == SISO_TERMS
    u_long = np.random.default_rng(2).uniform(-1.0, 1.0, (N_SIMULATE, 1))
    model.simulate(u_long[:100])  # compile / load the free-run kernels
    return Problem(u, y, model, u_long)


@pytest.fixture(scope="module")
def mimo() -> Problem:
    rng = np.random.default_rng(3)
    system = random_narx(2, 2, 2, 2, seed=rng)
    u = band_limited_noise(N_SAMPLES, 2, cutoff=0.3, seed=rng)
    y = system.simulate(u)
    y += 0.01 * rng.standard_normal(y.shape)
    model = Narx(order=3, degree=2).fit(u, y)
    assert np.all(model.n_terms_ == MIMO_TERMS)
    u_long = band_limited_noise(N_SIMULATE, 2, cutoff=0.3, seed=rng)
    model.simulate(u_long[:100])
    return Problem(u, y, model, u_long)


@pytest.mark.benchmark(group="regression_matrix")
@pytest.mark.parametrize("name", ["siso", "mimo"])
def test_regression_matrix(benchmark, request, name: str) -> None:
    p: Problem = request.getfixturevalue(name)
    ch, start = p.model.channels_[0], p.model.max_lag_
    X = benchmark(regression_matrix, p.u, p.y, ch, start)
    assert X.shape == (N_SAMPLES - start, ch.n_terms)


@pytest.mark.benchmark(group="fit")
@pytest.mark.filterwarnings("ignore::identification.IllConditionedWarning")  # solver="normal"
@pytest.mark.parametrize("solver", sorted(SOLVERS))
def test_fit_solver(benchmark, siso: Problem, solver: str) -> None:
    model = benchmark(lambda: siso.fresh(solver=solver).fit(siso.u, siso.y))
    np.testing.assert_allclose(model.coef_[0], siso.model.coef_[0], rtol=1e-5, atol=1e-7)


@pytest.mark.benchmark(group="fit")
def test_fit_mimo(benchmark, mimo: Problem) -> None:
    model = benchmark(lambda: mimo.fresh().fit(mimo.u, mimo.y))
    assert model.n_terms_.tolist() == [MIMO_TERMS, MIMO_TERMS]


@pytest.mark.benchmark(group="frols")
def test_forward_regression(benchmark, siso: Problem) -> None:
    ch, start = siso.model.channels_[0], siso.model.max_lag_
    X = regression_matrix(siso.u, siso.y, ch, start)
    sel = benchmark(forward_regression, X, siso.y[start:, 0], n_terms=SISO_TERMS)
    assert sel.selected.size == SISO_TERMS


@pytest.mark.benchmark(group="frols")
def test_fit_frols(benchmark, siso: Problem) -> None:
    model = benchmark(lambda: siso.fresh(n_terms=10).fit(siso.u, siso.y))
    assert model.n_terms_[0] == 10


@pytest.mark.benchmark(group="simulate")
@pytest.mark.parametrize("name", ["siso", "mimo"])
def test_simulate(benchmark, request, name: str) -> None:
    p: Problem = request.getfixturevalue(name)
    y = benchmark(p.model.simulate, p.u_long)
    assert y.shape == (N_SIMULATE, p.y.shape[1])


@pytest.mark.benchmark(group="predict")
@pytest.mark.parametrize("name", ["siso", "mimo"])
def test_predict(benchmark, request, name: str) -> None:
    p: Problem = request.getfixturevalue(name)
    y = benchmark(p.model.predict, p.u, p.y)
    assert y.shape == p.y.shape


@pytest.mark.benchmark(group="simulation-focus")
@pytest.mark.parametrize("name", ["siso", "mimo"])
def test_fit_simulation_focus(benchmark, request, name: str) -> None:
    """Output-error refinement (least squares, then Levenberg-Marquardt on the free run)."""
    p: Problem = request.getfixturevalue(name)
    model = benchmark(lambda: p.fresh(focus="simulation", max_iter=10).fit(p.u, p.y))
    assert model.refinement_ is not None and model.stability_["input"]


@pytest.mark.benchmark(group="simulation-focus")
def test_fit_simulation_selection(benchmark, siso: Problem) -> None:
    """SEMP term selection by free-run error over the 84 SISO candidates."""
    model = benchmark(lambda: siso.fresh(selection="simulation", n_terms=10).fit(siso.u, siso.y))
    assert 1 <= model.n_terms_[0] <= 10
