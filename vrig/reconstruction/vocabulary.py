"""One method vocabulary: a method name and its options (plus the rig's side-car defaults and the
simulation band) become a method object and its one-line description here, and only here.

``vrig reconstruct`` (``--method``, ``--order``, ``--degree``, ``--split-hz``, ``--search``,
``--budget``), :func:`vrig.reconstruct` / :class:`~vrig.reconstruction.DriveIteration` (``method``
and the method options of :class:`~vrig.reconstruction.IterationSettings`), the gymnasium envs
(:func:`vrig.envs.physics.rig_settings`) and the benchmark runner's built-in methods all build
their methods with :func:`method_spec`.

The vocabulary's own options, shared by the methods that take them (None: not given):

=============  ===========================================  ==========================================
option         methods                                      default
=============  ===========================================  ==========================================
``order``      arx, narx, split (both bands), error-signal  4; error-signal 3 (its inverse ARX's order,
               (``linear_order``)                           ``linear_order``); range 1..20
``degree``     narx, split (a NARX low band), error-signal  2 (split: none, an ARX low band); 1..5
``focus``      narx, error-signal                           ``"prediction"``
``split_hz``   split                                        :func:`vrig.reconstruction.defaults.default_split_hz`
                                                            (the side-car's split, else the band's
                                                            rule); inside the band
``search``     narx                                         False
``budget``     narx with ``search``                         60 s; > 0
=============  ===========================================  ==========================================

Layers, first wins: what the caller gives, the rig side-car's
``reconstruction.methods.METHOD`` (:class:`~vrig.rigs.spec.MethodDefaults`: ``order``,
``degree``, ``focus``, ``split_hz``; only where the method takes the option), the built-in
defaults above. Any other option is the method class's own keyword argument (``kind``, ``lead``,
``nperseg``, ``low``/``high`` band methods ...) and goes to it unchanged
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
from .defaults import default_split_hz
from .methods import InverseArx, InverseNarx, make_method

__all__ = [
    "BUILTIN_METHODS",
    "RATTLESNAKE_PREFIX",
    "MethodOptionError",
    "MethodSpec",
    "is_method_name",
    "method_spec",
    "side_car_options",
]

BUILTIN_METHODS = ("arx", "narx", "split", "frf", "error-signal")
"""The method names of ``vrig reconstruct --method`` (besides ``rattlesnake:...``)."""

RATTLESNAKE_PREFIX = "rattlesnake:"
"""The prefix of a Rattlesnake control law's method name, ``"rattlesnake:<file.py>:<name>"``."""

ORDER_RANGE = (1, 20)
DEGREE_RANGE = (1, 5)
DEFAULT_BUDGET_S = 60.0
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


def side_car_options(name: str, rig, band) -> dict:
    """The rig side-car's defaults for method ``name`` as keyword arguments of its class (what
    :func:`vrig.envs.physics.rig_settings` puts into ``method_options``): ``order`` (error-signal:
    ``linear_order``), ``degree``, ``focus``, and for ``split`` its ``split_hz`` (the side-car's,
    else :func:`vrig.reconstruction.defaults.default_split_hz`'s band rule, always given) and, when the side-car
    sets an order or degree, the band methods ``low`` / ``high``. Only options the method takes;
    the built-in defaults are left to the class.

    Parameters
    ----------
    name : str
        The method name.
    rig : Rig or None
        The rig; one without ``defaults`` gives the band rule's split only.
    band : (float, float)
        The simulation band [Hz].

    Returns
    -------
    dict
    """
    vocab = _side_car(name, rig)
    if name == "split":
        vocab.setdefault("split_hz", float(default_split_hz(band, rig)))
    return _class_options(name, vocab, {}, defaults=False)


def method_spec(name, *, rig=None, band=None, side_car: bool = True, **given) -> MethodSpec:
    """The method object for ``name`` and options, with its description (see the module
    docstring for the vocabulary and its layers).

    Parameters
    ----------
    name : str or method object
        A name of :data:`BUILTIN_METHODS`, ``"rattlesnake:<file.py>:<name>"``, or an object with
        ``identify`` and ``drive`` (returned as it is; no options then).
    rig : Rig, optional
        The rig: its side-car's defaults for the method (``side_car=True``) and its split
        frequency (:func:`vrig.reconstruction.defaults.default_split_hz`).
    band : (float, float), optional
        The simulation band [Hz]; ``split`` needs it (or ``split_hz``), and checks its split lies
        inside it.
    side_car : bool, optional
        Apply the side-car's ``order``, ``degree``, ``focus`` and ``split_hz`` (default). False:
        only the split frequency rule, as :func:`vrig.reconstruct` does.
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
        An unknown method name, or an option the method class does not take.
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
    if side_car:
        vocab = {**_side_car(name, rig), **vocab}
    if name == "split" and "split_hz" not in vocab:
        if band is None:
            raise ValueError("method 'split' needs split_hz, or a band to derive it from")
        vocab["split_hz"] = float(default_split_hz(band, rig))
    _check_ranges(vocab, band if name == "split" else None)
    options = _class_options(name, vocab, given, defaults=True)
    return MethodSpec(make_method(name, **options), _describe(name, options), options)


def _side_car(name: str, rig) -> dict:
    """The side-car's vocabulary options for ``name`` that the method takes (``{}`` without a
    side-car)."""
    defaults = getattr(rig, "defaults", None)
    if defaults is None or name not in _TAKES:
        return {}
    m = defaults.method(name)
    return {
        k: getattr(m, k)
        for k in ("order", "degree", "focus", "split_hz")
        if k in _TAKES[name] and getattr(m, k) is not None
    }


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


def _class_options(name: str, vocab: dict, rest: dict, *, defaults: bool) -> dict:
    """The method class's keyword arguments from the vocabulary options ``vocab`` (with the
    built-in defaults when ``defaults``) and the class's own options ``rest``."""
    out = dict(rest)
    order = vocab.get("order", (3 if name == "error-signal" else 4) if defaults else None)
    degree = vocab.get("degree", 2 if defaults and name != "split" else None)
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
        out.update(search=True, budget=float(vocab.get("budget", DEFAULT_BUDGET_S)))
    if name == "split":
        out["split_hz"] = float(vocab["split_hz"])
        if "low" not in rest and "high" not in rest and (defaults or order or degree):
            order = 4 if order is None else order
            out["low"] = InverseNarx(order, degree) if degree else InverseArx(order)
            out["high"] = InverseArx(order)
    return out


def _describe(name: str, options: dict) -> str:
    """The one-line description of a built-in method from its class options."""
    fit = (
        "" if options.get("focus", "prediction") == "prediction" else f", {options['focus']} focus"
    )
    if name == "arx":
        return f"arx order {options.get('order', 4)}"
    if name == "narx":
        order, degree = options.get("order", 4), options.get("degree", 2)
        if options.get("search"):
            return (
                f"narx searched by free-run validation (orders up to {2 * order}, degrees "
                f"1..{degree}, budget {options['budget']:g} s)"
            )
        return f"narx order {order} degree {degree}{fit}"
    if name == "split":
        return f"split spectra at {options['split_hz']:g} Hz ({_bands(options)})"
    if name == "error-signal":
        return (
            f"error-signal (arx order {options.get('linear_order', 3)} + narx order "
            f"{options.get('nonlinear_order', 2)} degree {options.get('degree', 2)} of its drive "
            f"error{fit})"
        )
    return "frf (H1, truncated-SVD/Tikhonov inverse)"


def _bands(options: dict) -> str:
    """``low ... order n, high arx order n`` of a split method's band methods."""
    low, high = options.get("low"), options.get("high")
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
