"""Exceptions raised by vrig."""

from __future__ import annotations

__all__ = ["FileFormatError", "RigLimitError", "RigModelError", "SimulationInstabilityError"]


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


class FileFormatError(ValueError):
    """A file is not what its name or reader expects: truncated, corrupt, foreign, of another
    encoding or version, not a regular file, or too large.

    Parameters
    ----------
    path : str or Path
        The file.
    fmt : str
        The format it was read as (``"RPC III"``, ``"CSV"``, ``"MATLAB .mat"``, ...).
    detail : str
        What is wrong.

    Attributes
    ----------
    path : str
    format : str
    detail : str
    """

    def __init__(self, path, fmt: str, detail: str):
        self.path, self.format, self.detail = str(path), str(fmt), str(detail)
        super().__init__(f"{self.path}: not a readable {self.format} file: {self.detail}")

    def __reduce__(self):  # picklable (worker processes)
        return type(self), (self.path, self.format, self.detail)
