"""The rig contract: what :func:`vrig.reconstruct`, the drive-iteration envs and the benchmark
runner use from a rig.

A rig is anything with these members (:class:`MujocoRig`, :class:`FileRig`, :class:`OutputSubset`
and a user's own class alike); nothing else of a rig is read by the iteration::

    name       str                        shown in progress bars and folders
    fs         float                      sample rate of drives and responses [Hz]
    inputs     tuple[ChannelSpec, ...]    the drive channels (names, units, full scales, limits)
    outputs    tuple[ChannelSpec, ...]    the response channels
    bandwidth  (low, high) [Hz]           the test band (the iteration's default band)
    run(drive, *, seed=None) -> TimeHistory
               plays a drive (ndarray (n_samples, n_inputs) or TimeHistory at ``fs``) and returns
               the sampled responses, one column per output, at ``fs``

A run's errors, as the iteration reads them: :class:`~vrig.errors.RigLimitError` for a drive
refused before it is sent or an interlock trip during the run (a trip stops the run, as it stops
a real rig; the error names the first trip's channel, time and value), and
:class:`~vrig.errors.SimulationInstabilityError` for a simulated rig that became numerically
unstable in the part it played — that takes precedence over a trip, which is often its symptom
(:meth:`MujocoRig.run <vrig.rigs.MujocoRig.run>`: the part played is up to the end of the chunk
in which the first trip happened). Callers that retry at a lower level (the identification
drive, :func:`vrig.desired.pseudo_field.pseudo_field`) retry on the first, never on the second.

``isinstance(obj, Rig)`` checks that the members exist (``typing.runtime_checkable``), not their
signatures or types. :class:`DescribedRig` adds ``describe()`` (the CLI's ``vrig describe``).
"""

from __future__ import annotations

from typing import Protocol, runtime_checkable

import numpy as np

from ..timehistory import TimeHistory
from .spec import ChannelSpec

__all__ = ["DescribedRig", "Rig"]


@runtime_checkable
class Rig(Protocol):
    """What a rig must provide to be iterated on (see the module docstring)."""

    @property
    def name(self) -> str:
        """The rig's name."""
        ...

    @property
    def fs(self) -> float:
        """Sample rate of drives and responses [Hz]."""
        ...

    @property
    def inputs(self) -> tuple[ChannelSpec, ...]:
        """The drive channels."""
        ...

    @property
    def outputs(self) -> tuple[ChannelSpec, ...]:
        """The response channels."""
        ...

    @property
    def bandwidth(self) -> tuple[float, float]:
        """The test band (low, high) [Hz]."""
        ...

    def run(self, drive: np.ndarray | TimeHistory, *, seed: int | None = None) -> TimeHistory:
        """Play ``drive`` (n_samples x n_inputs at ``fs``) and return the responses.

        Parameters
        ----------
        drive : ndarray or TimeHistory
            The drive, (n_samples, n_inputs) in the drive channels' units, sampled at ``fs``.
        seed : int, optional
            Noise seed for this run; None: the rig's own choice (a shipped rig: the next stream
            of its generator).

        Raises
        ------
        RigLimitError
            The drive is beyond a channel's full scale (not sent), or an interlock tripped (the
            run stopped there).
        SimulationInstabilityError
            The simulation became unstable before the run stopped (it takes precedence over a
            trip).
        """
        ...


@runtime_checkable
class DescribedRig(Rig, Protocol):
    """A :class:`Rig` that also describes itself as text (channels, limits, parameters)."""

    def describe(self) -> str:
        """What the rig is, as text."""
        ...
