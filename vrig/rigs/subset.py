"""A rig seen through some of its response transducers (remote-parameter selection, §3.2.2).

Which responses an inverse model is built on is a test-engineering choice: the reference text's
radiator is simulated from the top-tank accelerometer alone or from top tank *and* base (the
non-square inverse of §6.4.1), the motorcycle from the coil-spring strain gauge or from the
spindle accelerometer (Table 3.5). :class:`OutputSubset` wraps any rig and exposes the chosen
response channels only; the drives are the rig's own.
"""

from __future__ import annotations

from ..timehistory import TimeHistory

__all__ = ["OutputSubset"]


class OutputSubset:
    """``rig`` with only the response channels ``names`` (in that order).

    Everything else (drives, limits, sample rate, band) is the wrapped rig's; ``run`` plays the
    drive on the whole rig and returns the selected channels.

    Parameters
    ----------
    rig : Rig
        The wrapped rig.
    names : sequence of str
        Response channel names of ``rig`` to keep, in the order wanted.
    """

    def __init__(self, rig, names):
        if isinstance(names, str):
            names = [names]
        names = list(names)
        known = [c.name for c in rig.outputs]
        missing = [n for n in names if n not in known]
        if missing or not names:
            raise ValueError(f"rig {rig.name!r} has responses {known}; cannot select {names}")
        if len(set(names)) != len(names):
            raise ValueError(f"response channels selected twice: {names}")
        self.rig = rig
        self.names = names
        self.outputs = tuple(rig.outputs[known.index(n)] for n in names)

    defaults = None
    """None: the wrapped rig's side-car defaults (band, tolerance) were set on all its responses,
    so a subset gets the global ones (:func:`vrig.reconstruction.defaults.default_band`: the test band)."""

    def __getattr__(self, attr):  # inputs, fs, bandwidth, description, ... of the wrapped rig
        if attr == "rig":
            raise AttributeError(attr)
        return getattr(self.rig, attr)

    @property
    def name(self) -> str:
        """The wrapped rig's name with the selected channels, e.g. ``"rig[F,x]"``."""
        return f"{self.rig.name}[{','.join(self.names)}]"

    def run(self, drive, *, seed: int | None = None, **options) -> TimeHistory:
        """The wrapped rig's run (``options``: e.g. ``chunk_seconds``), selected channels.

        Parameters
        ----------
        drive : ndarray or TimeHistory
            The drive, as for the wrapped rig's ``run``.
        seed : int, optional
            Seed of the run's noise, as for the wrapped rig.
        **options
            Further keyword arguments of the wrapped rig's ``run`` (e.g. ``chunk_seconds``).
        """
        return self.rig.run(drive, seed=seed, **options)[self.names]

    def __repr__(self) -> str:
        return f"OutputSubset({self.rig!r}, {self.names})"
