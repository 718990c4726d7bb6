"""Explicit-integration stability of a rig's stiff elements at a physics timestep.

MuJoCo's integrators (``Euler``, ``implicit``, ``implicitfast``) are semi-implicit Euler schemes:
the new velocity comes from the forces at the *current* position, the new position from the new
velocity. Damping may be taken implicitly (``implicitfast`` and ``implicit``: every joint and
tendon damper; ``Euler``: joint damping only), a spring never is. One spring ``k`` on an
effective mass ``m`` with damping ``c`` (``a = c dt / m``) is therefore stable only while

* ``(ω dt)² < 4 + 2 a`` with implicit damping,
* ``(ω dt)² < 4 - 2 a`` with explicit damping (``ω = sqrt(k / m)``),

and ``ω dt < 2.83`` for ``RK4`` without damping. Beyond the limit the element's mode grows by a
factor per step: dry friction or a dead band may hold the growth to a bounded high-frequency
limit cycle for small motions (numerical noise, hidden by the anti-alias filter), larger drives
end in MuJoCo's ``BADQACC`` warning. The servo-hydraulic oil column (:mod:`vrig.rigs.hydraulics`)
integrates its load pressure explicitly from the piston velocity, which is the same scheme as a
spring ``4 β A² / V_t`` on the piston without damping.

:func:`stiff_elements` lists the springs of a compiled model (joint and tendon stiffness, oil
columns) with their effective masses at a pose; :func:`spectral_radius` is the growth factor per
step of the linearised model (all elements together, with the integrator's treatment of
damping), and :func:`max_stable_timestep` the largest timestep at which it stays <= 1.
Constraints (joint and tendon limits, equalities, contacts) are not listed: MuJoCo keeps them
stable by itself (``refsafe`` clamps a constraint's time constant to at least two timesteps).
Only the linear part of a spring counts (polynomial stiffness and dead bands are nonlinear: a
dead band only removes stiffness, dry friction only adds mass, so neither can make the linear
estimate optimistic; a hardening polynomial term can).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mujoco
import numpy as np

__all__ = ["StiffElement", "max_stable_timestep", "spectral_radius", "stiff_elements"]

_RK4 = int(mujoco.mjtIntegrator.mjINT_RK4)
_EULER = int(mujoco.mjtIntegrator.mjINT_EULER)
_EULERDAMP_OFF = int(mujoco.mjtDisableBit.mjDSBL_EULERDAMP)
# growth per step tolerated as round-off: rigid-body modes sit at 1 as a Jordan pair, which
# rounding may split by ~sqrt(1e-16); a spring beyond its limit grows by far more per step
_TOL = 1e-6


@dataclass(frozen=True)
class StiffElement:
    """One spring of the model, in generalised coordinates.

    Attributes
    ----------
    name : str
        What it is, e.g. ``"tendon 'loadcell'"``, ``"oil column of 'actuator_disp'"``.
    stiffness : float
        Spring rate [N/m or N m/rad].
    damping : float
        Parallel damper [N s/m or N m s/rad].
    implicit : bool
        Whether the integrator takes this element's damping implicitly.
    direction : ndarray (nv,)
        The element's Jacobian: its deflection rate per generalised velocity.
    mass : float
        Effective mass ``1 / (J M⁻¹ Jᵀ)`` at the pose it was computed for [kg or kg m²].
    """

    name: str
    stiffness: float
    damping: float
    implicit: bool
    direction: np.ndarray
    mass: float

    @property
    def frequency(self) -> float:
        """Natural frequency ``sqrt(k / m) / 2π`` [Hz] of the element on its effective mass."""
        return math.sqrt(self.stiffness / self.mass) / (2 * math.pi)

    def limit(self, integrator: int) -> float:
        """Largest stable timestep [s] of this element alone (closed form, see the module).

        Parameters
        ----------
        integrator : int
            The model's integrator (``mujoco.mjtIntegrator`` value: Euler, RK4, implicit or
            implicitfast).
        """
        w2, cm = self.stiffness / self.mass, self.damping / self.mass
        if integrator == _RK4:
            return 2.0 * math.sqrt(2.0) / math.sqrt(w2)
        if self.implicit:  # w² dt² - 2 (c/m) dt - 4 = 0
            return (cm + math.sqrt(cm * cm + 4 * w2)) / w2
        return (-cm + math.sqrt(cm * cm + 4 * w2)) / w2  # w² dt² + 2 (c/m) dt - 4 = 0


def _joint_damping_implicit(model: mujoco.MjModel) -> bool:
    integrator = int(model.opt.integrator)
    if integrator == _EULER:
        return not model.opt.disableflags & _EULERDAMP_OFF
    return integrator != _RK4


def _mass_matrix(model: mujoco.MjModel, data: mujoco.MjData) -> np.ndarray:
    mujoco.mj_forward(model, data)
    mass = np.zeros((model.nv, model.nv))
    mujoco.mj_fullM(model, data, mass)
    return mass


def _tendon_jacobian(model: mujoco.MjModel, data: mujoco.MjData) -> np.ndarray:
    jac = np.zeros((model.ntendon, model.nv))
    if model.ntendon:
        mujoco.mju_sparse2dense(
            jac, data.ten_J, model.ten_J_rownnz, model.ten_J_rowadr, model.ten_J_colind
        )
    return jac


def _joint_dofs(model: mujoco.MjModel, j: int) -> range:
    size = {0: 6, 1: 3, 2: 1, 3: 1}[int(model.jnt_type[j])]  # free, ball, slide, hinge
    start = int(model.jnt_dofadr[j])
    return range(start, start + size)


def stiff_elements(
    model: mujoco.MjModel, data: mujoco.MjData, oil_columns=(), springs=()
) -> list[StiffElement]:
    """The springs of ``model`` at the pose in ``data`` (``data`` is forwarded in place).

    Parameters
    ----------
    model, data
        The compiled rig and a pose (e.g. its ``home`` keyframe).
    oil_columns : sequence of (name, stiffness, dof address)
        Servo-hydraulic oil columns: ``4 β A² / V_t`` on the piston's degree of freedom.
    springs : sequence of (name, stiffness, direction (nv,))
        Springs evaluated outside MuJoCo's own elements, e.g. the small-signal rate of an air
        spring (:mod:`vrig.rigs.gas_spring`, applied explicitly by a passive-force callback)
        along its tendon's Jacobian.

    Returns
    -------
    list of StiffElement
    """
    mass = _mass_matrix(model, data)
    implicit_tendon = int(model.opt.integrator) not in (_EULER, _RK4)
    implicit_joint = _joint_damping_implicit(model)
    out = []

    def add(name, k, c, implicit, direction):
        inv = float(direction @ np.linalg.solve(mass, direction))
        out.append(StiffElement(name, float(k), float(c), implicit, direction, 1.0 / inv))

    for j in range(model.njnt):
        k = float(model.jnt_stiffness[j])
        if k <= 0:
            continue
        name = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_JOINT, j) or f"#{j}"
        for dof in _joint_dofs(model, j):
            e = np.zeros(model.nv)
            e[dof] = 1.0
            add(f"joint {name!r}", k, model.dof_damping[dof], implicit_joint, e)
    jac = _tendon_jacobian(model, data)
    for t in range(model.ntendon):
        k = float(model.tendon_stiffness[t])
        if k <= 0 or not jac[t].any():
            continue
        name = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_TENDON, t) or f"#{t}"
        add(f"tendon {name!r}", k, model.tendon_damping[t], implicit_tendon, jac[t])
    for name, k, dof in oil_columns:
        e = np.zeros(model.nv)
        e[dof] = 1.0
        add(f"oil column of {name!r}", k, 0.0, False, e)
    for name, k, direction in springs:
        if k > 0 and np.any(direction):
            add(name, k, 0.0, False, np.asarray(direction, dtype=float))
    return out


def _actuator_damping(model: mujoco.MjModel, jac: np.ndarray) -> np.ndarray:
    """The small-signal damping matrix of the actuators whose force has a velocity bias
    (``biastype`` affine, ``biasprm[2] = -c < 0``, on a joint or a tendon: e.g. the hydraulic
    damper law of :mod:`vrig.rigs.damper`). A one-sided ``forcerange`` acts in one direction of
    motion only, so per transmission the damping is the *smaller* of the two directions' sums
    (the sum of the ``c`` that may push negative, of those that may push positive): the
    damping the mode sees in its less damped half-cycle (a conservative linearisation)."""
    sums = {}  # (trntype, trnid) -> [c pushing negative, c pushing positive, direction]
    affine = int(mujoco.mjtBias.mjBIAS_AFFINE)
    kinds = {int(mujoco.mjtTrn.mjTRN_JOINT): "joint", int(mujoco.mjtTrn.mjTRN_TENDON): "tendon"}
    for i in range(model.nu):
        c = -float(model.actuator_biasprm[i, 2]) * float(model.actuator_gear[i, 0]) ** 2
        kind = kinds.get(int(model.actuator_trntype[i]))
        if int(model.actuator_biastype[i]) != affine or c <= 0 or kind is None:
            continue
        target = int(model.actuator_trnid[i, 0])
        if kind == "joint":
            g = np.zeros(model.nv)
            g[int(model.jnt_dofadr[target])] = 1.0
        else:
            g = jac[target]
        lo, hi = model.actuator_forcerange[i] if model.actuator_forcelimited[i] else (-1, 1)
        entry = sums.setdefault((kind, target), [0.0, 0.0, g])
        entry[0] += c if lo < 0 else 0.0
        entry[1] += c if hi > 0 else 0.0
    out = np.zeros((model.nv, model.nv))
    for neg, pos, g in sums.values():
        out += min(neg, pos) * np.outer(g, g)
    return out


def _damping(model: mujoco.MjModel, data: mujoco.MjData) -> tuple[np.ndarray, np.ndarray]:
    """The model's damping matrix (joints, tendons and velocity-biased actuators) and the part
    the integrator takes implicitly (MuJoCo's implicit integrators take the actuators' velocity
    derivatives like tendon damping; ``Euler`` and ``RK4`` do not)."""
    jac = _tendon_jacobian(model, data)
    tendon = jac.T @ (model.tendon_damping[:, None] * jac)
    actuator = _actuator_damping(model, jac)
    joint = np.diag(model.dof_damping)
    implicit = np.zeros_like(joint)
    if _joint_damping_implicit(model):
        implicit += joint
    if int(model.opt.integrator) not in (_EULER, _RK4):
        implicit += tendon + actuator
    return joint + tendon + actuator, implicit


def _step_matrix(mass, damping, elements, integrator: int, dt: float) -> np.ndarray:
    """The linearised one-step map of (q, v): springs ``elements``, ``damping`` = (full,
    implicit part) from :func:`_damping`."""
    nv = mass.shape[0]
    stiff = np.zeros((nv, nv))
    for e in elements:
        stiff += e.stiffness * np.outer(e.direction, e.direction)
    damp, damp_implicit = damping
    eye = np.eye(nv)
    if integrator == _RK4:
        a = np.block(
            [
                [np.zeros((nv, nv)), eye],
                [-np.linalg.solve(mass, stiff), -np.linalg.solve(mass, damp)],
            ]
        )
        ha = dt * a
        step, term = np.eye(2 * nv), np.eye(2 * nv)
        for k in range(1, 5):
            term = term @ ha / k
            step = step + term
        return step
    b = np.linalg.inv(mass + dt * damp_implicit)
    bk, bc = dt * b @ stiff, dt * b @ damp
    return np.block([[eye - dt * bk, dt * (eye - bc)], [-bk, eye - bc]])


def _radius(step: np.ndarray) -> float:
    return float(np.abs(np.linalg.eigvals(step)).max())


def spectral_radius(model: mujoco.MjModel, data: mujoco.MjData, elements, dt: float) -> float:
    """Growth factor per step (largest eigenvalue magnitude) of the linearised model at ``dt``.

    Stable when <= 1. ``data`` holds the pose ``elements`` were computed at.

    Parameters
    ----------
    model : mujoco.MjModel
        The compiled model.
    data : mujoco.MjData
        Its data, at the pose the elements were computed at.
    elements : sequence of StiffElement
        The springs of the model (see :func:`stiff_elements`).
    dt : float
        Timestep in s.
    """
    mass = _mass_matrix(model, data)
    damping = _damping(model, data)
    return _radius(_step_matrix(mass, damping, elements, int(model.opt.integrator), dt))


def max_stable_timestep(model: mujoco.MjModel, data: mujoco.MjData, elements) -> float:
    """Largest timestep [s] at which the linearised model does not grow.

    Bisection on :func:`spectral_radius`, to 0.01 % of the limit; ``inf`` without a spring (or
    above 10 s), 0.0 if it grows at any timestep (a negative stiffness).

    Parameters
    ----------
    model : mujoco.MjModel
        The compiled model.
    data : mujoco.MjData
        Its data, at the pose the elements were computed at.
    elements : sequence of StiffElement
        The springs of the model (see :func:`stiff_elements`).
    """
    if not elements:
        return math.inf
    mass = _mass_matrix(model, data)
    damping = _damping(model, data)
    integrator = int(model.opt.integrator)

    def stable(dt):
        return _radius(_step_matrix(mass, damping, elements, integrator, dt)) <= 1.0 + _TOL

    lo = min(e.limit(integrator) for e in elements) / 64
    for _ in range(40):
        if stable(lo):
            break
        lo /= 2
    else:
        return 0.0
    hi = 2 * lo
    while stable(hi):
        lo, hi = hi, 2 * hi
        if hi > 10.0:
            return math.inf
    while hi - lo > 1e-4 * lo:
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if stable(mid) else (lo, mid)
    return lo
