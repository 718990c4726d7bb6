"""Boundary validation helpers (internal). Public functions call these; internals trust inputs."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from .errors import IdentificationError

__all__ = [
    "as_signal",
    "check_initial_outputs",
    "check_same_length",
    "check_steps_ahead",
    "per_channel_int",
]


def as_signal(x, name: str, *, n_channels: int | None = None) -> np.ndarray:
    """Return ``x`` as a finite float64 array of shape (N, n) with time on axis 0.

    A 1-D array is one channel. Raises :class:`IdentificationError` naming ``name`` otherwise.
    """
    if x is None:
        raise IdentificationError(f"{name} is None; pass an array of shape (N,) or (N, channels)")
    try:
        a = np.asarray(x, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise IdentificationError(
            f"{name} must be numeric array-like, got {type(x).__name__}"
        ) from exc
    if a.ndim == 1:
        a = a[:, None]
    elif a.ndim != 2:
        raise IdentificationError(
            f"{name} must be 1-D (N,) or 2-D (N, channels) with time on axis 0; got shape {a.shape}"
        )
    if a.shape[0] == 0 or a.shape[1] == 0:
        raise IdentificationError(f"{name} is empty (shape {a.shape})")
    if a.shape[1] > a.shape[0]:
        raise IdentificationError(
            f"{name} has shape {a.shape}: more channels than samples. Time must be on axis 0; "
            f"did you mean {name}.T?"
        )
    if not np.all(np.isfinite(a)):
        bad = np.argwhere(~np.isfinite(a))[0]
        raise IdentificationError(
            f"{name} contains NaN or inf (first at sample {bad[0]}, channel {bad[1]}); "
            "remove or interpolate non-finite samples before identification"
        )
    if n_channels is not None and a.shape[1] != n_channels:
        raise IdentificationError(
            f"{name} has {a.shape[1]} channel(s) but the model expects {n_channels}"
        )
    return a


def check_same_length(a: np.ndarray, b: np.ndarray, name_a: str, name_b: str) -> None:
    if a.shape[0] != b.shape[0]:
        raise IdentificationError(
            f"{name_a} has {a.shape[0]} samples but {name_b} has {b.shape[0]}; "
            "input and output records must be the same length and time-aligned"
        )


def per_channel_int(value, n: int, name: str, *, minimum: int) -> tuple[int, ...]:
    """Expand an int or a sequence of ints to one value per channel, checking the minimum."""
    if isinstance(value, (int, np.integer)) and not isinstance(value, bool):
        values = (int(value),) * n
    elif isinstance(value, Sequence | np.ndarray) and not isinstance(value, str):
        values = tuple(value)
        if len(values) != n:
            raise IdentificationError(
                f"{name} has {len(values)} values but there are {n} output channels"
            )
        for v in values:
            if not isinstance(v, (int, np.integer)) or isinstance(v, bool):
                raise IdentificationError(f"{name} values must be integers, got {v!r}")
        values = tuple(int(v) for v in values)
    else:
        raise IdentificationError(
            f"{name} must be an int or one int per output channel, got {value!r}"
        )
    for v in values:
        if v < minimum:
            raise IdentificationError(f"{name} must be >= {minimum}, got {v}")
    return values


def check_initial_outputs(y0, u: np.ndarray, max_lag: int, n_outputs: int) -> np.ndarray:
    """``y0`` (the initial outputs a free run starts from: an initialisation window of
    ``L >= max_lag`` samples, whose last ``max_lag`` are the initial state) as a float array of
    shape (L, n_outputs), finite, with ``u`` at least ``L`` long; else IdentificationError."""
    y0 = np.asarray(y0, dtype=np.float64)
    if y0.ndim == 1 and n_outputs == 1:
        y0 = y0[:, None]
    if y0.ndim != 2 or y0.shape[1] != n_outputs or y0.shape[0] < max_lag:
        raise IdentificationError(
            f"y0 must have shape (L, ny) with L >= max_lag_ = {max_lag} samples and "
            f"ny = {n_outputs} (its last max_lag_ samples are the initial state), "
            f"got {y0.shape}"
        )
    if not np.all(np.isfinite(y0)):
        raise IdentificationError("y0 contains NaN or inf")
    if u.shape[0] < y0.shape[0]:
        raise IdentificationError(
            f"u has {u.shape[0]} samples, fewer than the {y0.shape[0]} initial outputs y0"
        )
    return y0


def check_steps_ahead(steps_ahead) -> int | None:
    """``steps_ahead`` of ``predict``: None (free run) or a positive int; else
    IdentificationError."""
    if steps_ahead is None:
        return None
    if (
        not isinstance(steps_ahead, (int, np.integer))
        or isinstance(steps_ahead, bool)
        or steps_ahead < 1
    ):
        raise IdentificationError(
            "steps_ahead must be None (free-run simulation from the first max_lag_ measured "
            f"outputs), 1 (one-step-ahead) or an integer k > 1 (k-step-ahead), got {steps_ahead!r}"
        )
    return int(steps_ahead)
