"""SysIdentPy's lag convention, ``Narx(order=n, lags="sysidentpy")`` (issue 24, deliverable 3):
output and input lags 1..n, as SysIdentPy's ``ylag = xlag = n``, so that comparisons are like
for like.

Truth: the explicit form ``na=n, nb=n, nk=1`` (MATLAB's convention, documented independently),
the definition (no input at lag 0), and SysIdentPy's own regressor space when it is installed.
"""

from __future__ import annotations

import numpy as np
import pytest

from identification import IdentificationError, Narx


def _term_set(model):
    """Each term as a sorted tuple of (source, lag): source "y<i>" or "u<j>" (constant: ())."""
    ny = model.n_outputs_
    out = []
    for ch in model.channels_:
        terms = set()
        for row in ch.terms:
            factors = []
            for i in row[row > 0]:
                src, lag = ch.regressors[i - 1]
                factors.append((f"y{src}" if src < ny else f"u{src - ny}", int(lag)))
            terms.add(tuple(sorted(factors)))
        out.append(terms)
    return out


def test_sysidentpy_lags_are_the_explicit_na_nb_nk1_model_term_for_term():
    rng = np.random.default_rng(8)
    u = rng.standard_normal((600, 2))
    y = rng.standard_normal(600)
    ours = Narx(order=3, degree=2, lags="sysidentpy").fit(u, y)
    explicit = Narx(na=3, nb=3, nk=1, degree=2).fit(u, y)
    np.testing.assert_array_equal(ours.channels_[0].regressors, explicit.channels_[0].regressors)
    np.testing.assert_array_equal(ours.channels_[0].terms, explicit.channels_[0].terms)
    np.testing.assert_array_equal(ours.coef_[0], explicit.coef_[0])
    assert ours.term_names() == explicit.term_names()
    lags = ours.channels_[0].regressors
    assert set(map(tuple, lags)) == {(s, k) for s in range(3) for k in (1, 2, 3)}  # no lag 0
    text = Narx(order=3, degree=2).fit(u, y)  # the default is still the text's: lags 0..3
    assert {(1, 0), (2, 0)} <= set(map(tuple, text.channels_[0].regressors))


def test_sysidentpy_lags_are_saved_and_loaded(tmp_path):
    rng = np.random.default_rng(9)
    u, y = rng.standard_normal(400), rng.standard_normal(400)
    model = Narx(order=2, degree=2, lags="sysidentpy").fit(u, y)
    back = Narx.load(model.save(tmp_path / "m.npz"))
    assert back.lags == "sysidentpy" and back._params()["lags"] == "sysidentpy"
    assert back.term_names() == model.term_names()
    np.testing.assert_array_equal(back.simulate(u), model.simulate(u))


def test_bad_lag_conventions_are_refused():
    with pytest.raises(IdentificationError, match="lags must be 'text'"):
        Narx(order=2, lags="matlab")
    with pytest.raises(IdentificationError, match="applies to order"):
        Narx(na=2, nb=2, nk=1, lags="sysidentpy")


@pytest.mark.parametrize("nu", [1, 2])
def test_the_term_set_is_sysidentpys_regressor_space(nu):
    """SysIdentPy's candidate terms for ylag = xlag = n, degree L (with its constant term):
    codes 1000 + lag for y(k-lag), 2000 + 1000 j + lag for input j."""
    pytest.importorskip("sysidentpy")
    from sysidentpy.basis_function import Polynomial
    from sysidentpy.narmax_base import RegressorDictionary

    n, degree = 3, 2
    xlag = n if nu == 1 else [n] * nu
    codes = RegressorDictionary(
        xlag=xlag, ylag=n, basis_function=Polynomial(degree=degree)
    ).regressor_space(nu)
    theirs = set()
    for row in codes:
        factors = []
        for c in row[row > 0]:
            kind, lag = divmod(int(c), 1000)
            factors.append(("y0" if kind == 1 else f"u{kind - 2}", lag))
        theirs.add(tuple(sorted(factors)))
    rng = np.random.default_rng(10)
    model = Narx(order=n, degree=degree, lags="sysidentpy", constant=True)
    model.fit(rng.standard_normal((400, nu)), rng.standard_normal(400))
    assert _term_set(model)[0] == theirs
    assert model.n_terms_[0] == len(codes)
