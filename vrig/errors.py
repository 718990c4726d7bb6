"""Exceptions raised by vrig.

Every exception vrig raises on purpose derives from :class:`VrigError`, and also from the
built-in it derived from before the root existed (``RuntimeError`` for a failed run,
``ValueError`` for bad input), so ``except RuntimeError`` / ``except ValueError`` code keeps
working. Failures of the identification library propagate as
:class:`identification.IdentificationError` (that package does not import vrig), so
``except ERRORS`` (``(VrigError, IdentificationError)``) catches anything either raised.
The one exception to the root is :class:`ReconstructionInterrupted`: a Ctrl-C, not an error, it
derives from :class:`KeyboardInterrupt` alone, so no ``except Exception`` swallows it.
"""

from __future__ import annotations

from identification.errors import IdentificationError

__all__ = [
    "ERRORS",
    "ControlLawError",
    "FileFormatError",
    "FolderLockedError",
    "ReconstructionError",
    "ReconstructionInterrupted",
    "ResultsFolderError",
    "ResultsNotSavedError",
    "RigLimitError",
    "RigModelError",
    "RigParameterError",
    "SimulationInstabilityError",
    "UnsupportedMethodWarning",
    "VrigError",
]


class VrigError(Exception):
    """The root of every exception vrig raises on purpose (each also keeps its built-in base)."""


ERRORS = (VrigError, IdentificationError)
"""``except ERRORS:`` catches anything vrig or the identification library raised on purpose."""


class RigLimitError(VrigError, RuntimeError):
    """An interlock tripped: the rig stopped, as a real controller would.

    Each parameter but ``hint`` is kept as the attribute of the same name.

    Parameters
    ----------
    kind : str
        ``"stroke"``, ``"force"``, ``"following error"``, ``"transducer range"``, ``"drive"``.
    channel : str
        The actuator or transducer channel whose limit was exceeded.
    time : float
        Time in seconds from the start of the drive (NaN when the drive was rejected before it
        was sent).
    value : float
        The offending value, in the channel's unit.
    limit : float
        The limit in force, in the channel's unit.
    unit : str, optional
        The channel's unit, for the message.
    hint : str, optional
        What to change, appended to the message.
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
        self.hint = hint
        when = "before the drive was sent" if time != time else f"at t = {time:.4f} s"
        super().__init__(
            f"interlock: {kind} limit on channel {channel!r} {when}: {value:.6g} {unit} exceeds "
            f"{limit:.6g} {unit}. {hint}".rstrip()
        )

    def __reduce__(self):
        """Pickle by the constructor's arguments (the default pickles ``args``, the message
        alone, which ``__init__`` cannot take): a trip in a worker process reaches the parent."""
        fields = (self.kind, self.channel, self.time, self.value, self.limit, self.unit, self.hint)
        return type(self), fields, self.__dict__


class SimulationInstabilityError(VrigError, RuntimeError):
    """MuJoCo reported a warning or the simulation became non-finite."""


class RigModelError(VrigError, ValueError):
    """A rig model (MJCF or its side-car description) is inconsistent or incomplete."""


class RigParameterError(RigModelError):
    """A rig value (a side-car entry or a ``load_rig`` override) is missing its type, is not a
    finite number, lies outside its allowed range, or is an unknown key.

    Parameters
    ----------
    message : str
        The error message.
    key : str, optional
        Where the value sits, e.g. ``"outputs[0].transducer.noise_rms"`` or ``"moving_mass"``.
    value : object, optional
        The offending value.
    allowed : str, optional
        The allowed range or values, e.g. ``"a finite number > 0"``.
    """

    def __init__(self, message: str, key: str = "", value=None, allowed: str = ""):
        super().__init__(message)
        self.key, self.value, self.allowed = key, value, allowed


class ControlLawError(VrigError, RuntimeError):
    """An exception raised inside a user's control law (a Rattlesnake law run as a method).

    The message names the law, the exception and where it was raised in the law's own file
    (``file:line in function``); the original exception is ``__cause__``. Each parameter is kept
    as the attribute of the same name.

    Parameters
    ----------
    message : str
        The error message.
    law : str
        The law's label (``file.py:name``).
    where : str
        ``"path/to/file.py:LINE in FUNCTION"``: the deepest frame of the traceback in the
        law's file ("" when none is).
    """

    def __init__(self, message: str, *, law: str = "", where: str = ""):
        super().__init__(message)
        self.law, self.where = law, where

    def __reduce__(self):  # picklable (worker processes): the keywords are not in ``args``
        return _rebuild_control_law_error, (str(self), self.law, self.where)


def _rebuild_control_law_error(message: str, law: str, where: str) -> ControlLawError:
    return ControlLawError(message, law=law, where=where)


class ReconstructionError(VrigError, RuntimeError):
    """A reconstruction failed before any iteration was played (identification or IT00).

    Raised by :func:`vrig.reconstruct` ``from`` the original exception (a
    :class:`RigLimitError`, :class:`SimulationInstabilityError`, an identification error, ...),
    carrying what was made before the failure so that it can still be saved and inspected
    (:meth:`vrig.TestFolder.save` writes it). Failures after IT00 do not raise: they stop the
    loop and :func:`vrig.reconstruct` returns the iterations played (``result.stopped``).

    Each parameter but ``message`` is kept as the attribute of the same name.

    Parameters
    ----------
    message : str
        The error message.
    result : ReconstructionResult
        A result with zero iterations (``drives == []``, ``errors`` of shape (0, n_outputs),
        ``best_iteration == -1``): the identification drive and response (``None`` when the
        identification drive itself could not be played), the method (identified when the fit
        succeeded), the desired response, ``stopped`` (why) and ``rejected`` (the drive that
        was refused or tripped the rig, when there is one).
    cause : Exception
        The original exception (also ``__cause__``).
    stage : str
        ``"identification"`` (IDDRV could not be played), ``"model"`` (the inverse model could
        not be fitted or diverged on the desired response) or ``"IT00"`` (IT00DRV was refused
        or tripped the rig).
    """

    def __init__(self, message: str, *, result, cause: BaseException, stage: str):
        super().__init__(message)
        self.result = result
        self.cause = cause
        self.stage = stage

    def __reduce__(self):  # picklable (worker processes): the keywords are not in ``args``
        return _rebuild_reconstruction_error, (type(self), str(self), self.__dict__)


class ReconstructionInterrupted(KeyboardInterrupt):
    """Ctrl-C (``SIGINT``) stopped a reconstruction: the :class:`KeyboardInterrupt`, with what was
    played attached.

    Raised by :func:`vrig.reconstruct` ``from`` the original interrupt, wherever it struck (the
    identification, the fit, an iteration's rig run or its drive update). It derives from
    :class:`KeyboardInterrupt` only (not from :class:`VrigError`, nor from :class:`Exception`),
    so ``except Exception`` never swallows a Ctrl-C and ``except KeyboardInterrupt`` code keeps
    working; ``exc.result`` can be saved like any other result (:meth:`vrig.TestFolder.save`).

    Parameters
    ----------
    message : str
        The error message.
    result : ReconstructionResult
        Every iteration played before the interrupt, whole (an iteration the interrupt cut
        short is not in it), with ``stop_kind`` ``"interrupted"`` and ``stopped`` naming where;
        with zero iterations (``best_iteration == -1``) when the interrupt came before IT00 was
        played (the identification records when they were made).
    """

    def __init__(self, message: str, *, result):
        super().__init__(message)
        self.result = result

    def __reduce__(self):  # picklable (worker processes): the keyword is not in ``args``
        return _rebuild_reconstruction_error, (type(self), str(self), self.__dict__)


class FolderLockedError(VrigError, OSError):
    """Another writer holds the lock of a results folder (:func:`vrig.files.folder_lock`).

    Parameters
    ----------
    message : str
        The error message (names the folder and, when known, the process holding it).
    path : str or Path
        The folder.
    pid : int or None
        The process holding the lock, when its lock file says so.
    """

    def __init__(self, message: str, *, path, pid: int | None = None):
        super().__init__(message)
        self.path, self.pid = str(path), pid

    def __reduce__(self):  # picklable (worker processes)
        return _rebuild_reconstruction_error, (type(self), str(self), self.__dict__)


class ResultsFolderError(VrigError, ValueError):
    """A results folder a reconstruction cannot write into, found before anything is played: a
    file, a non-empty folder without ``overwrite``, the working directory or a folder holding
    it, a mount point, a folder this process cannot write, or a disk without room for the
    results (:mod:`vrig.job`).

    Parameters
    ----------
    message : str
        The error message (names the folder).
    path : str or Path
        The folder.
    """

    def __init__(self, message: str, *, path):
        super().__init__(message)
        self.path = str(path)

    def __reduce__(self):  # picklable (worker processes)
        return _rebuild_reconstruction_error, (type(self), str(self), self.__dict__)


class ResultsNotSavedError(VrigError, OSError):
    """The results of a reconstruction could not be written (not even without the plots, on a
    full disk): nothing was saved, the folder keeps its previous contents (:mod:`vrig.job`).

    Parameters
    ----------
    message : str
        The error message (names the folder and the operating system's reason).
    path : str or Path
        The folder.
    result : ReconstructionResult or None
        The reconstruction that could not be saved (it can be saved elsewhere:
        :meth:`vrig.TestFolder.save`).
    """

    def __init__(self, message: str, *, path, result=None):
        super().__init__(message)
        self.path, self.result = str(path), result

    def __reduce__(self):  # picklable (worker processes)
        return _rebuild_reconstruction_error, (type(self), str(self), self.__dict__)


class FileFormatError(VrigError, ValueError):
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


def _rebuild_reconstruction_error(cls, message: str, state: dict):
    """Unpickle a :class:`ReconstructionError`, :class:`ReconstructionInterrupted`,
    :class:`FolderLockedError`, :class:`ResultsFolderError` or :class:`ResultsNotSavedError`
    (``__reduce__``): their constructors take keywords, which
    ``pickle`` cannot pass."""
    return cls(message, **state)


class UnsupportedMethodWarning(UserWarning):
    """A method the rig's side-car marks ``unsupported`` (the reference text reports it failing
    on the rig) runs all the same: a benchmark lets a user see a method do badly. Issued once per
    engine (:class:`~vrig.reconstruction.DriveIteration`) with the side-car's sentence quoted;
    ``vrig reconstruct`` prints it as one ``warning:`` line."""
