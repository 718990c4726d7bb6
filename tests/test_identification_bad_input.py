"""Every bad input to the identification API raises with a message that says what to change."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from identification import (
    Arx,
    IdentificationError,
    InsufficientDataError,
    Narx,
    RankDeficiencyWarning,
)


@pytest.fixture
def data():
    rng = np.random.default_rng(0)
    return rng.standard_normal((300, 2)), rng.standard_normal((300, 1))


def test_nan_in_input(data):
    u, y = data
    u[17, 1] = np.nan
    with pytest.raises(
        IdentificationError, match=r"u contains NaN or inf \(first at sample 17, channel 1\)"
    ):
        Narx(order=2).fit(u, y)


def test_inf_in_output(data):
    u, y = data
    y[5, 0] = np.inf
    with pytest.raises(IdentificationError, match="y contains NaN or inf"):
        Narx(order=2).fit(u, y)


def test_mismatched_lengths(data):
    u, y = data
    with pytest.raises(IdentificationError, match="u has 300 samples but y has 299"):
        Narx(order=2).fit(u, y[:-1])


def test_three_dimensional_input(data):
    u, y = data
    with pytest.raises(IdentificationError, match=r"1-D .* or 2-D"):
        Narx(order=2).fit(u[:, :, None], y)


def test_time_not_on_axis_0(data):
    u, y = data
    with pytest.raises(IdentificationError, match=r"did you mean u\.T"):
        Narx(order=2).fit(u.T, y)


def test_one_dimensional_signals_are_one_channel(data):
    u, y = data
    m = Narx(order=1, degree=1).fit(u[:, 0], y[:, 0])
    assert (m.n_inputs_, m.n_outputs_) == (1, 1)
    assert m.simulate(u[:, 0]).shape == (300, 1)


def test_fewer_usable_samples_than_terms(data):
    u, y = data
    # order 4, degree 3, 2 inputs, 1 output: R = 4 + 2*5 = 14 -> C(17, 3) - 1 = 679 terms
    with pytest.raises(InsufficientDataError, match="679 terms but only 296 usable samples"):
        Narx(order=4, degree=3).fit(u, y)


def test_the_closed_form_term_count_is_what_the_fit_needs():
    """Narx.term_count / max_lag (issue 25: a record's length is checked up front with them)
    agree with the fit's own refusal: 679 terms (C(17, 3) - 1) after a largest lag of 4."""
    m = Narx(order=4, degree=3)
    assert list(m.term_count(1, 2)) == [679] and m.max_lag(1, 2) == 4
    rng = np.random.default_rng(1)
    need = 679 + 4
    with pytest.raises(InsufficientDataError, match="679 terms"):
        Narx(order=4, degree=3).fit(rng.standard_normal((need - 1, 2)), rng.standard_normal(need - 1))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # a model that large on white noise is no model: no matter
        try:
            Narx(order=4, degree=3).fit(rng.standard_normal((need, 2)), rng.standard_normal(need))
        except InsufficientDataError:  # pragma: no cover - the failure this test guards
            pytest.fail("a record of term count + largest lag samples was refused as too short")
        except IdentificationError:
            pass  # fitted; its stability contract may refuse a random model, which is not size


def test_negative_order():
    with pytest.raises(IdentificationError, match="order must be >= 0"):
        Narx(order=-1)


def test_degree_below_one():
    with pytest.raises(IdentificationError, match="degree must be >= 1"):
        Narx(order=2, degree=0)


def test_unknown_solver():
    with pytest.raises(IdentificationError, match="unknown solver 'chol'"):
        Narx(order=2, solver="chol")


def test_unknown_kind():
    with pytest.raises(IdentificationError, match="unknown term kind"):
        Narx(order=2, kind="cubic")


def test_order_and_explicit_orders_together():
    with pytest.raises(IdentificationError, match="either order or na/nb/nk"):
        Narx(order=2, na=2, nb=2)
    with pytest.raises(IdentificationError, match="give the model order"):
        Narx()
    with pytest.raises(IdentificationError, match="both na and nb"):
        Narx(na=2)


def test_per_channel_order_count_must_match_outputs(data):
    u, y = data
    with pytest.raises(IdentificationError, match="order has 2 values but there are 1 output"):
        Narx(order=[2, 3]).fit(u, y)


def test_simulate_checks_input_channels_and_initial_conditions(data):
    u, y = data
    m = Arx(order=2).fit(u, y)
    with pytest.raises(IdentificationError, match="u has 1 channel\\(s\\) but the model expects 2"):
        m.simulate(u[:, :1])
    with pytest.raises(IdentificationError, match=r"y0 must have shape"):
        m.simulate(u, y0=np.zeros((1, 1)))  # shorter than max_lag_ = 2
    with pytest.raises(IdentificationError, match=r"y0 must have shape"):
        m.simulate(u, y0=np.zeros((3, 2)))  # two output channels for one
    with pytest.raises(IdentificationError, match="bound must be positive"):
        m.simulate(u, bound=-1.0)


def test_unfitted_model():
    with pytest.raises(IdentificationError, match="not fitted yet"):
        Narx(order=2).simulate(np.ones((10, 1)))


def test_invalid_forward_selection_options():
    with pytest.raises(IdentificationError, match="n_terms"):
        Narx(order=2, n_terms=0)
    with pytest.raises(IdentificationError, match="err_tol"):
        Narx(order=2, err_tol=1.5)


def test_rank_deficient_regression_warns_with_rank(data):
    u, y = data
    u2 = np.column_stack([u[:, 0], 2.0 * u[:, 0]])  # duplicated input channel
    with pytest.warns(RankDeficiencyWarning, match=r"effective rank 5 of 8 terms"):
        Arx(order=2).fit(u2, y)  # 2 output lags + 2x3 input lags, 3 of them duplicates


def test_load_rejects_foreign_files(tmp_path):
    path = tmp_path / "other.npz"
    np.savez(path, a=np.ones(3))
    with pytest.raises(IdentificationError, match="not a vrig identification model"):
        Narx.load(path)
    with pytest.raises(FileNotFoundError):
        Narx.load(tmp_path / "missing.npz")
