"""The search-baselines benchmark (benchmarks/search_baselines/): the user-record loader, the test
free-run conventions, the linear chooser on a known process, the protocol on a small simulated
record, the command line.

Truth comes from outside the code: the numbers written to the temporary files, the definition of
each free-run start, a second-order filter with a known noise floor (the true model's free-run
error is the measurement noise), the rows the protocol itself printed (the ratios must be their
quotients).
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
import pytest
from scipy.signal import lfilter

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:  # benchmarks/ is a source-checkout package, not in the wheel
    sys.path.insert(0, str(ROOT))

from benchmarks import search_baselines as sb  # noqa: E402
from benchmarks.search_baselines.baselines import linear_candidates  # noqa: E402
from benchmarks.search_baselines.protocol import DIVERGED, score_on_test, warm_up  # noqa: E402
from identification import synthetic  # noqa: E402


def _csv(path: Path, header: str, rows: list[str]) -> Path:
    path.write_text("\n".join([header, *rows]) + "\n", encoding="utf-8")
    return path


def _good_rows(n: int, rng) -> tuple[np.ndarray, list[str]]:
    data = rng.standard_normal((n, 3))
    return data, [
        f"{i * 0.01:.2f}," + ",".join(map(repr, map(float, r))) for i, r in enumerate(data)
    ]


# ---------------------------------------------------------------- the user-record loader
def test_csv_record_reads_the_named_columns_and_splits(tmp_path):
    data, rows = _good_rows(400, np.random.default_rng(0))
    path = _csv(tmp_path / "rig.csv", "t, force ,drive,disp", rows)
    rec = sb.load_user_record(path, ["drive", "force"], ["disp"], 0.75, 30, ts=0.01)
    assert rec.name == "rig" and rec.ts == 0.01
    np.testing.assert_array_equal(rec.u, data[:300, [1, 0]])  # input order as given
    np.testing.assert_array_equal(rec.y, data[:300, [2]])
    t = rec.test
    assert (t.start, t.stop, t.init, t.start_from) == (300, 400, 30, "init")
    np.testing.assert_array_equal(t.measured(), data[330:, [2]])
    assert rec.max_lag == 30


@pytest.mark.parametrize(
    "header, bad_row, inputs, outputs, expected",
    [
        ("t,force,drive,disp", None, ["drive"], ["position"], "no column 'position'"),
        ("t,force,drive,disp", "0.1,1.0,abc,2.0", ["drive"], ["disp"], "'abc' is not a number"),
        ("t,force,drive,disp", "0.1,1.0,,2.0", ["drive"], ["disp"], "an empty value"),
        ("t,force,drive,disp", "0.1,1.0,nan,2.0", ["drive"], ["disp"], "NaN or infinite"),
        ("t,force,drive,disp", "0.1,1.0,2.0,inf", ["drive"], ["disp"], "NaN or infinite"),
        ("t,force,drive,disp", None, ["drive"], ["drive"], "more than once"),
        ("t,force,drive,disp", None, [], ["disp"], "needs --input"),
    ],
)
def test_csv_record_errors_name_column_and_line(
    tmp_path, header, bad_row, inputs, outputs, expected
):
    _, rows = _good_rows(400, np.random.default_rng(1))
    if bad_row is not None:
        rows[6] = bad_row  # line 8 of the file (line 1 is the header)
    path = _csv(tmp_path / "bad.csv", header, rows)
    with pytest.raises(sb.RecordError, match=expected) as info:
        sb.load_user_record(path, inputs, outputs)
    if bad_row is not None:
        assert "line 8" in str(info.value)


def test_record_too_short_is_refused(tmp_path):
    _, rows = _good_rows(90, np.random.default_rng(2))
    path = _csv(tmp_path / "short.csv", "t,force,drive,disp", rows)
    with pytest.raises(sb.RecordError, match="too short"):
        sb.load_user_record(path, ["drive"], ["disp"], 0.5, 50)  # 45 test samples < 50 + 20
    with pytest.raises(sb.RecordError, match="too short"):
        sb.load_user_record(path, ["drive"], ["disp"], 0.5, 5)  # 11-sample validation slice


def test_npz_record_and_its_errors(tmp_path):
    rng = np.random.default_rng(3)
    u, y = rng.standard_normal((300, 2)), rng.standard_normal(300)
    np.savez(tmp_path / "ok.npz", u=u, y=y)
    rec = sb.load_user_record(tmp_path / "ok.npz", init=10)
    np.testing.assert_array_equal(rec.u, u[:150])
    np.testing.assert_array_equal(rec.y[:, 0], y[:150])
    np.savez(tmp_path / "no_y.npz", u=u)
    with pytest.raises(sb.RecordError, match="no array 'y'"):
        sb.load_user_record(tmp_path / "no_y.npz")
    y_nan = y.copy()
    y_nan[17] = np.nan
    np.savez(tmp_path / "nan.npz", u=u, y=y_nan)
    with pytest.raises(sb.RecordError, match="sample 17"):
        sb.load_user_record(tmp_path / "nan.npz")
    np.savez(tmp_path / "len.npz", u=u, y=y[:-1])
    with pytest.raises(sb.RecordError, match="u has 300 samples, y has 299"):
        sb.load_user_record(tmp_path / "len.npz")
    np.savez(tmp_path / "text.npz", u=np.array(["a"] * 300), y=y)
    with pytest.raises(sb.RecordError, match="must hold numbers"):
        sb.load_user_record(tmp_path / "text.npz")
    with pytest.raises(sb.RecordError, match="name CSV columns"):
        sb.load_user_record(tmp_path / "ok.npz", ["u0"], ["y0"])
    with pytest.raises(sb.RecordError, match="no such file"):
        sb.load_user_record(tmp_path / "absent.csv", ["a"], ["b"])


# ---------------------------------------------------------------- the test free-run conventions
class _Recorder:
    """A 'model' that returns its measured start and zeros after it, and remembers it."""

    max_lag, terms = 3, 1

    def simulate(self, u, y0):
        self.u_len, self.y0 = len(u), np.array(y0)
        return np.vstack([y0, np.zeros((len(u) - len(y0), y0.shape[1]))])


@pytest.mark.parametrize(
    "start_from, first, n_given", [("init", 100, 10), ("lags", 100, 3), ("training", 97, 3)]
)
def test_each_free_run_start_gets_the_measured_outputs_it_names(start_from, first, n_given):
    y = np.arange(200.0)[:, None]
    part = sb.ScoredPart(np.zeros((200, 1)), y, 100, 200, 10, start_from)
    m = _Recorder()
    sim = part.simulated(m)
    np.testing.assert_array_equal(m.y0[:, 0], np.arange(first, first + n_given))
    assert sim.shape == part.measured().shape == (90, 1)  # scored from sample 110 on
    np.testing.assert_array_equal(part.measured()[:, 0], np.arange(110.0, 200.0))


# ---------------------------------------------------------------- the linear chooser
def test_linear_chooser_reaches_the_noise_floor_of_a_known_second_order_process():
    rng = np.random.default_rng(1)
    n = 1600
    u = rng.standard_normal(n)
    truth = lfilter([0.0, 0.5, 0.3], [1.0, -1.2, 0.5], u)  # poles at radius 0.71
    noise = 0.1 * truth.std() * rng.standard_normal(n)  # on the measured output
    rec = sb.split_record("arx2", "arx2", u, truth + noise, 0.5, 20, "lfilter")
    cands, _ = linear_candidates(rec.max_lag, len(rec.y), 1, 1)
    choice = sb.choose(cands, rec.u, rec.y, max(c.lag for c in cands))
    v, metric, status = score_on_test(rec, choice.model)
    a = rec.test.start + rec.test.init
    floor = np.sqrt(np.mean(noise[a:] ** 2)) / (truth + noise)[a:].std()  # the true model's error
    assert status == "ok" and metric is None
    assert choice.candidate.lag >= 2  # a first-order model cannot follow two poles
    assert v <= 1.1 * floor, (choice.candidate.label, v, floor)


# ---------------------------------------------------------------- the protocol on one record
def test_protocol_on_a_ball_and_beam_record_gives_three_rows_and_their_ratios():
    warm_up()  # as the command line does before its first search
    r = synthetic.ball_and_beam(600, seed=0)
    rec = sb.split_record("bb", "ball_and_beam", r.u, r.y, 0.5, 50, "ball_and_beam(600)")
    res = sb.run_record(rec, 3.0, None, "disabled in the test")
    assert [row.family for row in res.rows] == ["NarxSearch", "FROLS", "linear"]
    assert "vrig: disabled in the test" in res.rows[1].model
    for row in res.rows:
        assert row.status in ("ok", DIVERGED), row.status
        assert np.isfinite(row.nrmse) == (row.status == "ok")
    ns, frols, linear = (row.nrmse for row in res.rows)
    assert res.ratio_frols == pytest.approx(sb.ratio(ns, frols))
    assert res.ratio_linear == pytest.approx(sb.ratio(ns, linear))
    if np.isfinite(ns) and np.isfinite(frols):
        assert res.ratio_frols == pytest.approx(ns / frols)
    assert res.goal["reached"] == (
        res.ratio_frols <= 0.5 and np.isfinite(ns) and res.ratio_linear <= 1.0
    )
    assert res.search["search_time_s"] > 0 and res.search["refit"]
    assert res.n_train == 300 and res.n_test == 250


def test_ratio_when_a_model_diverged():
    assert sb.ratio(0.2, 0.4) == 0.5
    assert sb.ratio(0.2, np.inf) == 0.0  # only the baseline diverged
    assert sb.ratio(np.inf, 0.4) == np.inf


# ---------------------------------------------------------------- the command line
def test_cli_refuses_a_missing_column_with_exit_code_2(tmp_path, capsys):
    _, rows = _good_rows(400, np.random.default_rng(4))
    path = _csv(tmp_path / "rig.csv", "t,force,drive,disp", rows)
    out = tmp_path / "res.json"
    code = sb.main(
        ["--record", str(path), "--input", "drive", "--output", "nope", "--results", str(out)]
    )
    assert code == 2 and not out.exists()
    assert "no column 'nope'" in capsys.readouterr().err


def test_cli_scores_a_user_record_and_writes_the_json(tmp_path, capsys):
    rng = np.random.default_rng(5)
    u = rng.standard_normal(400)
    y = lfilter([0.0, 0.5, 0.3], [1.0, -1.2, 0.5], u) + 0.05 * rng.standard_normal(400)
    np.savez(tmp_path / "arx.npz", u=u, y=y)
    out = tmp_path / "res.json"
    argv = ["--record", str(tmp_path / "arx.npz"), "--init", "10", "--budget", "1"]
    assert sb.main([*argv, "--no-sysidentpy", "--results", str(out)]) == 0
    printed = capsys.readouterr()
    assert "overall: goal" in printed.out and "[arx] NarxSearch" in printed.err
    res = json.loads(out.read_text(encoding="utf-8"))
    (rec,) = res["records"]
    assert [r["family"] for r in rec["rows"]] == ["NarxSearch", "FROLS", "linear"]
    assert rec["n_train"] == 200 and rec["n_test"] == 190
    assert res["frols_baseline"] == "vrig (--no-sysidentpy)" and res["budget_s"] == 1.0
    # the atomic write left no temporary file (``.res.json.tmp-*``) beside its result
    assert sorted(p.name for p in tmp_path.iterdir()) == ["arx.npz", "res.json"]
