"""Free-run simulation of condensed MIMO NARX models (Algorithm 5.2), compiled.

Only the past outputs must be computed sample by sample; everything that depends on the inputs
alone can be computed for a whole block of samples with array operations. Each channel's model
is therefore rewritten once (:func:`compile_plan`) as a polynomial in its output regressors whose
coefficients are polynomials in its input regressors::

    y_k(t) = sum_j a_kj(t) * m_kj(y(t-1), ..., y(t-n))
    a_kj(t) = sum_i W_k[i, j] * p_i(u(t), u(t-1), ...)

The input monomials ``p_i`` and the coefficients ``a_kj(t)`` are computed per block of samples
by a kernel whose loops run along time (vectorised), and the compiled recursion
(:func:`~identification._kernels.free_run`) costs
one multiplication and one multiply-add per distinct output monomial and sample. For the SISO
cubic model with 4 output and 5 input lags, 220 terms collapse to 35 output monomials.

Regressors with a static function (``abs``, dead zone, ...) keep their code and breakpoint in
the plan: the input kernel applies it to whole blocks, the recursion to each fed-back output
regressor (a model without output functions runs the plain recursion). Regressors that no term
uses (e.g. after forward selection) are left out of the plan.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ._kernels import free_run, input_coefficients, windowed_free_run
from .errors import SimulationDivergedError
from .structure import ChannelStructure

__all__ = ["SimulationPlan", "compile_plan", "predict_plan_k_step", "simulate_plan"]

_BLOCK_BYTES = 2 * 2**20


@dataclass(frozen=True, eq=False)
class InputPart:
    """Input-only factors of a group of channels that share input regressors and monomials.

    Parameters
    ----------
    reg_src, reg_lag, reg_fun, reg_bp : ndarray (Ru,)
        The group's input regressors: input index, lag in samples, function code (0: identity)
        and breakpoint (in the input's units).
    parent, factor : ndarray of int
        Input-monomial program: monomial m is monomial ``parent[m]`` times regressor
        ``factor[m]`` (monomial 0 is the constant 1).
    e_mono, e_col, e_coef : ndarray
        Entries of the coefficient matrix W: input monomial, column of A and coefficient.
    columns : ndarray of int
        The columns of A (output monomials, all channels) this part fills.
    """

    reg_src: np.ndarray  # (Ru,) input index of each input regressor
    reg_lag: np.ndarray  # (Ru,) its lag
    reg_fun: np.ndarray  # (Ru,) its function code
    reg_bp: np.ndarray  # (Ru,) and breakpoint
    parent: np.ndarray  # input-monomial program (monomial 0 = 1)
    factor: np.ndarray
    e_mono: np.ndarray  # entries: input monomial, column of A, coefficient
    e_col: np.ndarray
    e_coef: np.ndarray
    columns: np.ndarray  # the columns of A this part fills


@dataclass(frozen=True, eq=False)
class SimulationPlan:
    """Flat arrays consumed by the compiled free-run kernels (see :func:`compile_plan`).

    Parameters
    ----------
    ny, nu : int
        Numbers of output and input channels.
    max_lag : int
        Largest lag of any regressor, in samples.
    reg_src, reg_lag, reg_fun, reg_bp, reg_ptr : ndarray
        Fed-back output regressors of every channel, concatenated (output index, lag in samples,
        function code, breakpoint); channel k's are ``reg_ptr[k]:reg_ptr[k + 1]``.
    parent, factor, mono_ptr : ndarray of int
        Output-monomial programs: monomial m is monomial ``parent[m]`` times regressor
        ``factor[m]``; channel k's monomials are ``mono_ptr[k]:mono_ptr[k + 1]``.
    input_parts : tuple of InputPart
        The input-only coefficient polynomials, one part per group of channels sharing them.
    """

    ny: int
    nu: int
    max_lag: int
    reg_src: np.ndarray
    reg_lag: np.ndarray
    reg_fun: np.ndarray
    reg_bp: np.ndarray
    reg_ptr: np.ndarray
    parent: np.ndarray
    factor: np.ndarray
    mono_ptr: np.ndarray
    input_parts: tuple[InputPart, ...]

    @property
    def n_output_monomials(self) -> int:
        """Number of output monomials over all channels."""
        return int(self.mono_ptr[-1])


class _Program:
    """Monomials as ``mono[parent] * z[factor]``; missing parents are added on demand."""

    def __init__(self):
        self.index: dict[tuple[int, ...], int] = {(): 0}
        self.parent = [0]
        self.factor = [0]

    def add(self, key: tuple[int, ...]) -> int:
        if key not in self.index:
            p = self.add(key[:-1])
            self.index[key] = len(self.parent)
            self.parent.append(p)
            self.factor.append(key[-1])
        return self.index[key]


def _split_channel(ch: ChannelStructure, coef: np.ndarray, ny: int):
    """Output and input regressor tables (source, lag, function, breakpoint) of the regressors
    the terms use, their monomial programs and the (input monomial, output monomial, coef)
    entries."""
    table = np.column_stack([ch.regressors, ch.functions, ch.breakpoints])  # float: exact ints
    used = np.zeros(ch.n_regressors + 1, dtype=bool)
    used[ch.terms.ravel()] = True
    used = used[1:]
    is_out = ch.regressors[:, 0] < ny
    local = np.zeros(ch.n_regressors + 1, dtype=np.int64)  # z index -> index within its group
    local[1:][is_out & used] = np.arange(1, (is_out & used).sum() + 1)
    local[1:][~is_out & used] = np.arange(1, (~is_out & used).sum() + 1)
    out_of = np.concatenate([[False], is_out])
    yprog, uprog = _Program(), _Program()
    entries = []
    for row, c in zip(ch.terms, coef, strict=True):
        nz = [int(i) for i in row if i > 0]
        yi = yprog.add(tuple(sorted(int(local[i]) for i in nz if out_of[i])))
        ui = uprog.add(tuple(sorted(int(local[i]) for i in nz if not out_of[i])))
        entries.append((ui, yi, float(c)))
    utable = table[~is_out & used]
    utable[:, 0] -= ny
    return table[is_out & used], yprog, utable, uprog, entries


def _input_part(group: dict) -> InputPart:
    i64 = np.int64
    e = np.array(group["entries"], dtype=np.float64).reshape(-1, 3)
    regs = group["uregs"]
    return InputPart(
        reg_src=np.ascontiguousarray(regs[:, 0], dtype=i64),
        reg_lag=np.ascontiguousarray(regs[:, 1], dtype=i64),
        reg_fun=np.ascontiguousarray(regs[:, 2], dtype=i64),
        reg_bp=np.ascontiguousarray(regs[:, 3]),
        parent=np.array(group["prog"].parent, dtype=i64),
        factor=np.array(group["prog"].factor, dtype=i64),
        e_mono=e[:, 0].astype(i64),
        e_col=e[:, 1].astype(i64),
        e_coef=np.ascontiguousarray(e[:, 2]),
        columns=np.array(group["columns"], dtype=i64),
    )


def compile_plan(channels: tuple[ChannelStructure, ...], coefs, ny: int, nu: int) -> SimulationPlan:
    """Rewrite all output channels for :func:`simulate_plan` (see the module docstring).

    Parameters
    ----------
    channels : tuple of ChannelStructure
        The structure of each output channel.
    coefs : sequence of ndarray
        The coefficient vector of each channel (one per term).
    ny, nu : int
        Numbers of output and input channels.
    """
    yregs_all, reg_ptr = [], [0]
    par, fac, mono_ptr = [], [], [0]
    groups: list[dict] = []
    for ch, coef in zip(channels, coefs, strict=True):
        yregs, yprog, uregs, uprog, entries = _split_channel(ch, coef, ny)
        yregs_all.append(yregs)
        reg_ptr.append(reg_ptr[-1] + yregs.shape[0])
        offset = len(par)
        par.extend(yprog.parent)
        fac.extend(yprog.factor)
        mono_ptr.append(len(par))
        key = (uregs.tobytes(), tuple(uprog.parent), tuple(uprog.factor))
        group = next((g for g in groups if g["key"] == key), None)
        if group is None:
            group = {"key": key, "uregs": uregs, "prog": uprog, "entries": [], "columns": []}
            groups.append(group)
        group["entries"] += [(ui, offset + yi, c) for ui, yi, c in entries]
        group["columns"] += list(range(offset, offset + len(yprog.parent)))
    yt = np.concatenate(yregs_all) if yregs_all else np.zeros((0, 4))
    i64 = np.int64
    return SimulationPlan(
        ny=ny,
        nu=nu,
        max_lag=max((ch.max_lag for ch in channels), default=0),
        reg_src=np.ascontiguousarray(yt[:, 0], dtype=i64),
        reg_lag=np.ascontiguousarray(yt[:, 1], dtype=i64),
        reg_fun=np.ascontiguousarray(yt[:, 2], dtype=i64),
        reg_bp=np.ascontiguousarray(yt[:, 3]),
        reg_ptr=np.array(reg_ptr, dtype=i64),
        parent=np.array(par, dtype=i64),
        factor=np.array(fac, dtype=i64),
        mono_ptr=np.array(mono_ptr, dtype=i64),
        input_parts=tuple(_input_part(g) for g in groups),
    )


def simulate_plan(
    plan: SimulationPlan,
    u: np.ndarray,
    y0: np.ndarray | None,
    bound: np.ndarray,
    output_names,
) -> np.ndarray:
    """Run the compiled free run. ``u`` (N, nu) validated; ``y0`` None or (L, ny), L >= max_lag.

    With ``y0 = None`` the past before the first sample is zero (inputs and outputs) and every
    sample is simulated; otherwise the first ``L`` outputs are ``y0`` and simulation starts
    at sample ``L`` from its last ``max_lag`` rows, using the given inputs (the same numbers,
    bit for bit, as simulating ``u[L - max_lag:]`` from ``y0[-max_lag:]``).

    Parameters
    ----------
    plan : SimulationPlan
        The compiled model.
    u : ndarray (N, nu)
        Validated input record.
    y0 : ndarray (max_lag, ny) or None
        Measured initial outputs, or None for a zero past.
    bound : ndarray (ny,)
        Free-run magnitude bound per output channel, in the output's units.
    output_names : sequence of str
        Output channel names, for the divergence error message.

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
        offset = start = p
    else:
        U = u
        Y = np.zeros((N, plan.ny))
        start = y0.shape[0]
        Y[:start] = y0
        offset = 0
    total = Y.shape[0]
    block = _block_rows(plan)
    A = np.empty((min(block, max(total - start, 1)), plan.n_output_monomials), order="F")
    for t0 in range(start, total, block):
        t1 = min(t0 + block, total)
        _input_coefficients(plan, U, t0, t1, A)
        k, t = free_run(Y, t0, t1, A, *_recursion(plan), bound)
        if k >= 0:
            raise SimulationDivergedError(k, output_names[k], t - offset, Y[t, k], bound[k])
    return Y[offset:] if offset else Y


def predict_plan_k_step(
    plan: SimulationPlan,
    u: np.ndarray,
    y: np.ndarray,
    steps: int,
    bound: np.ndarray,
    output_names,
) -> np.ndarray:
    """k-step-ahead prediction (SysIdentPy's ``steps_ahead=k``): ``u`` (N, nu), ``y`` (N, ny)
    validated, N > max_lag, ``steps`` >= 1.

    The first ``max_lag`` outputs are ``y``'s; from sample ``p = max_lag`` on, the record is cut
    into windows of ``steps`` samples (the last one shorter) and each window is a free run
    started from the *measured* outputs ``y[i - p : i]`` before it. Each window's numbers are
    bit for bit those of ``simulate_plan(plan, u[i - p : i + steps], y[i - p : i], ...)``.

    Vectorised: with windows shorter than a block of samples, one compiled call
    (:func:`~identification._kernels.windowed_free_run`) runs every window of a block (blocks are
    whole windows); longer windows are each one :func:`simulate_plan` call (at most
    ``N / block`` of them).

    Parameters
    ----------
    plan : SimulationPlan
        The compiled model structure and coefficients.
    u, y : ndarray (N, nu), (N, ny)
        Measured inputs and outputs (validated, N > max_lag).
    steps : int
        k >= 1.
    bound : ndarray (ny,)
        Free-run bound per output channel.
    output_names : sequence of str
        Output channel names (for the error message).

    Raises
    ------
    SimulationDivergedError
        (``kind = "k-step prediction"``) naming the channel and sample where a window's free
        run left ``bound``.
    """
    p = plan.max_lag
    N = u.shape[0]
    out = np.array(y, dtype=np.float64, order="C")
    block = _block_rows(plan)
    if steps >= block:
        for i in range(p, N, steps):
            stop = min(i + steps, N)
            try:
                win = simulate_plan(plan, u[i - p : stop], y[i - p : i], bound, output_names)
            except SimulationDivergedError as exc:
                raise _k_step_error(exc, exc.sample + i - p, exc.value) from None
            out[i:stop] = win[p:]
        return out
    rows = max(block // steps, 1) * steps
    A = np.empty((min(rows, max(N - p, 1)), plan.n_output_monomials), order="F")
    S = np.empty((p + steps, plan.ny))
    ymeas = np.ascontiguousarray(y, dtype=np.float64)
    for t0 in range(p, N, rows):
        t1 = min(t0 + rows, N)
        _input_coefficients(plan, u, t0, t1, A)
        k, t = windowed_free_run(out, ymeas, t0, t1, steps, p, A, S, *_recursion(plan), bound)
        if k >= 0:
            exc = SimulationDivergedError(k, output_names[k], t, out[t, k], bound[k])
            raise _k_step_error(exc, t, out[t, k])
    return out


def _k_step_error(exc: SimulationDivergedError, sample: int, value: float):
    return SimulationDivergedError(
        exc.channel, exc.channel_name, sample, value, exc.bound, "k-step prediction"
    )


def _block_rows(plan: SimulationPlan) -> int:
    return int(np.clip(_BLOCK_BYTES // (8 * max(plan.n_output_monomials, 1)), 64, 2048))


def _input_coefficients(plan: SimulationPlan, U: np.ndarray, t0: int, t1: int, A) -> None:
    """Fill ``A[: t1 - t0]`` with the input coefficients of rows ``t0 .. t1 - 1``."""
    for part in plan.input_parts:
        input_coefficients(
            U,
            t0,
            t1,
            part.reg_src,
            part.reg_lag,
            part.reg_fun,
            part.reg_bp,
            part.parent,
            part.factor,
            part.e_mono,
            part.e_col,
            part.e_coef,
            part.columns,
            A,
        )


def _recursion(plan: SimulationPlan) -> tuple:
    """The output-recursion tables :func:`free_run` takes after ``A``."""
    return (
        plan.reg_src,
        plan.reg_lag,
        plan.reg_fun,
        plan.reg_bp,
        plan.reg_ptr,
        plan.parent,
        plan.factor,
        plan.mono_ptr,
    )
