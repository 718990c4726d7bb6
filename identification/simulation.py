"""Free-run simulation of condensed MIMO NARX models (Algorithm 5.2), compiled.

:func:`compile_plan` turns the per-channel structures and coefficients into flat arrays once; the
compiled recursion then costs one multiplication and one multiply-add per term and sample. Terms
are evaluated as monomials ``mono[parent] * z[factor]``; where a reduced term set lacks a parent
monomial it is added with a zero coefficient.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ._kernels import free_run
from .errors import SimulationDivergedError
from .structure import ChannelStructure

__all__ = ["SimulationPlan", "compile_plan", "simulate_plan"]


@dataclass(frozen=True, eq=False)
class SimulationPlan:
    """Flat arrays consumed by the compiled free-run kernel (see :func:`compile_plan`)."""

    ny: int
    nu: int
    max_lag: int
    reg_src: np.ndarray
    reg_lag: np.ndarray
    reg_ptr: np.ndarray
    parent: np.ndarray
    factor: np.ndarray
    coef: np.ndarray
    mono_ptr: np.ndarray


def _channel_program(terms: np.ndarray, coef: np.ndarray):
    """Monomial program of one channel: (parent, factor, coef) lists, constant first."""
    index: dict[tuple[int, ...], int] = {(): 0}
    parent, factor, c = [0], [0], [0.0]

    def ensure(key: tuple[int, ...]) -> int:
        if key in index:
            return index[key]
        p = ensure(key[:-1])
        index[key] = len(parent)
        parent.append(p)
        factor.append(key[-1])
        c.append(0.0)
        return index[key]

    for row, value in zip(terms, coef, strict=True):
        key = tuple(int(i) for i in row if i > 0)
        c[ensure(key)] += float(value)
    return parent, factor, c


def compile_plan(channels: tuple[ChannelStructure, ...], coefs, ny: int, nu: int) -> SimulationPlan:
    """Flatten structures and coefficients of all output channels for :func:`simulate_plan`."""
    reg_src, reg_lag, reg_ptr = [], [], [0]
    par, fac, cof, mono_ptr = [], [], [], [0]
    for ch, coef in zip(channels, coefs, strict=True):
        reg_src.extend(ch.regressors[:, 0].tolist())
        reg_lag.extend(ch.regressors[:, 1].tolist())
        reg_ptr.append(len(reg_src))
        p, f, c = _channel_program(ch.terms, coef)
        par.extend(p)
        fac.extend(f)
        cof.extend(c)
        mono_ptr.append(len(cof))
    i64 = np.int64
    return SimulationPlan(
        ny=ny,
        nu=nu,
        max_lag=max((ch.max_lag for ch in channels), default=0),
        reg_src=np.array(reg_src, dtype=i64),
        reg_lag=np.array(reg_lag, dtype=i64),
        reg_ptr=np.array(reg_ptr, dtype=i64),
        parent=np.array(par, dtype=i64),
        factor=np.array(fac, dtype=i64),
        coef=np.array(cof, dtype=np.float64),
        mono_ptr=np.array(mono_ptr, dtype=i64),
    )


def simulate_plan(
    plan: SimulationPlan,
    u: np.ndarray,
    y0: np.ndarray | None,
    bound: np.ndarray,
    output_names,
) -> np.ndarray:
    """Run the compiled free run. ``u`` (N, nu) validated; ``y0`` None or (max_lag, ny).

    With ``y0 = None`` the past before the first sample is zero (inputs and outputs) and every
    sample is simulated; otherwise the first ``max_lag`` outputs are ``y0`` and simulation starts
    at sample ``max_lag`` using the given inputs.

    Raises
    ------
    SimulationDivergedError
        naming the output channel and sample index where the output left ``bound``.
    """
    p = plan.max_lag
    N = u.shape[0]
    if y0 is None:
        U = np.zeros((N + p, plan.nu))
        U[p:] = u
        Y = np.zeros((N + p, plan.ny))
        offset = p
    else:
        U = np.ascontiguousarray(u)
        Y = np.zeros((N, plan.ny))
        Y[:p] = y0
        offset = 0
    k, t = free_run(
        U, Y, p, plan.reg_src, plan.reg_lag, plan.reg_ptr, plan.parent, plan.factor, plan.coef,
        plan.mono_ptr, bound,
    )
    if k >= 0:
        raise SimulationDivergedError(k, output_names[k], t - offset, Y[t, k], bound[k])
    return Y[offset:] if offset else Y
