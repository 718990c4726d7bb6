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


def test_vrig_bench_forwards_to_the_runner(capsys):
    from vrig.cli import main

    assert main(["bench", "list"]) == 0
    out = capsys.readouterr().out
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
