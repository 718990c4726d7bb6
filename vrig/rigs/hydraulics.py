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

from ._callbacks import MAX_LIVE, Hook, _as_pointer, _context_or_chain, _record_pointer
from ._checks import check_number, replace_fields

__all__ = [
    "CONTROL", "MAX_CHANNELS", "MAX_LIVE", "TRIP_KINDS", "Hook", "HydraulicActuator", "install",
    "trip_record", "uninstall",
]  # fmt: skip

MAX_CHANNELS = 16
"""At most this many MjData may have a live vrig context at once (per callback kind)."""
TRIP_KINDS = {1: "stroke", 2: "force", 3: "following error"}
_NON_NEGATIVE = ("leakage", "kp", "ki", "kd", "pressure_feedback")

# Layout of ``mjData.userdata`` (float64): a header, then ``_UD_PER_CHANNEL`` states per channel.
_UD_HEADER = 8
_UD_STEP = 0  # physics steps taken since install
_UD_TRIP_CODE = 1  # first interlock trip: kind (TRIP_KINDS; 0 none), channel, step, value, limit
_UD_TRIP_CHANNEL = 2
_UD_TRIP_STEP = 3
_UD_TRIP_VALUE = 4
_UD_TRIP_LIMIT = 5
_UD_PER_CHANNEL = 8
_S_SPOOL = 0  # spool position x_v [-]
_S_SPOOL_VEL = 1  # spool velocity [1/s]
_S_LOAD_PRESSURE = 2  # load pressure p_L [Pa]
_S_INTEGRAL = 3  # integral of the error [m s]
_S_PREV_ERROR = 4  # error at the previous controller update [m]
_S_VALVE_CMD = 5  # held valve command [-]

# One channel's parameters as the compiled callback reads them (derived values precomputed).
PARAM_DTYPE = np.dtype(
    [
        ("area", np.float64),  # A [m^2]
        ("supply_pressure", np.float64),  # P_s [Pa]
        ("max_flow", np.float64),  # Q_max [m^3/s]
        ("valve_omega", np.float64),  # 2 pi f_v [rad/s]
        ("valve_damping", np.float64),  # zeta_v [-]
        ("oil_gain", np.float64),  # 4 beta / V_t [Pa/m^3]
        ("leakage", np.float64),  # C_leak [m^3/(s Pa)]
        ("kp", np.float64),
        ("ki", np.float64),
        ("kd", np.float64),
        ("stroke", np.float64),  # [m]
        ("force_limit", np.float64),  # [N]
        ("error_limit", np.float64),  # [m]
        ("period", np.int64),  # physics steps per controller update
        ("controller_dt", np.float64),  # period * dt [s]
        ("pressure_feedback", np.float64),
        ("dt", np.float64),  # physics timestep [s]
        ("i_cmd", np.int64),  # ctrl index of the displacement command
        ("i_noise", np.int64),  # ctrl index of the valve noise
        ("i_force", np.int64),  # ctrl index of the piston force
        ("qpos", np.int64),  # qpos address of the piston joint
        ("dof", np.int64),  # dof address of the piston joint
    ],
    align=True,
)
# Per-MjData context: raw addresses and sizes of the arrays the callback works on.
CONTEXT_DTYPE = np.dtype(
    [(k, np.int64) for k in ("nch", "ctrl", "qpos", "qvel", "userdata", "params", "nu", "nq",
                             "nv", "nuserdata")]
)  # fmt: skip
_PARAM_NB = nb.from_dtype(PARAM_DTYPE)
_CONTEXT_NB = nb.from_dtype(CONTEXT_DTYPE)
_as_params = _record_pointer(_PARAM_NB)
_as_context = _record_pointer(_CONTEXT_NB)


@dataclass(frozen=True)
class HydraulicActuator:
    """Parameters of one servo-hydraulic actuator channel (SI units).

    Defaults describe a 25 kN, ±75 mm laboratory actuator at 21 MPa with a 38 L/min servo valve
    (datasheet-typical values for MTS 244 / Moog G761 class hardware).

    Attributes
    ----------
    area : float
        Piston annulus area A [m²] (default: 25 kN at 21 MPa).
    supply_pressure : float
        Supply pressure P_s [Pa].
    max_flow : float
        Rated valve flow Q_max [m³/s] (38 L/min: a 0.53 m/s velocity limit).
    valve_frequency : float
        Servo-valve natural frequency [Hz] (the -90 deg point).
    valve_damping : float
        Servo-valve damping ratio [-].
    bulk_modulus : float
        Effective oil bulk modulus, hoses included [Pa].
    oil_volume : float
        Total trapped oil volume V_t [m³].
    leakage : float
        Cross-port leakage coefficient [m³/(s Pa)].
    kp : float
        Proportional gain [valve fraction per m of following error] (about 40 Hz crossover).
    ki : float
        Integral gain [1/(m s)].
    kd : float
        Derivative gain [s/m].
    pressure_feedback : float
        Delta-P stabilisation [valve fraction per P_s of load pressure] (see the module).
    stroke : float
        Stroke limit (half stroke) [m].
    force_limit : float
        Force interlock [N].
    error_limit : float
        Following-error interlock [m].
    controller_rate : float
        Controller update rate [Hz] (at most the physics rate).
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
        """A copy with ``changes`` (unknown names refused, the values checked).

        Parameters
        ----------
        **changes
            New values of fields, by name (in the fields' units).
        """
        return replace_fields(self, changes, "hydraulic parameter")

    def record(self, dt: float, index=(0, 0, 0, 0, 0)) -> np.ndarray:
        """This channel as one :data:`PARAM_DTYPE` record for a physics timestep ``dt`` [s];
        ``index``: (cmd, noise, force ctrl index, qpos address, dof address).

        Parameters
        ----------
        dt : float
            Physics timestep in s.
        index : tuple of int, optional
            ``(cmd ctrl index, noise ctrl index, force ctrl index, qpos address, dof address)`` of
            the channel in the MuJoCo model.
        """
        r = np.zeros((), dtype=PARAM_DTYPE)
        steps = max(1, round(1.0 / (self.controller_rate * dt)))
        r["area"] = self.area
        r["supply_pressure"] = self.supply_pressure
        r["max_flow"] = self.max_flow
        r["valve_omega"] = 2 * np.pi * self.valve_frequency
        r["valve_damping"] = self.valve_damping
        r["oil_gain"] = 4.0 * self.bulk_modulus / self.oil_volume
        r["leakage"] = self.leakage
        r["kp"], r["ki"], r["kd"] = self.kp, self.ki, self.kd
        r["stroke"] = self.stroke
        r["force_limit"] = self.force_limit
        r["error_limit"] = self.error_limit
        r["period"] = steps
        r["controller_dt"] = steps * dt
        r["pressure_feedback"] = self.pressure_feedback
        r["dt"] = dt
        for key, value in zip(("i_cmd", "i_noise", "i_force", "qpos", "dof"), index, strict=True):
            r[key] = value
        return r


@nb.njit(cache=False)
def _controller(p, ud, s: int, err: float, noise: float, step: int) -> None:  # pragma: no cover
    """The PID with delta-P feedback, sample-and-hold at the controller's own rate; integrates
    only while the valve command is not saturated."""
    if step % p.period != 0:
        return
    tc = p.controller_dt
    deriv = (err - ud[s + _S_PREV_ERROR]) / tc if step > 0 else 0.0
    u = (
        p.kp * err
        + p.ki * ud[s + _S_INTEGRAL]
        + p.kd * deriv
        - p.pressure_feedback * ud[s + _S_LOAD_PRESSURE] / p.supply_pressure
        + noise
    )
    if u > 1.0:
        u = 1.0
    elif u < -1.0:
        u = -1.0
    else:
        ud[s + _S_INTEGRAL] += err * tc
    ud[s + _S_VALVE_CMD] = u
    ud[s + _S_PREV_ERROR] = err


@nb.njit(cache=False)
def _servo_valve(p, ud, s: int, dt: float) -> float:  # pragma: no cover
    """Second-order spool dynamics (semi-implicit Euler), the spool at its end stops: the new
    spool position."""
    wv = p.valve_omega
    acc = (
        wv * wv * (ud[s + _S_VALVE_CMD] - ud[s + _S_SPOOL])
        - 2.0 * p.valve_damping * wv * ud[s + _S_SPOOL_VEL]
    )
    ud[s + _S_SPOOL_VEL] += dt * acc
    xv = ud[s + _S_SPOOL] + dt * ud[s + _S_SPOOL_VEL]
    if xv > 1.0:
        xv = 1.0
        ud[s + _S_SPOOL_VEL] = 0.0
    elif xv < -1.0:
        xv = -1.0
        ud[s + _S_SPOOL_VEL] = 0.0
    ud[s + _S_SPOOL] = xv
    return xv


@nb.njit(cache=False)
def _oil_column(p, ud, s: int, xv: float, v: float, dt: float) -> float:  # pragma: no cover
    """Load-dependent flow through the valve into the compliant oil column: the piston force."""
    ps = p.supply_pressure
    pl = ud[s + _S_LOAD_PRESSURE]
    drop = ps - pl if xv >= 0.0 else ps + pl
    if drop < 0.0:
        drop = 0.0
    q = p.max_flow * xv * np.sqrt(drop / ps)
    pl += dt * p.oil_gain * (q - p.area * v - p.leakage * pl)
    if pl > ps:
        pl = ps
    elif pl < -ps:
        pl = -ps
    ud[s + _S_LOAD_PRESSURE] = pl
    return p.area * pl


@nb.njit(cache=False)
def _interlocks(p, ud, c: int, step: int, x: float, force: float, err: float) -> None:  # pragma: no cover
    """Record the first interlock trip (stroke, force, following error) in the userdata."""
    if ud[_UD_TRIP_CODE] != 0.0:
        return
    code = 0
    value = 0.0
    limit = 0.0
    if abs(x) > p.stroke:
        code, value, limit = 1, x, p.stroke
    elif abs(force) > p.force_limit:
        code, value, limit = 2, force, p.force_limit
    elif abs(err) > p.error_limit:
        code, value, limit = 3, err, p.error_limit
    if code:
        ud[_UD_TRIP_CODE] = code
        ud[_UD_TRIP_CHANNEL] = c
        ud[_UD_TRIP_STEP] = step
        ud[_UD_TRIP_VALUE] = value
        ud[_UD_TRIP_LIMIT] = limit


def _build_control(table_address: int):
    """Compile the control callback (once per process, on first use: ~1 s)."""

    @nb.cfunc(types.void(types.voidptr, types.voidptr), nopython=True, cache=False)
    def _control_callback(m, d):  # pragma: no cover - compiled, runs inside mj_step
        address = _context_or_chain(table_address, m, d)
        if address == 0:
            return
        ctx = nb.carray(_as_context(address), (1,))[0]
        nch = ctx.nch
        if nch == 0:
            return
        ctrl = nb.carray(_as_pointer(ctx.ctrl), (ctx.nu,), dtype=np.float64)
        qpos = nb.carray(_as_pointer(ctx.qpos), (ctx.nq,), dtype=np.float64)
        qvel = nb.carray(_as_pointer(ctx.qvel), (ctx.nv,), dtype=np.float64)
        ud = nb.carray(_as_pointer(ctx.userdata), (ctx.nuserdata,), dtype=np.float64)
        par = nb.carray(_as_params(ctx.params), (MAX_CHANNELS,))
        dt = par[0].dt
        step = int(ud[_UD_STEP])
        ud[_UD_STEP] = step + 1
        for c in range(nch):
            p = par[c]
            s = _UD_HEADER + _UD_PER_CHANNEL * c
            x = qpos[p.qpos]
            err = ctrl[p.i_cmd] - x
            _controller(p, ud, s, err, ctrl[p.i_noise], step)
            xv = _servo_valve(p, ud, s, dt)
            force = _oil_column(p, ud, s, xv, qvel[p.dof], dt)
            ctrl[p.i_force] = force
            _interlocks(p, ud, c, step, x, force, err)

    return _control_callback


CONTROL = Hook("control", _build_control)
"""vrig's ``mjcb_control`` hook (the servo-hydraulic channels of each live rig)."""


def install(
    model: mujoco.MjModel,
    data: mujoco.MjData,
    channels,
    dt: float,
    *,
    states: np.ndarray | None = None,
) -> np.ndarray:
    """Register ``data``'s context with the control callback for the hydraulic ``channels``
    (installing the callback if it is not, see :class:`Hook`).

    ``channels``: sequence of (HydraulicActuator, cmd ctrl index, noise ctrl index, force ctrl
    index, qpos address, dof address). Returns the context record (kept alive until
    :func:`uninstall`). Resets the callback's states in ``data.userdata`` to zero, or to
    ``states`` (from :func:`channel_states`, e.g. of a settled rig). Other MjData (other rigs,
    a user's own model) are unaffected.

    Parameters
    ----------
    model : mujoco.MjModel
        The rig's model.
    data : mujoco.MjData
        The rig's data (its ``userdata`` holds the callback's states).
    channels : sequence of tuple
        ``(HydraulicActuator, cmd ctrl index, noise ctrl index, force ctrl index, qpos address,
        dof address)`` per channel.
    dt : float
        Physics timestep in s.
    states : ndarray, optional
        Callback states to start from (from :func:`channel_states`); default zero.
    """
    n = len(channels)
    if n > MAX_CHANNELS:
        raise ValueError(f"at most {MAX_CHANNELS} hydraulic channels are supported, got {n}")
    need = _UD_HEADER + _UD_PER_CHANNEL * n
    if model.nuserdata < need:
        raise ValueError(f"the model needs <size nuserdata='{need}'/> for {n} hydraulic channels")
    params = np.zeros(MAX_CHANNELS, dtype=PARAM_DTYPE)
    for c, (act, *index) in enumerate(channels):
        params[c] = act.record(dt, index)
    data.userdata[:] = 0.0
    if states is not None:
        data.userdata[_UD_HEADER : _UD_HEADER + states.size] = states
    ctx = np.zeros(1, dtype=CONTEXT_DTYPE)
    ctx[0] = (n, data.ctrl.ctypes.data, data.qpos.ctypes.data, data.qvel.ctypes.data,
              data.userdata.ctypes.data, params.ctypes.data, model.nu, model.nq, model.nv,
              model.nuserdata)  # fmt: skip
    CONTROL.add(data, ctx, params, model)
    return ctx


def uninstall(data: mujoco.MjData | None = None) -> None:
    """Remove ``data``'s context (every one for None); the callback ignores that mjData from
    then on, and the previous callback is back once no context is left.

    Parameters
    ----------
    data : mujoco.MjData, optional
        The data whose context is removed; None removes every one.
    """
    CONTROL.remove(data)


def trip_record(data: mujoco.MjData):
    """(kind, channel index, step, value, limit) of the first interlock trip, or None.

    Parameters
    ----------
    data : mujoco.MjData
        A rig's data after a run.
    """
    ud = data.userdata
    if ud.size < _UD_HEADER or ud[_UD_TRIP_CODE] == 0:
        return None
    return (
        TRIP_KINDS[int(ud[_UD_TRIP_CODE])],
        int(ud[_UD_TRIP_CHANNEL]),
        int(ud[_UD_TRIP_STEP]),
        float(ud[_UD_TRIP_VALUE]),
        float(ud[_UD_TRIP_LIMIT]),
    )


def channel_states(data: mujoco.MjData, n: int) -> np.ndarray:
    """A copy of the callback's states (spool, spool velocity, load pressure, integrator, previous
    error, held valve command) of ``n`` channels, to restore with ``install(states=...)``.

    Parameters
    ----------
    data : mujoco.MjData
        A rig's data.
    n : int
        Number of hydraulic channels.
    """
    return data.userdata[_UD_HEADER : _UD_HEADER + _UD_PER_CHANNEL * n].copy()
