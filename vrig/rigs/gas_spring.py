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

from ._checks import check_number, replace_fields
from .hydraulics import _as_pointer

__all__ = ["MAX_AIR_SPRINGS", "AirSpring", "install", "uninstall"]

MAX_AIR_SPRINGS = 8
_NPAR = 12
_MIN_VOLUME = 0.01  # fraction of the design volume

# Process-wide context read by the callbacks: pointers of the arrays of the rig being run.
# MuJoCo's passive and sensor callbacks are global; a rig installs its context right before
# each rollout (n = 0: the callbacks return at once).
_CTX = np.zeros(16, dtype=np.int64)
_CTX_ADDR = _CTX.ctypes.data


@dataclass(frozen=True)
class AirSpring:
    """One air spring (SI units; see the module for the law).

    Attributes
    ----------
    name : str
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
        """A copy with ``changes`` (unknown names refused, the values checked)."""
        return replace_fields(self, changes, "air-spring field")

    # the law in NumPy (the compiled callback evaluates the same expressions)
    def effective_area_at(self, h):
        """``A_e(h)`` [m²]."""
        return np.maximum(self.effective_area + self.area_slope * (np.asarray(h) - self.design_height), 0.0)

    def volume_at(self, h):
        """``V(h)`` [m³] (at least 1 % of ``V_d``)."""
        d = np.asarray(h, dtype=float) - self.design_height
        v = self.volume + self.effective_area * d + 0.5 * self.area_slope * d * d
        return np.maximum(v, _MIN_VOLUME * self.volume)

    def pressure_at(self, h):
        """Gauge pressure ``p(h) - p_a`` [Pa]."""
        p0 = self.design_pressure + self.ambient_pressure
        return p0 * (self.volume / self.volume_at(h)) ** self.polytropic_index - self.ambient_pressure

    def force_at(self, h):
        """Force pushing the plates apart [N]."""
        return self.pressure_at(h) * self.effective_area_at(h)

    def rate_at(self, h):
        """Small-signal rate ``-dF/dh`` [N/m]."""
        p = self.pressure_at(h) + self.ambient_pressure
        a = self.effective_area_at(h)
        return self.polytropic_index * p * a * a / self.volume_at(h) - (
            p - self.ambient_pressure
        ) * self.area_slope

    def row(self, tendon_id: int, sensor_adr: int) -> np.ndarray:
        r = np.zeros(_NPAR)
        r[:9] = [
            tendon_id,
            sensor_adr,
            self.design_height,
            self.design_pressure + self.ambient_pressure,
            self.volume,
            self.effective_area,
            self.area_slope,
            self.polytropic_index,
            self.ambient_pressure,
        ]
        return r


@nb.njit(cache=False)
def _law(p, h):  # pragma: no cover - compiled
    """(gauge pressure [Pa], force [N]) of the air spring with parameter row ``p`` at ``h``."""
    d = h - p[2]
    area = p[5] + p[6] * d
    if area < 0.0:
        area = 0.0
    vol = p[4] + p[5] * d + 0.5 * p[6] * d * d
    vmin = _MIN_VOLUME * p[4]
    if vol < vmin:
        vol = vmin
    gauge = p[3] * math.pow(p[4] / vol, p[7]) - p[8]
    return gauge, gauge * area


def _build_callbacks():
    """Compile the passive-force and sensor callbacks (once per process, on first use)."""

    @nb.cfunc(types.void(types.voidptr, types.voidptr), nopython=True, cache=False)
    def _passive(m, d):  # pragma: no cover - compiled, runs inside mj_step
        ctx = nb.carray(_as_pointer(_CTX_ADDR), (16,), dtype=np.int64)
        n = ctx[0]
        if n == 0:
            return
        par = nb.carray(_as_pointer(ctx[1]), (MAX_AIR_SPRINGS, _NPAR), dtype=np.float64)
        length = nb.carray(_as_pointer(ctx[2]), (ctx[9],), dtype=np.float64)
        jac = nb.carray(_as_pointer(ctx[3]), (ctx[10],), dtype=np.float64)
        qfrc = nb.carray(_as_pointer(ctx[4]), (ctx[11],), dtype=np.float64)
        rownnz = nb.carray(_as_pointer(ctx[6]), (ctx[9],), dtype=np.int32)
        rowadr = nb.carray(_as_pointer(ctx[7]), (ctx[9],), dtype=np.int32)
        colind = nb.carray(_as_pointer(ctx[8]), (ctx[10],), dtype=np.int32)
        for c in range(n):
            p = par[c]
            t = int(p[0])
            _, force = _law(p, length[t])
            a = rowadr[t]
            for k in range(rownnz[t]):
                qfrc[colind[a + k]] += jac[a + k] * force

    @nb.cfunc(types.void(types.voidptr, types.voidptr, types.intc), nopython=True, cache=False)
    def _sensor(m, d, stage):  # pragma: no cover - compiled, runs inside mj_step
        ctx = nb.carray(_as_pointer(_CTX_ADDR), (16,), dtype=np.int64)
        n = ctx[0]
        if n == 0 or stage != 1:  # mjSTAGE_POS
            return
        par = nb.carray(_as_pointer(ctx[1]), (MAX_AIR_SPRINGS, _NPAR), dtype=np.float64)
        length = nb.carray(_as_pointer(ctx[2]), (ctx[9],), dtype=np.float64)
        sens = nb.carray(_as_pointer(ctx[5]), (ctx[12],), dtype=np.float64)
        for c in range(n):
            p = par[c]
            adr = int(p[1])
            if adr >= 0:
                gauge, _ = _law(p, length[int(p[0])])
                sens[adr] = gauge

    return _passive, _sensor


_CALLBACKS = None
_LIVE = None


def install(model: mujoco.MjModel, data: mujoco.MjData, springs) -> np.ndarray | None:
    """Point the global passive and sensor callbacks at ``data`` for ``springs``.

    ``springs``: sequence of (AirSpring, tendon id, sensor address or -1). Nothing to do (and
    the callbacks stay idle) for none. Returns the parameter buffer (kept alive here too).
    """
    global _CALLBACKS, _LIVE
    n = len(springs)
    if n == 0:
        _CTX[0] = 0
        return None
    if n > MAX_AIR_SPRINGS:
        raise ValueError(f"at most {MAX_AIR_SPRINGS} air springs are supported, got {n}")
    params = np.zeros((MAX_AIR_SPRINGS, _NPAR))
    for c, (spring, tendon_id, sensor_adr) in enumerate(springs):
        params[c] = spring.row(tendon_id, sensor_adr)
    _CTX[:] = 0
    _CTX[1:9] = [
        params.ctypes.data,
        data.ten_length.ctypes.data,
        data.ten_J.ctypes.data,
        data.qfrc_passive.ctypes.data,
        data.sensordata.ctypes.data,
        model.ten_J_rownnz.ctypes.data,
        model.ten_J_rowadr.ctypes.data,
        model.ten_J_colind.ctypes.data,
    ]
    _CTX[9:13] = [model.ntendon, data.ten_J.size, model.nv, model.nsensordata]
    _CTX[0] = n
    if _CALLBACKS is None:
        _CALLBACKS = _build_callbacks()
        mujoco.set_mjcb_passive(_CALLBACKS[0].ctypes)
        mujoco.set_mjcb_sensor(_CALLBACKS[1].ctypes)
    _LIVE = params  # the callbacks read it through a raw pointer: keep it alive
    return params


def uninstall() -> None:
    """Disable the callbacks (they return at once while no air spring is installed)."""
    _CTX[0] = 0
