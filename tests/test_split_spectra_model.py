"""Forward split-spectra model (§5.5.3, §6.3) against a system whose bands are known exactly.

The synthetic system (2 inputs, 3 outputs: MIMO and non-square) is
``y = C u_lo + Q [u1_lo^2, u1_lo u2_lo, u2_lo^2] + H(u_hi)``: a static quadratic map of a
slow input band (content up to 2 Hz, so the quadratic reaches 4 Hz) plus a linear ARX(2)
filter of a fast band (300-450 Hz), at fs = 1000 Hz, split at 50 Hz. Both bands are tapered to
zero at the record's ends by a C-infinity window (no edge transient in the zero-phase filter).
With an order-8 split the bands separate to (4/50)^16 ~ 3e-18 and (50/300)^16 ~ 4e-13, so
``Narx(order=0, degree=2)`` must recover C and Q and ``Arx(order=2)`` the ARX coefficients to
round-off, and the sum must reproduce y.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy import signal, special

from identification import (
    Arx,
    IdentificationError,
    InsufficientDataError,
    ModelFileError,
    Narx,
    SplitSpectraModel,
)
from identification.split_spectra import band_split

FS = 1000.0  # Hz
N = 20_000
SPLIT = 50.0  # Hz
C = np.array([[1.0, -0.5], [0.3, 0.8], [-0.2, 0.1]])  # low band, linear part (3 x 2)
Q = np.array([[0.4, 0.1, -0.3], [0.0, -0.6, 0.2], [0.5, 0.3, 0.1]])  # u1^2, u1 u2, u2^2
A = np.array([[1.0, -1.2, 0.5], [1.0, -0.5, 0.3], [1.0, 0.4, 0.2]])  # per-output denominators
B = np.array(  # B[k, j]: numerator from input j to output k, lags 0..2
    [
        [[0.2, 0.1, 0.05], [0.0, 0.3, -0.1]],
        [[0.5, 0.0, 0.0], [0.1, 0.1, 0.1]],
        [[0.0, -0.2, 0.1], [0.3, 0.0, 0.0]],
    ]
)


def _band_noise(lo, hi, seed):
    """Two channels of Gaussian noise with content exactly in [lo, hi] Hz, unit std."""
    rng = np.random.default_rng(seed)
    f = np.fft.rfftfreq(N, 1.0 / FS)
    band = (f >= lo) & (f <= hi)
    spec = np.zeros((f.size, 2), complex)
    spec[band] = rng.standard_normal((band.sum(), 2)) + 1j * rng.standard_normal((band.sum(), 2))
    x = np.fft.irfft(spec, n=N, axis=0)
    return x / x.std(axis=0)


def _taper(ramp=3000, quiet=1000):
    """Zero for ``quiet`` samples at each end, C-infinity (Planck) ramps, 1 in between."""
    t = np.arange(1, ramp) / ramp
    s = special.expit(1.0 / (1.0 - t) - 1.0 / t)
    w = np.ones(N)
    w[:quiet] = w[-quiet:] = 0.0
    w[quiet] = w[-quiet - 1] = 0.0
    w[quiet + 1 : quiet + ramp] = s
    w[-quiet - ramp : -quiet - 1] = s[::-1]
    return w


@pytest.fixture(scope="module")
def system():
    w = _taper()[:, None]
    u_lo = _band_noise(0.0, 2.0, 1) * w
    u_hi = 0.5 * _band_noise(300.0, 450.0, 2) * w
    quad = np.column_stack([u_lo[:, 0] ** 2, u_lo[:, 0] * u_lo[:, 1], u_lo[:, 1] ** 2])
    y_lo = u_lo @ C.T + quad @ Q.T
    y_hi = np.column_stack(
        [sum(signal.lfilter(B[k, j], A[k], u_hi[:, j]) for j in range(2)) for k in range(3)]
    )
    return u_lo + u_hi, y_lo + y_hi, u_lo, y_lo


def _coef(model, k):
    return dict(zip(model.term_names()[k], model.coef_[k], strict=True))


def test_split_model_is_exact_on_static_quadratic_low_and_linear_high_band(system):
    u, y, _, _ = system
    m = SplitSpectraModel(SPLIT, FS, filter_order=8).fit(u, y)
    assert isinstance(m.low_, Narx) and isinstance(m.high_, Arx) and m.factor_ == 1
    assert (m.n_inputs_, m.n_outputs_) == (2, 3)
    for k in range(3):  # the static quadratic map, term by term
        lo = _coef(m.low_, k)
        expected = {
            "u1(t)": C[k, 0],
            "u2(t)": C[k, 1],
            "u1(t)*u1(t)": Q[k, 0],
            "u1(t)*u2(t)": Q[k, 1],
            "u2(t)*u2(t)": Q[k, 2],
        }
        assert lo.keys() == expected.keys()
        for name, value in expected.items():
            assert lo[name] == pytest.approx(value, abs=1e-9), (k, name)
        hi = _coef(m.high_, k)  # the ARX(2): own lags -a, cross-output lags 0, inputs b
        for lag in (1, 2):
            assert hi[f"y{k + 1}(t-{lag})"] == pytest.approx(-A[k, lag], abs=1e-9)
            for other in set(range(3)) - {k}:
                assert hi[f"y{other + 1}(t-{lag})"] == pytest.approx(0.0, abs=1e-9)
        for j in range(2):
            for lag in range(3):
                name = f"u{j + 1}(t)" if lag == 0 else f"u{j + 1}(t-{lag})"
                assert hi[name] == pytest.approx(B[k, j, lag], abs=1e-9), (k, name)
    scale = np.abs(y).max()
    assert np.abs(m.simulate(u) - y).max() < 1e-10 * scale
    assert np.abs(m.predict(u, y) - y).max() < 1e-10 * scale


def test_low_band_at_its_own_sample_rate(system):
    u, y, _, _ = system
    m = SplitSpectraModel(SPLIT, FS, filter_order=8, decimate_low=True).fit(u, y)
    assert m.factor_ == 2  # the largest q with FS / q >= 10 x 50 Hz
    # a static map is rate-independent: the decimated low band recovers the same coefficients
    for k in range(3):
        lo = _coef(m.low_, k)
        assert lo["u1(t)*u2(t)"] == pytest.approx(Q[k, 1], abs=1e-9)
        assert lo["u2(t)"] == pytest.approx(C[k, 1], abs=1e-9)
    # the error left is the interpolation back to FS (documented: within 5e-7 of the
    # amplitude for content up to a tenth of the low rate; here it is far below that)
    assert np.abs(m.simulate(u) - y).max() < 5e-7 * np.abs(y).max()
    assert SplitSpectraModel(SPLIT, FS, decimate_low=4).factor == 4
    with pytest.raises(IdentificationError, match="aliases"):
        SplitSpectraModel(SPLIT, FS, decimate_low=10)  # 100 Hz rate: Nyquist at the split


def test_save_load_round_trip_is_exact(system, tmp_path):
    u, y, _, _ = system
    y = y + 0.01 * np.random.default_rng(5).standard_normal(y.shape)  # a non-degenerate fit
    for decimate in (False, True):
        low = Narx(order=1, degree=2, kind="input-polynomial", max_radius=0.98)  # lags: its rate
        m = SplitSpectraModel(SPLIT, FS, low, Arx(order=2), decimate_low=decimate)
        m.fit(u[:6000], y[:6000])
        path = m.save(tmp_path / f"split-{decimate}")
        assert path.name.endswith(".npz") and [p.name for p in tmp_path.iterdir()].count(
            path.name
        ) == 1
        back = SplitSpectraModel.load(path)
        assert (back.split_hz, back.fs, back.filter_order, back.factor_) == (
            m.split_hz, m.fs, m.filter_order, m.factor_
        )
        assert back.output_names_ == m.output_names_ and back.max_lag_ == m.max_lag_
        assert np.array_equal(back.simulate(u[6000:]), m.simulate(u[6000:]))
    with pytest.raises(ModelFileError, match="SplitSpectraModel"):
        Narx.load(path)  # a composite file is not a Narx file
    truncated = tmp_path / "cut.npz"
    truncated.write_bytes(path.read_bytes()[:300])
    with pytest.raises(ModelFileError):
        SplitSpectraModel.load(truncated)


def test_clear_errors(system):
    u, y, _, _ = system
    for bad in (0.0, -1.0, FS / 2, 600.0, np.inf, np.nan):
        with pytest.raises(IdentificationError, match=r"split_hz must lie in \(0, fs/2"):
            SplitSpectraModel(bad, FS)
    with pytest.raises(IdentificationError, match="fs must be"):
        SplitSpectraModel(10.0, 0.0)
    with pytest.raises(IdentificationError, match="Arx/Narx"):
        SplitSpectraModel(10.0, FS, low="narx")
    with pytest.raises(InsufficientDataError, match="too short for the order-4 split filter"):
        SplitSpectraModel(SPLIT, FS).fit(u[:15], y[:15])
    m = SplitSpectraModel(SPLIT, FS).fit(u, y)
    with pytest.raises(IdentificationError, match="fitted with 2 inputs"):
        m.simulate(u[:1000, :1])
    with pytest.raises(IdentificationError, match="not fitted"):
        SplitSpectraModel(SPLIT, FS).simulate(u)


def test_band_split_is_complementary_and_shared_with_vrig():
    from vrig.processing import band_split as vrig_band_split
    from vrig.timehistory import TimeHistory

    x = np.random.default_rng(3).standard_normal((4000, 2))
    low, high = band_split(x, 12.0, 200.0)
    np.testing.assert_allclose(low + high, x, rtol=0, atol=1e-14 * np.abs(x).max())
    th_lo, th_hi = vrig_band_split(TimeHistory(x, 200.0), 12.0)  # the reconstruction's split
    assert np.array_equal(th_lo.data, low) and np.array_equal(th_hi.data, high)
