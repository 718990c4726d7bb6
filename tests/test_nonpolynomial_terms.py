"""Non-polynomial regressor functions (§7.4.1: dead band, saturation, |x|, x|x|).

Every generating system here is written out as an explicit Python recursion in the test, with
its own definitions of the static functions, independent of the package's kernels.
"""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest
from scipy import signal

from identification import (
    Arx,
    ChannelStructure,
    IdentificationError,
    Narx,
    regression_matrix,
)


# ----------------------------------------------------------------- the functions, written out
def deadzone(x: float, b: float) -> float:
    if x > b:
        return x - b
    if x < -b:
        return x + b
    return 0.0


def saturation(x: float, b: float) -> float:
    return max(-b, min(b, x))


def sign_square(x: float) -> float:
    return x * abs(x)


def _coefs(model, k=0) -> dict[str, float]:
    return dict(zip(model.term_names()[k], model.coef_[k], strict=True))


def _assert_coefs(model, truth: dict[str, float], k=0, atol=1e-8):
    """Every term named in ``truth`` has that coefficient, every other term is zero."""
    got = _coefs(model, k)
    assert set(truth) <= set(got), sorted(set(truth) - set(got))
    for name, c in got.items():
        assert c == pytest.approx(truth.get(name, 0.0), abs=atol), name


# ----------------------------------------------------------------- recovery and free run
B_DZ = 0.3


def _siso_system(u: np.ndarray, y0=(0.0, 0.0)) -> np.ndarray:
    """y(t) = 0.5 y(t-1) - 0.2 y(t-2) + 0.8 u(t) + 0.3 u(t-1) + 0.1 y(t-1) u(t)
    + 0.6 deadzone(u(t-1), 0.3) + 0.4 |u(t)| - 0.15 u(t-1)|u(t-1)|."""
    N = u.shape[0]
    y = np.zeros(N)
    y[:2] = y0
    for t in range(2, N):
        y[t] = (
            0.5 * y[t - 1]
            - 0.2 * y[t - 2]
            + 0.8 * u[t]
            + 0.3 * u[t - 1]
            + 0.1 * y[t - 1] * u[t]
            + 0.6 * deadzone(u[t - 1], B_DZ)
            + 0.4 * abs(u[t])
            - 0.15 * sign_square(u[t - 1])
        )
    return y


SISO_TRUTH = {
    "y1(t-1)": 0.5,
    "y1(t-2)": -0.2,
    "u1(t)": 0.8,
    "u1(t-1)": 0.3,
    "y1(t-1)*u1(t)": 0.1,
    "deadzone(u1(t-1), 0.3)": 0.6,
    "abs(u1(t))": 0.4,
    "sign_square(u1(t-1))": -0.15,
}


def test_deadzone_abs_sign_square_model_is_recovered_and_simulated_exactly():
    u = np.random.default_rng(1).standard_normal(3000)
    y = _siso_system(u, y0=(0.2, -0.1))
    m = Narx(na=2, nb=2, nk=0, degree=2, functions=["abs", "sign_square", ("deadzone", B_DZ)])
    m.fit(u, y)
    # 14 quadratic terms of 4 regressors, then 3 functions x 2 input regressors
    assert m.n_terms_.tolist() == [14 + 6]
    assert m.term_names()[0][14:] == [
        "abs(u1(t))",
        "abs(u1(t-1))",
        "sign_square(u1(t))",
        "sign_square(u1(t-1))",
        "deadzone(u1(t), 0.3)",
        "deadzone(u1(t-1), 0.3)",
    ]
    _assert_coefs(m, SISO_TRUTH)
    np.testing.assert_allclose(m.simulate(u, y0=y[:2]), y[:, None], rtol=0, atol=1e-10)
    # zero past: the recursion from y(-1) = y(-2) = 0 and u(-1) = 0
    padded = _siso_system(np.concatenate([[0.0, 0.0], u]))[2:]
    np.testing.assert_allclose(m.simulate(u), padded[:, None], rtol=0, atol=1e-10)


def _output_saturation_system(u: np.ndarray, y_past=(0.0,)) -> np.ndarray:
    """y(t) = 0.3 y(t-1) + 0.5 sat(y(t-1), 0.5) + u(t) - 0.4 deadzone(u(t), 0.2)."""
    y = np.zeros(u.shape[0])
    y[0] = y_past[0]
    for t in range(1, u.shape[0]):
        y[t] = 0.3 * y[t - 1] + 0.5 * saturation(y[t - 1], 0.5) + u[t] - 0.4 * deadzone(u[t], 0.2)
    return y


def test_saturated_output_feedback_is_recovered_and_simulated_exactly():
    u = np.random.default_rng(2).standard_normal(2500)
    y = _output_saturation_system(u, y_past=(0.7,))
    m = Narx(
        na=1,
        nb=1,
        degree=1,
        functions=[("saturation", 0.5), ("deadzone", 0.2)],
        function_sources="all",
    ).fit(u, y)
    assert m.term_names()[0] == [
        "y1(t-1)",
        "u1(t)",
        "saturation(y1(t-1), 0.5)",
        "saturation(u1(t), 0.5)",
        "deadzone(y1(t-1), 0.2)",
        "deadzone(u1(t), 0.2)",
    ]
    truth = {"y1(t-1)": 0.3, "saturation(y1(t-1), 0.5)": 0.5, "u1(t)": 1.0}
    _assert_coefs(m, truth | {"deadzone(u1(t), 0.2)": -0.4})
    np.testing.assert_allclose(m.simulate(u, y0=y[:1]), y[:, None], rtol=0, atol=1e-10)
    fresh = 1.5 * np.random.default_rng(3).standard_normal(1000)
    expected = _output_saturation_system(np.concatenate([[0.0], fresh]))[1:]
    np.testing.assert_allclose(m.simulate(fresh), expected[:, None], rtol=0, atol=1e-10)
    np.testing.assert_allclose(m.predict(u, y)[1:], y[1:, None], rtol=0, atol=1e-10)
    assert not m.is_output_affine()
    with pytest.raises(IdentificationError, match="functions of past outputs"):
        m.pole_radius()
    with pytest.raises(IdentificationError, match="functions of past outputs"):
        m.stabilise()


def test_mimo_two_outputs_two_inputs():
    rng = np.random.default_rng(4)
    N = 3000
    u = rng.standard_normal((N, 2))
    y = np.zeros((N, 2))
    for t in range(1, N):
        y1, y2 = y[t - 1]
        u1, u2 = u[t]
        p1, p2 = u[t - 1]
        y[t, 0] = 0.4 * y1 + 0.2 * y2 + u1 + 0.5 * abs(p2) + 0.3 * saturation(y2, 0.8)
        y[t, 1] = -0.3 * y1 + 0.5 * y2 + 0.7 * p1 - 0.2 * u2 + 0.1 * y1 * u2 - 0.25 * abs(u1)
    m = Narx(order=1, degree=2, functions=["abs", ("saturation", 0.8)], function_sources="all")
    m.fit(u, y, output_names=["a", "b"], input_names=["f", "g"])
    # 6 regressors (a, b at t-1; f, g at t, t-1): 6 + 21 quadratic terms, 2 x 6 function terms
    assert m.n_terms_.tolist() == [39, 39]
    assert m.channels_[0].same_as(m.channels_[1])
    _assert_coefs(
        m,
        {
            "a(t-1)": 0.4,
            "b(t-1)": 0.2,
            "f(t)": 1.0,
            "abs(g(t-1))": 0.5,
            "saturation(b(t-1), 0.8)": 0.3,
        },
        k=0,
    )
    _assert_coefs(
        m,
        {"a(t-1)": -0.3, "b(t-1)": 0.5, "f(t-1)": 0.7, "g(t)": -0.2, "a(t-1)*g(t)": 0.1}
        | {"abs(f(t))": -0.25},
        k=1,
    )
    np.testing.assert_allclose(m.simulate(u, y0=y[:1]), y, rtol=0, atol=1e-10)
    text = m.describe()
    assert "regressor functions ['abs', ('saturation', 0.8)] on all" in text
    assert "12 function terms (abs, saturation)" in text


def test_auto_deadzone_forward_selection_picks_the_true_breakpoint():
    u = 2.0 * np.random.default_rng(5).standard_normal(4000)
    b_true = 0.5 * np.std(u)  # the middle one of the documented candidates 0.25, 0.5, 1.0 x std
    y = np.zeros_like(u)
    for t in range(1, u.shape[0]):
        y[t] = 0.5 * y[t - 1] + u[t] + 0.8 * deadzone(u[t - 1], b_true)
    m = Narx(na=1, nb=2, degree=1, functions=[("deadzone", "auto")], n_terms=3).fit(u, y)
    ch = m.channels_[0]
    candidates = np.sort(ch.breakpoints[ch.functions == 2])
    np.testing.assert_allclose(candidates, np.repeat(np.array([0.25, 0.5, 1.0]) * np.std(u), 2))
    chosen = [
        [*ch.regressors[row[-1] - 1].tolist(), ch.breakpoints[row[-1] - 1]] for row in ch.terms
    ]
    assert len(chosen) == 3
    assert [ny_src_lag_b for ny_src_lag_b in chosen if ny_src_lag_b[2] > 0] == [
        [1, 1, pytest.approx(b_true, rel=1e-12)]
    ]
    coef = {(c[0], c[1], c[2] > 0): v for c, v in zip(chosen, m.coef_[0], strict=True)}
    assert coef == {
        (0, 1, False): pytest.approx(0.5, abs=1e-8),
        (1, 0, False): pytest.approx(1.0, abs=1e-8),
        (1, 1, True): pytest.approx(0.8, abs=1e-8),
    }
    np.testing.assert_allclose(m.simulate(u, y0=y[:1]), y[:, None], rtol=0, atol=1e-10)
    # functions of inputs only: the free run stays linear in the past output, pole at 0.5
    assert m.is_output_affine()
    assert m.pole_radius() == pytest.approx(0.5, abs=1e-8)


def test_auto_breakpoints_skip_a_constant_source():
    rng = np.random.default_rng(12)
    u = np.column_stack([rng.standard_normal(500), np.ones(500)])  # u2 has zero deviation
    y = rng.standard_normal(500)
    m = Narx(na=1, nb=1, degree=1, functions=[("saturation", "auto")]).fit(u, y)
    ch = m.channels_[0]
    s = np.std(u[:, 0])
    assert m.term_names()[0][3:] == [f"saturation(u1(t), {f * s:.6g})" for f in (0.25, 0.5, 1.0)]
    assert ch.regressors[ch.functions != 0].tolist() == [[1, 0]] * 3


@pytest.mark.parametrize("kind", ["full", "pure", "quasi-static", "input-polynomial"])
@pytest.mark.parametrize("explicit", [False, True])
def test_every_term_kind_with_constant_and_either_order_form(kind, explicit):
    rng = np.random.default_rng(6)
    u = rng.standard_normal(2000)
    y = np.zeros_like(u)
    for t in range(2, u.shape[0]):
        y[t] = 0.2 + 0.6 * y[t - 1] - 0.1 * y[t - 2] + u[t] - 0.3 * abs(u[t - 2])
        y[t] += 0.5 * deadzone(u[t - 1], 0.4) + 0.2 * u[t] ** 2
    orders = {"na": 2, "nb": 3, "nk": 0} if explicit else {"order": 2}
    specs = ["abs", ("deadzone", 0.4), ("saturation", "auto")]
    m = Narx(degree=2, kind=kind, constant=True, functions=specs, **orders).fit(u, y)
    plain = Narx(degree=2, kind=kind, constant=True, **orders).fit(u, y)
    # 3 input regressors (u(t), u(t-1), u(t-2)) x (1 + 1 + 3 breakpoints) linear terms appended
    assert m.n_terms_[0] == plain.n_terms_[0] + 3 * 5
    assert m.term_names()[0][: plain.n_terms_[0]] == plain.term_names()[0]
    assert all(ch.degree == 2 for ch in m.channels_)
    truth = {"1": 0.2, "y1(t-1)": 0.6, "y1(t-2)": -0.1, "u1(t)": 1.0, "u1(t)*u1(t)": 0.2}
    _assert_coefs(m, truth | {"abs(u1(t-2))": -0.3, "deadzone(u1(t-1), 0.4)": 0.5})
    np.testing.assert_allclose(m.simulate(u, y0=y[:2]), y[:, None], rtol=0, atol=1e-10)


# ----------------------------------------------------------------- regression columns
def _g(name: str, b: float, x: np.ndarray) -> np.ndarray:
    """The functions of the module table, element by element."""
    f = {
        "abs": abs,
        "deadzone": lambda v: deadzone(v, b),
        "saturation": lambda v: saturation(v, b),
        "sign_square": sign_square,
    }[name]
    return np.array([f(float(v)) for v in x])


@pytest.mark.parametrize(
    "name,code,b",
    [("abs", 1, 0.0), ("deadzone", 2, 0.7), ("saturation", 3, 0.7), ("sign_square", 4, 0.0)],
)
@pytest.mark.parametrize("source,lag", [(0, 2), (1, 1), (2, 0)])
def test_regression_columns_hold_g_of_the_regressor(name, code, b, source, lag):
    rng = np.random.default_rng(7)
    u = rng.standard_normal((300, 2))
    y = rng.standard_normal((300, 1))
    ch = ChannelStructure([[source, lag], [source, lag]], [[1], [2]], None, [0, code], [0.0, b])
    start = 3
    X = regression_matrix(u, y, ch, start)
    data = np.column_stack([y, u])[:, source]
    x = data[start - lag : 300 - lag]
    np.testing.assert_array_equal(X[:, 0], x)
    np.testing.assert_array_equal(X[:, 1], _g(name, b, x))
    assert ch.term_names(["y1"], ["u1", "u2"])[1].startswith(f"{name}(")


def test_regressor_names():
    ch = ChannelStructure(
        [[1, 1], [1, 0], [0, 2], [2, 0]], [[1], [2], [3], [4]], None, [1, 2, 3, 4], [0, 0.1, 2.5, 0]
    )
    assert ch.regressor_names(["y1"], ["u1", "u2"]) == [
        "abs(u1(t-1))",
        "deadzone(u1(t), 0.1)",
        "saturation(y1(t-2), 2.5)",
        "sign_square(u2(t))",
    ]


def test_same_as_tells_functions_and_breakpoints_apart():
    base = ChannelStructure([[1, 0]], [[1]], None, [2], [0.1])
    assert base.same_as(ChannelStructure([[1, 0]], [[1]], None, [2], [0.1]))
    assert not base.same_as(ChannelStructure([[1, 0]], [[1]], None, [2], [0.2]))
    assert not base.same_as(ChannelStructure([[1, 0]], [[1]], None, [3], [0.1]))
    assert not base.same_as(ChannelStructure([[1, 0]], [[1]]))


def test_plain_models_have_identity_functions():
    rng = np.random.default_rng(8)
    m = Narx(order=2, degree=2).fit(rng.standard_normal(300), rng.standard_normal(300))
    ch = m.channels_[0]
    assert ch.functions.tolist() == [0] * ch.n_regressors
    assert ch.breakpoints.tolist() == [0.0] * ch.n_regressors
    assert "function" not in m.describe()


# ----------------------------------------------------------------- persistence
def test_save_load_round_trip_is_exact(tmp_path):
    u = np.random.default_rng(9).standard_normal(2500)
    y = _output_saturation_system(u)
    m = Narx(
        order=1,
        degree=2,
        functions=["sign_square", ("saturation", "auto"), ("deadzone", 0.2)],
        function_sources="all",
        n_terms=8,
    ).fit(u, y)
    loaded = Narx.load(m.save(tmp_path / "model.npz"))
    for a, b in zip(m.channels_, loaded.channels_, strict=True):
        assert a.same_as(b)
        assert np.array_equal(a.breakpoints, b.breakpoints)  # bit for bit
    assert all(np.array_equal(a, b) for a, b in zip(m.coef_, loaded.coef_, strict=True))
    assert loaded.term_names() == m.term_names()
    assert loaded.functions == m.functions and loaded.function_sources == "all"
    assert repr(loaded) == repr(m)
    assert loaded.describe() == m.describe()
    assert np.array_equal(loaded.simulate(u[:800]), m.simulate(u[:800]))


def test_file_saved_before_functions_existed_still_loads(tmp_path):
    # format 1, written out by hand: y(t) = 0.5 y(t-1) + u(t) + 0.25 u(t-1), no function arrays
    meta = {
        "format": "vrig-identification-model",
        "version": 1,
        "class": "Narx",
        "params": {
            "order": None,
            "degree": 2,
            "na": 1,
            "nb": 2,
            "nk": 0,
            "kind": "full",
            "constant": False,
            "solver": "qr",
            "rcond": None,
            "n_terms": 3,
            "err_tol": None,
            "bound_factor": 1000.0,
        },
        "ny": 1,
        "nu": 1,
        "input_names": ["u1"],
        "output_names": ["y1"],
        "max_lag": 1,
        "orders": [None],
    }
    path = tmp_path / "old.npz"
    np.savez(
        path,
        meta=np.array(json.dumps(meta)),
        bound=np.array([1e3]),
        regressors_0=np.array([[0, 1], [1, 0], [1, 1]]),
        terms_0=np.array([[0, 1], [0, 2], [0, 3]]),
        coef_0=np.array([0.5, 1.0, 0.25]),
        err_0=np.array([0.5, 0.3, 0.1]),
    )
    m = Narx.load(path)
    assert m.functions is None and m.function_sources == "inputs"
    assert m.channels_[0].functions.tolist() == [0, 0, 0]
    assert m.term_names() == [["y1(t-1)", "u1(t)", "u1(t-1)"]]
    u = np.random.default_rng(10).standard_normal(500)
    expected = signal.lfilter([1.0, 0.25], [1.0, -0.5], u)
    np.testing.assert_allclose(m.simulate(u), expected[:, None], rtol=0, atol=1e-12)


# ----------------------------------------------------------------- bad input
BAD_SPECS = [
    (["log"], "unknown regressor function 'log'; allowed: 'abs', 'sign_square'"),
    ([("tanh", 0.1)], "unknown regressor function 'tanh'"),
    (["deadzone"], "'deadzone' needs a breakpoint"),
    ([("saturation", -1.0)], "breakpoint of 'saturation' must be a finite number > 0 or 'auto'"),
    ([("deadzone", float("nan"))], "breakpoint of 'deadzone' must be a finite number > 0"),
    ([("deadzone", 0)], "breakpoint of 'deadzone' must be a finite number > 0"),
    ([("deadzone", float("inf"))], "breakpoint of 'deadzone' must be a finite number > 0"),
    ([("deadzone", "wide")], "breakpoint of 'deadzone' must be a finite number > 0 or 'auto'"),
    ([("deadzone", True)], "breakpoint of 'deadzone' must be a finite number > 0"),
    ([("abs", 0.1)], "'abs' takes no breakpoint"),
    ([("deadzone", 0.1, 0.2)], r"a name or a \(name, breakpoint\) pair"),
    ([3], r"a name or a \(name, breakpoint\) pair"),
    ("abs", "functions must be a list of regressor function specs"),
    (("deadzone", 0.1), "'deadzone' needs a breakpoint"),
    (["abs", "abs"], "functions lists 'abs' twice"),
]


@pytest.mark.parametrize("functions,message", BAD_SPECS, ids=[m for _, m in BAD_SPECS])
def test_bad_function_specs_are_named(functions, message):
    with pytest.raises(IdentificationError, match=message):
        Narx(order=1, degree=2, functions=functions)


def test_every_message_lists_the_allowed_specs():
    for functions in (["log"], ["deadzone"], [("deadzone", 1, 2)]):
        with pytest.raises(IdentificationError) as err:
            Narx(order=1, functions=functions)
        assert "('deadzone', b), ('saturation', b) with b > 0 or 'auto'" in str(err.value)


def test_bad_function_sources():
    with pytest.raises(
        IdentificationError,
        match=r"function_sources must be one of \('inputs', 'outputs', 'all'\), got 'both'",
    ):
        Narx(order=1, functions=["abs"], function_sources="both")


def test_arx_rejects_functions():
    with pytest.raises(IdentificationError, match="Arx is linear and takes no regressor functions"):
        Arx(order=2, functions=["abs"])


def test_state_space_refuses_transformed_regressors():
    rng = np.random.default_rng(11)
    m = Arx(order=1).fit(rng.standard_normal(200), rng.standard_normal(200))
    m.to_statespace()  # the plain model has one
    ch = m.channels_[0]
    m.channels_ = (dataclasses.replace(ch, functions=[0, 1, 0], breakpoints=None),)
    with pytest.raises(IdentificationError, match="non-polynomial regressor functions"):
        m.to_statespace()


@pytest.mark.parametrize(
    "functions,breakpoints,message",
    [
        ([1], [0.0, 0.0], r"breakpoints must hold one number per regressor \(1\), got shape"),
        ([0, 1], None, r"functions must hold one integer code per regressor \(1\), got shape"),
        ([0.5], None, r"functions must hold one integer code per regressor"),
        ([7], None, r"function codes must lie in 0\.\.4 \(0 identity, 1 abs"),
        ([2], [0.0], r"deadzone and saturation regressors need a breakpoint > 0"),
        ([3], [-1.0], r"deadzone and saturation regressors need a breakpoint > 0"),
        ([2], [np.nan], r"breakpoints must be finite"),
        ([1], [0.5], r"breakpoints must be 0 for regressors whose function takes none"),
    ],
)
def test_channel_structure_validates_functions(functions, breakpoints, message):
    with pytest.raises(IdentificationError, match=message):
        ChannelStructure([[1, 0]], [[1]], None, functions, breakpoints)
