"""Reproduce the reference text's reconstruction tables on the virtual rigs, side by side.

    python -m benchmarks.thesis_tables [--quick] [--out results/thesis]
                                       [--variant NAME [NAME ...]] [--severity S]

Each row runs the same procedure as the text (rig, simulation band, model type and order, the
responses the inverse is built on, the iteration reported) on vrig's virtual rig, on the text's
own kind of desired response (:attr:`Table.target`): a service record of the rig's field twin
(:mod:`vrig.service`: the specimen in its vehicle driven over a road) where the text's target was
a field measurement (6.3 the slow ditch, 6.12 a road record, 3.4 and 3.5 road simulations), a
pseudo-field record (the rig's response to a road-like drive, §6.5) where the text used one
(6.16); every table is also run on a pseudo-field record, printed beside it (a row's inverse is
fitted once for both targets where its identification records are the same, as they are unless
the row matches the identification to its target: :mod:`benchmarks.shared_fits`). The figures
are η0 (eq. 5-28, %) of ITxxRES against DESRES, except Table 3.7 (the
inverse model's free-run error on a held-out identification record). Each table ends with the
qualitative verdict: does vrig give the text's *ordering* of the methods? The absolute values
are not expected to match (other rigs, other field data); the ordering is the physics.

Tables: 6.3 (elastomeric damper), 6.16 (shock absorber), 6.12 (radiator), 3.4 (two-channel fuel
tank, split spectra), 3.5 (motorcycle, multiple-transducer split spectra), 3.7 (seven-channel
fuel tank, rig-specific identification PSDs of Algorithm 3.1); and the normal (forward) models
between measured channels (:data:`NORMAL_TABLES`): 6.5 (damper error-signal model), 6.7
(pneumatic trailer, air-spring pressure -> strain), 6.9 and 6.10 (light-truck front suspension,
six wheel forces -> ball joint / nine control-arm channels, split spectra at 2 Hz), each fitted
on one identification-type record and scored by η0 in free run on a held-out record, at 5 % and
20 % of the drives' full scale RMS (halved while the rig trips).

``--quick``: desired responses of 20 s and identification records of 30 s (instead of 30 s and
60 s), without the rows marked :attr:`Row.quick` False (Table 6.16's two vrig-only SEMP rows,
whose cubic SEMP over every lead candidate took 30 % of the quick report's time; their cells
say :data:`NOT_IN_QUICK`; every row of the text is run, so every verdict is there).

The run ends with each table's wall time (the slowest first) and its total (also the report's
last line); NumPy's BLAS gets one thread unless ``OPENBLAS_NUM_THREADS`` etc. are set
(:mod:`benchmarks.threads`).

``--variant NAME``: each table runs on the rig's variant NAME where the rig has it, else on the
rig's default variant (e.g. the motorcycle has no ``"thesis"``); several names run each table
once per variant, side by side. ``--severity S`` scales the non-linear elements of the rigs with
a severity axis (``vrig.severity_rigs()``); the linear rigs run as loaded. Every heading names
the variant (and severity) each column ran on.

Calibrated versus predicted (issue 12): a twin's ``"thesis"`` variant was calibrated on ONE row
of its table, the text's linear baseline (``benchmarks.calibrate.CALIBRATIONS``: Table 6.3
inverse ARX(6) IT00, 6.16 ARX(4) IT00, 6.12 ARX(6) top tank IT00, 3.4 full-spectrum ARX(4)
IT00). That row is marked *calibrated on* and judged against the text within the calibration's
tolerance (±25 % relative); every other row is a *prediction*, never tuned, judged on the
text's ordering and on the size of its gain over the baseline row against the text's gain.

Closing verdict table ("text vs vrig", :func:`closing_table`, the report's last table): one row
per figure the text reports in Tables 6.3, 6.16 (IT00 and IT05), 6.12, 3.4, 3.5 and 3.7, per run
(target kind and variant), with the text's figure, vrig's, its role and a verdict
(:func:`figure_verdict`):

* the **calibrated row** (and a table's uncalibrated baseline row, Table 3.7's figures, and a
  figure whose channel has no text baseline): vrig's figure against the text's, "within ±25 %"
  (``benchmarks.calibrate.TOLERANCE``, relative, bounds included) or "outside (×r)" with
  ``r = vrig / text``. On a run that is not the calibration's own (another variant, or the
  text's kind of target where the calibration used a pseudo-field record) the calibrated row is
  marked a comparison;
* a **predicted row** (NARX, IT05, split spectra, ...): its gain over the table's linear baseline
  row (the calibrated row, else the table's ``baseline`` row) against the text's gain, each as a
  fraction of its own baseline (the rule of :func:`gain_verdicts`: the calibrated baseline itself
  only lands within ±25 % of the text's), ``r = ((b - x) / b) / ((B - X) / B)`` with ``b, x``
  vrig's baseline and row figures and ``B, X`` the text's: "holds" when ``|r - 1| <= 0.25``
  (:data:`GAIN_TOLERANCE`), else "misses (×r)" (a negative ``r``: the opposite sign of the
  text's gain; where the text has no gain, "holds" only while vrig's is below 5 % of its
  baseline);
* the **ordering** of each table (its ``claim``): "same ordering" or "different ordering" (the
  per-table ordering verdict); Table 3.7: rig-specific PSDs below the triangular PSD on all
  seven channels, as in the text;
* a procedure that failed: "not comparable".
"""

from __future__ import annotations

import argparse
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import NamedTuple

from benchmarks.threads import one_blas_thread

if __name__ == "__main__":  # before NumPy loads its BLAS: one thread (benchmarks/threads.py)
    one_blas_thread()

import numpy as np

from vrig.files import atomic_write

__all__ = [
    "NORMAL_TABLES",
    "TABLES",
    "TableRun",
    "belgian_road_example",
    "calibrated_row",
    "closing_table",
    "figure_verdict",
    "gain_verdicts",
    "normal_records",
    "resolve_variant",
    "run_normal_table",
    "table_3_7",
    "thesis_report",
    "time_summary",
]


@dataclass
class Row:
    """One line of a thesis table: a procedure, where to read vrig's figure, the text's figure."""

    label: str
    method: object  # factory () -> method object, or a name
    options: dict = field(default_factory=dict)
    iteration: int = 0  # which ITxxRES the text reports
    thesis: tuple = ()  # the text's figure(s) [%], one per reported channel
    key: str = ""  # identifies a reconstruction run shared by rows (IT00 and IT05 of one run)
    quick: bool = True  # False: the full report only; a --quick report says so (NOT_IN_QUICK)


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
    target: str = "pseudo-field"  # the text's kind of desired response (vrig.field.desired_response)

    def verdict_rows(self):
        """The rows the text reports (vrig-only rows, labelled "vrig:", come after them)."""
        return [r for r in self.rows if not r.label.startswith("vrig:")]


def _arx(order, **kw):
    from vrig.reconstruction import InverseArx

    return lambda: InverseArx(order, **kw)


def _narx(order, degree, **kw):
    from vrig.reconstruction import InverseNarx

    return lambda: InverseNarx(order, degree, **kw)


def _split(split_hz, low, high, **kw):
    from vrig.reconstruction import SplitSpectra

    return lambda: SplitSpectra(split_hz, low(), high(), **kw)


TABLES = [
    Table(
        "Table 6.3: elastomeric damper, inverse models, IT00",
        "elastomeric-damper",
        (0.0, 25.0),
        ["damper_load"],
        [
            Row("QanTiM 6th order (inverse)", _arx(6), thesis=(57,)),
            Row(
                "NARX 4th order quadratic (inverse), simulation focus",
                _narx(4, 2, kind="full", focus="simulation"),
                thesis=(24,),
            ),
            Row(
                "vrig: NARX 4th order quadratic, least squares (prediction focus)",
                _narx(4, 2, kind="full"),
                thesis=(None,),
            ),
            Row(
                "vrig: NARX 4th order quadratic, input-polynomial",
                _narx(4, 2, kind="input-polynomial"),
                thesis=(None,),
            ),
            Row(
                "vrig: NARX 4th order quadratic, terms by free run (SEMP), simulation focus",
                _narx(4, 2, kind="full", focus="simulation", selection="simulation"),
                thesis=(None,),
            ),
            Row(
                "vrig: QanTiM 6th order, identification matched to the target (id_match)",
                _arx(6),
                options={"id_match": True},
                thesis=(None,),
            ),
            Row(
                "vrig: NARX 4th order quadratic, simulation focus, identification matched to the "
                "target (id_match)",
                _narx(4, 2, kind="full", focus="simulation"),
                options={"id_match": True},
                thesis=(None,),
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
            Row("QanTiM 4th order (inverse) IT00", _arx(4), thesis=(27,), key="arx"),
            Row("QanTiM 4th order (inverse) IT05", _arx(4), iteration=5, thesis=(17,), key="arx"),
            Row(
                "NARX 4th order cubic (inverse) IT00, simulation focus",
                _narx(4, 3, kind="full", focus="simulation"),
                thesis=(18,),
            ),
            Row(
                "vrig: NARX 4th order cubic, least squares (prediction focus), IT00",
                _narx(4, 3, kind="full"),
                thesis=(None,),
            ),
            Row(
                "vrig: NARX 4th order cubic, input-polynomial, IT00",
                _narx(4, 3, kind="input-polynomial"),
                thesis=(None,),
            ),
            # the two SEMP rows: 30 % of the --quick report's time on their own (cubic SEMP
            # over every lead candidate), so they run in the full report only
            Row(
                "vrig: NARX 4th order cubic, terms by free run (SEMP), simulation focus, IT00",
                _narx(4, 3, kind="full", focus="simulation", selection="simulation"),
                thesis=(None,),
                quick=False,
            ),
            Row(
                "vrig: the same plus dead-zone/saturation/|x| terms of the load (§7.4.1), IT00",
                _narx(
                    4,
                    3,
                    kind="full",
                    focus="simulation",
                    selection="simulation",
                    functions=[("saturation", "auto"), ("deadzone", "auto"), "abs", "sign_square"],
                ),
                thesis=(None,),
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
                _arx(6, responses=["toptank_acc"]),
                thesis=(35, None),
            ),
            Row(
                "NARX 6th order quadratic (inverse), top tank, simulation focus",
                _narx(6, 2, kind="full", focus="simulation", responses=["toptank_acc"]),
                thesis=(16, None),
            ),
            Row(
                "Non-square NARX 6th order quadratic, top tank + base, simulation focus",
                _narx(6, 2, kind="full", focus="simulation"),
                thesis=(14, 12),
            ),
            Row(
                "vrig: NARX 6th order quadratic, top tank, least squares (prediction focus)",
                _narx(6, 2, kind="full", responses=["toptank_acc"]),
                thesis=(None, None),
            ),
            Row(
                "vrig: NARX 6th order quadratic, input-polynomial, top tank",
                _narx(6, 2, kind="input-polynomial", responses=["toptank_acc"]),
                thesis=(None, None),
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
            Row("Full spectrum model (QanTiM 4th order)", _arx(4), thesis=(46, 46)),
            Row(
                "Combined split spectra model (12 Hz)",
                _split(12.0, _arx(4), _arx(4)),
                thesis=(20, 19),
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
                _arx(4, responses=["spring_strain"]),
                thesis=(56, 51),
            ),
            Row(
                "Broad spectrum, accelerometer simulation",
                _arx(4, responses=["spindle_acc"]),
                thesis=(78, 31),
            ),
            Row(
                "Split spectra (8 Hz): strain below, acceleration above",
                _split(
                    8.0,
                    _arx(4),
                    _arx(4),
                    low_responses=["spring_strain"],
                    high_responses=["spindle_acc"],
                ),
                thesis=(50, 29),
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
    thesis: tuple = ()  # the text's figure(s) [%], one per output channel (None: not given)
    refocus: bool = True  # least squares diverging in free run: refit with focus="simulation"


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


def _fwd_arx(order, **kw):
    from identification import Arx

    return lambda fs: Arx(order, **kw)


def _fwd_narx(order, degree, **kw):
    from identification import Narx

    return lambda fs: Narx(order, degree, **kw)


def _fwd_error_signal(lin_order, nl_order, nl_degree, **kw):
    from identification import Arx, ErrorSignalModel, Narx

    return lambda fs: ErrorSignalModel(Arx(lin_order), Narx(nl_order, nl_degree, **kw))


class PerOutput:
    """One model per output channel (each MISO: all inputs -> one output), fitted and
    simulated independently, as a QanTiM normal model per response channel."""

    def __init__(self, factory):
        self.factory = factory

    def fit(self, u, y):
        y = np.asarray(y, float)
        self.models_ = [self.factory().fit(u, y[:, [j]]) for j in range(y.shape[1])]
        return self

    def simulate(self, u):
        return np.hstack([m.simulate(u) for m in self.models_])


def _fwd_arx_per_output(order, **kw):
    from identification import Arx

    return lambda fs: PerOutput(lambda: Arx(order, **kw))


def _fwd_split(split_hz, low_order, low_degree, high_order):
    """Forward split-spectra model (§5.5.3, §6.3; Table 6.9): ``identification.SplitSpectraModel``
    — inputs and outputs split at ``split_hz`` by a 4th-order zero-phase Butterworth low-pass
    (the text: "a 4th order digital filter"), high = x - low, one model per band at the
    record's rate, the simulated bands summed."""
    from identification import Arx, Narx, SplitSpectraModel

    return lambda fs: SplitSpectraModel(
        split_hz, fs, Narx(order=low_order, degree=low_degree), Arx(order=high_order)
    )


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
            NormalRow("QanTiM 3rd order (normal)", _fwd_arx(3), thesis=(67,)),
            NormalRow(
                "QanTiM 3rd order (normal) + NARX 2nd order quadratic (normal) error-signal model",
                _fwd_error_signal(3, 2, 2),
                thesis=(35,),
            ),
            NormalRow(
                "vrig: the same, error-signal NARX with simulation focus",
                _fwd_error_signal(3, 2, 2, focus="simulation"),
                thesis=(None,),
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
            NormalRow("QanTiM 5th order (normal)", _fwd_arx(5), thesis=(95,)),
            NormalRow("NARX 3rd order quadratic (normal)", _fwd_narx(3, 2), thesis=(34,)),
            NormalRow(
                "vrig: QanTiM 5th order, simulation focus (the NARX row's fit, linear)",
                _fwd_arx(5, focus="simulation"),
                thesis=(None,),
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
            NormalRow("QanTiM 5th order (normal)", _fwd_arx(5), thesis=(46,)),
            NormalRow(
                "Split spectra at 2 Hz: static quadratic NARX below, QanTiM 2nd order above",
                _fwd_split(2.0, 0, 2, 2),
                thesis=(34,),
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
                _fwd_arx_per_output(5),
                thesis=(None,) * 9,
                refocus=False,
            ),
            NormalRow(
                "Split spectra at 2 Hz: static quadratic NARX below, QanTiM 2nd order above",
                _fwd_split(2.0, 0, 2, 2),
                thesis=(None,) * 9,
            ),
        ],
        "sum(v[1]) < sum(v[0])",
        "split spectra below QanTiM on the nine-channel mean (the text gives plots only, "
        "Figs. 6.12-6.20, no figures)",
    ),
]


def _rest_values(rig, names) -> np.ndarray:
    """Each channel's value at rest: the mean of the last second of a 3 s zero drive."""
    from vrig.timehistory import TimeHistory

    n = round(3.0 * rig.fs)
    zero = TimeHistory(
        np.zeros((n, len(rig.inputs))), rig.fs, [c.name for c in rig.inputs],
        [c.unit for c in rig.inputs],
    )  # fmt: skip
    y = rig.run(zero, seed=0)
    rest = {c.name: 0.0 for c in rig.inputs}
    rest.update({c: float(y[c].data[-round(rig.fs) :].mean()) for c in y.names})
    return np.array([rest[c] for c in names])


def normal_records(rig, table: NormalTable, *, seconds: float, level: float, log=print):
    """The identification record (seed 1) and the held-out record (seed 2) of ``table``: an
    identification-type random drive (triangular PSD over the identification band, the band
    widened by 20 %, as ``vrig.reconstruct`` identifies) at ``level`` x each drive's full scale
    RMS, halved (up to three times) while the rig trips. Returns ``((u1, y1), (u2, y2)), fs,
    rms`` at the model rate, each channel's value at rest removed."""
    from vrig.errors import RigLimitError
    from vrig.processing import decimate, gprepro, identification_band
    from vrig.signals import random_drive, triangular_psd
    from vrig.timehistory import TimeHistory

    id_band = identification_band(table.band, fs=rig.fs)
    dec = max(1, int(rig.fs // (8 * id_band[1])))
    names = [c.name for c in rig.inputs]
    full = np.array([c.full_scale for c in rig.inputs])
    n = round(seconds * rig.fs)
    cols = list(table.inputs) + list(table.channels)
    rest = _rest_values(rig, cols)
    rms = level * full
    for _attempt in range(4):
        try:
            recs = []
            for seed in (1, 2):
                u = random_drive(
                    triangular_psd((0.0, id_band[1])), n, rig.fs, channels=len(names), rms=rms,
                    seed=seed, names=names, unit=rig.inputs[0].unit,
                )  # fmt: skip
                y = rig.run(u, seed=seed)
                both = {
                    **{c: u[c].data[:, 0] for c in names},
                    **{c: y[c].data[:, 0] for c in y.names},
                }
                x = np.column_stack([both[c] for c in cols]) - rest
                th = TimeHistory(x, rig.fs, cols)
                x = decimate(gprepro(th, table.band, detrend=False, remove_dc=False), dec).data
                k = len(table.inputs)
                recs.append((x[:, :k], x[:, k:]))
            return recs, rig.fs / dec, rms
        except RigLimitError as exc:
            log(f"  {str(exc).splitlines()[0][:120]}: halving the drive RMS")
            rms = rms / 2
    raise RigLimitError(f"{rig.name}: the identification drive trips even at 1/8 of {level:.0%} FS")


def _fit_simulate(row: NormalRow, fs: float, u1, y1, u2):
    """Fit ``row``'s model on (u1, y1) and free-run it on u2; with ``row.refocus`` a model whose
    least-squares free run diverges (``UnstableModelError``) is refitted with the simulation
    focus. Returns (simulation, refocused?)."""
    from identification import UnstableModelError

    model = row.model(fs)
    try:
        model.fit(u1, y1)
        refocused = False
    except UnstableModelError:
        if not row.refocus:
            raise
        model = _refocus(model)
        model.fit(u1, y1)
        refocused = True
    return model.simulate(u2), refocused


def _refocus(model):
    """The same model with every least-squares part switched to ``focus="simulation"``."""
    import copy

    from identification import ErrorSignalModel, Narx, SplitSpectraModel

    model = copy.deepcopy(model)
    parts = [model]
    if isinstance(model, ErrorSignalModel):
        parts += [model.linear, model.nonlinear]
    elif isinstance(model, SplitSpectraModel):
        parts += [model.low, model.high]
    for m in parts:
        if isinstance(m, Narx):
            m.focus = "simulation"
    return model


def run_normal_table(table: NormalTable, *, seconds: float, level: float, variant=None,
                     severity=None, log=print):  # fmt: skip
    """vrig's figures for one normal table at one drive level: (values, notes, rms) with values
    a list (per row) of per-channel η0 [%] (or an error string) and notes per row ("simulation
    focus" where least squares diverged)."""
    import vrig
    from identification.metrics import qantim_fit_dc

    rig = vrig.load_rig(table.rig, seed=0, variant=variant, severity=severity)
    try:
        ((u1, y1), (u2, y2)), fs, rms = normal_records(
            rig, table, seconds=seconds, level=level, log=log
        )
    except Exception as exc:
        msg = f"{type(exc).__name__}: {str(exc).splitlines()[0][:160]}"
        return [msg] * len(table.rows), [""] * len(table.rows), "-"
    rms_text = ", ".join(f"{r:.3g} {c.unit}" for r, c in zip(rms, rig.inputs, strict=True))
    values, notes = [], []
    for row in table.rows:
        t0 = time.perf_counter()
        try:
            sim, refocused = _fit_simulate(row, fs, u1, y1, u2)
            if not np.all(np.isfinite(sim)):
                raise FloatingPointError("the free run on the held-out record is not finite")
            values.append([float(e) for e in qantim_fit_dc(y2, sim)])
            notes.append("simulation focus" if refocused else "")
            log(f"  {row.label} @ {level:.0%} FS: {np.round(values[-1], 1).tolist()} %"
                f"{' (simulation focus)' if refocused else ''} ({time.perf_counter() - t0:.0f} s)")  # fmt: skip
        except Exception as exc:  # the honest figure is the failure
            values.append(f"{type(exc).__name__}: {str(exc).splitlines()[0][:160]}")
            notes.append("")
            log(f"  {row.label} @ {level:.0%} FS: FAILED {values[-1]} "
                f"({time.perf_counter() - t0:.0f} s)")  # fmt: skip
    return values, notes, rms_text


def _markdown_normal(table: NormalTable, runs) -> str:
    """``runs``: a list of (column name, setting text, values, notes, rms text) per column."""
    lines = [
        f"### {table.name}",
        "",
        f"rig `{table.rig}`, band {table.band[0]:g}-{table.band[1]:g} Hz, normal (forward) "
        f"models {', '.join(table.inputs)} -> {', '.join(table.channels)}; fitted on one "
        "identification-type record (triangular PSD, seed 1), η0 [%] in free run on a held-out "
        "record (seed 2); " + "; ".join(f"vrig({r[0]}): {r[1]}, drive RMS {r[4]}" for r in runs),
    ]
    if table.note:
        lines.append(f"({table.note})")
    head = (
        "| procedure | channel | " + " | ".join(f"vrig({r[0]}) [%]" for r in runs) + " | text [%] |"
    )
    lines += ["", head, "|" + "---|" * (3 + len(runs))]
    for i, row in enumerate(table.rows):
        for k, c in enumerate(table.channels):
            cells = []
            for r in runs:
                v, note = r[2][i], r[3][i]
                cell = _fmt(v, k)
                if note and not isinstance(v, str):
                    cell += f" ({note})"
                cells.append(cell)
            t = row.thesis[k] if k < len(row.thesis) else None
            lines.append(
                f"| {row.label} | {c} | "
                + " | ".join(cells)
                + f" | {'-' if t is None else f'{t:g}'} |"
            )
        if len(table.channels) > 1:
            cells = [_fmt([float(np.mean(r[2][i]))], 0) if not isinstance(r[2][i], str) else ""
                     for r in runs]  # fmt: skip
            lines.append(
                f"| {row.label} | mean of {len(table.channels)} | " + " | ".join(cells) + " | - |"
            )
    lines.append("")
    for name, _s, values, _n, _r in runs:
        tag = f"vrig({name})"
        lines.append(f"**Predicted ordering, {tag}:** {_verdict(table, values)}  ")
        for g in gain_verdicts(table, values, 0):
            lines.append(f"**Predicted gain over the first row, {tag}:** {g}  ")
    lines.append("")
    return "\n".join(lines)


def normal_report(requested, severity, *, seconds: float, log=print, times=None) -> list:
    """Run the normal tables (each per requested variant and drive level): markdown parts.
    ``times`` (a list, optional) gets ``(table name, wall time [s])`` per table."""
    parts = []
    for table in NORMAL_TABLES:
        t0 = time.perf_counter()
        done, runs = {}, []
        for req in requested:
            setting = _setting(table.rig, req, severity)
            for level in table.levels:
                if (setting, level) not in done:
                    log(f"{table.name} [{_setting_text(setting, req)}, {level:.0%} FS]")
                    done[(setting, level)] = run_normal_table(
                        table, seconds=seconds, level=level, variant=setting[0],
                        severity=setting[1], log=log,
                    )  # fmt: skip
                values, notes, rms_text = done[(setting, level)]
                runs.append((f"{req or setting[0]}, {level:.0%} FS", _setting_text(setting, req),
                             values, notes, rms_text))  # fmt: skip
        wall = time.perf_counter() - t0
        parts.append(_markdown_normal(table, runs) + f"_wall time {wall:.0f} s_\n")
        if times is not None:
            times.append((table.name.split(":")[0], wall))
    return parts


def resolve_variant(rig_name: str, requested: str | None) -> str:
    """The variant a table on ``rig_name`` runs on for ``--variant requested``: ``requested``
    where the rig has it, else the rig's default variant (``None``: the default)."""
    from vrig.rigs import rig_path
    from vrig.rigs.spec import read_description

    desc = read_description(rig_path(rig_name))
    return requested if requested in desc.variants else desc.default_variant


def resolve_severity(rig_name: str, severity: float | None) -> float | None:
    """``severity`` for a rig with a severity axis, ``None`` (as loaded) for a linear rig."""
    import vrig

    if severity is None or rig_name not in vrig.severity_rigs():
        return None
    return float(severity)


def _setting(rig_name: str, requested: str | None, severity: float | None) -> tuple:
    """(variant, severity) a table on ``rig_name`` runs on."""
    return resolve_variant(rig_name, requested), resolve_severity(rig_name, severity)


def _setting_text(setting: tuple, requested: str | None) -> str:
    variant, severity = setting
    text = f"variant {variant!r}"
    if requested is not None and requested != variant:
        text += f" (the rig has no {requested!r})"
    if severity is not None:
        text += f", severity {severity:g}"
    return text


def calibrated_row(table: Table) -> int | None:
    """Index of the row the rig's ``"thesis"`` variant was calibrated on, taken from
    ``benchmarks.calibrate.CALIBRATIONS`` (the single source of truth): the inverse ARX of the
    calibration's order, on its responses, at IT00, in its band. ``None`` if the rig was not
    calibrated (every row a prediction). A calibrated rig whose table has no such row, or whose
    text figure for it differs from the calibration's target, is an error."""
    from benchmarks.calibrate import CALIBRATIONS
    from vrig.reconstruction import InverseArx

    cal = CALIBRATIONS.get(table.rig)
    if cal is None or cal["target"] is None:  # no calibration, or none on a linear baseline
        return None
    if tuple(table.band) != tuple(cal["band"]):
        raise ValueError(
            f"{table.name}: band {table.band} Hz is not the band {cal['band']} Hz "
            f"{table.rig!r} was calibrated in (benchmarks/calibrate.py)"
        )
    responses = list(cal["responses"]) if cal.get("responses") else None
    for i, row in enumerate(table.verdict_rows()):
        if row.iteration or not callable(row.method):
            continue
        method = row.method()
        if not isinstance(method, InverseArx) or method.order != cal["arx_order"]:
            continue
        if (list(method.responses) if method.responses is not None else None) != responses:
            continue
        chans = _cal_channels(table)
        texts = [t for c, t in zip(table.channels, row.thesis, strict=False) if c in chans]
        if any(t != cal["target"] for t in texts):
            raise ValueError(
                f"{table.name}: row {row.label!r} gives the text's figure {row.thesis} but "
                f"{table.rig!r} was calibrated on {cal['target']:g} % (benchmarks/calibrate.py)"
            )
        return i
    raise ValueError(
        f"{table.name}: no row is the linear baseline {table.rig!r} was calibrated on "
        f"(inverse ARX({cal['arx_order']}) on {responses or 'all responses'}, IT00; "
        "benchmarks/calibrate.py CALIBRATIONS)"
    )


def _cal_channels(table: Table) -> list:
    """The channels the calibration's objective is taken on (its ``channels``, default the
    table's first channel: the rig's first output in every table here)."""
    from benchmarks.calibrate import CALIBRATIONS

    cal = CALIBRATIONS.get(table.rig, {})
    return list(cal.get("channels") or table.channels[:1])


def _desired(rig, band, seconds, cache, target: str = "pseudo-field"):
    """The table's desired response on ``rig`` (cached): ``target`` made by
    :func:`vrig.field.desired_response` (a pseudo-field record over ``band``, or a service
    record of the rig's field twin)."""
    from vrig.field import desired_response

    key = (rig.name, getattr(rig, "variant", None), getattr(rig, "severity", None), band,
           seconds, target)  # fmt: skip
    if key not in cache:
        cache[key] = desired_response(rig, target, seconds, seed=0, band=band)[0]
    return cache[key]


_SHARED = "; fit shared with the run on the other target: same identification records"


def run_table(
    table: Table,
    *,
    seconds: float,
    id_seconds: float,
    cache: dict,
    variant: str | None = None,
    severity: float | None = None,
    target: str = "pseudo-field",
    quick: bool = False,
    log=print,
):
    """vrig's figures for one table: a list (per row) of per-channel values or an error string.

    ``quick``: the rows with :attr:`Row.quick` False are not run; their value is
    :data:`NOT_IN_QUICK`.

    ``variant``/``severity``: as resolved by :func:`resolve_variant`/:func:`resolve_severity`
    (``None``: the rig's default, as loaded). ``target``: the desired response's kind
    (:func:`vrig.field.desired_response`: ``"pseudo-field"`` or ``"field:<scenario>"``).
    ``cache``: the desired responses and, under ``"fits"``, the rows' inverse fits, shared
    between the runs of a row on the same identification records
    (:class:`~benchmarks.shared_fits.SharedFit`: the default identification does not depend on
    the target, so a row's pseudo-field run reuses its field run's fit; an ``id_match`` row
    fits again)."""
    import vrig
    from benchmarks.shared_fits import SharedFit

    rig = vrig.load_rig(table.rig, seed=0, variant=variant, severity=severity)
    try:
        desired = _desired(rig, table.band, seconds, cache, target)
    except Exception as exc:  # the honest figure is the failure, for every row
        why = f"no {target} target: {type(exc).__name__}: {str(exc).splitlines()[0][:160]}"
        log(f"  {why}")
        return [why] * len(table.rows)
    runs, values, fits = {}, [], cache.setdefault("fits", {})
    for row in table.rows:
        if quick and not row.quick:
            values.append(NOT_IN_QUICK)
            continue
        key = row.key or row.label
        if key not in runs:
            iterations = max(r.iteration for r in table.rows if (r.key or r.label) == key)
            t0 = time.perf_counter()
            method = SharedFit(row.method(), (table.name, key, variant, severity), fits)
            try:
                runs[key] = vrig.reconstruct(
                    rig,
                    desired,
                    method=method,
                    iterations=iterations,
                    bandwidth=table.band,
                    id_duration=id_seconds,
                    seed=0,
                    **row.options,  # e.g. id_match: the identification matched to the target
                )
                log(
                    f"  {row.label}: {runs[key].method.describe()} ({time.perf_counter() - t0:.0f} s"
                    f"{_SHARED if method.shared else ''})"
                )
            except Exception as exc:  # the honest figure is the failure
                runs[key] = f"{type(exc).__name__}: {str(exc).splitlines()[0][:160]}"
                log(
                    f"  {row.label}: FAILED {runs[key]} ({time.perf_counter() - t0:.0f} s"
                    f"{_SHARED if method.shared else ''})"
                )
        res = runs[key]
        if isinstance(res, str):
            values.append(res)
        elif row.iteration >= len(res.errors):
            values.append(f"stopped before IT{row.iteration:02d}: {res.stopped[:120]}")
        else:
            idx = [list(res.desired.names).index(c) for c in table.channels]
            values.append([float(res.errors[row.iteration][i]) for i in idx])
    return values


def _ordering(table: Table, values) -> bool | None:
    """Does vrig give the text's ordering (``table.verdict``)? ``None``: a procedure failed."""
    n = len(table.verdict_rows())
    if any(isinstance(v, str) for v in values[:n]):
        return None
    return bool(eval(table.verdict, {}, {"v": values}))  # expressions: module constants above


def _verdict(table: Table, values) -> str:
    ok = _ordering(table, values)
    if ok is None:
        return "not comparable (a procedure failed)"
    return f"{'same ordering as' if ok else 'different ordering from'} the text ({table.claim})"


CALIBRATED_VARIANT = "thesis"  # the variant benchmarks.calibrate writes (write_variant)


def calibrated_verdict(table: Table, values, variant: str | None = CALIBRATED_VARIANT) -> str:
    """The calibrated row's verdict: each objective channel within the calibration's
    tolerance of the text's figure (the tolerance and target from ``CALIBRATIONS``). On
    another ``variant`` than the calibrated one it is said to be a comparison only."""
    from benchmarks.calibrate import CALIBRATIONS, TOLERANCE

    i = calibrated_row(table)
    if i is None:
        return (
            f"no row calibrated on: {table.rig!r} has no linear-baseline calibration "
            "(benchmarks/calibrate.py); every row is a prediction"
        )
    cal, row, v = CALIBRATIONS[table.rig], table.rows[i], values[i]
    if isinstance(v, str):
        return f"calibrated row ({row.label}) failed: {v[:120]}"
    lo, hi = cal["target"] * (1 - TOLERANCE), cal["target"] * (1 + TOLERANCE)
    figs = {c: v[table.channels.index(c)] for c in _cal_channels(table)}
    ok = all(lo <= x <= hi for x in figs.values())
    shown = ", ".join(f"{c} {x:.1f} %" for c, x in figs.items())
    note = (
        ""
        if variant == CALIBRATED_VARIANT
        else f" (variant {variant!r} is not the calibrated {CALIBRATED_VARIANT!r}: a comparison)"
    )
    return (
        f"calibrated row ({row.label}): {shown} vs the text's {cal['target']:g} % -> "
        f"{'within' if ok else 'OUTSIDE'} ±{TOLERANCE:.0%} ({lo:.1f}-{hi:.1f} %){note}"
    )


GAIN_TOLERANCE = 0.25  # relative: a predicted gain "as the text's" if within ±25 % of it


def gain_verdicts(table: Table, values, baseline: int) -> list[str]:
    """Per text-reported row other than ``baseline`` and per channel the text reports for both:
    vrig's gain over the baseline row (percentage points, and as a fraction of the baseline)
    against the text's. The size is judged on the fraction (the calibrated baseline itself
    only lands within ±25 % of the text's): "as the text's" within ±25 % relative of it,
    else larger or smaller; "none" where vrig's row is not below its baseline."""
    out = []
    for i, k, t_base, t_row in _gain_pairs(table, baseline):
        text_gain = t_base - t_row
        head = f"{table.rows[i].label}, {table.channels[k]}: "
        text = f"the text's {text_gain:g} pts ({text_gain / t_base:.0%} of {t_base:g} %)"
        if isinstance(values[i], str) or isinstance(values[baseline], str):
            out.append(head + f"not comparable (a procedure failed) vs {text}")
            continue
        b, r = values[baseline][k], values[i][k]
        gain, frac = b - r, (b - r) / b
        out.append(
            head
            + f"gain {gain:.1f} pts ({frac:.0%} of {b:.1f} %) vs {text} -> "
            + _gain_size(frac, text_gain / t_base)
        )
    return out


def _text_figure(row, k: int):
    """The text's figure of ``row`` on channel ``k`` (``None``: the text gives none)."""
    return row.thesis[k] if k < len(row.thesis) else None


def _gain_pairs(table, baseline: int):
    """``(row, channel, text baseline, text figure)`` indices and figures of every text-reported
    row other than ``baseline`` and channel the text gives a figure for in both rows."""
    for i, row in enumerate(table.verdict_rows()):
        if i == baseline:
            continue
        for k in range(len(table.channels)):
            t_base, t_row = _text_figure(table.rows[baseline], k), _text_figure(row, k)
            if t_base is not None and t_row is not None:
                yield i, k, t_base, t_row


def _gain_size(frac: float, text_frac: float) -> str:
    """vrig's relative gain ``frac`` against the text's ``text_frac`` (both signed fractions of
    their baselines: negative = worse than the baseline)."""
    if text_frac == 0:
        return "as the text's (none)" if abs(frac) < 0.05 else "a change where the text has none"
    ratio = frac / text_frac
    if ratio <= 0:
        return "none (not below the baseline)" if text_frac > 0 else "opposite to the text's"
    if _gain_holds(ratio):
        return "as the text's"
    return f"{'larger' if ratio > 1 else 'smaller'} ({ratio:.2f} x the text's)"


def _gain_holds(ratio: float) -> bool:
    """A gain ``ratio`` x the text's (relative gains) is the text's within :data:`GAIN_TOLERANCE`."""
    return abs(ratio - 1) <= GAIN_TOLERANCE


def figure_verdict(text: float, vrig, *, text_base: float | None = None, vrig_base=None) -> str:
    """The closing table's verdict on one figure (the rule in the module documentation).

    Parameters
    ----------
    text : float
        The text's figure [%] (η0 of the row on one channel).
    vrig : float or str
        vrig's figure [%] for the same row and channel; a string: the procedure failed (why).
    text_base, vrig_base : float or str, optional
        The text's and vrig's figures [%] of the table's linear baseline row on the same
        channel. Given, the figure is a predicted row judged on its gain over that baseline
        (each gain a fraction of its own baseline, as :func:`gain_verdicts`); omitted, the
        figure itself is judged (the calibrated row).

    Returns
    -------
    str
        ``"within ±25 %"`` or ``"outside (×r)"`` (``r`` = vrig / text) for a figure;
        ``"holds"`` or ``"misses (×r)"`` (``r`` = vrig's relative gain / the text's) for a gain;
        ``"not comparable (failed)"`` where vrig's procedure failed.

    Raises
    ------
    ValueError
        If only one of ``text_base`` and ``vrig_base`` is given, or a text figure is not
        positive.
    """
    from benchmarks.calibrate import TOLERANCE

    if (text_base is None) != (vrig_base is None):
        raise ValueError("give both text_base and vrig_base (a gain) or neither (a figure)")
    if not text > 0 or (text_base is not None and not text_base > 0):
        raise ValueError(f"the text's figures must be > 0 %, got {text!r} and {text_base!r}")
    if isinstance(vrig, str) or isinstance(vrig_base, str):
        return "not comparable (failed)"
    if text_base is None:
        within = text * (1 - TOLERANCE) <= vrig <= text * (1 + TOLERANCE)
        return f"within ±{100 * TOLERANCE:g} %" if within else f"outside (×{vrig / text:.2f})"
    if not vrig_base > 0:
        return "not comparable (vrig's baseline is 0 %)"
    frac, text_frac = (vrig_base - vrig) / vrig_base, (text_base - text) / text_base
    if text_frac == 0:
        return "holds" if abs(frac) < 0.05 else "misses (the text has no gain)"
    ratio = frac / text_frac
    return "holds" if _gain_holds(ratio) else f"misses (×{ratio:.2f})"


def _baseline(table: Table) -> int:
    i = calibrated_row(table)
    return table.baseline if i is None else i


def _fmt(v, k) -> str:
    if isinstance(v, str):
        return v if k == 0 else ""
    return f"{v[k]:.1f}"


class TableRun(NamedTuple):
    """One run of a :class:`Table`: a column of its report."""

    name: str  # the column's name: "variant, target"
    setting: str  # the variant (and severity) in words, with the target
    values: list  # per row: per-channel η0 [%], or why the procedure failed (a string)
    variant: str  # the calibrated verdict's variant ("thesis on field:..." on a field target)
    target: str  # the desired response's kind (vrig.field.desired_response)


def _markdown(table: Table, runs) -> str:
    """``runs``: a list of :class:`TableRun`, one per variant and target."""
    chans = table.channels
    cal_i = calibrated_row(table)
    head = "| procedure | role | "
    cols = []
    for c in chans:
        cols += [f"vrig({run[0]}) {c} [%]" for run in runs] + [f"text {c} [%]"]
    head += " | ".join(cols) + " |"
    lines = [
        f"### {table.name}",
        "",
        f"rig `{table.rig}`, band {table.band[0]:g}-{table.band[1]:g} Hz; "
        + "; ".join(f"vrig({run[0]}) ran on {run[1]}" for run in runs),
    ]
    if table.note:
        lines.append(f"({table.note})")
    lines += ["", head, "|" + "---|" * (2 + len(cols))]
    for i, row in enumerate(table.rows):
        role = "CALIBRATED ON" if i == cal_i else "predicted"
        cells = []
        for k in range(len(chans)):
            cells += [_fmt(run[2][i], k) for run in runs]
            t = row.thesis[k] if k < len(row.thesis) else None
            cells.append("-" if t is None else f"{t:g}")
        lines.append(f"| {row.label} | {role} | " + " | ".join(cells) + " |")
    lines.append("")
    base = _baseline(table)
    for name, _text, values, variant, _target in runs:
        tag = f"vrig({name})"
        lines.append(f"**Calibrated, {tag}:** {calibrated_verdict(table, values, variant)}  ")
        lines.append(f"**Predicted ordering, {tag}:** {_verdict(table, values)}  ")
        gains = gain_verdicts(table, values, base)
        what = "gain over the calibrated row" if cal_i is not None else "gain over the first row"
        for g in gains:
            lines.append(f"**Predicted {what}, {tag}:** {g}  ")
    lines.append("")
    return "\n".join(lines)


THESIS_3_7 = (20, 22, 19, 29, 23, 19, 37)


def table_3_7(*, seconds: float, order: int = 4, variant: str | None = None, log=print):
    """Table 3.7: modelling error per channel, rig-specific (Algorithm 3.1) vs triangular PSD.

    A 0-40 Hz linear sine sweep at 0.015" (0.38 mm) is played through each actuator in turn
    (the text's procedure); Algorithm 3.1 turns each actuator's sweep drive/response PSDs into
    its identification PSD. Both identification drives have the same RMS per channel (5 % of
    full scale) and the 1-40 Hz band. The modelling error is the η0 [%] of the inverse ARX
    model's free-run drive on a held-out record of the same PSD (another seed).
    """
    import vrig
    from identification import Arx, InverseModel
    from identification.metrics import qantim_fit_dc
    from vrig.processing import decimate, gprepro
    from vrig.signals import random_drive, rig_specific_psd, sine_sweep, triangular_psd
    from vrig.timehistory import TimeHistory

    rig = vrig.load_rig("fuel-tank-7ch", seed=0, variant=variant)
    band, fs, n_in = (1.0, 40.0), rig.fs, len(rig.inputs)
    names = [c.name for c in rig.inputs]
    sweep = sine_sweep(0.5, 40.0, 20.0, fs, amplitude=0.015 * 0.0254).data[:, 0]
    drv = np.zeros((sweep.size, n_in))
    res = np.zeros((sweep.size, n_in))
    for k in range(n_in):  # one actuator at a time; response k pairs with drive k
        d = np.zeros((sweep.size, n_in))
        d[:, k] = sweep
        drv[:, k] = sweep
        res[:, k] = rig.run(TimeHistory(d, fs, names, [c.unit for c in rig.inputs]), seed=k).data[
            :, k
        ]
    specific = rig_specific_psd(
        TimeHistory(drv, fs, names), TimeHistory(res, fs, [c.name for c in rig.outputs])
    )

    def band_mask(shape):  # the rig-specific shape inside the 1-40 Hz band only
        return lambda f: np.where((f >= band[0]) & (f <= band[1]), shape(f), 0.0)

    shapes = {
        "triangular": [triangular_psd(band)] * n_in,
        "rig-specific (Alg. 3.1)": [band_mask(s) for s in specific],
    }
    n = round(seconds * fs)
    dec = max(1, int(fs // (8 * band[1] * 1.2)))

    def records(psd, rms):
        recs = []
        for seed in (1, 2):  # identification, validation
            u = random_drive(psd, n, fs, channels=n_in, rms=rms, seed=seed, names=names, unit="m")
            y = rig.run(u, seed=seed)
            recs.append(
                (decimate(gprepro(u, band), dec).data, decimate(gprepro(y, band), dec).data)
            )
        return recs

    # same RMS for both PSDs: 5 % of full scale, halved (for both) while either trips the rig
    rms = 0.05 * np.array([c.full_scale for c in rig.inputs])
    for _attempt in range(5):
        try:
            data = {label: records(psd, rms) for label, psd in shapes.items()}
            break
        except vrig.RigLimitError as exc:
            log(f"  {exc}: halving the identification RMS")
            rms = rms / 2
    else:
        return names, {label: "the rig trips even at 1/32 of 5 % full scale" for label in shapes}
    log(f"  identification RMS {', '.join(f'{1e3 * r:.2f}' for r in rms)} mm")
    out = {}
    for label, ((u_id, y_id), (u_val, y_val)) in data.items():
        inv = InverseModel(Arx(order=order)).fit(u_id, y_id)
        try:
            out[label] = qantim_fit_dc(u_val, inv.simulate(y_val, bound=np.inf)).tolist()
        except Exception as exc:
            out[label] = f"{type(exc).__name__}: {str(exc)[:120]}"
        fwd = Arx(order=order).fit(u_id, y_id)  # the normal model: responses from drives
        try:
            out[label + " normal"] = qantim_fit_dc(
                y_val, fwd.simulate(u_val, bound=np.inf)
            ).tolist()
        except Exception as exc:
            out[label + " normal"] = f"{type(exc).__name__}: {str(exc)[:120]}"
        log(f"  {label}: lead {inv.lead_}, contraction {inv.contraction_:.4f}")
    return [c.name for c in rig.inputs], out


def _markdown_3_7(names, out, setting: str = "its default variant") -> str:
    lines = [
        "### Table 3.7: seven-channel fuel tank, modelling error per channel",
        "",
        f"rig `fuel-tank-7ch` ({setting}), band 1-40 Hz, QanTiM 4th order, same identification RMS for both "
        "PSDs; error = η0 [%] in free run on a held-out record of the same PSD: the inverse "
        "model's drive per drive channel (the text's measure) and the normal model's response "
        "per response channel",
        "",
        "| channel | inverse, triangular | inverse, rig-specific | text (inverse, rig-specific) "
        "| normal, triangular | normal, rig-specific |",
        "|---|---|---|---|---|---|",
    ]
    keys = ["triangular", "rig-specific (Alg. 3.1)"]
    cols = [out[k] for k in keys] + [out[k + " normal"] for k in keys]
    if any(isinstance(c, str) for c in cols):
        lines.append(
            "| failed | " + " | ".join(c if isinstance(c, str) else "" for c in cols) + " |"
        )
        return "\n".join([*lines, "", "**Verdict:** not comparable", ""])
    for i, name in enumerate(names):
        a, b, c, d = (col[i] for col in cols)
        lines.append(f"| {name} | {a:.1f} | {b:.1f} | {THESIS_3_7[i]} | {c:.1f} | {d:.1f} |")
    inv_better, fwd_better = _rig_specific_better(out), _rig_specific_better(out, " normal")
    useless = np.min(cols[:2]) >= 100
    verdict = (
        f"rig-specific PSDs give the lower inverse modelling error on {inv_better} of 7 "
        f"channels and the lower normal modelling error on {fwd_better} of 7 (the text: better "
        "on all seven)"
    )
    if useless:
        verdict += (
            "; but every inverse error is >= 100 %: the drive's low-frequency displacement, "
            "which dominates a triangular displacement PSD, leaves almost no acceleration "
            "signature, so no inverse reproduces it and the comparison is not meaningful"
        )
    return "\n".join([*lines, "", f"**Verdict:** {verdict}", ""])


_3_7_KEYS = ("triangular", "rig-specific (Alg. 3.1)")  # table_3_7's results, inverse models


def _rig_specific_better(out: dict, suffix: str = "") -> int | None:
    """On how many channels the rig-specific PSD gives the lower modelling error than the
    triangular one (``suffix`` ``" normal"``: the normal models); ``None``: a model failed."""
    tri, spec = (out.get(k + suffix) for k in _3_7_KEYS)
    if tri is None or spec is None or isinstance(tri, str) or isinstance(spec, str):
        return None
    return int(np.sum(np.asarray(spec) < np.asarray(tri)))


def belgian_road_example(
    *,
    seconds: float,
    iterations: int = 3,
    variant: str | None = None,
    log=print,
) -> str:
    """The Belgian-block road record (real wheel accelerations, 256 Hz) as the desired response
    of the seven-channel fuel-tank rig: Table 3.7's rig on the text's kind of target (a road
    simulation).

    F2D by :func:`vrig.records.belgian_block_desired` (the one place it is done: the four outer
    wheels to the four vertical accelerations, 256 -> 250 Hz, band 1-40 Hz, 5 s skipped, one
    common scale so the best linear drive needs at most half of every actuator limit); the
    inverse is built on the four vertical responses (:func:`vrig.records.belgian_block_rig`: 7
    drives from 4 responses); the lateral and longitudinal responses are not controlled and not
    scored.
    """
    import vrig
    from vrig.records import belgian_block_desired, belgian_block_path, belgian_block_rig

    try:
        path = belgian_block_path()
    except FileNotFoundError as exc:
        return f"Belgian road example skipped: {exc}\n"
    full = vrig.load_rig("fuel-tank-7ch", seed=0, variant=variant)
    rig = belgian_block_rig(full)
    band = (1.0, 40.0)
    try:
        desired = belgian_block_desired(rig, path, seconds=seconds)
        res = vrig.reconstruct(
            rig, desired, method="arx", iterations=iterations, bandwidth=band, seed=0
        )
    except Exception as exc:
        return f"Belgian road example failed: {type(exc).__name__}: {exc}\n"
    log(res.table())
    rms = np.sqrt(np.mean(np.asarray(desired.data) ** 2, axis=0))
    return (
        "### Belgian-block road record on the seven-channel fuel tank (ARX, 1-40 Hz)\n\n"
        f"rig `fuel-tank-7ch`, variant {full.variant!r}; "
        f"{seconds:g} s of the four outer wheel accelerations (vrig.records.belgian_block_desired: "
        f"scaled so the best linear drive needs at most half of every actuator limit; "
        f"{', '.join(f'{v:.2f}' for v in rms)} m/s² RMS)\n\n"
        "```\n" + res.table() + f"\n```\n{('stopped: ' + res.stopped) if res.stopped else ''}\n"
    )


_ORDERING = {None: "not comparable", True: "same ordering", False: "different ordering"}


def _cell(v) -> str:
    """vrig's figure [%] in the closing table, or the failure's kind."""
    return f"failed ({v.split(':')[0]})" if isinstance(v, str) else f"{v:.1f}"


def _channel_value(values, i: int, k: int):
    """Row ``i``'s figure on channel ``k`` (the failure string for a failed row)."""
    return values[i] if isinstance(values[i], str) else values[i][k]


def _closing_rows(table: Table, run: TableRun) -> list[tuple]:
    """The closing table's rows of one table run: (table, row, run, text, vrig, role, verdict)
    per figure the text reports, then the table's ordering."""
    short = table.name.split(":")[0].removeprefix("Table ")
    cal_i, base = calibrated_row(table), _baseline(table)
    out = []
    for i, row in enumerate(table.verdict_rows()):
        for k, channel in enumerate(table.channels):
            t, v = _text_figure(row, k), _channel_value(run.values, i, k)
            if t is None:
                continue
            label = row.label if len(table.channels) == 1 else f"{row.label}, {channel}"
            t_base = _text_figure(table.rows[base], k)
            if i == base or t_base is None:  # the figure itself
                if i == cal_i:
                    role = "calibrated on" if run.variant == CALIBRATED_VARIANT else (
                        "calibrated row (comparison)"
                    )  # fmt: skip
                else:
                    role = "prediction (baseline)" if i == base else "prediction (figure)"
                cells = (f"{t:g}", _cell(v), role, figure_verdict(t, v))
            else:  # a predicted row: its gain over the baseline row
                vb = _channel_value(run.values, base, k)
                gain = "" if isinstance(v, str) or isinstance(vb, str) else (
                    f" (gain {vb - v:.1f} of {vb:.1f})"
                )  # fmt: skip
                cells = (
                    f"{t:g} (gain {t_base - t:g} of {t_base:g})",
                    _cell(v) + gain,
                    "prediction",
                    figure_verdict(t, v, text_base=t_base, vrig_base=vb),
                )
            out.append((short, label, run.name, *cells))
    ordering = _ORDERING[_ordering(table, run.values)]
    out.append((short, f"ordering: {table.claim}", run.name, "-", "-", "prediction", ordering))
    return out


def _closing_rows_3_7(names, out: dict, variant: str) -> list[tuple]:
    """Table 3.7's closing rows: each channel's inverse modelling error with the rig-specific
    PSD against the text's, then the ordering (rig-specific below triangular everywhere)."""
    if not names:
        return []
    run = f"{variant}, held-out identification record"
    spec = out.get(_3_7_KEYS[1], "no result")
    rows = [
        ("3.7", f"inverse ARX(4), rig-specific PSD, {name}", run, f"{THESIS_3_7[i]:g}",
         _cell(_channel_value([spec], 0, i)), "prediction (figure)",
         figure_verdict(THESIS_3_7[i], _channel_value([spec], 0, i)))
        for i, name in enumerate(names)
    ]  # fmt: skip
    better = _rig_specific_better(out)
    ordering = _ORDERING[None if better is None else better == len(names)]
    if better is not None and better != len(names):
        ordering += f" ({better} of {len(names)} channels)"
    claim = "ordering: rig-specific PSD below triangular on every channel (inverse)"
    return [*rows, ("3.7", claim, run, "-", "-", "prediction", ordering)]


def closing_table(table_runs, runs_3_7=()) -> str:
    """The report's closing table "text vs vrig" (markdown): one row per figure the text
    reports in the tables of ``table_runs`` and in Table 3.7, per run, with its verdict
    (:func:`figure_verdict`; the rule in the module documentation), and a count per verdict.

    Parameters
    ----------
    table_runs : sequence of (Table, list of TableRun)
        Each table with its runs (one per variant and target kind).
    runs_3_7 : sequence of (str, list, dict)
        Table 3.7's runs: (variant, channel names, :func:`table_3_7`'s results).

    Returns
    -------
    str
        The markdown section.
    """
    rows = [r for table, runs in table_runs for run in runs for r in _closing_rows(table, run)]
    rows += [r for variant, names, out in runs_3_7 for r in _closing_rows_3_7(names, out, variant)]
    lines = [
        "### Text vs vrig: the closing verdicts",
        "",
        "One row per figure the text reports (η0 [%]). Calibrated row: within ±25 % of the "
        "text's figure or not (`r` = vrig / text). Predicted row: its gain over the table's "
        "linear baseline row (points, of that baseline) against the text's gain, each as a "
        "fraction of its own baseline: holds within ±25 % of the text's, else misses (`r` = "
        "vrig's relative gain / the text's). Ordering: the table's ordering verdict.",
        "",
        "| table | row (method/model) | run (variant, target kind) | text [%] | vrig [%] | role "
        "| verdict |",
        "|---|---|---|---|---|---|---|",
        *("| " + " | ".join(r) + " |" for r in rows),
        "",
    ]
    counts: dict = {}
    for r in rows:
        counts[r[6].split(" (")[0]] = counts.get(r[6].split(" (")[0], 0) + 1
    lines.append("verdicts: " + ", ".join(f"{n} {v}" for v, n in counts.items()))
    return "\n".join([*lines, ""])


def report_name(variants=None, severity: float | None = None) -> str:
    """The report's file name: ``thesis_reproduction.md`` on the rigs' defaults, else tagged
    with the variants and severity it ran on (so a variant run never overwrites the default's)."""
    tag = "".join(f"_{v}" for v in variants or ())
    if severity is not None:
        tag += f"_s{severity:g}"
    return f"thesis_reproduction{tag}.md"


def _check_variants(variants) -> list:
    """``variants`` as a list (``[None]``: each rig's default); a name no rig has is an error."""
    if not variants:
        return [None]
    from vrig.rigs import list_rigs, rig_path
    from vrig.rigs.spec import read_description

    known = set()
    for name in list_rigs():
        known |= set(read_description(rig_path(name)).variants)
    bad = [v for v in variants if v not in known]
    if bad:
        raise ValueError(f"unknown variant(s) {bad}: the rigs have {sorted(known)}")
    if len(set(variants)) != len(variants):
        raise ValueError(f"variant named twice in {list(variants)}")
    return list(variants)


def _table_runs(table, requested, severity, seconds, id_seconds, cache, log, quick=False) -> list:
    """The table run once per requested variant and per target: the text's kind of target
    first, then the pseudo-field record beside it (once, where the text's kind is pseudo-field);
    a list of :class:`TableRun` for :func:`_markdown`."""
    done: dict = {}  # (setting, target) -> values: a variant the rig lacks runs its default once
    runs = []
    for req in requested:
        setting = _setting(table.rig, req, severity)
        for target in dict.fromkeys([table.target, "pseudo-field"]):
            if (setting, target) not in done:
                log(f"{table.name} [{_setting_text(setting, req)}, {target}]")
                done[setting, target] = run_table(
                    table, seconds=seconds, id_seconds=id_seconds, cache=cache,
                    variant=setting[0], severity=setting[1], target=target, quick=quick, log=log,
                )  # fmt: skip
            name = f"{req or setting[0]}, {target}"
            text = f"{_setting_text(setting, req)} with a {target} desired response"
            variant = setting[0] if target == "pseudo-field" else f"{setting[0]} on {target}"
            runs.append(TableRun(name, text, done[setting, target], variant, target))
    return runs


def thesis_report(
    out_dir: Path | str,
    quick: bool = False,
    log=print,
    *,
    variants=None,
    severity: float | None = None,
    times: list | None = None,
) -> str:
    """Run every table, write the report into ``out_dir`` (:func:`report_name`) and return it.

    ``variants``: names, each table run once per name on the rig's variant of that name where
    it has one, else its default (``None``: once, on each rig's default variant).
    ``severity``: in [0, 2], for the rigs with a severity axis (``None``: as loaded).
    ``times`` (a list, optional) gets ``(table, wall time [s])`` per table (Table 3.7 and the
    Belgian road example once per variant), in the order they ran; the report's last line
    gives the same per table and the total."""
    requested = _check_variants(variants)
    if severity is not None and not (0.0 <= float(severity) <= 2.0):
        raise ValueError(f"severity must lie in [0, 2], got {severity!r}")
    seconds, id_seconds = (20.0, 30.0) if quick else (30.0, 60.0)
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    flags = " --quick" if quick else ""
    if variants:
        flags += " --variant " + " ".join(variants)
    if severity is not None:
        flags += f" --severity {severity:g}"
    parts = [
        "# Reference-text tables reproduced on the virtual rigs",
        "",
        f"desired responses of {seconds:g} s — each table on the text's own kind of target "
        "(a service record of the rig's field twin, `vrig.service`, where the text's came from "
        "a field measurement; Table 6.16 a pseudo-field record as the text's) and on a "
        "pseudo-field record beside it — identification records of "
        f"{id_seconds:g} s, seed 0; η0 (eq. 5-28) in %. Generated by "
        f"`python -m benchmarks.thesis_tables{flags}`. Role: CALIBRATED ON = the row the "
        "rig's `thesis` variant was calibrated on (benchmarks/calibrate.py CALIBRATIONS; it "
        "only says something on that variant); predicted = never tuned.",
        "",
    ]
    cache: dict = {}
    table_runs, runs_3_7, times = [], [], [] if times is None else times
    for table in TABLES:
        t = time.perf_counter()
        runs = _table_runs(table, requested, severity, seconds, id_seconds, cache, log, quick)
        times.append((table.name.split(":")[0], time.perf_counter() - t))
        table_runs.append((table, runs))
        parts.append(_markdown(table, runs))
    parts += normal_report(requested, severity, seconds=id_seconds, log=log, times=times)
    settings_7 = {}
    for req in requested:
        settings_7.setdefault(resolve_variant("fuel-tank-7ch", req), req)
    for variant, req in settings_7.items():
        text = _setting_text((variant, None), req)
        log(f"Table 3.7: seven-channel fuel tank [{text}]")
        t = time.perf_counter()
        names, out = table_3_7(seconds=id_seconds, variant=variant, log=log)
        runs_3_7.append((variant, names, out))
        parts.append(_markdown_3_7(names, out, text))
        log(f"Belgian road on the seven-channel fuel tank [{text}]")
        t1 = time.perf_counter()
        parts.append(belgian_road_example(seconds=seconds, variant=variant, log=log))
        times += [("Table 3.7", t1 - t), ("Belgian road", time.perf_counter() - t1)]
    parts.append(closing_table(table_runs, runs_3_7))
    per_table = ", ".join(f"{name} {sec:.0f} s" for name, sec in times)
    parts.append(f"_wall time per table: {per_table}; total {time.perf_counter() - t0:.0f} s_\n")
    text = "\n".join(parts)
    with atomic_write(out_dir / report_name(variants, severity), "w", encoding="utf-8") as f:
        f.write(text)
    return text


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(
        prog="python -m benchmarks.thesis_tables", description=__doc__.split("\n")[0]
    )
    ap.add_argument(
        "--quick",
        action="store_true",
        help="shorter records (desired 20 s, identification 30 s instead of 30 s and 60 s), "
        "without the vrig-only rows of the full report (Table 6.16's two SEMP rows)",
    )
    ap.add_argument(
        "--out", default="results/thesis", help="output folder (default results/thesis)"
    )
    ap.add_argument(
        "--variant",
        nargs="+",
        metavar="NAME",
        help="run each table on the rig's variant NAME where it has one, else on its default "
        "(default: each rig's default variant); several names: side by side",
    )
    ap.add_argument(
        "--severity",
        type=float,
        metavar="S",
        help="non-linearity severity in [0, 2] of the rigs with a severity axis "
        "(default: as loaded); the linear rigs run as loaded",
    )
    args = ap.parse_args(argv)
    t0, times = time.perf_counter(), []
    try:
        text = thesis_report(
            args.out, quick=args.quick, variants=args.variant, severity=args.severity, times=times
        )
    except ValueError as exc:
        ap.error(str(exc))
    print(text)
    for line in time_summary(times, time.perf_counter() - t0):
        print(line)
    return 0


def time_summary(times, wall_s: float) -> list[str]:
    """The end-of-run lines of ``python -m benchmarks.thesis_tables``: each table's wall time
    and share of the run, the slowest first, then the run's total wall time.

    Parameters
    ----------
    times : list of (str, float)
        ``(table, wall time [s])`` as :func:`thesis_report` fills them.
    wall_s : float
        The whole run's wall time [s].

    Returns
    -------
    list of str
    """
    lines = ["", "wall time per table (slowest first):"]
    for name, sec in sorted(times, key=lambda t: -t[1]):
        lines.append(f"  {sec:7.1f} s {100 * sec / max(wall_s, 1e-12):5.1f} %  {name}")
    lines.append(f"wall time {wall_s:.0f} s ({wall_s / 60:.1f} min), the whole run")
    return lines


if __name__ == "__main__":
    raise SystemExit(main())
