"""TimeHistory: samples x channels with a sample rate, channel names and units.

Time is axis 0. A TimeHistory is immutable in spirit (its array is read-only); operations return
new objects.
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .errors import FileFormatError
from .files import atomic_write, read_npz

__all__ = ["TimeHistory"]


@dataclass(frozen=True, eq=False)
class TimeHistory:
    """A multi-channel record sampled at ``fs``.

    Parameters
    ----------
    data : array (N, n_channels) or (N,)
        Samples, time on axis 0.
    fs : float
        Sample rate in Hz.
    names : sequence of str, optional
        Channel names (unique); default ``ch1, ch2, ...``.
    units : sequence of str, optional
        Channel units (SI, e.g. ``"m"``, ``"N"``, ``"m/s^2"``); default ``"-"``.

    Examples
    --------
    >>> th = TimeHistory(np.zeros((100, 2)), fs=200.0, names=["x", "F"], units=["m", "N"])
    >>> th["F"].names
    ('F',)
    >>> th.duration
    0.5
    """

    data: np.ndarray
    fs: float
    names: tuple[str, ...] = ()
    units: tuple[str, ...] = ()

    def __post_init__(self):
        data = np.array(self.data, dtype=np.float64)  # own copy
        if data.ndim == 1:
            data = data[:, None]
        if data.ndim != 2:
            raise ValueError(
                f"TimeHistory data must be (N,) or (N, channels), got shape {data.shape}"
            )
        if data.shape[0] == 0:
            raise ValueError("TimeHistory needs at least one sample")
        if not np.all(np.isfinite(data)):
            bad = np.argwhere(~np.isfinite(data))[0]
            raise ValueError(
                f"TimeHistory data contains NaN or inf (first at sample {bad[0]}, channel {bad[1]})"
            )
        fs = float(self.fs)
        if not (np.isfinite(fs) and fs > 0):
            raise ValueError(f"fs must be a positive sample rate in Hz, got {self.fs!r}")
        n = data.shape[1]
        names = tuple(self.names) if self.names else tuple(f"ch{i + 1}" for i in range(n))
        units = tuple(self.units) if self.units else ("-",) * n
        if len(names) != n or len(units) != n:
            raise ValueError(
                f"{n} channels but {len(names)} names and {len(units)} units were given"
            )
        if len(set(names)) != n:
            raise ValueError(f"channel names must be unique, got {names}")
        data.setflags(write=False)
        object.__setattr__(self, "data", data)
        object.__setattr__(self, "fs", fs)
        object.__setattr__(self, "names", tuple(str(s) for s in names))
        object.__setattr__(self, "units", tuple(str(s) for s in units))

    # ------------------------------------------------------------------ basics
    @property
    def n_samples(self) -> int:
        """Number of samples (rows of ``data``)."""
        return int(self.data.shape[0])

    @property
    def n_channels(self) -> int:
        """Number of channels (columns of ``data``)."""
        return int(self.data.shape[1])

    @property
    def dt(self) -> float:
        """Sample interval ``1 / fs`` in s."""
        return 1.0 / self.fs

    @property
    def duration(self) -> float:
        """Record length in seconds (``n_samples / fs``)."""
        return self.n_samples / self.fs

    @property
    def time(self) -> np.ndarray:
        """Sample times in seconds, starting at 0."""
        return np.arange(self.n_samples) / self.fs

    def __len__(self) -> int:
        return self.n_samples

    def __array__(self, dtype=None, copy=None):
        return self.data if dtype is None else self.data.astype(dtype)

    def __repr__(self) -> str:
        chans = ", ".join(f"{n} [{u}]" for n, u in zip(self.names, self.units, strict=True))
        return (
            f"TimeHistory({self.n_samples} samples at {self.fs:g} Hz, {self.duration:g} s: {chans})"
        )

    # ------------------------------------------------------------------ selection
    def index(self, name: str) -> int:
        """Column index of the channel called ``name``.

        Parameters
        ----------
        name : str
            A channel name.

        Raises
        ------
        KeyError
            If there is no channel of that name (the message lists the names).
        """
        try:
            return self.names.index(name)
        except ValueError:
            raise KeyError(f"no channel {name!r}; channels are {list(self.names)}") from None

    def __getitem__(self, key) -> TimeHistory:
        """Select channels by name (``th["F"]``, ``th[["x", "F"]]``) or index/slice."""
        if isinstance(key, str):
            idx = [self.index(key)]
        elif (
            isinstance(key, Sequence)
            and not isinstance(key, str)
            and all(isinstance(k, str) for k in key)
        ):
            idx = [self.index(k) for k in key]
        elif isinstance(key, (int, np.integer)):
            idx = [int(key)]
        elif isinstance(key, slice):
            idx = list(range(self.n_channels))[key]
        else:
            idx = list(np.arange(self.n_channels)[key])
        return TimeHistory(
            self.data[:, idx], self.fs, [self.names[i] for i in idx], [self.units[i] for i in idx]
        )

    def channel(self, name: str) -> np.ndarray:
        """The samples of one channel as a 1-D array.

        Parameters
        ----------
        name : str
            A channel name.
        """
        return self.data[:, self.index(name)]

    def window(self, start: float = 0.0, stop: float | None = None) -> TimeHistory:
        """The samples with ``start <= t < stop`` (seconds).

        Parameters
        ----------
        start : float, optional
            First time kept, in s from the record's start.
        stop : float, optional
            End of the window (excluded), in s; default the end of the record.
        """
        i0 = round(start * self.fs)
        i1 = self.n_samples if stop is None else round(stop * self.fs)
        if not 0 <= i0 < i1 <= self.n_samples:
            raise ValueError(
                f"window [{start}, {stop}) s is outside the record (0 .. {self.duration} s)"
            )
        return self.with_data(self.data[i0:i1])

    def with_data(self, data) -> TimeHistory:
        """Same sample rate, names and units, new samples.

        Parameters
        ----------
        data : array_like, shape (n_samples, n_channels)
            The new samples, one column per channel of this history, in its units.
        """
        return TimeHistory(data, self.fs, self.names, self.units)

    # ------------------------------------------------------------------ persistence
    def save(self, path) -> Path:
        """Write an ``.npz`` with the data, ``fs``, names and units (atomically: see
        :func:`vrig.files.atomic_write`); a missing or other suffix becomes ``.npz``.

        Parameters
        ----------
        path : str or os.PathLike
            Target file.
        """
        path = Path(path)
        if path.suffix != ".npz":
            path = path.with_suffix(".npz")
        meta = {
            "format": "vrig-timehistory",
            "version": 1,
            "names": list(self.names),
            "units": list(self.units),
            "fs": self.fs,
        }
        with atomic_write(path) as f:  # a kill leaves the old file or the new one
            np.savez(f, data=self.data, meta=np.array(json.dumps(meta)))
        return path

    @classmethod
    def load(cls, path) -> TimeHistory:
        """Read a file written by :meth:`save`.

        Parameters
        ----------
        path : str or os.PathLike
            A file written by :meth:`save`.

        Raises
        ------
        FileNotFoundError
            If there is no such file.
        FileFormatError
            If the file is not a TimeHistory ``.npz``: not a regular file, larger than
            :data:`vrig.files.MAX_FILE_BYTES`, truncated or corrupt, without the ``data`` and
            ``meta`` arrays or the ``fs``, ``names``, ``units`` entries, or holding values a
            TimeHistory refuses (NaN, ``fs <= 0``...).
        """
        path = Path(path)
        arrays = read_npz(path, _NPZ)
        meta = _npz_meta(arrays, path)
        data = arrays["data"]
        if data.dtype.kind not in "iuf" or data.ndim not in (1, 2):
            raise FileFormatError(
                path,
                _NPZ,
                f"data must be a real (N,) or (N, channels) array, got {data.dtype} "
                f"of shape {data.shape}",
            )
        try:
            return cls(data, meta["fs"], meta["names"], meta["units"])
        except (TypeError, ValueError) as exc:
            raise FileFormatError(path, _NPZ, str(exc)) from None


_NPZ = "vrig TimeHistory .npz"


def _npz_meta(arrays: dict, path: Path) -> dict:
    """The checked ``meta`` entry of a TimeHistory ``.npz`` (see :meth:`TimeHistory.load`)."""
    missing = [k for k in ("data", "meta") if k not in arrays]
    if missing:
        raise FileFormatError(
            path,
            _NPZ,
            f"no {' or '.join(missing)} array (it holds {sorted(arrays) or 'none'}); "
            "TimeHistory.save writes data and meta",
        )
    raw = arrays["meta"]
    try:
        if raw.dtype.kind != "U" or raw.shape != ():
            raise ValueError("not a text scalar")
        meta = json.loads(str(raw))
    except ValueError as exc:
        raise FileFormatError(path, _NPZ, f"meta is not JSON text ({exc})") from None
    if not isinstance(meta, dict) or meta.get("format", "vrig-timehistory") != "vrig-timehistory":
        raise FileFormatError(path, _NPZ, "meta does not describe a vrig time history")
    if not isinstance(meta.get("version", 1), int) or meta.get("version", 1) > 1:
        raise FileFormatError(
            path, _NPZ, f"format version {meta.get('version')!r}; this vrig reads version 1"
        )
    missing = [k for k in ("fs", "names", "units") if k not in meta]
    if missing:
        raise FileFormatError(path, _NPZ, f"meta has no {', '.join(missing)}")
    for key in ("names", "units"):
        if not (isinstance(meta[key], list) and all(isinstance(v, str) for v in meta[key])):
            raise FileFormatError(path, _NPZ, f"meta {key} must be a list of strings")
    if isinstance(meta["fs"], bool) or not isinstance(meta["fs"], (int, float)):
        raise FileFormatError(path, _NPZ, f"meta fs must be a number, got {meta['fs']!r}")
    return meta
