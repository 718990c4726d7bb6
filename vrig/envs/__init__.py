"""Gymnasium environments for learned drive-iteration strategies (registered on ``import vrig``).

``vrig/DriveIteration-v2`` takes any rig: ``gymnasium.make("vrig/DriveIteration-v2", rig=...)``
(other ``make`` keywords as :class:`DriveIterationEnv`). Every shipped rig has an id of its own
from its side-car (``"reconstruction": {"gym": {"id": ..., "method": ..., "tolerance": ...}}``,
``models/README.md``; ``rig.defaults.gym_id``), with the rig fixed and, where the side-car names
one, the env's default ``method`` (the id's ``method`` keyword): :data:`ENV_IDS` lists them all.
Every id has ``max_episode_steps=10``: the ``TimeLimit`` wrapper owns the iteration budget (the
env itself never truncates; pass ``max_episode_steps`` to change it), and names
:class:`DriveIterationVectorEnv` as its ``vector_entry_point``: ``gymnasium.make_vec(id, n)``
plays the rig runs of the n sub-envs in one batch across threads (``vectorization_mode="sync"``
or ``"async"`` for gymnasium's own; the results are the same bit for bit). The ``-v0`` and
``-v1`` ids are not registered any more: ``gymnasium.make("vrig/Shaker-v0")`` raises gymnasium's
``DeprecatedEnv`` naming ``vrig/Shaker-v2``. ``gymnasium.make(id)`` gives
``TimeLimit<OrderEnforcing<ResetSafeEnvChecker<DriveIterationEnv>>>``: the entry point
:func:`~vrig.envs.checker.make_checked` applies gymnasium's passive checker in a form that
survives a reset that raises (:mod:`vrig.envs.checker`: the stock one is broken for good by a
failed first reset), and the spec has ``disable_env_checker=True`` so the stock one is not added.

**Rig defaults.** The env resolves its settings as every door does
(:func:`vrig.reconstruction.defaults.resolve`: what the caller passes, then the side-car's method
block, then its rig block, then the built-in defaults): the band, the method's options
(``order``, ``degree``, ``focus``, ``split_hz``) and its identification level (``id_rms``). A
method the side-car marks ``unsupported`` (the reference text reports it failing on the rig) runs
all the same, after a one-line :class:`~vrig.errors.UnsupportedMethodWarning` quoting why (a
benchmark lets a user see a method do badly). The gains are the actions: the
side-car gain enters only the tolerance rule below.

**Tolerance.** The env's default η0 tolerance [%, every channel] on a rig is its side-car's
``gym.tolerance`` (``rig.defaults.tolerance``; the side-car's ``gym.description`` keeps the
measured figure), else 2 %: reachable, but only after several iterations. The rule by which
each value is measured: the largest max-channel η0 at IT07 over the pseudo-field targets of
``reset(seed=0..2)`` of the full-fidelity env (20 s targets) at a fixed gain (0.8, or the rig
side-car's: ``gym.gain``, else the method's, else the rig's ``gain``: 0.3 on the two-channel
fuel tank, 0.5 for frf on the motorcycle and the seven-channel tank, 0.5 on the elastomeric
damper), rounded up to two significant figures, on the rig's default variant: the
calibrated ``thesis`` twin for the shock absorber, elastomeric damper, radiator, motorcycle and
two-channel fuel tank (issues 12 and 23; pass ``rig_options={"variant": "mild"}`` for the datasheet-typical set).
Where a side-car's value was set otherwise (the shaker's 0.5 %) or the rule
meets a trip or a stall, its description says so.

The ids (inputs x outputs; method, band [Hz] and rule gain; tolerance [%]; what the rule measured
and the known difficulty):

=========================== ====== ============================= ====== =========================
id                          size   method, band, gain            tol.   rule / difficulty
=========================== ====== ============================= ====== =========================
vrig/ShockAbsorber-v2       1 x 1  arx, 0-10, 0.8                6.1    6.01 % (thesis: damper law,
                                                                        controller noise; 1.61 %
                                                                        before issue 23)
vrig/ElastomericDamper-v2   1 x 1  arx, 0-25, 0.5                0.65   0.645 % (thesis with the
                                                                        Maxwell chain); at 0.8
                                                                        the force interlock trips
vrig/Shaker-v2              1 x 1  arx, 10-60, 0.8               0.5    0.20 % (set at 0.5)
vrig/Radiator-v2            1 x 2  arx, 2-30, 0.8                5.6    5.52 % (thesis with the
                                                                        controller noise; 1.68 %
                                                                        without it)
vrig/LightTruckFront-v2     6 x 10 arx, 0-25, 0.8                4.6    4.60 % (digressive
                                                                        damper; 4.04 % on mild)
vrig/MotorcycleRear-v2      1 x 2  frf, 0-30, 0.5                10     9.97 % (thesis: digressive
                                                                        damper + noise; 6.36 % on
                                                                        mild);
                                                                        arx diverges, narx stalls
vrig/PneumaticTrailer-v2    1 x 3  frf, 0-25, 0.8                38     37.8 %, slow (digressive
                                                                        shock; 6.73 % on mild);
                                                                        arx warns (Table 6.7),
                                                                        narx diverges
vrig/FuelTank2ch-v2         2 x 2  split 12 Hz, 0-40, 0.3        8.5    8.5 % (no trip); 0.8
                                                                        no longer trips
vrig/FuelTank7ch-v2         7 x 7  frf, 1-40, 0.5                14     stall level: every
                                                                        target trips at IT03
=========================== ====== ============================= ====== =========================

The hard ones, in detail:

* motorcycle-rear: one drive serves two responses (spindle acceleration, spring strain), so
  every time-domain correction is a least-squares compromise; ARX at gain 0.4 grows into the
  0.07 m drive limit by IT08-IT09 and NARX(2, 2, simulation focus) stalls at 11-17 % (fast env).
  The H1 (frf) inverse at its side-car gain 0.5 converges on all three targets (IT00 39 %,
  IT10 4.4-5.3 %), still falling slowly. These figures are the bilinear damper's (now the
  variant `mild`); on the default digressive damper (issue 23) frf at 0.5 bottoms out at
  6.3-7.4 % (IT05-IT06, IT00 51-54 %) and then grows slowly (IT10 7.1-8.5 %).
* pneumatic-trailer: with ARX (it warns: reference text Table 6.7) the iteration diverges in
  the body-bounce band (1-1.5 Hz, bounce at 1.35 Hz): below the bounce the 4200 kg chassis rides
  up and down with the pan, so pressure and strain (which follow the arm-to-chassis stroke) fall
  off as ω² and the axle accelerometer is high-passed at 1 Hz, and the linear time-domain
  inverse is ill-conditioned exactly where the pseudo-field content is. The H1 (frf) inverse of
  the same 0-25 Hz band converges at gain 0.8 (IT00 64-72 %, IT10 4.5-5.1 %); in the fast env
  NARX(3, 2, simulation focus) at 0.5 diverged into the pan limit on 2 of 3 targets,
  error-signal stalled at 16-31 % and split oscillated at 8-26 % (all on the bilinear shock, now
  the variant `mild`). On the default digressive shock (issue 23) frf at 0.8 converges far more
  slowly (IT00 80-93 %, IT07 23-38 %, IT10 9.4-20.7 %, no trip): the tolerance is that slow
  rule value.
* fuel-tank-2ch (thesis twin): the full-spectrum methods warn (reference text Table 3.4: they
  fail on the tank's resonances inside the band), so the id's method is split at 12 Hz, at gain
  0.3 (IT00 46-48 %, IT07 8.3-8.5 %, IT10 4.8-5.0 %, no trip). The gain was chosen on the
  issue-12 twin, which tripped an interlock at 0.8 (IT03-IT04, fore following error and force
  after 22 %) and at 0.5; the issue-23 twin (progressive buffers, no snubbers) runs 0.8 without a
  trip (IT07 0.9-1.0 %). The fast env converges at 0.8.
* fuel-tank-7ch: at full fidelity frf at the side-car gain 0.5 trips on every target at IT03
  (the LR_vertical drive: following error > 10 mm, or the 76.2 mm drive limit) after a
  max-channel η0 of 11-13 % at IT02 (IT00 19-20 %); at 0.3 the trip moves to IT04-IT05. The rule
  gives no value: 14 % is that stall level rounded up (every target reaches it before the
  trip). In the fast env frf at 0.5 reaches 3.0-6.5 % at IT07 without a trip; ARX at 0.8 stalls
  at 20-22 % and then grows (at full fidelity: best 30 % at IT02, a trip at IT06, seed 0).
"""

from __future__ import annotations

from gymnasium.envs.registration import register, registry

from ..errors import RigModelError
from ..rigs import list_rigs, rig_path
from ..rigs.spec import read_defaults
from .checker import ResetSafeEnvChecker, make_checked
from .drive_iteration import FALLBACK_TOLERANCE, ActionLayout, DriveIterationEnv
from .physics import IterationPhysics, clear_model_cache
from .task import IterationTask, band_edges, band_error_ratios, response_change_ratios
from .vector import DriveIterationVectorEnv

__all__ = [
    "ENV_IDS",
    "FALLBACK_TOLERANCE",
    "ActionLayout",
    "DriveIterationEnv",
    "DriveIterationVectorEnv",
    "IterationPhysics",
    "IterationTask",
    "ResetSafeEnvChecker",
    "band_edges",
    "band_error_ratios",
    "clear_model_cache",
    "make_checked",
    "response_change_ratios",
]

_ENTRY_POINT = "vrig.envs.checker:make_checked"
_VECTOR_ENTRY_POINT = "vrig.envs.vector:DriveIterationVectorEnv"
MAX_EPISODE_STEPS = 10
_GENERIC_ID = "vrig/DriveIteration-v2"


def _shipped_env_ids() -> dict:
    """The generic id, then each shipped rig's side-car gym id (``{"rig": name}``, plus
    ``"method"`` where the side-car's ``gym.method`` names one); an id named twice is a
    :class:`~vrig.errors.RigModelError` naming both side-cars."""
    ids, where = {_GENERIC_ID: {}}, {_GENERIC_ID: "vrig.envs"}
    for name in list_rigs():
        path = rig_path(name)
        defaults = read_defaults(path)
        gym_id = defaults.gym_id
        if gym_id is None:
            continue
        if gym_id in ids:
            raise RigModelError(f"{path}: gym id {gym_id!r} is already {where[gym_id]}'s")
        kwargs = {"rig": name}
        if defaults.gym_method is not None:
            kwargs["method"] = defaults.gym_method
        ids[gym_id], where[gym_id] = kwargs, str(path)
    return ids


ENV_IDS = _shipped_env_ids()
"""Registered ids and their fixed keyword arguments (read from the shipped side-cars)."""

for _id, _kwargs in ENV_IDS.items():
    if _id not in registry:
        register(
            id=_id,
            entry_point=_ENTRY_POINT,
            vector_entry_point=_VECTOR_ENTRY_POINT,
            max_episode_steps=MAX_EPISODE_STEPS,
            disable_env_checker=True,  # make_checked applies ResetSafeEnvChecker itself
            kwargs=dict(_kwargs),
        )
