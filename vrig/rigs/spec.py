"""Channel specifications and the rig side-car description (``<rig>.rig.json``).

The side-car file states what MuJoCo's MJCF cannot: which actuators are drives and which sensors
are responses, their units, full scales, transducer chains and interlock limits, the DAQ sample
rate, and the documented parameters a user may override (``load_rig(name, **overrides)``).
See ``models/README.md`` for the format.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..errors import RigLimitError, RigModelError
from .daq import AntiAliasFilter, Transducer
from .hydraulics import HydraulicActuator

__all__ = ["ChannelSpec", "Parameter", "RigDescription", "check_drive_limits", "read_description"]


@dataclass(frozen=True)
class ChannelSpec:
    """A drive or response channel: name, unit, full scale and what is behind it.

    Attributes
    ----------
    name, unit : str
    full_scale : float
        ± range of the channel in its unit (drives: the command range; responses: the
        transducer range — exceeding it trips the transducer-range interlock).
    kind : str
        Drives: ``"hydraulic"`` (servo-hydraulic actuator in displacement control) or
        ``"direct"`` (an actuator driven directly, e.g. a shaker amplifier voltage).
        Responses: the transducer kind (``accelerometer``, ``load_cell``, ``strain_gauge``,
        ``lvdt``, ...).
    description : str
    limits : dict
        The interlock limits of the channel (stroke, force, velocity, following error ...).
    """

    name: str
    unit: str
    full_scale: float
    kind: str
    description: str = ""
    limits: dict = field(default_factory=dict)

    def __str__(self) -> str:
        return f"{self.name} [{self.unit}] ±{self.full_scale:g} ({self.kind})"


@dataclass(frozen=True)
class Parameter:
    """A documented, overridable rig parameter."""

    name: str
    value: object
    unit: str
    description: str
    source: str
    apply: tuple


@dataclass(frozen=True)
class InputDef:
    spec: ChannelSpec
    actuator: str
    joint: str | None
    hydraulic: HydraulicActuator | None
    noise_rms: float  # valve-command noise (hydraulic) or drive noise in drive units (direct)


@dataclass(frozen=True)
class OutputDef:
    spec: ChannelSpec
    sensor: str
    component: int
    transducer: Transducer


@dataclass(frozen=True)
class RigDescription:
    """Everything in a side-car file, validated."""

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


def _need(d: dict, key: str, where: str):
    if key not in d:
        raise RigModelError(f"{where}: missing required key {key!r}")
    return d[key]


def read_description(path) -> RigDescription:
    """Read and validate a ``*.rig.json`` side-car file."""
    path = Path(path)
    try:
        raw = json.loads(path.read_text())
    except json.JSONDecodeError as exc:
        raise RigModelError(f"{path}: not valid JSON ({exc})") from exc
    where = str(path)
    mjcf = path.parent / _need(raw, "mjcf", where)
    if not mjcf.exists():
        raise RigModelError(f"{where}: MJCF file {mjcf} not found")
    fs = float(_need(raw, "fs", where))
    inputs = []
    for i, item in enumerate(_need(raw, "inputs", where)):
        w = f"{where} inputs[{i}]"
        kind = _need(item, "kind", w)
        if kind not in ("hydraulic", "direct"):
            raise RigModelError(f"{w}: kind must be 'hydraulic' or 'direct', got {kind!r}")
        hyd = None
        limits = {}
        if kind == "hydraulic":
            try:
                hyd = HydraulicActuator().replace(**item.get("hydraulic", {}))
            except ValueError as exc:
                raise RigModelError(f"{w}: {exc}") from None
            limits = {
                "stroke": hyd.stroke,
                "force": hyd.force_limit,
                "velocity": hyd.velocity_limit,
                "following_error": hyd.error_limit,
            }
        spec = ChannelSpec(
            name=_need(item, "name", w),
            unit=_need(item, "unit", w),
            full_scale=float(_need(item, "full_scale", w)),
            kind=kind,
            description=item.get("description", ""),
            limits=limits,
        )
        if hyd is not None and spec.full_scale > hyd.stroke:
            raise RigModelError(
                f"{w}: full scale {spec.full_scale} exceeds the stroke {hyd.stroke}"
            )
        inputs.append(
            InputDef(
                spec,
                _need(item, "actuator", w),
                item.get("joint"),
                hyd,
                float(item.get("noise_rms", 0.0)),
            )
        )
    outputs = []
    for i, item in enumerate(_need(raw, "outputs", where)):
        w = f"{where} outputs[{i}]"
        tr = item.get("transducer", {})
        try:
            transducer = Transducer(**tr)
        except TypeError as exc:
            raise RigModelError(f"{w}: bad transducer entry ({exc})") from None
        spec = ChannelSpec(
            name=_need(item, "name", w),
            unit=_need(item, "unit", w),
            full_scale=float(_need(item, "full_scale", w)),
            kind=transducer.kind,
            description=item.get("description", ""),
            limits={"range": float(item["full_scale"])},
        )
        outputs.append(
            OutputDef(spec, _need(item, "sensor", w), int(item.get("component", 0)), transducer)
        )
    names = [c.spec.name for c in inputs] + [c.spec.name for c in outputs]
    if len(set(names)) != len(names):
        raise RigModelError(f"{where}: channel names must be unique, got {names}")
    params = {}
    for name, p in raw.get("parameters", {}).items():
        w = f"{where} parameters.{name}"
        params[name] = Parameter(
            name=name,
            value=_need(p, "value", w),
            unit=p.get("unit", "-"),
            description=_need(p, "description", w),
            source=p.get("source", ""),
            apply=tuple(_need(p, "apply", w)),
        )
    aa = AntiAliasFilter(**raw.get("anti_alias", {}))
    fast_rate = raw.get("fast_physics_rate")
    if fast_rate is not None:
        ok = isinstance(fast_rate, (int, float)) and not isinstance(fast_rate, bool)
        if not ok or not np.isfinite(fast_rate) or fast_rate <= 0:
            raise RigModelError(
                f"{where}: fast_physics_rate must be a positive number of Hz (an integer "
                f"multiple of fs = {fs:g} Hz), got {fast_rate!r}"
            )
        fast_rate = float(fast_rate)
    band = tuple(float(b) for b in raw.get("bandwidth_hz", (0.0, fs / 4)))
    return RigDescription(
        name=_need(raw, "name", where),
        title=raw.get("title", ""),
        description=raw.get("description", ""),
        path=path,
        mjcf=mjcf,
        fs=fs,
        bandwidth=band,
        settle_time=float(raw.get("settle_time", 0.0)),
        anti_alias=aa,
        inputs=tuple(inputs),
        outputs=tuple(outputs),
        parameters=params,
        notes=tuple(raw.get("notes", ())),
        fast_physics_rate=fast_rate,
    )


def check_drive_limits(
    channels, drive, *, fs: float | None = None, what: str = "the drive"
) -> None:
    """Raise :class:`~vrig.errors.RigLimitError` if any drive channel exceeds its full scale.

    A drive beyond a channel's ± full scale (or not finite) is never sent: the error names the
    channel, the first offending sample (and its time when ``fs`` is given) and says the drive was not sent.
    """
    for j, c in enumerate(channels):
        over = ~(np.abs(drive[:, j]) <= c.full_scale)  # NaN counts as over: never sent either
        if over.any():
            i = int(np.argmax(over))
            when = f"sample {i}" + (f", t = {i / fs:.4f} s" if fs else "")
            fix = "scale it down" if np.isfinite(drive[i, j]) else "it is not finite"
            raise RigLimitError(
                "drive",
                c.name,
                float("nan"),
                drive[i, j],
                c.full_scale,
                c.unit,
                hint=f"({when}): {what} was not sent; {fix}.",
            )
