"""A rig backed by a MuJoCo model: drives in, sampled transducer responses out.

``run(drive)``: the drive (at the DAQ rate fs) is checked against the rig's limits, linearly
interpolated to the physics rate, and played through ``mujoco.rollout`` with the servo-hydraulic
control callback; the physics-rate sensor signals then pass through the transducer/DAQ chain
(:mod:`vrig.rigs.daq`). Long drives are played in chunks (``chunk_seconds``) that carry the whole
state across — MuJoCo's full physics state and solver warm start, the callback's states and
interlock record in ``mjData.userdata``, the DAQ filter states, the noise streams — so a run is
bit for bit the same in any chunking and only the sensors the DAQ samples are kept: memory does
not grow with the record length. As a real rig's interlock stops the rig, a run stops at the end
of the chunk in which its first interlock trip (stroke, force, following error) happened and
raises :class:`~vrig.errors.RigLimitError`; MuJoCo warnings or non-finite states detected up to
there raise :class:`~vrig.errors.SimulationInstabilityError` instead (see :meth:`MujocoRig.run`).
"""

from __future__ import annotations

import dataclasses
import math
import os
import queue
import sys
import threading
import warnings
from concurrent.futures import ThreadPoolExecutor, as_completed
from functools import partial
from pathlib import Path

import mujoco
import numpy as np
from mujoco import rollout
from scipy.signal import sosfilt

from ..errors import RigLimitError, RigModelError, RigParameterError, SimulationInstabilityError
from ..progress import RUN_BAR_DELAY_S, bar
from ..signals import flicker_sos
from ..timehistory import TimeHistory
from . import damper, gas_spring, hydraulics, maxwell, stability
from ._callbacks import MAX_LIVE, foreign_callbacks_suspended
from .daq import Acquisition
from .limits import check_drive_limits
from .spec import (
    ChannelSpec,
    InputDef,
    OutputDef,
    RigDefaults,
    RigDescription,
    check_outputs_for_rate,
    check_severity,
    read_description,
)

__all__ = ["FAST_MARGIN", "MAX_BATCH_THREADS", "MujocoRig", "collidable"]

_STATE = mujoco.mjtState.mjSTATE_FULLPHYSICS
_MAX_DECIMATION = 10_000  # physics steps per DAQ sample
_ELEMENTS = ("joint", "body", "geom", "site", "actuator", "tendon", "equality", "sensor")

MAX_BATCH_THREADS = 8
"""Most worker threads of :meth:`MujocoRig.run_batch` (each holds one live callback context and
one ``MjData`` clone of the rig)."""

_DATA_LOCK = threading.Lock()  # guards every rig's record of the MjData in use (brief holds)

FAST_MARGIN = 0.8
"""``fidelity="fast"`` runs at most at this fraction of the model's explicit-integration
stability limit (:mod:`vrig.rigs.stability`): the stiffest mode then decays by a clear factor per
step instead of hovering at the edge, and a parameter override that stiffens the model by up to
~50 % (the limit scales with 1/ω) still leaves it stable."""


class MujocoRig:
    """A virtual test rig from an MJCF model and its side-car description.

    Parameters
    ----------
    description : path or RigDescription
        The ``*.rig.json`` side-car file.
    seed : int
        Seed of the rig's noise generator (transducer noise, valve noise, mains phase). Runs
        without their own seed draw successive streams from it, like repeated runs of a real
        rig; ``run(drive, seed=s)`` is reproducible bit for bit.
    fidelity : {"full", "fast"}
        ``"full"`` (default) uses the documented timestep. ``"fast"`` (for short exploratory
        runs and learning) uses the side-car's ``fast_physics_rate``, else the largest timestep
        up to twice the documented one that the DAQ rate divides and that stays within
        :data:`FAST_MARGIN` of the model's explicit-integration stability limit
        (:attr:`stability_limit`).
    variant : str, optional
        A named parameter set of the side-car's ``"variants"`` (e.g. a calibration); ``None``
        (default): the side-car's ``default_variant``; ``"mild"``: the documented parameter
        values. Each value is checked against its parameter's range; explicit ``overrides``
        win over the variant's values.
    severity : float, optional
        The non-linearity severity in [0, 2] (side-car ``"severity"``,
        :class:`~vrig.rigs.spec.Severity`): scales the rig's non-linear elements *after* the
        variant and the overrides — 0 the linearised rig, 1 (``None``, default) the rig as
        loaded, 2 twice as non-linear. A rig without a severity axis (a linear rig) refuses
        it with :class:`~vrig.errors.RigParameterError`.
    spec_edit : callable, optional
        ``spec_edit(spec)``: edits the :class:`mujoco.MjSpec` after the parameters are applied
        and before it is compiled (e.g. :mod:`vrig.service` mounts the specimen in its service
        environment with it); it may raise :class:`~vrig.errors.RigModelError`.
    **overrides
        Documented parameters (see :meth:`describe`).

    Attributes
    ----------
    timestep : float
        Physics timestep of this fidelity [s]; ``decimation`` physics steps per DAQ sample.
    stability_limit : float
        Largest timestep [s] at which the linearised model (its springs, dampers and oil
        columns, :mod:`vrig.rigs.stability`) does not grow; a documented timestep beyond it
        gives a ``RuntimeWarning`` at load.
    overrides : dict
        The parameter overrides given (``**overrides``), as given.

    Raises
    ------
    RigModelError
        The model does not compile, its physics rate is not a multiple of fs, or the side-car's
        ``fast_physics_rate`` is not a multiple of fs or lies beyond the stability margin.
    """

    chunk_seconds = 1.0
    """Default simulated seconds per chunk of :meth:`run` (memory: about 1 kB per physics step
    of a chunk on the 7-channel rig); a run that trips an interlock stops at the end of the
    trip's chunk."""

    def __init__(
        self,
        description,
        *,
        seed: int = 0,
        fidelity: str = "full",
        variant: str | None = None,
        severity: float | None = None,
        spec_edit=None,
        **overrides,
    ):
        desc = (
            description
            if isinstance(description, RigDescription)
            else read_description(description)
        )
        if fidelity not in ("full", "fast"):
            raise ValueError(f"fidelity must be 'full' or 'fast', got {fidelity!r}")
        if not isinstance(seed, (int, np.integer)) or isinstance(seed, bool) or seed < 0:
            raise ValueError(f"seed must be a non-negative integer, got {seed!r}")
        unknown = set(overrides) - set(desc.parameters)
        if unknown:
            raise RigParameterError(
                f"unknown parameter(s) {sorted(unknown)} for rig {desc.name!r}; documented "
                f"parameters: {sorted(desc.parameters)}",
                key=", ".join(sorted(unknown)),
                allowed=", ".join(sorted(desc.parameters)),
            )
        if variant is not None and variant not in desc.variants:
            raise RigParameterError(
                f"unknown variant {variant!r} for rig {desc.name!r}; variants: "
                f"{sorted(desc.variants)}",
                key="variant",
                value=variant,
                allowed=", ".join(sorted(desc.variants)),
            )
        self._desc = desc
        self.overrides = dict(overrides)  # as given (a field twin rebuilds the rig from them)
        self.fidelity = fidelity
        self.variant = desc.default_variant if variant is None else variant
        chosen = desc.variants[self.variant].values if self.variant in desc.variants else {}
        chosen = {**chosen, **overrides}  # explicit overrides win over the variant's values
        self.parameters = {
            k: (p.check(chosen[k]) if k in chosen else p.value) for k, p in desc.parameters.items()
        }
        self.severity = self._severity(severity)
        if severity is not None:
            self.parameters = desc.severity.apply(self.parameters, self.severity, desc.parameters)
        try:
            spec = mujoco.MjSpec.from_file(str(desc.mjcf))
        except ValueError as exc:
            raise RigModelError(f"{desc.mjcf}: MuJoCo could not read the model: {exc}") from exc
        self._inputs, self._outputs = list(desc.inputs), list(desc.outputs)
        self._air = list(
            desc.air_springs
        )  # gas springs (vrig.rigs.gas_spring), parameter rules may change them
        self._dampers = list(desc.dampers)  # hydraulic dampers (vrig.rigs.damper), likewise
        self._maxwell = list(desc.maxwell)  # rubber Maxwell chains (vrig.rigs.maxwell), likewise
        for name, value in self.parameters.items():
            self._apply(spec, desc.parameters[name], value)
        self._realise_dampers(spec)
        if spec_edit is not None:
            spec_edit(spec)
        n_hyd = sum(1 for c in self._inputs if c.hydraulic is not None)
        spec.nuserdata = max(spec.nuserdata, 8 + 8 * n_hyd)
        documented, ratio = self._compile(spec)
        self.timestep = self._choose_timestep(documented, round(ratio))
        self.model.opt.timestep = self.timestep
        # a blow-up must not reset the data: the interlock record and the time stay (see run)
        self.model.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_AUTORESET)
        self.decimation = round(1.0 / (desc.fs * self.timestep))
        self._presettle()
        self._rng = np.random.default_rng(seed)
        self.seed = seed
        self._clones: list = []  # MjData clones for run_batch's threads (made on first use)
        self._busy: set = set()  # ids of the MjData a run is using (calls may overlap)

    # ------------------------------------------------------------------ set-up
    def _compile(self, spec) -> tuple[float, float]:
        """Compile ``spec``, make the data, bind the channels and find the stability limit, with
        every foreign MuJoCo callback suspended (:func:`~vrig.rigs._callbacks.
        foreign_callbacks_suspended`); returns the documented timestep [s] and fs x timestep."""
        desc = self._desc
        with foreign_callbacks_suspended(
            hydraulics.CONTROL, gas_spring.PASSIVE, gas_spring.SENSOR, damper.ACT_DYN
        ):
            try:
                self.model = spec.compile()
            except ValueError as exc:
                raise RigModelError(
                    f"{desc.mjcf}: MuJoCo could not compile the model: {exc}"
                ) from exc
            if not collidable(self.model):  # exact: no contact can form, skip the search
                self.model.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_CONTACT)
            self.data = mujoco.MjData(self.model)
            documented = float(self.model.opt.timestep)
            ratio = 1.0 / (desc.fs * documented)
            if abs(ratio - round(ratio)) > 1e-6 or not 1 <= round(ratio) <= _MAX_DECIMATION:
                raise RigModelError(
                    f"{desc.name}: the physics rate {1 / documented:g} Hz must be an integer "
                    f"multiple (1..{_MAX_DECIMATION}) of fs = {desc.fs:g} Hz"
                )
            self._bind()
            self.stability_limit, self._stiffest = self._stability()
        return documented, ratio

    def _severity(self, severity) -> float | None:
        """The checked severity: None for a linear rig, 1.0 when not given."""
        desc = self._desc
        if desc.severity is None:
            if severity is not None:
                raise RigParameterError(
                    f"rig {desc.name!r} has no severity axis (no non-linear element in its "
                    'operating range is declared in its side-car\'s "severity"); rigs with one: '
                    "see vrig.rigs.severity_rigs()",
                    key="severity",
                    value=severity,
                    allowed="None",
                )
            return None
        return 1.0 if severity is None else check_severity(severity, desc.name)

    def _apply(self, spec: mujoco.MjSpec, param, value) -> None:
        """Apply one parameter's rules; any failure is a RigModelError naming the parameter
        (a channel setting it makes invalid, e.g. a high-pass corner beyond fs/2, included)."""
        for rule in param.apply:
            try:
                self._apply_rule(spec, param, rule, value)
                check_outputs_for_rate(self._outputs, self._desc.fs, f"rule {rule}")
            except RigParameterError as exc:
                raise RigParameterError(
                    f"parameter {param.name!r} = {value!r}: {exc}", exc.key, exc.value, exc.allowed
                ) from None
            except RigModelError:
                raise
            except (AttributeError, TypeError, IndexError, KeyError, ValueError) as exc:
                raise RigModelError(
                    f"rig {self._desc.name!r}: parameter {param.name!r} = {value!r} cannot be "
                    f"applied by the rule {rule} ({type(exc).__name__}: {exc})"
                ) from None

    def _apply_rule(self, spec: mujoco.MjSpec, param, rule: dict, value) -> None:
        v = rule.get("map", {}).get(str(value).lower(), value) if "map" in rule else value
        if "scale" in rule:
            v = v * rule["scale"]
        if "input" in rule or "output" in rule:
            self._apply_channel(rule, v, param.name)
            return
        if "maxwell" in rule:
            i = next((k for k, c in enumerate(self._maxwell) if c.name == rule["maxwell"]), None)
            if i is None:
                raise RigModelError(
                    f"parameter {param.name!r}: no maxwell chain {rule['maxwell']!r}"
                )
            self._maxwell[i] = self._maxwell[i].with_branch(rule["field"], rule["index"], float(v))
            return
        if "air_spring" in rule or "damper" in rule:
            key, what, elements = (
                ("air_spring", "air spring", self._air) if "air_spring" in rule
                else ("damper", "damper", self._dampers)
            )  # fmt: skip
            i = next((k for k, a in enumerate(elements) if a.name == rule[key]), None)
            if i is None:
                raise RigModelError(f"parameter {param.name!r}: no {what} {rule[key]!r}")
            elements[i] = elements[i].replace(**{rule["field"]: float(v)})
            return
        kind = next((k for k in _ELEMENTS if k in rule), None)
        if kind is None:
            raise RigModelError(f"parameter {param.name!r}: rule {rule} names no element")
        element = getattr(spec, kind)(rule[kind])
        if element is None:
            raise RigModelError(f"parameter {param.name!r}: no {kind} named {rule[kind]!r}")
        attr = rule["attr"]
        current = getattr(element, attr)
        if rule.get("symmetric"):
            v = [-float(v), float(v)]
        if "index" in rule:
            arr = np.array(current, dtype=float)
            arr[rule["index"]] = v
            v = arr
        setattr(element, attr, v)

    def _realise_dampers(self, spec: mujoco.MjSpec) -> None:
        """Write the hydraulic dampers and the rubber's Maxwell chains (as the parameters left
        them) into ``spec`` (:func:`vrig.rigs.damper.realise`, :func:`vrig.rigs.maxwell.realise`)."""
        try:
            for d in self._dampers:
                damper.realise(spec, d)
            for chain in self._maxwell:
                maxwell.realise(spec, chain)
        except ValueError as exc:
            raise RigModelError(f"rig {self._desc.name!r}: {exc}") from None

    def _internal_state_elements(self) -> list:
        """The dampers and Maxwell branches whose internal node is advanced by the damper
        module's act_dyn hook (those without series compliance are skipped by its bind)."""
        return [*self._dampers, *(b for chain in self._maxwell for b in chain.branches())]

    def _apply_channel(self, rule, value, pname) -> None:
        if "input" in rule:
            i = next((k for k, c in enumerate(self._inputs) if c.spec.name == rule["input"]), None)
            if i is None:
                raise RigModelError(f"parameter {pname!r}: no input {rule['input']!r}")
            c = self._inputs[i]
            if "hydraulic" in rule:
                c = dataclasses.replace(
                    c, hydraulic=c.hydraulic.replace(**{rule["hydraulic"]: float(value)})
                )
            else:
                c = dataclasses.replace(c, **{rule["field"]: value})
            self._inputs[i] = c
        else:
            i = next(
                (k for k, c in enumerate(self._outputs) if c.spec.name == rule["output"]), None
            )
            if i is None:
                raise RigModelError(f"parameter {pname!r}: no output {rule['output']!r}")
            c = self._outputs[i]
            c = dataclasses.replace(
                c, transducer=dataclasses.replace(c.transducer, **{rule["transducer"]: value})
            )
            self._outputs[i] = c

    def _bind(self) -> None:
        m = self.model

        def actuator(name):
            i = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_ACTUATOR, name)
            if i < 0:
                raise RigModelError(f"{self.name}: the MJCF has no actuator {name!r}")
            return i

        self._hyd = []  # (parameters, cmd, noise, force actuator, qpos adr, dof adr) per hydraulic drive
        self._slots = []  # per drive: (ctrl column of the command, ctrl column its noise goes to)
        for c in self._inputs:
            if c.hydraulic is not None:
                j = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, c.joint or "")
                if j < 0:
                    raise RigModelError(
                        f"{self.name}: hydraulic input {c.spec.name!r} needs its piston joint"
                    )
                i_cmd, i_noise = actuator(c.actuator + "_cmd"), actuator(c.actuator + "_noise")
                self._hyd.append(
                    (
                        c.hydraulic,
                        i_cmd,
                        i_noise,
                        actuator(c.actuator + "_force"),
                        int(m.jnt_qposadr[j]),
                        int(m.jnt_dofadr[j]),
                    )
                )
                self._slots.append((i_cmd, i_noise))
            else:
                i_act = actuator(c.actuator)
                self._slots.append((i_act, i_act))
        self._air_bound = self._bind_air_springs(m)  # (AirSpring, tendon id, sensor adr or -1)
        try:
            # series compliance and Maxwell branches (act_dyn)
            self._damper_bound = damper.bind(m, self._internal_state_elements())
        except ValueError as exc:
            raise RigModelError(f"rig {self._desc.name!r}: {exc}") from None
        self._sensor_cols = []
        for o in self._outputs:
            s = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_SENSOR, o.sensor)
            if s < 0:
                raise RigModelError(f"{self.name}: the MJCF has no sensor {o.sensor!r}")
            if not 0 <= o.component < m.sensor_dim[s]:
                raise RigModelError(
                    f"{self.name}: sensor {o.sensor!r} has no component {o.component}"
                )
            self._sensor_cols.append(int(m.sensor_adr[s]) + o.component)
        key = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_KEY, "home")
        if key >= 0:
            mujoco.mj_resetDataKeyframe(m, self.data, key)
        else:
            mujoco.mj_resetData(m, self.data)
        self._state0 = np.empty(mujoco.mj_stateSize(m, _STATE))
        mujoco.mj_getState(m, self.data, self._state0, _STATE)

    def _bind_air_springs(self, m) -> list:
        """(AirSpring, tendon id, pressure sensor address or -1) per air spring of the rig."""
        bound = []
        for a in self._air:
            t = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_TENDON, a.tendon)
            if t < 0:
                raise RigModelError(f"{self.name}: air spring {a.name!r}: no tendon {a.tendon!r}")
            if m.tendon_stiffness[t] != 0:
                raise RigModelError(
                    f"{self.name}: air spring {a.name!r}: its tendon {a.tendon!r} must have no "
                    "stiffness of its own (the gas law is the spring)"
                )
            adr = -1
            if a.sensor is not None:
                s = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_SENSOR, a.sensor)
                if (
                    s < 0
                    or m.sensor_type[s] != mujoco.mjtSensor.mjSENS_USER
                    or (
                        m.sensor_dim[s] != 1 or m.sensor_needstage[s] != mujoco.mjtStage.mjSTAGE_POS
                    )
                ):
                    raise RigModelError(
                        f"{self.name}: air spring {a.name!r}: its sensor {a.sensor!r} must be an "
                        'MJCF <user dim="1" needstage="pos"/> sensor'
                    )
                adr = int(m.sensor_adr[s])
            bound.append((a, t, adr))
        return bound

    def _stability(self) -> tuple[float, list]:
        """The linearised model's explicit-integration stability limit [s] at the home pose and
        its three stiffest elements (:mod:`vrig.rigs.stability`)."""
        hyd_inputs = [c for c in self._inputs if c.hydraulic is not None]
        oil = [
            (c.spec.name, c.hydraulic.oil_stiffness, h[5])
            for c, h in zip(hyd_inputs, self._hyd, strict=True)
        ]
        elements = stability.stiff_elements(self.model, self.data, oil, self._air_rates())
        limit = stability.max_stable_timestep(self.model, self.data, elements)
        integrator = int(self.model.opt.integrator)
        return limit, sorted(elements, key=lambda e: e.limit(integrator))[:3]

    def _air_rates(self) -> list:
        """(name, small-signal rate [N/m], tendon Jacobian) of each air spring at the pose in
        ``self.data`` (the home pose): its linear part, for the stability limit."""
        if not self._air_bound:
            return []
        m, d = self.model, self.data
        mujoco.mj_forward(m, d)
        jac = np.zeros((m.ntendon, m.nv))
        mujoco.mju_sparse2dense(jac, d.ten_J, m.ten_J_rownnz, m.ten_J_rowadr, m.ten_J_colind)
        return [
            (f"air spring {a.name!r}", float(a.rate_at(d.ten_length[t])), jac[t].copy())
            for a, t, _ in self._air_bound
        ]

    def _stiffest_text(self) -> str:
        return ", ".join(f"{e.name} {e.frequency:.0f} Hz" for e in self._stiffest)

    def _choose_timestep(self, documented: float, full_decimation: int) -> float:
        """The physics timestep of the fidelity (see :data:`FAST_MARGIN`)."""
        limit, fs = self.stability_limit, self.fs
        if documented > limit:
            warnings.warn(
                f"{self.name}: the physics timestep {documented * 1e3:g} ms exceeds the "
                f"explicit-integration stability limit {limit * 1e3:.4g} ms of the model "
                f"(stiffest: {self._stiffest_text()}): runs will blow up or carry numerical "
                "noise; reduce the timestep, or soften or damp that element",
                RuntimeWarning,
                stacklevel=4,
            )
        if self.fidelity == "full":
            return documented
        rate = self._desc.fast_physics_rate
        if rate is None:  # the largest timestep up to twice the documented one that is safe
            for k in range(math.ceil(full_decimation / 2), full_decimation):
                if 1.0 / (fs * k) <= FAST_MARGIN * limit:
                    return 1.0 / (fs * k)
            return documented
        k = round(rate / fs)
        if abs(rate / fs - k) > 1e-9 * k or not 1 <= k <= full_decimation:
            raise RigModelError(
                f"{self._desc.path}: fast_physics_rate {rate:g} Hz must be an integer multiple of "
                f"fs = {fs:g} Hz and at most the documented physics rate {1 / documented:g} Hz"
            )
        if 1.0 / rate > max(documented, FAST_MARGIN * limit):
            raise RigModelError(
                f"{self._desc.path}: fast_physics_rate {rate:g} Hz (timestep {1e3 / rate:.4g} ms) "
                f"is beyond {FAST_MARGIN:g} x the stability limit {limit * 1e3:.4g} ms of the "
                f"model (stiffest: {self._stiffest_text()}); use at least "
                f"{1 / (FAST_MARGIN * limit):.0f} Hz"
            )
        return 1.0 / rate

    def _install_elements(self, d: mujoco.MjData) -> None:
        """Register ``d`` with the compiled element callbacks: the air springs (passive force,
        pressure sensors) and the dampers' series compliance (activation dynamics)."""
        gas_spring.install(self.model, d, self._air_bound)
        damper.install(self.model, d, self._damper_bound)

    def _presettle(self) -> None:
        """Start every run from static equilibrium: play ``settle_time`` of zero drive once
        (no noise) and keep the final mechanical state and servo-loop states, so no run begins
        with the rig sagging under gravity from its model pose."""
        self._hyd_states = None
        steps = round(self._desc.settle_time / self.timestep)
        if steps == 0:
            return
        m, d = self.model, self.data
        for w in d.warning:
            w.number = 0
        hydraulics.install(m, d, self._hyd, self.timestep)
        self._install_elements(d)
        try:
            state, _ = rollout.rollout(m, d, self._state0[None, :], np.zeros((1, steps, m.nu)))
        finally:
            hydraulics.uninstall(d)
            _uninstall_elements(d)
        if hydraulics.trip_record(d) is not None or any(w.number for w in d.warning):
            raise RigModelError(f"{self.name}: the rig does not settle under gravity at rest")
        self._state0 = state[0, -1].copy()
        self._state0[0] = 0.0  # time
        self._hyd_states = hydraulics.channel_states(d, len(self._hyd))

    # ------------------------------------------------------------------ public
    @property
    def name(self) -> str:
        """The rig's name (from its side-car description)."""
        return self._desc.name

    @property
    def fs(self) -> float:
        """DAQ sample rate [Hz] of drives and responses."""
        return self._desc.fs

    @property
    def inputs(self) -> tuple[ChannelSpec, ...]:
        """The drive channels (name, unit, full scale), in drive column order."""
        return tuple(c.spec for c in self._inputs)

    @property
    def outputs(self) -> tuple[ChannelSpec, ...]:
        """The response channels (name, unit, full scale), in response column order."""
        return tuple(c.spec for c in self._outputs)

    @property
    def bandwidth(self) -> tuple[float, float]:
        """The rig's test band [Hz] (from the reference text)."""
        return self._desc.bandwidth

    @property
    def input_defs(self) -> tuple[InputDef, ...]:
        """The side-car definitions of the drive channels (actuator, limits...)."""
        return tuple(self._inputs)

    @property
    def output_defs(self) -> tuple[OutputDef, ...]:
        """The side-car definitions of the response channels (sensor, transducer...)."""
        return tuple(self._outputs)

    @property
    def description(self) -> RigDescription:
        """The rig's parsed side-car description."""
        return self._desc

    @property
    def defaults(self) -> RigDefaults:
        """The rig's own defaults from its side-car (band, gain, gym id, tolerance); the same
        for every variant, severity and override."""
        return self._desc.defaults

    def describe(self) -> str:
        """What the rig is, its channels, limits and parameters, as text."""
        d = self._desc
        lines = [
            f"{d.name}: {d.title}",
            "",
            d.description.strip(),
            "",
            f"DAQ rate fs = {self.fs:g} Hz, physics timestep {self.timestep * 1e3:g} ms "
            f"({self.decimation} steps per sample, fidelity {self.fidelity!r}), "
            f"test band {d.bandwidth[0]:g}-{d.bandwidth[1]:g} Hz",
            f"explicit-integration stability limit {self.stability_limit * 1e3:.4g} ms "
            f"(stiffest: {self._stiffest_text()})",
            "",
            "drives:",
        ]
        for c in self._inputs:
            lines.append(f"  {c.spec}  {c.spec.description}")
            if c.hydraulic is not None:
                h = c.hydraulic
                lines.append(
                    f"      servo-hydraulic: A = {h.area * 1e4:g} cm², Ps = {h.supply_pressure / 1e6:g} MPa, "
                    f"velocity limit {h.velocity_limit:.3g} m/s, valve {h.valve_frequency:g} Hz, "
                    f"oil stiffness {h.oil_stiffness:.3g} N/m; interlocks: stroke ±{h.stroke:g} m, "
                    f"force ±{h.force_limit:g} N, following error ±{h.error_limit:g} m"
                )
        lines.append("responses:")
        for o in self._outputs:
            t = o.transducer
            extra = f", high-pass {t.highpass_hz:g} Hz" if t.highpass_hz else ""
            lines.append(
                f"  {o.spec}  noise {t.noise_rms:g} {o.spec.unit} rms{extra}  {o.spec.description}"
            )
        if d.variants:
            lines.append(
                f"variants (load_rig(name, variant=NAME); this one: {self.variant!r}, "
                f"default: {d.default_variant!r}):"
            )
            for vname, v in d.variants.items():
                vals = ", ".join(f"{k} = {val!r}" for k, val in v.values.items())
                lines.append(f"  {vname}: {v.description}" + (f" [{vals}]" if vals else ""))
        if d.severity is not None:
            scaled = ", ".join(f"{k} ({law})" for k, law in d.severity.scales.items())
            lines.append(
                f"severity (load_rig(name, severity=s), s in [0, 2]; this one: {self.severity:g}): "
                f"{d.severity.description} [scales {scaled}]"
            )
        if self.parameters:
            lines.append("parameters (override with load_rig(name, **{param: value})):")
            for k, p in d.parameters.items():
                lines.append(
                    f"  {k} = {self.parameters[k]!r} {p.unit}: {p.description} [{p.source}]"
                )
        if d.service:
            lines.append("service scenarios (field records: vrig reconstruct --target field:NAME):")
            lines.extend(f"  {k}: {v.get('description', '')}" for k, v in d.service.items())
        return "\n".join(lines)

    def __repr__(self) -> str:
        return f"<MujocoRig {self.name!r}: {len(self._inputs)} drives, {len(self._outputs)} responses, fs {self.fs:g} Hz>"

    # ------------------------------------------------------------------ running
    def _check_drive(self, drive) -> np.ndarray:
        n_in = len(self._inputs)
        if isinstance(drive, TimeHistory):
            if abs(drive.fs - self.fs) > 1e-9 * self.fs:
                raise ValueError(
                    f"drive is sampled at {drive.fs:g} Hz but rig {self.name!r} runs at fs = {self.fs:g} Hz; "
                    "resample it first (e.g. scipy.signal.resample_poly)"
                )
            expected = [c.spec.name for c in self._inputs]
            default = [f"ch{i + 1}" for i in range(drive.n_channels)]
            if list(drive.names) not in (expected, default):
                raise ValueError(
                    f"drive channels {list(drive.names)} do not match the rig's drives {expected}"
                )
            x = np.array(drive.data)
        else:
            x = np.asarray(drive, dtype=float)
            if x.ndim == 1 and n_in == 1:
                x = x[:, None]
        if x.ndim != 2 or x.shape[1] != n_in:
            raise ValueError(
                f"drive must have shape (N, {n_in}) for rig {self.name!r} "
                f"(drives {[c.spec.name for c in self._inputs]}), got {x.shape}"
            )
        if x.shape[0] < 2:
            raise ValueError("drive needs at least 2 samples")
        if not np.all(np.isfinite(x)):
            bad = np.argwhere(~np.isfinite(x))[0]
            raise ValueError(
                f"drive contains NaN or inf (first at sample {bad[0]}, channel {bad[1]})"
            )
        check_drive_limits(self.inputs, x, fs=self.fs)
        return x

    def run(
        self, drive, *, seed: int | None = None, chunk_seconds: float | None = None
    ) -> TimeHistory:
        """Play a drive on the rig and return the sampled responses.

        The drive is simulated in chunks of ``chunk_seconds``: each chunk starts from the full
        physics state (including the constraint solver's warm start), the servo callback's
        states and the DAQ filter states and noise streams where the previous one ended, so the
        result is bit for bit the same for any chunk length and memory does not grow with the
        record length (only the drive and the sampled response do).

        An interlock trip stops the run, as it stops a real rig: the trip record (stroke, force,
        following error, checked every physics step) is read after each chunk, and no chunk is
        simulated after the one in which the first trip happened. The error is then, in this
        order of precedence:

        1. :class:`~vrig.errors.SimulationInstabilityError` if a MuJoCo warning or a non-finite
           value (sensor, or after the transducer chain) was detected in the part played, i.e.
           before the trip or after it within the trip's chunk (a blow-up usually trips an
           interlock first: the trip is its symptom). An instability that would only have
           shown in a later chunk is not reached: the trip is reported;
        2. :class:`~vrig.errors.RigLimitError` of the first trip: its kind, channel, time and
           value, which do not depend on the chunk length (the run up to the trip is the same
           bit for bit in any chunking);
        3. :class:`~vrig.errors.RigLimitError` of the first response channel beyond its
           transducer range, at its first sample beyond it (this check does not stop the run:
           without a trip the whole drive is played, so any chunking gives the same error).

        The error is the same for any chunk length unless an instability follows the first
        trip: it is reported if it shows within the trip's chunk (with ``math.inf``: anywhere
        in the drive), else the trip is.

        Parameters
        ----------
        drive : TimeHistory or array (N, n_inputs)
            Drive signals at the rig's fs, in the drive channels' units.
        seed : int, optional
            Noise seed for this run; default: the next stream of the rig's generator.
        chunk_seconds : float, optional
            Simulated seconds per chunk (rounded to whole DAQ samples, at least one); default
            :attr:`chunk_seconds`; ``math.inf``: the whole record in one piece.

        Raises
        ------
        ValueError
            wrong shape, sample rate or channel names; NaN; a chunk length that is not a
            positive number.
        RigLimitError
            a drive beyond full scale (not sent), an interlock trip during the run (the run
            stopped at the end of the trip's chunk) or a response beyond its transducer range.
        SimulationInstabilityError
            a MuJoCo warning or a non-finite state in the part played (before the first trip or
            within its chunk): it takes precedence over the trip.
        """
        x = self._check_drive(drive)
        chunk = self._chunk_samples(chunk_seconds)
        streams = self._streams(seed)
        (d,) = self._take_data(1)  # the rig's own, unless another call is using it
        try:
            return self._responses(self._play(x, chunk, *streams, d))
        finally:
            self._give_data([d])

    def _streams(self, seed):
        """The run's (valve noise, DAQ) generators: from ``seed``, else from the next stream of
        the rig's generator (independent streams: chunking cannot interleave them)."""
        rng = (
            np.random.default_rng(seed)
            if seed is not None
            else np.random.default_rng(self._rng.integers(2**63))
        )
        return rng.spawn(2)

    def _responses(self, data: np.ndarray) -> TimeHistory:
        return TimeHistory(
            data,
            self.fs,
            [o.spec.name for o in self._outputs],
            [o.spec.unit for o in self._outputs],
        )

    def run_batch(
        self,
        drives,
        *,
        seeds=None,
        threads: int | None = None,
        chunk_seconds: float | None = None,
        return_exceptions: bool = False,
        then=None,
    ) -> list:
        """Play many drives at once across threads; result ``i`` is bit for bit
        ``run(drives[i], seed=seeds[i], chunk_seconds=chunk_seconds)``, errors included: a
        drive that trips an interlock stops at the end of the trip's chunk (its error as in
        :meth:`run`) and its thread goes on with the next drive, the other runs unaffected.

        Every drive is checked (shape, NaN, limits) before anything is simulated. Each thread
        plays its drives one after another on its own ``MjData`` (the rig's own and clones of
        it, made on first use and kept, each with its own callback context installed per run
        and removed after it, and its own transducer chain), through the same code as
        :meth:`run`; ``mujoco.rollout`` releases the GIL while it steps. It is not one
        ``mujoco.rollout`` call over all drives because the servo-hydraulic states, the step
        counter and the trip record live in each ``mjData.userdata``, which rollout's initial
        state (``mjSTATE_FULLPHYSICS``) does not include, while rollout hands its items to
        threads dynamically so one ``MjData`` would carry its userdata from one drive into the
        next. Nor does rollout return each item's final solver warm start, which the next chunk
        of a long run needs to stay bit for bit the same as one piece.

        Parameters
        ----------
        drives : sequence of TimeHistory or array (N, n_inputs)
            The drives, as for :meth:`run` (their lengths may differ).
        seeds : sequence of int or None, optional
            One noise seed per drive (None in a slot, or ``seeds=None``: that drive takes the
            next stream of the rig's generator, in drive order, exactly as successive
            :meth:`run` calls would; a refused drive takes none, as in :meth:`run`).
        threads : int, optional
            Worker threads, 1 to :data:`MAX_BATCH_THREADS`; default ``min(len(drives),
            os.cpu_count(), MAX_BATCH_THREADS)``; 1 plays in the calling thread.
        chunk_seconds : float, optional
            Simulated seconds per chunk, as for :meth:`run`.
        return_exceptions : bool
            False (default): after every drive has finished, raise the exception of the first
            failing drive (lowest index). True: return each failure in its slot instead (like
            ``asyncio.gather``).
        then : callable, optional
            ``then(i, response)``, called in the worker thread as soon as drive ``i`` has
            played (not for a failed drive): its return value takes slot ``i`` (an exception
            it raises does, as a failing drive's). The work that follows each run (processing,
            scoring) then overlaps the other threads' runs instead of waiting for the whole
            batch; ``then`` must be safe to call from several threads at once.

        Returns
        -------
        list of TimeHistory (or Exception, with ``return_exceptions=True``)
            One per drive, in drive order (``then``'s values with ``then``).

        Raises
        ------
        ValueError
            bad ``seeds``, ``threads`` or ``chunk_seconds``; a drive's own errors as in
            :meth:`run` (``ValueError``, ``RigLimitError``, ``SimulationInstabilityError``).
        """
        drives = list(drives)
        if then is not None and not callable(then):
            raise TypeError(f"then must be callable or None, got {type(then).__name__}")
        seeds = _batch_seeds(seeds, len(drives))
        workers = _batch_threads(threads, len(drives))
        chunk = self._chunk_samples(chunk_seconds)
        results: list = [None] * len(drives)
        jobs = []
        for i, (drive, seed) in enumerate(zip(drives, seeds, strict=True)):
            try:
                x = self._check_drive(drive)
            except Exception as exc:  # the drive's own error, in its slot (run raises it)
                results[i] = exc
                continue
            jobs.append((i, x, *self._streams(seed)))
        self._play_jobs(jobs, chunk, min(workers, max(len(jobs), 1)), results, then)
        if not return_exceptions:
            failed = next((r for r in results if isinstance(r, BaseException)), None)
            if failed is not None:
                raise failed
        return results

    def _play_jobs(self, jobs, chunk: int, workers: int, results: list, then=None) -> None:
        """Play ``jobs`` ((index, drive, valve rng, DAQ rng)) on ``workers`` threads, each on a
        free ``MjData`` of the pool; store each response (or ``then(index, response)``, or the
        exception) at its index. An
        interrupt (Ctrl-C) or error in the calling thread stops the workers after their current
        chunk and waits for them (their contexts removed) before it goes on."""
        shown = bar(len(jobs), desc=f"{self.name}: batch of {len(jobs)} runs", unit="run",
                    delay=RUN_BAR_DELAY_S)  # fmt: skip
        try:
            if workers <= 1:  # in the calling thread, on the rig's own data (if free)
                (d,) = self._take_data(1)
                try:
                    for i, x, valve_rng, daq_rng in jobs:
                        try:
                            out = self._responses(self._play(x, chunk, valve_rng, daq_rng, d))
                            results[i] = out if then is None else then(i, out)
                        except Exception as exc:
                            results[i] = exc
                        shown.update(1)
                finally:
                    self._give_data([d])
                return
            self._play_threaded(jobs, chunk, workers, results, shown, then)
        finally:
            shown.close()

    def _play_threaded(self, jobs, chunk: int, workers: int, results: list, shown, then) -> None:
        """:meth:`_play_jobs` on ``workers`` threads. Whatever happens in the calling thread
        (Ctrl-C lands there), it returns only once no run is active any more: the executor's
        own shutdown cannot be trusted for that (an interrupt inside ``submit`` can start a
        worker thread that it never records, and never joins)."""
        free, taken = queue.SimpleQueue(), self._take_data(workers)
        for d in taken:
            free.put(d)
        cancel, state, active = threading.Event(), threading.Condition(), [0]

        def play(i, x, valve_rng, daq_rng):
            with state:
                if cancel.is_set():
                    raise _Cancelled
                active[0] += 1
            try:
                d = free.get()  # as many data as threads: one is always free
                try:
                    out = self._responses(
                        self._play(x, chunk, valve_rng, daq_rng, d, cancel=cancel)
                    )
                finally:
                    free.put(d)
                return out if then is None else then(i, out)
            finally:
                with state:
                    active[0] -= 1
                    state.notify_all()

        pool = ThreadPoolExecutor(workers, thread_name_prefix=f"vrig-{self.name}")
        try:
            futures = {pool.submit(play, *job): job[0] for job in jobs}
            for f in as_completed(futures):
                exc = f.exception()
                results[futures[f]] = f.result() if exc is None else exc
                shown.update(1)
        finally:
            with state:  # no run starts from here on; the active ones stop after their chunk
                cancel.set()
                state.wait_for(lambda: active[0] == 0)
            pool.shutdown(wait=True, cancel_futures=True)
            self._give_data(taken)

    def _take_data(self, n: int) -> list:
        """``n`` MjData no other run is using, marked as in use: the rig's own first, then
        clones (made on first use and kept, each in the presettled state). Every run starts
        from the presettled state whatever data it is on, so overlapping :meth:`run` /
        :meth:`run_batch` calls (from different threads) each play on their own data."""
        with _DATA_LOCK:
            taken = [d for d in (self.data, *self._clones) if id(d) not in self._busy][:n]
            while len(taken) < n:
                d = mujoco.MjData(self.model)
                mujoco.mj_setState(self.model, d, self._state0, _STATE)
                self._clones.append(d)
                taken.append(d)
            self._busy.update(id(d) for d in taken)
        return taken

    def _give_data(self, taken: list) -> None:
        """Mark the data of :meth:`_take_data` free again."""
        with _DATA_LOCK:
            self._busy.difference_update(id(d) for d in taken)

    def _chunk_samples(self, chunk_seconds) -> int:
        value = self.chunk_seconds if chunk_seconds is None else chunk_seconds
        ok = isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(
            value, bool
        )
        if not ok or not value > 0:
            raise ValueError(
                f"chunk_seconds must be a positive number of seconds (math.inf: one chunk), "
                f"got {chunk_seconds!r}"
            )
        return sys.maxsize if math.isinf(value) else max(1, round(value * self.fs))

    def _play(self, x, chunk: int, valve_rng, daq_rng, data=None, *, cancel=None) -> np.ndarray:
        """Simulate the settling period and the drive ``x`` in chunks of ``chunk`` DAQ samples
        on ``data`` (default :attr:`data`; :meth:`run_batch` passes each thread's clone): from
        the presettled state ``_state0`` and callback states ``_hyd_states``, its callback
        context installed for the run and removed after, whatever happens. Returns the sampled
        responses of the drive period (errors: see :meth:`run`); the trip record is read after
        each chunk and the run stops after the chunk of the first trip (its stability and
        transducer-chain checks made first: they take precedence); ``cancel``: an event checked
        after each chunk (set: :class:`_Cancelled` is raised)."""
        m, dec = self.model, self.decimation
        d = self.data if data is None else data
        # the one-argument form for the rig's own data (a test hooks ``_check_stability``)
        check = self._check_stability if d is self.data else partial(self._check_stability, d=d)
        n, settle = x.shape[0], round(self._desc.settle_time * self.fs)  # settle: zero drive
        total = settle + n
        full = np.array([o.spec.full_scale for o in self._outputs])
        # the transducer and anti-alias filters run through the settling period too (as on a
        # real rig, where they are powered before the test): no start-up transient from DC
        chain = Acquisition(
            [o.transducer for o in self._outputs], full, fs=self.fs, decimation=dec,
            aa=self._desc.anti_alias, rng=daq_rng,
        )  # fmt: skip
        out = np.empty((n, len(self._outputs)))
        t_drive = np.arange(n) * dec
        steps = min(chunk, total) * dec
        state_buf = np.empty((1, steps, self._state0.size))
        sens_buf = np.empty((1, steps, m.nsensordata))
        state, warm, trip = self._state0, None, None
        over = {}  # channel -> (first sample beyond the transducer range, value)
        noise = (valve_rng, self._control_noise(valve_rng))  # valve, controller
        hydraulics.install(m, d, self._hyd, self.timestep, states=self._hyd_states)
        self._install_elements(d)
        shown = bar(total, desc=f"{self.name}: run {n / self.fs:g} s", unit="sample",
                    delay=RUN_BAR_DELAY_S)  # fmt: skip
        try:
            for k0 in range(0, total, chunk):
                k1 = min(k0 + chunk, total)
                ctrl = self._controls(x, t_drive, k0 * dec, k1 * dec, settle * dec, noise)
                k = (k1 - k0) * dec
                _, sens = rollout.rollout(
                    m,
                    d,
                    state[None, :],
                    ctrl,
                    initial_warmstart=warm,
                    state=state_buf[:, :k],
                    sensordata=sens_buf[:, :k],
                )
                raw = sens[0][:, self._sensor_cols]
                check(k0 * dec, raw)
                sampled = chain.process(raw)
                if not np.all(np.isfinite(sampled)):  # e.g. a huge transducer gain overflowed
                    raise SimulationInstabilityError(
                        f"{self.name}: non-finite response after the transducer chain (check "
                        "the transducer gains and noise levels)"
                    )
                if k1 > settle:  # the drive period (the settling samples are dropped)
                    lo = max(k0, settle)
                    out[lo - settle : k1 - settle] = sampled[lo - k0 :]
                    self._note_range(over, lo - settle, sampled[lo - k0 :], full)
                shown.update(k1 - k0)
                trip = hydraulics.trip_record(d)
                if trip is not None:  # the interlock stopped the rig: no further chunk
                    break
                state = np.empty(self._state0.size)
                mujoco.mj_getState(m, d, state, _STATE)
                warm = d.qacc_warmstart[None, :].copy()
                if cancel is not None and cancel.is_set():
                    raise _Cancelled
        finally:
            shown.close()
            hydraulics.uninstall(d)
            _uninstall_elements(d)
        if trip is not None:
            raise self._trip_error(trip, settle * dec)
        if over:  # the transducer-range interlock: the first channel, at its first sample
            j = min(over)
            o = self._outputs[j].spec
            raise RigLimitError(
                "transducer range",
                o.name,
                over[j][0] / self.fs,
                over[j][1],
                full[j],
                o.unit,
                hint="The response is beyond the transducer's range: reduce the drive.",
            )
        return out

    def _control_noise(self, rng):
        """The run's command/feedback-path flicker noise source, or None where every level is
        0 (then ``rng`` is left untouched: runs without it stay bit for bit): a child of the
        valve-noise generator (the valve noise stream is the same with or without it), the
        causal flicker filter of each noisy drive at the physics rate (``flicker_sos``, gains
        to each level) and its state, warmed up over five time constants of its lowest pole so
        the run starts in the noise's steady state. Drawn per physics step, chunk by chunk."""
        levels = np.array([c.control_noise_rms for c in self._inputs])
        if not np.any(levels > 0):
            return None
        child = rng.spawn(1)[0]
        rate = 1.0 / self.timestep
        state = []
        for j in np.flatnonzero(levels > 0):  # one filter per noisy drive, not per sample
            sos, rms = flicker_sos(self._inputs[j].control_noise_corner_hz, rate)
            warm = child.standard_normal(round(5 / (2 * np.pi * 0.1) * rate))
            _, zi = sosfilt(sos, warm, zi=np.zeros((sos.shape[0], 2)))
            state.append([int(j), sos, zi, levels[j] / rms])
        return child, state

    def _flicker(self, source, steps: int) -> list:
        """The next ``steps`` physics steps of each noisy drive's flicker noise (advances the
        filter states of ``source``): ``(drive index, values)`` per noisy drive."""
        child, state = source
        out = []
        for entry in state:
            j, sos, zi, gain = entry
            y, entry[2] = sosfilt(sos, child.standard_normal(steps), zi=zi)
            out.append((j, gain * y))
        return out

    def _controls(self, x, t_drive, g0: int, g1: int, settle_steps: int, noise) -> np.ndarray:
        """Controls of physics steps ``g0:g1`` of the run: the drive linearly interpolated to the
        physics rate after ``settle_steps`` of zero, plus valve or amplifier noise and the
        controller's flicker noise; ``noise`` = (the valve-noise generator, the flicker record
        at the DAQ rate with the settling period, or None)."""
        rng, flicker = noise
        ctrl = np.zeros((1, g1 - g0, self.model.nu))
        s = np.arange(g0, g1) - settle_steps
        noisy = [j for j, c in enumerate(self._inputs) if c.noise_rms > 0]
        noise = rng.standard_normal((g1 - g0, len(noisy))) if noisy else None
        for j, (c, (i_cmd, i_noise)) in enumerate(zip(self._inputs, self._slots, strict=True)):
            ctrl[0, :, i_cmd] = np.where(s >= 0, np.interp(s, t_drive, x[:, j]), 0.0)

            if c.noise_rms > 0:  # valve-command noise (hydraulic) or amplifier noise (direct)
                ctrl[0, :, i_noise] += c.noise_rms * noise[:, noisy.index(j)]
        if flicker is not None:  # the controller's noise, on the command: the loop follows it
            for j, values in self._flicker(flicker, g1 - g0):
                ctrl[0, :, self._slots[j][0]] += values
        return ctrl

    def _check_stability(self, g0: int, raw, d=None) -> None:
        """Raise SimulationInstabilityError if the chunk that starts at physics step ``g0`` of
        the run on ``d`` (default :attr:`data`) blew up: a MuJoCo warning (``mujoco.rollout``
        stops stepping at the first one; the rig's auto-reset is off, so the time says where)
        or a non-finite sensor value."""
        d = self.data if d is None else d
        counts = d.warning.number
        finite = np.isfinite(raw.sum())  # one pass: NaN and inf propagate into the sum
        if finite and not counts.any():
            return
        warned = [(mujoco.mjtWarning(i).name, int(c)) for i, c in enumerate(counts) if c]
        bad = ~np.all(np.isfinite(raw), axis=1)
        if not warned and not bad.any():  # the sum overflowed, the values did not
            return
        step = round(d.time / self.timestep) - 1 if warned else sys.maxsize
        if bad.any():
            step = min(step, g0 + int(np.argmax(bad)))
        t = step * self.timestep - self._desc.settle_time
        what = (
            f"MuJoCo reported {warned} during the run"
            if warned
            else "non-finite sensor values during the run"
        )
        raise SimulationInstabilityError(
            f"{self.name}: {what} (t = {t:.4f} s); the model became unstable for this drive "
            "(reduce its amplitude, or check the model's timestep)"
        )

    @staticmethod
    def _note_range(over: dict, i0: int, sampled, full) -> None:
        """Record in ``over`` each channel's first sample beyond its transducer range among
        ``sampled`` (samples ``i0`` on of the drive period), unless it has one already."""
        beyond = np.abs(sampled) > full
        for j in np.flatnonzero(beyond.any(axis=0)):
            if j not in over:
                i = int(np.argmax(beyond[:, j]))
                over[int(j)] = (i0 + i, float(sampled[i, j]))

    def _trip_error(self, trip, settle_steps: int) -> RigLimitError:
        kind, c, step, value, limit = trip
        spec = [cc for cc in self._inputs if cc.hydraulic is not None][c].spec
        t = (step - settle_steps) * self.timestep
        hint = {
            "following error": "The demanded velocity or acceleration exceeds what the "
            "servo valve can deliver: reduce the drive's amplitude or bandwidth.",
            "stroke": "",
            "force": "Reduce the drive amplitude.",
        }[kind]
        unit = "N" if kind == "force" else spec.unit
        return RigLimitError(kind, spec.name, t, value, limit, unit, hint=hint)


class _Cancelled(Exception):
    """A batch run stopped between chunks because the batch was interrupted."""


def collidable(model: mujoco.MjModel) -> bool:
    """Whether any contact can ever form in ``model``: an explicit ``<contact><pair>``, a flex
    that may collide, or two geoms (the world's included) that pass MuJoCo's bitmask rule
    (``contype`` of one AND ``conaffinity`` of the other non-zero, either way round).

    A rig whose model has none (every vrig rig: ``contype="0" conaffinity="0"`` throughout)
    runs with ``mjDSBL_CONTACT`` set at load (:class:`MujocoRig`): collision detection then
    is skipped each physics step, and since it would find nothing, every run is bit for bit
    the one with it (``tests/test_rig_exact_speedups.py``). The rule is conservative: geom
    pairs that MuJoCo filters out anyway (parent and child bodies, ``<exclude>``) still count.

    Parameters
    ----------
    model : mujoco.MjModel
        A compiled model.

    Returns
    -------
    bool
        True if some contact can form (contact detection must stay on).
    """
    if model.npair > 0:
        return True
    if model.nflex > 0 and (np.any(model.flex_contype) or np.any(model.flex_conaffinity)):
        return True
    contype = np.asarray(model.geom_contype, dtype=np.int64)
    affinity = np.asarray(model.geom_conaffinity, dtype=np.int64)
    hits = (contype[:, None] & affinity[None, :]) != 0  # geom i's type meets geom j's affinity
    return bool(np.any(np.triu(hits | hits.T, k=1)))  # pairs of distinct geoms


def _uninstall_elements(d: mujoco.MjData) -> None:
    """Undo :meth:`MujocoRig._install_elements` for ``d``."""
    gas_spring.uninstall(d)
    damper.uninstall(d)


def _batch_seeds(seeds, n: int) -> list:
    """One seed (a non-negative int, or None: the rig's next stream) per drive."""
    if seeds is None:
        return [None] * n
    seeds = list(seeds)
    if len(seeds) != n:
        raise ValueError(f"seeds must have one entry per drive ({n}), got {len(seeds)}")
    for s in seeds:
        ok = s is None or (isinstance(s, (int, np.integer)) and not isinstance(s, bool) and s >= 0)
        if not ok:
            raise ValueError(f"each seed must be a non-negative integer or None, got {s!r}")
    return seeds


def _batch_threads(threads, n: int) -> int:
    """The checked number of worker threads of a batch of ``n`` drives."""
    if threads is None:
        return max(1, min(n, os.cpu_count() or 1, MAX_BATCH_THREADS))
    ok = isinstance(threads, (int, np.integer)) and not isinstance(threads, bool)
    if not ok or not 1 <= threads <= MAX_BATCH_THREADS:
        raise ValueError(
            f"threads must be an integer from 1 to {MAX_BATCH_THREADS} (each thread holds a live "
            f"callback context while it runs; at most {MAX_LIVE} per process), got {threads!r}"
        )
    return int(threads)


def _models_dir() -> Path:
    """The shipped models: ``models/`` of a source checkout, else the installed ``vrig.models``."""
    checkout = Path(__file__).resolve().parents[2] / "models"
    if (checkout / "common" / "hydraulic.xml").exists():
        return checkout
    from importlib.resources import files

    return Path(str(files("vrig.models")))
