"""The QanTiM test folder: every record of a reconstruction written and read back."""

from __future__ import annotations

import json
import multiprocessing
import os
import random
import signal
import sys
import time
from pathlib import Path

import numpy as np
import pytest

import vrig
import vrig.io
from identification import Narx
from vrig.io import read_rpc3_header
from vrig.reconstruction import reconstruct
from vrig.signals import flat_psd, random_drive
from vrig.testfolder import TestFolder

BAND = (10.0, 60.0)  # the shaker's accelerometer is deaf below ~10 Hz


@pytest.fixture(scope="module")
def case():
    rig = vrig.load_rig("shaker", seed=0)
    d = random_drive(
        flat_psd((0.0, 50.0)),
        int(4 * rig.fs),
        rig.fs,
        rms=0.5,
        seed=7,
        names=[c.name for c in rig.inputs],
        unit="V",
    )
    field = rig.run(d, seed=99)
    result = reconstruct(rig, field, method="arx", order=4, iterations=2, bandwidth=BAND)
    return rig, d, field, result


def _same(a: vrig.TimeHistory, b: vrig.TimeHistory, *, exact: bool) -> None:
    assert a.names == b.names and a.units == b.units and a.fs == b.fs
    assert a.n_samples == b.n_samples
    if exact:
        np.testing.assert_array_equal(a.data, b.data)
    else:  # RPC III FLOATING_POINT stores float32
        np.testing.assert_allclose(a.data, b.data, rtol=1e-6, atol=1e-6 * np.abs(b.data).max())


@pytest.mark.parametrize("fmt", ["rsp", "npz", "csv"])
def test_save_and_read_back_every_record(case, tmp_path, fmt):
    rig, desdrv, field, result = case
    folder = TestFolder(tmp_path / "run")
    written = folder.save(result, field=field, rig=rig, fmt=fmt, records={"DESDRV": desdrv})
    assert written[-1].name == "summary.json"
    assert all(p.exists() for p in written)
    n = len(result.drives)
    expected = ["DESDRV", "IDDRV", "IDRES", "FIELD01", "DESRES01"]
    for it in range(n):
        expected += [f"IT{it:02d}DRV", f"RIT{it:02d}RES", f"IT{it:02d}RES"]
    expected += ["FINDRV01", "FINRES01"]
    files = folder.files()
    assert list(files) == expected  # process order
    exact = fmt != "rsp"
    if fmt == "rsp":
        assert files["IT00DRV"].suffix == ".drv" and files["FINDRV01"].suffix == ".drv"
        assert files["IT00RES"].suffix == ".rsp" and files["IDRES"].suffix == ".rsp"
        header = read_rpc3_header(files["IT01DRV"])
        assert header["TIME_TYPE"] == "DRIVE" and header["DATA_TYPE"] == "FLOATING_POINT"
        assert read_rpc3_header(files["RIT01RES"])["TIME_TYPE"] == "RESPONSE"
    else:
        assert {p.suffix for p in files.values()} == {f".{fmt}"}

    _same(folder.read("IDDRV"), result.id_drive, exact=exact)
    _same(folder.read("IDRES"), result.id_response, exact=exact)
    _same(folder.read("FIELD01"), field, exact=exact)
    _same(folder.read("DESRES01"), result.desired, exact=exact)
    _same(folder.read("DESDRV"), desdrv, exact=exact)
    _same(folder.read("FINDRV01"), result.final_drive, exact=exact)
    _same(folder.read("FINRES01"), result.final_response, exact=exact)
    assert folder.iterations == list(range(n))
    for it in range(n):
        rec = folder.load_iteration(it)
        assert rec.index == it
        _same(rec.drive, result.drives[it], exact=exact)
        _same(rec.raw_response, result.raw_responses[it], exact=exact)
        _same(rec.response, result.responses[it], exact=exact)
        np.testing.assert_allclose(rec.eta0, result.errors[it])
        np.testing.assert_allclose(rec.rms_error, result.rms_errors[it])
        np.testing.assert_allclose(rec.damage_ratio, result.damage_ratio[it])

    s = folder.summary()
    assert s["rig"] == "shaker"
    assert s["bandwidth_hz"] == list(BAND)
    assert s["best_iteration"] == result.best_iteration
    assert s["iterations_run"] == n - 1
    assert s["stop_reason"]
    assert s["method"]["name"] == "arx" and s["method"]["order"] == 4
    assert "Arx" in s["method"]["description"]
    assert s["table"] == result.table().splitlines()
    assert s["files"]["FINDRV01"] == files["FINDRV01"].name
    json.dumps(s, allow_nan=False)  # strict JSON


def test_the_inverse_model_is_saved_and_reloads(case, tmp_path):
    _, _, field, result = case
    folder = TestFolder(tmp_path / "run")
    folder.save(result, field=field, fmt="npz")
    assert (tmp_path / "run" / "model.npz").exists()
    models = folder.load_models()
    model, lead = models["model"]
    assert isinstance(model, Narx)
    assert lead == result.method.inverse.lead_
    x = np.random.default_rng(0).standard_normal((200, 1))
    np.testing.assert_allclose(model.simulate(x), result.method.inverse.model.simulate(x))


def test_a_method_without_an_inverse_model_is_noted_not_saved(case, tmp_path):
    rig, _, field, _ = case
    res = reconstruct(rig, field, method="frf", iterations=0, bandwidth=BAND)
    folder = TestFolder(tmp_path / "frf")
    written = folder.save(res)
    assert not any(p.name.startswith("model") for p in written)
    s = folder.summary()
    assert s["models"] == {} and "not saved" in s["model_note"]
    assert folder.load_models() == {}


def test_never_overwrites_a_non_empty_folder_silently(case, tmp_path):
    _, _, _, result = case
    target = tmp_path / "run"
    target.mkdir()
    (target / "notes.txt").write_text("mine")
    with pytest.raises(FileExistsError, match="overwrite=True"):
        TestFolder(target).save(result)
    assert sorted(p.name for p in target.iterdir()) == ["notes.txt"]  # nothing written

    folder = TestFolder(target)
    folder.save(result, fmt="npz", overwrite=True)
    (target / "IT07DRV.npz").write_bytes(b"stale record of an older, longer run")
    folder.save(result, fmt="csv", overwrite=True)
    assert (target / "notes.txt").read_text() == "mine"  # not ours: left alone
    assert not (target / "IT07DRV.npz").exists()
    assert {p.suffix for p in folder.files().values()} == {".csv"}


def test_bad_arguments(case, tmp_path):
    _, _, _, result = case
    with pytest.raises(ValueError, match="fmt"):
        TestFolder(tmp_path / "a").save(result, fmt="xls")
    with pytest.raises(ValueError, match="QanTiM name"):
        TestFolder(tmp_path / "b").save(result, records={"my record": result.desired})
    (tmp_path / "file").write_text("x")
    with pytest.raises(FileExistsError, match="not a folder"):
        TestFolder(tmp_path / "file").save(result)
    with pytest.raises(FileNotFoundError):
        TestFolder(tmp_path / "missing").files()
    folder = TestFolder(tmp_path / "c")
    folder.save(result, fmt="npz")
    with pytest.raises(KeyError, match="no iteration 07"):
        folder.load_iteration(7)
    with pytest.raises(KeyError, match="no record"):
        folder.read("FIELD01")


# ------------------------------------------------------------------ interrupted overwrite
def _snapshot(folder: Path) -> dict[str, bytes]:
    """Every file of a folder, byte for byte."""
    return {p.name: p.read_bytes() for p in sorted(folder.iterdir())}


def _assert_complete(folder: TestFolder, fmt: str) -> None:
    """The folder holds a whole save in ``fmt``: the summary and every record it lists."""
    summary = folder.summary()
    assert summary["record_format"] == fmt
    assert set(folder.files()) == set(summary["files"])
    for name in summary["files"]:
        folder.read(name)
    assert (folder.path / "notes.txt").read_text() == "mine"


@pytest.mark.parametrize("interrupt", [KeyboardInterrupt, OSError])
def test_an_overwrite_interrupted_by_an_exception_leaves_the_old_folder_byte_identical(
    case, tmp_path, monkeypatch, interrupt
):
    _, _, _, result = case
    target = tmp_path / "run"
    TestFolder(target).save(result, fmt="rsp")
    (target / "notes.txt").write_text("mine")
    before = _snapshot(target)
    real, calls = vrig.io.write_rpc3, []

    def write_then_fail(*args, **kwargs):  # Ctrl-C (or a full disk) at the fourth record
        calls.append(args[0])
        if len(calls) == 4:
            raise interrupt("interrupted while writing")
        return real(*args, **kwargs)

    monkeypatch.setattr(vrig.io, "write_rpc3", write_then_fail)
    with pytest.raises(interrupt):
        TestFolder(target).save(result, fmt="rsp", overwrite=True)
    assert len(calls) == 4
    assert _snapshot(target) == before
    assert [p.name for p in tmp_path.iterdir()] == ["run"]  # the staging folder is gone too


def _save_in_child(target: Path, result, fmt: str, ready) -> None:
    ready.set()
    TestFolder(target).save(result, fmt=fmt, overwrite=True)
    time.sleep(60)  # done: wait to be killed


@pytest.mark.skipif(sys.platform != "linux", reason="forks a child process (Linux)")
def test_a_save_killed_midway_leaves_the_old_folder_or_the_new_one(case, tmp_path):
    _, _, _, result = case
    target = tmp_path / "run"
    folder = TestFolder(target)
    t_save = {}
    for fmt in ("csv", "rsp"):
        t0 = time.perf_counter()
        folder.save(result, fmt=fmt, overwrite=True)
        t_save[fmt] = time.perf_counter() - t0
    (target / "notes.txt").write_text("mine")
    ctx = multiprocessing.get_context("fork")
    rng = random.Random(0)
    mid_save = 0
    for i in range(6):
        fmt = ("csv", "rsp")[i % 2]
        before = _snapshot(target)
        ready = ctx.Event()
        child = ctx.Process(target=_save_in_child, args=(target, result, fmt, ready), daemon=True)
        child.start()
        try:
            assert ready.wait(60)
            time.sleep(rng.uniform(0.05, 1.0) * t_save[fmt])
        finally:
            os.kill(child.pid, signal.SIGKILL)
            child.join()
        folder.files()  # puts back a folder a kill set aside mid-swap
        if _snapshot(target) != before:
            _assert_complete(folder, fmt)
        debris = [p.name for p in tmp_path.iterdir() if p.name.startswith(".run.tmp-")]
        assert len(debris) <= 1  # this kill's at most: each save deletes the ones before it
        mid_save += len(debris)
    assert mid_save  # some kills struck mid-save


def test_a_folder_set_aside_by_a_kill_mid_swap_is_put_back(case, tmp_path):
    _, _, _, result = case
    target = tmp_path / "run"
    TestFolder(target).save(result, fmt="npz")
    before = _snapshot(target)
    target.rename(tmp_path / ".run.old-0123abcd")  # killed between the two renames of the swap
    (tmp_path / ".run.tmp-89abcdef").mkdir()  # the new folder beside it
    folder = TestFolder(target)
    assert list(folder.files())
    assert _snapshot(target) == before
    assert folder.summary()["record_format"] == "npz"
