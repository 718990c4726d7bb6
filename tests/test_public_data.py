"""Public benchmark data (benchmarks/public_data/): loaders, splits, scoring protocol.

Expected values come from outside this code: the SOURCE.md of each data folder (sample counts,
sampling rates), the split indices of the official ``nonlinear_benchmarks`` loader, the figures
printed by SysIdentPy's tutorials (Silverbox 7.727682 mV, F-16 RRSE 0.2910), hand computations
and known synthetic systems. Tests that need a data folder skip when it is absent (folder
``../shared/external-data/`` next to the repository, or ``$VRIG_EXTERNAL_DATA``).
"""

from __future__ import annotations

import dataclasses
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:  # benchmarks/ is a source-checkout package, not in the wheel
    sys.path.insert(0, str(ROOT))

from benchmarks import public_data as pdata  # noqa: E402
from identification import Narx  # noqa: E402


def _need(folder: str, name: str) -> Path:
    path = pdata.data_file(folder, name)
    if path is None:
        pytest.skip(
            f"external data {folder}/{name} not found under {pdata.external_data_root()} "
            f"(set {pdata.ENV_VAR} to the external-data folder)"
        )
    return path


@pytest.fixture(scope="module")
def silverbox():
    return pdata.load_silverbox(_need(pdata.SILVERBOX_FOLDER, pdata.SILVERBOX_FILE))


@pytest.fixture(scope="module")
def tanks():
    return pdata.load_cascaded_tanks(_need(pdata.TANKS_FOLDER, pdata.TANKS_FILE))


@pytest.fixture(scope="module")
def f16():
    return pdata.load_f16(_need(pdata.F16_FOLDER, pdata.F16_FILE))


@pytest.fixture(scope="module")
def mr_damper():
    return pdata.load_mr_damper(_need(pdata.MR_FOLDER, pdata.MR_FILE))


# ---------------------------------------------------------------- data location (no data needed)
def test_root_from_env_var(monkeypatch, tmp_path):
    monkeypatch.setenv(pdata.ENV_VAR, str(tmp_path))
    assert pdata.external_data_root() == tmp_path
    assert pdata.data_file("silverbox", "SNLS80mV.csv") is None
    (tmp_path / "silverbox").mkdir()
    (tmp_path / "silverbox" / "SNLS80mV.csv").write_text("x")
    assert pdata.data_file("silverbox", "SNLS80mV.csv") == tmp_path / "silverbox" / "SNLS80mV.csv"


def test_default_root_is_next_to_the_repository(monkeypatch):
    monkeypatch.delenv(pdata.ENV_VAR, raising=False)
    assert pdata.external_data_root() == ROOT.parent / "shared" / "external-data"


def test_absent_data_sets_are_skipped_with_a_reason(tmp_path):
    report = pdata.run(quick=True, root=tmp_path, use_sysidentpy=False)
    assert {r.dataset for r in report.rows} == {
        "Silverbox",
        "Cascaded Tanks",
        "F-16 subset",
        "MR damper",
    }
    for r in report.rows:
        assert r.status.startswith("skipped:") and "not found" in r.status
        assert r.vrig is None
    table = pdata.format_table(report, None)
    assert table.count("skipped:") == 4


# ---------------------------------------------------------------- metrics and helpers
def test_scores_against_hand_computation():
    y = np.array([0.001, -0.002, 0.003, 0.0])
    yhat = np.zeros(4)
    # RMSE in mV: sqrt((1 + 4 + 9 + 0) / 4) = sqrt(3.5)
    assert pdata._score("rmse_mv", y, yhat) == pytest.approx(np.sqrt(3.5))
    y = np.array([1.0, 2.0, 3.0, 6.0])  # mean 3, sum of squared deviations 4 + 1 + 0 + 9 = 14
    yhat = np.array([1.0, 3.0, 3.0, 4.0])  # squared errors 0 + 1 + 0 + 4 = 5
    assert pdata._score("rrse", y, yhat) == pytest.approx(np.sqrt(5 / 14))
    # NRMSE = RMSE / std(y) = sqrt(5 / 4) / sqrt(14 / 4)
    assert pdata._score("nrmse", y, yhat) == pytest.approx(np.sqrt(5 / 14))
    assert pdata._score("rmse", y, yhat) == pytest.approx(np.sqrt(5 / 4))


def test_advance_shifts_inputs_by_one_sample():
    u = np.arange(10.0).reshape(5, 2)
    v = pdata.advance(u, 1)
    assert v.shape == u.shape
    np.testing.assert_array_equal(v[:-1], u[1:])
    np.testing.assert_array_equal(v[-1], u[-1])
    assert pdata.advance(u, 0) is not None and np.array_equal(pdata.advance(u, 0), u)


def test_selection_finds_the_degree_of_a_known_system():
    # y(t) = 0.5 y(t-1) + u(t-1) + 0.3 u(t-1)^2: quadratic, one lag
    rng = np.random.default_rng(3)
    u = rng.uniform(-1, 1, 3000)
    y = np.zeros_like(u)
    for t in range(1, len(u)):
        y[t] = 0.5 * y[t - 1] + u[t - 1] + 0.3 * u[t - 1] ** 2
    cands = pdata.grid((1, 2), (1, 2), (3, 4, 6))
    sel = pdata.select_and_fit(u[:2000], y[:2000], cands, "rrse", 5)
    assert sel.best.degree == 2
    assert sel.n_tried == len(cands)
    # ties go to fewer terms: the true model has 3 terms (plus a constant candidate)
    assert int(sel.model.n_terms_[0]) <= 4
    sim = pdata.free_run(sel.model, u[2000:], y[2000:])
    assert pdata._score("rrse", y[2005:], sim[5:]) < 1e-6
    # a term budget is respected
    small = pdata.select_and_fit(u[:2000], y[:2000], cands, "rrse", 5, max_terms=3)
    assert int(small.model.n_terms_[0]) <= 3


# ---------------------------------------------------------------- loaders against SOURCE.md
def test_silverbox_loader(silverbox):
    u, y = silverbox
    # SOURCE.md: 131072 rows, V1 input, V2 output; fs = 1e7 / 2^14 ~ 610.35 Hz
    assert u.shape == y.shape == (131072,)
    assert pdata.SILVERBOX_FS == pytest.approx(610.35, abs=0.01)
    assert np.all(np.isfinite(u)) and np.all(np.isfinite(y))


def test_silverbox_split_is_the_official_one():
    # nonlinear_benchmarks.Silverbox: multisine = data[40650:127400] (86750 samples), first
    # int(0.75 * 86750) = 65062 train; arrow = data[100:40575]; no-extrapolation = first 32000
    sp = pdata.silverbox_splits()
    assert sp["train"] == (40650, 40650 + 65062)
    assert sp["test_multisine"] == (40650 + 65062, 127400)
    assert sp["test_multisine"][1] - sp["test_multisine"][0] == 21688
    assert sp["test_arrow_full"] == (100, 40575)
    assert sp["test_arrow_no_extrapolation"] == (100, 32100)
    assert pdata.SILVERBOX_INIT == 50


def test_cascaded_tanks_loader(tanks):
    # SOURCE.md: 1024 rows of uEst, uVal, yEst, yVal; Ts = 4 s in row 1 only
    for key in ("uEst", "uVal", "yEst", "yVal"):
        assert tanks[key].shape == (1024,)
        assert np.all(np.isfinite(tanks[key]))
    assert tanks["Ts"] == 4.0 == pdata.TANKS_TS


def test_f16_loader_and_split(f16):
    u, y = f16
    # SOURCE.md: 32768 rows, x1, x2 inputs and y output, each column scaled to (about) max 1
    assert u.shape == (32768, 2) and y.shape == (32768,)
    np.testing.assert_allclose(u.max(axis=0), 1.0)
    assert 0.95 < y.max() <= 1.0
    # identification on rows 0:16384, validation on 16384: (half and half)
    assert pdata.F16_SPLIT == 16384 == len(y) // 2


def test_mr_damper_loader_and_split(mr_damper):
    d = mr_damper
    # SOURCE.md: 74068 rows, ~24.65 s, fs = 3004.8 Hz (dt = 3.328e-4 s)
    for key in ("t", "D", "Y", "F"):
        assert d[key].shape == (74068,)
    assert d["fs"] == pytest.approx(3004.8)
    # t is printed with 4 decimals, so check the mean step
    assert (d["t"][-1] - d["t"][0]) / (len(d["t"]) - 1) == pytest.approx(3.328e-4, rel=1e-4)
    assert 1 / d["fs"] == pytest.approx(3.328e-4, rel=1e-4)
    assert d["t"][-1] == pytest.approx(24.65, abs=0.01)
    # first 70 %: int(0.7 * 74068) = 51847 samples train, 22221 test
    cut = pdata.mr_damper_split(len(d["F"]))
    assert (cut, len(d["F"]) - cut) == (51847, 22221)


# ---------------------------------------------------------------- published figures reproduced
def test_f16_published_structure_reproduces_sysidentpy_figure(f16):
    # SOURCE.md / SysIdentPy F-16 tutorial: degree 1, ylag 20, xlag 1..9 for both inputs,
    # 30 terms, identification 0:16384, free-run RRSE 0.2910 on 16384:
    u, y = f16
    n = pdata.F16_SPLIT
    model = pdata.Candidate(1, 20, 9, 30).model().fit(u[:n], y[:n])
    assert int(model.n_terms_[0]) == 30
    rrse = pdata._score("rrse", y[n:], pdata.free_run(model, u[n:], y[n:]))
    assert rrse == pytest.approx(0.2910, abs=5e-4)


def test_silverbox_published_structure_reproduces_sysidentpy_figure(silverbox):
    # SysIdentPy Silverbox tutorial: degree 2, xlag = ylag = 7, err_tol 0.999, trained on the
    # multisine training part, free run continuing from the training record: 7.727682 mV
    u, y = silverbox
    (a, b), (c, d) = pdata.silverbox_splits()["train"], pdata.silverbox_splits()["test_multisine"]
    model = Narx(na=7, nb=7, nk=1, degree=2, constant=True, n_terms=40, err_tol=1e-3)
    model.fit(u[a:b], y[a:b])
    p = model.max_lag_
    sim = pdata.free_run(model, u[c - p : d], y[c - p : d])
    rmse_mv = pdata._score("rmse_mv", y[c + 50 : d], sim[p + 50 :])
    assert rmse_mv == pytest.approx(7.727682, abs=0.01)


def test_sysidentpy_mirror_with_current_input_matches_vrig():
    # the nk = 0 mirror (inputs advanced one sample) must give SysIdentPy the same candidate set
    pytest.importorskip("sysidentpy", reason="sysidentpy not installed (optional)")
    sip = pdata.get_sysidentpy()
    rng = np.random.default_rng(5)
    u = rng.uniform(-1, 1, (1500, 2))
    y = np.zeros(1500)
    for t in range(1, 1500):
        y[t] = 0.6 * y[t - 1] + 0.8 * u[t, 0] - 0.4 * u[t - 1, 1] + 0.2 * u[t, 0] * u[t, 1]
    cand = pdata.Candidate(2, 1, 2, 5, nk=0)
    vm = cand.model().fit(u[:1000], y[:1000])
    sm, _ = sip.mirror(cand, 2, u[:1000], y[:1000])
    vs = pdata.free_run(vm, u[1000:], y[1000:])
    ss = sip.free_run(sm, u[1000:], y[1000:], nk=0)
    assert pdata._score("rrse", y[1002:], vs[2:]) < 1e-8
    np.testing.assert_allclose(ss[2:], vs[2:], atol=1e-8)


# ---------------------------------------------------------------- simulation-error rows
def _sim_rows(report, dataset):
    return [r for r in report.rows if r.dataset == dataset and "sim. focus" in r.model]


def test_candidate_passes_the_simulation_options_to_narx():
    c = pdata.Candidate(
        3,
        3,
        (3, 8),
        None,
        nk=0,
        kind="input-polynomial",
        focus="simulation",
        holdout=0.0,
        max_iter=7,
        features="v",
    )
    m = c.model()
    assert (m.focus, m.holdout, m.max_iter, m.kind, m.n_terms) == (
        "simulation",
        0.0,
        7,
        "input-polynomial",
        None,
    )
    assert m.nb == [3, 8] and m.nk == 0 and m.constant
    assert "u lags 0..2/0..7" in c.label(12) and "sim. focus (holdout 0)" in c.label(12)
    assert "(all)" in c.label(12) and "inputs + v" in c.label(12)
    semp = pdata.Candidate(3, 4, 4, 15, kind="pure", selection="simulation", focus="simulation")
    assert semp.model().selection == "simulation"
    assert "pure-power" in semp.label(9) and "SEMP ≤15" in semp.label(9)
    # the one-step rows keep their model and label
    old = pdata.Candidate(2, 4, 4, 10).model()
    assert (old.focus, old.selection, old.kind) == ("prediction", "frols", "full")
    assert pdata.Candidate(2, 4, 4, 10).label() == "NARX deg 2, y lags 1..4, u lags 1..4, 10 terms"


def test_two_fold_validation_uses_both_ends_of_the_training_record(monkeypatch):
    calls = []

    def fake(cand, u, y, fit, val, metric, skip):
        calls.append((fit, val, len(u), len(y)))
        return (1.0 if len(calls) == 1 else 3.0), 4

    monkeypatch.setattr(pdata.search, "_fit_and_score", fake)
    u, y = np.zeros(1000), np.zeros(1000)
    cand = pdata.Candidate(1, 1, 1, None)
    assert pdata.validation_score(cand, u, y, "rmse", 5) == (1.0, 4)
    assert calls == [(slice(0, 750), slice(750, 1000), 1000, 1000)]
    calls.clear()
    assert pdata.validation_score(cand, u, y, "rmse", 5, two_fold=True) == (2.0, 4)
    assert calls == [
        (slice(0, 750), slice(750, 1000), 1000, 1000),
        (slice(250, 1000), slice(0, 250), 1000, 1000),
    ]


def test_simulation_focus_beats_least_squares_with_output_noise():
    # an output-error system: least squares is biased by the noise, the simulation focus is not
    rng = np.random.default_rng(7)
    n = 4000
    u = rng.uniform(-1, 1, n)
    x = np.zeros(n)
    for t in range(2, n):
        x[t] = 1.5 * x[t - 1] - 0.7 * x[t - 2] + 0.5 * u[t - 1] + 0.2 * u[t - 1] ** 2
    y = x + 0.3 * rng.standard_normal(n)
    split = 3000
    report = pdata.Report()
    sc = pdata.Scoring(
        "synthetic",
        "rrse",
        "RRSE",
        5,
        "train 0:3000",
        lambda m, c: pdata._score(
            "rrse", x[split + 5 :], pdata.free_run(m, u[split:], x[split:])[5:]
        ),
        old=1.0,
    )
    search = pdata.SimSearch(
        "test",
        full=pdata._sim((2,), (2,), (None,)),
        quick=pdata._sim((2,), (2,), (None,)),
        goal=0.05,
        reference="none",
        missed="explanation",
    )
    (sel,) = pdata.simulation_rows(report, sc, [search], False, u[:split], y[:split])
    assert sel.model.focus == "simulation" and sel.model.refinement_ is not None
    ls = pdata.Candidate(2, 2, 2, None).model().fit(u[:split], y[:split])
    ls_score = sc.test(ls, None)
    (row,) = report.rows
    assert row.vrig < 0.5 * ls_score  # the output-error fit removes most of the noise bias
    assert row.vrig < 0.05 and "sim. focus" in row.model and row.fit_s > 0
    assert report.notes == [pdata.goal_note(sc, search, row.model, row.vrig)]
    assert report.notes[0].endswith("reached") and "explanation" not in report.notes[0]
    # a missed goal prints its reason
    missed = pdata.goal_note(sc, search, "m", 0.5)
    assert "NOT reached - explanation" in missed


def test_mr_inputs_velocity_is_a_backward_difference():
    D = np.arange(100.0) ** 2
    d = {"D": D, "Y": -D, "fs": 3004.8}
    base = pdata.mr_inputs(d, 0, 100)
    np.testing.assert_array_equal(base, np.column_stack([D[::10], -D[::10]]))
    u = pdata.mr_inputs(d, 20, 100, "v,tanh:2")
    idx = np.arange(20, 100, 10)
    v = (D[idx] - D[idx - 10]) * 300.48
    np.testing.assert_allclose(u[:, 2], v)
    np.testing.assert_allclose(u[:, 3], np.tanh(v / 2))
    assert pdata.mr_inputs(d, 0, 100, "v")[0, 2] == 0.0  # no sample before the record
    with pytest.raises(ValueError):
        pdata.mr_inputs(d, 0, 100, "v,abs")


def _replace_loader(monkeypatch, key, load):
    """The table's record ``key`` with another loader, for this test only."""
    monkeypatch.setitem(pdata.DATASETS, key, dataclasses.replace(pdata.DATASETS[key], load=load))


def _poisoned_tanks(d):
    d = dict(d)
    rng = np.random.default_rng(0)
    d["uVal"] = rng.permutation(d["uVal"])
    d["yVal"] = 12.0 - d["yVal"][::-1]
    return d


def test_tanks_simulation_row_is_chosen_on_training_data_only(tanks, monkeypatch):
    # the same choices with the test record replaced by garbage: the test is only scored
    real = pdata.run(quick=True, only=["tanks"], use_sysidentpy=False)
    sim = _sim_rows(real, "Cascaded Tanks")
    assert len(sim) == 1 and np.isfinite(sim[0].vrig)
    one_step = [r for r in real.rows if r.dataset == "Cascaded Tanks" and r not in sim]
    assert sim[0].vrig < one_step[0].vrig  # the simulation focus beats the one-step search
    assert any(n.startswith("goal Cascaded Tanks / validation") for n in real.notes)
    _replace_loader(monkeypatch, "tanks", lambda p: _poisoned_tanks(tanks))
    poisoned = pdata.run(quick=True, only=["tanks"], use_sysidentpy=False)
    assert [r.model for r in poisoned.rows] == [r.model for r in real.rows]
    assert [r.terms for r in poisoned.rows] == [r.terms for r in real.rows]
    assert _sim_rows(poisoned, "Cascaded Tanks")[0].vrig != sim[0].vrig


def test_mr_damper_simulation_rows_are_chosen_on_training_data_only(mr_damper, monkeypatch):
    real = pdata.run(quick=True, only=["mr"], use_sysidentpy=False)
    sim = _sim_rows(real, "MR damper")
    assert [("tanh" in r.model, "functions" in r.model) for r in sim] == [
        (False, False),
        (True, False),
        (False, True),
    ]
    assert all(np.isfinite(r.vrig) and r.terms > 0 and r.fit_s > 0 for r in sim)
    one_step = next(r for r in real.rows if r.dataset == "MR damper")
    assert sim[0].vrig < one_step.vrig and sim[1].vrig < sim[0].vrig
    cut = pdata.mr_damper_split(len(mr_damper["F"]))
    poisoned = {k: (v.copy() if isinstance(v, np.ndarray) else v) for k, v in mr_damper.items()}
    for key in ("D", "Y", "F"):
        poisoned[key][cut:] = poisoned[key][cut:][::-1] * 1.7
    _replace_loader(monkeypatch, "mr", lambda p: poisoned)
    other = pdata.run(quick=True, only=["mr"], use_sysidentpy=False)
    assert [r.model for r in other.rows] == [r.model for r in real.rows]
    assert [r.vrig for r in _sim_rows(other, "MR damper")] != [r.vrig for r in sim]


@pytest.mark.slow
@pytest.mark.parametrize("only", ["silverbox", "f16"])
def test_simulation_rows_reach_the_goal(only):
    # Silverbox <= 0.4 mV and F-16 RRSE <= 0.2 with the --quick grids
    names = {"silverbox": "Silverbox", "f16": "F-16 subset"}
    folder = {"silverbox": pdata.SILVERBOX_FOLDER, "f16": pdata.F16_FOLDER}[only]
    if not (pdata.external_data_root() / folder).is_dir():
        pytest.skip(f"external data {folder} not found")
    report = pdata.run(quick=True, only=[only], use_sysidentpy=False)
    first = _sim_rows(report, names[only])[0]
    assert first.vrig <= {"silverbox": 0.4, "f16": 0.2}[only]
    assert any(n.startswith(f"goal {names[only]}") and n.endswith("reached") for n in report.notes)


# ---------------------------------------------------------------- the table and the pipeline
def test_every_data_set_record_is_complete():
    # one record per data set, in the order of the table and of the --only names
    assert list(pdata.DATASETS) == ["silverbox", "tanks", "f16", "mr"]
    assert pdata.BENCHES is pdata.DATASETS
    for key, ds in pdata.DATASETS.items():
        assert callable(ds.load) and callable(ds.split), key
        assert ds.folder and ds.file and ds.name and ds.test and ds.label, key
        assert ds.metric in ("rmse_mv", "rmse", "rrse", "nrmse") and ds.skip > 0, key
        # a non-empty model grid; --quick searches a subset of it
        assert ds.grid and all(isinstance(c, pdata.Candidate) for c in ds.grid), key
        assert ds.quick_grid and set(ds.quick_grid) <= set(ds.grid), key
        for s in ds.simulation:
            assert s.full and s.quick and set(s.quick) <= set(s.full), (key, s.test)
        # published figures with their sources, or the stated reason why there is none
        assert ds.published or ds.unpublished, key
        for p in ds.published:
            assert np.isfinite(p.value) and p.value > 0 and len(p.source) > 20, (key, p)
        if ds.budget or ds.config:  # these rows print the published model's size beside it
            assert ds.figure() is not None and ds.figure().terms, key
        for name in ds.transfer.tests if ds.transfer else ():
            assert ds.figure(name) is not None, (key, name)
    # the figures printed beside the rows are the ones the tutorials print (module docstring)
    assert pdata.DATASETS["silverbox"].figure().value == pytest.approx(7.727682, abs=1e-5)
    assert pdata.DATASETS["f16"].figure().value == pytest.approx(0.2910090, abs=1e-6)
    assert pdata.DATASETS["f16"].figure().terms == 30
    assert pdata.DATASETS["tanks"].figure() is None  # the literature figures are goal quotes
    assert not pdata.DATASETS["mr"].published and "no published" in pdata.DATASETS["mr"].unpublished


def _toy_arx_record(tmp_path):
    """A synthetic data set: y(t) = 0.6 y(t-1) - 0.2 y(t-2) + 0.5 u(t-1) + 0.3 u(t-2),
    noise-free, written as a CSV file and run through the generic pipeline."""
    rng = np.random.default_rng(11)
    u = rng.uniform(-1, 1, 2000)
    y = np.zeros_like(u)
    for t in range(2, len(u)):
        y[t] = 0.6 * y[t - 1] - 0.2 * y[t - 2] + 0.5 * u[t - 1] + 0.3 * u[t - 2]
    (tmp_path / "toy").mkdir()
    np.savetxt(tmp_path / "toy" / "arx.csv", np.column_stack([u, y]), delimiter=",")

    def split(data):
        u, y = data
        test = pdata.ScoredRecord(
            u, y, 1500, 2000, 5, "train 0:1500, test 1500:2000", continues=True
        )
        return pdata.Problem(u[:1500], y[:1500], test)

    return pdata.DataSet(
        name="toy ARX",
        folder="toy",
        file="arx.csv",
        load=lambda path: tuple(np.loadtxt(path, delimiter=",").T),
        split=split,
        metric="rrse",
        label="RRSE",
        test="test",
        skip=5,
        grid=tuple(pdata.grid((1, 2), (1, 2, 3), (2, 4, 6))),
        quick_grid=tuple(pdata.grid((1,), (2,), (4,))),
        unpublished="synthetic",
        simulation=(pdata.SimSearch("test", pdata._sim((1,), (2,), (None,)), (), None, "none"),),
    )


def test_pipeline_recovers_a_known_arx_model(tmp_path):
    truth = {"y1(t-1)": 0.6, "y1(t-2)": -0.2, "u1(t-1)": 0.5, "u1(t-2)": 0.3}
    ds = _toy_arx_record(tmp_path)
    report = pdata.Report()
    fitted = pdata.run_dataset(report, ds, None, False, tmp_path)
    models = [fitted.one_step[0].model, fitted.simulation[0].model]
    for m in models:
        coef = dict(zip(m.term_names()[0], m.coef_[0], strict=True))
        for term, value in truth.items():
            assert coef.pop(term) == pytest.approx(value, abs=1e-9), term
        assert all(abs(c) < 1e-9 for c in coef.values()), coef  # any other term: zero
    one_step, sim = report.rows
    assert (one_step.dataset, one_step.test, one_step.metric) == ("toy ARX", "test", "RRSE")
    assert one_step.split == "train 0:1500, test 1500:2000" and one_step.published is None
    assert one_step.vrig < 1e-9 and sim.vrig < 1e-9  # the free run reproduces the test record
    assert "sim. focus" in sim.model and "sim. focus" not in one_step.model
    # an absent file is a skipped row, as for the real data sets
    other = pdata.Report()
    assert pdata.run_dataset(other, ds, None, False, tmp_path / "absent") is None
    assert other.rows[0].status == "skipped: toy/arx.csv not found"


def test_no_function_of_the_package_is_longer_than_80_lines():
    # the standard of tests/test_function_length.py (vrig/, identification/), counted with docstrings
    import ast

    files = sorted((ROOT / "benchmarks" / "public_data").glob("*.py"))
    assert len(files) > 5
    for path in files:
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
                assert node.end_lineno - node.lineno < 80, f"{path.name}: {node.name}"
