"""Free-run scores of vrig's polynomial NARX/ARX models on public nonlinear benchmark data.

Run from the repository root::

    python -m benchmarks.public_data            # all four data sets, ~3-4 min on 2 busy cores
    python -m benchmarks.public_data --quick    # smaller searches, no SysIdentPy F-16 run, no NarxSearch rows
    python -m benchmarks.public_data --only silverbox f16 --no-sysidentpy

The data are read from ``../shared/external-data/`` (next to the repository) or from the folder
named by the environment variable ``VRIG_EXTERNAL_DATA``; every data set whose folder is absent is
skipped with a reason. Each folder has a SOURCE.md that documents the file.

Protocol (the same for every data set)
    * The data are split into an identification (training) part and a test part; the split is
      printed with the scores, as sample ranges of the record.
    * The model is chosen on the training part only: every candidate structure of a small grid
      (polynomial degree, output/input lags, number of FROLS terms) is fitted on the first 75 %
      of the training part and free-run on the last 25 % (from that slice's own first measured
      outputs); the candidate with the best validation score (ties within 0.1 %: fewer terms)
      is refitted on the whole training part and kept if its free run over the training part
      stays bounded (else the next one is taken). The test part is used once, to score it.
    * Scores are free-run (simulation, outputs fed back), never one-step-ahead.
    * vrig's models mirror SysIdentPy's ``FROLS`` candidate sets: output lags 1..na, input lags
      1..nb (``Narx(na=..., nb=..., nk=1, degree=..., constant=True, n_terms=...)``), constant
      term in the candidates, least-squares re-estimation of the selected terms.
    * For Silverbox and F-16 the same search is also run with a term budget equal to the
      published model's (5 and 30 terms: rows "≤5 terms", "≤30 terms"), and vrig is run with
      the published SysIdentPy configuration itself (rows "published config").
    * Where sysidentpy is importable, SysIdentPy 0.9.0 is run in the same process on the same
      split: with the configuration of its published example where there is one (Silverbox,
      F-16), otherwise with the same candidate structure and number of terms as vrig's model.

Simulation-error rows (``focus="simulation"``, ``selection="simulation"``)
    * The simulation-error rows, the data sets, their splits and the published figures (with
      their sources) are documented in ``datasets.py``, next to their records.

Layout (``benchmarks/public_data/``)
    ``data`` (file location, loaders, official splits), ``search`` (candidate structures, scores,
    the choice on training data), ``sysidentpy`` (the optional in-process comparison),
    ``simulation`` (simulation-error searches and goal notes), ``table`` (the record types),
    ``datasets`` (the table: one :class:`DataSet` per data set, :data:`DATASETS`), ``pipeline``
    (:func:`run_dataset` runs any record, :func:`run` the table), ``report`` (rows and the
    printed table), ``cli`` (``python -m benchmarks.public_data``, ``results/public_data.json``).
"""

from .cli import RESULTS_PATH, main
from .data import (
    ENV_VAR,
    F16_FILE,
    F16_FOLDER,
    F16_PUBLISHED_RRSE,
    F16_PUBLISHED_TERMS,
    F16_SPLIT,
    MR_DECIMATION,
    MR_FILE,
    MR_FOLDER,
    MR_FS,
    MR_INIT,
    MR_TRAIN_FRACTION,
    SILVERBOX_ARROW,
    SILVERBOX_ARROW_NO_EXTRAPOLATION,
    SILVERBOX_FILE,
    SILVERBOX_FOLDER,
    SILVERBOX_FS,
    SILVERBOX_INIT,
    SILVERBOX_MULTISINE,
    SILVERBOX_PUBLISHED_ARROW_MV,
    SILVERBOX_PUBLISHED_ARROW_NOEXT_MV,
    SILVERBOX_PUBLISHED_MV,
    SILVERBOX_PUBLISHED_TERMS,
    SILVERBOX_TRAIN_FRACTION,
    TANKS_FILE,
    TANKS_FOLDER,
    TANKS_INIT,
    TANKS_TS,
    data_file,
    external_data_root,
    load_cascaded_tanks,
    load_f16,
    load_mr_damper,
    load_silverbox,
    mr_damper_split,
    mr_inputs,
    silverbox_splits,
)
from .datasets import (
    DATASETS,
    F16,
    F16_SIM,
    MR_DAMPER,
    MR_FUNCTIONS,
    MR_SIM,
    SILVERBOX,
    SILVERBOX_SIM,
    TANKS,
    TANKS_SIM,
)
from .pipeline import Fitted, run, run_dataset
from .report import Report, Row, format_table
from .search import (
    VALIDATION_FRACTION,
    Candidate,
    Pool,
    Selection,
    _score,
    _sim,
    choose,
    free_run,
    grid,
    score_candidates,
    select_and_fit,
    stable_on,
    validation_score,
)
from .simulation import Scoring, SimSearch, goal_note, simulation_rows
from .sysidentpy import SKIP_SYSIDENTPY, SysIdentPy, advance, get_sysidentpy
from .table import DataSet, Problem, Published, PublishedConfig, ScoredRecord, Sweep, Transfer

BENCHES = DATASETS  # the former name of the table

__all__ = [
    "BENCHES",
    "DATASETS",
    "ENV_VAR",
    "F16",
    "F16_FILE",
    "F16_FOLDER",
    "F16_PUBLISHED_RRSE",
    "F16_PUBLISHED_TERMS",
    "F16_SIM",
    "F16_SPLIT",
    "MR_DAMPER",
    "MR_DECIMATION",
    "MR_FILE",
    "MR_FOLDER",
    "MR_FS",
    "MR_FUNCTIONS",
    "MR_INIT",
    "MR_SIM",
    "MR_TRAIN_FRACTION",
    "RESULTS_PATH",
    "SILVERBOX",
    "SILVERBOX_ARROW",
    "SILVERBOX_ARROW_NO_EXTRAPOLATION",
    "SILVERBOX_FILE",
    "SILVERBOX_FOLDER",
    "SILVERBOX_FS",
    "SILVERBOX_INIT",
    "SILVERBOX_MULTISINE",
    "SILVERBOX_PUBLISHED_ARROW_MV",
    "SILVERBOX_PUBLISHED_ARROW_NOEXT_MV",
    "SILVERBOX_PUBLISHED_MV",
    "SILVERBOX_PUBLISHED_TERMS",
    "SILVERBOX_SIM",
    "SILVERBOX_TRAIN_FRACTION",
    "SKIP_SYSIDENTPY",
    "TANKS",
    "TANKS_FILE",
    "TANKS_FOLDER",
    "TANKS_INIT",
    "TANKS_SIM",
    "TANKS_TS",
    "VALIDATION_FRACTION",
    "Candidate",
    "DataSet",
    "Fitted",
    "Pool",
    "Problem",
    "Published",
    "PublishedConfig",
    "Report",
    "Row",
    "ScoredRecord",
    "Scoring",
    "Selection",
    "SimSearch",
    "Sweep",
    "SysIdentPy",
    "Transfer",
    "_score",
    "_sim",
    "advance",
    "choose",
    "data_file",
    "external_data_root",
    "format_table",
    "free_run",
    "get_sysidentpy",
    "goal_note",
    "grid",
    "load_cascaded_tanks",
    "load_f16",
    "load_mr_damper",
    "load_silverbox",
    "main",
    "mr_damper_split",
    "mr_inputs",
    "run",
    "run_dataset",
    "score_candidates",
    "select_and_fit",
    "silverbox_splits",
    "simulation_rows",
    "stable_on",
    "validation_score",
]
