"""The closing "text vs vrig" table of ``benchmarks.thesis_tables`` (issue 23): the verdict rule
on hand-computed cases, and the table on synthetic numbers whose verdicts follow from the rule
(the text's own figures, and the text's figures scaled: a relative gain does not change when
every figure of a table is scaled). No rig is run."""

from __future__ import annotations

import pytest

from benchmarks import thesis_tables
from benchmarks.thesis_tables import (
    TABLES,
    THESIS_3_7,
    TableRun,
    calibrated_row,
    closing_table,
    figure_verdict,
)

# ------------------------------------------------------------------ the verdict, by hand


@pytest.mark.parametrize(
    ("text", "vrig", "verdict"),
    [
        # the text's 57 %: ±25 % relative is 42.75-71.25 % (bounds included)
        (57.0, 57.0, "within ±25 %"),
        (57.0, 42.75, "within ±25 %"),
        (57.0, 71.25, "within ±25 %"),
        (57.0, 42.7, "outside (×0.75)"),  # 42.7 / 57 = 0.749
        (57.0, 71.3, "outside (×1.25)"),  # 71.3 / 57 = 1.2509
        (27.0, 13.5, "outside (×0.50)"),
        (35.0, "RigLimitError: tripped", "not comparable (failed)"),
    ],
)
def test_a_calibrated_figure_is_judged_within_25_percent_of_the_texts(text, vrig, verdict):
    assert figure_verdict(text, vrig) == verdict


@pytest.mark.parametrize(
    ("text_base", "text", "vrig_base", "vrig", "verdict"),
    [
        # the text 27 -> 18 %: a gain of 9 pts = 1/3 of its baseline. vrig 30 -> 25 %: 5 pts =
        # 1/6 of its baseline: half the text's relative gain (5 / 9 = 0.56 in points)
        (27.0, 18.0, 30.0, 25.0, "misses (×0.50)"),
        (27.0, 18.0, 30.0, 20.0, "holds"),  # 10/30 = 1/3: the text's relative gain
        (27.0, 18.0, 24.0, 16.0, "holds"),  # 8/24 = 1/3
        (27.0, 18.0, 30.0, 22.4, "holds"),  # 7.6/30 / (1/3) = 0.76
        (27.0, 18.0, 30.0, 22.6, "misses (×0.74)"),  # 7.4/30 / (1/3) = 0.74
        (27.0, 18.0, 30.0, 17.6, "holds"),  # 12.4/30 / (1/3) = 1.24
        (27.0, 18.0, 30.0, 17.4, "misses (×1.26)"),  # 12.6/30 / (1/3) = 1.26
        (27.0, 18.0, 30.0, 10.0, "misses (×2.00)"),  # 20/30 / (1/3)
        (27.0, 18.0, 30.0, 33.0, "misses (×-0.30)"),  # worse than the baseline: -0.1 / (1/3)
        # Table 3.5: the accelerometer alone is worse on the strain, 56 -> 78 % (-22/56); vrig
        # 40 -> 56 % (-16/40 = -0.4): 1.018 x the text's loss
        (56.0, 78.0, 40.0, 56.0, "holds"),
        (56.0, 78.0, 40.0, 36.0, "misses (×-0.25)"),  # a gain where the text has a loss
        # no gain in the text: holds while vrig's is below 5 % of its baseline
        (27.0, 27.0, 30.0, 29.0, "holds"),
        (27.0, 27.0, 30.0, 25.0, "misses (the text has no gain)"),
        (27.0, 18.0, 30.0, "UnstableModelError: diverged", "not comparable (failed)"),
        (27.0, 18.0, "RigLimitError: tripped", 25.0, "not comparable (failed)"),
    ],
)
def test_a_predicted_gain_is_judged_against_the_texts(text_base, text, vrig_base, vrig, verdict):
    assert figure_verdict(text, vrig, text_base=text_base, vrig_base=vrig_base) == verdict


def test_the_verdict_refuses_half_a_baseline_and_a_text_figure_of_zero():
    with pytest.raises(ValueError, match="both text_base and vrig_base"):
        figure_verdict(18.0, 25.0, text_base=27.0)
    with pytest.raises(ValueError, match="both text_base and vrig_base"):
        figure_verdict(18.0, 25.0, vrig_base=30.0)
    with pytest.raises(ValueError, match="must be > 0"):
        figure_verdict(0.0, 25.0)


# -------------------------------------------------------------- the table, synthetic numbers


def _texts(table, scale=1.0, fill=5.0):
    """Per row, per channel: the text's figure x ``scale`` (``fill`` where the text has none)."""
    return [[fill if t is None else scale * t for t in row.thesis] for row in table.rows]


def _runs(table, values):
    """The two runs a table has: the text's kind of target and the calibrated pseudo-field."""
    return [
        TableRun("thesis, field:x", "s", values, "thesis on field:x", "field:x"),
        TableRun("thesis, pseudo-field", "s", values, "thesis", "pseudo-field"),
    ]


def _rows(text: str) -> list[list[str]]:
    """The closing table's body rows, split into cells."""
    lines = [x for x in text.splitlines() if x.startswith("| ") and not x.startswith("| table")]
    return [[c.strip() for c in x.strip("|").split("|")] for x in lines]


def _n_figures(table) -> int:
    return sum(t is not None for row in table.verdict_rows() for t in row.thesis)


def test_the_texts_own_figures_hold_everywhere():
    """vrig = the text, and vrig = 1.2 x the text (inside ±25 %, relative gains unchanged)."""
    for scale in (1.0, 1.2):
        rows = _rows(closing_table([(t, _runs(t, _texts(t, scale))) for t in TABLES]))
        assert len(rows) == sum(2 * (_n_figures(t) + 1) for t in TABLES)  # + the ordering
        assert {r[6] for r in rows} == {"within ±25 %", "holds", "same ordering"}, scale


def test_a_scaled_table_keeps_its_gains_but_leaves_the_25_percent_band():
    """vrig = 1.5 x the text: every figure outside (×1.50), every relative gain holds."""
    table = next(t for t in TABLES if t.rig == "shock-absorber")
    rows = _rows(closing_table([(table, _runs(table, _texts(table, 1.5)))]))
    cal = [r for r in rows if r[5].startswith("calibrated")]
    assert [r[6] for r in cal] == ["outside (×1.50)"] * 2
    assert [r[5] for r in cal] == ["calibrated row (comparison)", "calibrated on"]
    it05 = [r for r in rows if r[1] == "QanTiM 4th order (inverse) IT05"]
    assert [r[3] for r in it05] == ["17 (gain 10 of 27)"] * 2
    assert [r[4] for r in it05] == ["25.5 (gain 15.0 of 40.5)"] * 2
    assert {r[6] for r in it05} == {"holds"}


def test_the_rows_carry_table_role_and_target():
    """Table 6.12: the base channel has no text baseline (a figure); the calibrated row is
    calibrated on only on the pseudo-field run of the calibrated variant."""
    table = next(t for t in TABLES if t.rig == "radiator")
    rows = _rows(closing_table([(table, _runs(table, _texts(table)))]))
    assert {r[0] for r in rows} == {"6.12"}
    assert [r[2] for r in rows] == ["thesis, field:x"] * 5 + ["thesis, pseudo-field"] * 5
    base = [r for r in rows if r[1].endswith(", base_acc")]
    assert [(r[3], r[5]) for r in base] == [("12", "prediction (figure)")] * 2
    label = table.rows[calibrated_row(table)].label + ", toptank_acc"
    assert [r[5] for r in rows if r[1] == label] == ["calibrated row (comparison)", "calibrated on"]


def test_a_failed_row_is_not_comparable_and_the_ordering_too():
    table = next(t for t in TABLES if t.rig == "elastomeric-damper")
    values = _texts(table)
    values[1] = "UnstableModelError: diverged"
    rows = _rows(closing_table([(table, _runs(table, values)[1:])]))
    assert [r[4:] for r in rows] == [
        ["57.0", "calibrated on", "within ±25 %"],
        ["failed (UnstableModelError)", "prediction", "not comparable (failed)"],
        ["-", "prediction", "not comparable"],
    ]


def test_table_3_7_per_channel_and_its_ordering():
    names = [f"ch{k}" for k in range(7)]
    spec = [float(t) for t in THESIS_3_7]
    out = {"triangular": [t + 1 for t in spec], "rig-specific (Alg. 3.1)": spec}
    rows = _rows(closing_table([], [("mild", names, out)]))
    assert [r[6] for r in rows] == ["within ±25 %"] * 7 + ["same ordering"]
    out["rig-specific (Alg. 3.1)"] = [2 * t for t in spec]
    out["triangular"] = [2 * t + 1 for t in spec]
    out["triangular"][3] = 2 * spec[3] - 1  # the triangular PSD wins one channel
    rows = _rows(closing_table([], [("mild", names, out)]))
    assert [r[6] for r in rows] == ["outside (×2.00)"] * 7 + [
        "different ordering (6 of 7 channels)"
    ]
    assert _rows(closing_table([], [("mild", [], {})])) == []  # no result: no rows


def test_the_report_ends_with_the_closing_table(tmp_path, monkeypatch):
    """After every other table (the normal tables and Table 3.7 included), before the wall time."""
    from tests.test_thesis_tables import _fake_runs

    _fake_runs(monkeypatch)
    text = thesis_tables.thesis_report(tmp_path, True, log=lambda *_: None)
    closing = text.index("### Text vs vrig")
    assert closing > max(text.index(f"### {t.name}") for t in TABLES)
    assert closing > text.index("### Table 6.10") and "### " not in text[closing + 4 :]
    assert text.rstrip().endswith("s_")  # the wall time last
