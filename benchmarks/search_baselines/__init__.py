"""NarxSearch against the FROLS+BIC baseline and the best linear model, record by record.

Run from the repository root::

    python -m benchmarks.search_baselines                 # public sets + ball_and_beam seeds 0-2, 60 s budget
    python -m benchmarks.search_baselines --quick         # 10 s budget; ball_and_beam and Cascaded Tanks
    python -m benchmarks.search_baselines --record my.csv --input force --output disp --init 20
    python -m benchmarks.search_baselines --record my.npz --split 0.7  # arrays u (N, nu), y (N, ny)

It prints one table (record, training/scored test samples, model, terms, test NRMSE, the
record's own metric, fit seconds, NarxSearch / FROLS and NarxSearch / best linear), then per
record its split, NarxSearch's budget used (``search_time_``) and ``refit_``, how each baseline
was chosen and the goal line, and writes ``results/search_baselines.json``. Progress lines go
to stderr. The goal, per record: **NarxSearch <= 0.5x FROLS, never diverging, never worse than
the best linear model** (test NRMSE).

Records
    * The four public data sets of :mod:`benchmarks.public_data` (Silverbox, Cascaded Tanks,
      F-16, MR damper), read from ``../shared/external-data/`` or ``$VRIG_EXTERNAL_DATA`` with
      that package's loaders, official splits, test conventions and metrics; a data set whose
      file is absent is skipped with the reason. The MR damper record's inputs are those of its
      NarxSearch row there (D, Y, the velocity v and tanh(v / 2 cm/s), fixed transforms of the
      measured D); every model of the record gets the same inputs.
    * ``identification.synthetic.ball_and_beam(1000, seed=s)`` for each ``--seeds`` (default 0,
      1, 2): a closed-loop record of an open-loop unstable double integrator (beam angle in,
      ball position out); the first half trains, the second tests, 50 measured outputs start
      the test free run.
    * A user's record (``--record``; :mod:`.user_record`): a CSV file with a header, the
      columns named by ``--input``/``--output``, or an ``.npz`` file with arrays ``u`` and
      ``y``; the first ``--split`` (0.5) trains, the rest tests, ``--init`` (50) measured
      outputs start the test free run. With ``--record`` only that record runs (unless
      ``--only`` names others).

Protocol (the same for every record)
    * Every model is chosen on the training part only and scored once on the test part, by a
      free run (outputs fed back, never one step ahead) started from the test part's first
      ``init`` measured outputs (the public sets: their own convention, as
      :class:`benchmarks.public_data.table.ScoredRecord` scores them - from the model's first
      ``max_lag`` test outputs, or for Silverbox from the training record's last ones, and
      scored after the initialisation window). Score: NRMSE = RMSE / standard deviation of the
      measured test output, mean over the outputs; for the public sets also their own metric
      (RMSE mV, RMSE V, RRSE, NRMSE). No model may have a lag longer than the record's
      measured window (``init``; the public sets: their ``DataSet.skip``).
    * NarxSearch: ``identification.NarxSearch(budget=--budget, seed=0).fit(u_train, y_train)``,
      its default grid (orders capped at the measured window); the public sets get their own
      ``DataSet.search.grid`` and init window, as ``benchmarks/public_data`` runs them
      (``--default-grid``: the default grid there too). The lines under the table say which.
    * FROLS + BIC (:mod:`.baselines`): SysIdentPy 0.9 ``FROLS(order_selection=True,
      info_criteria="bic")``, Polynomial basis, least squares, where sysidentpy is importable
      (``pip install -e .[bench]``); else (or ``--no-sysidentpy``) vrig's ``Narx(na=n, nb=n,
      nk=1, degree=d, selection="frols", criterion="bic", constant=True)``, and the row says so.
      ``ylag = xlag = n`` in 1, 2, 4, 8 and degree 1, 2 are chosen by the validation below.
      Its input lags are 1..n (SysIdentPy's convention, no current input: on the MR damper,
      whose force follows the current displacement, that costs it; the linear models and
      NarxSearch's default grid have input lags from 0).
    * Best linear model: ARX (least squares) and linear output error (``Narx(degree=1,
      focus="simulation")``) of orders 1, 2, 3, 4, 6, 8, chosen by the validation below.
    * Validation of both baselines: each candidate is fitted on the first 75 % of the training
      part and run free on the last 25 % from that slice's first measured outputs (as many as
      the largest lag of the grid; the public sets: their init window), NRMSE of the rest; the
      best (ties within 0.1 %: fewer terms) is refitted on the whole training part and kept if
      its free run over it stays bounded, else the next one. NarxSearch validates by its own
      documented protocol (:mod:`identification.narx_search`), on the training part only too.
    * DIVERGED: the test free run left the model's bound (vrig raises
      ``SimulationDivergedError``; a SysIdentPy run that is not finite or leaves the same bound,
      1000x the training output's peak, counts as diverged). Ratios: NarxSearch's test NRMSE
      over the baseline's (0 when only the baseline diverged).

Layout
    ``records`` (the record type, the public and simulated records), ``user_record`` (CSV /
    npz loader), ``scoring`` (free runs, NRMSE, the validation score), ``baselines`` (the FROLS
    and linear grids, the chooser), ``protocol`` (one record through the three families, the
    goal), ``report`` (table, goal lines, JSON), ``cli``.
"""

from .baselines import FROLS_DEGREES, FROLS_LAGS, LINEAR_ORDERS, Candidate, Choice, choose
from .cli import RESULTS_PATH, main
from .protocol import GOAL_VS_FROLS, GOAL_VS_LINEAR, RecordResult, Row, ratio, run_record
from .records import Record, ScoredPart, Skipped, public_records, simulated_records, split_record
from .report import format_report, results_json
from .user_record import RecordError, load_user_record

__all__ = [
    "FROLS_DEGREES",
    "FROLS_LAGS",
    "GOAL_VS_FROLS",
    "GOAL_VS_LINEAR",
    "LINEAR_ORDERS",
    "RESULTS_PATH",
    "Candidate",
    "Choice",
    "Record",
    "RecordError",
    "RecordResult",
    "Row",
    "ScoredPart",
    "Skipped",
    "choose",
    "format_report",
    "load_user_record",
    "main",
    "public_records",
    "ratio",
    "results_json",
    "run_record",
    "simulated_records",
    "split_record",
]
