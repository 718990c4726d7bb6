"""Error measures between a reference record and a simulated/achieved one (pure functions).

Time is axis 0; 2-D inputs give one value per channel (a 1-D array), 1-D inputs a scalar.

* :func:`qantim_fit` — QanTiM fit value η, eq. 5-27: ``100 * sum|e| / sum|y|`` [%]
* :func:`qantim_fit_dc` — DC-corrected η0, eq. 5-28 (means removed from both records) [%]
* :func:`rms_error_percent` — ``100 * rms(e0) / rms(y0)`` with means removed [%]
* :func:`nrmse` — ``rms(e) / std(y)`` (or normalised by the range of y)
* :func:`rrse` — root relative squared error ``sqrt(sum e^2 / sum (y - mean y)^2)``
* :func:`fit_percent` — MATLAB ``compare``: ``100 * (1 - ||y - yhat|| / ||y - mean(y)||)`` [%]
* :func:`rmse` — root mean square error, in the units of y
"""

from __future__ import annotations

import numpy as np

from .errors import IdentificationError

__all__ = [
    "fit_percent",
    "nrmse",
    "qantim_fit",
    "qantim_fit_dc",
    "rms_error_percent",
    "rmse",
    "rrse",
]


def _pair(y, yhat):
    y = np.asarray(y, dtype=np.float64)
    yhat = np.asarray(yhat, dtype=np.float64)
    # a single channel may be given as (N,) on one side and (N, 1) on the other
    if y.ndim == 1 and yhat.shape == (y.shape[0], 1):
        y = y[:, None]
    elif yhat.ndim == 1 and y.shape == (yhat.shape[0], 1):
        yhat = yhat[:, None]
    if y.shape != yhat.shape:
        raise IdentificationError(
            f"reference and estimate must have the same shape, got {y.shape} and {yhat.shape}"
        )
    if y.ndim not in (1, 2) or y.shape[0] == 0:
        raise IdentificationError(
            f"records must be (N,) or (N, channels) with N > 0, got {y.shape}"
        )
    if not (np.all(np.isfinite(y)) and np.all(np.isfinite(yhat))):
        raise IdentificationError("records contain NaN or inf")
    return y, yhat


def _ratio(num, den, what):
    den = np.asarray(den)
    if np.any(den == 0):
        bad = np.flatnonzero(np.atleast_1d(den) == 0)
        raise IdentificationError(
            f"{what}: the reference channel(s) {bad.tolist()} are constant/zero, so the relative "
            "error is undefined"
        )
    return num / den


def qantim_fit(y, yhat):
    """QanTiM fit value η (eq. 5-27): ``100 * sum|y - yhat| / sum|y|`` in %.

    Parameters
    ----------
    y : array_like, shape (N,) or (N, channels)
        Reference record (time on axis 0), in its physical units.
    yhat : array_like, same shape as ``y``
        Simulated or achieved record to compare with ``y``, in the same units.
    """
    y, yhat = _pair(y, yhat)
    return 100.0 * _ratio(np.abs(y - yhat).sum(axis=0), np.abs(y).sum(axis=0), "qantim_fit")


def qantim_fit_dc(y, yhat):
    """DC-corrected QanTiM fit value η0 (eq. 5-28) in %: both records' means removed first.

    Parameters
    ----------
    y : array_like, shape (N,) or (N, channels)
        Reference record (time on axis 0), in its physical units.
    yhat : array_like, same shape as ``y``
        Simulated or achieved record to compare with ``y``, in the same units.
    """
    y, yhat = _pair(y, yhat)
    y0 = y - y.mean(axis=0)
    e0 = y0 - (yhat - yhat.mean(axis=0))
    return 100.0 * _ratio(np.abs(e0).sum(axis=0), np.abs(y0).sum(axis=0), "qantim_fit_dc")


def rms_error_percent(y, yhat):
    """RMS error in % of the reference RMS, means removed: ``100 * rms(e0) / rms(y0)``.

    Parameters
    ----------
    y : array_like, shape (N,) or (N, channels)
        Reference record (time on axis 0), in its physical units.
    yhat : array_like, same shape as ``y``
        Simulated or achieved record to compare with ``y``, in the same units.
    """
    y, yhat = _pair(y, yhat)
    y0 = y - y.mean(axis=0)
    e0 = y0 - (yhat - yhat.mean(axis=0))
    return 100.0 * _ratio(
        np.sqrt((e0**2).mean(axis=0)), np.sqrt((y0**2).mean(axis=0)), "rms_error_percent"
    )


def rmse(y, yhat):
    """Root mean square error ``sqrt(mean((y - yhat)^2))`` in the units of y.

    Parameters
    ----------
    y : array_like, shape (N,) or (N, channels)
        Reference record (time on axis 0), in its physical units.
    yhat : array_like, same shape as ``y``
        Simulated or achieved record to compare with ``y``, in the same units.
    """
    y, yhat = _pair(y, yhat)
    return np.sqrt(((y - yhat) ** 2).mean(axis=0))


def nrmse(y, yhat, *, norm: str = "std"):
    """Normalised RMSE: ``rmse / std(y)`` (``norm="std"``) or ``rmse / (max y - min y)``.

    Parameters
    ----------
    y : array_like, shape (N,) or (N, channels)
        Reference record (time on axis 0), in its physical units.
    yhat : array_like, same shape as ``y``
        Simulated or achieved record to compare with ``y``, in the same units.
    norm : {"std", "range"}, optional
        Normalise by the standard deviation of ``y`` (default) or by its range (max - min).
    """
    y, yhat = _pair(y, yhat)
    if norm == "std":
        den = y.std(axis=0)
    elif norm == "range":
        den = y.max(axis=0) - y.min(axis=0)
    else:
        raise IdentificationError(f"norm must be 'std' or 'range', got {norm!r}")
    return _ratio(rmse(y, yhat), den, "nrmse")


def rrse(y, yhat):
    """Root relative squared error ``sqrt(sum (y - yhat)^2 / sum (y - mean y)^2)``.

    Parameters
    ----------
    y : array_like, shape (N,) or (N, channels)
        Reference record (time on axis 0), in its physical units.
    yhat : array_like, same shape as ``y``
        Simulated or achieved record to compare with ``y``, in the same units.
    """
    y, yhat = _pair(y, yhat)
    return np.sqrt(
        _ratio(((y - yhat) ** 2).sum(axis=0), ((y - y.mean(axis=0)) ** 2).sum(axis=0), "rrse")
    )


def fit_percent(y, yhat):
    """Fit in % as MATLAB ``compare`` reports it: ``100 * (1 - ||y - yhat|| / ||y - mean(y)||)``.

    Parameters
    ----------
    y : array_like, shape (N,) or (N, channels)
        Reference record (time on axis 0), in its physical units.
    yhat : array_like, same shape as ``y``
        Simulated or achieved record to compare with ``y``, in the same units.
    """
    return 100.0 * (1.0 - rrse(y, yhat))
