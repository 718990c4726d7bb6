"""Service scenarios: how a rig's specimen is mounted in its vehicle (side-car ``"service"``).

A rig's side-car may declare one or more *service scenarios*: the specimen the rig tests (the
damper, the cab mount, the radiator, the fuel tank), taken from the rig's own MJCF, mounted in
its service environment instead of on the rig's actuators, and driven by road inputs at a speed.
The *field twin* built from it (:func:`vrig.service.field_twin`) records the rig's own response
channels (names, units, transducer models): its records are service loads, the desired
responses the reference text's NARX results came from (§6.1.1's slow ditch, §6.4.1's road
record) instead of the rig's own response to a Gaussian drive.

The side-car block (validated by ``models/rig.schema.json``)::

    "service": {
      "<scenario>": {
        "description": "what it is, and what differs from the rig",
        "road": {"class": "C", "speed_kmh": 40, "contact_length": 0.3,
                 "events": [{"kind": "slow-ditch", "at": 0.3}]},
        "settle_time": 5.0,
        "wheels": [{"drive": "<rig drive>", "name": "LF", "track": 0, "offset": 0.0,
                    "base_mass": 350.0,
                    "tyre": {"stiffness": 1.6e6},
                    "axle": {"mass": 400.0, "stiffness": 3e5, "damping": 1e4},
                    "source": "..."}],
        "loads": [{"drive": "<rig drive>", "name": "lateral", "mass": 900.0,
                   "stiffness": 5e5, "damping": 2e4, "source": "..."}],
        "reaction": {"tendon": "loadcell", "mass": 3000.0, "stiffness": 3e5,
                     "damping": 0.0, "source": "..."}
      }
    }

Each rig drive becomes either a *wheel path* (road -> tyre with lift-off -> [axle -> suspension]
-> the drive's piston body, which then stands for the vehicle point the specimen is fixed to) or
an *inertial load* (the piston body held by the vehicle's compliance and loaded by a manoeuvre's
acceleration); a drive named by neither is locked (its piston held where it settles). The
``reaction`` names the tendon that held the specimen to the rig's frame (its load cell): in
service it holds it to a sprung mass instead (the vehicle body or the cab corner), with an
optional spring (and damper) in parallel with the specimen between that mass and the drive's
piston body (the vehicle's own suspension spring beside a damper).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from ..errors import RigModelError

__all__ = [
    "DEFAULT_FIELD_RANGE",
    "InertialLoad",
    "Reaction",
    "RoadSetting",
    "Scenario",
    "WheelPath",
    "read_scenarios",
]

DEFAULT_FIELD_RANGE = 4.0
"""A field twin's transducer ranges as a multiple of the rig's (field transducers are sized for
the service peaks; the rig's own ranges are checked by :func:`vrig.desired.range_report.range_report`)."""


def _number(block: dict, key: str, where: str, *, default=None, positive=False) -> float:
    value = block.get(key, default)
    if value is None:
        raise RigModelError(f"{where}: {key!r} is required")
    ok = isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)
    if not ok or value < 0 or (positive and value == 0):
        need = "> 0" if positive else ">= 0"
        raise RigModelError(f"{where}: {key!r} must be a finite number {need}, got {value!r}")
    return float(value)


@dataclass(frozen=True)
class RoadSetting:
    """The road a scenario is driven on by default (``"road"``).

    Attributes
    ----------
    road_class : str
        ISO 8608 road class ``"A"`` .. ``"H"`` of the random profile.
    speed_kmh : float
        Vehicle speed [km/h].
    contact_length : float
        Tyre contact-patch length [m] of the enveloping filter (:func:`vrig.roads.road_input`).
    events : tuple of dict
        Discrete events ``{"kind": ..., "at": fraction of the record in (0, 1), ...dimensions}``
        (:data:`vrig.roads.EVENTS`).
    """

    road_class: str
    speed_kmh: float
    contact_length: float = 0.2
    events: tuple = ()


@dataclass(frozen=True)
class WheelPath:
    """A rig drive replaced by a road input through a tyre (``"wheels"`` item).

    Attributes
    ----------
    drive : str
        The rig's drive channel whose piston body becomes the vehicle point.
    name : str
        The field twin's input channel: the road displacement under this wheel [m].
    track : int
        Wheel track (profile column) of the road under the wheel.
    offset : float
        Longitudinal distance behind the front axle [m] (a rear axle meets the road later).
    base_mass : float
        Mass added to the piston body [kg] (the hub or the chassis share at that point).
    tyre : dict or None
        ``{"stiffness": N/m, "damping": N s/m}`` of a tyre that can lift off (its damping acts in
        the air too: keep it to the few per cent of critical a tyre has); ``None``: the road
        moves the piston body itself (the rig's platen is the road, e.g. the motorcycle's wheel
        pan).
    axle : dict or None
        ``{"mass": kg, "stiffness": N/m, "damping": N s/m}``: an unsprung axle between the tyre
        and the piston body, on the vehicle's suspension; ``None``: the tyre acts on the piston
        body directly (the piston body is the hub).
    """

    drive: str
    name: str
    track: int
    offset: float
    base_mass: float
    tyre: dict | None
    axle: dict | None = None


@dataclass(frozen=True)
class InertialLoad:
    """A rig drive replaced by a manoeuvre's inertial load (``"loads"`` item).

    Attributes
    ----------
    drive : str
        The rig's drive channel (a lateral or longitudinal actuator).
    name : str
        The field twin's input channel: the vehicle's acceleration along that drive [m/s^2].
    mass : float
        Mass whose inertia loads the piston body [kg] (the force is ``mass * a``).
    stiffness, damping : float
        The vehicle's compliance holding the piston body along that axis [N/m, N s/m].
    manoeuvre : tuple of dict
        Acceleration pulses of the default record: ``{"at": fraction of the record in (0, 1),
        "duration": s, "level": m/s^2}``, each with 0.5 s raised-cosine edges (a corner, a
        braking).
    """

    drive: str
    name: str
    mass: float
    stiffness: float
    damping: float
    manoeuvre: tuple = ()


@dataclass(frozen=True)
class Reaction:
    """The sprung mass the specimen reacts against in service (``"reaction"``).

    Attributes
    ----------
    tendon : str
        The rig's tendon that held the specimen to the frame (its load cell).
    mass : float
        The sprung mass [kg] (vehicle body corner, cab corner).
    stiffness, damping : float
        Spring and damper in parallel with the specimen, between the sprung mass and the piston
        body of the first wheel path [N/m, N s/m] (0: none).
    """

    tendon: str
    mass: float
    stiffness: float = 0.0
    damping: float = 0.0


@dataclass(frozen=True)
class Scenario:
    """A service scenario of a rig (one item of the side-car's ``"service"``).

    Attributes
    ----------
    name : str
        The scenario's name (``vrig.field_scenarios(rig)``).
    description : str
        What it is, and what differs from the rig (boundary conditions, degrees of freedom).
    road : RoadSetting
        The default road.
    wheels : tuple of WheelPath
        The drives replaced by road inputs through tyres.
    loads : tuple of InertialLoad
        The drives replaced by manoeuvre loads.
    reaction : Reaction or None
        The sprung mass the specimen reacts against; ``None``: as on the rig.
    settle_time : float
        Zero road played before every run [s] (the vehicle settles on its springs).
    field_range : float
        Transducer ranges as a multiple of the rig's (:data:`DEFAULT_FIELD_RANGE`).
    """

    name: str
    description: str
    road: RoadSetting
    wheels: tuple = ()
    loads: tuple = ()
    reaction: Reaction | None = None
    settle_time: float = 5.0
    field_range: float = DEFAULT_FIELD_RANGE

    @property
    def inputs(self) -> tuple[str, ...]:
        """The field twin's input channel names: wheels first, then inertial loads."""
        return tuple(w.name for w in self.wheels) + tuple(x.name for x in self.loads)


def _wheel(item: dict, where: str) -> WheelPath:
    tyre = item.get("tyre")
    if tyre is not None:
        tyre = {
            "stiffness": _number(tyre, "stiffness", f"{where}.tyre", positive=True),
            "damping": _number(tyre, "damping", f"{where}.tyre", default=0.0),
        }
    axle = item.get("axle")
    if axle is not None:
        w = f"{where}.axle"
        axle = {
            "mass": _number(axle, "mass", w, positive=True),
            "stiffness": _number(axle, "stiffness", w, positive=True),
            "damping": _number(axle, "damping", w, default=0.0),
        }
        if tyre is None:
            raise RigModelError(f"{where}: an axle needs a tyre under it")
    track = item.get("track", 0)
    if not isinstance(track, int) or isinstance(track, bool) or track < 0:
        raise RigModelError(f"{where}: 'track' must be a non-negative integer, got {track!r}")
    return WheelPath(
        drive=item["drive"],
        name=item.get("name", f"road_{item['drive']}"),
        track=track,
        offset=_number(item, "offset", where, default=0.0),
        base_mass=_number(item, "base_mass", where, default=0.0),
        tyre=tyre,
        axle=axle,
    )


def _load(item: dict, where: str) -> InertialLoad:
    return InertialLoad(
        drive=item["drive"],
        name=item.get("name", f"accel_{item['drive']}"),
        mass=_number(item, "mass", where, positive=True),
        stiffness=_number(item, "stiffness", where, positive=True),
        damping=_number(item, "damping", where, default=0.0),
        manoeuvre=tuple(
            {
                "at": _number(m, "at", f"{where}.manoeuvre[{i}]", positive=True),
                "duration": _number(m, "duration", f"{where}.manoeuvre[{i}]", positive=True),
                "level": float(m["level"]),
            }
            for i, m in enumerate(item.get("manoeuvre", ()))
        ),
    )


def _scenario(name: str, raw: dict, drives: tuple, where: str) -> Scenario:
    road = raw.get("road", {})
    wheels = tuple(_wheel(w, f"{where}.wheels[{i}]") for i, w in enumerate(raw.get("wheels", ())))
    loads = tuple(_load(x, f"{where}.loads[{i}]") for i, x in enumerate(raw.get("loads", ())))
    used = [w.drive for w in wheels] + [x.drive for x in loads]
    unknown = sorted(set(used) - set(drives))
    if unknown:
        raise RigModelError(f"{where}: unknown drive(s) {unknown}; the rig's drives: {list(drives)}")
    if len(set(used)) != len(used):
        raise RigModelError(f"{where}: a drive is named by more than one wheel or load")
    names = [w.name for w in wheels] + [x.name for x in loads]
    if len(set(names)) != len(names) or not names:
        raise RigModelError(f"{where}: needs at least one wheel or load, with unique names")
    reaction = raw.get("reaction")
    if reaction is not None:
        w = f"{where}.reaction"
        reaction = Reaction(
            tendon=reaction["tendon"],
            mass=_number(reaction, "mass", w, positive=True),
            stiffness=_number(reaction, "stiffness", w, default=0.0),
            damping=_number(reaction, "damping", w, default=0.0),
        )
        if not wheels and (reaction.stiffness or reaction.damping):
            raise RigModelError(f"{w}: a parallel spring needs a wheel path's piston body")
    setting = RoadSetting(
        road_class=str(road.get("class", "C")),
        speed_kmh=_number(road, "speed_kmh", f"{where}.road", default=40.0, positive=True),
        contact_length=_number(road, "contact_length", f"{where}.road", default=0.2),
        events=tuple(dict(e) for e in road.get("events", ())),
    )
    return Scenario(
        name=name,
        description=raw.get("description", ""),
        road=setting,
        wheels=wheels,
        loads=loads,
        reaction=reaction,
        settle_time=_number(raw, "settle_time", where, default=5.0),
        field_range=_number(raw, "field_range", where, default=DEFAULT_FIELD_RANGE, positive=True),
    )


def read_scenarios(raw: dict | None, drives, where: str = "side-car") -> dict:
    """The side-car's ``"service"`` block as scenario name -> :class:`Scenario`.

    Parameters
    ----------
    raw : dict or None
        The block (already validated against the side-car schema); ``None``: no scenario.
    drives : sequence of str
        The rig's drive channel names (every wheel and load must name one).
    where : str
        Where the block comes from, for error messages.

    Raises
    ------
    RigModelError
        A number out of range, an unknown drive, a drive used twice, a scenario without input.
    """
    return {
        name: _scenario(name, item, tuple(drives), f"{where}: service.{name}")
        for name, item in (raw or {}).items()
    }
