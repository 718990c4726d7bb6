"""Rattlesnake control laws as vrig methods: ``method="rattlesnake:<file.py>:<name>"``.

Sandia's Rattlesnake vibration controller lets its user write the *transient* control law in
Python, in one of three forms; :class:`RattlesnakeLaw` runs such a law, unchanged, as a vrig
reconstruction method (:class:`~vrig.reconstruction.protocol.Method`), with vrig's
identification run standing in for Rattlesnake's system identification.

The three forms (Rattlesnake's transient environment; channels first, time last)::

    # function: called for every drive
    law(sample_rate, specification_signals, frequency_spacing, transfer_function,
        noise_response_cpsd, noise_reference_cpsd, sysid_response_cpsd, sysid_reference_cpsd,
        multiple_coherence, frames, total_frames, output_oversample_factor, extra_parameters,
        last_excitation_signals, last_response_signals) -> drive

    # generator: made with no argument, primed with next(), then sent the same 15 arguments
    # as one tuple for every drive; it yields the drive
    gen = law(); next(gen); drive = gen.send((sample_rate, ..., last_response_signals))

    # class: made with the arguments below, told of a new identification by system_id_update,
    # asked for a drive by control
    obj = law(sample_rate, specification_signals, output_oversample_factor, extra_parameters,
              frequency_spacing, transfer_function, noise_response_cpsd, noise_reference_cpsd,
              sysid_response_cpsd, sysid_reference_cpsd, multiple_coherence, frames,
              total_frames, last_excitation_signals, last_response_signals)
    obj.system_id_update(frequency_spacing, transfer_function, noise_response_cpsd,
                         noise_reference_cpsd, sysid_response_cpsd, sysid_reference_cpsd,
                         multiple_coherence, frames, total_frames)
    drive = obj.control(last_excitation_signals, last_response_signals)

What vrig gives the law (all from the identification records, at the model rate):

* ``sample_rate`` [Hz]; ``specification_signals`` (n_responses, n_samples): the response the
  drive is asked for; ``frequency_spacing`` [Hz] ``= sample_rate / nperseg``;
* ``transfer_function`` (F, n_responses, n_drives), complex: the H1 estimate (Welch,
  ``nperseg`` samples a frame, Hann window, half overlap: :func:`vrig.spectra.frf_h1` with
  ``regularisation="line"``, the estimate :class:`~vrig.reconstruction.InverseFrf` inverts);
* ``sysid_response_cpsd`` (F, n_responses, n_responses), ``sysid_reference_cpsd`` (F, n_drives,
  n_drives): one-sided cross-power spectral densities of the identification response and drive;
* ``noise_response_cpsd``: what the linear FRF does not explain of the identification response,
  ``Syy - H Suu H^H`` (Rattlesnake measures its noise in a run with the drives off; a simulated
  rig's run-to-run noise and non-linearity are both in this residual); ``noise_reference_cpsd``:
  zeros (vrig's drive is known exactly, not measured);
* ``multiple_coherence`` (F, n_responses); ``frames`` and ``total_frames``: the number of Welch
  frames averaged (both the same: every frame there was);
* ``output_oversample_factor``: ``oversample`` (default 1); the law's drive is taken at every
  ``oversample``-th sample;
* ``extra_parameters``: the ``extra_parameters`` string as given (Rattlesnake's free-text box);
* ``last_excitation_signals`` (n_drives, n_samples) and ``last_response_signals``
  (n_responses, n_samples): the drive last played and its processed response, once an iteration
  has been played (``observe``, which the iteration calls after each play), else None.

The law must return the drive as a real, finite array (n_drives, n_samples x oversample).

How vrig iterates with it: IT00DRV is the law's drive for DESRES; an iteration corrects with
``gain * (law(DESRES) - law(ITnRES))`` as for every method (for a law linear in the
specification, e.g. the pseudo-inverse, this is the law's drive for the remaining error). Each
distinct specification gets its own generator or class object (the generator of Rattlesnake's
examples computes the specification's spectrum once, on its first call).
"""

from __future__ import annotations

import hashlib
import importlib.util
import inspect
import os
import traceback
from collections import OrderedDict
from pathlib import Path

import numpy as np

from ..errors import ControlLawError
from ..spectra import frf_h1
from ..timehistory import TimeHistory
from .methods import FRF_MIN_SAMPLES

__all__ = ["FUNCTION_ARGUMENTS", "RattlesnakeLaw", "load_law"]

FUNCTION_ARGUMENTS = (
    "sample_rate",
    "specification_signals",
    "frequency_spacing",
    "transfer_function",
    "noise_response_cpsd",
    "noise_reference_cpsd",
    "sysid_response_cpsd",
    "sysid_reference_cpsd",
    "multiple_coherence",
    "frames",
    "total_frames",
    "output_oversample_factor",
    "extra_parameters",
    "last_excitation_signals",
    "last_response_signals",
)
"""The arguments of a function law, in order (a generator law is sent them as one tuple)."""

_SYSID = FUNCTION_ARGUMENTS[2:11]  # system_id_update's arguments
_CLASS_INIT = (
    *FUNCTION_ARGUMENTS[:2],
    "output_oversample_factor",
    "extra_parameters",
    *_SYSID,
    "last_excitation_signals",
    "last_response_signals",
)
_LIVE = 4  # generators / class objects kept, one per specification (DESRES, the last ITnRES)


def load_law(path, name: str):
    """The control law ``name`` defined in the Python file ``path`` (imported with importlib,
    under a private module name; nothing is added to ``sys.path``).

    Parameters
    ----------
    path : str or Path
        The law's file.
    name : str
        The function, generator function or class in it.

    Raises
    ------
    ValueError
        No such file, a file that fails to import (the error quoted), or no ``name`` in it.
    """
    p = Path(path)
    if not p.is_file():
        raise ValueError(f"Rattlesnake control law file {str(path)!r}: no such file")
    digest = hashlib.sha256(str(p.resolve()).encode()).hexdigest()[:12]
    spec = importlib.util.spec_from_file_location(f"_vrig_rattlesnake_{digest}", p)
    if spec is None or spec.loader is None:
        raise ValueError(f"Rattlesnake control law file {str(path)!r}: not a Python file")
    module = importlib.util.module_from_spec(spec)
    try:
        spec.loader.exec_module(module)
    except Exception as exc:  # the user's file: say what went wrong in it
        raise ValueError(
            f"Rattlesnake control law file {str(path)!r} could not be loaded: "
            f"{type(exc).__name__}: {exc}"
        ) from exc
    law = getattr(module, name, None)
    if law is None:
        found = sorted(k for k, v in vars(module).items() if callable(v) and not k.startswith("_"))
        raise ValueError(
            f"Rattlesnake control law file {str(path)!r} defines no {name!r} (it defines: "
            f"{', '.join(found) or 'nothing callable'})"
        )
    return law


def _form(law, label: str) -> str:
    """``"function"``, ``"generator"`` or ``"class"``; a TypeError naming the law and the
    interface it misses."""
    if inspect.isclass(law):
        missing = [
            m for m in ("system_id_update", "control") if not callable(getattr(law, m, None))
        ]
        if missing:
            raise TypeError(
                f"Rattlesnake control law {label}: a class law needs the methods "
                f"system_id_update and control; it has no {', '.join(missing)}"
            )
        _binds(law, _CLASS_INIT, label, "a class law's __init__")
        _binds(law.control, (None, *FUNCTION_ARGUMENTS[13:]), label, "control")
        _binds(law.system_id_update, (None, *_SYSID), label, "system_id_update")
        return "class"
    if inspect.isgeneratorfunction(law):
        _binds(law, (), label, "a generator law")
        return "generator"
    if callable(law):
        _binds(law, FUNCTION_ARGUMENTS, label, "a function law")
        return "function"
    raise TypeError(
        f"Rattlesnake control law {label} is a {type(law).__name__}: expected a function, a "
        "generator function or a class"
    )


def _binds(fn, names, label: str, what: str) -> None:
    """``fn`` accepts ``len(names)`` positional arguments, or a TypeError saying which."""
    try:
        inspect.signature(fn).bind(*([None] * len(names)))
    except TypeError as exc:
        args = ", ".join(n for n in names if n) or "no argument"
        raise TypeError(
            f"Rattlesnake control law {label}: {what} must take ({args}); {exc}"
        ) from None
    except ValueError:  # no signature (a builtin): called as it is
        return


class RattlesnakeLaw:
    """A Rattlesnake transient control law run as a vrig method (see the module docstring).

    Parameters
    ----------
    law : str or callable
        ``"<file.py>:<name>"`` (loaded with :func:`load_law`) or the law itself (a function,
        generator function or class of Rattlesnake's transient interface).
    extra_parameters : str, optional
        Rattlesnake's free-text parameters, passed to the law as they are.
    nperseg : int, optional
        Welch frame length of the FRF and CPSDs [samples at the model rate] (frequency spacing
        ``fs / nperseg``); at most a quarter of the identification record.
    oversample : int, optional
        ``output_oversample_factor`` given to the law; vrig takes every ``oversample``-th sample
        of its drive.

    Raises
    ------
    ValueError
        A source string without ``:``, a missing file or name (:func:`load_law`), bad options.
    TypeError
        A law of none of the three forms or with the wrong arguments.
    """

    name = "rattlesnake"

    def __init__(self, law, *, extra_parameters: str = "", nperseg: int = 512, oversample: int = 1):
        if not isinstance(extra_parameters, str):
            raise TypeError(
                f"extra_parameters must be a string, got {type(extra_parameters).__name__}"
            )
        for key, value, low in (("nperseg", nperseg, 8), ("oversample", oversample, 1)):
            if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < low:
                raise ValueError(f"{key} must be an integer >= {low}, got {value!r}")
        self.source = law if isinstance(law, str) else None
        self.extra_parameters, self.nperseg, self.oversample = extra_parameters, nperseg, oversample
        self._law = self._load() if self.source is not None else law
        self.label = self.source or getattr(law, "__qualname__", repr(law))
        self._file = _law_file(self.source, self._law)
        self.form = _form(self._law, repr(self.label))
        self._live: OrderedDict = OrderedDict()
        self._last = (None, None)
        self._sysid: dict | None = None

    def _load(self):
        path, sep, name = self.source.rpartition(":")
        if not sep or not path or not name:
            raise ValueError(
                f"a Rattlesnake control law is named 'rattlesnake:<file.py>:<name>', got "
                f"'rattlesnake:{self.source}'"
            )
        return load_law(path, name)

    def __getstate__(self):
        state = dict(self.__dict__)
        state["_live"] = OrderedDict()  # generators cannot be copied: made again when needed
        if self.source is not None:
            state["_law"] = None  # loaded again from the file (a module not in sys.modules)
        return state

    def __setstate__(self, state):
        self.__dict__.update(state)
        if self._law is None:
            self._law = self._load()

    def identify(self, iddrv: TimeHistory, idres: TimeHistory) -> None:
        """The FRF, CPSDs and coherence the law is given, from the identification records.

        Parameters
        ----------
        iddrv : TimeHistory
            Identification drive record.
        idres : TimeHistory
            The response measured for it (same length and sample rate).
        """
        n = iddrv.n_samples
        nper = min(self.nperseg, n // 4)
        h1 = frf_h1(iddrv.data, idres.data, fs=iddrv.fs, nperseg=nper, regularisation="line")
        H, suu, syy = h1.frf, h1.gxx, h1.gyy
        noise = syy - np.einsum("fij,fjk,flk->fil", H, suu, H.conj())
        frames = 1 + (n - nper) // (nper - nper // 2)  # scipy's Welch: half-overlapping frames
        self.n_drives, self.fs = iddrv.n_channels, float(iddrv.fs)
        self._sysid = {
            "frequency_spacing": self.fs / nper,
            "transfer_function": H,
            "noise_response_cpsd": noise,
            "noise_reference_cpsd": np.zeros_like(suu),
            "sysid_response_cpsd": syy,
            "sysid_reference_cpsd": suu,
            "multiple_coherence": h1.coherence,
            "frames": frames,
            "total_frames": frames,
        }
        for key, live in list(self._live.items()):
            if self.form == "class":  # told of the new identification, as Rattlesnake does
                live.system_id_update(*(self._sysid[k] for k in _SYSID))
            else:
                del self._live[key]

    def observe(self, drive: TimeHistory, response: TimeHistory) -> None:
        """Keep the drive last played and its processed response: the law's
        ``last_excitation_signals`` and ``last_response_signals`` from now on.

        Parameters
        ----------
        drive : TimeHistory
            The drive played (ITxxDRV), at the model rate.
        response : TimeHistory
            Its processed response (ITxxRES), at the model rate.
        """
        self._last = (np.array(drive.data.T, dtype=float), np.array(response.data.T, dtype=float))

    def drive(self, response: TimeHistory) -> np.ndarray:
        """The law's drive for ``response`` (n_samples, n_drives).

        Parameters
        ----------
        response : TimeHistory
            The specification (DESRES, or an iteration's response), at the model rate.

        Raises
        ------
        ValueError
            The law returned a drive of the wrong shape, or one not real and finite.
        """
        if self._sysid is None:
            raise RuntimeError("identify() first")
        spec = np.array(response.data.T, dtype=float)
        args = {
            "sample_rate": self.fs,
            "specification_signals": spec,
            **self._sysid,
            "output_oversample_factor": self.oversample,
            "extra_parameters": self.extra_parameters,
            "last_excitation_signals": self._last[0],
            "last_response_signals": self._last[1],
        }
        cwd = os.getcwd()
        try:
            out = self._call(spec, args)
        except (Exception, SystemExit) as exc:  # the law's own error (or exit), with its line
            where = _where_in(exc, self._file)
            raise ControlLawError(
                f"Rattlesnake control law {self.label!r} raised {type(exc).__name__}: {exc}"
                + (f" (at {where})" if where else ""),
                law=self.label,
                where=where,
            ) from exc
        finally:  # a law that changes directory does not move the run's relative paths
            if os.getcwd() != cwd:
                os.chdir(cwd)
        return self._checked(out, spec.shape[1])

    def _call(self, spec: np.ndarray, args: dict):
        """The law's output for ``args`` in its form (a generator or object per specification)."""
        if self.form == "function":
            return self._law(*(args[k] for k in FUNCTION_ARGUMENTS))
        key = hashlib.sha256(spec.tobytes()).hexdigest()
        live = self._live.get(key)
        if live is None:
            if self.form == "generator":
                live = self._law()
                next(live)
            else:
                live = self._law(*(args[k] for k in _CLASS_INIT))
            self._live[key] = live
            while len(self._live) > _LIVE:
                self._live.popitem(last=False)
        self._live.move_to_end(key)
        last = (args["last_excitation_signals"], args["last_response_signals"])
        if self.form == "generator":
            return live.send(tuple(args[k] for k in FUNCTION_ARGUMENTS))
        return live.control(*last)

    def _checked(self, out, n: int) -> np.ndarray:
        """The law's output as vrig's drive (n, n_drives), or a ValueError naming the law."""
        want = (self.n_drives, n * self.oversample)
        x = np.asarray(out) if out is not None else None
        if x is None or x.shape != want:
            got = "None" if x is None else f"shape {x.shape}"
            raise ValueError(
                f"Rattlesnake control law {self.label!r} returned {got}; expected the drive as "
                f"an array (n_drives, n_samples x oversample) = {want}"
            )
        if not np.isrealobj(x) or not np.issubdtype(x.dtype, np.number):
            raise ValueError(
                f"Rattlesnake control law {self.label!r} returned a {x.dtype} drive; expected "
                "real numbers"
            )
        if not np.all(np.isfinite(x)):
            raise ValueError(
                f"Rattlesnake control law {self.label!r} returned a drive with non-finite values"
            )
        return np.array(x[:, :: self.oversample].T, dtype=float)

    def describe(self) -> str:
        """One line: the law, its form and the FRF it was given."""
        text = self.describe_law()
        if self._sysid is not None:
            lines = self._sysid["transfer_function"].shape[0]
            text += f", H1 with {lines} lines from {self._sysid['frames']} frames"
        return text

    def describe_law(self) -> str:
        """One line naming the law and its form (before :meth:`identify`)."""
        return f"rattlesnake {self.form} law {self.label}"

    def min_samples(self, n_drives: int, n_responses: int) -> int:
        """The shortest identification record [samples at the model rate]:
        :data:`~vrig.reconstruction.methods.FRF_MIN_SAMPLES`, as :class:`InverseFrf`.

        Parameters
        ----------
        n_drives, n_responses : int
            Numbers of drive and response channels of the rig (not used).
        """
        return FRF_MIN_SAMPLES

    def options(self) -> dict:
        """``law``, ``extra_parameters``, ``nperseg``, ``oversample``."""
        return {
            "law": self.label,
            "extra_parameters": self.extra_parameters,
            "nperseg": self.nperseg,
            "oversample": self.oversample,
        }

    def fitted_models(self) -> dict:
        """``{}``: the law has no model file."""
        return {}

    def model_size(self) -> int | None:
        """Real numbers in the FRF the law is given (2 per complex entry); None before
        :meth:`identify`."""
        return None if self._sysid is None else int(2 * self._sysid["transfer_function"].size)


def _law_file(source: str | None, law) -> str | None:
    """The path of the file the law is written in (None when it cannot be told)."""
    if source is not None:
        return source.rpartition(":")[0]
    try:
        return inspect.getsourcefile(law)
    except TypeError:
        return None


def _where_in(exc: BaseException, source) -> str:
    """``"file:line in function"`` of the deepest traceback frame of ``exc`` in the law's file
    ``source`` ("" when no frame is)."""
    if source is None:
        return ""
    try:
        target = Path(source).resolve()
    except (TypeError, OSError):
        return ""
    frames = [f for f in traceback.extract_tb(exc.__traceback__) if _same_file(f.filename, target)]
    if not frames:
        return ""
    f = frames[-1]
    return f"{f.filename}:{f.lineno} in {f.name}"


def _same_file(name: str, target: Path) -> bool:
    try:
        return Path(name).resolve() == target
    except OSError:
        return False
