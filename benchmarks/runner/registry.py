"""Reconstruction methods of the benchmark runner: the built-ins and the plugins.

A *method* is a :class:`vrig.reconstruction.protocol.Method`:

* ``identify(iddrv, idres)`` — fit from processed identification records (``TimeHistory``,
  drive and response, at the model rate);
* ``drive(response) -> ndarray (n_samples, n_drives)`` — the drive it predicts for a response;
* ``describe() -> str`` — one line (optional: without it the record shows the class name);
* ``model_size() -> int`` — number of model coefficients (optional:
  :class:`~vrig.reconstruction.protocol.SizedMethod`; every vrig method has it);
* ``fitted_lead()`` / ``set_lead(lead)`` (optional:
  :class:`~vrig.reconstruction.protocol.InverseModelMethod`): the runner's extra modelling-error
  fits keep the reconstruction's lead and make the forward model causal.

A *plugin* registers a name and a factory ``factory(rig, band) -> method`` (``band`` is the
simulation bandwidth (low, high) in Hz; a factory without parameters is called without them)::

    from benchmarks.runner import register_method
    register_method("arx6", lambda rig, band: InverseArx(order=6), description="inverse ARX(6)")

Plugins are Python modules: every module of ``benchmarks/plugins/`` is loaded, and
``--plugin MODULE_OR_FILE.py`` adds more. Because records run in worker processes (or on a Ray
cluster), a plugin is loaded again in each worker from its *spec* — a module name, or the source
text of a file — never pickled as a live object.
"""

from __future__ import annotations

import hashlib
import importlib
import inspect
import pkgutil
import sys
import types
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from vrig.reconstruction.protocol import SizedMethod

__all__ = [
    "MethodPlugin",
    "PluginError",
    "PluginSpec",
    "default_plugin_specs",
    "get_method",
    "load_plugins",
    "method_names",
    "model_size",
    "plugin_spec",
    "register_method",
]


@dataclass(frozen=True)
class MethodPlugin:
    """A registered method: ``factory(rig, band)`` builds a fresh, unfitted method object.

    ``forward`` (optional) builds the object used for the *normal* (forward) modelling error
    with the roles of drive and response swapped; by default the method's own factory is used.
    ``quick`` says whether the method belongs to ``--quick`` runs; ``origin`` where it came from.
    ``linear``: True for a linear model (ARX, FIR, FRF, split spectra of ARX), False for a
    non-linear one (NARX), None when the plugin did not say; the leaderboard's severity section
    compares the best non-linear with the best linear method (unclassified ones are left out).
    ``update``: the iteration's model update (``vrig.IterationSettings.update``, default
    ``"none"``) the record runs the method with.
    """

    name: str
    factory: Callable
    description: str = ""
    quick: bool = True
    forward: Callable | None = None
    origin: str = "builtin"
    linear: bool | None = None
    update: str = "none"

    def make(self, rig, band):
        return _call(self.factory, rig, band)

    def make_forward(self, rig, band):
        return _call(self.forward or self.factory, rig, band)


def _call(factory, rig, band):
    try:
        n_params = len(inspect.signature(factory).parameters)
    except (TypeError, ValueError):  # builtins without a signature
        n_params = 2
    return factory() if n_params == 0 else factory(rig, band)


_REGISTRY: dict[str, MethodPlugin] = {}
_LOADING: list[str] = ["builtin"]  # origin given to methods registered while a plugin loads


def register_method(
    name: str,
    factory: Callable,
    *,
    description: str = "",
    quick: bool = True,
    forward: Callable | None = None,
    linear: bool | None = None,
    update: str = "none",
) -> MethodPlugin:
    """Register a reconstruction method under ``name`` (re-registering replaces it).

    Parameters
    ----------
    name : str
        Method name used by ``--methods`` and in the leaderboard (letters, digits, ``-``, ``_``).
    factory : callable
        ``factory(rig, band) -> method object`` (or ``factory()``); called once per use, so it
        must return a fresh, unfitted object. It must be a pure function of its arguments (no
        global random state): records are pure functions of their key.
    description : str
        One line for the leaderboard.
    quick : bool
        Include the method in ``--quick`` runs (say False for slow methods).
    forward : callable, optional
        Factory of the object used for the normal modelling error (see ``record.py``).
    linear : bool, optional
        True if the method's model is linear in the response (ARX, FIR, FRF), False if it is
        non-linear (NARX); None (default): unclassified, left out of the severity crossover
        (the lowest severity at which the best non-linear method beats the best linear one).
    update : str
        The drive iteration's model update (``vrig.IterationSettings.update``: ``"none"``,
        ``"frf"``, ``"secant"``, ``"reidentify"``, ``"ilc"``) the method's records run with.
    """
    if not name or not all(c.isalnum() or c in "-_" for c in name):
        raise ValueError(f"method name {name!r}: use letters, digits, '-' and '_' only")
    if not callable(factory):
        raise TypeError(f"factory of method {name!r} must be callable")
    if linear is not None and not isinstance(linear, bool):
        raise TypeError(f"linear of method {name!r} must be True, False or None, got {linear!r}")
    from vrig.reconstruction import UPDATES

    if update not in UPDATES:
        raise ValueError(f"update of method {name!r} must be one of {UPDATES}, got {update!r}")
    plugin = MethodPlugin(
        name, factory, description, bool(quick), forward, _LOADING[-1], linear, update
    )
    _REGISTRY[name] = plugin
    return plugin


def get_method(name: str) -> MethodPlugin:
    try:
        return _REGISTRY[name]
    except KeyError:
        raise KeyError(
            f"unknown method {name!r}; registered: {', '.join(method_names())} (a plugin module "
            "registers more: --plugin MODULE_OR_FILE.py)"
        ) from None


def method_names(*, quick: bool = False) -> list[str]:
    """Registered method names (built-ins first, then plugins in load order)."""
    return [n for n, p in _REGISTRY.items() if p.quick or not quick]


# ---------------------------------------------------------------------------------------------
# built-in methods (vrig.reconstruction's, resolved as vrig reconstruct resolves them)
# ---------------------------------------------------------------------------------------------
def _built(name: str, **options):
    """A factory ``(rig, band) -> method`` of method ``name`` and ``options`` resolved as every
    door resolves it (:func:`vrig.reconstruction.defaults.resolve`: the options given here, then
    the rig side-car's method block, then the method class's defaults): the object
    ``vrig reconstruct --method NAME`` runs on that rig."""

    def factory(rig, band):
        from vrig.reconstruction.defaults import resolve

        return resolve(rig, method=name, bandwidth=band, **options).method

    return factory


class ForwardFrf:
    """The forward model of the FRF method for the normal modelling error: H1 from the
    ``idres`` argument to the ``iddrv`` argument, applied directly (no inversion).

    The runner identifies forward models with drive and response swapped, so here ``idres`` is
    the rig's drive and ``drive(x)`` returns the predicted rig response to drive ``x``. (The
    FRF method's own object would invert twice, H1 of the swapped records and its regularised
    inverse, which is not the FRF forward model the method is built on.)"""

    def __init__(self, *, nperseg: int = 512):
        self.nperseg = nperseg

    def identify(self, iddrv, idres) -> None:
        from vrig.spectra import frf_h1

        x, y = idres.data, iddrv.data  # input: the rig's drive, output: its response
        nper = min(self.nperseg, x.shape[0] // 4)
        h1 = frf_h1(x, y, fs=idres.fs, nperseg=nper, regularisation="line")  # the FRF method's
        self.f, self.fs, self.H = h1.f, idres.fs, h1.frf  # (F, n_out, n_in)

    def drive(self, response) -> np.ndarray:
        from vrig.spectra import frf_filter

        return frf_filter(self.H, self.f, self.fs, response.data)

    def describe(self) -> str:
        return f"forward H1 FRF with {self.f.size} lines"

    def model_size(self) -> int | None:
        """Real numbers in the FRF matrices; None before :meth:`identify`."""
        h = getattr(self, "H", None)
        return None if h is None else int(2 * np.asarray(h).size)


def _register_builtins() -> None:
    register_method("arx", _built("arx"), description="inverse ARX, QanTiM", linear=True)
    register_method(
        "narx",
        _built("narx", kind="full"),
        description="inverse NARX, every monomial (full)",
        quick=False,  # its free run diverges on most rigs at --quick settings; narx-ip is quick
        linear=False,
    )
    register_method(
        "narx-ip",
        _built("narx", kind="input-polynomial"),
        description="inverse NARX, input-polynomial terms (vrig's default)",
        linear=False,
    )
    register_method(
        "narx-sim",
        _built("narx", kind="full", focus="simulation", selection="simulation"),
        description="inverse NARX, terms chosen and refined by free-run error "
        "(SEMP, simulation focus)",
        linear=False,
    )
    register_method(
        "narx-search",
        _built("narx", search=True),
        description="inverse NARX searched by free-run validation (orders 1-8, degrees 1-2, "
        "both term kinds, least squares / simulation focus, all / FROLS / SEMP terms; 60 s "
        "budget; identification.NarxSearch)",
        quick=False,  # a minute per record
        linear=False,
    )
    register_method(
        "error-signal",
        _built("error-signal"),
        description="inverse ARX plus an input-polynomial NARX of its drive error (§5.5.4, "
        "Table 6.5)",
        quick=False,
        linear=False,
    )
    register_method(
        "split",
        _built("split"),
        description="split spectra at the rig's split (side-car, else the band rule), inverse "
        "ARX per band",
        linear=True,
    )
    register_method(
        "frf",
        _built("frf"),
        description="H1 FRF, regularised inverse (RPC)",
        forward=lambda: ForwardFrf(),
        linear=True,
    )
    _register_updates()


def _register_updates() -> None:
    """The model-updating iterations (``vrig.IterationSettings.update``) as method rows: not in
    ``--quick`` (each adds a full reconstruction per rig; the rows compare iteration schemes);
    their methods built by the one method vocabulary, as the built-ins."""
    for name, update, text in (
        ("arx-frf-update", "frf", "H1 FRF updated from every iteration record (TWR-style)"),
        ("arx-secant", "secant", "per-band Broyden (secant) update of the correction"),
        ("arx-ilc", "ilc", "norm-optimal ILC with the identified H1 FRF"),
    ):
        register_method(name, _built("arx"), description=f"inverse ARX, {text}",
                        quick=False, linear=True, update=update)  # fmt: skip
    register_method(
        "narx-reidentify",
        _built("narx", kind="input-polynomial"),
        description="inverse NARX, input-polynomial, refitted on identification + "
        "iteration records before every correction",
        quick=False,
        linear=False,
        update="reidentify",
    )


_register_builtins()


# ---------------------------------------------------------------------------------------------
# plugin specs and loading
# ---------------------------------------------------------------------------------------------
PluginSpec = tuple[str, str, str]
"""``("module", module_name, "")`` or ``("source", file_name, source_text)``: picklable."""

_LOADED: set[PluginSpec] = set()


def plugin_spec(text: str) -> PluginSpec:
    """The spec of ``--plugin TEXT``: a ``.py`` file (its source is shipped) or a module name."""
    if text.endswith(".py") or Path(text).is_file():
        path = Path(text)
        if not path.is_file():
            raise FileNotFoundError(f"--plugin {text}: no such file")
        return ("source", str(path.resolve()), path.read_text())
    return ("module", text, "")


def default_plugin_specs() -> list[PluginSpec]:
    """Every module of the ``benchmarks.plugins`` package."""
    from .. import plugins

    return [
        ("module", f"{plugins.__name__}.{m.name}", "")
        for m in sorted(pkgutil.iter_modules(plugins.__path__), key=lambda m: m.name)
        if not m.name.startswith("_")
    ]


class PluginError(RuntimeError):
    """A plugin could not be loaded (its module is missing or its code raised)."""


def _load(kind: str, name: str, source: str) -> None:
    if kind == "module":
        importlib.import_module(name)
    elif kind == "source":
        mod_name = "_vrig_bench_plugin_" + hashlib.sha1(source.encode()).hexdigest()[:12]
        module = types.ModuleType(mod_name)
        module.__file__ = name
        sys.modules[mod_name] = module
        try:
            exec(compile(source, name, "exec"), module.__dict__)
        except BaseException:
            sys.modules.pop(mod_name, None)
            raise
    else:
        raise ValueError(f"unknown plugin spec kind {kind!r}")


def load_plugins(specs) -> list[str]:
    """Load plugin specs (once per process); returns the names of the methods they registered.

    Raises :class:`PluginError` (naming the plugin) when one cannot be imported or raises."""
    new = []
    for spec in specs:
        spec = tuple(spec)
        if spec in _LOADED:
            continue
        kind, name, source = spec
        before = dict(_REGISTRY)
        _LOADING.append(name)
        try:
            _load(kind, name, source)
        except Exception as exc:  # the plugin's own code raised: name the plugin
            raise PluginError(f"plugin {name} failed to load: {type(exc).__name__}: {exc}") from exc
        finally:
            _LOADING.pop()
        _LOADED.add(spec)
        new += [n for n, p in _REGISTRY.items() if before.get(n) is not p]
    return new


# ---------------------------------------------------------------------------------------------
# model size
# ---------------------------------------------------------------------------------------------
def model_size(method) -> int | None:
    """Number of coefficients of a fitted method object (None if unknown).

    ``method.model_size()`` for a :class:`~vrig.reconstruction.protocol.SizedMethod` (every
    vrig method: inverse ARX/NARX: terms over all channels; split spectra: the sum of its
    bands; FRF: real numbers in the inverse FRF matrices); None for a method without one."""
    if not isinstance(method, SizedMethod):
        return None
    value = method.model_size()
    return None if value is None else int(value)
