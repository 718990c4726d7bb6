"""The "## Policies" section of the benchmark runner's leaderboard (benchmarks/runner/report.py),
read from the learned-iteration results. Independent truth: the numbers written by hand below."""

from __future__ import annotations

import json

import pytest

from benchmarks.runner.cli import _parser as build_parser
from benchmarks.runner.report import policies_section, write_outputs

RESULTS = {
    "quick": False,
    "policies": [
        {"policy": "fixed 0.8", "rig": "shock-absorber", "mean_iterations": 4.25,
         "success_rate": 0.95, "mean_final_eta0": 1.234, "max_final_eta0": 2.0, "trips": 0,
         "held_out": 20},
        {"policy": "SB3 SAC", "rig": "shock-absorber", "mean_iterations": 3.5,
         "success_rate": 1.0, "mean_final_eta0": 0.987, "max_final_eta0": 1.5, "trips": 1,
         "held_out": 20},
        {"policy": "fixed 0.8", "rig": "light-truck-front", "mean_iterations": 11.0,
         "success_rate": 0.0, "mean_final_eta0": 7.5, "max_final_eta0": 9.0, "trips": 2,
         "held_out": 20},
    ],
}  # fmt: skip


def _write(tmp_path, doc=RESULTS):
    path = tmp_path / "learned_iteration.json"
    path.write_text(json.dumps(doc))
    return path


def test_policy_by_rig_table_holds_the_written_numbers(tmp_path):
    lines = policies_section(_write(tmp_path))
    assert lines[0] == "## Policies"
    header = "| policy | shock-absorber | light-truck-front |"
    i = lines.index(header)
    assert lines[i + 1] == "|---|---:|---:|"
    assert lines[i + 2] == "| fixed 0.8 | 4.25 / 1.23 / 0 | 11.00 / 7.50 / 2 |"
    assert lines[i + 3] == "| SB3 SAC | 3.50 / 0.99 / 1 |  |"  # not scored on the truck
    text = "\n".join(lines)
    assert "20 per rig" in text and "budget + 1" in text and "trips" in text


def test_absent_results_give_one_line_saying_how_to_make_them(tmp_path):
    lines = [ln for ln in policies_section(tmp_path / "nope.json") if ln]
    assert len(lines) == 1
    assert "python -m benchmarks.learned_iteration" in lines[0]
    assert "## Policies" not in lines[0]


@pytest.mark.parametrize(
    "doc", [{"rigs": []}, {"policies": [{"policy": "x", "rig": "y"}]}, {"policies": 3}]
)
def test_results_without_a_policies_list_are_a_clear_error(tmp_path, doc):
    with pytest.raises(ValueError, match=r"learned_iteration\.json.*policies"):
        policies_section(_write(tmp_path, doc))


def test_leaderboard_file_ends_with_the_section_only_when_asked(tmp_path):
    path = _write(tmp_path)
    (tmp_path / "with").mkdir()
    (tmp_path / "without").mkdir()
    write_outputs(tmp_path / "with", [], None, plots=False, policies=path)
    board = (tmp_path / "with" / "leaderboard.md").read_text()
    assert "## Policies" in board and "| SB3 SAC | 3.50 / 0.99 / 1 |  |" in board
    write_outputs(tmp_path / "without", [], None, plots=False)
    assert "Policies" not in (tmp_path / "without" / "leaderboard.md").read_text()


def test_runner_commands_take_the_results_path():
    parser = build_parser()
    for cmd in (["run"], ["report"]):
        args = parser.parse_args([*cmd, "--policies", "x.json"])
        assert str(args.policies) == "x.json"
        assert str(parser.parse_args(cmd).policies) == "results/learned_iteration.json"


def test_rig_columns_name_the_tolerance_the_file_says_they_were_scored_at(tmp_path):
    doc = dict(RESULTS, rigs=[{"rig": "shock-absorber", "tolerance_percent": 1.1}])
    lines = policies_section(_write(tmp_path, doc))
    assert "| policy | shock-absorber (η0 ≤ 1.1 %) | light-truck-front |" in lines
