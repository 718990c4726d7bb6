"""Inverse models and delay estimation (Section 1.6; lead for rig delay)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import signal

from identification import (
    Arx,
    IdentificationError,
    InverseModel,
    Narx,
    band_limited_noise,
    estimate_delay,
    metrics,
)

# minimum-phase G(q) = B(q)/A(q): zeros at 0.5 and -0.3, poles 0.9 e^{±0.6j}
B = np.poly([0.5, -0.3]) * 0.4
A = np.real(np.poly([0.9 * np.exp(0.6j), 0.9 * np.exp(-0.6j)]))
DELAY = 3


def _plant(u):
    return signal.lfilter(np.concatenate([np.zeros(DELAY), B]), A, u, axis=0)


def test_estimate_delay_finds_pure_delay():
    u = band_limited_noise(5000, 1, cutoff=0.6, seed=1)
    assert estimate_delay(u, _plant(u)) == DELAY


def test_estimate_delay_mimo_takes_earliest_pair():
    u = band_limited_noise(5000, 2, cutoff=0.6, seed=2)
    y = np.column_stack(
        [
            signal.lfilter([0, 0, 0, 0, 1.0], [1, -0.5], u[:, 0])
            + signal.lfilter([0, 0, 1.0], [1], u[:, 1]),
            signal.lfilter([0, 0, 0, 0, 0, 1.0], [1], u[:, 1]),
        ]
    )
    assert estimate_delay(u, y) == 2


# noise-free data and a model order above the plant's: a rank-deficient regression is expected
@pytest.mark.filterwarnings("ignore::identification.errors.RankDeficiencyWarning")
def test_inverse_arx_recovers_the_drive_of_a_minimum_phase_system_with_delay():
    drive_id = band_limited_noise(6000, 1, cutoff=0.5, seed=3)
    inv = InverseModel(Arx(order=4), lead="auto").fit(drive_id, _plant(drive_id))
    assert inv.lead_ == DELAY
    drive = band_limited_noise(4000, 1, cutoff=0.4, seed=4)
    recovered = inv.simulate(_plant(drive))
    assert recovered.shape == drive.shape
    assert metrics.qantim_fit_dc(drive, recovered)[0] < 1.0


def test_without_the_lead_the_inverse_cannot_reproduce_the_drive():
    drive_id = band_limited_noise(6000, 1, cutoff=0.5, seed=3)
    inv = InverseModel(Arx(order=4), lead=0).fit(drive_id, _plant(drive_id))
    drive = band_limited_noise(4000, 1, cutoff=0.4, seed=4)
    try:
        err = metrics.qantim_fit_dc(drive, inv.simulate(_plant(drive), bound=np.inf))[0]
    except ArithmeticError:
        err = np.inf
    assert err > 20.0


def _quadratic_plant(u):
    # y(t) = 0.6 y(t-1) + 0.5 u(t-1) + 0.1 y(t-1)^2: its inverse is the polynomial
    # u(t) = 2 y(t+1) - 1.2 y(t) - 0.2 y(t)^2, a quadratic NARX with lead 1
    y = np.zeros(len(u))
    for t in range(1, len(u)):
        y[t] = 0.6 * y[t - 1] + 0.5 * u[t - 1] + 0.1 * y[t - 1] ** 2
    return y


@pytest.mark.filterwarnings("ignore::identification.errors.RankDeficiencyWarning")
def test_inverse_narx_is_exact_when_the_inverse_is_polynomial():
    drive_id = 0.5 * band_limited_noise(4000, 1, cutoff=0.4, seed=5)[:, 0]
    inv = InverseModel(Narx(order=2, degree=2), lead="auto").fit(
        drive_id, _quadratic_plant(drive_id)
    )
    assert inv.lead_ == 1
    coef = dict(zip(inv.model.term_names()[0], inv.model.coef_[0], strict=True))
    assert coef["u1(t-1)*u1(t-1)"] == pytest.approx(-0.2, abs=1e-9)  # u1 is the response y(t)
    drive = 0.4 * band_limited_noise(3000, 1, cutoff=0.3, seed=6)[:, 0]
    recovered = inv.simulate(_quadratic_plant(drive))[:, 0]
    np.testing.assert_allclose(recovered[:-1], drive[:-1], atol=1e-9)


@pytest.mark.filterwarnings("ignore::identification.errors.RankDeficiencyWarning")
def test_a_searched_inverse_finds_the_polynomial_inverse_and_its_lead():
    """The same plant: its inverse is a quadratic NARX with lead 1 and order 1. A NarxSearch
    inverse (the lead chosen by its ARX stand-in first) recovers the drive to round-off."""
    from identification import NarxSearch

    drive_id = 0.5 * band_limited_noise(4000, 1, cutoff=0.4, seed=5)[:, 0]
    search = NarxSearch(budget=None, orders=(1, 2), degrees=(1, 2), kinds=("full",))
    inv = InverseModel(search, lead="auto").fit(drive_id, _quadratic_plant(drive_id))
    assert inv.lead_ == 1 and isinstance(inv.model, Narx)
    assert inv.search_.best_result_.candidate.degree == 2
    drive = 0.4 * band_limited_noise(3000, 1, cutoff=0.3, seed=6)[:, 0]
    recovered = inv.simulate(_quadratic_plant(drive))[:, 0]
    np.testing.assert_allclose(recovered[:-1], drive[:-1], atol=1e-8)


def test_inverse_model_bad_input():
    with pytest.raises(IdentificationError, match="lead"):
        InverseModel(Arx(order=2), lead=-1)
    with pytest.raises(IdentificationError, match="Narx or Arx"):
        InverseModel("arx")
    with pytest.raises(IdentificationError, match="not fitted"):
        InverseModel(Arx(order=2)).simulate(np.ones(10))
    with pytest.raises(IdentificationError, match="samples"):
        estimate_delay(np.ones(20), np.ones(20), max_lag=10)
    with pytest.raises(IdentificationError, match="lead_domain"):
        InverseModel(Arx(order=2), lead_domain="frequency")


@pytest.mark.filterwarnings("ignore::identification.errors.RankDeficiencyWarning")
def test_auto_lead_judged_in_the_response_domain_for_a_non_square_rig():
    """Two drives, three responses (one a mix of both), pure delay 3 on every path: the
    response-domain ranking runs (forward model drive -> response) and finds the delay, and
    the inverse reproduces a fresh drive."""
    def rig(u):
        y1, y2 = _plant(u[:, 0]), _plant(u[:, 1])
        return np.column_stack([y1, y2, 0.5 * y1 + 0.3 * y2])

    drive_id = band_limited_noise(6000, 2, cutoff=0.5, seed=5)
    inv = InverseModel(Arx(order=4), lead="auto", lead_domain="response")
    inv.fit(drive_id, rig(drive_id))
    assert inv.lead_score_domain_ == "response"
    assert inv.lead_ == DELAY
    drive = band_limited_noise(4000, 2, cutoff=0.4, seed=6)
    assert np.all(metrics.qantim_fit_dc(drive, inv.simulate(rig(drive))) < 1.0)


# --- pole contraction (inverse models with near-integrator poles)


def _ar2(poles, u):
    return signal.lfilter([0.0, 1.0], np.real(np.poly(poles)), u)


def test_pole_radius_is_the_generating_systems_largest_pole():
    u = band_limited_noise(4000, 1, cutoff=0.8, seed=5)[:, 0]
    poles = [0.95 * np.exp(0.3j), 0.95 * np.exp(-0.3j)]
    m = Arx(order=2).fit(u, _ar2(poles, u))
    assert m.pole_radius() == pytest.approx(0.95, abs=1e-6)


def test_stabilise_scales_every_pole_by_the_same_factor():
    u = band_limited_noise(4000, 1, cutoff=0.8, seed=6)[:, 0]
    m = Arx(order=2).fit(u, _ar2([0.9, 0.5], u))
    assert m.stabilise(0.95) == 1.0  # already inside: untouched
    rho = m.stabilise(0.6)
    assert rho == pytest.approx(0.6 / 0.9, rel=1e-6)
    # contracted poles: 0.9 rho and 0.5 rho -> the free run equals the filter with those poles
    np.testing.assert_allclose(
        m.simulate(u)[:, 0], _ar2([0.9 * rho, 0.5 * rho], u), rtol=1e-6, atol=1e-9
    )


def test_an_unstable_inverse_is_contracted_to_a_bounded_one():
    # the plant is a differentiator (zero at z = 1): its exact inverse integrates, a pole on the
    # unit circle that noise pushes outside; the contracted inverse stays bounded and still
    # reproduces the band-limited drive
    rng = np.random.default_rng(7)
    drive = band_limited_noise(6000, 1, cutoff=0.3, seed=7)
    response = np.diff(drive, axis=0, prepend=0.0) + 1e-3 * rng.normal(size=drive.shape)
    raw = InverseModel(Arx(order=2), lead=0, max_radius=None).fit(drive, response)
    assert raw.model.pole_radius() > 0.99
    inv = InverseModel(Arx(order=2), lead=0, max_radius=0.99).fit(drive, response)
    assert inv.model.pole_radius() <= 0.99 + 1e-9
    assert inv.contraction_ <= 1.0
    # a fresh record: above the leaky integrator's corner the drive is reproduced
    new = band_limited_noise(20000, 1, cutoff=0.3, seed=8)
    sim = inv.simulate(np.diff(new, axis=0, prepend=0.0))
    hp = signal.butter(4, 0.02, btype="highpass", output="sos")
    fit = metrics.qantim_fit_dc(
        signal.sosfiltfilt(hp, new, axis=0), signal.sosfiltfilt(hp, sim, axis=0)
    )
    assert fit[0] < 10.0
    with pytest.raises(IdentificationError, match="max_radius"):
        InverseModel(Arx(order=2), max_radius=1.5)


def test_poles_of_a_model_linear_in_its_outputs_and_none_for_output_products():
    u = band_limited_noise(4000, 1, cutoff=0.8, seed=9)[:, 0]
    y = np.zeros_like(u)
    for t in range(1, u.size):  # y(t) = 0.9 y(t-1) + u(t-1) + 0.5 u(t-1)^2
        y[t] = 0.9 * y[t - 1] + u[t - 1] + 0.5 * u[t - 1] ** 2
    m = Narx(order=1, degree=2, kind="input-polynomial").fit(u, y)
    assert m.is_output_affine()
    assert m.pole_radius() == pytest.approx(0.9, abs=1e-6)
    full = Narx(order=1, degree=2).fit(u, y)
    assert not full.is_output_affine()
    with pytest.raises(IdentificationError, match="products with past outputs"):
        full.pole_radius()
