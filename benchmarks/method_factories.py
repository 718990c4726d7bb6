"""Factories of the models a benchmark row names: written once for every benchmark.

A row of ``benchmarks.thesis_tables``, an entry of ``benchmarks.calibrate`` and a method of
``benchmarks.matched_identification`` each need a *fresh* model per run (a fitted model keeps
its state), so they hold a factory, not a model. Two kinds:

* inverse (reconstruction) methods, ``() -> method`` for :func:`vrig.reconstruct`:
  :func:`inverse_arx`, :func:`inverse_narx`, :func:`split_spectra`;
* normal (forward) models between measured channels, ``(fs) -> model`` with ``fit(u, y)`` and
  ``simulate(u)`` (the sampling rate for the split filters): :func:`forward_arx`,
  :func:`forward_narx`, :func:`forward_error_signal`, :func:`forward_arx_per_output`,
  :func:`forward_split`.

The factories import the model classes when called, so importing a benchmark's tables loads
neither ``vrig.reconstruction`` nor ``identification``.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

__all__ = [
    "PerOutput",
    "forward_arx",
    "forward_arx_per_output",
    "forward_error_signal",
    "forward_narx",
    "forward_split",
    "inverse_arx",
    "inverse_narx",
    "split_spectra",
]


def inverse_arx(order: int, **options) -> Callable:
    """A factory of :class:`vrig.reconstruction.InverseArx` (QanTiM, inverse).

    Parameters
    ----------
    order : int
        Model order.
    **options
        Keywords of ``InverseArx`` (e.g. ``responses``).

    Returns
    -------
    callable
        ``() -> InverseArx``.
    """

    def make():
        from vrig.reconstruction import InverseArx

        return InverseArx(order, **options)

    return make


def inverse_narx(order: int, degree: int, **options) -> Callable:
    """A factory of :class:`vrig.reconstruction.InverseNarx`.

    Parameters
    ----------
    order : int
        Model order.
    degree : int
        Polynomial degree.
    **options
        Keywords of ``InverseNarx`` (``kind``, ``focus``, ``selection``, ``responses``, ...).

    Returns
    -------
    callable
        ``() -> InverseNarx``.
    """

    def make():
        from vrig.reconstruction import InverseNarx

        return InverseNarx(order, degree, **options)

    return make


def split_spectra(split_hz: float, low: Callable, high: Callable, **options) -> Callable:
    """A factory of :class:`vrig.reconstruction.SplitSpectra` from two method factories.

    Parameters
    ----------
    split_hz : float
        Split frequency [Hz].
    low, high : callable
        Factories of the methods below and above the split.
    **options
        Keywords of ``SplitSpectra`` (e.g. ``low_responses``, ``high_responses``).

    Returns
    -------
    callable
        ``() -> SplitSpectra``, with fresh ``low()`` and ``high()`` methods.
    """

    def make():
        from vrig.reconstruction import SplitSpectra

        return SplitSpectra(split_hz, low(), high(), **options)

    return make


def forward_arx(order: int, **options) -> Callable:
    """A factory ``(fs) -> identification.Arx`` (QanTiM, normal) of ``order``, with the
    keywords ``options`` of ``Arx`` (e.g. ``focus``)."""
    from identification import Arx

    return lambda fs: Arx(order, **options)


def forward_narx(order: int, degree: int, **options) -> Callable:
    """A factory ``(fs) -> identification.Narx`` (normal) of ``order`` and ``degree``, with the
    keywords ``options`` of ``Narx``."""
    from identification import Narx

    return lambda fs: Narx(order, degree, **options)


def forward_error_signal(lin_order: int, nl_order: int, nl_degree: int, **options) -> Callable:
    """A factory ``(fs) -> identification.ErrorSignalModel``: a linear ARX plus a NARX of its
    error signal (§5.5.4).

    Parameters
    ----------
    lin_order : int
        Order of the linear ARX.
    nl_order, nl_degree : int
        Order and degree of the error signal's NARX.
    **options
        Keywords of the NARX (e.g. ``focus``).

    Returns
    -------
    callable
    """
    from identification import Arx, ErrorSignalModel, Narx

    return lambda fs: ErrorSignalModel(Arx(lin_order), Narx(nl_order, nl_degree, **options))


class PerOutput:
    """One model per output channel (each MISO: all inputs -> one output), fitted and
    simulated independently, as a QanTiM normal model per response channel.

    Parameters
    ----------
    factory : callable
        ``() -> model`` with ``fit(u, y)`` and ``simulate(u)``.
    """

    def __init__(self, factory):
        self.factory = factory

    def fit(self, u, y):
        """Fit one model per column of ``y``.

        Parameters
        ----------
        u : array_like
            Inputs, (n, inputs).
        y : array_like
            Outputs, (n, outputs).

        Returns
        -------
        PerOutput
            Itself.
        """
        y = np.asarray(y, float)
        self.models_ = [self.factory().fit(u, y[:, [j]]) for j in range(y.shape[1])]
        return self

    def simulate(self, u):
        """The free run of every output's model, side by side.

        Parameters
        ----------
        u : array_like
            Inputs, (n, inputs).

        Returns
        -------
        ndarray
            (n, outputs).
        """
        return np.hstack([m.simulate(u) for m in self.models_])


def forward_arx_per_output(order: int, **options) -> Callable:
    """A factory ``(fs) -> PerOutput`` of one ``identification.Arx`` of ``order`` per output,
    with the keywords ``options`` of ``Arx``."""
    from identification import Arx

    return lambda fs: PerOutput(lambda: Arx(order, **options))


def forward_split(split_hz: float, low_order: int, low_degree: int, high_order: int) -> Callable:
    """Forward split-spectra model (§5.5.3, §6.3; Table 6.9): ``identification.SplitSpectraModel``
    — inputs and outputs split at ``split_hz`` by a 4th-order zero-phase Butterworth low-pass
    (the text: "a 4th order digital filter"), high = x - low, one model per band at the
    record's rate, the simulated bands summed.

    Parameters
    ----------
    split_hz : float
        Split frequency [Hz].
    low_order, low_degree : int
        Order and degree of the NARX below the split (order 0: static).
    high_order : int
        Order of the ARX above the split.

    Returns
    -------
    callable
        ``(fs) -> SplitSpectraModel``.
    """
    from identification import Arx, Narx, SplitSpectraModel

    return lambda fs: SplitSpectraModel(
        split_hz, fs, Narx(order=low_order, degree=low_degree), Arx(order=high_order)
    )
