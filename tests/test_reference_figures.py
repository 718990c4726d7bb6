"""vrig.reference_figures: the figures are the reference text's (read from the text itself, next
to their labels), every copy in the rig side-cars equals them, and every benchmark row names
figures of its own rig and channel."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

from vrig.reference_figures import FIGURES, figure, figures, repeatability_label
from vrig.rigs import list_rigs, rig_path

ROOT = Path(__file__).resolve().parents[1]
TEXT = ROOT.parent / "shared" / "reference" / "response-reconstruction-thesis.md"


def _raw(rig):
    return json.loads(rig_path(rig).read_text())


# ------------------------------------------------------- against the text, read independently


@pytest.fixture(scope="module")
def text_lines():
    if not TEXT.exists():
        pytest.skip(f"the reference text is not here ({TEXT})")
    return TEXT.read_text(encoding="utf-8").splitlines()


def _numbers_on_row(lines, heading: str, label: str) -> list[float]:
    """The numbers on the first line containing ``label`` within 30 lines after the line that
    starts with ``heading`` (the table's bold title)."""
    start = next(i for i, ln in enumerate(lines) if ln.startswith(heading))
    row = next(ln for ln in lines[start + 1 : start + 30] if label in ln)
    return [float(x) for x in re.findall(r"\d+(?:\.\d+)?", re.sub(r"<[^>]+>", " ", row))]


# (key, the table's title, a label on its row, which number on the row: -1 the last)
ROWS = [
    ("table-6.3/qantim-6-inverse", "**Table 6.3 ", "QanTiM 6", -1),
    ("table-6.3/narx-4-quadratic-inverse", "**Table 6.3 ", "NARX 4", -1),
    ("table-6.5/qantim-3-normal", "**Table 6.5 ", "QanTiM 3", -1),
    ("table-6.5/qantim-3-narx-2-error-signal", "**Table 6.5 ", "error signal model", -1),
    ("table-6.7/qantim-5-normal", "**Table 6.7 ", "QanTiM 5", -1),
    ("table-6.7/narx-3-quadratic-normal", "**Table 6.7 ", "NARX 3", -1),
    ("table-6.9/qantim-5-normal", "**Table 6.9 ", "QanTiM 5", -1),
    ("table-6.9/split-2hz-narx-0-quadratic-qantim-2", "**Table 6.9 ", "Split spectra", -1),
    ("table-6.12/qantim-6-inverse/toptank_acc", "**Table 6.12 ", "QanTiM 6", -1),
    ("table-6.12/narx-6-quadratic-inverse/toptank_acc", "**Table 6.12 ", "NARX 6", -1),
    (
        "table-6.12/non-square-narx-6-quadratic-inverse/toptank_acc",
        "**Table 6.12 ",
        "Non-square",
        1,
    ),
    ("table-6.12/non-square-narx-6-quadratic-inverse/base_acc", "**Table 6.12 ", "Non-square", 2),
    ("table-6.16/qantim-4-inverse/IT00", "**Table 6.16 ", "(inverse) IT00RES", -1),
    ("table-6.16/qantim-4-inverse/IT05", "**Table 6.16 ", "(inverse) IT05RES", -1),
    ("table-6.16/narx-4-cubic-inverse/IT00", "**Table 6.16 ", "NARX 4", -1),
    ("table-3.4/full-spectrum/fore_acc", "**Table 3.4:", "Full spectra model", 0),
    ("table-3.4/full-spectrum/aft_acc", "**Table 3.4:", "Full spectra model", 1),
    ("table-3.4/split-spectra-12hz/fore_acc", "**Table 3.4:", "Combined split", 0),
    ("table-3.4/split-spectra-12hz/aft_acc", "**Table 3.4:", "Combined split", 1),
    ("table-3.5/broad-strain/spring_strain", "**Table 3.5 ", "strain gauge simulation", 0),
    ("table-3.5/broad-strain/spindle_acc", "**Table 3.5 ", "strain gauge simulation", 1),
    ("table-3.5/broad-acceleration/spring_strain", "**Table 3.5 ", "accelerometer simulation", 0),
    ("table-3.5/broad-acceleration/spindle_acc", "**Table 3.5 ", "accelerometer simulation", 1),
    ("table-3.5/split-spectra-8hz/spring_strain", "**Table 3.5 ", "Combined split", 0),
    ("table-3.5/split-spectra-8hz/spindle_acc", "**Table 3.5 ", "Combined split", 1),
    ("table-3.1/threaded/damper_load", "**Table 3.1 ", "Repeatability Number", 0),
    ("table-3.1/rubber-bush/damper_load", "**Table 3.1 ", "Repeatability Number", 1),
    ("table-3.2/spindle_acc", "**Table 3.2 ", "Repeatability number", 0),
    ("table-3.2/spring_strain", "**Table 3.2 ", "Repeatability number", 1),
    ("table-3.3/base_acc", "**Table 3.3 ", "Repeatability number", 0),
    ("table-3.3/toptank_acc", "**Table 3.3 ", "Repeatability number", 1),
]
T37 = ["L/F vertical", "R/F vertical", "L/R vertical", "R/R vertical", "Front lateral",
       "Rear lateral", "Longitudinal"]  # fmt: skip


@pytest.mark.parametrize(("key", "heading", "label", "index"), ROWS)
def test_a_figure_is_the_number_on_its_row_of_the_texts_table(
    text_lines, key, heading, label, index
):
    assert _numbers_on_row(text_lines, heading, label)[index] == figure(key).value


@pytest.mark.parametrize("k", range(7))
def test_table_3_7_error_and_order_per_channel_are_the_texts(text_lines, k):
    """Each row of Table 3.7: ..., order, error (the last two numbers)."""
    (fig,) = [f for f in figures(table="Table 3.7") if f"Ch {k + 1} {T37[k]}," in f.condition]
    *_, order, error = _numbers_on_row(text_lines, "**Table 3.7:", f"\t{T37[k]}\t")
    assert (fig.value, fig.order) == (error, order)


def test_the_shakers_number_and_the_split_are_the_texts(text_lines):
    whole = "\n".join(text_lines)
    assert f"repeatability number for the test system is {figure('sec-3.1.1/shaft_acc').value}" \
        in whole  # fmt: skip
    split = figure("figure-3.9/resonance").value
    assert f"a low frequency area below {split:g} Hz and a high-frequency area above {split:g} Hz" \
        in whole  # fmt: skip


def test_every_text_figure_of_the_tables_is_checked_against_the_text():
    checked = {key for key, *_ in ROWS} | {f.key for f in figures(table="Table 3.7")}
    checked |= {"sec-3.1.1/shaft_acc", "figure-3.9/resonance"}
    assert checked == set(FIGURES)


# ------------------------------------------------------------------------ the module itself


def test_keys_are_unique_and_each_figure_names_a_shipped_rig_and_its_channel():
    assert list(FIGURES) == [f.key for f in figures()]
    for f in FIGURES.values():
        raw = _raw(f.rig)
        names = {c["name"] for c in raw["inputs"]} | {c["name"] for c in raw["outputs"]}
        assert f.channel in names or (f.channel == "" and f.quantity == "resonance"), f.key
        assert f.unit == ("Hz" if f.quantity == "resonance" else "%")


def test_a_bad_key_or_field_is_refused_with_what_there_is():
    with pytest.raises(KeyError, match=r"'table-6\.16' has"):
        figure("table-6.16/nonsense")
    with pytest.raises(KeyError, match="the tables are"):
        figure("table-9.9/x")
    with pytest.raises(TypeError, match="not a field"):
        figures(colour="red")
    assert [f.key for f in figures(table="Table 3.3")] == ["table-3.3/base_acc",
                                                           "table-3.3/toptank_acc"]  # fmt: skip


# -------------------------------------------------------------- the side-cars' copies of them


@pytest.mark.parametrize("rig", [r for r in list_rigs() if "repeatability" in _raw(r)])
def test_a_side_cars_repeatability_numbers_are_the_module_figures(rig):
    block = _raw(rig)["repeatability"]
    for channel, number in block["numbers"].items():
        (fig,) = [
            f for f in figures(rig=rig, channel=channel, quantity="repeatability number")
            if repeatability_label(f) == block["table"]
        ]  # fmt: skip
        assert (fig.value, fig.band) == (number, tuple(float(x) for x in block["band"]))


def _calibrations():
    return [(rig, name, v["calibration"]) for rig in list_rigs()
            for name, v in _raw(rig).get("variants", {}).items() if "calibration" in v]  # fmt: skip


@pytest.mark.parametrize(("rig", "variant", "cal"), _calibrations())
def test_a_calibration_record_names_its_figures_and_holds_their_values(rig, variant, cal):
    if "target" in cal:
        fig = figure(cal["reference"])
        assert (fig.rig, fig.value) == (rig, cal["target"])
    if "repeatability" in cal:
        refs = cal["repeatability"]["references"]
        assert set(refs) == set(cal["repeatability"]["target"])
        for channel, key in refs.items():
            fig = figure(key)
            assert (fig.rig, fig.channel) == (rig, channel)
            assert fig.value == cal["repeatability"]["target"][channel]
    if "resonance" in cal:
        fig = figure(cal["resonance"]["reference"])
        assert (fig.rig, fig.value) == (rig, cal["resonance"]["target_hz"])


def test_the_side_cars_were_calibrated_on_the_figures_calibrate_names():
    from benchmarks.calibrate import CALIBRATIONS

    for rig, cal in CALIBRATIONS.items():
        record = _raw(rig)["variants"]["thesis"]["calibration"]
        assert record.get("reference") == cal.get("reference")
        if "repeatability" in cal:
            assert sorted(record["repeatability"]["references"].values()) == sorted(
                cal["repeatability"]["references"]
            )


# ------------------------------------------------------------- the benchmarks' use of them


def test_every_thesis_table_row_names_figures_of_its_rig_and_channels():
    from benchmarks.thesis_tables import NORMAL_TABLES, TABLES

    for table in TABLES + NORMAL_TABLES:
        for row in table.rows:
            assert len(row.figures) == len(table.channels), (table.name, row.label)
            for key, channel in zip(row.figures, table.channels, strict=True):
                if key is not None:
                    fig = figure(key)
                    assert (fig.rig, fig.channel) == (table.rig, channel), key
                    assert fig.table == table.name.split(":")[0]
