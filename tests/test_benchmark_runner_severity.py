"""The benchmark runner's non-linearity severity axis (issue 12, deliverable 3).

``python -m benchmarks run --severity S ...`` makes the severity part of the record key; records
without one (every results folder older than the axis) are the rig as loaded and still resume.
The leaderboard's severity section and its crossover are checked on synthetic records with
known numbers; one tiny real run (4 s records, IT00 only, fast rigs) checks the CLI end to end.
"""

from __future__ import annotations

import json
import re
import sys
from dataclasses import replace
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:  # benchmarks/ is a source-checkout package, not in the wheel
    sys.path.insert(0, str(ROOT))

import vrig  # noqa: E402
from benchmarks.runner import (  # noqa: E402
    RecordKey,
    Settings,
    Store,
    compute_record,
    execute,
    leaderboard,
    write_outputs,
)
from benchmarks.runner.cli import _parser, _rig_severities, main  # noqa: E402
from benchmarks.runner.record import check_record, key_dict, record_id  # noqa: E402
from benchmarks.runner.registry import get_method  # noqa: E402
from benchmarks.runner.report import (  # noqa: E402
    method_linearity,
    severity_crossover,
    severity_section,
)

TINY = Settings(seconds=4.0, iterations=0, fidelity="fast")
RIG = "shock-absorber"  # has a severity axis and is the fastest of those rigs
PNG = b"\x89PNG\r\n\x1a\n"


# ---------------------------------------------------------------------------------------------
# CLI
# ---------------------------------------------------------------------------------------------
def test_cli_parses_severity_values():
    args = _parser().parse_args(["run", "--severity", "0", "0.5", "1", "1.5", "2"])
    assert args.severity == [0.0, 0.5, 1.0, 1.5, 2.0]
    assert _parser().parse_args(["run"]).severity is None  # default: no axis


@pytest.mark.parametrize("bad", ["2.5", "-0.1", "nan", "inf"])
def test_severity_outside_0_2_is_exit_2_with_one_line(bad, tmp_path, capsys):
    out = tmp_path / "out"
    code = main(["run", "--severity", "1", bad, "--rigs", RIG, "--out", str(out), "--no-thesis"])
    err = capsys.readouterr().err
    assert code == 2
    assert len(err.strip().splitlines()) == 1 and "--severity" in err and "[0, 2]" in err
    assert not out.exists()  # refused before anything ran


def test_rigs_without_a_severity_axis_run_once_as_loaded():
    axis = vrig.severity_rigs()
    linear = [r for r in vrig.list_rigs() if r not in axis]
    assert axis and linear
    got = _rig_severities([axis[0], linear[0]], [2, 0, 0.5, 0])
    assert got == {axis[0]: [0.0, 0.5, 2.0], linear[0]: [None]}
    assert _rig_severities([axis[0]], None) == {axis[0]: [None]}  # no --severity: no axis


# ---------------------------------------------------------------------------------------------
# record key
# ---------------------------------------------------------------------------------------------
def test_record_key_carries_severity_and_keeps_old_ids():
    old = RecordKey(RIG, "arx", 0, 0)
    assert old.severity is None
    assert record_id(old) == f"{RIG}--arx--d0--s0"  # the id records had before the axis
    assert key_dict(old) == {"rig": RIG, "method": "arx", "desired": 0, "seed": 0}
    half = RecordKey(RIG, "arx", 0, 0, 0.5)
    assert record_id(half) == f"{RIG}--arx--d0--s0--sev0.5"
    assert key_dict(half)["severity"] == 0.5
    assert RecordKey(RIG, "arx", 0, 0, 1) == RecordKey(RIG, "arx", 0, 0, 1.0)
    assert record_id(RecordKey(RIG, "arx", 0, 0, 1)) == f"{RIG}--arx--d0--s0--sev1"
    assert len({record_id(RecordKey(RIG, "arx", 0, 0, s)) for s in (None, 0, 1, 2)}) == 4
    assert sorted([half, old, RecordKey(RIG, "arx", 0, 0, 0.0)])[0] == old  # None sorts first
    for bad in (-0.5, 2.01, float("nan"), "1", True):
        with pytest.raises(ValueError):
            RecordKey(RIG, "arx", 0, 0, bad)


@pytest.fixture(scope="module")
def severity_records():
    """arx records on the shock absorber as loaded (no severity) and at severities 0 and 2."""
    return {s: compute_record(RecordKey(RIG, "arx", 0, 0, s), TINY) for s in (None, 0.0, 2.0)}


def test_records_at_a_severity_are_well_formed_and_keep_the_severity(severity_records):
    for s, rec in severity_records.items():
        assert rec["status"] == "ok", rec["error"]
        assert check_record(rec, RecordKey(RIG, "arx", 0, 0, s), TINY) is None
        assert rec["key"].get("severity") == s
        assert rec["method_linear"] is True
    assert "severity" not in severity_records[None]["key"]  # written exactly as before


def test_severity_reaches_the_rig_linear_error_grows_with_it(severity_records):
    """The linearised rig (0) is easier for a linear inverse than the twice-as-non-linear one
    (2): issue 12's monotonic linear error, here through the runner."""
    assert severity_records[0.0]["eta0_it00"] < severity_records[2.0]["eta0_it00"]


def test_desired_response_is_the_rig_at_the_records_severity():
    """The documented choice: the pseudo-field response of the rig at that severity."""
    import numpy as np

    from benchmarks.runner.record import _desired
    from vrig.desired.pseudo_field import pseudo_field
    from vrig.reconstruction.defaults import default_band

    rig = vrig.load_rig(RIG, seed=0, fidelity="fast", severity=2.0)
    _drive, want = pseudo_field(rig, default_band(rig), 4.0, seed=0)
    _band, got = _desired(RIG, "fast", 4.0, 0, 2.0)
    np.testing.assert_array_equal(got.data, want.data)
    _band, as_loaded = _desired(RIG, "fast", 4.0, 0, None)
    assert not np.array_equal(as_loaded.data, want.data)


def test_old_records_without_severity_load_and_resume(severity_records, tmp_path):
    """A results folder made before the axis: its records (no severity in the key) are kept by
    a re-run, and adding --severity computes only the new records."""
    store = Store(tmp_path)
    store.prepare(TINY)
    old = json.loads(json.dumps(severity_records[None]))
    assert set(old["key"]) == {"rig", "method", "desired", "seed"}  # the pre-axis format
    store.write(old)
    before = store.path(RecordKey(RIG, "arx", 0, 0)).read_bytes()
    assert store.all_records(TINY) == [old] and store.rejected(TINY) == {}
    keys = [RecordKey(RIG, "arx", 0, 0, s) for s in (None, 0.0)]
    summary = execute(keys, TINY, store, backend="serial", log=None)
    assert summary["skipped"] == [old["id"]]
    assert summary["computed"] == [f"{old['id']}--sev0"]
    assert store.path(keys[0]).read_bytes() == before
    # a key field severity: null, or outside the range, is not a record's
    assert "null" in check_record({**old, "key": {**old["key"], "severity": None}})
    bad = {**old, "key": {**old["key"], "severity": 3.0}, "id": old["id"] + "--sev3"}
    assert "severity" in check_record(bad)
    # a record at severity 0 is not the record of the rig as loaded, and vice versa
    rec0 = store.load(keys[1])
    assert "not of" in check_record(rec0, keys[0], TINY)
    assert "not of" in check_record(old, keys[1], TINY)


def test_cli_run_with_a_linear_rig_and_the_severity_section(tmp_path, capsys):
    """One tiny real run: the linear shaker runs once (note printed), the shock absorber at
    each severity; the leaderboard has the section and the plot is written."""
    linear = next(r for r in vrig.list_rigs() if r not in vrig.severity_rigs())
    out = tmp_path / "run"
    args = [
        "run", "--rigs", linear, RIG, "--methods", "arx", "--severity", "2", "0",
        "--desired", "0", "--seconds", "4", "--iterations", "0", "--fidelity", "fast",
        "--backend", "serial", "--no-thesis", "--out", str(out),
    ]  # fmt: skip
    assert main(args) == 0
    stdout = capsys.readouterr().out
    assert re.search(rf"note: {linear} has no severity axis.*run once as loaded", stdout)
    names = sorted(p.name for p in (out / "records").glob("*.json"))
    assert names == sorted(
        [
            f"{linear}--arx--d0--s0.json",
            f"{RIG}--arx--d0--s0--sev0.json",
            f"{RIG}--arx--d0--s0--sev2.json",
        ]
    )
    board = (out / "leaderboard.md").read_text()
    assert "## Severity" in board and f"### {RIG}" in board and f"### {linear}" not in board
    assert (out / "plots" / f"severity-{RIG}.png").read_bytes().startswith(PNG)
    assert not (out / "plots" / f"severity-{linear}.png").exists()
    assert json.loads((out / "run.json").read_text())["severity"] == [2.0, 0.0]
    # report rebuilds the section and the plot from the records
    (out / "leaderboard.md").unlink()
    (out / "plots" / f"severity-{RIG}.png").unlink()
    assert main(["report", "--out", str(out)]) == 0
    assert (out / "leaderboard.md").read_text() == board
    assert (out / "plots" / f"severity-{RIG}.png").read_bytes().startswith(PNG)


# ---------------------------------------------------------------------------------------------
# leaderboard section, crossover and plot on synthetic records (known numbers)
# ---------------------------------------------------------------------------------------------
def test_registry_classifies_linear_and_nonlinear_methods():
    """ARX, split spectra of ARX, FRF and FIR models are linear; NARX models are not."""
    for m in ("arx", "split", "frf", "fir"):
        assert get_method(m).linear is True, m
    for m in ("narx", "narx-ip"):
        assert get_method(m).linear is False, m


def _record(rig, method, sev, it00, best, *, desired=0, linear=None, failed=False):
    key = RecordKey(rig, method, desired, 0, sev)
    rec = {
        "schema": 1,
        "id": record_id(key),
        "key": key_dict(key),
        "settings": {},
        "status": "failed" if failed else "ok",
        "error": None,
        "timing": {"fit_s": 0.1, "record_s": 1.0},
        "method_description": method,
    }
    if linear is not None:
        rec["method_linear"] = linear
    if failed:
        rec["error"] = {"stage": "reconstruction", "type": "Diverged", "message": "boom"}
        return rec
    per = [it00, best]
    return {
        **rec,
        "eta0_per_iteration": per,
        "eta0_it00": it00,
        "eta0_final": best,
        "eta0_best": best,
        "best_iteration": 1,
        "iterations_run": 1,
        "iterations_to_tolerance": None,
        "rms_error": best,
        "damage_ratio": 1.0,
        "model_size": 10,
        "stopped": "done",
    }


IT00 = {  # IT00 η0 [%] at severity 0, 1, 2: narx-ip first beats every linear method at 1
    "arx": (10.0, 15.0, 30.0),
    "frf": (11.0, 16.0, 25.0),
    "narx-ip": (12.0, 14.0, 20.0),
}


def _synthetic(rig="damper-x"):
    recs = []
    for m, values in IT00.items():
        for s, v in zip((0.0, 1.0, 2.0), values, strict=True):
            recs.append(_record(rig, m, s, v, v / 2))
    return recs


def _row(board: str, method: str, nth: int) -> list[str]:
    rows = re.findall(rf"^\| {re.escape(method)} \| [a-z-]+ \|(.*)\|$", board, re.M)
    return [c.strip() for c in rows[nth].split("|")]


def test_leaderboard_severity_tables_and_crossover():
    board = leaderboard(_synthetic())
    assert "## Severity" in board and "### damper-x" in board
    assert "| method | class | s = 0 | s = 1 | s = 2 |" in board
    assert _row(board, "narx-ip", 0) == ["12.0", "14.0", "20.0"]  # the IT00 table
    assert _row(board, "narx-ip", 1) == ["6.0", "7.0", "10.0"]  # the best-η0 table
    assert "| arx | linear |" in board and "| narx-ip | non-linear |" in board
    assert "crossover at severity 1: narx-ip 14.0 % beats arx 15.0 %" in board
    # the main tables keep severities apart (damper-x@1 is its own rig column)
    assert re.search(r"^## damper-x@1$", board, re.M)


def test_crossover_cases():
    lin = {"arx": True, "frf": True, "narx-ip": False, "odd": None}
    # never beaten
    c = severity_crossover({"arx": {0: 5, 1: 6}, "narx-ip": {0: 5, 1: 7}}, lin)
    assert c["severity"] is None and c["reason"].startswith("no crossover in the range 0–1")
    # equal is not beating; the lowest severity where it beats, and where it stops again
    c = severity_crossover(
        {"arx": {0: 5, 0.5: 6, 1: 6, 2: 9}, "narx-ip": {0: 5, 0.5: 5.5, 1: 7, 2: 8}}, lin
    )
    assert c["severity"] == 0.5 and c["nonlinear"] == ("narx-ip", 5.5) and c["linear"] == ("arx", 6)
    assert c["not_at"] == [1]
    # the best of each class counts: frf is the best linear method at 1
    c = severity_crossover({"arx": {0: 5, 1: 9}, "frf": {0: 6, 1: 7}, "narx-ip": {0: 8, 1: 8}}, lin)
    assert c["severity"] is None
    # a failed linear method (None) is beaten by any non-linear result
    c = severity_crossover({"arx": {0: 5, 2: None}, "narx-ip": {0: 6, 2: 40}}, lin)
    assert c["severity"] == 2 and "every linear method failed" in c["reason"]
    # unclassified methods are left out; one class missing: no crossover, said why
    c = severity_crossover({"odd": {0: 1, 1: 1}, "arx": {0: 5, 1: 6}}, lin)
    assert c["severity"] is None and "needs a linear and a non-linear method" in c["reason"]


def test_failed_records_show_and_count_as_not_reached():
    recs = [r for r in _synthetic() if r["key"]["method"] != "arx"]  # frf is the linear one
    recs.append(_record("damper-x", "frf", 3.0 / 2, 0, 0, failed=True))  # 1.5: frf failed
    recs.append(_record("damper-x", "narx-ip", 1.5, 30.0, 15.0))
    board = "\n".join(severity_section(recs))
    assert _row(board, "frf", 0)[2] == "fail"  # the s = 1.5 column
    assert "crossover at severity 1: narx-ip 14.0 % beats frf 16.0 %" in board


def test_no_severity_section_with_one_severity_or_none():
    one = [r for r in _synthetic() if r["key"]["severity"] == 1.0]
    assert severity_section(one) == [] and "## Severity" not in leaderboard(one)
    as_loaded = [replace_key(r, None) for r in one]  # the rig as loaded is not a point of the axis
    assert severity_section(as_loaded + one) == []


def replace_key(rec, severity):
    key = replace(RecordKey(**rec["key"]), severity=severity)
    return {**rec, "key": key_dict(key), "id": record_id(key)}


def test_linearity_from_records_then_registry():
    recs = [
        _record("r", "mine", 0.0, 1, 1, linear=False),
        _record("r", "arx", 0.0, 1, 1),  # no field: the registry's flag
        _record("r", "unknown-method", 0.0, 1, 1),
    ]
    assert method_linearity(recs) == {"mine": False, "arx": True, "unknown-method": None}


def test_severity_plot_is_written_atomically(tmp_path):
    recs = _synthetic() + _synthetic("other")
    recs.append(_record("flat", "arx", None, 3.0, 1.0))  # a linear rig: no severity plot
    written = write_outputs(tmp_path, recs, None)
    plots = tmp_path / "plots"
    for rig in ("damper-x", "other"):
        assert plots / f"severity-{rig}.png" in written
        assert (plots / f"severity-{rig}.png").read_bytes().startswith(PNG)
    assert not (plots / "severity-flat.png").exists()
    assert (plots / "bars_damper-x--sev1.png").exists() and (plots / "bars_flat.png").exists()
    assert not [p for p in plots.iterdir() if p.name.startswith(".")]  # no temporary left
    csv = (tmp_path / "records.csv").read_text().splitlines()
    col = csv[0].split(",").index("severity")
    assert sorted({row.split(",")[col] for row in csv[1:]}) == ["", "0.0", "1.0", "2.0"]
