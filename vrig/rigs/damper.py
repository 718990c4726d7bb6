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
A smooth knee cannot be expressed this way (it needs a curved clamp): the knee is sharp.

Series compliance (optional: ``series_stiffness`` ``k_s`` > 0)
--------------------------------------------------------------
The oil's compressibility and the reservoir gas put a spring in series with the valves: the
damper force lags the velocity and the force-velocity plot becomes a hysteresis loop that opens
with frequency (Dixon 2007, ch. 8, the damper's compliance and its F-v loop; Duym, *Vehicle
System Dynamics* 33 (2000) 261-285, the oil compressibility of a physical damper model). vrig
models it as the internal state ``x_d`` of a massless valve node: the force on the joint/tendon
is ``f = k_s (x_d - (q - q_0))`` (``q`` the joint position or tendon length, ``q_0`` its value at
the model's reference pose) and the node moves at the velocity at which the law carries that
force, ``ẋ_d = g⁻¹(f)`` with ``g(v) = -extension F(extension v)`` (the law is piecewise linear
and monotone: its inverse is exact). For ``k_s → ∞`` this is the memoryless law; the lag is
``τ = c / k_s`` (``c`` the slope in use). Realisation: one actuator ``NAME_compliance`` with
``dyntype="user"`` (its activation is ``x_d``, integrated by MuJoCo: part of the rig's state)
and the affine force above; ``ẋ_d`` comes from vrig's compiled ``mjcb_act_dyn`` callback (a
:class:`~vrig.rigs._callbacks.Hook`, registered per run like the air springs'). MuJoCo steps the
activation by explicit Euler, which would be unstable for ``dt > 2 τ`` and lag-wrong by about
``dt / 2τ``; the callback therefore returns the rate that makes the step exact on the active
segment of the law for a joint/tendon moving at its current velocity ``v``:
``v + (1 - exp(-h)) / h · (g⁻¹(f) - v)``, ``h = dt / τ`` (the node's lag behind its equilibrium
decays by ``exp(-h)`` per step): stable at any timestep. The spring ``k_s`` is not counted in
the stability estimate (:mod:`vrig.rigs.stability`).

A rig declares its dampers in the side-car (``"dampers"``, ``models/README.md``); parameters
change a damper's fields by ``{"damper": NAME, "field": F}`` rules; :func:`realise` writes the
element into the :class:`mujoco.MjSpec` after the parameters are applied.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mujoco
import numba as nb
import numpy as np
from llvmlite import ir
from numba import types
from numba.core import cgutils
from numba.extending import intrinsic

from ._callbacks import Hook, _as_pointer, _lookup, _record_pointer
from ._checks import check_number, replace_fields

__all__ = [
    "ACT_DYN", "MAX_DAMPERS", "Damper", "add_compliance", "bind", "install", "realise", "uninstall",
]  # fmt: skip

MAX_DAMPERS = 8
"""Most internal-state elements per rig: dampers with series compliance plus Maxwell branches
(:mod:`vrig.rigs.maxwell`)."""

UNCLAMPED_N = 1e6
"""The open side of a one-directional actuator's force range [N] (never reached)."""


@dataclass(frozen=True)
class Damper:
    """One hydraulic damper (SI units; see the module for the law).

    Attributes
    ----------
    name : str
        The damper's name; its actuators are ``NAME_compression``, ``NAME_rebound`` (slopes)
        and ``NAME_compression_bleed``, ``NAME_rebound_bleed`` (bleed above the blow-off), or
        ``NAME_compliance`` with series compliance.
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
        ``v_c`` [m/s] (>= 0): compression speed at which the blow-off valve opens (0: open
        from rest, the law linear at the blow-off slope; a severity axis's linearised end).
    knee_velocity_rebound : float
        ``v_r`` [m/s] (>= 0): the same in rebound.
    series_stiffness : float
        ``k_s`` [N/m] (>= 0) of the spring in series with the valves; 0 (the default): none,
        the memoryless law.
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
    series_stiffness: float = 0.0
    realisation: str = "auto"

    FIELDS = (
        "damping", "rebound_ratio", "rebound_damping", "blowoff_ratio_compression",
        "blowoff_ratio_rebound", "knee_velocity_compression", "knee_velocity_rebound",
        "series_stiffness",
    )  # fmt: skip
    """The numeric fields a side-car parameter may set (``{"damper": NAME, "field": F}``)."""

    def __post_init__(self):
        """Validate the element (a :class:`~vrig.errors.RigParameterError` names the field)."""
        for key in self.FIELDS:
            value = getattr(self, key)
            if value is not None:
                check_number(f"damper {self.name!r}: {key}", value, minimum=0)
        if self.series_stiffness > 0 and self.least_slope() <= 0:
            raise ValueError(
                f"damper {self.name!r}: series compliance needs every slope of the law > 0 "
                "(its inverse gives the valve velocity)"
            )
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

    def least_slope(self) -> float:
        """The smallest slope of the law [N s/m] (bleed or blow-off, either stroke)."""
        return min(min(c, beta * c) for _, _, c, beta, _ in self.sides())

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

    def velocity_at(self, force):
        """The inverse law: the extension velocity ``u`` [m/s] at which the damper force is
        ``force`` [N] (positive: rebound; every slope of the law must be > 0).

        Parameters
        ----------
        force : float or ndarray
            Damper force in N.
        """
        force = np.asarray(force, dtype=float)
        u = np.zeros_like(force)
        for _, sign, c, beta, knee in self.sides():
            f = np.maximum(sign * force, 0.0)
            speed = np.where(f <= c * knee, f / c, knee + (f - c * knee) / (beta * c))
            u = u + sign * speed
        return u

    def actuators(self) -> list:
        """The MJCF actuators that realise a non-linear law: ``(name, coefficient c in
        bias -c v [N s/m], force range [N])`` each; empty for a linear law (unless the
        realisation is ``"actuators"``)."""
        if self.series_stiffness > 0:
            return []  # the compliance actuator carries the whole law
        if self.linear and self.realisation == "auto":
            return []
        out = []
        for label, sign, c, beta, knee in self.sides():
            direction = -self.extension * sign  # sign of the coordinate force in this stroke
            out.append((f"{self.name}_{label}", beta * c, _range(direction * UNCLAMPED_N)))
            if beta != 1.0 and knee > 0:  # knee 0: the blow-off slope from rest, no bleed
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
    memoryless = damper.series_stiffness == 0
    coefficients[0] = damper.damping if memoryless and not damper.actuators() else 0.0
    element.damping = coefficients
    if not memoryless:
        add_compliance(spec, damper, kind, target)
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


def add_compliance(spec: mujoco.MjSpec, damper: Damper, kind: str, target: str) -> None:
    """Add the series-compliance actuator ``NAME_compliance``: activation ``x_d``
    (``dyntype`` user), force ``k_s (x_d - q)``; :func:`bind` adds ``k_s q_0`` once the model
    is compiled. Shared with the Maxwell branches of :mod:`vrig.rigs.maxwell`.

    Parameters
    ----------
    spec : mujoco.MjSpec
        The rig's model specification (edited in place).
    damper : Damper
        The element (``series_stiffness`` > 0).
    kind : str
        ``"joint"`` or ``"tendon"``: what ``target`` names.
    target : str
        The joint or tendon the actuator acts on.

    Raises
    ------
    ValueError
        If the actuator name is already taken.
    """
    name = f"{damper.name}_compliance"
    if spec.actuator(name) is not None:
        raise ValueError(f"damper {damper.name!r}: the model already has an actuator {name!r}")
    act = spec.add_actuator(name=name, target=target)
    act.trntype = mujoco.mjtTrn.mjTRN_JOINT if kind == "joint" else mujoco.mjtTrn.mjTRN_TENDON
    act.dyntype = mujoco.mjtDyn.mjDYN_USER
    act.actdim = 1
    act.gainprm[0] = damper.series_stiffness
    act.biastype = mujoco.mjtBias.mjBIAS_AFFINE
    act.biasprm[:3] = [0.0, -damper.series_stiffness, 0.0]
    act.ctrllimited = mujoco.mjtLimited.mjLIMITED_FALSE
    act.actlimited = mujoco.mjtLimited.mjLIMITED_FALSE


# --- series compliance: the valve node's velocity in a compiled mjcb_act_dyn callback -----
PARAM_DTYPE = np.dtype(
    [
        ("actuator", np.int64),  # the compliance actuator's id
        ("extension", np.float64),  # +1 / -1
        ("stiffness", np.float64),  # k_s [N/m]
        ("offset", np.float64),  # q_0 [m]
        ("c", np.float64, (2,)),  # bleed [N s/m]: compression, rebound
        ("beta", np.float64, (2,)),  # blow-off ratio [-]
        ("knee", np.float64, (2,)),  # knee velocity [m/s]
    ],
    align=True,
)
CONTEXT_DTYPE = np.dtype(
    [(k, np.int64) for k in ("n", "params", "length", "velocity", "act", "actadr", "nu")]
    + [("dt", np.float64)]
)
_as_params = _record_pointer(nb.from_dtype(PARAM_DTYPE))
_as_context = _record_pointer(nb.from_dtype(CONTEXT_DTYPE))


@intrinsic
def _call_act(typingctx, function, m, d, i):
    """Call the C function at ``function`` as ``mjtNum f(const mjModel*, const mjData*, int)``."""
    sig = types.float64(function, m, d, i)

    def codegen(context, builder, signature, args):
        fnty = ir.FunctionType(
            ir.DoubleType(), [cgutils.voidptr_t, cgutils.voidptr_t, ir.IntType(32)]
        )
        return builder.call(builder.inttoptr(args[0], fnty.as_pointer()), list(args[1:]))

    return sig, codegen


@nb.njit(cache=False)
def _node_velocity(p, length, velocity, x_d, dt):  # pragma: no cover - compiled
    """``ẋ_d = g⁻¹(f)`` of the damper with parameter record ``p`` at the joint/tendon position
    ``length`` [m] and velocity [m/s] and the valve node ``x_d`` [m] (the module's law,
    inverted), made exact for MuJoCo's explicit step ``dt`` [s] on the active segment."""
    f = p.stiffness * (x_d - (length - p.offset))  # the force on the joint/tendon
    y = -p.extension * f  # the damper force asked of the law (positive: rebound)
    side = 1 if y > 0.0 else 0
    mag = abs(y)
    c, beta, knee = p.c[side], p.beta[side], p.knee[side]
    bleed = mag <= c * knee
    speed = mag / c if bleed else knee + (mag - c * knee) / (beta * c)
    rate = p.extension * (speed if side == 1 else -speed)
    # exact over the step on the active segment for a joint/tendon moving at ``velocity``:
    # the node's lag behind its equilibrium decays by exp(-dt / tau), tau = slope / k_s, so
    # MuJoCo's explicit Euler step of the activation lands on the exact solution
    h = dt * p.stiffness / (c if bleed else beta * c)
    scale = (1.0 - math.exp(-h)) / h if h > 1e-12 else 1.0
    return velocity + scale * (rate - velocity)


def _build_act_dyn(table_address: int):
    """Compile the activation-dynamics callback (once per process, on first use)."""

    @nb.cfunc(types.float64(types.voidptr, types.voidptr, types.intc), nopython=True, cache=False)
    def _act_dyn(m, d, i):  # pragma: no cover - compiled, runs inside mj_step
        address = _lookup(table_address, d)
        if address == 0:
            previous = nb.carray(_as_pointer(table_address), (1,), dtype=np.int64)[0]
            return _call_act(previous, m, d, i) if previous != 0 else 0.0
        ctx = nb.carray(_as_context(address), (1,))[0]
        par = nb.carray(_as_params(ctx.params), (MAX_DAMPERS,))
        length = nb.carray(_as_pointer(ctx.length), (ctx.nu,), dtype=np.float64)
        velocity = nb.carray(_as_pointer(ctx.velocity), (ctx.nu,), dtype=np.float64)
        actadr = nb.carray(_as_pointer(ctx.actadr), (ctx.nu,), dtype=np.int32)
        for c in range(ctx.n):
            p = par[c]
            if p.actuator == i:
                act = nb.carray(_as_pointer(ctx.act), (actadr[i] + 1,), dtype=np.float64)
                return _node_velocity(p, length[i], velocity[i], act[actadr[i]], ctx.dt)
        return 0.0

    return _act_dyn


ACT_DYN = Hook("act_dyn", _build_act_dyn)
"""vrig's ``mjcb_act_dyn`` hook (the valve nodes of the dampers with series compliance)."""


def bind(model: mujoco.MjModel, dampers) -> list:
    """The compiled model's parameter records of the dampers with series compliance; sets each
    compliance actuator's force offset ``k_s q_0`` (``q_0``: its length at ``qpos0``).

    Parameters
    ----------
    model : mujoco.MjModel
        The compiled rig model (its ``actuator_biasprm`` is edited).
    dampers : sequence of Damper
        The rig's dampers (those without series compliance are skipped).

    Returns
    -------
    list of numpy.ndarray
        One :data:`PARAM_DTYPE` record per damper with series compliance.
    """
    out = []
    data = None
    for dmp in dampers:
        if dmp.series_stiffness == 0:
            continue
        if data is None:
            data = mujoco.MjData(model)
            mujoco.mj_fwdPosition(model, data)
            mujoco.mj_transmission(model, data)
        i = model.actuator(f"{dmp.name}_compliance").id
        r = np.zeros((), dtype=PARAM_DTYPE)
        r["actuator"], r["extension"], r["stiffness"] = i, dmp.extension, dmp.series_stiffness
        r["offset"] = data.actuator_length[i]
        model.actuator_biasprm[i, 0] = dmp.series_stiffness * r["offset"]
        sides = dmp.sides()
        r["c"] = [sides[0][2], sides[1][2]]
        r["beta"] = [sides[0][3], sides[1][3]]
        r["knee"] = [sides[0][4], sides[1][4]]
        out.append(r)
    if len(out) > MAX_DAMPERS:
        raise ValueError(f"at most {MAX_DAMPERS} dampers with series compliance, got {len(out)}")
    return out


def install(model: mujoco.MjModel, data: mujoco.MjData, records) -> np.ndarray | None:
    """Register ``data``'s context with :data:`ACT_DYN` for the damper ``records`` of
    :func:`bind` (nothing for none). Returns the context (kept alive until :func:`uninstall`).

    Parameters
    ----------
    model : mujoco.MjModel
        The rig's model.
    data : mujoco.MjData
        The rig's data.
    records : sequence of numpy.ndarray
        :func:`bind`'s records.
    """
    if len(records) == 0:
        uninstall(data)
        return None
    params = np.zeros(MAX_DAMPERS, dtype=PARAM_DTYPE)
    for c, r in enumerate(records):
        params[c] = r
    ctx = np.zeros(1, dtype=CONTEXT_DTYPE)
    ctx[0] = (len(records), params.ctypes.data, data.actuator_length.ctypes.data,
              data.actuator_velocity.ctypes.data, data.act.ctypes.data, model.actuator_actadr.ctypes.data, model.nu,
              float(model.opt.timestep))  # fmt: skip
    ACT_DYN.add(data, ctx, params, model)
    return ctx


def uninstall(data: mujoco.MjData | None = None) -> None:
    """Remove ``data``'s context (every one for None) from :data:`ACT_DYN`.

    Parameters
    ----------
    data : mujoco.MjData, optional
        The data whose context is removed; None removes every one.
    """
    ACT_DYN.remove(data)
