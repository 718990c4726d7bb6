"""The thesis tables' data: which rows each table has, the procedure each row runs, and which
reference-text figure each row compares with (keys of :mod:`vrig.reference_figures`, the one
place the text's numbers are written)."""

from __future__ import annotations

from dataclasses import dataclass, field

from benchmarks.method_factories import (
    forward_arx,
    forward_arx_per_output,
    forward_error_signal,
    forward_narx,
    forward_split,
    inverse_arx,
    inverse_narx,
    split_spectra,
)
from vrig.reference_figures import figure

__all__ = [
    "NORMAL_TABLES",
    "NOT_IN_QUICK",
    "TABLES",
    "THESIS_3_7",
    "TRUCK_9",
    "TRUCK_FORCES",
    "NormalRow",
    "NormalTable",
    "Row",
    "Table",
    "text_figures",
]


def text_figures(keys) -> tuple:
    """The text's figures [%] of ``keys`` (:mod:`vrig.reference_figures`; ``None`` stays
    ``None``: the text gives no figure for that channel)."""
    return tuple(None if k is None else figure(k).value for k in keys)


@dataclass
class Row:
    """One line of a thesis table: a procedure, where to read vrig's figure, the text's figure."""

    label: str
    method: object  # factory () -> method object, or a name
    options: dict = field(default_factory=dict)
    iteration: int = 0  # which ITxxRES the text reports
    figures: tuple = ()  # reference-figure keys (vrig.reference_figures), one per channel
    key: str = ""  # identifies a reconstruction run shared by rows (IT00 and IT05 of one run)
    quick: bool = True  # False: the full report only; a --quick report says so (NOT_IN_QUICK)

    @property
    def thesis(self) -> tuple:
        """The text's figure(s) [%], one per reported channel (``None``: not given)."""
        return text_figures(self.figures)


NOT_IN_QUICK = "not run with --quick: the full report has it"
"""The cell of a row left out of ``--quick`` (:attr:`Row.quick` False: a vrig-only row whose fit
takes minutes; none of the text's rows is left out, so every verdict stays)."""


@dataclass
class Table:
    name: str
    rig: str
    band: tuple
    channels: list  # the response channels the text reports
    rows: list
    verdict: str  # the ordering the text found, as a Python expression over row values v[i]
    claim: str  # the same in words
    note: str = ""
    baseline: int = 0  # the row gains are measured from when no row was calibrated on
    target: str = (
        "pseudo-field"  # the text's kind of desired response (vrig.desired.kinds.desired_response)
    )

    def verdict_rows(self):
        """The rows the text reports (vrig-only rows, labelled "vrig:", come after them)."""
        return [r for r in self.rows if not r.label.startswith("vrig:")]


TABLES = [
    Table(
        "Table 6.3: elastomeric damper, inverse models, IT00",
        "elastomeric-damper",
        (0.0, 25.0),
        ["damper_load"],
        [
            Row(
                "QanTiM 6th order (inverse)",
                inverse_arx(6),
                figures=("table-6.3/qantim-6-inverse",),
            ),
            Row(
                "NARX 4th order quadratic (inverse), simulation focus",
                inverse_narx(4, 2, kind="full", focus="simulation"),
                figures=("table-6.3/narx-4-quadratic-inverse",),
            ),
            Row(
                "vrig: NARX 4th order quadratic, least squares (prediction focus)",
                inverse_narx(4, 2, kind="full"),
                figures=(None,),
            ),
            Row(
                "vrig: NARX 4th order quadratic, input-polynomial",
                inverse_narx(4, 2, kind="input-polynomial"),
                figures=(None,),
            ),
            Row(
                "vrig: NARX 4th order quadratic, terms by free run (SEMP), simulation focus",
                inverse_narx(4, 2, kind="full", focus="simulation", selection="simulation"),
                figures=(None,),
            ),
            Row(
                "vrig: QanTiM 6th order, identification matched to the target (id_match)",
                inverse_arx(6),
                options={"id_match": True},
                figures=(None,),
            ),
            Row(
                "vrig: NARX 4th order quadratic, simulation focus, identification matched to the "
                "target (id_match)",
                inverse_narx(4, 2, kind="full", focus="simulation"),
                options={"id_match": True},
                figures=(None,),
            ),
        ],
        "v[1][0] < v[0][0]",
        "NARX below QanTiM",
        target="field:slow-ditch",  # §6.1.1: loads measured whilst negotiating a slow ditch
    ),
    Table(
        "Table 6.16: shock absorber (free play), inverse models",
        "shock-absorber",
        (0.0, 10.0),
        ["damper_load"],
        [
            Row(
                "QanTiM 4th order (inverse) IT00",
                inverse_arx(4),
                figures=("table-6.16/qantim-4-inverse/IT00",),
                key="arx",
            ),
            Row(
                "QanTiM 4th order (inverse) IT05",
                inverse_arx(4),
                iteration=5,
                figures=("table-6.16/qantim-4-inverse/IT05",),
                key="arx",
            ),
            Row(
                "NARX 4th order cubic (inverse) IT00, simulation focus",
                inverse_narx(4, 3, kind="full", focus="simulation"),
                figures=("table-6.16/narx-4-cubic-inverse/IT00",),
            ),
            Row(
                "vrig: NARX 4th order cubic, least squares (prediction focus), IT00",
                inverse_narx(4, 3, kind="full"),
                figures=(None,),
            ),
            Row(
                "vrig: NARX 4th order cubic, input-polynomial, IT00",
                inverse_narx(4, 3, kind="input-polynomial"),
                figures=(None,),
            ),
            # the two SEMP rows: 30 % of the --quick report's time on their own (cubic SEMP
            # over every lead candidate), so they run in the full report only
            Row(
                "vrig: NARX 4th order cubic, terms by free run (SEMP), simulation focus, IT00",
                inverse_narx(4, 3, kind="full", focus="simulation", selection="simulation"),
                figures=(None,),
                quick=False,
            ),
            Row(
                "vrig: the same plus dead-zone/saturation/|x| terms of the load (§7.4.1), IT00",
                inverse_narx(
                    4,
                    3,
                    kind="full",
                    focus="simulation",
                    selection="simulation",
                    functions=[("saturation", "auto"), ("deadzone", "auto"), "abs", "sign_square"],
                ),
                figures=(None,),
                quick=False,
            ),
        ],
        "v[1][0] < v[2][0] < v[0][0]",
        "QanTiM IT05 < NARX IT00 < QanTiM IT00",
    ),
    Table(
        "Table 6.12: radiator, inverse models, IT00 (top-tank acceleration)",
        "radiator",
        (2.0, 30.0),
        ["toptank_acc", "base_acc"],
        [
            Row(
                "QanTiM 6th order (inverse), top tank",
                inverse_arx(6, responses=["toptank_acc"]),
                figures=("table-6.12/qantim-6-inverse/toptank_acc", None),
            ),
            Row(
                "NARX 6th order quadratic (inverse), top tank, simulation focus",
                inverse_narx(6, 2, kind="full", focus="simulation", responses=["toptank_acc"]),
                figures=("table-6.12/narx-6-quadratic-inverse/toptank_acc", None),
            ),
            Row(
                "Non-square NARX 6th order quadratic, top tank + base, simulation focus",
                inverse_narx(6, 2, kind="full", focus="simulation"),
                figures=(
                    "table-6.12/non-square-narx-6-quadratic-inverse/toptank_acc",
                    "table-6.12/non-square-narx-6-quadratic-inverse/base_acc",
                ),
            ),
            Row(
                "vrig: NARX 6th order quadratic, top tank, least squares (prediction focus)",
                inverse_narx(6, 2, kind="full", responses=["toptank_acc"]),
                figures=(None, None),
            ),
            Row(
                "vrig: NARX 6th order quadratic, input-polynomial, top tank",
                inverse_narx(6, 2, kind="input-polynomial", responses=["toptank_acc"]),
                figures=(None, None),
            ),
        ],
        "v[2][0] <= v[1][0] < v[0][0]",
        "non-square NARX <= NARX < QanTiM",
        target="field:truck-front",  # §6.4.1: a road-simulation field acceleration
    ),
    Table(
        "Table 3.4: two-channel fuel tank, split vs full spectrum, IT00",
        "fuel-tank-2ch",
        (1.0, 40.0),
        ["fore_acc", "aft_acc"],
        [
            Row(
                "Full spectrum model (QanTiM 4th order)",
                inverse_arx(4),
                figures=("table-3.4/full-spectrum/fore_acc", "table-3.4/full-spectrum/aft_acc"),
            ),
            Row(
                "Combined split spectra model (12 Hz)",
                split_spectra(12.0, inverse_arx(4), inverse_arx(4)),
                figures=(
                    "table-3.4/split-spectra-12hz/fore_acc",
                    "table-3.4/split-spectra-12hz/aft_acc",
                ),
            ),
        ],
        "v[1][0] < v[0][0] and v[1][1] < v[0][1]",
        "split below full on both channels",
        note="band 1-40 Hz: the text's 7-channel rig used 1 Hz; an accelerometer sees nothing at 0 Hz",
        target="field:chassis-road",  # §3.3: a road simulation
    ),
    Table(
        "Table 3.5: motorcycle rear wheel, single vs multiple-transducer split spectra, IT00",
        "motorcycle-rear",
        (0.0, 30.0),
        ["spring_strain", "spindle_acc"],
        [
            Row(
                "Broad spectrum, strain gauge simulation",
                inverse_arx(4, responses=["spring_strain"]),
                figures=(
                    "table-3.5/broad-strain/spring_strain",
                    "table-3.5/broad-strain/spindle_acc",
                ),
            ),
            Row(
                "Broad spectrum, accelerometer simulation",
                inverse_arx(4, responses=["spindle_acc"]),
                figures=(
                    "table-3.5/broad-acceleration/spring_strain",
                    "table-3.5/broad-acceleration/spindle_acc",
                ),
            ),
            Row(
                "Split spectra (8 Hz): strain below, acceleration above",
                split_spectra(
                    8.0,
                    inverse_arx(4),
                    inverse_arx(4),
                    low_responses=["spring_strain"],
                    high_responses=["spindle_acc"],
                ),
                figures=(
                    "table-3.5/split-spectra-8hz/spring_strain",
                    "table-3.5/split-spectra-8hz/spindle_acc",
                ),
            ),
        ],
        "v[0][0] < v[1][0] and v[2][0] <= v[0][0] and v[2][1] <= v[0][1]",
        "strain beats acceleration as the single transducer; split beats broad spectrum",
        target="field:rough-road",  # §3.3: a road simulation
    ),
]


# ------------------------------------------------------------------ normal (forward) models


@dataclass
class NormalRow:
    """One line of a normal-modelling table: a forward model factory and the text's figure(s)."""

    label: str
    model: object  # factory () -> object with fit(u, y) and simulate(u)
    figures: tuple = ()  # reference-figure keys, one per output channel (None: not given)
    refocus: bool = True  # least squares diverging in free run: refit with focus="simulation"

    @property
    def thesis(self) -> tuple:
        """The text's figure(s) [%], one per output channel (``None``: not given)."""
        return text_figures(self.figures)


@dataclass
class NormalTable:
    """A normal (forward) model between measured channels (Ch. 6.1.2, 6.2, 6.3): fitted on one
    identification-type record, judged by η0 in free run on a held-out record of the same kind.

    ``inputs``/``channels``: channel names, each a drive or a response of the rig (Table 6.7's
    input is a response: the air-spring pressure). Every channel has its value at rest (zero
    drive) subtracted (the text's "pressure minus its static value"), is low-passed to the
    model band (zero-phase) and decimated to the model rate. ``levels``: identification RMS
    as fractions of each drive's full scale (halved while the rig trips), one column each."""

    name: str
    rig: str
    band: tuple
    inputs: list
    channels: list
    rows: list
    verdict: str
    claim: str
    note: str = ""
    levels: tuple = (0.05, 0.20)

    def verdict_rows(self):
        return [r for r in self.rows if not r.label.startswith("vrig:")]


TRUCK_9 = [
    "ucaf_vertical",
    "ucaf_lateral",
    "ucar_vertical",
    "ucar_lateral",
    "lcaf_vertical",
    "lcaf_lateral",
    "lcar_vertical",
    "lcar_lateral",
    "lca_angle",
]
TRUCK_FORCES = ["Fx", "Fy", "Fz", "Mx", "My", "Mz"]

NORMAL_TABLES = [
    NormalTable(
        "Table 6.5: elastomeric damper, normal models, error-signal model",
        "elastomeric-damper",
        (0.0, 25.0),
        ["actuator_disp"],
        ["damper_load"],
        [
            NormalRow(
                "QanTiM 3rd order (normal)", forward_arx(3), figures=("table-6.5/qantim-3-normal",)
            ),
            NormalRow(
                "QanTiM 3rd order (normal) + NARX 2nd order quadratic (normal) error-signal model",
                forward_error_signal(3, 2, 2),
                figures=("table-6.5/qantim-3-narx-2-error-signal",),
            ),
            NormalRow(
                "vrig: the same, error-signal NARX with simulation focus",
                forward_error_signal(3, 2, 2, focus="simulation"),
                figures=(None,),
            ),
        ],
        "v[1][0] < v[0][0]",
        "error-signal model below QanTiM",
        note="Table 6.4: actuator displacement drive -> damper load, 0-25 Hz",
    ),
    NormalTable(
        "Table 6.7: pneumatic trailer suspension, pressure -> strain, normal models",
        "pneumatic-trailer",
        (0.0, 25.0),
        ["air_pressure"],
        ["arm_strain"],
        [
            NormalRow(
                "QanTiM 5th order (normal)", forward_arx(5), figures=("table-6.7/qantim-5-normal",)
            ),
            NormalRow(
                "NARX 3rd order quadratic (normal)",
                forward_narx(3, 2),
                figures=("table-6.7/narx-3-quadratic-normal",),
            ),
            NormalRow(
                "vrig: QanTiM 5th order, simulation focus (the NARX row's fit, linear)",
                forward_arx(5, focus="simulation"),
                figures=(None,),
            ),
        ],
        "v[1][0] < v[0][0]",
        "NARX below QanTiM",
        note="Table 6.6: air-spring pressure minus its static value -> channel-three strain, "
        "0-25 Hz; drive: the wheel-pan displacement",
    ),
    NormalTable(
        "Table 6.9: light-truck front suspension, wheel forces -> upper ball joint (MISO)",
        "light-truck-front",
        (0.0, 25.0),
        TRUCK_FORCES,
        ["ubj_longitudinal"],
        [
            NormalRow(
                "QanTiM 5th order (normal)", forward_arx(5), figures=("table-6.9/qantim-5-normal",)
            ),
            NormalRow(
                "Split spectra at 2 Hz: static quadratic NARX below, QanTiM 2nd order above",
                forward_split(2.0, 0, 2, 2),
                figures=("table-6.9/split-2hz-narx-0-quadratic-qantim-2",),
            ),
        ],
        "v[1][0] < v[0][0]",
        "split spectra below QanTiM",
        note="Table 6.8: six spindle forces/moments -> upper ball-joint longitudinal force",
    ),
    NormalTable(
        "Table 6.10: light-truck front suspension, wheel forces -> control arms (non-square 6 -> 9)",
        "light-truck-front",
        (0.0, 25.0),
        TRUCK_FORCES,
        TRUCK_9,
        [
            NormalRow(
                "QanTiM 5th order (normal), one MISO model per output (vrig's linear baseline: "
                "the text gives none for 6.10)",
                forward_arx_per_output(5),
                figures=(None,) * 9,
                refocus=False,
            ),
            NormalRow(
                "Split spectra at 2 Hz: static quadratic NARX below, QanTiM 2nd order above",
                forward_split(2.0, 0, 2, 2),
                figures=(None,) * 9,
            ),
        ],
        "sum(v[1]) < sum(v[0])",
        "split spectra below QanTiM on the nine-channel mean (the text gives plots only, "
        "Figs. 6.12-6.20, no figures)",
    ),
]


THESIS_3_7 = text_figures(f"table-3.7/rig-specific-psd/{name}" for name in (
    "LF_vertical", "RF_vertical", "LR_vertical", "RR_vertical", "front_lateral", "rear_lateral",
    "longitudinal",
))  # fmt: skip
"""Table 3.7's inverse modelling error [%] per drive channel (rig-specific PSD), in the
seven-channel fuel tank's drive order."""
