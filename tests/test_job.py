"""The reconstruction job in the library (:mod:`vrig.job`, issue 33 deliverable 4): the two doors,
``vrig reconstruct --out`` and ``vrig.reconstruct(..., out=)``, write the same test folder; the
Python door's outcomes are vrig exceptions, never the command line's usage errors.

The hostile cases of both doors (Ctrl-C, a full disk, a second writer, too little space) are in
``tests/test_testfolder_hostile.py``, beside each other.
"""

from __future__ import annotations

import contextlib
import io
import json

import pytest

import vrig
import vrig.io
from vrig.cli import main
from vrig.desired.pseudo_field import pseudo_field
from vrig.errors import RigLimitError
from vrig.reconstruction.engine import DriveIteration
from vrig.testfolder import TestFolder


@pytest.fixture(scope="module")
def rig():
    return vrig.load_rig("shock-absorber", fidelity="fast")


@pytest.fixture(scope="module")
def desired(rig):
    _, th = pseudo_field(rig, rig.bandwidth, 3.0, seed=3)
    return th


@pytest.fixture
def fast_rigs(monkeypatch):
    """``vrig reconstruct`` loads its rig at ``fast`` fidelity (as benchmarks.fingerprints)."""
    real = vrig.load_rig

    def load_rig(*args, **kwargs):
        kwargs.setdefault("fidelity", "fast")
        return real(*args, **kwargs)

    monkeypatch.setattr(vrig, "load_rig", load_rig)


def _cli(argv) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main([str(a) for a in argv])
    return code, out.getvalue(), err.getvalue()


def _summary(folder) -> dict:
    return json.loads((folder / "summary.json").read_text(encoding="utf-8"))


@pytest.mark.parametrize(
    "plots", [False, pytest.param(True, marks=pytest.mark.slow)], ids=["records", "plots"]
)
def test_both_doors_write_the_same_files_and_summary_keys(
    rig, desired, tmp_path, fast_rigs, monkeypatch, plots
):
    """The same record, 1 iteration: the same records, models, plots (drawn in the slow case,
    left out in both doors in the fast one) and ``summary.json`` entries (its ``settings`` too,
    the update rule among them), whichever door ran the job."""
    if not plots:
        monkeypatch.setattr("vrig.plots.save_reconstruction_plots", lambda *a, **k: [])
    csv = vrig.io.write_csv(tmp_path / "desired.csv", desired)
    argv = ["reconstruct", "--rig", "shock-absorber", "--desired", csv, "--iterations", "1"]
    code, stdout, err = _cli([*argv, "--out", tmp_path / "cli"])
    assert code == 0, err
    assert "update    none, strategy fixed, tolerance none" in stdout  # the run header
    cli = _summary(tmp_path / "cli")
    result = vrig.reconstruct(
        rig, vrig.io.read(csv), iterations=1, gain=cli["settings"]["gain"], out=tmp_path / "py"
    )
    py = _summary(tmp_path / "py")
    files = {p.name for p in (tmp_path / "cli").iterdir()}
    assert files == {p.name for p in (tmp_path / "py").iterdir()}
    assert {"IDDRV.drv", "IT01DRV.drv", "FINRES01.rsp", "summary.json"} <= files
    assert ("overlay.png" in files) == plots and len(py["plots"]) == len(cli["plots"])
    assert cli.keys() == py.keys() and cli["target_check"].keys() == py["target_check"].keys()
    assert cli["settings"].keys() == py["settings"].keys()
    assert cli["settings"]["update"] == py["settings"]["update"] == "none"
    assert py["settings"]["command"] == "vrig.reconstruct" and py["iterations_run"] == 1
    assert len(result.drives) == 2


def test_the_update_rule_is_in_the_header_and_the_summary(tmp_path, fast_rigs, monkeypatch):
    """``--update frf``: the run header and ``summary.json``'s settings say so (they did not)."""
    monkeypatch.setattr("vrig.plots.save_reconstruction_plots", lambda *a, **k: [])
    out = tmp_path / "o"
    argv = ["reconstruct", "--rig", "shock-absorber", "--seconds", "3", "--iterations", "1"]
    code, stdout, err = _cli([*argv, "--update", "frf", "--format", "npz", "--out", out])
    assert code == 0, err
    assert "update    frf, strategy fixed" in stdout
    settings = _summary(out)["settings"]
    assert settings["update"] == "frf" and settings["update_options"] == {}
    assert _summary(out)["updates"]  # the rule ran


def test_a_failure_before_it00_is_saved_and_still_raised(rig, desired, tmp_path, monkeypatch):
    """IT00DRV refused: the identification records and the model are kept in ``out`` and the
    ReconstructionError says what to change, in the Python keywords (not the CLI's flags)."""

    def refused(self):
        raise RigLimitError("drive", "actuator_disp", float("nan"), 0.2, 0.1, "m")

    monkeypatch.setattr(DriveIteration, "first_drive", refused)
    monkeypatch.setattr("vrig.plots.save_reconstruction_plots", lambda *a, **k: [])
    out = tmp_path / "o"
    with pytest.raises(vrig.ReconstructionError) as info:
        vrig.reconstruct(rig, desired, iterations=1, out=out, fmt="npz")
    text = str(info.value)
    assert "bandwidth" in text and "--band" not in text and f"in {out}/" in text
    assert {p.name for p in info.value.saved} >= {"IDDRV.npz", "IDRES.npz", "summary.json"}
    assert TestFolder(out).summary()["iterations_run"] == -1
    assert info.value.result.drives == [] and info.value.stage == "model"


def test_a_stop_after_it00_is_saved_and_warns_with_the_advice(rig, desired, tmp_path, monkeypatch):
    """IT01DRV refused: the result is returned and saved, and one RuntimeWarning carries the
    line ``vrig reconstruct`` prints (why, what to change in the Python keywords, where the
    best iteration is kept)."""

    def refused(self, *args, **kwargs):
        raise RigLimitError("drive", "actuator_disp", float("nan"), 0.2, 0.1, "m")

    monkeypatch.setattr(DriveIteration, "next_drive", refused)
    out = tmp_path / "o"
    wanted = r"stopped: IT01DRV: .*\(a lower gain, e\.g\. 0\.4, overshoots less\); best IT00 kept"
    with pytest.warns(RuntimeWarning, match=wanted):
        result = vrig.reconstruct(rig, desired, iterations=2, gain=0.8, out=out, plots=False)
    assert result.stop_kind == "refused" and TestFolder(out).summary()["stop_kind"] == "refused"
    assert TestFolder(out).iterations == [0]


@pytest.mark.parametrize("kind", ["a file", "not empty", "the working directory"])
def test_a_bad_results_folder_is_a_vrig_value_error_before_anything_is_played(
    rig, desired, tmp_path, monkeypatch, kind
):
    def refuse(*args, **kwargs):
        raise AssertionError("the rig ran before the bad folder was reported")

    monkeypatch.setattr(vrig.rigs.mujoco_rig.MujocoRig, "run", refuse)
    out = tmp_path / "o"
    if kind == "a file":
        out.write_text("x")
    elif kind == "not empty":
        out.mkdir()
        (out / "notes.txt").write_text("mine")
    else:
        out.mkdir()
        (out / "notes.txt").write_text("mine")
        monkeypatch.chdir(out)
    overwrite = kind == "the working directory"
    with pytest.raises(vrig.errors.ResultsFolderError) as info:
        vrig.reconstruct(rig, desired, iterations=1, out=out, overwrite=overwrite)
    assert isinstance(info.value, ValueError) and isinstance(info.value, vrig.VrigError)
    assert str(out) in str(info.value) and "--" not in str(info.value)
    assert info.value.path == str(out)
