"""Exceptions and warnings raised by the identification package.

Every exception the package raises on purpose derives from :class:`IdentificationError`, the
package's root. It is a ``ValueError`` (bad input is what most of them report), so all of them
are ``ValueError`` too, including :class:`SimulationDivergedError`, which also stays an
``ArithmeticError`` as it always was. The warnings derive from ``UserWarning`` only.
"""

from __future__ import annotations

import math

__all__ = [
    "IdentificationError",
    "IllConditionedWarning",
    "InsufficientDataError",
    "MemoryBudgetError",
    "ModelFileError",
    "RankDeficiencyWarning",
    "SimulationDivergedError",
    "StabilityWarning",
    "UnstableModelError",
]


class IdentificationError(ValueError):
    """The root of every exception the identification package raises on purpose; raised itself
    for bad input to an identification function (shape, values, structure or option)."""


class InsufficientDataError(IdentificationError):
    """Fewer usable samples than model terms."""


class MemoryBudgetError(IdentificationError):
    """An array a function was about to allocate exceeds the memory budget
    (:data:`identification.budget.MEMORY_BUDGET_BYTES`); the message names its size and what to
    change. Nothing was allocated: a caller may retry with less data."""


class ModelFileError(IdentificationError):
    """A model file is not one :meth:`Narx.save <identification.Narx.save>` wrote: truncated,
    corrupt, foreign, tampered, of a newer format version, not a regular file or too large.

    Parameters
    ----------
    path : str or os.PathLike
        The file (kept as the attribute ``path``, a ``str``).
    detail : str
        What is wrong (kept as the attribute ``detail``).
    """

    def __init__(self, path, detail: str):
        self.path, self.detail = str(path), str(detail)
        super().__init__(f"{self.path}: not a valid identification model file: {self.detail}")

    def __reduce__(self):  # picklable (worker processes)
        return type(self), (self.path, self.detail)


class UnstableModelError(IdentificationError):
    """``fit`` could not produce a model whose free run stays bounded on its identification input.

    Parameters
    ----------
    message : str
        What was tried and why no model was accepted.
    cause : SimulationDivergedError or None, optional
        The divergence of the last model tried (channel, sample, value); kept as the attribute
        ``cause``.
    """

    def __init__(self, message: str, cause=None):
        super().__init__(message)
        self.cause = cause


class StabilityWarning(UserWarning):
    """The fitted model's free run diverges at the stability margin (e.g. 1.5x the input)."""


class RankDeficiencyWarning(UserWarning):
    """The regression matrix is rank deficient; a minimum-norm solution was returned."""


class IllConditionedWarning(UserWarning):
    """The normal equations are ill-conditioned; accuracy is lost (use a QR-type solver)."""


class SimulationDivergedError(IdentificationError, ArithmeticError):
    """A free-run simulation left the bounded region or produced a non-finite value, or a
    one-step prediction was not finite.

    An :class:`IdentificationError` (hence also a ``ValueError``) and an ``ArithmeticError``.
    Each parameter is kept as the attribute of the same name.

    Parameters
    ----------
    channel : int
        Zero-based index of the output channel that diverged.
    channel_name : str
        Name of that channel.
    sample : int
        Zero-based sample index at which it diverged.
    value : float
        The offending value (may be inf or nan).
    bound : float
        The magnitude bound that was in force (inf for a prediction).
    kind : str
        ``"free-run simulation"`` (:meth:`Narx.simulate`) or ``"one-step prediction"``
        (:meth:`Narx.predict`).
    """

    def __init__(
        self,
        channel: int,
        channel_name: str,
        sample: int,
        value: float,
        bound: float,
        kind: str = "free-run simulation",
    ):
        self.channel = int(channel)
        self.channel_name = str(channel_name)
        self.sample = int(sample)
        self.value = float(value)
        self.bound = float(bound)
        self.kind = str(kind)
        what = "not finite" if not math.isfinite(self.value) else f"beyond the bound {self.bound:.6g}"
        if self.kind == "one-step prediction":
            hint = (
                "The model's terms overflow for data of this magnitude: check the data's units "
                "and amplitude against the identification data."
            )
        else:
            hint = (
                "The model is unstable for this input: check the input amplitude against the "
                "identification data, lower the model order/degree, or raise `bound` if the "
                "growth is genuine."
            )
        super().__init__(
            f"{self.kind} diverged on output channel {self.channel} "
            f"({self.channel_name!r}) at sample {self.sample}: value {self.value:.6g} "
            f"is {what}. {hint}"
        )

    def __reduce__(self):  # picklable (worker processes)
        return type(self), (
            self.channel,
            self.channel_name,
            self.sample,
            self.value,
            self.bound,
            self.kind,
        )

