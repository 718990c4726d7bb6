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

The reference text's figures are :mod:`vrig.reference_figures` (each row names its figures by
key). The package: :mod:`~benchmarks.thesis_tables.data` (the tables, their rows and figures),
:mod:`~benchmarks.thesis_tables.run` (vrig's figures per row),
:mod:`~benchmarks.thesis_tables.verdicts` (vrig against the text),
:mod:`~benchmarks.thesis_tables.render` (the markdown) and
:mod:`~benchmarks.thesis_tables.report` (the whole report and the command line). Its names are
read from those modules when first used, so ``python -m benchmarks.thesis_tables`` can set the
BLAS threads before NumPy loads.
"""

from __future__ import annotations

import importlib

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

_MODULES = ("data", "run", "verdicts", "render", "report")
"""The package's modules, in the order a name is looked up in them."""


def __getattr__(name: str):
    """A name of the package's modules (:data:`_MODULES`), imported on first use."""
    if name in _MODULES:
        return importlib.import_module(f"{__name__}.{name}")
    for module in _MODULES:
        found = getattr(importlib.import_module(f"{__name__}.{module}"), name, _MISSING)
        if found is not _MISSING:
            return found
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__() -> list:
    return sorted(set(globals()) | set(__all__) | set(_MODULES))


_MISSING = object()
