"""Air spring (gas spring) element: a closed gas volume under the polytropic law, acting along a
tendon, with an effective area and a volume that change with its height.

MuJoCo has no gas-spring element (a tendon's ``springlength``/``stiffness`` is linear, and an
added polynomial would not be a gas law), so vrig evaluates it in a compiled **passive-force
callback** (a numba ``cfunc`` registered with ``mujoco.set_mjcb_passive``) inside MuJoCo's own
stepping (``mujoco.rollout``), like the servo-hydraulic control callback
(:mod:`vrig.rigs.hydraulics`): no Python call per physics step. A rig declares its air springs
in the side-car (``"air_springs"``, ``models/README.md``); the rig installs their context right
before each rollout and removes it after.

Per air spring, its height ``h`` [m] is the length of a tendon (a spatial tendon between the
spring's two plates), ``Δ = h - h_d`` its deviation from the design height ``h_d``:

* effective area ``A_e(h) = A_d + A' Δ`` [m²] (``A'`` = ``area_slope``: a rolling-lobe spring's
  area grows as it compresses onto a flared piston: ``A' < 0``);
* volume ``V(h) = V_d + A_d Δ + A' Δ² / 2`` [m³], so that ``dV/dh = A_e``: the force below is
  the exact derivative of the gas energy (virtual work; the bellows wall's own stiffness and
  hysteresis are neglected), the element is conservative;
* absolute pressure, polytropic with index ``n`` (a closed air mass: 1 isothermal, 1.4
  adiabatic): ``p(h) = (p_d + p_a) (V_d / V(h))^n`` [Pa]; ``p_d`` is the gauge pressure at the
  design height, ``p_a`` the ambient pressure;
* force pushing the plates apart ``F(h) = (p(h) - p_a) A_e(h)`` [N], applied as the tendon force
  (generalised force ``J_tendonᵀ F`` added to ``qfrc_passive``).

The element's small-signal rate at height ``h`` is
``k(h) = -dF/dh = n p(h) A_e(h)² / V(h) - (p(h) - p_a) A'`` [N/m].

A user sensor (``<user name=... dim="1" needstage="pos"/>``, filled by the compiled sensor
callback ``mujoco.set_mjcb_sensor``) reads the gauge pressure ``p(h) - p_a`` [Pa]: the
pressure transducer. The volume is kept at or above 1 % of ``V_d`` (an air spring squeezed
that far would have hit its internal bump stop long before: the rig's joint limits must prevent
it) and the effective area at or above 0.

MJCF convention: the tendon must not have its own stiffness for the air spring (it may have
damping); give the air spring's plates sites and the tendon ``<spatial>`` between them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mujoco
import numba as nb
import numpy as np
from numba import types

from ._callbacks import Hook, _as_pointer, _call_sensor, _context_or_chain, _lookup, _record_pointer
from ._checks import check_number, replace_fields

__all__ = ["MAX_AIR_SPRINGS", "PASSIVE", "SENSOR", "AirSpring", "install", "uninstall"]

MAX_AIR_SPRINGS = 8
_MIN_VOLUME = 0.01  # fraction of the design volume

# One air spring as the compiled callbacks read it.
PARAM_DTYPE = np.dtype(
    [
        ("tendon", np.int64),  # tendon id (its length is the height h)
        ("sensor", np.int64),  # sensordata address of the pressure sensor, -1 for none
        ("design_height", np.float64),  # h_d [m]
        ("p0", np.float64),  # absolute pressure at the design height p_d + p_a [Pa]
        ("volume", np.float64),  # V_d [m^3]
        ("area", np.float64),  # A_d [m^2]
        ("area_slope", np.float64),  # A' [m^2/m]
        ("index", np.float64),  # polytropic index n [-]
        ("ambient", np.float64),  # p_a [Pa]
    ],
    align=True,
)
# Per-MjData context: raw addresses and sizes of the arrays the callbacks work on.
CONTEXT_DTYPE = np.dtype(
    [(k, np.int64) for k in ("n", "params", "ten_length", "ten_J", "qfrc_passive", "sensordata",
                             "rownnz", "rowadr", "colind", "ntendon", "njac", "nv",
                             "nsensordata")]
)  # fmt: skip
_as_params = _record_pointer(nb.from_dtype(PARAM_DTYPE))
_as_context = _record_pointer(nb.from_dtype(CONTEXT_DTYPE))


@dataclass(frozen=True)
class AirSpring:
    """One air spring (SI units; see the module for the law).

    Attributes
    ----------
    name : str
        The air spring's name (in messages and the side-car).
    tendon : str
        The MJCF tendon whose length is the air-spring height ``h`` [m].
    sensor : str or None
        An MJCF ``user`` sensor (dim 1, ``needstage="pos"``) that reads the gauge pressure [Pa].
    design_height : float
        ``h_d`` [m].
    design_pressure : float
        Gauge pressure ``p_d`` at the design height [Pa] (> -p_a).
    volume : float
        Gas volume ``V_d`` at the design height (bellows + piston / reservoir) [m³].
    effective_area : float
        ``A_d`` at the design height [m²].
    area_slope : float
        ``A' = dA_e/dh`` [m²/m] (negative for a rolling lobe on a flared piston).
    polytropic_index : float
        ``n`` [-], 1 (isothermal) to 1.4 (adiabatic, air).
    ambient_pressure : float
        ``p_a`` [Pa].
    """

    name: str
    tendon: str
    design_height: float
    design_pressure: float
    volume: float
    effective_area: float
    area_slope: float = 0.0
    polytropic_index: float = 1.3
    ambient_pressure: float = 101325.0
    sensor: str | None = None

    def __post_init__(self):
        """Validate every number (a :class:`~vrig.errors.RigParameterError` names it)."""
        for key in ("design_height", "volume", "effective_area", "ambient_pressure"):
            check_number(f"air spring {self.name!r}: {key}", getattr(self, key),
                         exclusive_minimum=0)  # fmt: skip
        check_number(f"air spring {self.name!r}: area_slope", self.area_slope)
        check_number(
            f"air spring {self.name!r}: polytropic_index", self.polytropic_index,
            minimum=1.0, maximum=1.4,
        )  # fmt: skip
        check_number(
            f"air spring {self.name!r}: design_pressure", self.design_pressure,
            exclusive_minimum=-self.ambient_pressure,
        )  # fmt: skip

    FIELDS = (
        "design_height", "design_pressure", "volume", "effective_area", "area_slope",
        "polytropic_index", "ambient_pressure",
    )  # fmt: skip
    """The numeric fields a side-car parameter may set (``{"air_spring": NAME, "field": F}``)."""

    def replace(self, **changes) -> AirSpring:
        """A copy with ``changes`` (unknown names refused, the values checked).

        Parameters
        ----------
        **changes
            New values of fields, by name (in the fields' SI units).
        """
        return replace_fields(self, changes, "air-spring field")

    # the law in NumPy (the compiled callback evaluates the same expressions)
    def effective_area_at(self, h):
        """``A_e(h)`` [m²].

        Parameters
        ----------
        h : float or ndarray
            Air-spring height in m.
        """
        return np.maximum(self.effective_area + self.area_slope * (np.asarray(h) - self.design_height), 0.0)

    def volume_at(self, h):
        """``V(h)`` [m³] (at least 1 % of ``V_d``).

        Parameters
        ----------
        h : float or ndarray
            Air-spring height in m.
        """
        d = np.asarray(h, dtype=float) - self.design_height
        v = self.volume + self.effective_area * d + 0.5 * self.area_slope * d * d
        return np.maximum(v, _MIN_VOLUME * self.volume)

    def pressure_at(self, h):
        """Gauge pressure ``p(h) - p_a`` [Pa].

        Parameters
        ----------
        h : float or ndarray
            Air-spring height in m.
        """
        p0 = self.design_pressure + self.ambient_pressure
        return p0 * (self.volume / self.volume_at(h)) ** self.polytropic_index - self.ambient_pressure

    def force_at(self, h):
        """Force pushing the plates apart [N].

        Parameters
        ----------
        h : float or ndarray
            Air-spring height in m.
        """
        return self.pressure_at(h) * self.effective_area_at(h)

    def rate_at(self, h):
        """Small-signal rate ``-dF/dh`` [N/m].

        Parameters
        ----------
        h : float or ndarray
            Air-spring height in m.
        """
        p = self.pressure_at(h) + self.ambient_pressure
        a = self.effective_area_at(h)
        return self.polytropic_index * p * a * a / self.volume_at(h) - (
            p - self.ambient_pressure
        ) * self.area_slope

    def record(self, tendon_id: int, sensor_adr: int) -> np.ndarray:
        """This air spring as one :data:`PARAM_DTYPE` record.

        Parameters
        ----------
        tendon_id : int
            Id of the MJCF tendon that gives the height.
        sensor_adr : int
            Address of the pressure sensor in ``sensordata`` (-1: none).
        """
        r = np.zeros((), dtype=PARAM_DTYPE)
        r["tendon"], r["sensor"] = tendon_id, sensor_adr
        r["design_height"] = self.design_height
        r["p0"] = self.design_pressure + self.ambient_pressure
        r["volume"] = self.volume
        r["area"] = self.effective_area
        r["area_slope"] = self.area_slope
        r["index"] = self.polytropic_index
        r["ambient"] = self.ambient_pressure
        return r


@nb.njit(cache=False)
def _law(p, h):  # pragma: no cover - compiled
    """(gauge pressure [Pa], force [N]) of the air spring with parameter record ``p`` at ``h``."""
    d = h - p.design_height
    area = p.area + p.area_slope * d
    if area < 0.0:
        area = 0.0
    vol = p.volume + p.area * d + 0.5 * p.area_slope * d * d
    vmin = _MIN_VOLUME * p.volume
    if vol < vmin:
        vol = vmin
    gauge = p.p0 * math.pow(p.volume / vol, p.index) - p.ambient
    return gauge, gauge * area


def _build_passive(table_address: int):
    """Compile the passive-force callback (once per process, on first use)."""

    @nb.cfunc(types.void(types.voidptr, types.voidptr), nopython=True, cache=False)
    def _passive(m, d):  # pragma: no cover - compiled, runs inside mj_step
        address = _context_or_chain(table_address, m, d)
        if address == 0:
            return
        ctx = nb.carray(_as_context(address), (1,))[0]
        par = nb.carray(_as_params(ctx.params), (MAX_AIR_SPRINGS,))
        length = nb.carray(_as_pointer(ctx.ten_length), (ctx.ntendon,), dtype=np.float64)
        jac = nb.carray(_as_pointer(ctx.ten_J), (ctx.njac,), dtype=np.float64)
        qfrc = nb.carray(_as_pointer(ctx.qfrc_passive), (ctx.nv,), dtype=np.float64)
        rownnz = nb.carray(_as_pointer(ctx.rownnz), (ctx.ntendon,), dtype=np.int32)
        rowadr = nb.carray(_as_pointer(ctx.rowadr), (ctx.ntendon,), dtype=np.int32)
        colind = nb.carray(_as_pointer(ctx.colind), (ctx.njac,), dtype=np.int32)
        for c in range(ctx.n):
            p = par[c]
            t = p.tendon
            _, force = _law(p, length[t])
            a = rowadr[t]
            for k in range(rownnz[t]):
                qfrc[colind[a + k]] += jac[a + k] * force

    return _passive


def _build_sensor(table_address: int):
    """Compile the sensor callback (the pressure transducers; once per process, on first use)."""

    @nb.cfunc(types.void(types.voidptr, types.voidptr, types.intc), nopython=True, cache=False)
    def _sensor(m, d, stage):  # pragma: no cover - compiled, runs inside mj_step
        address = _lookup(table_address, d)
        if address == 0:
            previous = nb.carray(_as_pointer(table_address), (1,), dtype=np.int64)[0]
            if previous != 0:
                _call_sensor(previous, m, d, stage)
            return
        if stage != 1:  # mjSTAGE_POS
            return
        ctx = nb.carray(_as_context(address), (1,))[0]
        par = nb.carray(_as_params(ctx.params), (MAX_AIR_SPRINGS,))
        length = nb.carray(_as_pointer(ctx.ten_length), (ctx.ntendon,), dtype=np.float64)
        sens = nb.carray(_as_pointer(ctx.sensordata), (ctx.nsensordata,), dtype=np.float64)
        for c in range(ctx.n):
            p = par[c]
            if p.sensor >= 0:
                gauge, _ = _law(p, length[p.tendon])
                sens[p.sensor] = gauge

    return _sensor


PASSIVE = Hook("passive", _build_passive)
"""vrig's ``mjcb_passive`` hook (the air-spring forces of each live rig)."""
SENSOR = Hook("sensor", _build_sensor)
"""vrig's ``mjcb_sensor`` hook (the air-spring pressure sensors of each live rig)."""


def install(model: mujoco.MjModel, data: mujoco.MjData, springs) -> np.ndarray | None:
    """Register ``data``'s context with the passive and sensor callbacks for ``springs``
    (installing them if they are not, see :class:`~vrig.rigs._callbacks.Hook`).

    ``springs``: sequence of (AirSpring, tendon id, sensor address or -1). Nothing to do for
    none (``data`` gets no context: the callbacks leave it alone). Returns the context record
    (kept alive until :func:`uninstall`). Other MjData are unaffected.

    Parameters
    ----------
    model : mujoco.MjModel
        The rig's model.
    data : mujoco.MjData
        The rig's data.
    springs : sequence of tuple
        ``(AirSpring, tendon id, sensor address or -1)`` per air spring.
    """
    n = len(springs)
    if n == 0:
        uninstall(data)
        return None
    if n > MAX_AIR_SPRINGS:
        raise ValueError(f"at most {MAX_AIR_SPRINGS} air springs are supported, got {n}")
    params = np.zeros(MAX_AIR_SPRINGS, dtype=PARAM_DTYPE)
    for c, (spring, tendon_id, sensor_adr) in enumerate(springs):
        params[c] = spring.record(tendon_id, sensor_adr)
    ctx = np.zeros(1, dtype=CONTEXT_DTYPE)
    ctx[0] = (n, params.ctypes.data, data.ten_length.ctypes.data, data.ten_J.ctypes.data,
              data.qfrc_passive.ctypes.data, data.sensordata.ctypes.data,
              model.ten_J_rownnz.ctypes.data, model.ten_J_rowadr.ctypes.data,
              model.ten_J_colind.ctypes.data, model.ntendon, data.ten_J.size, model.nv,
              model.nsensordata)  # fmt: skip
    PASSIVE.add(data, ctx, params, model)
    SENSOR.add(data, ctx, params, model)
    return ctx


def uninstall(data: mujoco.MjData | None = None) -> None:
    """Remove ``data``'s context (every one for None) from both callbacks; the previous
    callbacks are back once no context is left.

    Parameters
    ----------
    data : mujoco.MjData, optional
        The data whose context is removed; None removes every one.
    """
    PASSIVE.remove(data)
    SENSOR.remove(data)
