"""The method contract: what :func:`vrig.reconstruct` and the benchmark runner use from a
reconstruction method, and the optional capabilities the runner asks for by name.

:class:`Method` (every shipped method, and what a user's or a benchmark plugin's method
provides)::

    identify(iddrv, idres) -> None     fit from the processed identification records
                                       (TimeHistory drive and response, at the model rate)
    drive(response) -> ndarray         the drive (n_samples, n_drives) predicted for a response
    describe() -> str                  one line: what was fitted (after identify)

:func:`vrig.reconstruct` itself needs only ``identify`` and ``drive``
(:func:`~vrig.reconstruction.make_method` accepts any object with those two); ``describe`` is
what result folders and benchmark records show.

Optional capabilities, each a protocol of its own so that ``isinstance`` says whether a method
has it:

* :class:`SizedMethod` — ``model_size()``: number of fitted coefficients (None before
  ``identify``);
* :class:`SavableMethod` — ``options()`` and ``fitted_models()``: what a test folder records
  (``summary.json``, the model files);
* :class:`InverseModelMethod` — a time-domain inverse model with a *lead* (the rig's delay the
  inverse advances the response by): ``fitted_lead()`` reads the lead the fit chose,
  ``set_lead(lead)`` fixes it for the next ``identify`` (0: a causal model, no lead search).
  The runner uses these for its extra modelling-error fits: the fresh inverse keeps the
  reconstruction's lead, the forward model (roles of drive and response swapped) is causal;
* :class:`ObservingMethod` — ``observe(drive, response)``: told, after every drive the iteration
  plays, that drive and its processed response (at the model rate); a Rattlesnake control law
  gets them as its last excitation and response (:mod:`vrig.reconstruction.rattlesnake`).

``isinstance(obj, Method)`` checks that the members exist (``typing.runtime_checkable``), not
their signatures.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any, Protocol, runtime_checkable

import numpy as np

from ..timehistory import TimeHistory

__all__ = [
    "InverseModelMethod",
    "Lead",
    "Method",
    "ObservingMethod",
    "SavableMethod",
    "SizedMethod",
]

Lead = int | str | None | Mapping[str, "Lead"]
"""A method's lead [samples]: an int (``"auto"``: searched at identification; None: not
identified); for a method made of parts (split spectra) a mapping ``{part: Lead}``
(``{"low": 3, "high": 2}``)."""


@runtime_checkable
class Method(Protocol):
    """A reconstruction method (see the module docstring)."""

    def identify(self, iddrv: TimeHistory, idres: TimeHistory) -> None:
        """Fit the method from identification drive ``iddrv`` and response ``idres``.

        Parameters
        ----------
        iddrv : TimeHistory
            Identification drive record.
        idres : TimeHistory
            The response measured for it (same length and sample rate).
        """
        ...

    def drive(self, response: TimeHistory) -> np.ndarray:
        """The drive (n_samples, n_drives) the fitted method predicts for ``response``.

        Parameters
        ----------
        response : TimeHistory
            The response to compute a drive for (desired, or an iteration's target).
        """
        ...

    def describe(self) -> str:
        """One line saying what was fitted."""
        ...


@runtime_checkable
class SizedMethod(Protocol):
    """A method that counts its model's coefficients."""

    def model_size(self) -> int | None:
        """Number of fitted coefficients; None before ``identify``."""
        ...


@runtime_checkable
class InverseModelMethod(Method, SizedMethod, Protocol):
    """A time-domain inverse-model method with a lead (vrig's ARX/NARX/error-signal inverses,
    and split spectra of them)."""

    def fitted_lead(self) -> Lead:
        """The lead [samples] the last ``identify`` chose (None before one)."""
        ...

    def set_lead(self, lead: Lead) -> None:
        """Fix the lead for the next ``identify``: a number of samples >= 0 (0: causal), or
        ``"auto"`` (search it); a method of parts takes one value for all of them or a mapping
        as :meth:`fitted_lead` returns it (a part whose lead is None is left as it is).

        Parameters
        ----------
        lead : int, "auto" or mapping of str to int or None
            The lead (samples) or leads of the parts.
        """
        ...


@runtime_checkable
class SavableMethod(Protocol):
    """A method whose options and fitted models a test folder records (``summary.json`` and the
    model files, :class:`vrig.TestFolder`)."""

    def options(self) -> dict[str, Any]:
        """The method's options by name (numbers, strings, or band methods for a method made of
        parts), as given to its constructor."""
        ...

    def fitted_models(self) -> dict[str, Any]:
        """``{file stem: fitted model}`` (models with ``save(path)``); empty before
        ``identify``."""
        ...


@runtime_checkable
class ObservingMethod(Protocol):
    """A method told of every drive the iteration plays and its response."""

    def observe(self, drive: TimeHistory, response: TimeHistory) -> None:
        """Take note of a played drive and its processed response (both at the model rate).

        Parameters
        ----------
        drive : TimeHistory
            The drive played (ITxxDRV).
        response : TimeHistory
            Its response after GPREPRO (ITxxRES).
        """
        ...
