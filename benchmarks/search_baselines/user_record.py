"""A user's record: a CSV file with a header (columns chosen by name) or an ``.npz`` file with
arrays ``u`` and ``y``, split into a training part (the first ``train_fraction``) and a test
part (the rest, its free run started from its first ``init`` measured outputs).

Every problem with the file is a :class:`RecordError` that names the file, the column and the
line: a missing column, a value that is not a number, a NaN or infinity, a record too short for
the protocol.
"""

from __future__ import annotations

import csv
import math
from pathlib import Path

import numpy as np

from .baselines import LINEAR_ORDERS
from .records import Record, split_record
from .scoring import validation_cut

#: training fraction and measured outputs that start the test free run, unless given
DEFAULT_SPLIT = 0.5
DEFAULT_INIT = 50
#: fewest samples a score may be taken over (the test part's, the validation slice's)
MIN_SCORED = 20

__all__ = ["DEFAULT_INIT", "DEFAULT_SPLIT", "MIN_SCORED", "RecordError", "load_user_record"]


class RecordError(ValueError):
    """A user's record that cannot be scored (the message says why and where)."""


def _number(path: Path, line: int, name: str, row: list[str], i: int) -> float:
    cell = row[i].strip() if i < len(row) else ""
    try:
        v = float(cell)
    except ValueError:
        what = f"the value {cell!r}" if cell else "an empty value"
        raise RecordError(f"{path}, line {line}, column {name!r}: {what} is not a number") from None
    if not math.isfinite(v):
        raise RecordError(
            f"{path}, line {line}, column {name!r}: {cell!r} (NaN or infinite): fill or cut such "
            "values before scoring"
        )
    return v


def _read_csv(path: Path, inputs, outputs):
    if not inputs or not outputs:
        raise RecordError(f"{path}: a CSV record needs --input COL [COL ...] and --output COL")
    with open(path, newline="", encoding="utf-8-sig") as fh:
        rows = list(csv.reader(fh))
    if not rows:
        raise RecordError(f"{path}: the file is empty (a header line of column names expected)")
    header = [h.strip() for h in rows[0]]
    twice = sorted({c for c in [*inputs, *outputs] if [*inputs, *outputs].count(c) > 1})
    if twice:
        raise RecordError(f"{path}: column(s) {', '.join(twice)} given more than once")
    index = {}
    for name in [*inputs, *outputs]:
        hits = [i for i, h in enumerate(header) if h == name]
        if not hits:
            known = ", ".join(repr(h) for h in header if h)
            raise RecordError(f"{path}: no column {name!r} in the header (columns: {known})")
        if len(hits) > 1:
            raise RecordError(f"{path}: the header names column {name!r} {len(hits)} times")
        index[name] = hits[0]
    values = []
    for line, row in enumerate(rows[1:], start=2):
        if not any(cell.strip() for cell in row):
            continue  # a blank line (e.g. at the end of the file)
        values.append([_number(path, line, name, row, i) for name, i in index.items()])
    data = np.array(values, dtype=float).reshape(len(values), len(index))
    names = list(index)
    return data[:, : len(inputs)], data[:, len(inputs) :], names


def _read_npz(path: Path, inputs, outputs):
    if inputs or outputs:
        raise RecordError(
            f"{path}: --input/--output name CSV columns; an .npz record holds arrays 'u' and 'y'"
        )
    try:
        with np.load(path, allow_pickle=False) as z:
            files = list(z.files)
            arrays = {k: z[k] for k in ("u", "y") if k in files}
    except (OSError, ValueError, AttributeError) as exc:  # not an archive, pickled objects
        raise RecordError(f"{path}: not a readable .npz archive of number arrays ({exc})") from None
    missing = [k for k in ("u", "y") if k not in arrays]
    if missing:
        raise RecordError(f"{path}: no array {' or '.join(map(repr, missing))} (arrays: {files})")
    out = []
    for k, a in arrays.items():
        if a.dtype.kind not in "iuf" or a.ndim not in (1, 2):
            raise RecordError(
                f"{path}: array {k!r} must hold numbers, shape (N,) or (N, channels); got "
                f"dtype {a.dtype}, shape {a.shape}"
            )
        out.append(a.astype(float).reshape(len(a), -1))
    u, y = out
    if len(u) != len(y):
        raise RecordError(f"{path}: u has {len(u)} samples, y has {len(y)}")
    names = [f"u[{j}]" for j in range(u.shape[1])] + [f"y[{j}]" for j in range(y.shape[1])]
    return u, y, names


def _check_finite(path: Path, data: np.ndarray, names: list[str]) -> None:
    bad = ~np.isfinite(data)
    if bad.any():
        r, c = np.argwhere(bad)[0]
        raise RecordError(
            f"{path}, sample {r}, {names[c]}: {data[r, c]} (NaN or infinite; "
            f"{int(bad.sum())} such values in the record): fill or cut them before scoring"
        )


def _check_length(path: Path, n: int, train_fraction: float, init: int) -> None:
    """The test part must hold ``init`` measured + :data:`MIN_SCORED` scored samples, and the
    training part's validation slice (its last quarter) the validation window (``init``, at
    most the largest linear order) + :data:`MIN_SCORED`."""
    cut = round(n * train_fraction)
    val = cut - validation_cut(cut)
    window = min(init, max(LINEAR_ORDERS))
    if n - cut - init < MIN_SCORED or val < window + MIN_SCORED:
        raise RecordError(
            f"{path}: a record of {n} samples is too short: split {train_fraction:g} gives "
            f"{cut} training and {n - cut} test samples; the test part needs {init} measured + "
            f"{MIN_SCORED} scored samples, the training part's last quarter ({val} samples) "
            f"{window} + {MIN_SCORED}. Give a longer record, another --split or a smaller --init"
        )


def load_user_record(
    path,
    inputs=(),
    outputs=(),
    train_fraction: float = DEFAULT_SPLIT,
    init: int = DEFAULT_INIT,
    ts: float | None = None,
) -> Record:
    """The record in ``path`` (``.csv`` with a header, or ``.npz`` with ``u`` and ``y``), split.

    Parameters
    ----------
    path : str or Path
        The file.
    inputs, outputs : sequence of str
        CSV column names of the inputs and outputs (not for ``.npz``).
    train_fraction : float
        Fraction of the record (its start) that trains, in (0, 1).
    init : int
        Measured outputs that start the test free run (also the largest lag a model may have).
    ts : float, optional
        Sample interval [s], printed with the record.

    Raises
    ------
    RecordError
        for a missing file or column, a value that is not a number, NaN or infinity, a bad
        split or init, a record too short.
    """
    path = Path(path)
    if not path.is_file():
        raise RecordError(f"{path}: no such file")
    if not (isinstance(train_fraction, (int, float)) and 0 < train_fraction < 1):
        raise RecordError(f"--split must be a fraction in (0, 1), got {train_fraction!r}")
    if isinstance(init, bool) or not isinstance(init, (int, np.integer)) or init < 1:
        raise RecordError(f"--init must be an integer >= 1, got {init!r}")
    if ts is not None and not (np.isfinite(ts) and ts > 0):
        raise RecordError(f"--ts must be a positive sample interval [s], got {ts!r}")
    suffix = path.suffix.lower()
    if suffix == ".npz":
        u, y, names = _read_npz(path, inputs, outputs)
        _check_finite(path, np.hstack([u, y]), names)
    elif suffix == ".csv":
        u, y, names = _read_csv(path, inputs, outputs)  # checks every value as it reads it
    else:
        raise RecordError(f"{path}: a record is a .csv file with a header or an .npz file")
    _check_length(path, len(y), train_fraction, int(init))
    cols = f"inputs {', '.join(names[: u.shape[1]])}; outputs {', '.join(names[u.shape[1] :])}"
    return split_record(
        path.stem, path.stem, u, y, train_fraction, int(init), f"{path} ({cols})", ts
    )
