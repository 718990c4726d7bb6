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
        """Channels by name or index, samples by slice (pandas' ``DataFrame[...]`` rules).

        * ``th["F"]``, ``th[["x", "F"]]``: channels by name; ``th[0]``, ``th[[0, 2]]``, an
          integer or boolean array: channels by index.
        * ``th[100:200]``: samples 100 .. 199 (a slice selects samples, as ``df[100:200]``
          selects rows). ``th[::q]`` keeps every q-th sample and its sample rate becomes
          ``fs / q`` (plain down-sampling, no anti-alias filter: low-pass first, e.g.
          :func:`scipy.signal.decimate`, when there is content above the new Nyquist
          frequency). A negative step (time reversed) and an empty selection are refused.
        * ``th[100:200, "F"]``, ``th[::2, [0, 1]]``: samples and channels.

        The result starts at ``t = 0`` (a TimeHistory has no start time).
        """
        if isinstance(key, tuple):
            if len(key) != 2 or not isinstance(key[0], slice):
                raise KeyError(
                    f"a two-part key is (sample slice, channels), e.g. th[100:200, 'F']; "
                    f"got {key!r}"
                )
            return self[key[0]][key[1]]
        if isinstance(key, slice):
            return self._samples(key)
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
        else:
            idx = list(np.arange(self.n_channels)[key])
        return TimeHistory(
            self.data[:, idx], self.fs, [self.names[i] for i in idx], [self.units[i] for i in idx]
        )

    def _samples(self, key: slice) -> TimeHistory:
        """Samples selected by a slice; a step q > 1 divides ``fs`` by q."""
        start, stop, step = key.indices(self.n_samples)
        if step < 0:
            raise ValueError(
                f"a negative step ({key.step}) would reverse time; a TimeHistory runs forward"
            )
        data = self.data[start:stop:step]
        if data.shape[0] == 0:
            raise ValueError(
                f"samples [{key.start}:{key.stop}:{key.step}] select nothing from a record of "
                f"{self.n_samples} samples"
            )
        return TimeHistory(data, self.fs / step, self.names, self.units)

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

    # ------------------------------------------------------------------ pandas
    def to_pandas(self):
        """A ``pandas.DataFrame``: one column per channel (named), the index the sample times
        in seconds (``"time [s]"``, from 0), ``attrs["units"]`` the channel units by name and
        ``attrs["fs"]`` the sample rate in Hz (so :meth:`from_pandas` gives back this record
        exactly). Needs pandas (``pip install 'vrig[pandas]'``)."""
        pd = _pandas()
        df = pd.DataFrame(
            np.array(self.data),
            index=pd.Index(self.time, name="time [s]"),
            columns=list(self.names),
        )
        df.attrs["units"] = dict(zip(self.names, self.units, strict=True))
        df.attrs["fs"] = self.fs
        return df

    @classmethod
    def from_pandas(cls, df, fs: float | None = None) -> TimeHistory:
        """A TimeHistory from a ``pandas.DataFrame`` (or Series) of numeric columns.

        Channel names are the column names; units come from ``df.attrs["units"]`` (a dict by
        name, as :meth:`to_pandas` writes, or a list in column order), ``"-"`` where missing.
        The sample rate in Hz: ``fs`` when given, else ``df.attrs["fs"]``, else inferred from
        the index, which holds the sample times (seconds as numbers, or a ``DatetimeIndex`` /
        ``TimedeltaIndex``). The index must be uniform: every time within 1 % of a sample period
        of ``t0 + i / fs`` (time stamps rounded on export pass; missing samples, jitter or a
        changed rate are refused, resample first). Its start time ``t0`` is dropped (a
        TimeHistory starts at 0). The default ``RangeIndex`` holds sample numbers, not times:
        it needs ``fs``.

        Parameters
        ----------
        df : pandas.DataFrame or pandas.Series
            Numeric columns, one per channel; the index holds the sample times.
        fs : float, optional
            Sample rate [Hz] (default: ``df.attrs["fs"]`` or inferred from the index).

        Raises
        ------
        ValueError
            for a non-uniform or decreasing index, a ``RangeIndex`` without ``fs``, an ``fs``
            the index contradicts, non-numeric or non-finite data, or units of the wrong length.
        """
        pd = _pandas()
        if isinstance(df, pd.Series):
            df = df.to_frame()
        if not isinstance(df, pd.DataFrame):
            raise TypeError(f"from_pandas takes a pandas DataFrame or Series, got {type(df)}")
        try:
            data = df.to_numpy(dtype=np.float64)
        except (TypeError, ValueError) as exc:
            raise ValueError(f"every column must be numeric ({exc})") from None
        names = [str(c) for c in df.columns]
        units = _units_from_attrs(df.attrs.get("units"), names)
        rate = _rate_from_index(pd, df.index, fs, df.attrs.get("fs"))
        return cls(data, rate, names, units)

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
_UNIFORM = 0.01  # index tolerance of from_pandas, in sample periods


def _pandas():
    try:
        import pandas
    except ImportError as exc:
        raise ImportError(
            "TimeHistory.to_pandas/from_pandas need pandas: pip install 'vrig[pandas]'"
        ) from exc
    return pandas


def _units_from_attrs(units, names: list[str]) -> list[str]:
    if units is None:
        return ["-"] * len(names)
    if isinstance(units, dict):
        return [str(units.get(n, "-")) for n in names]
    if isinstance(units, str):
        raise ValueError(f"attrs['units'] must be a dict by column or a list, got {units!r}")
    units = [str(u) for u in units]
    if len(units) != len(names):
        raise ValueError(f"attrs['units'] has {len(units)} units for {len(names)} columns")
    return units


def _index_seconds(pd, index) -> np.ndarray | None:
    """The index as times in seconds; None for the default RangeIndex (sample numbers)."""
    if isinstance(index, pd.RangeIndex):
        return None
    if isinstance(index, (pd.DatetimeIndex, pd.TimedeltaIndex)):
        return np.asarray((index - index[0]) / pd.Timedelta(1, "s"), dtype=np.float64)
    try:
        return np.asarray(index, dtype=np.float64)
    except (TypeError, ValueError):
        raise ValueError(
            f"the index must hold sample times (seconds, datetimes or timedeltas), got "
            f"{index.dtype}"
        ) from None


def _rate_from_index(pd, index, fs, attrs_fs) -> float:
    """The sample rate in Hz of a DataFrame (see :meth:`TimeHistory.from_pandas`)."""
    t = _index_seconds(pd, index)
    rate = fs if fs is not None else attrs_fs
    if t is None:
        if rate is None:
            raise ValueError(
                "the index is a RangeIndex (sample numbers, not times): pass fs= (Hz) or set "
                "a time index in seconds"
            )
        return float(rate)
    if t.size and not np.all(np.isfinite(t)):
        raise ValueError("the time index holds NaN or inf")
    if rate is None:
        if t.size < 2 or not t[-1] > t[0]:
            raise ValueError(
                "cannot infer the sample rate from an index of fewer than two increasing "
                "times: pass fs= (Hz)"
            )
        rate = (t.size - 1) / (t[-1] - t[0])
    rate = float(rate)
    if not (np.isfinite(rate) and rate > 0):
        raise ValueError(f"fs must be a positive sample rate in Hz, got {rate!r}")
    off = np.abs((t - t[0]) * rate - np.arange(t.size)) if t.size else np.zeros(0)
    if off.size and off.max() > _UNIFORM:
        i = int(np.argmax(off))
        raise ValueError(
            f"the time index is not uniform at {rate:g} Hz: sample {i} is at {t[i]:g} s, "
            f"{off[i]:.3g} sample periods off the grid (tolerance {_UNIFORM}); resample to "
            "a uniform rate first (a TimeHistory has one sample rate)"
        )
    return rate


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
