"""Channel specifications and the rig side-car description (``<rig>.rig.json``).

The side-car file states what MuJoCo's MJCF cannot: which actuators are drives and which sensors
are responses, their units, full scales, transducer chains and interlock limits, the DAQ sample
rate, and the documented parameters a user may override (``load_rig(name, **overrides)``).
See ``models/README.md`` for the format.
"""

from __future__ import annotations

import contextlib
import functools
import json
import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from types import MappingProxyType

import jsonschema

from ..errors import RigModelError, RigParameterError
from ._checks import check_number, describe_range
from .damper import Damper
from .daq import AntiAliasFilter, Transducer
from .gas_spring import AirSpring
from .hydraulics import HydraulicActuator
from .limits import check_drive_limits  # re-exported: its public path before rigs.limits
from .maxwell import MaxwellChain

__all__ = [
    "MILD",
    "SEVERITY_LAWS",
    "SEVERITY_RANGE",
    "ChannelSpec",
    "MethodDefaults",
    "Parameter",
    "RigDefaults",
    "RigDescription",
    "Severity",
    "Variant",
    "check_drive_limits",
    "check_outputs_for_rate",
    "check_severity",
    "read_defaults",
    "read_description",
    "rig_schema",
    "schema_path",
    "validate_description",
]


@dataclass(frozen=True)
class ChannelSpec:
    """A drive or response channel: name, unit, full scale and what is behind it.

    Attributes
    ----------
    name : str
        Channel name (unique within the rig), e.g. ``"damper_load"``.
    unit : str
        Engineering unit of the channel (``"m"``, ``"N"``, ``"m/s^2"``, ``"V"``, ...).
    full_scale : float
        ± range of the channel in its unit (drives: the command range; responses: the
        transducer range — exceeding it trips the transducer-range interlock).
    kind : str
        Drives: ``"hydraulic"`` (servo-hydraulic actuator in displacement control) or
        ``"direct"`` (an actuator driven directly, e.g. a shaker amplifier voltage).
        Responses: the transducer kind (``accelerometer``, ``load_cell``, ``strain_gauge``,
        ``lvdt``, ...).
    description : str
        What the channel is, in words (side-car ``"description"``; may be empty).
    limits : dict
        The interlock limits of the channel (stroke, force, velocity, following error ...).
    """

    name: str
    unit: str
    full_scale: float
    kind: str
    description: str = ""
    limits: dict = field(default_factory=dict)

    def __post_init__(self):
        if not (isinstance(self.name, str) and self.name):
            raise RigParameterError(
                f"channel name must be a non-empty string, got {self.name!r}", "name", self.name
            )
        check_number(f"{self.name}: full_scale", self.full_scale, exclusive_minimum=0)

    def __str__(self) -> str:
        return f"{self.name} [{self.unit}] ±{self.full_scale:g} ({self.kind})"


@dataclass(frozen=True)
class Parameter:
    """A documented, overridable rig parameter.

    A numeric parameter's allowed range is given by ``minimum``, ``exclusive_minimum``,
    ``maximum``, ``exclusive_maximum`` (the side-car's ``minimum``, ``exclusiveMinimum``, ...;
    none: any finite number); a string parameter's values by ``enum``.

    Attributes
    ----------
    name : str
        The parameter's key in the side-car's ``"parameters"`` (the ``load_rig`` keyword).
    value : float or str
        The documented default value (the ``"mild"`` variant's), in ``unit``.
    unit : str
        Unit of the value (``"-"``: dimensionless or a string).
    description : str
        What the parameter is, in words.
    source : str
        Where the value comes from (datasheet, reference-text section, calibration).
    apply : tuple of dict
        The side-car's ``apply`` rules: which MjSpec attribute, channel or air-spring field
        the value sets (``models/README.md``, *Parameters*).
    minimum, exclusive_minimum, maximum, exclusive_maximum : float or None
        The allowed range of a numeric value, in ``unit`` (the side-car's ``minimum``,
        ``exclusiveMinimum``, ``maximum``, ``exclusiveMaximum``); ``None``: unbounded.
    enum : tuple of str or None
        The allowed values of a string parameter; ``None``: any string.
    """

    name: str
    value: object
    unit: str
    description: str
    source: str
    apply: tuple
    minimum: float | None = None
    exclusive_minimum: float | None = None
    maximum: float | None = None
    exclusive_maximum: float | None = None
    enum: tuple | None = None

    @property
    def allowed(self) -> str:
        """The allowed values in words."""
        if isinstance(self.value, str):
            if self.enum is None:
                return "a string"
            return "one of " + ", ".join(repr(v) for v in self.enum)
        return describe_range(
            minimum=self.minimum,
            exclusive_minimum=self.exclusive_minimum,
            maximum=self.maximum,
            exclusive_maximum=self.exclusive_maximum,
        ) + (f" [{self.unit}]" if self.unit and self.unit != "-" else "")

    def check(self, value):
        """``value`` if it is allowed for this parameter, else :class:`RigParameterError`
        naming the parameter and its allowed range (the type follows the default's).

        Parameters
        ----------
        value : float or str
            A candidate value, in :attr:`unit`: a finite number within the range for a numeric
            parameter, a string (in :attr:`enum` when given) for a string one.
        """
        if isinstance(self.value, str):
            ok = isinstance(value, str) and (self.enum is None or value in self.enum)
        else:
            try:
                check_number(
                    self.name,
                    value,
                    minimum=self.minimum,
                    exclusive_minimum=self.exclusive_minimum,
                    maximum=self.maximum,
                    exclusive_maximum=self.exclusive_maximum,
                )
                ok = True
            except RigParameterError:
                ok = False
        if not ok:
            raise RigParameterError(
                f"parameter {self.name!r} must be {self.allowed}, got {value!r}",
                key=self.name,
                value=value,
                allowed=self.allowed,
            )
        return value


@dataclass(frozen=True)
class InputDef:
    """A drive channel of the side-car (``"inputs"``), read: what MujocoRig needs to drive it.

    Attributes
    ----------
    spec : ChannelSpec
        The channel (name, unit, full scale, ``kind`` ``"hydraulic"`` or ``"direct"``, and the
        interlock limits of a hydraulic drive).
    actuator : str
        MJCF actuator name: of a direct drive, the actuator whose ``ctrl`` is the drive; of a
        hydraulic one, the prefix of its ``<actuator>_cmd``, ``_noise`` and ``_force`` actuators.
    joint : str or None
        The piston's slide joint of a hydraulic drive; ``None`` for a direct one.
    hydraulic : HydraulicActuator or None
        The servo-hydraulic actuator (the defaults with the side-car's ``"hydraulic"`` fields
        applied); ``None`` for a direct drive.
    noise_rms : float
        Command noise RMS, >= 0: of the servo-valve (fraction of full opening) on a hydraulic
        drive, of the amplifier (in the drive's unit) on a direct one.
    control_noise_rms : float
        Low-frequency noise of the controller's command and feedback path, >= 0, in the drive's
        unit: RMS of a 1/f (flicker) process over 0.1 Hz to the Nyquist frequency, added to the
        command, so the loop follows it and the piston moves by it inside the loop bandwidth —
        the rig's in-band run-to-run variation (reference text §3.1). 0 (default): none.
    control_noise_corner_hz : float
        Corner of that noise [Hz], > 0: its 1/f spectrum rolls off as a second-order low-pass
        above it (the controller electronics' flicker corner and the loop's bandwidth).
    """

    spec: ChannelSpec
    actuator: str
    joint: str | None
    hydraulic: HydraulicActuator | None
    noise_rms: float  # valve-command noise (hydraulic) or drive noise in drive units (direct)
    control_noise_rms: float = 0.0  # 1/f command/feedback-path noise [drive unit rms]
    control_noise_corner_hz: float = 30.0  # its second-order roll-off [Hz]

    def __post_init__(self):
        check_number(f"{self.spec.name}: noise_rms", self.noise_rms, minimum=0)
        check_number(f"{self.spec.name}: control_noise_rms", self.control_noise_rms, minimum=0)
        check_number(
            f"{self.spec.name}: control_noise_corner_hz",
            self.control_noise_corner_hz,
            exclusive_minimum=0,
        )


@dataclass(frozen=True)
class OutputDef:
    """A response channel of the side-car (``"outputs"``), read: where MujocoRig measures it.

    Attributes
    ----------
    spec : ChannelSpec
        The channel (name, unit, full scale = the transducer range, transducer kind).
    sensor : str
        The MJCF sensor name.
    component : int
        Index of the measured component within a multi-axis sensor (0 for a scalar sensor).
    transducer : Transducer
        The transducer chain (gain, noise, high-pass, mains pickup, ADC bits).
    """

    spec: ChannelSpec
    sensor: str
    component: int
    transducer: Transducer


@dataclass(frozen=True)
class MethodDefaults:
    """A rig's defaults for one reconstruction method (side-car
    ``"reconstruction": {"methods": {NAME: {...}}}``); ``None``: not set (the rig's or the
    global default applies).

    Attributes
    ----------
    description : str
        Why these values (what the global ones do on this rig), or what the reference text
        reports when the method is ``unsupported``.
    order, degree : int or None
        Model order and NARX degree (``vrig reconstruct``'s ``--order`` / ``--degree``).
    focus : str or None
        ``"prediction"`` or ``"simulation"``: the fit of a NARX inverse (``narx``,
        ``error-signal``; :class:`~vrig.reconstruction.InverseNarx`).
    split_hz : float or None
        Split frequency [Hz] of ``split`` (``--split-hz``).
    gain : float or None
        Iteration gain in (0, 2] for this method (wins over the rig's ``gain``).
    id_rms : float or None
        Identification drive RMS as a fraction of each drive's full scale, in (0, 0.5] (wins
        over the rig's ``id_rms``).
    unsupported : str or None
        The method fails on this rig by the reference text (the sentence that says so, citing
        where): a warning, not a refusal. ``vrig reconstruct`` and the gymnasium envs quote it
        in one warning line and run the method all the same, with its defaults (a benchmark
        lets a user see a method do badly; only the drive checks and the interlocks stop a
        run). The env's default method (``gym.method``) is never one marked so.
    """

    description: str = ""
    order: int | None = None
    degree: int | None = None
    focus: str | None = None
    split_hz: float | None = None
    gain: float | None = None
    id_rms: float | None = None
    unsupported: str | None = None


@dataclass(frozen=True)
class RigDefaults:
    """A rig's own defaults where they differ from the global ones (side-car
    ``"reconstruction"``; ``rig.defaults`` of a rig built from a side-car).

    They belong to the rig, not to a parameter set: ``variant``, ``severity`` and parameter
    overrides do not change them. ``None``: the side-car sets none (the global default applies).

    Attributes
    ----------
    band : (float, float) or None
        Simulation band (low, high) [Hz] of reconstructions, pseudo-field desired responses and
        the gymnasium envs where it differs from the test band ``bandwidth``
        (:func:`vrig.reconstruction.defaults.default_band`).
    gain : float or None
        Iteration gain in (0, 2] of ``vrig reconstruct`` (global default 0.8).
    gym_id : str or None
        The gymnasium id of the rig (``"vrig/Shaker-v2"``); a shipped rig's id is registered on
        ``import vrig`` (:data:`vrig.envs.ENV_IDS`).
    gym_method : str or None
        The env's default inverse-model method on this rig (side-car ``gym.method``; the id's
        ``method`` keyword, global default ``"arx"``), e.g. ``"split"`` where the full-spectrum
        methods are ``unsupported``.
    gym_gain : float or None
        The fixed gain in (0, 2] of the tolerance rule (:mod:`vrig.envs`) where it differs from
        the method's or the rig's ``gain`` (side-car ``gym.gain``): the fixed-gain baseline of
        the env on this rig. The env's gains are its actions; this sets none of them.
    tolerance : float or None
        Default η0 tolerance [%] of the drive-iteration env on this rig, measured by the rule
        stated in :mod:`vrig.envs` (global default 2 %).
    id_rms : float or None
        Identification drive RMS of ``vrig reconstruct`` as a fraction of each drive's full
        scale, in (0, 0.5] (global default 0.05).
    methods : mapping of str to MethodDefaults
        Per-method defaults of ``vrig reconstruct`` (:meth:`method`); empty when none is set.
    """

    band: tuple[float, float] | None = None
    gain: float | None = None
    gym_id: str | None = None
    gym_method: str | None = None
    gym_gain: float | None = None
    tolerance: float | None = None
    id_rms: float | None = None
    methods: Mapping[str, MethodDefaults] = field(default_factory=lambda: MappingProxyType({}))

    def method(self, name: str) -> MethodDefaults:
        """The defaults of method ``name`` (empty :class:`MethodDefaults` when none are set).

        Parameters
        ----------
        name : str
            A method name (``"arx"``, ``"narx"``, ``"split"``, ``"frf"``, ``"error-signal"``).

        Returns
        -------
        MethodDefaults
        """
        return self.methods.get(name, MethodDefaults())


@dataclass(frozen=True)
class RigDescription:
    """Everything in a side-car file, validated (:func:`read_description`).

    Attributes
    ----------
    name : str
        The rig's name (the side-car's ``"name"``; a shipped rig's folder name).
    title : str
        One-line title (may be empty).
    description : str
        What the rig is, in words (may be empty).
    path : Path
        The side-car file read.
    mjcf : Path
        The MJCF model file (the side-car's ``"mjcf"``, relative to its folder).
    fs : float
        DAQ sample rate [Hz]; the physics rate is an integer multiple of it.
    bandwidth : (float, float)
        The test band (low, high) [Hz], ``0 <= low < high <= fs/2`` (side-car
        ``"bandwidth_hz"``; default (0, fs/4)).
    settle_time : float
        Zero drive played before every run and discarded [s] (gravity sag, preload; default 0).
    anti_alias : AntiAliasFilter
        The DAQ's causal anti-alias filter.
    inputs : tuple of InputDef
        The drive channels, in drive-column order.
    outputs : tuple of OutputDef
        The response channels, in response-column order.
    parameters : dict
        Parameter name -> :class:`Parameter`: the documented, overridable parameters.
    notes : tuple of str
        Free-text notes of the side-car.
    fast_physics_rate : float or None
        Physics rate of ``fidelity="fast"`` [Hz]; ``None``: derived by MujocoRig from the
        model's stability limit.
    variants : dict
        Variant name -> :class:`Variant`; always holds :data:`MILD` (the documented values).
    default_variant : str
        The variant ``load_rig(name)`` gives (``variant=None``); :data:`MILD` unless the
        side-car names another.
    severity : Severity or None
        The non-linearity severity axis; ``None``: a rig linear in its operating range.
    air_springs : tuple of AirSpring
        The gas-spring elements (side-car ``"air_springs"``; :mod:`vrig.rigs.gas_spring`).
    dampers : tuple of Damper
        The hydraulic dampers (side-car ``"dampers"``; :mod:`vrig.rigs.damper`).
    maxwell : tuple of MaxwellChain
        The rate-dependent rubber chains (side-car ``"maxwell"``; :mod:`vrig.rigs.maxwell`).
    defaults : RigDefaults
        The rig's own defaults (side-car ``"reconstruction"``: band, gain, gym id, tolerance).
    service : dict
        The side-car's ``"service"`` block as validated by the schema: service scenarios by name
        (read by :mod:`vrig.service`; empty: the specimen has no field twin).
    repeatability : dict
        The side-car's ``"repeatability"`` block: the reference text's repeatability test of
        this rig (``table``, its simulation ``band`` [Hz], the ``numbers`` [%] per response
        channel); ``vrig repeatability`` runs in that band and prints them. Empty: none.
    """

    name: str
    title: str
    description: str
    path: Path
    mjcf: Path
    fs: float
    bandwidth: tuple[float, float]
    settle_time: float
    anti_alias: AntiAliasFilter
    inputs: tuple[InputDef, ...]
    outputs: tuple[OutputDef, ...]
    parameters: dict
    notes: tuple[str, ...] = ()
    fast_physics_rate: float | None = None  # Hz; None: derived (see MujocoRig)
    variants: dict = field(default_factory=dict)  # name -> Variant ("mild": the defaults)
    default_variant: str = "mild"  # the variant load_rig(name) gives (variant=None)
    severity: Severity | None = None  # the non-linearity severity axis; None: a linear rig
    air_springs: tuple = ()  # AirSpring elements (vrig.rigs.gas_spring), side-car "air_springs"
    dampers: tuple = ()  # Damper elements (vrig.rigs.damper), side-car "dampers"
    maxwell: tuple = ()  # MaxwellChain elements (vrig.rigs.maxwell), side-car "maxwell"
    defaults: RigDefaults = RigDefaults()  # side-car "reconstruction": band, gain, gym, tolerance
    service: dict = field(default_factory=dict)  # side-car "service": scenarios (vrig.service)
    repeatability: dict = field(default_factory=dict)  # side-car "repeatability": the text's test


MILD = "mild"
"""The implicit variant: the side-car's documented parameter values (``parameters.*.value``).
``variant=None`` gives the side-car's ``default_variant`` (``"mild"`` unless it names another)."""


@dataclass(frozen=True)
class Variant:
    """A named set of parameter values of a rig (side-car ``"variants"``), e.g. a calibration.

    ``values`` are checked against each parameter's declared range when the side-car is read.

    Attributes
    ----------
    name : str
        The variant's key in the side-car's ``"variants"`` (``load_rig(name, variant=...)``).
    description : str
        What was set or calibrated, on what, to which value.
    values : dict
        Parameter name -> value (in the parameter's unit); parameters not named keep their
        documented value.
    """

    name: str
    description: str
    values: dict


SEVERITY_RANGE = (0.0, 2.0)
"""The documented severity axis: 0 = the linearised rig, 1 = the rig as loaded, 2 = twice as
non-linear."""

SEVERITY_LAWS = {
    "proportional": "value x s (a play, a gap, a polynomial stiffness coefficient: 0 removes it)",
    "reciprocal": "value / s, and 0 at s = 0 (a slip displacement whose 0 means 'no slider': "
    "at s -> 0 the element never slips, i.e. it is the elastic spring it is at s = 0)",
    "linearised": "{'linearised': L}: L + s (value - L), kept at or above the parameter's minimum; "
    "L is a number, another parameter's name, or {'mean': [names]} (e.g. asymmetric damping "
    "about its mean; a contact that lifts off, bonded at s = 0)",
}
"""How a :class:`Severity` scales a parameter's value with the severity ``s``."""


@dataclass(frozen=True)
class Severity:
    """The non-linearity severity axis of a rig (side-car ``"severity"``).

    ``severity=s`` (``load_rig(name, severity=s)``, ``s`` in :data:`SEVERITY_RANGE`) scales the
    parameters named in ``scales`` — the rig's non-linear elements, after the variant and any
    explicit overrides are applied — by their law (:data:`SEVERITY_LAWS`): ``s = 0`` is the
    linearised rig (plays closed, polynomial stiffness linear, hysteresis elements stuck),
    ``s = 1`` the rig as loaded (the calibrated twin by default), ``s = 2`` twice as non-linear.
    Values at ``s > 1`` may leave a parameter's documented *plausible* range (the axis is a
    benchmark axis, not a physical rig); they never leave its physically valid range (a
    parameter's minimum).

    Attributes
    ----------
    description : str
        What severity 0, 1 and 2 mean on this rig.
    scales : dict
        Parameter name -> law: ``"proportional"``, ``"reciprocal"`` or ``{"linearised": L}``
        (:data:`SEVERITY_LAWS`).
    """

    description: str
    scales: dict  # parameter name -> law: "proportional", "reciprocal" or {"linearised": L}

    def linearised_value(self, law: dict, values: dict) -> float:
        """The value ``L`` of a ``{"linearised": L}`` law, resolved on ``values``.

        Parameters
        ----------
        law : dict
            ``{"linearised": L}``: ``L`` a number, another parameter's name, or ``{"mean":
            [names]}`` (the mean of those parameters' values).
        values : dict
            Parameter name -> value (unscaled) the names resolve on.

        Returns
        -------
        float
            ``L``, in the unit of the parameters it names.
        """
        target = law["linearised"]
        if isinstance(target, str):
            return float(values[target])
        if isinstance(target, dict):
            return float(sum(float(values[k]) for k in target["mean"]) / len(target["mean"]))
        return float(target)

    def apply(self, values: dict, s: float, parameters: dict | None = None) -> dict:
        """``values`` (parameter name -> value, the variant and overrides applied) with the
        scaled parameters at severity ``s``; every linearised reference is resolved on the
        unscaled ``values``. ``parameters`` (name -> :class:`Parameter`) supply the minima a
        linearised law keeps to.

        Parameters
        ----------
        values : dict
            Parameter name -> value, with the variant and the overrides applied; every
            parameter in :attr:`scales` must be present.
        s : float
            The severity (dimensionless, :data:`SEVERITY_RANGE`; not checked here).
        parameters : dict, optional
            Parameter name -> :class:`Parameter`; a linearised value is kept at or above its
            parameter's ``minimum``. ``None``: no minima.
        """
        out = dict(values)
        for name, law in self.scales.items():
            v = float(values[name])
            if law == "proportional":
                out[name] = v * s
            elif law == "reciprocal":
                out[name] = v / s if s > 0 else 0.0
            else:
                lin = self.linearised_value(law, values)
                new = lin + s * (v - lin)
                p = (parameters or {}).get(name)
                if p is not None and p.minimum is not None:
                    new = max(new, float(p.minimum))
                out[name] = new
        return out


def check_severity(value, rig: str) -> float:
    """``value`` as a float if it lies in :data:`SEVERITY_RANGE`, else RigParameterError.

    Parameters
    ----------
    value : float
        The severity asked for (dimensionless).
    rig : str
        The rig's name, for the error message.
    """
    lo, hi = SEVERITY_RANGE
    check_number(f"rig {rig!r}: severity", value, minimum=lo, maximum=hi)
    return float(value)


def schema_path() -> Path:
    """The published JSON Schema of the side-car: ``models/rig.schema.json`` of a source
    checkout, else the installed ``vrig.models/rig.schema.json``."""
    checkout = Path(__file__).resolve().parents[2] / "models" / "rig.schema.json"
    if checkout.exists():
        return checkout
    from importlib.resources import files

    return Path(str(files("vrig.models") / "rig.schema.json"))


@functools.cache
def rig_schema() -> dict:
    """The side-car's JSON Schema (draft 2020-12) as a dict."""
    return json.loads(schema_path().read_text())


def _json_path(parts) -> str:
    out = ""
    for p in parts:
        out += f"[{p}]" if isinstance(p, int) else (f".{p}" if out else str(p))
    return out or "(top level)"


def _non_finite(node, path=()):
    """Paths and values of every NaN or infinite number in a parsed JSON document."""
    if isinstance(node, float) and not math.isfinite(node):
        yield path, node
    elif isinstance(node, dict):
        for k, v in node.items():
            yield from _non_finite(v, (*path, k))
    elif isinstance(node, list):
        for i, v in enumerate(node):
            yield from _non_finite(v, (*path, i))


def _schema_allowed(error) -> str:
    """What the failing part of the schema allows, in words."""
    sub = error.schema if isinstance(error.schema, dict) else {}
    if error.validator == "additionalProperties":
        return "allowed keys: " + ", ".join(sorted(sub.get("properties", {})))
    if "enum" in sub:
        return "allowed: " + ", ".join(repr(v) for v in sub["enum"])
    if sub.get("type") in ("number", "integer"):
        return "allowed: " + describe_range(
            minimum=sub.get("minimum"),
            exclusive_minimum=sub.get("exclusiveMinimum"),
            maximum=sub.get("maximum"),
            exclusive_maximum=sub.get("exclusiveMaximum"),
            integer=sub["type"] == "integer",
            nonzero="not" in sub,
        )
    return sub.get("description", "")


def validate_description(raw, where: str = "side-car", *, schema: dict | None = None) -> None:
    """Check a parsed side-car against :func:`rig_schema` (and for NaN/infinite numbers, which
    JSON Schema cannot see); raises :class:`RigParameterError` naming the key and what is
    allowed (unknown keys such as a misspelt ``noise_rmss`` included). ``schema``: check
    against this (part of the) schema instead.

    Parameters
    ----------
    raw : object
        The parsed JSON document (``json.loads`` of the side-car).
    where : str
        Where it came from (the file's path), put in front of the error message.
    schema : dict, optional
        A JSON Schema (draft 2020-12) to check against instead of :func:`rig_schema`.
    """
    for path, value in _non_finite(raw):
        key = _json_path(path)
        raise RigParameterError(
            f"{where}: {key} is {value!r}: every number must be finite", key, value, "finite"
        )
    error = jsonschema.exceptions.best_match(
        jsonschema.Draft202012Validator(schema or rig_schema()).iter_errors(raw)
    )
    if error is not None:
        key = _json_path(error.absolute_path)
        allowed = _schema_allowed(error)
        raise RigParameterError(
            f"{where}: {key}: {error.message}" + (f" ({allowed})" if allowed else ""),
            key,
            error.instance,
            allowed,
        )


@contextlib.contextmanager
def _located(where: str):
    """Re-raise a value error of a dataclass check with the side-car location in front."""
    try:
        yield
    except RigParameterError as exc:
        raise RigParameterError(f"{where}: {exc}", exc.key, exc.value, exc.allowed) from None


def _read_input(item: dict, w: str) -> InputDef:
    kind = item["kind"]
    hyd, limits = None, {}
    with _located(w):
        if kind == "hydraulic":
            hyd = HydraulicActuator().replace(**item.get("hydraulic", {}))
            limits = {
                "stroke": hyd.stroke,
                "force": hyd.force_limit,
                "velocity": hyd.velocity_limit,
                "following_error": hyd.error_limit,
            }
        spec = ChannelSpec(
            name=item["name"],
            unit=item["unit"],
            full_scale=float(item["full_scale"]),
            kind=kind,
            description=item.get("description", ""),
            limits=limits,
        )
        if hyd is not None and spec.full_scale > hyd.stroke:
            raise RigParameterError(
                f"full_scale {spec.full_scale} exceeds the stroke {hyd.stroke}",
                "full_scale",
                spec.full_scale,
                f"a number in (0, {hyd.stroke:g}] (the stroke)",
            )
        return InputDef(
            spec,
            item["actuator"],
            item.get("joint"),
            hyd,
            item.get("noise_rms", 0.0),
            item.get("control_noise_rms", 0.0),
            item.get("control_noise_corner_hz", 30.0),
        )


def _read_output(item: dict, w: str) -> OutputDef:
    with _located(w):
        transducer = Transducer(**item.get("transducer", {}))
        spec = ChannelSpec(
            name=item["name"],
            unit=item["unit"],
            full_scale=float(item["full_scale"]),
            kind=transducer.kind,
            description=item.get("description", ""),
            limits={"range": float(item["full_scale"])},
        )
    return OutputDef(spec, item["sensor"], int(item.get("component", 0)), transducer)


def _read_air_springs(raw: list, w: str) -> tuple:
    """The side-car's ``"air_springs"`` as :class:`~vrig.rigs.gas_spring.AirSpring` elements
    (each number checked; names unique)."""
    out = []
    for i, item in enumerate(raw):
        with _located(f"{w} air_springs[{i}]"):
            fields_ = {k: v for k, v in item.items() if k != "description"}
            out.append(AirSpring(**fields_))
    names = [a.name for a in out]
    if len(set(names)) != len(names):
        raise RigModelError(f"{w}: air-spring names must be unique, got {names}")
    return tuple(out)


def _read_dampers(raw: list, w: str) -> tuple:
    """The side-car's ``"dampers"`` as :class:`~vrig.rigs.damper.Damper` elements (each number
    checked; names unique)."""
    out = []
    for i, item in enumerate(raw):
        with _located(f"{w} dampers[{i}]"):
            out.append(Damper(**{k: v for k, v in item.items() if k != "description"}))
    names = [d.name for d in out]
    if len(set(names)) != len(names):
        raise RigModelError(f"{w}: damper names must be unique, got {names}")
    return tuple(out)


def _read_maxwell(raw: list, w: str) -> tuple:
    """The side-car's ``"maxwell"`` chains as :class:`~vrig.rigs.maxwell.MaxwellChain`
    elements (each number checked; names unique; a clash of a branch's actuator name with the
    model's is refused when the rig realises it)."""
    out = []
    for i, item in enumerate(raw):
        with _located(f"{w} maxwell[{i}]"):
            out.append(MaxwellChain(**{k: v for k, v in item.items() if k != "description"}))
    names = [c.name for c in out]
    if len(set(names)) != len(names):
        raise RigModelError(f"{w}: maxwell chain names must be unique, got {names}")
    return tuple(out)


def _read_parameter(name: str, p: dict, w: str) -> Parameter:
    param = Parameter(
        name=name,
        value=p["value"],
        unit=p.get("unit", "-"),
        description=p["description"],
        source=p.get("source", ""),
        apply=tuple(p["apply"]),
        minimum=p.get("minimum"),
        exclusive_minimum=p.get("exclusiveMinimum"),
        maximum=p.get("maximum"),
        exclusive_maximum=p.get("exclusiveMaximum"),
        enum=tuple(p["enum"]) if "enum" in p else None,
    )
    with _located(w):
        param.check(param.value)  # the default must lie in the parameter's own range
    return param


def _read_variant(name: str, v: dict, params: dict, where: str) -> Variant:
    """A named variant; every value must name a documented parameter and lie in its range."""
    values = dict(v.get("parameters", {}))
    unknown = sorted(set(values) - set(params))
    if unknown:
        raise RigParameterError(
            f"{where}: unknown parameter(s) {unknown}; documented parameters: {sorted(params)}",
            key=f"variants.{name}.parameters.{unknown[0]}",
            value=values[unknown[0]],
            allowed=", ".join(sorted(params)),
        )
    for k, value in values.items():
        try:
            params[k].check(value)
        except RigParameterError as exc:
            raise RigParameterError(
                f"{where}: {exc}", f"variants.{name}.parameters.{k}", value, exc.allowed
            ) from None
    return Variant(name, v.get("description", ""), values)


def _read_severity(raw: dict | None, params: dict, where: str) -> Severity | None:
    """The side-car's severity axis; every scaled parameter must be a documented numeric one."""
    if raw is None:
        return None
    numeric = sorted(k for k, p in params.items() if not isinstance(p.value, str))
    for name, law in raw["scales"].items():
        named = [name]
        if isinstance(law, dict):
            target = law["linearised"]
            named += [target] if isinstance(target, str) else list(
                target["mean"] if isinstance(target, dict) else []
            )
        for k in named:
            if k not in numeric:
                raise RigParameterError(
                    f"{where}: severity.scales.{name} names {k!r}, which is not a documented "
                    f"numeric parameter; documented numeric parameters: {numeric}",
                    f"severity.scales.{name}",
                    law,
                    ", ".join(numeric),
                )
    return Severity(raw.get("description", ""), dict(raw["scales"]))


def check_outputs_for_rate(outputs, fs: float, where: str) -> None:
    """A transducer's high-pass corner must lie below the DAQ Nyquist frequency fs/2.

    Parameters
    ----------
    outputs : iterable of OutputDef
        The response channels to check (``transducer.highpass_hz`` [Hz] >= 0 and < fs/2).
    fs : float
        The DAQ sample rate [Hz].
    where : str
        Where the channels come from (a side-car path, a parameter rule), for the error.

    Raises
    ------
    RigParameterError
        A high-pass corner outside [0, fs/2).
    """
    for o in outputs:
        check_number(
            f"{o.spec.name}: transducer.highpass_hz",
            o.transducer.highpass_hz,
            where=where,
            minimum=0,
            exclusive_maximum=fs / 2,
        )


def _band(values, fs: float, where: str, key: str = "bandwidth_hz") -> tuple[float, float]:
    """``values`` as a band (low, high) [Hz] with 0 <= low < high <= fs/2, else
    :class:`RigParameterError` naming ``key``."""
    band = tuple(float(b) for b in values)
    if not 0 <= band[0] < band[1] <= fs / 2:
        allowed = f"[low, high] with 0 <= low < high <= fs/2 = {fs / 2:g} Hz"
        raise RigParameterError(
            f"{where}: {key} must be {allowed}, got {list(band)}", key, band, allowed
        )
    return band


def _read_defaults(raw: dict, fs: float, where: str) -> RigDefaults:
    """The side-car's ``"reconstruction"`` block (types and ranges: the schema) as
    :class:`RigDefaults`; the band is checked against ``fs``."""
    block = raw.get("reconstruction", {})
    gym = block.get("gym", {})
    band = block.get("band")
    methods = {}
    for name, m in block.get("methods", {}).items():
        methods[name] = MethodDefaults(
            description=m["description"],
            order=m.get("order"),
            degree=m.get("degree"),
            focus=m.get("focus"),
            split_hz=None if "split_hz" not in m else float(m["split_hz"]),
            gain=None if "gain" not in m else float(m["gain"]),
            id_rms=None if "id_rms" not in m else float(m["id_rms"]),
            unsupported=m.get("unsupported"),
        )
        split = methods[name].split_hz
        if split is not None and not 0 < split < fs / 2:
            allowed = f"0 < split_hz < fs/2 = {fs / 2:g} Hz"
            key = f"reconstruction.methods.{name}.split_hz"
            raise RigParameterError(
                f"{where}: {key} must be {allowed}, got {split:g}", key, split, allowed
            )
    gym_method = gym.get("method")
    if gym_method is not None and gym_method in methods and methods[gym_method].unsupported:
        key = "reconstruction.gym.method"
        raise RigParameterError(
            f"{where}: {key} {gym_method!r} is marked unsupported in reconstruction.methods",
            key,
            gym_method,
            "a method not marked unsupported",
        )
    return RigDefaults(
        band=None if band is None else _band(band, fs, where, "reconstruction.band"),
        gain=None if "gain" not in block else float(block["gain"]),
        gym_id=gym.get("id"),
        gym_method=gym_method,
        gym_gain=None if "gain" not in gym else float(gym["gain"]),
        tolerance=None if "tolerance" not in gym else float(gym["tolerance"]),
        id_rms=None if "id_rms" not in block else float(block["id_rms"]),
        methods=MappingProxyType(methods),
    )


def _read_json(path: Path) -> dict:
    try:
        return json.loads(path.read_text())
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise RigModelError(f"{path}: not valid JSON ({exc})") from exc


def read_defaults(path) -> RigDefaults:
    """Only the :class:`RigDefaults` of a ``*.rig.json`` side-car file, checked as
    :func:`read_description` checks them, without reading the rest (the gymnasium registration
    reads every shipped side-car on ``import vrig``).

    Parameters
    ----------
    path : str or Path
        The ``*.rig.json`` side-car file.

    Raises
    ------
    RigModelError
        Not JSON.
    RigParameterError
        (a RigModelError) ``fs`` or the ``"reconstruction"`` block is missing, of the wrong
        type, out of range or has an unknown key.
    """
    path = Path(path)
    raw = _read_json(path)
    full = rig_schema()
    part = {
        "type": "object",
        "required": ["fs"],
        "properties": {k: full["properties"][k] for k in ("fs", "reconstruction")},
    }
    if isinstance(raw, dict):  # (not an object: the schema says so)
        raw = {k: raw[k] for k in ("fs", "reconstruction") if k in raw}
    validate_description(raw, str(path), schema=part)
    return _read_defaults(raw, float(raw["fs"]), str(path))


def read_description(path) -> RigDescription:
    """Read and validate a ``*.rig.json`` side-car file.

    Parameters
    ----------
    path : str or Path
        The ``*.rig.json`` side-car file; its ``"mjcf"`` is relative to the file's folder.

    Raises
    ------
    RigModelError
        Not JSON, or the MJCF file is missing.
    RigParameterError
        (a RigModelError) a value of the wrong type, not finite, outside its allowed range
        (:func:`rig_schema` and the checks it names), or an unknown key.
    """
    path = Path(path)
    raw = _read_json(path)
    where = str(path)
    validate_description(raw, where)
    mjcf = path.parent / raw["mjcf"]
    if not mjcf.is_file():
        raise RigModelError(f"{where}: MJCF file {mjcf} not found")
    fs = float(raw["fs"])
    inputs = [_read_input(item, f"{where} inputs[{i}]") for i, item in enumerate(raw["inputs"])]
    outputs = [_read_output(it, f"{where} outputs[{i}]") for i, it in enumerate(raw["outputs"])]
    names = [c.spec.name for c in inputs] + [c.spec.name for c in outputs]
    if len(set(names)) != len(names):
        raise RigModelError(f"{where}: channel names must be unique, got {names}")
    check_outputs_for_rate(outputs, fs, where)
    params = {
        name: _read_parameter(name, p, f"{where} parameters.{name}")
        for name, p in raw.get("parameters", {}).items()
    }
    raw_variants = raw.get("variants", {})
    if MILD in raw_variants and raw_variants[MILD].get("parameters"):
        raise RigParameterError(
            f"{where}: variants.{MILD} is the side-car's default parameter values; it cannot "
            "change any (give the changed values another name)",
            f"variants.{MILD}",
            raw_variants[MILD],
            "no parameters",
        )
    variants = {MILD: Variant(MILD, "the documented default parameter values", {})}
    for vname, v in raw_variants.items():
        variants[vname] = _read_variant(
            vname, v, params, f"{where} variants.{vname}"
        ) if vname != MILD else Variant(MILD, v.get("description", variants[MILD].description), {})
    default_variant = raw.get("default_variant", MILD)
    if default_variant not in variants:
        raise RigParameterError(
            f"{where}: default_variant {default_variant!r} is not a variant; variants: "
            f"{sorted(variants)}",
            "default_variant",
            default_variant,
            ", ".join(sorted(variants)),
        )
    with _located(where):
        aa = AntiAliasFilter(**raw.get("anti_alias", {}))
    fast_rate = raw.get("fast_physics_rate")  # range: schema; on the fs grid: MujocoRig
    fast_rate = None if fast_rate is None else float(fast_rate)
    return RigDescription(
        name=raw["name"],
        title=raw.get("title", ""),
        description=raw.get("description", ""),
        path=path,
        mjcf=mjcf,
        fs=fs,
        bandwidth=_band(raw.get("bandwidth_hz", (0.0, fs / 4)), fs, where),
        settle_time=float(raw.get("settle_time", 0.0)),
        anti_alias=aa,
        inputs=tuple(inputs),
        outputs=tuple(outputs),
        parameters=params,
        notes=tuple(raw.get("notes", ())),
        fast_physics_rate=fast_rate,
        variants=variants,
        default_variant=default_variant,
        severity=_read_severity(raw.get("severity"), params, where),
        air_springs=_read_air_springs(raw.get("air_springs", []), where),
        dampers=_read_dampers(raw.get("dampers", []), where),
        maxwell=_read_maxwell(raw.get("maxwell", []), where),
        defaults=_read_defaults(raw, fs, where),
        service=dict(raw.get("service", {})),
        repeatability=_read_repeatability(raw.get("repeatability"), outputs, fs, where),
    )


def _read_repeatability(block, outputs, fs: float, where: str) -> dict:
    """The side-car's ``"repeatability"`` block (structure checked by the schema): its band
    inside (0, fs/2) and its channels among the rig's responses."""
    if not block:
        return {}
    lo, hi = (float(b) for b in block["band"])
    if not 0 <= lo < hi < fs / 2:
        raise RigModelError(f"{where}: repeatability band {lo:g}-{hi:g} Hz not inside 0-{fs / 2:g}")
    names = {o.spec.name for o in outputs}
    unknown = sorted(set(block["numbers"]) - names)
    if unknown:
        raise RigModelError(f"{where}: repeatability numbers for unknown responses {unknown}")
    return {"table": block["table"], "band": (lo, hi), "numbers": dict(block["numbers"])}

