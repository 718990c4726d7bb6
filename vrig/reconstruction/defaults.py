"""The reconstruction defaults, each written once, and the one resolver that applies them.

Every door into a reconstruction (``vrig reconstruct``, :func:`vrig.reconstruct` /
:class:`~vrig.reconstruction.DriveIteration`, the gymnasium environments, the benchmark runner and
the benchmarks) resolves its settings with :func:`resolve`, so the same rig, method, desired
response and seed give the same figure by any door.

Precedence, first wins, for each value:

1. **the caller** (a keyword of :func:`vrig.reconstruct`, a field of
   :class:`~vrig.reconstruction.IterationSettings`, a ``vrig reconstruct`` flag);
2. **the rig side-car's method block** ``reconstruction.methods.METHOD`` (:class:`~vrig.rigs.spec.
   MethodDefaults`: ``gain``, ``id_rms``, ``order``, ``degree``, ``focus``, ``split_hz``);
3. **the side-car's rig block** ``reconstruction`` (:class:`~vrig.rigs.spec.RigDefaults`: ``band``,
   ``gain``, ``id_rms``);
4. **the built-in default**: the simulation band is the rig's test band ``rig.bandwidth``; the gain
   :data:`DEFAULT_GAIN`; the identification level :data:`DEFAULT_ID_RMS_FRACTION` of each drive's
   full scale; the split frequency :func:`default_split_hz`'s band rule; a model option the method
   class's own signature default (``InverseArx(order=4)``, ``InverseNarx(order=4, degree=2,
   budget=60.0)``, ...: read from the class, never retyped); every other setting the field
   default of :class:`~vrig.reconstruction.IterationSettings` (iterations, strategy, taper, seeds,
   stopping rule, update).

:func:`resolve` returns the filled-in settings and, for each value, where it came from
(:attr:`ResolvedSettings.sources`): ``vrig reconstruct`` prints that table before the run, and the
result (``ReconstructionResult.setting_sources``) and its ``summary.json`` record it.
"""

from __future__ import annotations

import dataclasses
import inspect
from collections.abc import Mapping
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any

import numpy as np

__all__ = [
    "DEFAULT_GAIN",
    "DEFAULT_ID_RMS_FRACTION",
    "SOURCES",
    "ResolvedSettings",
    "default_band",
    "default_id_rms",
    "default_split_hz",
    "resolve",
    "resolved",
]

DEFAULT_GAIN = 0.8
"""The iteration gain where neither the caller nor the rig's side-car names one."""

DEFAULT_ID_RMS_FRACTION = 0.05
"""The identification drive's RMS as a fraction of each drive's full scale where neither the caller
nor the rig's side-car names one (halved while the rig trips on it,
:meth:`~vrig.reconstruction.DriveIteration.identify`)."""

CALLER = "caller"
METHOD_BLOCK = "side-car reconstruction.methods.{method}"
RIG_BLOCK = "side-car reconstruction"
BUILT_IN = "built-in"
SOURCES = (CALLER, METHOD_BLOCK, RIG_BLOCK, BUILT_IN)
"""Where a resolved value can come from (``{method}`` is the method's name), in precedence order;
the band's built-in default is recorded as ``"built-in (the rig's test band)"``, a method class's
signature default as ``"built-in (<Class> default)"``."""

_MODEL_OPTIONS = ("order", "degree", "focus", "split_hz")
"""The vocabulary options a side-car's method block can set (where the method takes them)."""


@dataclass(frozen=True)
class ResolvedSettings:
    """The settings of one reconstruction with every default applied (:func:`resolve`).

    Attributes
    ----------
    settings : IterationSettings
        Every value filled in: ``bandwidth``, ``gain``, ``id_rms`` (per drive channel, in the
        drives' units) and the method's vocabulary options in ``method_options``.
    sources : Mapping[str, str]
        For each resolved value, where it came from (:data:`SOURCES`): ``bandwidth``, ``gain``,
        ``id_rms``, ``method``, and each model option of the method (``order``, ``degree``,
        ``focus``, ``split_hz``, ``budget`` ... as the method takes them).
    method : object
        The (unfitted) method object.
    description : str
        One line saying what the method is (``"narx order 4 degree 2"``).
    warning : str or None
        The rig's side-car marks the method ``unsupported`` (the reference text reports it failing
        there): the one line that says so, quoting it. The method runs all the same.
    method_options : Mapping[str, Any]
        The method's model options as built (the given, the side-car's and the class defaults
        the method took), by name: what :attr:`sources` reports on.
    """

    settings: Any
    sources: Mapping[str, str]
    method: Any
    description: str
    warning: str | None = None
    method_options: Mapping[str, Any] = field(default_factory=dict)

    def __post_init__(self):
        object.__setattr__(self, "sources", MappingProxyType(dict(self.sources)))
        object.__setattr__(self, "method_options", MappingProxyType(dict(self.method_options)))

    def replace(self, **changes) -> ResolvedSettings:
        """A copy whose settings have ``changes`` applied (settings no default depends on, e.g.
        ``run_seed``: the sources stay as they are).

        Parameters
        ----------
        **changes
            New values of settings, by name.

        Returns
        -------
        ResolvedSettings
        """
        resolved = {"bandwidth", "gain", "id_rms", "method", "method_options"}
        if resolved & set(changes):
            raise ValueError(
                f"{sorted(resolved & set(changes))} are resolved values: resolve the settings again"
            )
        return dataclasses.replace(self, settings=self.settings.replace(**changes))

    def values(self) -> dict:
        """``{name: value}`` of every value in :attr:`sources` (JSON-ready: tuples as lists)."""
        s = self.settings
        out: dict = {}
        for name in self.sources:
            if name == "method":
                out[name] = self.description
            elif name in ("bandwidth", "gain", "id_rms"):
                out[name] = _plain(getattr(s, name))
            else:
                out[name] = _plain(self.method_options.get(name))
        return out

    def record(self) -> dict:
        """``{name: {"value": value, "source": source}}`` of every resolved value (JSON-ready):
        what a result and its ``summary.json`` keep."""
        return {k: {"value": v, "source": self.sources[k]} for k, v in self.values().items()}

    def lines(self) -> list[str]:
        """One line per resolved value: ``name value (source)``, for a run's header."""
        return [
            f"{name:<10} {_text(value)}  ({self.sources[name]})"
            for name, value in self.values().items()
        ]


def _plain(value):
    if isinstance(value, (tuple, list, np.ndarray)):
        return [_plain(v) for v in value]
    if isinstance(value, np.generic):
        return value.item()
    return value


def _text(value) -> str:
    if isinstance(value, list):
        return ", ".join(_text(v) for v in value)
    if isinstance(value, float):
        return f"{value:.6g}"
    return str(value)


def resolve(rig, settings=None, **options) -> ResolvedSettings:
    """The settings of a reconstruction on ``rig`` with every default applied (module docstring:
    the precedence), and where each value came from.

    Deterministic and idempotent: resolving :attr:`ResolvedSettings.settings` again gives the same
    settings (every value then counts as the caller's).

    Parameters
    ----------
    rig : Rig
        The rig; its side-car defaults (``rig.defaults``) where it has them.
    settings : IterationSettings, optional
        What the caller gives (default: nothing: every default).
    **options
        Settings by name on top of ``settings`` (:meth:`IterationSettings.build`).

    Returns
    -------
    ResolvedSettings

    Raises
    ------
    MethodOptionError
        A method option that does not apply to the method or lies outside its range.
    ValueError
        An unknown method, a band outside ``0 <= low < high <= fs/2``, ...
    """
    from .settings import IterationSettings
    from .vocabulary import BUILTIN_METHODS, method_spec, side_car_vocabulary

    s = IterationSettings.build(settings, **options)
    defaults = getattr(rig, "defaults", None)
    # the side-car block of a named method, or of a built-in method's object (by its ``name``:
    # its settings - gain, identification level - are the method's; its model options were
    # fixed when the object was built)
    name = s.method if isinstance(s.method, str) else getattr(s.method, "name", None)
    if name not in BUILTIN_METHODS and not isinstance(s.method, str):
        name = None
    block = defaults.method(name) if defaults is not None and name is not None else None
    method_source = METHOD_BLOCK.format(method=name)
    sources: dict[str, str] = {}
    changes: dict[str, Any] = {}

    if s.bandwidth is not None:
        band, sources["bandwidth"] = tuple(s.bandwidth), CALLER
    elif getattr(defaults, "band", None) is not None:
        band, sources["bandwidth"] = tuple(defaults.band), RIG_BLOCK
    else:
        band, sources["bandwidth"] = tuple(rig.bandwidth), BUILT_IN + " (the rig's test band)"
    changes["bandwidth"] = tuple(float(b) for b in band)

    gain, sources["gain"] = _first(
        (s.gain, CALLER),
        (getattr(block, "gain", None), method_source),
        (getattr(defaults, "gain", None), RIG_BLOCK),
        (DEFAULT_GAIN, BUILT_IN),
    )
    changes["gain"] = gain

    if s.id_rms is not None:
        sources["id_rms"] = CALLER
    else:
        fraction, sources["id_rms"] = _first(
            (getattr(block, "id_rms", None), method_source),
            (getattr(defaults, "id_rms", None), RIG_BLOCK),
            (DEFAULT_ID_RMS_FRACTION, BUILT_IN),
        )
        changes["id_rms"] = tuple(float(v) for v in default_id_rms(rig, fraction))

    given = dict(s.method_options)
    model: dict[str, Any] = {}
    if isinstance(s.method, str):
        side = side_car_vocabulary(name, rig)
        for key, value in side.items():
            if given.get(key) is None:
                model[key], sources[key] = value, method_source
        if name == "split" and given.get("split_hz") is None and "split_hz" not in model:
            model["split_hz"] = float(default_split_hz(changes["bandwidth"]))
            sources["split_hz"] = BUILT_IN + " (the band rule)"
        for key in (*_MODEL_OPTIONS, "budget"):
            if given.get(key) is not None:
                sources[key] = CALLER
    options_out = {**given, **model}
    spec = method_spec(s.method, rig=rig, band=changes["bandwidth"], **options_out)
    sources["method"] = CALLER if "method" in _given_fields(settings, options) else BUILT_IN
    for key, value in (_class_defaults(spec) if isinstance(s.method, str) else {}).items():
        sources.setdefault(key, BUILT_IN + f" ({type(spec.method).__name__} default)")
        options_out.setdefault(key, value)
    changes["method_options"] = {**given, **model}
    warning = _unsupported(name, rig, block)
    resolved = s.replace(**changes)
    order = ("method", "bandwidth", "gain", "id_rms", *_MODEL_OPTIONS, "budget")
    sources = {k: sources[k] for k in order if k in sources}
    shown = {k: options_out[k] for k in sources if k in options_out}
    return ResolvedSettings(resolved, sources, spec.method, spec.description, warning, shown)


def resolved(rig, settings=None, **options) -> ResolvedSettings:
    r"""``settings`` as :class:`ResolvedSettings`: as they are when resolved already (and no
    ``options`` are given), else :func:`resolve`\ d, with the one
    :class:`~vrig.errors.UnsupportedMethodWarning` of a method the side-car marks
    ``unsupported`` (the doors that take settings from a caller: :func:`vrig.reconstruct`,
    :class:`~vrig.reconstruction.DriveIteration`).

    Parameters
    ----------
    rig : Rig
        The rig.
    settings : IterationSettings or ResolvedSettings, optional
        What the caller gives.
    **options
        Settings by name on top of ``settings``.

    Returns
    -------
    ResolvedSettings
    """
    if isinstance(settings, ResolvedSettings) and not options:
        return settings
    out = resolve(rig, settings, **options)
    if out.warning:
        import warnings

        from ..errors import UnsupportedMethodWarning

        warnings.warn(out.warning, UnsupportedMethodWarning, stacklevel=3)
    return out


def _first(*candidates):
    """The first ``(value, source)`` whose value is not None."""
    return next((v, src) for v, src in candidates if v is not None)


def _given_fields(settings, options) -> set:
    given = set(options)
    if settings is not None:
        from .settings import IterationSettings

        base = IterationSettings()
        given |= {
            n for n in IterationSettings.field_names() if getattr(settings, n) != getattr(base, n)
        }
    return given


def _class_defaults(spec) -> dict:
    """The vocabulary options the built method took from its class's signature defaults."""
    method = spec.method
    params = inspect.signature(type(method).__init__).parameters
    out = {}
    for key in ("order", "degree", "focus", "budget"):
        if key in params and key not in spec.options and hasattr(method, key):
            if key == "budget" and not getattr(method, "search", False):
                continue
            out[key] = getattr(method, key)
    if "linear_order" in params and "linear_order" not in spec.options:
        out["order"] = method.linear_order
    return out


def _unsupported(name, rig, block) -> str | None:
    text = getattr(block, "unsupported", None)
    if not text:
        return None
    quoted = " ".join(str(text).split())
    return (
        f"method {name!r} on rig {getattr(rig, 'name', rig)!r}: the reference text reports it "
        f'failing here ("{quoted}"; the side-car\'s reconstruction.methods.{name}); running it '
        "anyway"
    )


def default_id_rms(rig, fraction: float | None = None) -> np.ndarray:
    """The identification drive RMS per drive channel [drive units]: ``fraction`` (default
    :data:`DEFAULT_ID_RMS_FRACTION`) of each drive's full scale.

    Parameters
    ----------
    rig : Rig
        The rig (its ``inputs``' full scales).
    fraction : float, optional
        Fraction of full scale.

    Returns
    -------
    ndarray (n_inputs,)
    """
    f = DEFAULT_ID_RMS_FRACTION if fraction is None else float(fraction)
    return np.array([f * c.full_scale for c in rig.inputs], dtype=float)


def default_band(rig) -> tuple[float, float]:
    """The simulation band reconstructions use on ``rig`` unless told otherwise [Hz].

    The rig's side-car band (``rig.defaults.band``, side-car ``"reconstruction": {"band": ...}``)
    where it differs from the test band (e.g. the shaker's 10-60 Hz: its README), else the test
    band ``rig.bandwidth`` (also for a rig without a side-car, e.g. a user's own :class:`vrig.rigs.Rig`).

    Parameters
    ----------
    rig : Rig
        Any rig with a ``bandwidth`` (low, high) [Hz]; a ``defaults.band`` [Hz] wins when given.
    """
    band = getattr(getattr(rig, "defaults", None), "band", None)
    return tuple(rig.bandwidth if band is None else band)


def default_split_hz(band: tuple[float, float], rig=None) -> float:
    """The split frequency [Hz] of method ``"split"`` when the caller gives none.

    The one rule of ``vrig reconstruct``, :func:`vrig.reconstruct` and the gym envs: the rig
    side-car's ``reconstruction.methods.split.split_hz`` when it names one (a frequency chosen
    below the rig's first resonance in the band, as the reference text's §3.2.1 splits the fuel
    tank's 0-40 Hz at 12 Hz from its identification FRF); else, from the band alone (a user's own
    rig, whose side-car has no ``"reconstruction"`` block), the band's geometric mean
    ``sqrt(low * high)``, or a quarter of its upper edge ``high / 4`` for a band from 0 Hz (no
    geometric mean: the two octaves below the upper edge go to the high band). Either way the
    split lies inside the band (``low < split < high``) for any band ``0 <= low < high``.

    Parameters
    ----------
    band : (float, float)
        The simulation band ``(low, high)`` [Hz] of the reconstruction.
    rig : Rig, optional
        The rig; its ``defaults.method("split").split_hz`` wins when set. None: the band rule.

    Returns
    -------
    float
        The split frequency [Hz].
    """
    defaults = getattr(rig, "defaults", None)
    split = None if defaults is None else defaults.method("split").split_hz
    if split is not None:
        return float(split)
    lo, hi = (float(b) for b in band)
    return float(np.sqrt(lo * hi)) if lo > 0 else hi / 4
