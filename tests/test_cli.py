"""The vrig command line: the main job runs end to end and rejects bad arguments."""

from __future__ import annotations

import pytest

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
