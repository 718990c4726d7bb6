"""Hydraulic damper element: a force-velocity law with separate rebound and compression curves,
each a laminar bleed up to a knee velocity and a digressive (or progressive) blow-off beyond it,
realised **natively in MJCF** (exactly, at no cost per physics step).

The law
-------
Let ``u`` [m/s] be the damper's extension velocity (``u > 0``: rebound, the damper lengthens;
``u < 0``: compression). The damper force ``F(u)`` [N] (positive in rebound: a tension that
resists the extension) is, per stroke direction ``s`` (``r`` rebound, ``c`` compression),
with bleed coefficient ``c_s`` [N s/m], knee velocity ``v_s`` [m/s] and blow-off ratio
``β_s`` [-] (blow-off slope / bleed slope)::

    |F| = c_s |u|                              for |u| <= v_s   (bleed: laminar orifice flow)
    |F| = c_s v_s + β_s c_s (|u| - v_s)        for |u| >  v_s   (blow-off valves open)

continuous at the knee; ``β_s < 1`` is digressive (the usual valved damper), ``β_s = 1`` linear,
``β_s > 1`` progressive. The bleed coefficients are ``c_c`` = ``damping`` and
``c_r`` = ``rebound_ratio`` x ``damping`` (or ``rebound_damping`` when given). This is the piecewise-linear "bleed + blow-off"
characteristic of a valved telescopic damper (Dixon, *The Shock Absorber Handbook*, 2nd ed.,
Wiley 2007, ch. 5 (valve characteristics) and ch. 8 (the linear/bilinear/trilinear models):
the low-speed bleed region is laminar-viscous, the blow-off valve opens at a cracking pressure
and the force then grows much more slowly; rebound is typically 2-4 times compression at a
given speed, knees at 0.05-0.3 m/s). Seal friction is not part of the law: it stays the
joint's ``frictionloss``.

Realisation (why no callback)
-----------------------------
A ``general`` actuator with zero gain and an affine bias ``-c v`` on the damper's joint or
tendon is a dashpot; its ``forcerange`` clamps it. Per stroke direction two such actuators
compose the law exactly:

* the *slope* actuator: ``-β_s c_s v``, clamped to the stroke direction's sign
  (``[-1e6, 0]`` or ``[0, 1e6]`` N): the blow-off slope at every speed of that direction;
* the *bleed* actuator (only when ``β_s != 1``): ``-(1 - β_s) c_s v``, clamped to
  ``(1 - β_s) c_s v_s`` in that direction: the extra bleed force, saturated at the knee.

Their sum is the law above for every ``u`` (the clamps make each act in one direction only).
Actuator forces with a velocity bias enter MuJoCo's implicit integrators (``implicitfast``)
like joint damping, so the element is as stable as a dashpot of the bleed coefficient. A linear
symmetric law (``rebound_ratio = 1``, ``β = 1`` both ways) is realised as the joint's or
tendon's own ``damping`` instead (no actuator: the model is the hand-written one, bit for bit).
A smooth knee and series compliance (oil/gas compressibility, a hysteresis loop) cannot be
expressed this way (the first needs a curved clamp, the second an internal state); they are not
modelled: the knee is sharp, the law memoryless.

A rig declares its dampers in the side-car (``"dampers"``, ``models/README.md``); parameters
change a damper's fields by ``{"damper": NAME, "field": F}`` rules; :func:`realise` writes the
element into the :class:`mujoco.MjSpec` after the parameters are applied.
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np

from ._checks import check_number, replace_fields

__all__ = ["Damper", "realise"]

UNCLAMPED_N = 1e6
"""The open side of a one-directional actuator's force range [N] (never reached)."""


@dataclass(frozen=True)
class Damper:
    """One hydraulic damper (SI units; see the module for the law).

    Attributes
    ----------
    name : str
        The damper's name; its actuators are ``NAME_compression``, ``NAME_rebound`` (slopes)
        and ``NAME_compression_bleed``, ``NAME_rebound_bleed`` (bleed above the blow-off).
    joint : str or None
        The MJCF slide joint whose velocity is the damper's (exactly one of joint, tendon).
    tendon : str or None
        The MJCF tendon whose velocity is the damper's.
    extension : int
        +1 when a positive joint/tendon velocity lengthens the damper (rebound), -1 when it
        shortens it (e.g. a tendon that measures compression).
    damping : float
        Compression bleed coefficient ``c_c`` [N s/m] (>= 0).
    rebound_ratio : float
        ``c_r / c_c`` [-] (>= 0): rebound bleed over compression bleed.
    rebound_damping : float or None
        The rebound bleed ``c_r`` itself [N s/m] (>= 0); when given, ``rebound_ratio`` is
        not used (for rigs whose parameters set the two strokes' coefficients independently).
    blowoff_ratio_compression : float
        ``β_c`` [-] (>= 0): blow-off slope over bleed slope in compression (1: no knee).
    blowoff_ratio_rebound : float
        ``β_r`` [-] (>= 0): the same in rebound.
    knee_velocity_compression : float
        ``v_c`` [m/s] (> 0): compression speed at which the blow-off valve opens.
    knee_velocity_rebound : float
        ``v_r`` [m/s] (> 0): the same in rebound.
    realisation : str
        ``"auto"``: a linear law as the joint's/tendon's ``damping``, any other as actuators;
        ``"actuators"``: always the actuators (a rig whose MJCF had them, kept bit for bit at
        every parameter value).
    """

    name: str
    damping: float
    joint: str | None = None
    tendon: str | None = None
    extension: int = 1
    rebound_ratio: float = 1.0
    rebound_damping: float | None = None
    blowoff_ratio_compression: float = 1.0
    blowoff_ratio_rebound: float = 1.0
    knee_velocity_compression: float = 0.3
    knee_velocity_rebound: float = 0.3
    realisation: str = "auto"

    FIELDS = (
        "damping", "rebound_ratio", "rebound_damping", "blowoff_ratio_compression",
        "blowoff_ratio_rebound", "knee_velocity_compression", "knee_velocity_rebound",
    )  # fmt: skip
    """The numeric fields a side-car parameter may set (``{"damper": NAME, "field": F}``)."""

    def __post_init__(self):
        """Validate the element (a :class:`~vrig.errors.RigParameterError` names the field)."""
        for key in self.FIELDS:
            value = getattr(self, key)
            if value is not None:
                bound = "exclusive_minimum" if key.startswith("knee") else "minimum"
                check_number(f"damper {self.name!r}: {key}", value, **{bound: 0})
        if self.realisation not in ("auto", "actuators"):
            raise ValueError(
                f"damper {self.name!r}: realisation must be 'auto' or 'actuators', "
                f"got {self.realisation!r}"
            )
        if (self.joint is None) == (self.tendon is None):
            raise ValueError(
                f"damper {self.name!r}: give exactly one of joint and tendon, got "
                f"joint={self.joint!r}, tendon={self.tendon!r}"
            )
        if self.extension not in (1, -1) or isinstance(self.extension, bool):
            raise ValueError(
                f"damper {self.name!r}: extension must be 1 or -1, got {self.extension!r}"
            )

    def replace(self, **changes) -> Damper:
        """A copy with ``changes`` (unknown names refused, the values checked).

        Parameters
        ----------
        **changes
            New values of fields, by name (in the fields' SI units).
        """
        return replace_fields(self, changes, "damper field")

    @property
    def rebound_bleed(self) -> float:
        """``c_r`` [N s/m]: ``rebound_damping`` if given, else ``rebound_ratio`` x ``damping``."""
        if self.rebound_damping is not None:
            return float(self.rebound_damping)
        return self.rebound_ratio * self.damping

    @property
    def linear(self) -> bool:
        """Whether the law is one linear dashpot (symmetric, no knee)."""
        return (
            self.rebound_bleed == self.damping
            and self.blowoff_ratio_compression == 1.0
            and self.blowoff_ratio_rebound == 1.0
        )

    def sides(self) -> tuple:
        """Per stroke direction ``(label, sign of u, bleed c [N s/m], blow-off ratio, knee
        velocity [m/s])``: compression (sign -1) then rebound (+1)."""
        return (
            ("compression", -1, self.damping, self.blowoff_ratio_compression,
             self.knee_velocity_compression),
            ("rebound", 1, self.rebound_bleed, self.blowoff_ratio_rebound,
             self.knee_velocity_rebound),
        )  # fmt: skip

    def force_at(self, u):
        """Damper force ``F(u)`` [N], positive in rebound (a tension resisting extension).

        Parameters
        ----------
        u : float or ndarray
            Extension velocity in m/s (positive: rebound, negative: compression).
        """
        u = np.asarray(u, dtype=float)
        f = np.zeros_like(u)
        for _, sign, c, beta, knee in self.sides():
            speed = np.maximum(sign * u, 0.0)
            magnitude = c * np.minimum(speed, knee) + beta * c * np.maximum(speed - knee, 0.0)
            f = f + sign * magnitude
        return f

    def generalised_force_at(self, v):
        """The force on the joint or tendon coordinate [N] at its velocity ``v`` [m/s]:
        ``-extension * F(extension * v)`` (always opposing ``v``).

        Parameters
        ----------
        v : float or ndarray
            Velocity of the joint or tendon in m/s.
        """
        return -self.extension * self.force_at(self.extension * np.asarray(v, dtype=float))

    def actuators(self) -> list:
        """The MJCF actuators that realise a non-linear law: ``(name, coefficient c in
        bias -c v [N s/m], force range [N])`` each; empty for a linear law (unless the
        realisation is ``"actuators"``)."""
        if self.linear and self.realisation == "auto":
            return []
        out = []
        for label, sign, c, beta, knee in self.sides():
            direction = -self.extension * sign  # sign of the coordinate force in this stroke
            out.append((f"{self.name}_{label}", beta * c, _range(direction * UNCLAMPED_N)))
            if beta != 1.0:
                extra = (1.0 - beta) * c
                out.append((f"{self.name}_{label}_bleed", extra, _range(direction * extra * knee)))
        return out


def _range(limit: float) -> list:
    """The force range between 0 and ``limit`` [N]."""
    return [min(0.0, limit), max(0.0, limit)]


def realise(spec: mujoco.MjSpec, damper: Damper) -> None:
    """Write ``damper`` into ``spec``: its joint's or tendon's ``damping`` for a linear law,
    otherwise that damping set to 0 and the bias-only actuators of :meth:`Damper.actuators`.

    Parameters
    ----------
    spec : mujoco.MjSpec
        The rig's model specification (edited in place).
    damper : Damper
        The element.

    Raises
    ------
    ValueError
        If the joint or tendon is not in ``spec``, or an actuator name is already taken.
    """
    kind, target = (
        ("joint", damper.joint) if damper.joint is not None else ("tendon", damper.tendon)
    )
    element = getattr(spec, kind)(target)
    if element is None:
        raise ValueError(f"damper {damper.name!r}: no {kind} {target!r} in the model")
    coefficients = np.array(element.damping, dtype=float)
    coefficients[0] = 0.0 if damper.actuators() else damper.damping
    element.damping = coefficients
    for name, c, force_range in damper.actuators():
        if spec.actuator(name) is not None:
            raise ValueError(f"damper {damper.name!r}: the model already has an actuator {name!r}")
        act = spec.add_actuator(name=name, target=target)
        act.trntype = mujoco.mjtTrn.mjTRN_JOINT if kind == "joint" else mujoco.mjtTrn.mjTRN_TENDON
        act.gainprm[0] = 0.0
        act.biastype = mujoco.mjtBias.mjBIAS_AFFINE
        act.biasprm[:3] = [0.0, 0.0, -c]
        act.ctrllimited = mujoco.mjtLimited.mjLIMITED_FALSE
        act.forcelimited = mujoco.mjtLimited.mjLIMITED_TRUE
        act.forcerange = force_range
