"""Service scenarios and field twins: the rigs' specimens in their vehicles, driven by roads.

* :mod:`vrig.service.scenario` -- the side-car's ``"service"`` block, read and checked;
* :mod:`vrig.service.mount` -- the MjSpec edits that mount the rig's specimen in service;
* :mod:`vrig.service.twin` -- the field twin and its records (:func:`field_record`).
"""

from __future__ import annotations

from .scenario import Scenario, read_scenarios
from .twin import field_record, field_records, field_scenarios, field_twin, road_drive, scenario

__all__ = [
    "Scenario",
    "field_record",
    "field_records",
    "field_scenarios",
    "field_twin",
    "read_scenarios",
    "road_drive",
    "scenario",
]
