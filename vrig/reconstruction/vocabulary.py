"""One method vocabulary: a method name and its options become a method object and its one-line
description here, and only here.

``vrig reconstruct`` (``--method``, ``--order``, ``--degree``, ``--split-hz``, ``--search``,
``--budget``), :func:`vrig.reconstruct` / :class:`~vrig.reconstruction.DriveIteration` (``method``
and the method options of :class:`~vrig.reconstruction.IterationSettings`), the gymnasium envs
and the benchmark runner's built-in methods all build their methods with :func:`method_spec`,
through the one defaults resolver (:func:`vrig.reconstruction.defaults.resolve`).

The vocabulary's own options, shared by the methods that take them (None: not given); their
defaults are the method classes' own (:mod:`vrig.reconstruction.defaults`: the precedence):

=============  ===========================================  ==========================================
option         methods                                      range
=============  ===========================================  ==========================================
``order``      arx, narx, split (both bands), error-signal  1..20
               (``linear_order``)
``degree``     narx, split (a NARX low band), error-signal  1..5
``focus``      narx, error-signal                           ``"prediction"`` or ``"simulation"``
``split_hz``   split                                        inside the band
``search``     narx                                         True or False
``budget``     narx with ``search``                         > 0 s
=============  ===========================================  ==========================================

:func:`method_spec` builds a method from what it is given; the rig side-car's method block and the
built-in defaults are applied before, by :func:`vrig.reconstruction.defaults.resolve` (the one
resolver every door uses), which reads the side-car's values with :func:`side_car_vocabulary`.
Any other option is the method class's own keyword argument (``kind``, ``lead``, ``nperseg``,
``low``/``high`` band methods ...) and goes to it unchanged
(:func:`~vrig.reconstruction.make_method` refuses one it does not take).

A name ``"rattlesnake:<file.py>:<name>"`` is a control law written to Sandia Rattlesnake's
transient control-law interface (:class:`~vrig.reconstruction.rattlesnake.RattlesnakeLaw`).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any

from ..errors import VrigError
from .methods import InverseArx, InverseNarx, make_method

__all__ = [
    "BUILTIN_METHODS",
    "RATTLESNAKE_PREFIX",
    "MethodOptionError",
    "MethodSpec",
    "is_method_name",
    "method_spec",
    "side_car_vocabulary",
]

BUILTIN_METHODS = ("arx", "narx", "split", "frf", "error-signal")
"""The method names of ``vrig reconstruct --method`` (besides ``rattlesnake:...``)."""

RATTLESNAKE_PREFIX = "rattlesnake:"
"""The prefix of a Rattlesnake control law's method name, ``"rattlesnake:<file.py>:<name>"``."""

ORDER_RANGE = (1, 20)
DEGREE_RANGE = (1, 5)
_VOCABULARY = ("order", "degree", "focus", "split_hz", "search", "budget")
_TAKES = {  # the vocabulary options each built-in method takes
    "arx": {"order"},
    "narx": {"order", "degree", "focus", "search", "budget"},
    "split": {"order", "degree", "split_hz"},
    "error-signal": {"order", "degree", "focus"},
    "frf": set(),
}


class MethodOptionError(VrigError, ValueError):
    """A method option that does not apply to the method or lies outside its range.

    ``str(exc)`` says it in Python's words (``order must be 1..20, got 0``); ``exc.cli`` in the
    command line's (``--order must be 1..20, got 0``), which ``vrig reconstruct`` prints as a
    usage error (exit code 2).

    Parameters
    ----------
    message : str
        The message in Python's words.
    cli : str
        The same message in the command line's words.
    """

    def __init__(self, message: str, cli: str):
        super().__init__(message)
        self.cli = cli


@dataclass(frozen=True)
class MethodSpec:
    """A method built by :func:`method_spec`.

    Attributes
    ----------
    method : Method
        The (unfitted) method object.
    description : str
        One line saying what it is (``"narx order 4 degree 2"``): ``vrig reconstruct``'s
        ``method`` line and its results folder's ``settings.json``.
    options : Mapping
        The keyword arguments the method class was built with (after every default), read-only.
    """

    method: Any
    description: str
    options: Mapping[str, Any] = field(default_factory=dict)

    def __post_init__(self):
        object.__setattr__(self, "options", MappingProxyType(dict(self.options)))


def is_method_name(name) -> bool:
    """Whether ``name`` is a method name of the vocabulary: one of :data:`BUILTIN_METHODS` or
    ``"rattlesnake:<file.py>:<name>"`` (the file is not looked at here).

    Parameters
    ----------
    name : object
        The candidate.
    """
    return isinstance(name, str) and (
        name in BUILTIN_METHODS or name.startswith(RATTLESNAKE_PREFIX)
    )


def side_car_vocabulary(name: str, rig) -> dict:
    """The rig side-car's vocabulary options for method ``name`` (``reconstruction.methods.NAME``:
    ``order``, ``degree``, ``focus``, ``split_hz``), only those the method takes and the side-car
    sets (``{}`` without a side-car or for a name outside :data:`BUILTIN_METHODS`).

    Parameters
    ----------
    name : str
        The method name.
    rig : Rig or None
        The rig (``rig.defaults``, :class:`~vrig.rigs.spec.RigDefaults`).

    Returns
    -------
    dict
    """
    defaults = getattr(rig, "defaults", None)
    if defaults is None or name not in _TAKES:
        return {}
    m = defaults.method(name)
    return {
        k: getattr(m, k)
        for k in ("order", "degree", "focus", "split_hz")
        if k in _TAKES[name] and getattr(m, k) is not None
    }


def method_spec(name, *, rig=None, band=None, **given) -> MethodSpec:
    """The method object for ``name`` and the options given, with its description (see the
    module docstring for the vocabulary). No default is applied here: an option not given is the
    method class's own default (:func:`vrig.reconstruction.defaults.resolve` applies the rig
    side-car's first).

    Parameters
    ----------
    name : str or method object
        A name of :data:`BUILTIN_METHODS`, ``"rattlesnake:<file.py>:<name>"``, or an object with
        ``identify`` and ``drive`` (returned as it is; no options then).
    rig : Rig, optional
        Unused by the options (kept for the description of a split's source); may be None.
    band : (float, float), optional
        The simulation band [Hz]: a ``split_hz`` must lie inside it.
    **given
        Options: the vocabulary's (None: not given) and the method class's own.

    Returns
    -------
    MethodSpec

    Raises
    ------
    MethodOptionError
        A vocabulary option the method does not take, or one outside its range.
    ValueError
        An unknown method name, an option the method class does not take, or ``split``
        without ``split_hz``.
    """
    if not isinstance(name, str):
        method = make_method(name, **given)
        return MethodSpec(method, str(getattr(method, "name", type(method).__name__)), {})
    vocab = {k: given.pop(k) for k in _VOCABULARY if k in given}
    vocab = {k: v for k, v in vocab.items() if v is not None and v is not False}
    if name.startswith(RATTLESNAKE_PREFIX):
        return _rattlesnake(name, vocab, given)
    if name not in _TAKES:
        make_method(name)  # the unknown-name error of make_method
    _check_applies(name, vocab)
    if name == "split" and "split_hz" not in vocab:
        raise ValueError(
            "method 'split' needs split_hz (vrig.reconstruction.defaults.resolve gives the rig's "
            "or the band rule's)"
        )
    _check_ranges(vocab, band if name == "split" else None)
    options = _class_options(name, vocab, given)
    method = make_method(name, **options)
    return MethodSpec(method, _describe(name, method), options)


def _say(message: str, *, cli: str) -> MethodOptionError:
    return MethodOptionError(message, cli)


def _check_applies(name: str, vocab: dict) -> None:
    """Each given vocabulary option applies to ``name`` (the command line's messages)."""
    if "order" in vocab and "order" not in _TAKES.get(name, ()):
        text = f"order applies to arx, narx and split, not {name}"
        raise _say(text, cli="--" + text)
    if "degree" in vocab and "degree" not in _TAKES.get(name, ()):
        text = (
            f"degree applies to narx and split (a NARX low band), and to error-signal; not {name}"
        )
        raise _say(text, cli="--" + text)
    if "split_hz" in vocab and name != "split":
        raise _say(
            "split_hz applies to method 'split' only",
            cli="--split-hz applies to --method split only",
        )
    if "search" in vocab and name != "narx":
        raise _say(
            "search applies to method 'narx' only", cli="--search applies to --method narx only"
        )
    if "budget" in vocab and "search" not in vocab:
        raise _say("budget applies to search=True only", cli="--budget applies to --search only")
    if "focus" in vocab and "focus" not in _TAKES.get(name, ()):
        text = f"focus applies to narx and error-signal, not {name}"
        raise _say(text, cli=text)  # (no flag: only a side-car or the Python API gives it)


def _check_ranges(vocab: dict, band) -> None:
    """The vocabulary options' ranges (the command line's messages)."""
    budget = vocab.get("budget")
    if budget is not None and not (0 < budget < float("inf")):
        text = f"budget must be a positive number of seconds, got {budget:g}"
        raise _say(text, cli="--" + text)
    for key, (lo, hi) in (("order", ORDER_RANGE), ("degree", DEGREE_RANGE)):
        value = vocab.get(key)
        if value is not None and not lo <= value <= hi:
            text = f"{key} must be {lo}..{hi}, got {value}"
            raise _say(text, cli="--" + text)
    split = vocab.get("split_hz")
    if split is not None and band is not None:
        lo, hi = band
        if not lo < split < hi:
            text = f"must lie inside the band {lo:g}-{hi:g} Hz, got {split:g}"
            raise _say(f"split_hz {text}", cli=f"--split-hz {text}")


def _class_options(name: str, vocab: dict, rest: dict) -> dict:
    """The method class's keyword arguments from the vocabulary options ``vocab`` given and the
    class's own options ``rest`` (nothing given: the class's own defaults)."""
    out = dict(rest)
    order, degree = vocab.get("order"), vocab.get("degree")
    if name in ("arx", "narx") and order is not None:
        out["order"] = order
    if name == "error-signal":
        if "order" in vocab and "linear_order" in rest:
            raise ValueError("error-signal: give order or linear_order, not both")
        if order is not None:
            out.setdefault("linear_order", order)
    if name in ("narx", "error-signal"):
        if degree is not None:
            out["degree"] = degree
        if "focus" in vocab and not vocab.get("search"):
            out["focus"] = vocab["focus"]
    if name == "narx" and vocab.get("search"):
        out["search"] = True
        if "budget" in vocab:
            out["budget"] = float(vocab["budget"])
    if name == "split":
        out["split_hz"] = float(vocab["split_hz"])
        if "low" not in rest and "high" not in rest and (order or degree):
            band_order = {} if order is None else {"order": order}
            out["low"] = (
                InverseNarx(degree=degree, **band_order) if degree else InverseArx(**band_order)
            )
            out["high"] = InverseArx(**band_order)
    return out


def _describe(name: str, method) -> str:
    """The one-line description of a built-in method, read from the built object."""
    focus = getattr(method, "focus", "prediction")
    fit = "" if focus == "prediction" else f", {focus} focus"
    if name == "arx":
        return f"arx order {method.order}"
    if name == "narx":
        if getattr(method, "search", False):
            return (
                f"narx searched by free-run validation (orders up to {2 * method.order}, degrees "
                f"1..{method.degree}, budget {method.budget:g} s)"
            )
        return f"narx order {method.order} degree {method.degree}{fit}"
    if name == "split":
        return f"split spectra at {method.split_hz:g} Hz ({_bands(method)})"
    if name == "error-signal":
        return (
            f"error-signal (arx order {method.linear_order} + narx order "
            f"{method.nonlinear_order} degree {method.degree} of its drive error{fit})"
        )
    return "frf (H1, truncated-SVD/Tikhonov inverse)"


def _bands(method) -> str:
    """``low ... order n, high arx order n`` of a split method's band methods."""
    low, high = method.low, method.high
    parts = []
    for part, band in (("low", low), ("high", high)):
        if isinstance(band, InverseNarx):
            parts.append(f"{part} narx degree {band.degree} order {band.order}")
        elif isinstance(band, InverseArx):
            parts.append(f"{part} arx order {band.order}")
        else:
            parts.append(f"{part} {getattr(band, 'name', type(band).__name__)}")
    return ", ".join(parts)


def _rattlesnake(name: str, vocab: dict, given: dict) -> MethodSpec:
    """A Rattlesnake control law's method (no vocabulary option applies to it)."""
    from .rattlesnake import RattlesnakeLaw

    if vocab:
        key = next(iter(vocab))
        flag = "--" + key.replace("_", "-")
        raise _say(
            f"{key} does not apply to a Rattlesnake control law ({name})",
            cli=f"{flag} does not apply to --method {name}",
        )
    method = RattlesnakeLaw(name[len(RATTLESNAKE_PREFIX) :], **given)
    return MethodSpec(method, method.describe_law(), {"law": method.source, **given})
