"""The vrig command line: the main job runs end to end and rejects bad arguments."""

from __future__ import annotations

import contextlib
import io
import json

import numpy as np
import pytest

import vrig
import vrig.io
from vrig.cli import main


def test_demo_identifies_and_reports(capsys):
    assert main(["demo", "--samples", "4000", "--seed", "3"]) == 0
    out = capsys.readouterr().out
    assert "η0 eq.5-28 %" in out
    assert "free run" in out and "M samples/s" in out
    for name in ("y1", "y2", "y3"):
        assert f"      {name}" in out


def test_demo_rejects_bad_arguments(capsys):
    assert main(["demo", "--samples", "100"]) == 2
    assert "--samples must be >= 2000" in capsys.readouterr().err
    assert main(["demo", "--noise", "2"]) == 2


def test_unknown_command_exits_with_usage():
    with pytest.raises(SystemExit) as err:
        main(["reconstruct-everything"])
    assert err.value.code == 2


# ---------------------------------------------------------------------------------------------
# rigs, describe
# ---------------------------------------------------------------------------------------------
def test_rigs_lists_every_rig_with_its_title(capsys):
    assert main(["rigs"]) == 0
    out = capsys.readouterr().out
    lines = out.splitlines()
    for name in vrig.list_rigs():
        (line,) = [ln for ln in lines if ln.startswith(name + " ")]
        assert len(line) > len(name) + 10  # a title follows
    assert "Heavy-vehicle damper" in out


def test_describe_prints_channels_and_limits(capsys):
    assert main(["describe", "shock-absorber"]) == 0
    out = capsys.readouterr().out
    assert "actuator_disp [m] ±0.05" in out and "damper_load [N] ±10000" in out
    assert "test band 0-10 Hz" in out


def test_describe_an_unknown_rig_exits_2(capsys):
    assert main(["describe", "no-such-rig"]) == 2
    err = capsys.readouterr().err
    assert "unknown rig 'no-such-rig'" in err and "shock-absorber" in err


# ---------------------------------------------------------------------------------------------
# reconstruct
# ---------------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def reconstructed(tmp_path_factory):
    out = tmp_path_factory.mktemp("cli") / "shock"
    argv = [
        "reconstruct",
        "--rig",
        "shock-absorber",
        "--method",
        "arx",
        "--seconds",
        "10",
        "--iterations",
        "2",
        "--out",
        str(out),
    ]
    buf = io.StringIO()
    with contextlib.redirect_stdout(buf), contextlib.redirect_stderr(io.StringIO()):
        code = main(argv)
    return code, out, buf.getvalue()


def test_reconstruct_writes_the_test_folder_plots_and_table(reconstructed):
    code, out, text = reconstructed
    assert code == 0
    assert "iteration    damper_load     mean" in text
    for it in ("IT00", "IT01", "IT02"):
        assert f"     {it} " in text
    assert "*" in text and "stopped" in text
    names = {p.name for p in out.iterdir()}
    expected = {
        "IDDRV.drv",
        "IDRES.rsp",
        "FIELD01.rsp",
        "DESRES01.rsp",
        "DESDRV.drv",
        "FINDRV01.drv",
        "FINRES01.rsp",
        "summary.json",
        "model.npz",
    }
    for it in range(3):
        expected |= {f"IT{it:02d}DRV.drv", f"RIT{it:02d}RES.rsp", f"IT{it:02d}RES.rsp"}
    expected |= {
        "overlay.png",
        "overlay_zoom.png",
        "psd.png",
        "error_vs_iteration.png",
        "drive_vs_limits.png",
    }
    assert expected <= names
    assert str(out) in text
    summary = json.loads((out / "summary.json").read_text())
    assert summary["rig"] == "shock-absorber" and summary["bandwidth_hz"] == [0.0, 10.0]
    assert summary["iterations_run"] == 2
    assert summary["settings"]["gain"] == 0.8
    # the pseudo-field reconstruction converges (IT00 ~10 %, each iteration lower)
    eta = np.array(summary["errors"]["eta0_percent"])[:, 0]
    assert eta[0] < 30 and eta[-1] < eta[0] / 2


def test_reconstruct_refuses_a_non_empty_folder_without_overwrite(reconstructed, capsys):
    _, out, _ = reconstructed
    before = (out / "summary.json").read_bytes()
    argv = ["reconstruct", "--rig", "shock-absorber", "--seconds", "4", "--out", str(out)]
    assert main(argv) == 2
    assert "--overwrite" in capsys.readouterr().err
    assert (out / "summary.json").read_bytes() == before


def test_reconstruct_a_desired_file(reconstructed, tmp_path, capsys):
    _, out, _ = reconstructed
    field = vrig.io.read(out / "FIELD01.rsp")
    renamed = tmp_path / "road.csv"
    vrig.io.write(renamed, vrig.TimeHistory(field.data, field.fs, ["F"], ["N"]))
    dest = tmp_path / "fromfile"
    argv = [
        "reconstruct",
        "--rig",
        "shock-absorber",
        "--desired",
        str(renamed),
        "--seconds",
        "4",
        "--iterations",
        "0",
        "--format",
        "npz",
        "--out",
        str(dest),
    ]
    assert main(argv) == 0
    text = capsys.readouterr().out
    assert "matched by position" in text and "road.csv (4 s)" in text
    assert (dest / "IT00DRV.npz").exists() and (dest / "FINDRV01.npz").exists()
    assert not (dest / "DESDRV.npz").exists()
    assert vrig.TimeHistory.load(dest / "FIELD01.npz").duration == 4.0


@pytest.mark.parametrize(
    "extra,message",
    [
        (["--rig", "no-such-rig"], "unknown rig 'no-such-rig'"),
        (["--rig", "shock-absorber", "--gain", "3"], "--gain must lie in (0, 2]"),
        (["--rig", "shock-absorber", "--iterations", "-1"], "--iterations must be 0..99"),
        (["--rig", "shock-absorber", "--band", "10", "5"], "--band 10 5: need 0 <= LOW < HIGH"),
        (["--rig", "shock-absorber", "--band", "0", "400"], "fs/2 = 250 Hz"),
        (["--rig", "shock-absorber", "--seconds", "1"], "--seconds must be 2..3600"),
        (["--rig", "shock-absorber", "--degree", "3"], "--degree applies to narx and split"),
        (["--rig", "shock-absorber", "--split-hz", "3"], "--split-hz applies to --method split"),
        (["--rig", "shock-absorber", "--method", "frf", "--order", "3"], "--order applies to"),
        (["--rig", "shock-absorber", "--order", "0"], "--order must be 1..20"),
        (
            ["--rig", "shock-absorber", "--method", "split", "--split-hz", "20"],
            "--split-hz must lie inside the band 0-10 Hz",
        ),
        (["--rig", "shock-absorber", "--desired", "missing.rsp"], "--desired: no file missing.rsp"),
    ],
)
def test_reconstruct_rejects_bad_arguments(extra, message, capsys, tmp_path):
    assert main(["reconstruct", *extra, "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert err.startswith("vrig reconstruct: ") and message in err
    assert not (tmp_path / "o").exists()


def test_reconstruct_rejects_a_desired_file_that_does_not_fit_the_rig(tmp_path, capsys):
    wrong_fs = tmp_path / "wrong_fs.npz"
    vrig.TimeHistory(np.zeros((1000, 1)), 256.0, ["damper_load"], ["N"]).save(wrong_fs)
    two = tmp_path / "two.npz"
    vrig.TimeHistory(np.zeros((1000, 2)), 500.0, ["a", "b"], ["N", "N"]).save(two)
    bad = tmp_path / "bad.rsp"
    bad.write_bytes(b"not an RPC file")
    for path, message in [
        (wrong_fs, "sampled at 256 Hz but rig 'shock-absorber' runs at 500 Hz"),
        (two, "has 2 channels ['a', 'b'] but rig 'shock-absorber' has 1 responses"),
        (bad, "cannot read"),
    ]:
        argv = [
            "reconstruct",
            "--rig",
            "shock-absorber",
            "--desired",
            str(path),
            "--out",
            str(tmp_path / "o"),
        ]
        assert main(argv) == 2
        assert message in capsys.readouterr().err


def test_reconstruct_argument_syntax_errors_exit_2(capsys):
    for argv in (
        ["reconstruct"],
        ["reconstruct", "--rig", "shaker", "--method", "magic"],
        ["reconstruct", "--rig", "shaker", "--gain", "high"],
    ):
        with pytest.raises(SystemExit) as err:
            main(argv)
        assert err.value.code == 2
    assert "invalid choice: 'magic'" in capsys.readouterr().err


# ---------------------------------------------------------------------------------------------
# repeatability
# ---------------------------------------------------------------------------------------------
def test_repeatability_prints_numbers_and_writes_the_plot(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    assert main(["repeatability", "--rig", "shock-absorber", "--runs", "2", "--seconds", "4"]) == 0
    out = capsys.readouterr().out
    (line,) = [ln for ln in out.splitlines() if ln.startswith("damper_load")]
    assert "%" in line and "dB" in line
    assert float(line.split()[1].rstrip("%")) > 95.0
    png = tmp_path / "results" / "shock-absorber-repeatability" / "repeatability.png"
    assert png.read_bytes()[:4] == b"\x89PNG"


def test_repeatability_rejects_bad_arguments(capsys):
    assert main(["repeatability", "--rig", "shock-absorber", "--runs", "1"]) == 2
    assert "--runs must be 2..50" in capsys.readouterr().err
    assert main(["repeatability", "--rig", "nope"]) == 2
    assert "unknown rig" in capsys.readouterr().err


def test_demo_says_when_the_stability_contract_refuses_the_fit(capsys):
    # seed 5 with 4,000 samples: the least-squares cubic model (454 terms per output, 3,000
    # identification samples) diverges on its own input from a zero past
    assert main(["demo", "--samples", "4000", "--seed", "5"]) == 1
    err = capsys.readouterr().err
    assert "diverges on its own identification input" in err and "--samples" in err
