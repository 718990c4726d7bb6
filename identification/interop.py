"""Data sets of the system-identification ecosystem: nonlinear_benchmarks' ``Input_output_data``.

`nonlinear_benchmarks <https://github.com/GerbenBeintema/nonlinear_benchmarks>`_ (the loaders of
nonlinearbenchmark.org: Silverbox, Wiener-Hammerstein, EMPS, ...) hands out records as
``Input_output_data(u, y, sampling_time, name=..., state_initialization_window_length=...)``:
``u``/``y`` arrays with time on axis 0, ``sampling_time`` in seconds (None for a discrete-time
record) and the number of initial samples a model may use to set its state (the benchmark then
scores from that sample on). The package is an optional extra (``pip install vrig[interop]``)
and is imported only when :func:`to_input_output_data` builds one of its objects;
:func:`from_input_output_data` reads any object with those attributes.

Conventions that meet here::

    u, y, fs = from_input_output_data(test)                    # fs in Hz (None: discrete time)
    n = test.state_initialization_window_length                # e.g. 50 samples
    y_sim = model.simulate(u, y0=y[:n])                        # any window >= max_lag_
    y_k = model.predict(u, y, steps_ahead=None)                # SysIdentPy's free run

This module never imports ``vrig``.
"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from .errors import IdentificationError

__all__ = ["from_input_output_data", "to_input_output_data"]


def from_input_output_data(obj) -> tuple[np.ndarray, np.ndarray, float | None]:
    """``(u, y, fs)`` of a nonlinear_benchmarks ``Input_output_data`` (or any object with
    ``.u``, ``.y`` and ``.sampling_time``).

    ``u`` and ``y`` are float arrays (copies) with time on axis 0, as the object holds them
    ((N,) stays (N,), every model here takes both); ``fs = 1 / sampling_time`` in Hz, or None
    for a discrete-time record (``sampling_time`` None). The object's
    ``state_initialization_window_length`` is not returned: read it from the object and pass
    ``y0=y[:n]`` to ``simulate``.

    Parameters
    ----------
    obj : Input_output_data or object with ``u``, ``y``, ``sampling_time``
        The record.

    Returns
    -------
    u, y : ndarray
        Inputs and outputs, time on axis 0.
    fs : float or None
        Sample rate [Hz]; None for a discrete-time record.

    Raises
    ------
    IdentificationError
        when an attribute is missing, ``u`` and ``y`` differ in length or are not numeric, or
        ``sampling_time`` is not a positive number of seconds.
    """
    missing = [a for a in ("u", "y", "sampling_time") if not hasattr(obj, a)]
    if missing:
        raise IdentificationError(
            f"{type(obj).__name__} has no {', '.join(missing)}: expected a nonlinear_benchmarks "
            "Input_output_data (attributes u, y, sampling_time)"
        )
    try:
        u = np.array(obj.u, dtype=np.float64)
        y = np.array(obj.y, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise IdentificationError(f"u and y must be numeric arrays ({exc})") from None
    if u.ndim not in (1, 2) or y.ndim not in (1, 2) or len(u) != len(y):
        raise IdentificationError(
            f"u {u.shape} and y {y.shape} must be (N,) or (N, channels) arrays of one length N"
        )
    return u, y, _fs(obj.sampling_time)


def to_input_output_data(
    u, y, sampling_time: float | None, *, name: str | None = None,
    state_initialization_window_length: int | None = None,
):
    """A nonlinear_benchmarks ``Input_output_data(u, y, sampling_time)`` (requires the
    optional package: ``pip install vrig[interop]`` or ``pip install nonlinear_benchmarks``).

    ``sampling_time`` in seconds (``1 / fs``), or None for a discrete-time record; ``u`` and
    ``y`` are stored as float arrays (copies) of the shapes given. The data round-trip exactly;
    ``fs -> 1 / fs -> fs`` is exact to the last bit of a double (one rounding per division).

    Parameters
    ----------
    u, y : array_like, (N,) or (N, channels)
        Inputs and outputs, time on axis 0.
    sampling_time : float or None
        Sample period [s]; None for a discrete-time record.
    name : str, optional
        The record's name.
    state_initialization_window_length : int, optional
        Samples at the start reserved for the model's initial state (nonlinear_benchmarks'
        convention, e.g. 50).

    Raises
    ------
    ImportError
        naming the extra when nonlinear_benchmarks is not installed.
    IdentificationError
        as :func:`from_input_output_data`, and for a window length that is not a
        non-negative integer.
    """
    try:
        from nonlinear_benchmarks import Input_output_data
    except ImportError as exc:
        raise ImportError(
            "to_input_output_data needs the optional package nonlinear_benchmarks: "
            "pip install 'vrig[interop]' (or pip install nonlinear_benchmarks)"
        ) from exc
    n = state_initialization_window_length
    if n is not None and (not isinstance(n, (int, np.integer)) or isinstance(n, bool) or n < 0):
        raise IdentificationError(
            f"state_initialization_window_length must be a number of samples >= 0, got {n!r}"
        )
    # validated by the reader: one set of rules both ways
    u, y, _ = from_input_output_data(SimpleNamespace(u=u, y=y, sampling_time=sampling_time))
    return Input_output_data(
        u,
        y,
        sampling_time=None if sampling_time is None else float(sampling_time),
        name=name,
        state_initialization_window_length=None if n is None else int(n),
    )


def _fs(sampling_time) -> float | None:
    if sampling_time is None:
        return None
    if isinstance(sampling_time, bool) or not isinstance(sampling_time, (int, float, np.number)):
        raise IdentificationError(
            f"sampling_time must be a number of seconds or None (discrete time), "
            f"got {sampling_time!r}"
        )
    dt = float(sampling_time)
    if not (np.isfinite(dt) and dt > 0):
        raise IdentificationError(f"sampling_time must be > 0 seconds, got {sampling_time!r}")
    return 1.0 / dt
