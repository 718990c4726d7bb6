"""Order selection: error versus order for each output channel (Fig. 3.21)."""

from __future__ import annotations

import numpy as np
import pytest

from identification import Narx, order_scan


@pytest.mark.filterwarnings("ignore::identification.errors.RankDeficiencyWarning")  # noise-free
def test_order_scan_finds_the_generating_order():
    rng = np.random.default_rng(2)
    u = rng.standard_normal(3000)
    y = np.zeros(3000)
    for t in range(3, 3000):
        y[t] = 1.2 * y[t - 1] - 0.6 * y[t - 2] + 0.1 * y[t - 3] + u[t] + 0.5 * u[t - 2]
    scan = order_scan(u[:2000], y[:2000], range(0, 6), validation=(u[2000:], y[2000:]))
    err = dict(zip(scan.orders.tolist(), scan.errors[:, 0], strict=True))
    assert all(err[n] < 1e-6 for n in (3, 4, 5))
    assert all(err[n] > 1.0 for n in (0, 1, 2))
    assert "order" in scan.table()


def test_order_scan_marks_a_diverging_order_instead_of_failing():
    # an unstable plant (pole 1.05) identified on a short record diverges on a long one
    rng = np.random.default_rng(4)
    u = rng.standard_normal(2200)
    y = np.zeros(2200)
    for t in range(1, 2200):
        y[t] = 1.05 * y[t - 1] + u[t]
    # the validation output only sets the initial conditions: the free run diverges regardless
    scan = order_scan(
        u[:200], y[:200] + 1e-3 * rng.standard_normal(200), [1, 2], validation=(u[200:], y[200:])
    )
    assert scan.diverged.all()
    assert np.all(np.isinf(scan.errors))
    assert "diverged" in scan.table()


def test_order_scan_rejects_empty_orders():
    with pytest.raises(ValueError, match="non-empty"):
        order_scan(np.ones(100), np.ones(100), [])


def test_scan_model_matches_a_direct_fit():
    rng = np.random.default_rng(1)
    u = rng.standard_normal(800)
    y = np.convolve(u, [0.5, 0.3, 0.1])[:800]
    scan = order_scan(u, y, [2])
    assert scan.n_terms[0] == Narx(order=2, degree=1).fit(u, y).n_terms_[0]
