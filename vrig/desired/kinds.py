"""Desired responses by kind: a target name (``"pseudo-field"``, ``"field:<scenario>"``) made into a
record.

A *pseudo-field* desired response is the rig's own response to a road-like drive
(:mod:`vrig.desired.pseudo_field`); a *service* (field) desired response is the record of the
rig's specimen in its vehicle driven over a road (:mod:`vrig.service`): the kind of target the
text's NARX results came from (§6.1.1's slow ditch, §6.4.1's road record) — non-Gaussian, with
content the rig's own drives may not reach. :func:`desired_response` makes either from a target
name; the CLI, the gymnasium environments and the benchmarks choose their targets through it.
"""

from __future__ import annotations

from functools import partial

import numpy as np

from .pseudo_field import _seed, pseudo_field, pseudo_fields

__all__ = [
    "TARGET_KINDS",
    "desired_response",
    "desired_responses",
    "parse_target",
]

TARGET_KINDS = ("pseudo-field", "field")
"""The generated target kinds: ``"pseudo-field"`` and ``"field:<scenario>"`` (``"field"`` alone:
the rig's first service scenario, :func:`vrig.service.field_scenarios`)."""


def parse_target(rig, target: str) -> tuple[str, str | None]:
    """The kind and scenario of a target name: ``("pseudo-field", None)`` or ``("field", name)``.

    Parameters
    ----------
    rig : Rig
        The rig (its service scenarios name the field targets).
    target : str
        ``"pseudo-field"``, ``"field:<scenario>"`` or ``"field"`` (the rig's first scenario).

    Raises
    ------
    ValueError
        Not a target name, a rig without service scenarios, an unknown scenario (the message
        lists the rig's).
    """
    from ..service import field_scenarios

    if not isinstance(target, str):
        raise TypeError(f"target must be a string, got {type(target).__name__}")
    kind, _, scenario = target.partition(":")
    if kind == "pseudo-field" and not scenario:
        return "pseudo-field", None
    if kind != "field":
        raise ValueError(
            f"unknown target {target!r}: 'pseudo-field', 'field' or 'field:<scenario>'"
        )
    names = field_scenarios(rig)
    if not names:
        raise ValueError(f"rig {rig.name!r} has no service scenario: its targets are pseudo-field")
    if not scenario:
        return "field", names[0]
    if scenario not in names:
        raise ValueError(
            f"rig {rig.name!r} has no service scenario {scenario!r}; its scenarios: {names}"
        )
    return "field", scenario


def desired_response(rig, target: str = "pseudo-field", seconds: float = 30.0, *, seed=0,
                     band=None) -> tuple:  # fmt: skip
    """A generated desired (field) record for ``rig``: pseudo-field or service.

    Parameters
    ----------
    rig : Rig
        The rig to reconstruct on.
    target : str
        ``"pseudo-field"`` (:func:`pseudo_field` over ``band``) or ``"field:<scenario>"`` (the
        scenario's field twin over its default road, :func:`vrig.service.field_record`).
    seconds : float
        Record length [s].
    seed : int
        Seed of the random drive (pseudo-field) or of the road (field).
    band : (float, float), optional
        Drive band of a pseudo-field record [Hz] (default :func:`vrig.reconstruction.defaults.default_band`).

    Returns
    -------
    (field, source, extra) : TimeHistory, str, dict
        The record at the rig's fs with its response channels, a one-line description of
        where it comes from, and the records that made it (``{"DESDRV": ...}`` for a
        pseudo-field record, ``{"FIELDDRV01": ...}`` for a service record: the road inputs of
        the field twin).
    """
    kind, scenario = parse_target(rig, target)
    if kind == "pseudo-field":
        from ..reconstruction.defaults import default_band

        band = default_band(rig) if band is None else tuple(band)
        desdrv, field = pseudo_field(rig, band, seconds, seed=seed)
        return _pseudo_field_made(rig, band, seconds, seed, desdrv, field)
    from ..progress import status
    from ..service import field_record

    status(f"desired response: {seconds:g} s service record {rig.name}:{scenario} ...")
    road, field = field_record(rig, scenario, seconds, seed=seed, with_road=True)
    return _service_made(rig, scenario, seconds, seed, road, field)


def desired_responses(rig, target: str, seconds: float, seeds, *, band=None,
                      threads: int | None = None, twin=None) -> list:  # fmt: skip
    """:func:`desired_response` of many seeds, their rig runs batched level by level
    (:func:`pseudo_fields`; a service target: :func:`vrig.service.field_records`).

    Result ``i`` is bit for bit ``desired_response(rig, target, seconds, seed=seeds[i],
    band=band)``, or the exception that call raises, in its slot.

    Parameters
    ----------
    rig : Rig
        The rig to reconstruct on.
    target : str
        As :func:`desired_response`'s (checked with :func:`parse_target`: a bad name raises).
    seconds : float
        Record length [s].
    seeds : sequence of int
        Seeds of the random drives (pseudo-field) or of the roads (field), each >= 0.
    band : (float, float), optional
        Drive band of a pseudo-field record [Hz] (default :func:`vrig.reconstruction.defaults.default_band`).
    threads : int, optional
        Worker threads of the batched rig runs (:meth:`vrig.rigs.MujocoRig.run_batch`).
    twin : MujocoRig, optional
        A service target's field twin already built (:func:`vrig.service.field_twin`; its
        construction is the costly part of a short record): default, built here.

    Returns
    -------
    list
        Per seed: ``(field, source, extra)`` as :func:`desired_response` returns it, or the
        exception it raises.
    """
    kind, scenario = parse_target(rig, target)
    seeds = [_seed(s) for s in seeds]
    if kind == "pseudo-field":
        from ..reconstruction.defaults import default_band

        band = default_band(rig) if band is None else tuple(band)
        made = pseudo_fields(rig, band, seconds, seeds, threads=threads)
        finish = partial(_pseudo_field_made, rig, band, seconds)
    else:
        from ..progress import status
        from ..service import field_records

        status(f"desired responses: {len(seeds)} x {seconds:g} s service records "
               f"{rig.name}:{scenario} (batched) ...")  # fmt: skip
        made = field_records(rig, scenario, seconds, seeds, threads=threads, twin=twin,
                             with_road=True)  # fmt: skip
        finish = partial(_service_made, rig, scenario, seconds)
    return [
        m if isinstance(m, BaseException) else finish(s, *m)
        for s, m in zip(seeds, made, strict=True)
    ]


def _pseudo_field_made(rig, band, seconds: float, seed: int, desdrv, field) -> tuple:
    """:func:`desired_response`'s ``(field, source, extra)`` of a pseudo-field record."""
    rms = np.sqrt(np.mean(desdrv.data**2, axis=0)) / [c.full_scale for c in rig.inputs]
    source = (
        f"pseudo-field response to a {seconds:g} s random drive (triangular PSD "
        f"{band[0]:g}-{band[1]:g} Hz, {100 * rms.max():.3g} % of full scale rms, seed {seed})"
    )
    return field, source, {"DESDRV": desdrv}


def _service_made(rig, scenario: str, seconds: float, seed: int, road, field) -> tuple:
    """:func:`desired_response`'s ``(field, source, extra)`` of a service record."""
    from ..service import scenario as get_scenario

    sc = get_scenario(rig, scenario)
    source = (
        f"service record '{scenario}' ({seconds:g} s): the specimen in its vehicle on an ISO "
        f"8608 class-{sc.road.road_class} road at {sc.road.speed_kmh:g} km/h"
        + (f" with {', '.join(e['kind'] for e in sc.road.events)}" if sc.road.events else "")
        + f", seed {seed}"
    )
    return field, source, {"FIELDDRV01": road}
