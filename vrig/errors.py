"""Exceptions raised by vrig."""

from __future__ import annotations

__all__ = ["RigLimitError", "RigModelError", "RigParameterError", "SimulationInstabilityError"]


class RigLimitError(RuntimeError):
    """An interlock tripped: the rig stopped, as a real controller would.

    Attributes
    ----------
    channel : str
        The actuator or transducer channel whose limit was exceeded.
    time : float
        Time in seconds from the start of the drive (NaN when the drive was rejected before it
        was sent).
    value : float
        The offending value, in the channel's unit.
    limit : float
        The limit in force.
    kind : str
        ``"stroke"``, ``"force"``, ``"following error"``, ``"transducer range"``, ``"drive"``.
    """

    def __init__(
        self,
        kind: str,
        channel: str,
        time: float,
        value: float,
        limit: float,
        unit: str = "",
        hint: str = "",
    ):
        self.kind, self.channel = kind, channel
        self.time, self.value, self.limit, self.unit = float(time), float(value), float(limit), unit
        when = "before the drive was sent" if time != time else f"at t = {time:.4f} s"
        super().__init__(
            f"interlock: {kind} limit on channel {channel!r} {when}: {value:.6g} {unit} exceeds "
            f"{limit:.6g} {unit}. {hint}".rstrip()
        )


class SimulationInstabilityError(RuntimeError):
    """MuJoCo reported a warning or the simulation became non-finite."""


class RigModelError(ValueError):
    """A rig model (MJCF or its side-car description) is inconsistent or incomplete."""


class RigParameterError(RigModelError):
    """A rig value (a side-car entry or a ``load_rig`` override) is missing its type, is not a
    finite number, lies outside its allowed range, or is an unknown key.

    Attributes
    ----------
    key : str
        Where the value sits, e.g. ``"outputs[0].transducer.noise_rms"`` or ``"moving_mass"``.
    value : object
        The offending value.
    allowed : str
        The allowed range or values, e.g. ``"a finite number > 0"``.
    """

    def __init__(self, message: str, key: str = "", value=None, allowed: str = ""):
        super().__init__(message)
        self.key, self.value, self.allowed = key, value, allowed
