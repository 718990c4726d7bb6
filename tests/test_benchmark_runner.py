"""The benchmark runner (benchmarks/runner): resumable, backend-independent, plugins.

Short records on the fast shock-absorber rig (6 s, one iteration) keep this file quick.
"""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:  # benchmarks/ is a source-checkout package, not in the wheel
    sys.path.insert(0, str(ROOT))

from benchmarks.runner import (  # noqa: E402
    RecordKey,
    Settings,
    Store,
    compute_record,
    execute,
    leaderboard,
    strip_timing,
    write_outputs,
)
from benchmarks.runner.execute import SettingsMismatchError  # noqa: E402
from benchmarks.runner.registry import default_plugin_specs, plugin_spec  # noqa: E402

SETTINGS = Settings(seconds=4.0, iterations=1, fidelity="fast")
KEYS = [RecordKey("shock-absorber", m, 0, 0) for m in ("arx", "fir", "frf")]
# "fir" is the example plugin of benchmarks/plugins
CLI_ARGS = [
    "--rigs", "shock-absorber", "--methods", "arx", "fir", "frf", "--desired", "0",
    "--seconds", "4", "--iterations", "1", "--fidelity", "fast", "--no-thesis", "--no-plots",
]  # fmt: skip


def _by_id(records):
    return {r["id"]: strip_timing(r) for r in records}


@pytest.fixture(scope="module")
def serial_run(tmp_path_factory):
    """An uninterrupted serial run of KEYS: (store, summary)."""
    store = Store(tmp_path_factory.mktemp("serial"))
    store.prepare(SETTINGS)
    summary = execute(
        KEYS, SETTINGS, store, plugin_specs=default_plugin_specs(), backend="serial", log=None
    )
    return store, summary


def test_serial_run_records_every_key(serial_run):
    store, summary = serial_run
    assert sorted(summary["computed"]) == sorted(store.path(k).stem for k in KEYS)
    records = store.all_records()
    assert len(records) == len(KEYS)
    for r in records:
        assert r["status"] == "ok", r["error"]
        assert len(r["eta0_per_iteration"]) == r["iterations_run"] + 1
        assert r["eta0_best"] == min(r["eta0_per_iteration"])
        assert r["model_size"] > 0
        assert r["inverse_model_error"] is not None and r["normal_model_error"] is not None
        assert set(r["timing"]) >= {"fit_s", "model_sim_s", "reconstruction_s", "record_s"}


def test_outputs_and_plugin_in_leaderboard(serial_run, tmp_path):
    store, _ = serial_run
    written = write_outputs(tmp_path, store.all_records(), None)
    names = {p.name for p in written}
    assert {"records.json", "records.csv", "leaderboard.md"} <= names
    assert "bars_shock-absorber.png" in names and "error_vs_iteration_fir.png" in names
    board = (tmp_path / "leaderboard.md").read_text()
    assert re.search(r"^\| \d+ \| fir \|", board, re.M)  # the plugin is ranked
    assert re.search(r"^\| \d+ \| arx \|", board, re.M)
    assert len(json.loads((tmp_path / "records.json").read_text())) == len(KEYS)


def test_process_backend_equals_serial(serial_run, tmp_path):
    store, _ = serial_run
    other = Store(tmp_path)
    other.prepare(SETTINGS)
    execute(
        KEYS,
        SETTINGS,
        other,
        plugin_specs=default_plugin_specs(),
        backend="process",
        workers=2,
        log=None,
    )
    assert _by_id(other.all_records()) == _by_id(store.all_records())


def test_killed_run_resumes_only_missing_records(serial_run, tmp_path):
    store, _ = serial_run
    out = tmp_path / "killed"
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    cmd = [sys.executable, "-m", "benchmarks", "run", *CLI_ARGS, "--backend", "serial"]
    proc = subprocess.Popen(
        [*cmd, "--out", str(out)],
        cwd=ROOT,
        env=env,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
    )
    records_dir = out / "records"
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline and proc.poll() is None:
        if len(list(records_dir.glob("*.json"))) >= 1:
            break
        time.sleep(0.02)
    proc.kill()
    proc.wait()
    before = {p.name: p.read_bytes() for p in records_dir.glob("*.json")}
    assert 1 <= len(before) < len(KEYS), "the kill should interrupt the run midway"
    (records_dir / ".arx.json.999.tmp").write_text("{half a rec")  # as a kill mid-write leaves

    from benchmarks.runner.cli import main

    assert main(["run", *CLI_ARGS, "--backend", "serial", "--out", str(out), "--quiet"]) == 0
    info = json.loads((out / "run.json").read_text())
    assert info["skipped"] == len(before)
    assert info["computed"] == len(KEYS) - len(before)
    for name, data in before.items():  # finished records were not recomputed
        assert (records_dir / name).read_bytes() == data
    assert not list(records_dir.glob(".*.tmp"))
    assert _by_id(Store(out).all_records()) == _by_id(store.all_records())
    assert (out / "leaderboard.md").exists()


def test_failing_method_is_recorded_not_raised(tmp_path):
    plugin = tmp_path / "broken_plugin.py"
    plugin.write_text(
        "from benchmarks.runner import register_method\n"
        "class Broken:\n"
        "    def identify(self, iddrv, idres):\n"
        "        raise ValueError('no model for you')\n"
        "    def drive(self, response):\n"
        "        raise AssertionError\n"
        "register_method('broken', lambda: Broken())\n"
    )
    rec = compute_record(
        RecordKey("shock-absorber", "broken", 0, 0), SETTINGS, [plugin_spec(str(plugin))]
    )
    assert rec["status"] == "failed"
    assert rec["error"]["stage"] == "reconstruction"
    assert rec["error"]["type"] == "ValueError" and "no model for you" in rec["error"]["message"]
    board = leaderboard([rec])
    assert "fail" in board and "no model for you" in board


def test_other_settings_are_refused(tmp_path):
    store = Store(tmp_path)
    store.prepare(SETTINGS)
    with pytest.raises(SettingsMismatchError):
        store.prepare(Settings(seconds=7.0, iterations=1, fidelity="fast"))


def test_readme_plugin_example_is_the_shipped_plugin():
    """The <= 30-line plugin shown in benchmarks/README.md is benchmarks/plugins/inverse_fir.py
    (which the runs above rank in the leaderboard)."""
    readme = (ROOT / "benchmarks" / "README.md").read_text()
    block = re.search(r"```python\n(# benchmarks/plugins/inverse_fir\.py.*?)```", readme, re.S)
    assert block is not None
    code = block.group(1).split("\n", 1)[1]
    assert len(code.strip().splitlines()) <= 30
    shipped = (ROOT / "benchmarks" / "plugins" / "inverse_fir.py").read_text()
    assert shipped.endswith(code)


def test_vrig_bench_forwards_to_the_runner(capfd):
    from vrig.cli import main

    assert main(["bench", "list"]) == 0
    out = capfd.readouterr().out  # the runner runs in a child interpreter
    assert "fir" in out and "arx" in out


@pytest.mark.slow
def test_ray_backend_equals_serial(serial_run, tmp_path, request):
    """A local Ray instance (~25 s to start here): only with ``-m slow``, as the marker says."""
    if "slow" not in (request.config.getoption("markexpr") or "").replace("not slow", ""):
        pytest.skip("starts a local Ray instance: run with -m slow")
    pytest.importorskip("ray")
    store, _ = serial_run
    other = Store(tmp_path)
    other.prepare(SETTINGS)
    execute(
        KEYS[:2],
        SETTINGS,
        other,
        plugin_specs=default_plugin_specs(),
        backend="ray",
        workers=2,
        log=None,
    )
    want = {
        k: v
        for k, v in _by_id(store.all_records()).items()
        if k in {r["id"] for r in other.all_records()}
    }
    assert len(want) == 2
    assert _by_id(other.all_records()) == want


# ---------------------------------------------------------------------------------------------
# clean shutdown: no process outlives a killed runner; malformed records are recomputed
# ---------------------------------------------------------------------------------------------
SLEEPY_PLUGIN = """
import multiprocessing, os, time
from pathlib import Path
from benchmarks.runner import register_method
from vrig.reconstruction import InverseArx

if multiprocessing.parent_process() is not None:  # loaded in a pool worker: a long record
    Path(os.environ["VRIG_TEST_MARKERS"], str(os.getpid())).write_text("started")
    time.sleep(60)
register_method("sleepy", lambda: InverseArx(2))
"""


def _descendants(pid: int) -> set[int]:
    """Pids of every live descendant of ``pid`` (Linux /proc)."""
    children: dict[int, list[int]] = {}
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            text = stat.read_text()
        except OSError:
            continue
        fields = text[text.rindex(")") + 2 :].split()
        children.setdefault(int(fields[1]), []).append(int(stat.parent.name))
    out, todo = set(), [pid]
    while todo:
        for child in children.get(todo.pop(), []):
            out.add(child)
            todo.append(child)
    return out


def _running(pid: int) -> bool:
    try:
        text = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return False
    return text[text.rindex(")") + 2] not in "ZX"


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc")
def test_kill_9_of_the_runner_leaves_no_worker_or_thesis_process(tmp_path):
    """A record in a pool worker and the thesis reproduction alongside; the runner is killed
    with SIGKILL while the worker is busy: every process it started is gone soon after (on
    today's code the worker and the thesis report run on)."""
    plugin, markers, out = tmp_path / "sleepy.py", tmp_path / "markers", tmp_path / "out"
    plugin.write_text(SLEEPY_PLUGIN)
    markers.mkdir()
    env = {**os.environ, "PYTHONPATH": str(ROOT), "VRIG_TEST_MARKERS": str(markers)}
    cmd = [
        sys.executable, "-m", "benchmarks", "run", "--rigs", "shock-absorber", "--methods",
        "sleepy", "--desired", "0", "--seconds", "4", "--iterations", "0", "--fidelity",
        "fast", "--backend", "process", "--workers", "1", "--plugin", str(plugin), "--no-plots",
        "--quick", "--thesis", "--out", str(out),
    ]  # fmt: skip
    proc = subprocess.Popen(
        cmd, cwd=ROOT, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE
    )
    started: set[int] = set()
    try:
        deadline = time.monotonic() + 90
        while not list(markers.iterdir()) and proc.poll() is None:
            assert time.monotonic() < deadline, "the worker did not start"
            time.sleep(0.05)
        assert proc.poll() is None, proc.stderr.read().decode()
        started = _descendants(proc.pid)
        workers = {int(p.name) for p in markers.iterdir()}
        assert workers <= started and len(started) >= 2  # the worker + the thesis process
        proc.kill()
        proc.wait()
        deadline = time.monotonic() + 5
        while any(_running(p) for p in started) and time.monotonic() < deadline:
            time.sleep(0.05)
        assert not [p for p in started if _running(p)]
    finally:
        proc.kill()
        proc.wait()
        for p in started:  # what the test started, by pid (only left on a failure)
            if _running(p):
                os.kill(p, 9)


def test_tampered_foreign_and_nan_records_are_recomputed(serial_run, tmp_path):
    import shutil

    store, _ = serial_run
    shutil.copytree(store.out, tmp_path / "run")
    other = Store(tmp_path / "run")
    arx, fir, frf = (other.path(k) for k in KEYS)
    rec = json.loads(arx.read_text())
    rec["eta0_best"] = float("nan")  # a NaN score (json writes NaN)
    arx.write_text(json.dumps(rec))
    fir.write_text(frf.read_text())  # a foreign record: frf's under fir's name
    rec = json.loads(frf.read_text())
    rec["eta0_per_iteration"] = ";".join(map(str, rec["eta0_per_iteration"]))  # wrong type
    frf.write_text(json.dumps(rec))
    assert not any(other.finished(k, SETTINGS) for k in KEYS)
    assert other.all_records(SETTINGS) == [] and len(other.rejected(SETTINGS)) == 3
    summary = execute(
        KEYS, SETTINGS, other, plugin_specs=default_plugin_specs(), backend="serial", log=None
    )
    assert sorted(summary["computed"]) == sorted(p.stem for p in (arx, fir, frf))
    assert _by_id(other.all_records(SETTINGS)) == _by_id(store.all_records())


def test_a_record_of_another_key_or_with_a_bad_id_is_not_finished(serial_run, tmp_path):
    from benchmarks.runner.record import check_record

    store, _ = serial_run
    rec = store.load(KEYS[0])
    assert check_record(rec, KEYS[0], SETTINGS) is None
    assert "not of" in check_record(rec, KEYS[1], SETTINGS)
    assert "does not match" in check_record({**rec, "id": "x"}, KEYS[0], SETTINGS)
    assert "other settings" in check_record(rec, KEYS[0], Settings(seconds=5.0))
    bad_key = {**rec, "key": {**rec["key"], "seed": "0"}}
    assert "integers" in check_record(bad_key, None, SETTINGS)
    assert "status" in check_record({**rec, "status": "running"}, KEYS[0], SETTINGS)
    assert "finite" in check_record({**rec, "rms_error": float("inf")}, KEYS[0], SETTINGS)


def test_the_thesis_report_does_not_overlap_another_runs(tmp_path, monkeypatch):
    """While another process holds the folder's thesis lock, a run's thesis reproduction is
    skipped (and touches nothing); once that process is dead its lock is stale."""
    import multiprocessing

    from benchmarks import thesis_tables
    from benchmarks.runner import cli

    calls = []
    monkeypatch.setattr(thesis_tables, "thesis_report", lambda out, quick: calls.append(out))
    holder = subprocess.Popen(
        [sys.executable, "-c", "import sys, time; from benchmarks.runner.lifetime import PidLock; "
         "PidLock(sys.argv[1]).acquire(); print('locked', flush=True); time.sleep(60)",
         str(tmp_path / cli.THESIS_LOCK)],
        cwd=ROOT, env={**os.environ, "PYTHONPATH": str(ROOT)}, stdout=subprocess.PIPE,
    )  # fmt: skip
    try:
        assert holder.stdout.readline() == b"locked\n"

        def run_child():
            recv, send = multiprocessing.Pipe(duplex=False)
            cli._thesis_child(str(tmp_path), True, send)
            return recv.recv()

        line, ok = run_child()
        assert ok and "skipped" in line and f"pid {holder.pid}" in line
        assert calls == [] and not (tmp_path / "thesis_reproduction.log").exists()
    finally:
        holder.kill()
        holder.wait()
    line, ok = run_child()  # the holder is dead: its lock is stale
    assert ok and "skipped" not in line and calls == [tmp_path]


class _FakeThesis:
    """Stands in for the runner's thesis process: runs nothing."""

    def result(self):
        return "thesis reproduction (stand-in)", True

    def stop(self):
        pass


def test_quick_leaves_the_thesis_out_unless_asked_and_ends_with_the_times(
    tmp_path, monkeypatch, capsys
):
    """``run --quick`` starts no thesis reproduction (``--thesis`` does, as the full run does)
    and ends with the record times (the slowest first) and the run's wall time, last."""
    from benchmarks.runner import cli

    started = []
    monkeypatch.setattr(
        cli, "_Thesis", lambda out, quick: started.append((out, quick)) or _FakeThesis()
    )
    args = ["run", "--quick", "--rigs", "shock-absorber", "--methods", "arx", "frf",
            "--seconds", "4", "--iterations", "1", "--backend", "serial", "--no-plots"]  # fmt: skip
    assert cli.main([*args, "--out", str(tmp_path / "q")]) == 0
    lines = capsys.readouterr().out.rstrip().splitlines()
    assert started == [] and cli.QUICK_THESIS_NOTE in lines
    assert lines[-1].startswith("wall time ") and lines[-1].endswith("the whole run")
    first = lines.index(next(ln for ln in lines if ln.startswith("records     2 computed")))
    times = lines[first + 1 : first + 3]
    ids = [ln.split()[-1] for ln in times]
    assert sorted(ids) == ["shock-absorber--arx--d0--s0", "shock-absorber--frf--d0--s0"]
    recs = {r["id"]: r for r in json.loads((tmp_path / "q" / "records.json").read_text())}
    secs = [recs[i]["timing"]["record_s"] for i in ids]
    assert secs == sorted(secs, reverse=True)  # the slowest first
    assert cli.main([*args, "--thesis", "--out", str(tmp_path / "t")]) == 0
    assert started == [(tmp_path / "t", True)]
    assert "thesis reproduction (stand-in)" in capsys.readouterr().out


def test_thesis_and_no_thesis_together_are_refused(capsys):
    from benchmarks.runner import cli

    assert cli.main(["run", "--quick", "--thesis", "--no-thesis"]) == 2
    assert "--thesis and --no-thesis" in capsys.readouterr().err


def test_the_time_summary_lists_this_runs_records_slowest_first():
    from benchmarks.runner.cli import timing_lines

    def rec(name, seconds, status="ok"):
        return {"id": name, "status": status, "timing": {"record_s": seconds}}

    records = [rec("a", 1.0), rec("b", 5.0, "failed"), rec("c", 3.0), rec("old", 100.0)]
    lines = timing_lines(records, ["a", "b", "c"], 6.0, slowest=2)
    assert lines[0].startswith("records     3 computed in 6 s of wall time (9 s summed")
    assert [ln.split()[-1] for ln in lines[1:]] == ["(failed)", "c"]  # "old" was resumed
    assert "b (failed)" in lines[1] and f"{100 * 5 / 9:5.1f} %" in lines[1]
    assert len(timing_lines(records, [], 0.0)) == 1  # nothing computed: one line says so


def test_a_long_record_gets_status_lines_on_stderr(tmp_path, monkeypatch, capsys):
    """While a record runs and none finishes, the runner prints a status line on stderr every
    HEARTBEAT_S seconds (shortened here; the record itself is a stub that takes its time)."""
    import importlib

    ex = importlib.import_module("benchmarks.runner.execute")

    def slow_record(key, settings, specs):
        time.sleep(0.6)
        raise KeyboardInterrupt  # stop after the first record: the lines are what is tested

    monkeypatch.setattr(ex, "HEARTBEAT_S", 0.2)
    monkeypatch.setattr(ex, "compute_record", slow_record)
    store = Store(tmp_path / "o")
    store.prepare(SETTINGS)
    with pytest.raises(KeyboardInterrupt):
        execute(KEYS[:2], SETTINGS, store, backend="serial")
    err = capsys.readouterr().err
    assert "benchmarks: 0 of 2 records done, running for" in err
    assert err.count("benchmarks:") >= 2  # 0.6 s at one line per 0.2 s of silence
    with pytest.raises(KeyboardInterrupt):
        execute(KEYS[:2], SETTINGS, store, backend="serial", log=None)
    assert capsys.readouterr().err == ""  # --quiet: no status lines either


# ---------------------------------------------------------------------------------------------
# the target axis (issue 22): pseudo-field (default) and field:<scenario> records
# ---------------------------------------------------------------------------------------------


@pytest.fixture
def fake_field(monkeypatch):
    """``vrig.desired.kinds.desired_response`` replaced for field targets: half the pseudo-field record
    of the same seed (reachable and quick), with a source line naming it; the runner's
    per-process cache of desired responses is emptied before and after."""
    import vrig.desired.kinds
    from benchmarks.runner import record

    real = vrig.desired.kinds.desired_response

    def fake(rig, target="pseudo-field", seconds=30.0, *, seed=0, band=None):
        field, source, extra = real(rig, "pseudo-field", seconds, seed=seed, band=band)
        if target == "pseudo-field":
            return field, source, extra
        half = field.with_data(0.5 * field.data)
        return half, f"stand-in service record {target} seed {seed}", {}

    record._target.cache_clear()
    monkeypatch.setattr(vrig.desired.kinds, "desired_response", fake)
    yield
    record._target.cache_clear()


def test_the_record_key_holds_the_target_and_a_pseudo_field_key_is_written_as_before():
    from benchmarks.runner.record import key_dict, record_id

    old = RecordKey("shock-absorber", "arx", 0, 0)
    assert old == RecordKey("shock-absorber", "arx", 0, 0, None, "pseudo-field")
    assert record_id(old) == "shock-absorber--arx--d0--s0"  # the id before the axis
    assert key_dict(old) == {"rig": "shock-absorber", "method": "arx", "desired": 0, "seed": 0}
    field = RecordKey("shock-absorber", "arx", 0, 0, target="field:rough-road")
    assert field != old and sorted([field, old]) == [old, field]
    assert record_id(field) == "shock-absorber--arx--d0--s0--field-rough-road"
    assert key_dict(field)["target"] == "field:rough-road"
    both = RecordKey("shock-absorber", "arx", 0, 0, 0.5, "field:rough-road")
    assert record_id(both) == "shock-absorber--arx--d0--s0--sev0.5--field-rough-road"
    for bad in ("field", "field:", "road", "pseudo-field:x", None):
        with pytest.raises(ValueError, match="target must be"):
            RecordKey("shock-absorber", "arx", 0, 0, target=bad)


def test_a_record_without_a_target_loads_as_pseudo_field(serial_run, tmp_path):
    """A record file as written before the target axis (no ``target`` in its key, the old id)
    is a finished pseudo-field record: resumed, not recomputed, and ranked as pseudo-field."""
    from benchmarks.runner.record import check_record
    from benchmarks.runner.report import target_of

    store, _ = serial_run
    rec = store.load(KEYS[0])
    assert set(rec["key"]) == {"rig", "method", "desired", "seed"}
    assert rec["id"] == "shock-absorber--arx--d0--s0" and "target_source" not in rec
    other = Store(tmp_path)
    other.prepare(SETTINGS)
    (other.records_dir / f"{rec['id']}.json").write_text(json.dumps(rec))
    assert other.finished(RecordKey("shock-absorber", "arx", 0, 0, target="pseudo-field"), SETTINGS)
    assert target_of(rec) == "pseudo-field"
    board = leaderboard(other.all_records(SETTINGS))
    assert "## Field targets" not in board and "## Pseudo-field targets" not in board
    named = {**rec, "key": {**rec["key"], "target": "pseudo-field"}}
    assert "has no target" in check_record(named)  # written only for a field target
    bad = {**rec, "key": {**rec["key"], "target": "field:"}}
    assert "target must be" in check_record(bad)


def test_targets_run_as_an_axis_with_a_field_section_and_a_skip_note(tmp_path, capsys, fake_field):
    """``--targets pseudo-field field:rough-road`` on the shock absorber and the shaker: the
    shaker has no service scenario, so its field target is skipped with one note; the field
    record is its own record (key, id, source) and the leaderboard ranks it in its own
    section."""
    from benchmarks.runner.cli import main

    out = tmp_path / "run"
    args = [
        "run", "--rigs", "shock-absorber", "shaker", "--methods", "arx", "--desired", "0",
        "--seconds", "4", "--iterations", "1", "--fidelity", "fast", "--no-thesis",
        "--no-plots", "--backend", "serial", "--out", str(out),
        "--targets", "pseudo-field", "field:rough-road",
    ]  # fmt: skip
    assert main(args) == 0
    stdout = capsys.readouterr().out
    notes = [line for line in stdout.splitlines() if line.startswith("note: target")]
    assert notes == [
        "note: target field:rough-road skipped on shaker (no scenario): not a service scenario "
        "of that rig"
    ]
    records = {r["id"]: r for r in Store(out).all_records()}
    assert sorted(records) == [
        "shaker--arx--d0--s0",
        "shock-absorber--arx--d0--s0",
        "shock-absorber--arx--d0--s0--field-rough-road",
    ]
    field = records["shock-absorber--arx--d0--s0--field-rough-road"]
    assert field["status"] == "ok", field["error"]
    assert field["key"]["target"] == "field:rough-road"
    assert field["target_source"] == "stand-in service record field:rough-road seed 0"
    assert "target" not in records["shock-absorber--arx--d0--s0"]["key"]
    board = (out / "leaderboard.md").read_text()
    assert board.index("## Pseudo-field targets") < board.index("## Field targets")
    field_part = board[board.index("## Field targets") :]
    assert "### shock-absorber:rough-road" in field_part and "shaker" not in field_part
    assert "stand-in service record field:rough-road seed 0" in field_part
    assert "### shock-absorber\n" in board[: board.index("## Field targets")]
    csv_rows = (out / "records.csv").read_text().splitlines()
    assert csv_rows[0].split(",")[6] == "target"
    assert sorted(row.split(",")[6] for row in csv_rows[1:]) == [
        "field:rough-road", "pseudo-field", "pseudo-field",
    ]  # fmt: skip
    info = json.loads((out / "run.json").read_text())
    assert info["targets"] == {
        "shock-absorber": ["pseudo-field", "field:rough-road"],
        "shaker": ["pseudo-field"],
    }


def test_field_alone_is_each_rigs_first_scenario_and_a_target_no_rig_has_is_an_error(
    tmp_path, capsys
):
    from benchmarks.runner.cli import _rig_targets, main

    targets = _rig_targets(["shock-absorber", "radiator", "shaker"], ["field"], "fast")
    assert targets == {
        "shock-absorber": ["field:rough-road"],
        "radiator": ["field:truck-front"],
        "shaker": [],
    }
    assert "skipped on shaker (no scenario)" in capsys.readouterr().out
    common = ["--methods", "arx", "--seconds", "4", "--fidelity", "fast", "--no-thesis"]
    out = tmp_path / "never"
    args = ["run", "--rigs", "shock-absorber", "shaker", *common, "--out", str(out)]
    assert main([*args, "--targets", "field:slow-ditch"]) == 2
    err = capsys.readouterr().err
    assert "--targets field:slow-ditch: no rig of this run has it" in err
    assert "shock-absorber (rough-road)" in err
    assert main([*args, "--targets", "road"]) == 2
    assert "unknown target 'road'" in capsys.readouterr().err
    assert not out.exists()  # refused before anything ran


def test_a_field_record_reconstructs_a_real_service_record():
    """The real field path: the radiator in its truck front end on a class road (4 s, fast)."""
    import vrig
    from benchmarks.runner.record import _desired
    from vrig.service import field_record

    key = RecordKey("radiator", "arx", 0, 0, target="field:truck-front")
    rec = compute_record(key, SETTINGS)
    assert rec["status"] == "ok", rec["error"]
    assert rec["key"]["target"] == "field:truck-front"
    assert "service record 'truck-front' (4 s)" in rec["target_source"]
    assert len(rec["eta0_per_iteration"]) == 2

    _band, desired = _desired("radiator", "fast", 4.0, 0, None, "field:truck-front")
    truth = field_record(vrig.load_rig("radiator", fidelity="fast"), "truck-front", 4.0, seed=0)
    np.testing.assert_array_equal(desired.data, truth.data)  # the record's target, bit for bit
