"""Mount a rig's specimen in its service environment: the MjSpec edits of a field twin.

:func:`mount` turns the rig's model (its parameters already applied) into the field twin's: the
servo-hydraulic actuators of the rig's drives are removed and each drive's piston body becomes
the vehicle point the specimen is fixed to, reached from the road through the wheel path, or
held by the vehicle's compliance and loaded by a manoeuvre (:mod:`vrig.service.scenario`). The
specimen itself — its bodies, joints, tendons, non-linear elements, sensors — is the rig's, never
a copy of its parameters.

Elements added (names are the scenario's channel names):

* ``road_<wheel>``: a body on a vertical slide whose position follows the road input through a
  stiff position servo (:data:`ROAD_MASS`, :data:`ROAD_HZ`: the road is a 1 t body tracking the
  profile with a 200 Hz critically damped loop, far above the tyre-enveloped road content); a
  wheel path without a tyre puts that servo and mass on the piston body itself (the rig's
  platen under the tyre is the road);
* ``tyre_<wheel>``: a fixed tendon (wheel minus road) that pushes only in compression — its
  spring acts below zero length and is slack above (``springlength = [0, 1e3]``): the wheel lifts
  off; its damping (a tendon's acts at every length) is kept to a tyre's few per cent of critical,
  so the pull it adds while the wheel is in the air stays small against the wheel load;
* ``axle_<wheel>`` and ``suspension_<wheel>``: an unsprung axle on the vehicle's suspension
  spring and damper, when the wheel path has one;
* ``load_<name>``: the manoeuvre's inertial force ``mass * a`` on the piston joint, held by a
  spring and damper to the ground (the vehicle's compliance along that axis);
* ``sprung`` and ``parallel_spring``: the sprung mass the specimen reacts against, and the spring
  and damper beside the specimen.

Everything starts unloaded: gravity sags the vehicle onto its springs during the scenario's
``settle_time`` (the tyre's static deflection, the suspension's and the specimen's), as the rig's
own pre-settling does, so no preload needs computing and the static operating point (e.g. a cab
mount carrying the cab's weight) is the physical one.
"""

from __future__ import annotations

import math

import mujoco

from ..errors import RigModelError

__all__ = ["ROAD_HZ", "ROAD_MASS", "mount"]

ROAD_MASS = 1000.0
"""Mass of each road body [kg] (its servo is tuned to it)."""

ROAD_HZ = 200.0
"""Natural frequency of the road bodies' position servo [Hz], critically damped."""

_SLIDE = mujoco.mjtJoint.mjJNT_SLIDE
_SPHERE = mujoco.mjtGeom.mjGEOM_SPHERE


def _mass_geom(body, name: str, mass: float) -> None:
    """Add ``mass`` [kg] to ``body`` as a collision-free sphere."""
    if mass > 0:
        body.add_geom(
            name=name, type=_SPHERE, size=[0.05, 0, 0], mass=mass, contype=0, conaffinity=0,
            rgba=[0.8, 0.5, 0.1, 1],
        )  # fmt: skip


def _slide_body(spec, name: str, mass: float, pos):
    body = spec.worldbody.add_body(name=name, pos=list(pos))
    body.add_joint(name=name, type=_SLIDE, axis=[0, 0, 1], limited=0)
    _mass_geom(body, f"{name}_mass", mass)
    return body


def _tendon(spec, name: str, joints, *, stiffness=0.0, damping=0.0, springlength=None):
    t = spec.add_tendon(name=name, limited=0)
    for joint, coef in joints:
        t.wrap_joint(joint, coef)
    t.stiffness = [stiffness, 0.0, 0.0]  # MuJoCo 4: polynomial coefficients (linear only here)
    t.damping = [damping, 0.0, 0.0]
    if springlength is not None:
        t.springlength = list(springlength)
    return t


def _piston(spec, drive) -> tuple:
    """The drive's piston joint and body, with the rig's actuators and seal losses removed."""
    joint = spec.joint(drive.joint or "")
    if joint is None:
        raise RigModelError(f"drive {drive.spec.name!r}: no piston joint {drive.joint!r}")
    for suffix in ("_cmd", "_noise", "_force"):
        act = spec.actuator(drive.actuator + suffix)
        if act is not None:
            spec.delete(act)
    joint.frictionloss = 0.0  # the actuator's seals and bearings are not in the vehicle
    joint.damping = [0.0] * len(joint.damping)
    joint.armature = 0.0
    return joint, joint.parent


def _road_servo(spec, name: str, joint: str) -> None:
    """The stiff position servo that makes ``joint`` (carrying :data:`ROAD_MASS`) follow the
    road input of wheel ``name``."""
    w = 2 * math.pi * ROAD_HZ
    act = spec.add_actuator(name=f"road_{name}", target=joint, trntype=mujoco.mjtTrn.mjTRN_JOINT)
    act.set_to_position(kp=ROAD_MASS * w * w, kv=2 * ROAD_MASS * w)


def _wheel_path(spec, wheel, drives: dict) -> str:
    """Road -> tyre -> [axle -> suspension] -> the drive's piston body; returns the piston joint."""
    joint, body = _piston(spec, drives[wheel.drive])
    if wheel.tyre is None:  # the piston body is the road (a platen under the tyre)
        _mass_geom(body, f"road_mass_{wheel.name}", ROAD_MASS + wheel.base_mass)
        _road_servo(spec, wheel.name, joint.name)
        return joint.name
    _mass_geom(body, f"base_mass_{wheel.name}", wheel.base_mass)
    below = [body.pos[0], body.pos[1], body.pos[2] - 0.5]
    road = f"road_{wheel.name}"
    _slide_body(spec, road, ROAD_MASS, below)
    _road_servo(spec, wheel.name, road)
    wheel_joint = joint.name
    if wheel.axle is not None:
        axle = f"axle_{wheel.name}"
        _slide_body(spec, axle, wheel.axle["mass"], [below[0], below[1], below[2] + 0.25])
        _tendon(spec, f"suspension_{wheel.name}", [(joint.name, 1.0), (axle, -1.0)],
                stiffness=wheel.axle["stiffness"], damping=wheel.axle["damping"])  # fmt: skip
        wheel_joint = axle
    _tendon(spec, f"tyre_{wheel.name}", [(wheel_joint, 1.0), (road, -1.0)],
            stiffness=wheel.tyre["stiffness"], damping=wheel.tyre["damping"],
            springlength=(0.0, 1e3))  # fmt: skip
    return joint.name


def _inertial_load(spec, load, drives: dict) -> None:
    """The piston held by the vehicle's compliance, loaded by ``mass * a`` (ctrl = a [m/s^2])."""
    joint, _ = _piston(spec, drives[load.drive])
    joint.stiffness = [load.stiffness] + [0.0] * (len(joint.stiffness) - 1)
    joint.damping = [load.damping] + [0.0] * (len(joint.damping) - 1)
    act = spec.add_actuator(
        name=f"load_{load.name}", target=joint.name, trntype=mujoco.mjtTrn.mjTRN_JOINT
    )
    act.gear = [load.mass, 0, 0, 0, 0, 0]


def _reaction(spec, reaction, piston_joint: str | None) -> None:
    tendon = spec.tendon(reaction.tendon)
    if tendon is None:
        raise RigModelError(f"reaction: the rig has no tendon {reaction.tendon!r}")
    _slide_body(spec, "sprung", reaction.mass, [0.0, 0.0, 1.0])
    tendon.wrap_joint("sprung", -1.0)  # the specimen now reacts against the sprung mass
    if reaction.stiffness or reaction.damping:
        _tendon(spec, "parallel_spring", [("sprung", 1.0), (piston_joint, -1.0)],
                stiffness=reaction.stiffness, damping=reaction.damping)  # fmt: skip


def _lock_others(spec, drives: dict, used: set) -> None:
    """A rig drive the scenario does not use: its actuators removed, its piston welded."""
    for name, drive in drives.items():
        if name not in used:
            joint, _ = _piston(spec, drive)
            spec.add_equality(
                type=mujoco.mjtEq.mjEQ_JOINT, name1=joint.name, objtype=mujoco.mjtObj.mjOBJ_JOINT
            )


def mount(spec: mujoco.MjSpec, scenario, drives) -> None:
    """Edit the rig's ``spec`` into the field twin of ``scenario`` (in place).

    Parameters
    ----------
    spec : mujoco.MjSpec
        The rig's model with its parameters applied (not yet compiled).
    scenario : Scenario
        The service scenario (:class:`vrig.service.scenario.Scenario`).
    drives : sequence of InputDef
        The rig's drive channels (their piston joints and actuator prefixes).

    Raises
    ------
    RigModelError
        A piston joint or reaction tendon the model does not have.
    """
    by_name = {d.spec.name: d for d in drives}
    pistons = [_wheel_path(spec, w, by_name) for w in scenario.wheels]
    for load in scenario.loads:
        _inertial_load(spec, load, by_name)
    _lock_others(spec, by_name, {w.drive for w in scenario.wheels} | {x.drive for x in scenario.loads})
    if scenario.reaction is not None:
        _reaction(spec, scenario.reaction, pistons[0] if pistons else None)
