"""Gymnasium environments for learned drive-iteration strategies (registered on ``import vrig``).

================================  =====================================================
id                                rig (other ``make`` keywords as :class:`DriveIterationEnv`)
================================  =====================================================
``vrig/DriveIteration-v0``        any: ``gymnasium.make("vrig/DriveIteration-v0", rig=...)``
``vrig/ShockAbsorber-v0``         shock-absorber (SISO, 0-10 Hz, tolerance 1.7 %)
``vrig/ElastomericDamper-v0``     elastomeric-damper (SISO, 0-25 Hz, tolerance 0.91 %)
``vrig/Shaker-v0``                shaker (SISO, 10-60 Hz, tolerance 0.5 %)
``vrig/Radiator-v0``              radiator (1 drive, 2 accelerations, tolerance 3 %)
``vrig/LightTruckFront-v0``       light-truck-front (6 force drives, 10 responses, 0-25 Hz,
                                  tolerance 4.1 %)
================================  =====================================================

Every id has ``max_episode_steps=10`` (the env's default ``max_iterations``; pass both to change
the budget). The tolerances (:data:`DEFAULT_TOLERANCE`) follow one rule, stated there, on each
rig's default variant: the calibrated ``thesis`` twin for the shock absorber, elastomeric damper,
radiator and two-channel fuel tank (issue 12; pass ``rig_options={"variant": "mild"}`` for the
datasheet-typical set). Measured old (``mild``) -> new (``thesis``): shock absorber 0.5 -> 1.7 %
(one target of three ends at 1.1 % after 10 steps at gain 0.8), elastomeric damper 1.3 -> 0.91 %
(at its side-car gain 0.5: gain 0.8 trips the force interlock or stalls on ``thesis``). The
calibrated radiator's top tank stalls at 10-14 % at gain 0.8: its 3 % is out of reach of a fixed
gain there (a learned strategy has to find it, or pass ``tolerance=``).

No id of their own (``vrig/DriveIteration-v0`` accepts them with tuned options):

* motorcycle-rear and fuel-tank-7ch: with the default settings (ARX, gain 0.8) their iteration
  diverges or trips an interlock.
* fuel-tank-2ch: on its calibrated default (``thesis``) two pseudo-field targets of three
  converge at gain 0.8 (max-channel η0 44 % at IT00, 2.1-3.5 % after 10 steps) but the third
  trips the fore actuator's force interlock at IT08 (24.4 kN > 24 kN after stalling at 10-16 %),
  so the rule gives no tolerance every target reaches; on ``mild`` the iteration diverges.
* pneumatic-trailer: the default iteration (ARX, 0-25 Hz, gain 0.8) diverges. The error grows in
  the body-bounce band (1-1.5 Hz, bounce at 1.35 Hz): the IT00 drive already misses pressure and
  strain there by 160-170 % of the band's RMS, and every update adds to it. Below the bounce the
  4200 kg chassis rides up and down with the pan, so pressure and strain (which follow the
  arm-to-chassis stroke) fall off as ω² and the axle accelerometer is high-passed at 1 Hz: the
  linear inverse is ill-conditioned exactly where the pseudo-field content is. Neither an honest
  gain (0.4 diverges), a 1-25 Hz band, a coarser model rate (decimation 5) nor ARX order 8 fixes
  it; a 2-25 Hz band converges but stalls at 5 % and leaves out the bounce the test is about.
"""

from __future__ import annotations

from gymnasium.envs.registration import register, registry

from .drive_iteration import DEFAULT_TOLERANCE, ActionLayout, DriveIterationEnv
from .physics import IterationPhysics, clear_model_cache
from .task import IterationTask, band_edges, band_error_ratios

__all__ = [
    "DEFAULT_TOLERANCE",
    "ENV_IDS",
    "ActionLayout",
    "DriveIterationEnv",
    "IterationPhysics",
    "IterationTask",
    "band_edges",
    "band_error_ratios",
    "clear_model_cache",
]

_ENTRY_POINT = "vrig.envs.drive_iteration:DriveIterationEnv"
MAX_EPISODE_STEPS = 10

ENV_IDS = {
    "vrig/DriveIteration-v0": {},
    "vrig/ShockAbsorber-v0": {"rig": "shock-absorber"},
    "vrig/ElastomericDamper-v0": {"rig": "elastomeric-damper"},
    "vrig/Shaker-v0": {"rig": "shaker"},
    "vrig/Radiator-v0": {"rig": "radiator"},
    "vrig/LightTruckFront-v0": {"rig": "light-truck-front"},
}
"""Registered ids and their fixed keyword arguments."""

for _id, _kwargs in ENV_IDS.items():
    if _id not in registry:
        register(
            id=_id,
            entry_point=_ENTRY_POINT,
            max_episode_steps=MAX_EPISODE_STEPS,
            kwargs=dict(_kwargs),
        )
