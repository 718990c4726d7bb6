"""Servo-hydraulic actuator: displacement PID, servo valve, load-dependent flow, oil compliance.

The actuator law runs inside MuJoCo's own stepping (``mujoco.rollout``) as a compiled control
callback (a numba ``cfunc`` registered with ``mujoco.set_mjcb_control``): no Python call per
physics step. Per channel and physics step:

* **controller** (at the controller rate, sample-and-hold): error ``e = x_cmd - x`` from the LVDT,
  valve command ``i = kp e + ki ∫e + kd de/dt - k_dp p_L / P_s + valve noise``, clipped to ±1
  (anti-windup: the integrator holds while the command saturates). The delta-P term
  (``pressure_feedback``) is the usual stabilisation of the lightly damped oil-column resonance;
  the integrator removes the static error it causes under load. It damps the oil-column mode
  when that mode lies below the servo-valve bandwidth; with a light payload or a small oil
  volume (oil-column mode above the valve frequency) it can destabilise it: set it to 0 and use
  cross-port ``leakage`` for damping (the radiator and motorcycle rigs do);
* **servo valve**: second-order spool dynamics ``x_v'' = ω_v² (i - x_v) - 2 ζ_v ω_v x_v'``,
  spool travel ±1;
* **flow** through the valve, load dependent (orifice law):
  ``Q = Q_max x_v sqrt((P_s - sign(x_v) p_L) / P_s)``; flow saturation at full spool opening
  limits the piston velocity to ``Q_max / A``;
* **oil column** compliance: ``dp_L/dt = (4 β / V_t) (Q - A v - C_leak p_L)``, ``|p_L| <= P_s``;
* **force** on the piston ``F = A p_L`` (applied by a ``motor`` actuator).

With the default parameters and ~25 kg moving mass the displacement loop is flat within about
±1 dB to 80 Hz and -3 dB near 150 Hz (``tests/test_hydraulics.py`` checks the simulated loop
against its linearisation); heavier payloads lower the oil-column resonance and the bandwidth.

Interlocks checked every physics step (first trip recorded): stroke ``|x| > stroke``, force
``|F| > force_limit``, following error ``|e| > error_limit``.

MJCF convention for a hydraulic channel ``NAME`` (see ``models/common/hydraulic.xml``): a slide
joint for the piston and three actuators on it: ``NAME_cmd`` (the displacement command, no
force), ``NAME_noise`` (valve-noise input, no force) and ``NAME_force`` (a motor, gear 1).
"""

from __future__ import annotations

from dataclasses import dataclass, fields

import mujoco
import numba as nb
import numpy as np
from numba import types
from numba.core import cgutils
from numba.extending import intrinsic

from ._checks import check_number, replace_fields

__all__ = ["MAX_CHANNELS", "TRIP_KINDS", "HydraulicActuator", "install", "trip_record"]

MAX_CHANNELS = 16
_NPAR = 20
_NINT = 8
_UD_HEADER = 8
_UD_PER_CHANNEL = 8
TRIP_KINDS = {1: "stroke", 2: "force", 3: "following error"}
_NON_NEGATIVE = ("leakage", "kp", "ki", "kd", "pressure_feedback")


@dataclass(frozen=True)
class HydraulicActuator:
    """Parameters of one servo-hydraulic actuator channel (SI units).

    Defaults describe a 25 kN, ±75 mm laboratory actuator at 21 MPa with a 38 L/min servo valve
    (datasheet-typical values for MTS 244 / Moog G761 class hardware).
    """

    area: float = 1.2e-3  # piston annulus area A [m^2]: 25 kN at 21 MPa
    supply_pressure: float = 21e6  # P_s [Pa]
    max_flow: float = 6.3e-4  # Q_max [m^3/s]: 38 L/min -> velocity limit 0.53 m/s
    valve_frequency: float = 120.0  # servo-valve natural frequency [Hz] (-90 deg point)
    valve_damping: float = 0.7  # servo-valve damping ratio
    bulk_modulus: float = 1.0e9  # effective oil bulk modulus incl. hoses [Pa]
    oil_volume: float = 3.8e-4  # total trapped oil volume V_t [m^3]
    leakage: float = 2e-12  # cross-port leakage [m^3/(s Pa)]
    kp: float = 470.0  # proportional gain [valve fraction per m]: ~40 Hz loop crossover
    ki: float = 2000.0  # integral gain [1/(m s)]
    kd: float = 0.0  # derivative gain [s/m]
    pressure_feedback: float = (
        1.0  # delta-P stabilisation [valve fraction per P_s of load pressure]
    )
    stroke: float = 0.075  # stroke limit (half stroke) [m]
    force_limit: float = 24e3  # force interlock [N]
    error_limit: float = 0.01  # following-error interlock [m]
    controller_rate: float = 5000.0  # controller update rate [Hz] (<= physics rate)

    def __post_init__(self):
        """Validate every field: a finite number, > 0 (>= 0 for ``leakage``, the gains and
        ``pressure_feedback``); a :class:`~vrig.errors.RigParameterError` names it."""
        for f in fields(self):
            bound = {"minimum": 0} if f.name in _NON_NEGATIVE else {"exclusive_minimum": 0}
            check_number(f.name, getattr(self, f.name), **bound)

    @property
    def velocity_limit(self) -> float:
        """No-load velocity at full valve opening ``Q_max / A`` [m/s]."""
        return self.max_flow / self.area

    @property
    def oil_stiffness(self) -> float:
        """Oil-column stiffness ``4 β A^2 / V_t`` [N/m]."""
        return 4.0 * self.bulk_modulus * self.area**2 / self.oil_volume

    def replace(self, **changes) -> HydraulicActuator:
        """A copy with ``changes`` (unknown names refused, the values checked)."""
        return replace_fields(self, changes, "hydraulic parameter")

    def as_row(self, dt: float) -> np.ndarray:
        row = np.zeros(_NPAR)
        steps = max(1, round(1.0 / (self.controller_rate * dt)))
        row[:15] = [
            self.area,
            self.supply_pressure,
            self.max_flow,
            2 * np.pi * self.valve_frequency,
            self.valve_damping,
            4.0 * self.bulk_modulus / self.oil_volume,
            self.leakage,
            self.kp,
            self.ki,
            self.kd,
            self.stroke,
            self.force_limit,
            self.error_limit,
            float(steps),
            steps * dt,
        ]
        row[15] = self.pressure_feedback
        row[16] = dt

        return row


@intrinsic
def _as_pointer(typingctx, address):
    sig = types.voidptr(address)

    def codegen(context, builder, signature, args):
        return builder.inttoptr(args[0], cgutils.voidptr_t)

    return sig, codegen


# Process-wide context read by the callback: pointers of the MjData arrays of the rig being run.
# MuJoCo's control callback is global; a rig installs its context right before each rollout.
_CTX = np.zeros(16, dtype=np.int64)
_CTX_ADDR = _CTX.ctypes.data


def _build_callback():
    """Compile the control callback (once per process, on first use: ~1 s)."""

    @nb.cfunc(types.void(types.voidptr, types.voidptr), nopython=True, cache=False)
    def _control_callback(m, d):  # pragma: no cover - compiled, runs inside mj_step
        ctx = nb.carray(_as_pointer(_CTX_ADDR), (16,), dtype=np.int64)
        nch = ctx[0]
        if nch == 0:
            return
        ctrl = nb.carray(_as_pointer(ctx[1]), (ctx[7],), dtype=np.float64)
        qpos = nb.carray(_as_pointer(ctx[2]), (ctx[8],), dtype=np.float64)
        qvel = nb.carray(_as_pointer(ctx[3]), (ctx[9],), dtype=np.float64)
        ud = nb.carray(_as_pointer(ctx[4]), (ctx[10],), dtype=np.float64)
        par = nb.carray(_as_pointer(ctx[5]), (MAX_CHANNELS, _NPAR), dtype=np.float64)
        idx = nb.carray(_as_pointer(ctx[6]), (MAX_CHANNELS, _NINT), dtype=np.int64)
        dt = par[0, 16]
        step = int(ud[0])
        ud[0] = step + 1
        for c in range(nch):
            p = par[c]
            s = _UD_HEADER + _UD_PER_CHANNEL * c
            x = qpos[idx[c, 3]]
            v = qvel[idx[c, 4]]
            err = ctrl[idx[c, 0]] - x
            # controller, sample-and-hold at its own rate
            per = int(p[13])
            if step % per == 0:
                tc = p[14]
                deriv = (err - ud[s + 4]) / tc if step > 0 else 0.0
                u = (
                    p[7] * err
                    + p[8] * ud[s + 3]
                    + p[9] * deriv
                    - p[15] * ud[s + 2] / p[1]
                    + ctrl[idx[c, 1]]
                )
                if u > 1.0:
                    u = 1.0
                elif u < -1.0:
                    u = -1.0
                else:
                    ud[s + 3] += err * tc  # integrate only while the valve is not saturated
                ud[s + 5] = u
                ud[s + 4] = err
            # servo valve, second order (semi-implicit Euler)
            wv = p[3]
            acc = wv * wv * (ud[s + 5] - ud[s + 0]) - 2.0 * p[4] * wv * ud[s + 1]
            ud[s + 1] += dt * acc
            xv = ud[s + 0] + dt * ud[s + 1]
            if xv > 1.0:
                xv = 1.0
                ud[s + 1] = 0.0
            elif xv < -1.0:
                xv = -1.0
                ud[s + 1] = 0.0
            ud[s + 0] = xv
            # load-dependent flow through the valve
            ps = p[1]
            pl = ud[s + 2]
            drop = ps - pl if xv >= 0.0 else ps + pl
            if drop < 0.0:
                drop = 0.0
            q = p[2] * xv * np.sqrt(drop / ps)
            # oil-column compliance
            pl += dt * p[5] * (q - p[0] * v - p[6] * pl)
            if pl > ps:
                pl = ps
            elif pl < -ps:
                pl = -ps
            ud[s + 2] = pl
            force = p[0] * pl
            ctrl[idx[c, 2]] = force
            # interlocks: record the first trip
            if ud[1] == 0.0:
                code = 0
                value = 0.0
                limit = 0.0
                if abs(x) > p[10]:
                    code, value, limit = 1, x, p[10]
                elif abs(force) > p[11]:
                    code, value, limit = 2, force, p[11]
                elif abs(err) > p[12]:
                    code, value, limit = 3, err, p[12]
                if code:
                    ud[1] = code
                    ud[2] = c
                    ud[3] = step
                    ud[4] = value
                    ud[5] = limit

    return _control_callback


_CALLBACK = None
_LIVE = None


@dataclass
class _Installed:
    params: np.ndarray
    index: np.ndarray


def install(
    model: mujoco.MjModel,
    data: mujoco.MjData,
    channels,
    dt: float,
    *,
    states: np.ndarray | None = None,
) -> _Installed:
    """Point the global control callback at ``data`` for the given hydraulic ``channels``.

    ``channels``: sequence of (HydraulicActuator, cmd ctrl index, noise ctrl index, force ctrl
    index, qpos address, dof address). Returns the parameter/index buffers (keep a reference
    while the rollout runs). Resets the callback's states in ``data.userdata`` to zero, or to
    ``states`` (from :func:`channel_states`, e.g. of a settled rig).
    """
    global _CALLBACK, _LIVE
    n = len(channels)
    if n > MAX_CHANNELS:
        raise ValueError(f"at most {MAX_CHANNELS} hydraulic channels are supported, got {n}")
    need = _UD_HEADER + _UD_PER_CHANNEL * n
    if model.nuserdata < need:
        raise ValueError(f"the model needs <size nuserdata='{need}'/> for {n} hydraulic channels")
    params = np.zeros((MAX_CHANNELS, _NPAR))
    index = np.zeros((MAX_CHANNELS, _NINT), dtype=np.int64)
    for c, (act, i_cmd, i_noise, i_force, qadr, dadr) in enumerate(channels):
        params[c] = act.as_row(dt)
        index[c, :5] = [i_cmd, i_noise, i_force, qadr, dadr]
    data.userdata[:] = 0.0
    if states is not None:
        data.userdata[_UD_HEADER : _UD_HEADER + states.size] = states
    _CTX[:] = 0
    _CTX[1:7] = [
        data.ctrl.ctypes.data,
        data.qpos.ctypes.data,
        data.qvel.ctypes.data,
        data.userdata.ctypes.data,
        params.ctypes.data,
        index.ctypes.data,
    ]
    _CTX[7:11] = [model.nu, model.nq, model.nv, model.nuserdata]
    _CTX[0] = n
    if _CALLBACK is None:
        _CALLBACK = _build_callback()
        mujoco.set_mjcb_control(_CALLBACK.ctypes)
    # the callback reads these buffers through raw pointers: keep them alive until the next
    # install, whatever the caller does with the return value
    _LIVE = _Installed(params, index)
    return _LIVE


def uninstall() -> None:
    """Disable the callback (it returns at once while no channel is installed)."""
    _CTX[0] = 0


def trip_record(data: mujoco.MjData):
    """(kind, channel index, step, value, limit) of the first interlock trip, or None."""
    ud = data.userdata
    if ud.size < _UD_HEADER or ud[1] == 0:
        return None
    return TRIP_KINDS[int(ud[1])], int(ud[2]), int(ud[3]), float(ud[4]), float(ud[5])


def channel_states(data: mujoco.MjData, n: int) -> np.ndarray:
    """A copy of the callback's states (spool, spool velocity, load pressure, integrator, previous
    error, held valve command) of ``n`` channels, to restore with ``install(states=...)``."""
    return data.userdata[_UD_HEADER : _UD_HEADER + _UD_PER_CHANNEL * n].copy()
