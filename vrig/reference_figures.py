"""The reference text's figures that vrig compares against, one record per figure.

Every number of the reference text (*Advances in dynamic response reconstruction using
non-linear time domain system identification*) that a benchmark, a calibration or a test judges
vrig against lives here once: the simulation errors of Tables 6.3, 6.12 and 6.16 (η0 of ITxxRES
against DESRES, eq. 5-28), the split-spectra errors of Tables 3.4 and 3.5, the per-channel
modelling errors of Table 3.7, the normal models' modelling errors of Tables 6.5, 6.7 and 6.9,
the repeatability numbers of §3.1 (Tables 3.1-3.3 and §3.1.1) and the resonance of Fig. 3.9 at
which §3.2.1 splits the spectrum. Each :class:`ReferenceFigure` carries where the text gives it
(table or figure, section), what it is (quantity, unit), and what it belongs to (the vrig rig
and response channel, the text's procedure, the condition); :func:`figure` looks one up by its
stable :attr:`~ReferenceFigure.key`, :func:`figures` selects several.

Readers: ``benchmarks.thesis_tables`` (the text column of every table and the closing
verdicts), ``benchmarks.calibrate`` (the calibration targets and the predicted rows),
``benchmarks.matched_identification`` (the text's ARX order per rig), and the tests.

**The rig side-cars keep their own copy, checked against this module.** A side-car
(``models/<rig>/<rig>.rig.json``) holds the text's figures in two places: its top-level
``"repeatability"`` block (read by :mod:`vrig.rigs.spec`, printed by ``vrig repeatability``)
and its calibrated variant's ``"calibration"`` record (written by ``benchmarks.calibrate
--write``). Both stay self-contained JSON with the value written out, because (1) the
side-car format is the user's: a user's own rig has its own repeatability test, not one of the
text's, so the block must hold numbers, not a key into this module; (2) the ``"calibration"``
block is a record of what the variant was calibrated on, readable without vrig installed; and
(3) the rig reader then stays independent of the reference text. The calibration records name
the figure they were calibrated on by its key (``"figure"``, and ``"figures"`` per channel for
a repeatability target), and ``tests/test_reference_figures.py`` asserts that every side-car
value equals the module's figure, so a copy that drifts fails the test rather than the
benchmark.
"""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["FIGURES", "ReferenceFigure", "figure", "figures", "repeatability_label"]


@dataclass(frozen=True)
class ReferenceFigure:
    """One figure the reference text reports.

    Attributes
    ----------
    key : str
        Stable look-up key, ``"<table>/<procedure>[/<channel or condition>]"``, e.g.
        ``"table-6.16/qantim-4-inverse/IT00"``.
    value : float
        The text's number, as printed (e.g. 27 for "27 %").
    unit : str
        Its unit (``"%"`` or ``"Hz"``).
    quantity : str
        What the number is: ``"simulation error"`` (η0 of ITxxRES against DESRES, eq. 5-28),
        ``"modelling error"`` (η0 of a model's free run on a held-out record),
        ``"repeatability number"`` (§3.1) or ``"resonance"``.
    table : str
        Where the text gives it: ``"Table 6.16"``, ``"Figure 3.9"`` or ``"Sec. 3.1.1"``.
    section : str
        The text's section, e.g. ``"6.5"``.
    rig : str
        The vrig rig that stands for the text's test system.
    channel : str
        The vrig channel the figure is on (a response; a drive for Table 3.7's inverse
        modelling error); ``""``: every objective channel (Fig. 3.9's resonance).
    method : str
        The text's procedure in its own words (the row label of its table).
    order : int or None
        The model order of the procedure (QanTiM/NARX order; the linear part for a combined
        model); ``None`` where no model is fitted.
    band : tuple of float or None
        The simulation band the text used [Hz], where it states one.
    condition : str
        What else singles the figure out (the iteration, the mounting, the identification
        PSD, the text's channel label); ``""``: nothing.
    """

    key: str
    value: float
    unit: str
    quantity: str
    table: str
    section: str
    rig: str
    channel: str
    method: str
    order: int | None = None
    band: tuple[float, float] | None = None
    condition: str = ""


def _percent(quantity, key, value, table, section, rig, channel, method, order, band, condition=""):
    """A figure [%] of ``quantity``; the other arguments in :class:`ReferenceFigure`'s order."""
    return ReferenceFigure(key, value, "%", quantity, table, section, rig, channel, method,
                           order=order, band=band, condition=condition)  # fmt: skip


def _sim(*args, **kw):
    """A simulation error [%] (η0, eq. 5-28, of ITxxRES against DESRES)."""
    return _percent("simulation error", *args, **kw)


def _model(*args, **kw):
    """A modelling error [%] (η0 of a model's free run on a held-out record)."""
    return _percent("modelling error", *args, **kw)


def _rep(key, value, table, section, rig, channel, band, condition=""):
    """A repeatability number [%] (§3.1: 100 - mean η0 of each run against the mean run)."""
    method = "five runs of one triangular-PSD random drive"
    return _percent("repeatability number", key, value, table, section, rig, channel, method,
                    None, band, condition)  # fmt: skip


_T37 = "table-3.7/rig-specific-psd"
_T37_CHANNELS = [  # (vrig drive, the text's label, IDDRV amplitude, model order, error %)
    ("LF_vertical", "L/F vertical", '1"', 4, 20.0),
    ("RF_vertical", "R/F vertical", '1"', 9, 22.0),
    ("LR_vertical", "L/R vertical", '1"', 6, 19.0),
    ("RR_vertical", "R/R vertical", '1"', 7, 29.0),
    ("front_lateral", "Front lateral", '0.2"', 5, 23.0),
    ("rear_lateral", "Rear lateral", '0.2"', 7, 19.0),
    ("longitudinal", "Longitudinal", '0.2"', 6, 37.0),
]

_ALL = [
    # ---------------------------------------------- Table 6.3: elastomeric damper, §6.1.1
    _sim(
        "table-6.3/qantim-6-inverse",
        57.0,
        "Table 6.3",
        "6.1.1",
        "elastomeric-damper",
        "damper_load",
        "QanTiM 6th order model (inverse)",
        6,
        (0.0, 25.0),
        "IT00RES",
    ),
    _sim(
        "table-6.3/narx-4-quadratic-inverse",
        24.0,
        "Table 6.3",
        "6.1.1",
        "elastomeric-damper",
        "damper_load",
        "NARX 4th order quadratic model (inverse)",
        4,
        (0.0, 25.0),
        "IT00RES",
    ),
    # ---------------------------------------------- Table 6.5: elastomeric damper, §6.1.2
    _model(
        "table-6.5/qantim-3-normal",
        67.0,
        "Table 6.5",
        "6.1.2",
        "elastomeric-damper",
        "damper_load",
        "QanTiM 3rd order model (normal)",
        3,
        (0.0, 25.0),
    ),
    _model(
        "table-6.5/qantim-3-narx-2-error-signal",
        35.0,
        "Table 6.5",
        "6.1.2",
        "elastomeric-damper",
        "damper_load",
        "Combined QanTiM 3rd order (normal) and NARX "
        "2nd order (normal) non-linear error signal model",
        3,
        (0.0, 25.0),
    ),
    # ---------------------------------------------- Table 6.7: pneumatic trailer, §6.2
    _model(
        "table-6.7/qantim-5-normal",
        95.0,
        "Table 6.7",
        "6.2",
        "pneumatic-trailer",
        "arm_strain",
        "QanTiM 5th order model (normal)",
        5,
        (0.0, 25.0),
        "air-spring pressure -> channel-three strain",
    ),
    _model(
        "table-6.7/narx-3-quadratic-normal",
        34.0,
        "Table 6.7",
        "6.2",
        "pneumatic-trailer",
        "arm_strain",
        "NARX 3rd order quadratic model (normal)",
        3,
        (0.0, 25.0),
        "air-spring pressure -> channel-three strain",
    ),
    # ---------------------------------------------- Table 6.9: light truck, §6.3.1
    _model(
        "table-6.9/qantim-5-normal",
        46.0,
        "Table 6.9",
        "6.3.1",
        "light-truck-front",
        "ubj_longitudinal",
        "QanTiM 5th order model (normal)",
        5,
        (0.0, 25.0),
        "six spindle forces/moments -> upper ball-joint longitudinal force",
    ),
    _model(
        "table-6.9/split-2hz-narx-0-quadratic-qantim-2",
        34.0,
        "Table 6.9",
        "6.3.1",
        "light-truck-front",
        "ubj_longitudinal",
        "Split spectra NARX model: frequency split "
        "at 2 Hz, low: NARX 0th order (static) quadratic, high: QanTiM 2nd order (normal)",
        2,
        (0.0, 25.0),
        "six spindle forces/moments -> upper ball-joint longitudinal force",
    ),
    # ---------------------------------------------- Table 6.12: radiator, §6.4.1
    _sim(
        "table-6.12/qantim-6-inverse/toptank_acc",
        35.0,
        "Table 6.12",
        "6.4.1",
        "radiator",
        "toptank_acc",
        "QanTiM 6th order model (inverse)",
        6,
        (2.0, 30.0),
        "IT00RES",
    ),
    _sim(
        "table-6.12/narx-6-quadratic-inverse/toptank_acc",
        16.0,
        "Table 6.12",
        "6.4.1",
        "radiator",
        "toptank_acc",
        "NARX 6th order quadratic model (inverse)",
        6,
        (2.0, 30.0),
        "IT00RES",
    ),
    _sim(
        "table-6.12/non-square-narx-6-quadratic-inverse/toptank_acc",
        14.0,
        "Table 6.12",
        "6.4.1",
        "radiator",
        "toptank_acc",
        "Non-square NARX 6th order quadratic model (inverse)",
        6,
        (2.0, 30.0),
        "IT00RES",
    ),
    _sim(
        "table-6.12/non-square-narx-6-quadratic-inverse/base_acc",
        12.0,
        "Table 6.12",
        "6.4.1",
        "radiator",
        "base_acc",
        "Non-square NARX 6th order quadratic model (inverse)",
        6,
        (2.0, 30.0),
        "IT00RES (base acceleration)",
    ),
    # ---------------------------------------------- Table 6.16: shock absorber, §6.5
    _sim(
        "table-6.16/qantim-4-inverse/IT00",
        27.0,
        "Table 6.16",
        "6.5",
        "shock-absorber",
        "damper_load",
        "QanTiM 4th order model (inverse)",
        4,
        (0.0, 10.0),
        "IT00RES",
    ),
    _sim(
        "table-6.16/qantim-4-inverse/IT05",
        17.0,
        "Table 6.16",
        "6.5",
        "shock-absorber",
        "damper_load",
        "QanTiM 4th order model (inverse)",
        4,
        (0.0, 10.0),
        "IT05RES",
    ),
    _sim(
        "table-6.16/narx-4-cubic-inverse/IT00",
        18.0,
        "Table 6.16",
        "6.5",
        "shock-absorber",
        "damper_load",
        "NARX 4th order cubic model (inverse)",
        4,
        (0.0, 10.0),
        "IT00RES",
    ),
    # ---------------------------------------------- Table 3.4: two-channel fuel tank, §3.2.1
    _sim(
        "table-3.4/full-spectrum/fore_acc",
        46.0,
        "Table 3.4",
        "3.2.1",
        "fuel-tank-2ch",
        "fore_acc",
        "Full spectra model",
        4,
        None,
        "Channel 1",
    ),
    _sim(
        "table-3.4/full-spectrum/aft_acc",
        46.0,
        "Table 3.4",
        "3.2.1",
        "fuel-tank-2ch",
        "aft_acc",
        "Full spectra model",
        4,
        None,
        "Channel 2",
    ),
    _sim(
        "table-3.4/split-spectra-12hz/fore_acc",
        20.0,
        "Table 3.4",
        "3.2.1",
        "fuel-tank-2ch",
        "fore_acc",
        "Combined split spectra model (12 Hz)",
        4,
        None,
        "Channel 1",
    ),
    _sim(
        "table-3.4/split-spectra-12hz/aft_acc",
        19.0,
        "Table 3.4",
        "3.2.1",
        "fuel-tank-2ch",
        "aft_acc",
        "Combined split spectra model (12 Hz)",
        4,
        None,
        "Channel 2",
    ),
    # ---------------------------------------------- Table 3.5: motorcycle rear, §3.2.2
    _sim(
        "table-3.5/broad-strain/spring_strain",
        56.0,
        "Table 3.5",
        "3.2.2",
        "motorcycle-rear",
        "spring_strain",
        "Coil spring strain gauge simulation (broad spectrum)",
        4,
        (0.0, 30.0),
        "Strain",
    ),
    _sim(
        "table-3.5/broad-strain/spindle_acc",
        51.0,
        "Table 3.5",
        "3.2.2",
        "motorcycle-rear",
        "spindle_acc",
        "Coil spring strain gauge simulation (broad spectrum)",
        4,
        (0.0, 30.0),
        "Acceleration",
    ),
    _sim(
        "table-3.5/broad-acceleration/spring_strain",
        78.0,
        "Table 3.5",
        "3.2.2",
        "motorcycle-rear",
        "spring_strain",
        "Spindle accelerometer simulation (broad spectrum)",
        4,
        (0.0, 30.0),
        "Strain",
    ),
    _sim(
        "table-3.5/broad-acceleration/spindle_acc",
        31.0,
        "Table 3.5",
        "3.2.2",
        "motorcycle-rear",
        "spindle_acc",
        "Spindle accelerometer simulation (broad spectrum)",
        4,
        (0.0, 30.0),
        "Acceleration",
    ),
    _sim(
        "table-3.5/split-spectra-8hz/spring_strain",
        50.0,
        "Table 3.5",
        "3.2.2",
        "motorcycle-rear",
        "spring_strain",
        "Combined split spectra simulation results",
        4,
        (0.0, 30.0),
        "Strain",
    ),
    _sim(
        "table-3.5/split-spectra-8hz/spindle_acc",
        29.0,
        "Table 3.5",
        "3.2.2",
        "motorcycle-rear",
        "spindle_acc",
        "Combined split spectra simulation results",
        4,
        (0.0, 30.0),
        "Acceleration",
    ),
    # ---------------------------------------------- Table 3.7: seven-channel fuel tank, §3.3.1
    *(
        _model(
            f"{_T37}/{name}",
            error,
            "Table 3.7",
            "3.3.1",
            "fuel-tank-7ch",
            name,
            "MISO rig-specific modelling (inverse)",
            order,
            (1.0, 40.0),
            f"Ch {i} {label}, rig-specific PSD, IDDRV amplitude {amp}",
        )
        for i, (name, label, amp, order, error) in enumerate(_T37_CHANNELS, start=1)
    ),
    # ---------------------------------------------- repeatability, §3.1
    _rep("sec-3.1.1/shaft_acc", 99.75, "Sec. 3.1.1", "3.1.1", "shaker", "shaft_acc", (0.0, 80.0)),
    _rep(
        "table-3.1/threaded/damper_load",
        98.49,
        "Table 3.1",
        "3.1.2",
        "shock-absorber",
        "damper_load",
        (0.0, 10.0),
        "threaded mounting",
    ),
    _rep(
        "table-3.1/rubber-bush/damper_load",
        98.45,
        "Table 3.1",
        "3.1.2",
        "shock-absorber",
        "damper_load",
        (0.0, 10.0),
        "rubber-bush mounting",
    ),
    _rep(
        "table-3.2/spindle_acc",
        97.80,
        "Table 3.2",
        "3.1.3",
        "motorcycle-rear",
        "spindle_acc",
        (0.0, 30.0),
    ),
    _rep(
        "table-3.2/spring_strain",
        98.15,
        "Table 3.2",
        "3.1.3",
        "motorcycle-rear",
        "spring_strain",
        (0.0, 30.0),
    ),
    _rep("table-3.3/base_acc", 97.76, "Table 3.3", "3.1.4", "radiator", "base_acc", (0.0, 25.0)),
    _rep(
        "table-3.3/toptank_acc", 96.95, "Table 3.3", "3.1.4", "radiator", "toptank_acc", (0.0, 25.0)
    ),
    # ---------------------------------------------- the resonance at the split, §3.2.1
    ReferenceFigure(
        "figure-3.9/resonance",
        12.0,
        "Hz",
        "resonance",
        "Figure 3.9",
        "3.2.1",
        "fuel-tank-2ch",
        "",
        "identification frequency response",
        condition="the resonant peak, where the spectrum is split (below / above 12 Hz)",
    ),
]

FIGURES: dict[str, ReferenceFigure] = {f.key: f for f in _ALL}
"""Every figure, by :attr:`ReferenceFigure.key` (in the text's table order)."""
if len(FIGURES) != len(_ALL):  # a key written twice would silently drop a figure
    raise RuntimeError("vrig.reference_figures: a key is given twice")


def figure(key: str) -> ReferenceFigure:
    """The figure of ``key``.

    Parameters
    ----------
    key : str
        A :attr:`ReferenceFigure.key`, e.g. ``"table-6.16/qantim-4-inverse/IT00"``.

    Returns
    -------
    ReferenceFigure

    Raises
    ------
    KeyError
        If no figure has that key (the message lists the keys of the same table).
    """
    try:
        return FIGURES[key]
    except KeyError:
        head = key.split("/")[0]
        near = [k for k in FIGURES if k.split("/")[0] == head]
        raise KeyError(
            f"no reference figure {key!r}; {head!r} has {near}"
            if near
            else f"no reference figure {key!r}; the tables are "
            f"{sorted({k.split('/')[0] for k in FIGURES})}"
        ) from None


def figures(**match) -> list[ReferenceFigure]:
    """The figures whose fields equal every ``field=value`` given, in the text's order.

    Parameters
    ----------
    **match
        Field names of :class:`ReferenceFigure` and the values they must have, e.g.
        ``table="Table 3.3"`` or ``rig="radiator", quantity="repeatability number"``.

    Returns
    -------
    list of ReferenceFigure

    Raises
    ------
    TypeError
        If a name is not a field of :class:`ReferenceFigure`.
    """
    fields = ReferenceFigure.__dataclass_fields__
    bad = sorted(set(match) - set(fields))
    if bad:
        raise TypeError(f"not a field of ReferenceFigure: {bad}; the fields are {list(fields)}")
    return [f for f in _ALL if all(getattr(f, k) == v for k, v in match.items())]


def repeatability_label(fig: ReferenceFigure) -> str:
    """Where a repeatability number stands in the text, as the side-cars' ``"repeatability"``
    block names it: the table, with the condition in brackets where there is one.

    Parameters
    ----------
    fig : ReferenceFigure
        A repeatability number.

    Returns
    -------
    str
        E.g. ``"Table 3.1 (rubber-bush mounting)"`` or ``"Table 3.3"``.
    """
    return f"{fig.table} ({fig.condition})" if fig.condition else fig.table
