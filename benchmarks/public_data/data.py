"""Public benchmark data: where the files are, their loaders and the official splits.

Each data folder has a SOURCE.md that documents its file (origin, columns, sampling rate).
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

ENV_VAR = "VRIG_EXTERNAL_DATA"

# ---------------------------------------------------------------- data set constants
SILVERBOX_FOLDER, SILVERBOX_FILE = "silverbox", "SNLS80mV.csv"
SILVERBOX_FS = 1e7 / 2**14  # 610.35 Hz (benchmark documentation)
# nonlinear_benchmarks.Silverbox: data[100:40575] arrow, data[40650:127400] multisine (75 % train)
SILVERBOX_ARROW = (100, 40575)
SILVERBOX_ARROW_NO_EXTRAPOLATION = 32000  # samples of the arrow record
SILVERBOX_MULTISINE = (40650, 127400)
SILVERBOX_TRAIN_FRACTION = 0.75
SILVERBOX_INIT = 50
SILVERBOX_PUBLISHED_MV = 7.72768  # multisine test, SysIdentPy tutorial prints 7.727682109791501
SILVERBOX_PUBLISHED_ARROW_MV = 4.149  # arrow full, SysIdentPy tutorial (xlag=ylag=14, degree 3)
SILVERBOX_PUBLISHED_ARROW_NOEXT_MV = 2.229  # arrow without extrapolation, same tutorial

TANKS_FOLDER, TANKS_FILE = "cascaded-tanks", "dataBenchmark.csv"
TANKS_TS = 4.0
TANKS_INIT = 5

F16_FOLDER, F16_FILE = "f16-gvt-sysidentpy-subset", "f-16.txt"
F16_SPLIT = 16384
F16_PUBLISHED_RRSE = 0.291009  # SysIdentPy F-16 tutorial prints 0.2910089654603829
F16_PUBLISHED_TERMS = 30
SILVERBOX_PUBLISHED_TERMS = 5  # y(k-1), y(k-2), y(k-4), x(k-1), constant

MR_FOLDER, MR_FILE = "mr-damper-dyke-nees", "ranran_50_converted.csv"
MR_FS = 3004.8
MR_TRAIN_FRACTION = 0.70
MR_DECIMATION = 10
MR_INIT = 10  # subsampled samples


# ---------------------------------------------------------------- data location and loading
def external_data_root() -> Path:
    """``$VRIG_EXTERNAL_DATA`` if set, else ``<repo>/../shared/external-data``."""
    env = os.environ.get(ENV_VAR)
    if env:
        return Path(env)
    return Path(__file__).resolve().parents[2].parent / "shared" / "external-data"


def data_file(folder: str, name: str, root: Path | None = None) -> Path | None:
    """Path of ``root/folder/name``, or None when it does not exist."""
    path = (external_data_root() if root is None else Path(root)) / folder / name
    return path if path.is_file() else None


def _csv(path: Path, usecols, skiprows: int = 1) -> np.ndarray:
    # the benchmark CSV files end every line with a trailing comma (an empty last column)
    return np.loadtxt(path, delimiter=",", skiprows=skiprows, usecols=usecols, ndmin=2)


def load_silverbox(path: Path) -> tuple[np.ndarray, np.ndarray]:
    """Silverbox input V1 and output V2 [V], each (131072,)."""
    d = _csv(path, (0, 1))
    return d[:, 0].copy(), d[:, 1].copy()


def load_cascaded_tanks(path: Path) -> dict[str, np.ndarray | float]:
    """Cascaded Tanks: ``uEst, yEst, uVal, yVal`` (1024,) each and ``Ts`` [s]."""
    d = np.genfromtxt(path, delimiter=",", skip_header=1, usecols=(0, 1, 2, 3, 4))
    return {
        "uEst": d[:, 0].copy(),
        "uVal": d[:, 1].copy(),
        "yEst": d[:, 2].copy(),
        "yVal": d[:, 3].copy(),
        "Ts": float(d[0, 4]),  # given only in the first row
    }


def load_f16(path: Path) -> tuple[np.ndarray, np.ndarray]:
    """F-16 subset: inputs (32768, 2) = [x1, x2], output (32768,) = y."""
    d = np.loadtxt(path, delimiter=",", ndmin=2)
    return d[:, :2].copy(), d[:, 2].copy()


def load_mr_damper(path: Path) -> dict[str, np.ndarray | float]:
    """MR damper record: ``t`` [s], ``D`` [cm], ``Y`` [V], ``F`` [N] (74068,) each and ``fs``."""
    d = _csv(path, (0, 2, 3, 6))
    with open(path) as fh:
        fh.readline()
        fs = float(fh.readline().split(",")[4])  # given only in the first data row
    return {
        "t": d[:, 0].copy(),
        "D": d[:, 1].copy(),
        "Y": d[:, 2].copy(),
        "F": d[:, 3].copy(),
        "fs": fs,
    }


# ---------------------------------------------------------------- splits
def silverbox_splits() -> dict[str, tuple[int, int]]:
    """Sample ranges (start, stop) of the record: train, test (multisine), arrow tests."""
    a, b = SILVERBOX_MULTISINE
    cut = a + int((b - a) * SILVERBOX_TRAIN_FRACTION)
    arrow = SILVERBOX_ARROW
    return {
        "train": (a, cut),
        "test_multisine": (cut, b),
        "test_arrow_full": arrow,
        "test_arrow_no_extrapolation": (arrow[0], arrow[0] + SILVERBOX_ARROW_NO_EXTRAPOLATION),
    }


def mr_damper_split(n: int) -> int:
    """First test sample of the full-rate record: the first 70 % train."""
    return int(n * MR_TRAIN_FRACTION)


def mr_inputs(d, start: int, stop: int, features: str = "") -> np.ndarray:
    """Model inputs at the record's samples ``start:stop:MR_DECIMATION``: D, Y, then by
    ``features``: ``"v"`` adds the velocity ``v(t) = (D(t) - D(t - 10)) * fs / 10`` [cm/s] (the
    backward difference over one model sample; 0 at the record's first sample), ``"v,tanh:s"``
    also ``tanh(v / s)``. Fixed transforms of the measured input D, nothing is learned."""
    k = MR_DECIMATION
    idx = np.arange(start, stop, k)
    D = np.asarray(d["D"])
    cols = [D[idx], np.asarray(d["Y"])[idx]]
    names = [f for f in features.split(",") if f]
    if names:
        if names[0] != "v" or any(not f.startswith("tanh:") for f in names[1:]):
            raise ValueError(f"unknown MR damper features {features!r}")
        v = (D[idx] - D[np.maximum(idx - k, 0)]) * (float(d["fs"]) / k)
        cols.append(v)
        cols += [np.tanh(v / float(f[5:])) for f in names[1:]]
    return np.column_stack(cols)
