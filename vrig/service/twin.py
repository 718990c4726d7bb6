"""Field twins: a rig's specimen in service, driven by a road, recording the rig's channels.

:func:`field_twin` builds the twin of one service scenario (:mod:`vrig.service.scenario`) as a
:class:`~vrig.rigs.MujocoRig` whose drives are the road displacements under the wheels (and the
manoeuvre accelerations) and whose responses are the rig's own channels — the same sensors, the
same transducer models and DAQ — with ranges :attr:`Scenario.field_range` times the rig's.
:func:`field_record` drives it with a road (:mod:`vrig.roads`) and returns the FIELD record.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from ..errors import RigModelError
from ..rigs.spec import ChannelSpec, InputDef
from ..timehistory import TimeHistory
from .mount import mount
from .scenario import Scenario, read_scenarios

__all__ = ["field_record", "field_records", "field_scenarios", "field_twin", "scenario"]

_FADE_S = 1.0  # road fade-in and fade-out [s]
_EDGE_S = 0.5  # rise and fall of a manoeuvre pulse [s]
_MAX_SECONDS = 3600.0


def _rig(rig):
    from ..rigs import load_rig

    return load_rig(rig) if isinstance(rig, str) else rig


def _scenarios(rig) -> dict:
    desc = getattr(rig, "description", None)
    if desc is None or not hasattr(desc, "service"):
        return {}
    return read_scenarios(desc.service, [c.name for c in rig.inputs], str(desc.path))


def field_scenarios(rig) -> list[str]:
    """The service scenarios of ``rig`` (its side-car's ``"service"``), by name.

    Parameters
    ----------
    rig : str or MujocoRig
        A shipped rig's name or a loaded rig.

    Returns
    -------
    list of str
        Empty for a rig without a service scenario (e.g. a user's rig, or a rig whose specimen
        has no vehicle to go into).
    """
    return sorted(_scenarios(_rig(rig)))


def scenario(rig, name: str) -> Scenario:
    """The service scenario ``name`` of ``rig``.

    Parameters
    ----------
    rig : str or MujocoRig
        A shipped rig's name or a loaded rig.
    name : str
        The scenario (:func:`field_scenarios`).

    Raises
    ------
    ValueError
        No such scenario (the message lists the rig's).
    """
    rig = _rig(rig)
    found = _scenarios(rig)
    if name not in found:
        raise ValueError(
            f"rig {rig.name!r} has no service scenario {name!r}; its scenarios: "
            f"{sorted(found) or 'none'}"
        )
    return found[name]


def _road_input(name: str, unit: str, description: str) -> InputDef:
    spec = ChannelSpec(name=name, unit=unit, full_scale=1.0 if unit == "m" else 100.0,
                       kind="direct", description=description)  # fmt: skip
    return InputDef(spec, f"road_{name}" if unit == "m" else f"load_{name}", None, None, 0.0)


def _field_outputs(outputs, factor: float) -> tuple:
    out = []
    for o in outputs:
        full = o.spec.full_scale * factor
        spec = dataclasses.replace(o.spec, full_scale=full, limits={**o.spec.limits, "range": full})
        out.append(dataclasses.replace(o, spec=spec))
    return tuple(out)


def _field_description(desc, sc: Scenario):
    """The rig's description with the scenario's inputs, widened ranges and the rules that set
    the rig's drive channels (valve noise, servo gains: not in the vehicle) left out."""
    inputs = tuple(
        _road_input(w.name, "m", f"road displacement under wheel {w.name} (drive {w.drive})")
        for w in sc.wheels
    ) + tuple(
        _road_input(x.name, "m/s^2", f"vehicle acceleration loading drive {x.drive}")
        for x in sc.loads
    )
    parameters = {
        k: dataclasses.replace(p, apply=tuple(r for r in p.apply if "input" not in r))
        for k, p in desc.parameters.items()
    }
    return dataclasses.replace(
        desc,
        name=f"{desc.name}:field:{sc.name}",
        inputs=inputs,
        outputs=_field_outputs(desc.outputs, sc.field_range),
        parameters=parameters,
        settle_time=sc.settle_time,
        fast_physics_rate=None,
    )


def field_twin(rig, name: str, *, seed: int = 0):
    """The field twin of ``rig`` in service scenario ``name``.

    The twin is built from the rig as loaded (its variant, severity, parameter overrides and
    fidelity): the same specimen, mounted by :func:`vrig.service.mount.mount`.

    Parameters
    ----------
    rig : str or MujocoRig
        A shipped rig's name or a loaded rig.
    name : str
        The scenario (:func:`field_scenarios`).
    seed : int
        Noise seed of the twin (transducer noise).

    Returns
    -------
    MujocoRig
        Its ``inputs`` are the scenario's road displacements [m] and manoeuvre accelerations
        [m/s^2]; its ``outputs`` the rig's channels; ``run(road)`` gives a field record.
    """
    from ..rigs import MujocoRig

    rig = _rig(rig)
    sc = scenario(rig, name)
    desc = rig.description
    try:
        return MujocoRig(
            _field_description(desc, sc),
            seed=seed,
            fidelity=rig.fidelity,
            variant=rig.variant,
            severity=rig.severity,
            spec_edit=lambda spec: mount(spec, sc, desc.inputs),
            **rig.overrides,
        )
    except RigModelError as exc:
        raise RigModelError(f"field twin {rig.name}:{name}: {exc}") from exc


def _check_record(seconds, speed_kmh) -> None:
    ok = isinstance(seconds, (int, float, np.integer, np.floating)) and not isinstance(seconds, bool)
    if not ok or not 2 * _FADE_S < seconds <= _MAX_SECONDS:
        raise ValueError(
            f"seconds must be a number in ({2 * _FADE_S:g}, {_MAX_SECONDS:g}] s, got {seconds!r}"
        )
    ok = isinstance(speed_kmh, (int, float, np.integer, np.floating)) and not isinstance(
        speed_kmh, bool
    )
    if not ok or not (np.isfinite(speed_kmh) and speed_kmh > 0):
        raise ValueError(f"speed_kmh must be a finite number > 0 [km/h], got {speed_kmh!r}")


def _events(sc: Scenario, length: float, span: float) -> list:
    """The scenario's events placed on the profile: ``at`` is a fraction of the record's road
    length ``span`` [m] (after the lead-in of the rear axles)."""
    placed = []
    for e in sc.road.events:
        dims = {k: v for k, v in e.items() if k not in ("kind", "at")}
        at = float(e.get("at", 0.5))
        if not 0 < at < 1:
            raise RigModelError(f"scenario {sc.name!r}: event 'at' must be in (0, 1), got {at!r}")
        placed.append((e["kind"], (length - span) + at * span, dims))
    return placed


def _manoeuvre(pulses, n: int, fs: float) -> np.ndarray:
    """Acceleration pulses [m/s^2] (``at`` a fraction of the record, ``duration`` [s],
    ``level`` [m/s^2]) with :data:`_EDGE_S` raised-cosine edges; zero between them."""
    a = np.zeros(n)
    t = np.arange(n) / fs
    for p in pulses:
        t0 = p["at"] * n / fs
        t1 = t0 + p["duration"]
        rise = np.clip((t - t0) / _EDGE_S, 0, 1)
        fall = np.clip((t1 + _EDGE_S - t) / _EDGE_S, 0, 1)
        a += p["level"] * 0.5 * (1 - np.cos(np.pi * np.minimum(rise, fall)))
    return a


def road_drive(sc: Scenario, fs: float, seconds: float, *, speed_kmh, road_class, seed: int):
    """The field twin's drive for ``seconds``: the road under each wheel (ISO 8608 profile of
    ``road_class`` with the scenario's events, the tyre-enveloping filter), faded in and out
    over :data:`_FADE_S`, and the inertial loads' manoeuvre pulses.

    Parameters
    ----------
    sc : Scenario
        The scenario.
    fs : float
        Sample rate [Hz].
    seconds : float
        Record length [s].
    speed_kmh : float
        Vehicle speed [km/h].
    road_class : str
        ISO 8608 class.
    seed : int
        Seed of the profile (and of random events such as pave).

    Returns
    -------
    TimeHistory
    """
    from scipy.signal.windows import tukey

    from .. import roads

    n = round(seconds * fs)
    v = speed_kmh / 3.6
    span = seconds * v
    lead = max((w.offset for w in sc.wheels), default=0.0) + sc.road.contact_length
    length = span + lead + 1.0
    cols = []
    if sc.wheels:
        x, z = roads.iso8608_profile(road_class, length, seed=seed)
        z = roads.add_events(x, z, _events(sc, length - 1.0, span))
        wheels = {w.name: (w.track, w.offset) for w in sc.wheels}
        ri = roads.road_input((x, z), speed_kmh, fs, wheels=wheels,
                              contact_length=sc.road.contact_length)  # fmt: skip
        data = np.asarray(ri.data)
        start = data.shape[0] - n  # the last n samples: every wheel on the profile
        if start < 0:
            raise RigModelError(f"scenario {sc.name!r}: the road profile is too short")
        cols.append(data[start:] - data[start:].mean(axis=0))
    if sc.loads:
        cols.append(np.column_stack([_manoeuvre(x.manoeuvre, n, fs) for x in sc.loads]))
    drive = np.concatenate(cols, axis=1) * tukey(n, min(1.0, 2 * _FADE_S / seconds))[:, None]
    units = ["m"] * len(sc.wheels) + ["m/s^2"] * len(sc.loads)
    return TimeHistory(drive, fs, list(sc.inputs), units)


def field_record(
    rig, scenario_name: str, seconds: float, *, speed_kmh=None, road_class=None, seed: int = 0,
    with_road: bool = False,
):  # fmt: skip
    """A service record (FIELD) of ``rig``'s response channels in scenario ``scenario_name``.

    The scenario's field twin (:func:`field_twin`) is driven over a seeded ISO 8608 road of
    ``road_class`` with the scenario's events (:mod:`vrig.roads`) at ``speed_kmh``.

    Parameters
    ----------
    rig : str or MujocoRig
        A shipped rig's name or a loaded rig.
    scenario_name : str
        The service scenario (:func:`field_scenarios`).
    seconds : float
        Record length [s] (a 1 s fade-in and fade-out of the road included).
    speed_kmh : float, optional
        Vehicle speed [km/h]; default the scenario's.
    road_class : str, optional
        ISO 8608 road class ``"A"`` .. ``"H"``; default the scenario's.
    seed : int
        Seed of the road profile (the twin's noise runs with ``seed + 20_000``); the same seed
        gives the same record, bit for bit.
    with_road : bool
        Return the road drive too.

    Returns
    -------
    TimeHistory, or (TimeHistory, TimeHistory) with ``with_road``
        At the rig's fs, with the rig's response channel names and units (FIELD); with
        ``with_road``, ``(road, field)``: the twin's drive first.

    Raises
    ------
    ValueError
        Unknown scenario or road class, ``speed_kmh <= 0``, ``seconds`` out of range.
    """
    rig = _rig(rig)
    sc = scenario(rig, scenario_name)
    speed = sc.road.speed_kmh if speed_kmh is None else speed_kmh
    _check_record(seconds, speed)
    cls = sc.road.road_class if road_class is None else road_class
    drive = road_drive(sc, rig.fs, seconds, speed_kmh=speed, road_class=cls, seed=seed)
    twin = field_twin(rig, scenario_name, seed=seed)
    field = twin.run(drive, seed=seed + 20_000)
    field = TimeHistory(field.data, field.fs, field.names, field.units)
    return (drive, field) if with_road else field


def field_records(rig, scenario_name: str, seconds: float, seeds, *, threads: int | None = None,
                  twin=None, with_road: bool = False) -> list:  # fmt: skip
    """:func:`field_record` of many road seeds (the scenario's default speed and road class),
    the twin's runs in one batch (:meth:`vrig.rigs.MujocoRig.run_batch`, across threads).

    Result ``i`` is bit for bit ``field_record(rig, scenario_name, seconds, seed=seeds[i],
    with_road=with_road)``, or the exception it raises, in its slot. One twin plays every road:
    a twin's construction seed only seeds its generator of unseeded runs, and each record is
    played with its own run seed (``seed + 20_000``).

    Parameters
    ----------
    rig : str or MujocoRig
        A shipped rig's name or a loaded rig.
    scenario_name : str
        The service scenario (:func:`field_scenarios`).
    seconds : float
        Record length [s] (a 1 s fade-in and fade-out of the road included).
    seeds : sequence of int
        Seeds of the road profiles (each >= 0).
    threads : int, optional
        Worker threads of the batch (:meth:`vrig.rigs.MujocoRig.run_batch`).
    twin : MujocoRig, optional
        The scenario's field twin (:func:`field_twin` of ``rig`` and ``scenario_name``), when
        the caller keeps one; default: built here.
    with_road : bool
        Each result ``(road, field)`` instead of ``field``.

    Returns
    -------
    list
        Per seed: the field record (with ``with_road``: ``(road, field)``) or the exception.

    Raises
    ------
    ValueError
        Unknown scenario, ``seconds`` out of range, a seed that is not an integer >= 0.
    """
    rig = _rig(rig)
    sc = scenario(rig, scenario_name)
    _check_record(seconds, sc.road.speed_kmh)
    seeds = list(seeds)
    for s in seeds:
        if isinstance(s, bool) or not isinstance(s, (int, np.integer)) or s < 0:
            raise ValueError(f"each seed must be an integer >= 0, got {s!r}")
    roads: list = []
    for s in seeds:
        try:
            roads.append(road_drive(sc, rig.fs, seconds, speed_kmh=sc.road.speed_kmh,
                                    road_class=sc.road.road_class, seed=int(s)))  # fmt: skip
        except Exception as exc:  # this seed's own error, in its slot
            roads.append(exc)
    twin = field_twin(rig, scenario_name) if twin is None else twin
    played = [i for i, r in enumerate(roads) if not isinstance(r, BaseException)]
    runs = twin.run_batch([roads[i] for i in played], seeds=[int(seeds[i]) + 20_000 for i in played],
                          threads=threads, return_exceptions=True)  # fmt: skip
    out: list = list(roads)
    for i, field in zip(played, runs, strict=True):
        if not isinstance(field, BaseException):
            field = TimeHistory(field.data, field.fs, field.names, field.units)
            field = (roads[i], field) if with_road else field
        out[i] = field
    return out
