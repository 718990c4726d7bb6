"""The leaderboard flags absurd numbers with their cause (issue 25, item 10): a modelling error of
4,475,297,457 % (a model whose held-out free run blew up) and a damage ratio of 136 were printed
as plain numbers, and the blown-up value made the mean of its cell meaningless.

The records are made by hand (the fields :func:`benchmarks.runner.report.leaderboard` reads), so
the expected cells follow from the definitions: η0 = 100 % is a prediction of zero, above 1000 %
the prediction is ten times the record; a pseudo-damage ratio R at S-N slope 5 is cycles
R^(1/5) times the desired ones' size.
"""

from __future__ import annotations

import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:  # benchmarks/ is a source-checkout package
    sys.path.insert(0, str(ROOT))

from benchmarks.runner.report import aggregate, leaderboard  # noqa: E402


def _record(method, seed, *, normal=20.0, inverse=25.0, damage=1.0, rig="fuel-tank-2ch"):
    return {
        "id": f"{rig}-{method}-{seed}",
        "key": {"rig": rig, "method": method, "desired": 0, "seed": seed},
        "status": "ok",
        "eta0_it00": 30.0,
        "eta0_final": 5.0,
        "eta0_best": 5.0,
        "iterations_to_tolerance": None,
        "rms_error": 6.0,
        "damage_ratio": damage,
        "normal_model_error": normal,
        "inverse_model_error": inverse,
        "timing": {"fit_s": 0.1},
        "model_size": 10,
    }


def _row(board: str, method: str) -> list[str]:
    (line,) = [ln for ln in board.splitlines() if ln.startswith("| ") and f"| {method} |" in ln
               and ln.count("|") > 10]  # fmt: skip
    return [c.strip() for c in line.strip("|").split("|")]


COLUMNS = ["rank", "method", "ok", "it00", "final", "best", "tol", "rms", "damage", "normal",
           "inverse", "fit", "size"]  # fmt: skip


def _cells(board, method):
    return dict(zip(COLUMNS, _row(board, method), strict=True))


def test_a_blown_up_modelling_error_is_flagged_and_left_out_of_the_mean():
    records = [
        _record("fir", 0, normal=4_475_297_457.05, inverse=569_296.1),
        _record("fir", 1, normal=12.0, inverse=14.0),
        _record("fir", 2, normal=18.0, inverse=16.0),
        _record("arx", 0, normal=500.0),  # bad (5 x a zero prediction) but not blown up
    ]
    board = leaderboard(records)
    fir = _cells(board, "fir")
    assert fir["normal"] == "15.0 (1/3 blew up †)"  # mean of 12 and 18
    assert fir["inverse"] == "15.0 (1/3 blew up †)"
    assert _cells(board, "arx")["normal"] == "500.0"
    assert "4475297457" not in board and "4,475" not in board
    (note,) = [ln for ln in board.splitlines() if ln.startswith("† ")]
    assert "more than ten times the size of the record it predicts" in note
    assert "4.5e+09 %" in note and "fir (normal)" in note and "fir (inverse)" in note
    agg = aggregate(records)[("fuel-tank-2ch", "fir")]
    assert agg["normal_model_error"] == 15.0 and agg["normal_model_blew_up"] == [4_475_297_457.05]


def test_every_value_blown_up_reads_blew_up():
    board = leaderboard([_record("fir", 0, normal=2.2e9, inverse=5.2e5)])
    fir = _cells(board, "fir")
    assert fir["normal"] == fir["inverse"] == "blew up †"


def test_a_damage_ratio_off_by_an_order_of_magnitude_is_flagged_with_its_cycle_size():
    records = [
        _record("narx-ip", 0, damage=136.511, rig="elastomeric-damper"),
        _record("arx", 0, damage=0.17, rig="elastomeric-damper"),  # within a factor 10
        _record("fir", 0, damage=0.05, rig="elastomeric-damper"),
    ]
    board = leaderboard(records)
    assert _cells(board, "narx-ip")["damage"] == "136.51 ‡"
    assert _cells(board, "arx")["damage"] == "0.17"
    assert _cells(board, "fir")["damage"] == "0.05 ‡"
    (note,) = [ln for ln in board.splitlines() if ln.startswith("‡ ")]
    # 136.511 ** (1 / 5) = 2.674..., 0.05 ** (1 / 5) = 0.549...
    assert "narx-ip 137 → 2.67 x" in note and "fir 0.05 → 0.55 x" in note
    assert "; arx" not in note and ": arx" not in note  # 0.17 is not flagged


def test_a_table_with_nothing_absurd_has_no_footnote():
    board = leaderboard([_record("arx", 0), _record("frf", 0, damage=2.5)])
    assert "†" not in board and "‡" not in board
