"""ARX and polynomial NARX models (Chapters 4 and 5), MIMO and non-square.

Each output channel k is a MISO model (eq. 5-2) with its own order n_k and degree L_k; the fitted
model holds the condensed structure (:class:`~identification.structure.ChannelStructure`, the
thesis's ``Mpar_k`` generalised to any degree) and one coefficient vector per channel.
"""

from __future__ import annotations

import dataclasses
import json
import time
import warnings
from pathlib import Path

import numpy as np

from ._files import atomic_write, read_npz
from ._initial_state import estimate_state
from ._transforms import FUNCTIONS
from ._validation import (
    as_signal,
    check_initial_outputs,
    check_same_length,
    check_steps_ahead,
    per_channel_int,
)
from .budget import check_allocation, product
from .errors import (
    IdentificationError,
    InsufficientDataError,
    ModelFileError,
    SimulationDivergedError,
    StabilityWarning,
    UnstableModelError,
)
from .free_run_selection import (
    SELECTION_BUDGET_S,
    check_criterion,
    criterion_path,
    simulation_selection,
)
from .output_error import FlatModel, check_refinement_budget, refine
from .regression import regression_matrix
from .selection import forward_regression
from .simulation import compile_plan, predict_plan_k_step, simulate_plan
from .solvers import get_solver
from .structure import (
    AUTO_BREAKPOINTS,
    FUNCTION_SOURCES,
    TERM_KINDS,
    ChannelStructure,
    explicit_regressors,
    format_count,
    full_order_regressors,
    function_regressors,
    function_specs,
    polynomial_term_count,
    polynomial_terms,
)
from .validation import criterion_value

__all__ = ["Arx", "Narx"]

_FORMAT_VERSION = 2  # 2: per-channel regressor functions and breakpoints (1 had none)

DAMPING_FACTORS = (0.5, 0.25, 0.125, 0.0625)
"""Factors the stability remedy tries, in turn, on the coefficients of the terms that feed past
outputs back non-linearly, until the free run is bounded (see ``Narx(stability_margin=...)``)."""

REMEDY_HEADROOM = 1.25
"""The stability remedy's bounded refinements keep the free run bounded at this factor times the
stability margin (on the identification input and on it reversed in time), while a remedy is
accepted when bounded at the margin: headroom so that the refinement stops inside the bounded
set. Chosen on a study of 36 remedied fits of three known NARX systems (cubic and ``y*u``
feedback, two noise levels, four records each): headroom 1.0 / 1.1 / 1.25 / 1.5 / 2.0 gave a
geometric-mean fresh-data free-run error of 0.79 / 0.68 / 0.62 / 0.76 / 0.93 times the drop's,
and diverged on 6 / 12 / 2 / 1 / 0 of 144 fresh inputs at 1.5x (the drop: 0)."""

N_PROBES = 3
"""Number of held-out probe inputs of the stability remedy: phase-randomised copies of the
identification input at the stability margin (the same amplitude spectrum and cross-spectra,
other waveforms, from a fixed seed)."""


def _probe_inputs(u: np.ndarray, scale: float, n: int = N_PROBES, seed: int = 0) -> list:
    """``scale`` times ``n`` phase-randomised copies of the record ``u`` (N, nu).

    Each copy has ``u``'s mean and amplitude spectrum, and its cross-spectra (one random phase
    per frequency, shared by all channels), with uniform random phases from ``seed``: other
    waveforms of the same band and power, reproducible.

    Parameters
    ----------
    u : ndarray (N, nu)
        The record (time on axis 0).
    scale : float
        Factor applied to each copy (the stability margin).
    n : int, optional
        Number of copies.
    seed : int, optional
        Seed of the random phases.
    """
    N = u.shape[0]
    mean = u.mean(axis=0)
    spectrum = np.fft.rfft(u - mean, axis=0)
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(n):
        phase = np.exp(2j * np.pi * rng.random(spectrum.shape[0]))[:, None]
        phase[0] = 1.0
        if N % 2 == 0:
            phase[-1] = 1.0  # the Nyquist bin stays real
        copy = np.fft.irfft(spectrum * phase, n=N, axis=0) + mean
        out.append(np.ascontiguousarray(scale * copy))
    return out


def _check_terms_finite(X: np.ndarray, u: np.ndarray, y: np.ndarray, outputs) -> None:
    """An :class:`IdentificationError` saying why when a regression matrix built from finite
    records is not finite: a polynomial term of the records overflowed float64 (records of
    magnitude ~1e300 to the degree 2). A least-squares fit is otherwise scale-invariant (the
    solvers scale each column without overflow), so the remedy is to rescale the records."""
    if np.all(np.isfinite(X)):
        return
    col = int(np.flatnonzero(~np.all(np.isfinite(X), axis=0))[0])
    raise IdentificationError(
        f"output channel(s) {list(outputs)}: regression term {col} overflows float64 (the "
        f"records peak at |u| = {np.max(np.abs(u)):.3g}, |y| = {np.max(np.abs(y)):.3g}; a "
        "product of lagged values is beyond 1.8e308): rescale the records (e.g. to SI or "
        "percent units) or lower the degree"
    )


def _names(given, n: int, prefix: str, what: str) -> tuple[str, ...]:
    if given is None:
        return tuple(f"{prefix}{i + 1}" for i in range(n))
    names = tuple(str(s) for s in given)
    if len(names) != n:
        raise IdentificationError(f"{what} has {len(names)} names for {n} channels")
    if len(set(names)) != n:
        raise IdentificationError(f"{what} must be unique, got {names}")
    return names


def _lag_table(value, ny: int, n_src: int, name: str, minimum: int) -> np.ndarray:
    """Explicit order argument -> (ny, n_src) int table (scalar, per source, or full matrix)."""
    a = np.asarray(value)
    if a.dtype.kind not in "iu" or a.ndim > 2:
        raise IdentificationError(
            f"{name} must be an int, one int per {'output' if name == 'na' else 'input'} "
            f"channel, or an (outputs x sources) integer table; got {value!r}"
        )
    if a.ndim == 0:
        a = np.full((ny, n_src), int(a))
    elif a.ndim == 1:
        if a.shape[0] != n_src:
            raise IdentificationError(f"{name} has {a.shape[0]} values for {n_src} channels")
        a = np.tile(a, (ny, 1))
    elif a.shape != (ny, n_src):
        raise IdentificationError(f"{name} table must have shape {(ny, n_src)}, got {a.shape}")
    if np.any(a < minimum):
        raise IdentificationError(f"{name} values must be >= {minimum}, got {value!r}")
    return a.astype(np.int64)


def _check_lag(lag, n_samples: int | None, what: str) -> None:
    """The largest lag must leave samples to fit: checked before any table is built."""
    if n_samples is not None and lag >= n_samples:
        raise InsufficientDataError(
            f"the largest lag {lag:.0f} ({what}) needs more than {lag:.0f} samples, but the record "
            f"has {n_samples}: lower the {what} or provide a longer record"
        )


def _check_focus_options(focus, horizon, max_iter, stability_margin) -> None:
    if focus not in ("prediction", "simulation"):
        raise IdentificationError(
            f"focus must be 'prediction' (one-step least squares) or 'simulation' (free-run "
            f"error), got {focus!r}"
        )
    if horizon is not None and (
        not isinstance(horizon, (int, np.integer)) or isinstance(horizon, bool) or horizon < 1
    ):
        raise IdentificationError(
            f"horizon must be a positive number of samples or None (the whole record), "
            f"got {horizon!r}"
        )
    if not isinstance(max_iter, (int, np.integer)) or isinstance(max_iter, bool) or max_iter < 1:
        raise IdentificationError(f"max_iter must be a positive integer, got {max_iter!r}")
    if not (isinstance(stability_margin, (int, float)) and 1.0 <= stability_margin < np.inf):
        raise IdentificationError(
            f"stability_margin must be a finite factor >= 1 (1 checks the identification "
            f"input only), got {stability_margin!r}"
        )


LAG_CONVENTIONS = ("text", "sysidentpy")
"""The lag conventions of ``Narx(order=n, lags=...)``: the reference text's full-order structure
(output lags 1..n, input lags 0..n, eq. 5-3) or SysIdentPy's ``ylag=xlag=n`` (output and input
lags 1..n)."""


def _check_structure_options(order, degree, na, nb, nk, kind, solver, lags) -> None:
    """Model structure: ``order`` xor explicit ``na``/``nb``/``nk``, lag convention, degree,
    term kind, solver."""
    if lags not in LAG_CONVENTIONS:
        raise IdentificationError(
            f"lags must be 'text' (order n: output lags 1..n, input lags 0..n) or 'sysidentpy' "
            f"(output and input lags 1..n), got {lags!r}"
        )
    explicit = na is not None or nb is not None or nk is not None
    if explicit and lags != "text":
        raise IdentificationError(
            f"lags={lags!r} applies to order=...; with explicit na/nb/nk the input lags are "
            "nk .. nk + nb - 1 (SysIdentPy's xlag=n is nb=n, nk=1)"
        )
    if order is None and not explicit:
        raise IdentificationError(
            "give the model order (e.g. Narx(order=4, degree=2)) or explicit na/nb/nk"
        )
    if order is not None and explicit:
        raise IdentificationError("give either order or na/nb/nk, not both")
    if explicit and (na is None or nb is None):
        raise IdentificationError("explicit orders need both na and nb (nk defaults to 0)")
    if order is not None:
        per_channel_int(order, 1 if np.ndim(order) == 0 else len(order), "order", minimum=0)
    per_channel_int(degree, 1 if np.ndim(degree) == 0 else len(degree), "degree", minimum=1)
    if kind not in TERM_KINDS:
        raise IdentificationError(f"unknown term kind {kind!r}; choose one of {TERM_KINDS}")
    get_solver(solver)


def _check_fit_options(
    n_terms,
    err_tol,
    bound_factor,
    focus,
    horizon,
    max_iter,
    stability_margin,
    selection,
    criterion,
    holdout,
    max_radius,
) -> None:
    """Term count and ERR tolerance, divergence bound, focus options, selection and holdout."""
    if n_terms is not None and (not isinstance(n_terms, (int, np.integer)) or n_terms < 1):
        raise IdentificationError(f"n_terms must be a positive integer, got {n_terms!r}")
    if err_tol is not None and not 0.0 <= err_tol < 1.0:
        raise IdentificationError(f"err_tol must be in [0, 1), got {err_tol!r}")
    if not bound_factor > 0:
        raise IdentificationError(f"bound_factor must be > 0, got {bound_factor!r}")
    _check_focus_options(focus, horizon, max_iter, stability_margin)
    if selection not in ("frols", "simulation"):
        raise IdentificationError(
            f"selection must be 'frols' (one-step error reduction ratio) or 'simulation' "
            f"(free-run error, SEMP), got {selection!r}"
        )
    check_criterion(criterion)
    if not (isinstance(holdout, (int, float)) and 0.0 <= holdout < 0.5):
        raise IdentificationError(
            f"holdout must be a fraction in [0, 0.5) of the record, got {holdout!r}"
        )
    if max_radius is not None and not 0 < max_radius <= 1:
        raise IdentificationError(f"max_radius must lie in (0, 1] or be None, got {max_radius!r}")


def _function_options(functions, function_sources: str):
    """The parsed non-polynomial function specs; ``function_sources`` checked."""
    specs = function_specs(functions)
    if function_sources not in FUNCTION_SOURCES:
        raise IdentificationError(
            f"function_sources must be one of {FUNCTION_SOURCES}, got {function_sources!r}"
        )
    return specs


def _is_output_affine_term(ch: ChannelStructure, row, ny: int) -> bool:
    """True unless the term multiplies a past output by another factor (or transforms it)."""
    factors = [int(i) for i in row if i > 0]
    outs = [i for i in factors if ch.regressors[i - 1, 0] < ny]
    if not outs:
        return True
    transformed = any(ch.functions[i - 1] != 0 for i in outs)
    return len(factors) == 1 and not transformed


class Narx:
    """Polynomial NARX model, full-order MIMO structure (eq. 5-3 / 5-4, any degree).

    Parameters
    ----------
    order : int or sequence of int, optional
        Full-order dynamic model order n_k per output channel (na = n_k for every output,
        nb = n_k + 1 terms for every input, nk = 0; see ``lags``). Give either ``order`` or
        ``na``/``nb``/``nk``.
    degree : int or sequence of int
        Polynomial degree L_k >= 1 per output channel (1 = linear ARX).
    lags : {"text", "sysidentpy"}
        Lag convention of ``order``. ``"text"`` (default): the reference text's full-order
        structure, output lags 1..n and input lags 0..n (eq. 5-3: the input acts in the same
        sample). ``"sysidentpy"``: SysIdentPy's ``ylag=n, xlag=n``, output and input lags 1..n
        (the input acts one sample later), the same model as ``na=n, nb=n, nk=1`` term for term;
        use it to compare with SysIdentPy like for like. Only with ``order`` (explicit
        ``na``/``nb``/``nk`` state their own lags).
    na, nb, nk : int, sequence or 2-D table, optional
        Explicit ARX orders instead of ``order``: output lags 1..na of each output, input lags
        nk .. nk + nb - 1 of each input (MATLAB ``arx`` convention); an int applies to every
        channel, a sequence gives one value per source channel, a 2-D table one per
        (output channel, source channel). ``nk`` defaults to 0.
    kind : {"full", "pure", "quasi-static", "input-polynomial"}
        Term set: all monomials (eq. 5-8), pure powers without cross products (purely
        quadratic NARX, eq. 5-24), linear plus pure powers of the lag-0 inputs
        (quasi-static NARX, eq. 5-25), or linear plus every monomial of the input regressors
        (past outputs enter linearly: the free run is stable exactly when its linear
        autoregression is).
    constant : bool
        Include a constant term (the full-order NARX of the reference text has none).
    functions : sequence, optional
        Non-polynomial terms (§7.4.1: dead band, saturation/backlash-like limits). Each item is
        ``"abs"`` (``|x|``), ``"sign_square"`` (``x |x|``), ``("deadzone", b)``
        (``sign(x) max(|x| - b, 0)``) or ``("saturation", b)`` (``clip(x, -b, b)``), with the
        breakpoint ``b`` a positive number in the source signal's units, or ``"auto"``: one
        candidate at each of 0.25, 0.5 and 1.0 times the source channel's standard deviation on
        the identification data (a constant source gets none). Every function version of each
        selected regressor (see ``function_sources``) is added as a linear term after the
        polynomial terms: ``#functions x #breakpoints x #regressors`` more terms, no products
        with them. With ``n_terms``/``err_tol`` forward regression chooses among them (e.g. the
        best "auto" breakpoint); otherwise least squares weighs them all.
    function_sources : {"inputs", "outputs", "all"}
        Which regressors get the function versions: the channel's input regressors (default),
        its past-output regressors, or both. A function of a past output makes the model
        non-affine in its outputs (no poles, no state-space form).
    solver : str or callable
        ``"qr"`` (default), ``"householder"``, ``"mgs"``, ``"cgs"``, ``"svd"``, ``"normal"`` or a
        function ``solver(X, Y, *, rcond=None)``.
    rcond : float, optional
        Relative singular-value threshold for rank decisions (default ``max(N, M) * eps``).
    n_terms : int, optional
        Select at most this many terms per channel (by ``selection``).
    err_tol : float, optional
        With FROLS, stop when the unexplained output fraction drops below this.
    selection : {"frols", "simulation"}
        How terms are chosen when ``n_terms``, ``err_tol`` or ``criterion`` is given (or always,
        for ``"simulation"``). ``"frols"``: orthogonal forward regression by one-step error
        reduction ratio. ``"simulation"``: forward selection with pruning by *free-run* error
        (SEMP, :mod:`identification.free_run_selection`; at most ``n_terms``, default 40).
    criterion : {"aic", "aicc", "bic", "fpe", "press"}, optional
        Choose the number of terms along the selection path by this criterion (on the one-step
        residuals for FROLS, the free-run residuals for ``"simulation"``, whose default is
        ``"bic"``); PRESS is the leave-one-out one-step error.
    bound_factor : float
        Free-run divergence bound: ``bound_factor * max|y|`` of the identification output per
        channel (see :meth:`simulate`).
    focus : {"prediction", "simulation"}
        What the coefficients minimise. ``"prediction"`` (default): the one-step-ahead error,
        by linear least squares (fast; biased when the noise is on the measured output).
        ``"simulation"``: the free-run (output-error) error over the record, by
        Levenberg-Marquardt started from the least-squares estimate with the exact sensitivity
        Jacobian (:mod:`identification.output_error`); MIMO outputs weighted by 1/std.
    horizon : int, optional
        With ``focus="simulation"``: a truncated horizon in samples (the record cut into
        segments restarted from the measured outputs). Default: the whole record, reached by a
        horizon continuation when the least-squares free run diverges.
    max_iter : int
        With ``focus="simulation"``: Levenberg-Marquardt iterations per horizon stage.
    holdout : float
        With ``focus="simulation"``: the fraction of the record (its end) held out for early
        stopping; the refinement keeps the iterate with the best held-out free-run error (an
        over-parameterised model otherwise fits the noise into dynamics that diverge on other
        inputs). 0 fits the whole record to convergence.
    stability_margin : float
        The stability contract: after fitting, the free run is checked on the identification
        input and on ``stability_margin`` times it (from the record's first measured outputs and
        from a zero past, within ``bound_``). ``fit`` never returns a model that diverges on its
        identification input. With ``focus="prediction"`` it raises :class:`UnstableModelError`
        (suggesting the simulation focus) and only warns (:class:`StabilityWarning`) at the
        margin. With ``focus="simulation"`` a model must also be bounded at the margin (it is
        meant for simulation, on inputs other than the record): otherwise, when terms feed
        past outputs back non-linearly, three remedies are tried and the bounded one whose free
        run validates best on the refinement's held-out end (``holdout``) is kept (with
        ``holdout=0`` nothing is held out and a larger model always fits the record better:
        the one with the smallest BIC of its free-run error over the record): (a) those terms' coefficients damped (x0.5, 0.25, ... until bounded, see
        :data:`DAMPING_FACTORS`) and the refinement rerun with every accepted step bounded at
        1x, at the margin and at :data:`REMEDY_HEADROOM` times the margin (there also on the
        input reversed in time: a second waveform of the same amplitude and spectrum); (b) the
        drop's model below with those terms regrown from zero by the same bounded refinement;
        (c) those terms dropped and the rest refitted and refined. "Bounded" here also requires
        a bounded free run on :data:`N_PROBES` inputs held out of the refinement:
        phase-randomised copies of the identification input at the margin (its spectrum,
        other waveforms, reproducible). Then (none bounded, or no such terms) the poles of a
        linear autoregression are contracted. It raises only if the free run on the
        identification input still diverges, and warns if only the margin does. What was done
        is in ``stability_["remedy"]`` and :meth:`describe`; each remedy tried, whether it was
        bounded and its held-out error, in ``stability_["tried"]``.
    max_radius : float, optional
        For a model linear in its past outputs (:meth:`is_output_affine`): after fitting,
        contract its poles inside this radius (:meth:`stabilise`; the factor applied is
        ``contraction_``) before the stability check. Inverting an acceleration or a
        high-passed response to a displacement drive puts poles at ``z ~ 1`` that estimation
        noise pushes outside the unit circle; 0.995 turns them into leaky integrators.

    Attributes
    ----------
    channels_ : tuple of ChannelStructure
    coef_ : tuple of ndarray, one coefficient vector per output channel
    n_terms_ : ndarray of int, terms per output channel
    err_ : tuple of ndarray or None, error-reduction ratios with forward selection
    max_lag_ : int
    input_names_, output_names_ : tuple of str
    bound_ : ndarray, free-run bound per output channel
    fit_time_ : float, seconds spent in fit
    timed_out_ : bool, the fit's ``deadline`` passed before its iterative stages ended
    refinement_ : RefinementResult or None, what the simulation focus did
    coef_std_ : tuple of ndarray or None, standard errors of ``coef_`` (simulation focus)
    stability_ : dict, the stability contract's checks (``"input"``, ``"margin"``: bounded or
        not; ``"remedy"``: what was done to make the free run bounded, or None; ``"tried"``,
        only when a remedy ran: one dict per remedy tried with ``"remedy"``, ``"bounded"`` (on
        the identification input at 1x and at the margin, and on the held-out probe inputs),
        ``"validation_error"`` (RMS free-run error / std of each output on the held-out end, or
        the whole record with ``holdout=0``; inf when not bounded), with ``holdout=0``
        ``"bic"`` (the score then), and ``"chosen"``)
    """

    _linear_only = False

    def __init__(
        self,
        order=None,
        degree=2,
        *,
        na=None,
        nb=None,
        nk=None,
        lags: str = "text",
        kind: str = "full",
        constant: bool = False,
        solver="qr",
        rcond: float | None = None,
        n_terms: int | None = None,
        err_tol: float | None = None,
        bound_factor: float = 1e3,
        focus: str = "prediction",
        horizon: int | None = None,
        max_iter: int = 50,
        holdout: float = 0.2,
        stability_margin: float = 1.5,
        max_radius: float | None = None,
        selection: str = "frols",
        criterion: str | None = None,
        functions=None,
        function_sources: str = "inputs",
    ):
        _check_structure_options(order, degree, na, nb, nk, kind, solver, lags)
        _check_fit_options(
            n_terms,
            err_tol,
            bound_factor,
            focus,
            horizon,
            max_iter,
            stability_margin,
            selection,
            criterion,
            holdout,
            max_radius,
        )
        specs = _function_options(functions, function_sources)
        self.order = order
        self.degree = degree
        self.na, self.nb, self.nk = na, nb, nk
        self.lags = lags
        self.kind = kind
        self.constant = bool(constant)
        self.solver = solver
        self.rcond = rcond
        self.n_terms = n_terms
        self.err_tol = err_tol
        self.bound_factor = float(bound_factor)
        self.focus = focus
        self.horizon = None if horizon is None else int(horizon)
        self.max_iter = int(max_iter)
        self.holdout = float(holdout)
        self.stability_margin = float(stability_margin)
        self.max_radius = max_radius
        self.selection = selection
        self.criterion = criterion
        self.functions = specs or None
        self.function_sources = function_sources

    # ------------------------------------------------------------------ structure
    def _structure(
        self, ny: int, nu: int, scale: np.ndarray, n_samples: int | None = None
    ) -> tuple[ChannelStructure, ...]:
        """Channel structures; ``scale`` (ny + nu,): the sources' standard deviations on the
        identification data (for "auto" breakpoints). Sizes are checked before anything is
        built: the largest lag against ``n_samples`` (the record length, when known), each
        channel's term count (closed form) and its regression matrix against the memory
        budget."""
        degrees = per_channel_int(self.degree, ny, "degree", minimum=1)
        regs, orders = self._regressors(ny, nu, n_samples)
        rows = 0
        if n_samples is not None:
            rows = n_samples - max(int(r[:, 1].max()) if r.size else 0 for r in regs)
        channels = []
        for k in range(ny):
            if regs[k].shape[0] == 0 and not self.constant:
                raise IdentificationError(
                    f"output channel {k} has no regressors (order 0 with no inputs, or na = nb = 0)"
                )
            count = polynomial_term_count(
                regs[k], degrees[k], kind=self.kind, constant=self.constant, ny=ny
            )
            self._check_size(k, count, rows, regs[k].shape[0], degrees[k])
            terms = polynomial_terms(
                regs[k], degrees[k], kind=self.kind, constant=self.constant, ny=ny
            )
            ch = self._with_functions(regs[k], terms, orders[k], ny, scale)
            if ch.n_terms > count:  # the function terms
                self._check_size(k, ch.n_terms, rows, ch.n_regressors, degrees[k])
            channels.append(ch)
        return tuple(channels)

    def term_count(self, n_outputs: int, n_inputs: int) -> np.ndarray:
        """Polynomial terms per output channel of this structure on ``n_outputs`` outputs and
        ``n_inputs`` inputs, in closed form (nothing is built): what a fit needs at least as
        many samples as (after the largest lag), before any term selection (``n_terms``) and
        without the function terms (``functions``).

        Parameters
        ----------
        n_outputs, n_inputs : int
            Numbers of output and input channels of the record the model would be fitted on.

        Returns
        -------
        ndarray of int, shape (n_outputs,)
        """
        degrees = per_channel_int(self.degree, n_outputs, "degree", minimum=1)
        regs, _orders = self._regressors(n_outputs, n_inputs, None)
        return np.array(
            [
                polynomial_term_count(
                    regs[k], degrees[k], kind=self.kind, constant=self.constant, ny=n_outputs
                )
                for k in range(n_outputs)
            ]
        )

    def max_lag(self, n_outputs: int, n_inputs: int) -> int:
        """The largest lag [samples] of this structure on ``n_outputs`` outputs and
        ``n_inputs`` inputs: the samples a fit loses at the start of the record.

        Parameters
        ----------
        n_outputs, n_inputs : int
            Numbers of output and input channels.
        """
        regs, _orders = self._regressors(n_outputs, n_inputs, None)
        return max((int(r[:, 1].max()) if r.size else 0) for r in regs)

    def _regressors(self, ny: int, nu: int, n_samples: int | None):
        """Each channel's linear regressors and full order (None with explicit na/nb/nk); the
        largest lag is checked against the record length before the tables are built."""
        if self.order is not None:
            orders = per_channel_int(self.order, ny, "order", minimum=0)
            _check_lag(max(orders), n_samples, "order")
            if self.lags == "sysidentpy":  # na = nb = n, nk = 1: not eq. 5-3, no full order
                ones = np.ones(nu, dtype=np.int64)
                regs = [explicit_regressors(ny, nu, [n] * ny, n * ones, ones) for n in orders]
                return regs, (None,) * ny
            return [full_order_regressors(ny, nu, n) for n in orders], orders
        na = _lag_table(self.na, ny, ny, "na", 0)
        nb = _lag_table(self.nb, ny, nu, "nb", 0)
        nk = _lag_table(0 if self.nk is None else self.nk, ny, nu, "nk", 0)
        input_lag = np.where(nb > 0, nk.astype(float) + nb - 1, 0.0)  # float: no int overflow
        _check_lag(
            max(float(na.max(initial=0)), float(input_lag.max(initial=0))), n_samples, "na/nb/nk"
        )
        regs = [explicit_regressors(ny, nu, na[k], nb[k], nk[k]) for k in range(ny)]
        return regs, (None,) * ny

    def _check_size(self, k: int, n_terms: int, rows: int, n_regs: int, degree: int) -> None:
        """Refuse a channel whose regression matrix would exceed the memory budget (a model needs
        at least as many samples as terms, so it is never smaller than terms x terms)."""
        height = max(rows, n_terms)
        remedy = (
            "lower the order or the degree, or choose a smaller term set (kind='pure', "
            "'quasi-static' or 'input-polynomial')"
        )
        if rows >= n_terms:
            remedy += ", or fit a shorter (or decimated) record"
        check_allocation(
            product(height, n_terms, 8),
            f"output channel {k}: Narx(kind={self.kind!r}, degree {degree}) on {n_regs:,} "
            f"regressors has {format_count(n_terms)} terms; its regression matrix "
            f"({format_count(height)} rows{'' if rows >= n_terms else ' (at least one per term)'}"
            f" x {format_count(n_terms)} terms x 8 bytes)",
            remedy,
        )

    def _with_functions(self, regs, terms, order, ny: int, scale) -> ChannelStructure:
        """The channel with its function regressors appended, one linear term each."""
        if not self.functions:
            return ChannelStructure(regs, terms, order)
        fregs, funs, bps = function_regressors(
            regs, self.functions, sources=self.function_sources, ny=ny, scale=scale
        )
        R, L = regs.shape[0], terms.shape[1]
        extra = np.zeros((fregs.shape[0], L), dtype=np.int64)
        extra[:, -1] = np.arange(R + 1, R + 1 + fregs.shape[0])
        return ChannelStructure(
            np.concatenate([regs, fregs]),
            np.concatenate([terms, extra]),
            order,
            np.concatenate([np.zeros(R, dtype=np.int64), funs]),
            np.concatenate([np.zeros(R), bps]),
        )

    # ------------------------------------------------------------------ fitting
    def fit(self, u, y, *, input_names=None, output_names=None, deadline=None):
        """Identify the model from input ``u`` (N, nu) and output ``y`` (N, ny); returns self.

        Channels that share a structure share one regression matrix, factorised once for all
        of them. With ``n_terms``/``err_tol`` each channel's terms are chosen by forward
        regression and then re-estimated with ``solver``. With ``focus="simulation"`` the
        coefficients are then refined on the free-run error. Either way the stability contract
        (see ``stability_margin``) is enforced before the model is returned.

        Parameters
        ----------
        u : array_like, shape (N, nu) or (N,)
            Identification input record, in its physical units (time on axis 0).
        y : array_like, shape (N, ny) or (N,)
            Identification output record, same N, in its physical units.
        input_names, output_names : sequence of str, optional
            Channel names (default ``u1, u2, ...``, ``y1, y2, ...``), kept in the model.
        deadline : float, optional
            A ``time.perf_counter()`` value after which the iterative stages stop early and keep
            the best reached so far: the simulation-error refinement (and the stability remedy's
            refinements) start no further iteration, and free-run term selection (SEMP) plans
            for the time left (its size estimate then shortlists the candidates per step, or
            refuses: see :mod:`~identification.free_run_selection`). ``timed_out_`` says
            whether the deadline passed. The least-squares fit and the
            stability contract always run to the end. Default: no deadline.
        """
        t0 = time.perf_counter()
        self._deadline = deadline
        u, y = self._fit_least_squares(u, y, input_names, output_names)
        if self.focus == "simulation":
            self._refine(u, y)
        self.contraction_ = 1.0
        if self.max_radius is not None and self.is_output_affine():
            self.contraction_ = self.stabilise(self.max_radius)
        self._enforce_stability(u, y)
        self.fit_time_ = time.perf_counter() - t0
        self.timed_out_ = deadline is not None and time.perf_counter() > deadline
        self._deadline = None
        return self

    def _fit_least_squares(self, u, y, input_names=None, output_names=None):
        """Validate, build the structure and fit by least squares (no refinement, no stability
        contract: for generators such as :func:`~identification.random_narx` that check their
        own). Returns the validated ``u, y``."""
        u = as_signal(u, "u")
        y = as_signal(y, "y")
        check_same_length(u, y, "u", "y")
        N, nu = u.shape
        ny = y.shape[1]
        channels = self._structure(ny, nu, np.concatenate([y.std(axis=0), u.std(axis=0)]), N)
        start = max(ch.max_lag for ch in channels)
        rows = N - start
        for k, ch in enumerate(channels):
            if rows < ch.n_terms:
                raise InsufficientDataError(
                    f"output channel {k}: {ch.n_terms} terms but only {max(rows, 0)} usable "
                    "samples "
                    f"({N} samples minus the largest lag {start}). Provide at least "
                    f"{ch.n_terms + start} samples, or lower the order/degree."
                )
        if self.focus == "simulation":  # refused now, not after the least-squares start
            self._check_refinement_size(channels, rows, ny)
        self.n_inputs_, self.n_outputs_ = nu, ny
        self.input_names_ = _names(input_names, nu, "u", "input_names")
        self.output_names_ = _names(output_names, ny, "y", "output_names")
        scale = np.max(np.abs(y), axis=0)
        self.bound_ = self.bound_factor * np.where(scale > 0, scale, 1.0)
        self.max_lag_ = start
        self._install(*self._least_squares(u, y, channels, start))
        self.refinement_, self.coef_std_ = None, None
        self.contraction_ = 1.0
        self.stability_ = {"input": None, "margin": None, "remedy": None}
        self.fit_time_ = float("nan")
        self.timed_out_ = False
        return u, y

    def _check_refinement_size(self, channels, rows: int, ny: int) -> None:
        """``focus="simulation"``: the output-error Jacobian the refinement will need
        (:func:`~.output_error.refine`: ``rows x ny`` residuals by the model's parameters), checked
        against the memory budget before anything is built. Its size is known now (every term,
        or ``n_terms`` per channel with forward selection); with ``err_tol`` / ``criterion`` the
        term count is only known after the selection, and ``refine`` checks it then."""
        if self.selection == "simulation" or self.err_tol is not None or self.criterion:
            return
        n_params = sum(
            ch.n_terms if self.n_terms is None else min(self.n_terms, ch.n_terms)
            for ch in channels
        )
        check_refinement_budget(rows * ny, n_params)

    def _least_squares(self, u, y, channels, start):
        """One-step least squares (with forward selection when asked): channels, coefs, errs."""
        ny = y.shape[1]
        solve = get_solver(self.solver)
        coefs: list[np.ndarray | None] = [None] * ny
        errs: list[np.ndarray | None] = [None] * ny
        final_channels = list(channels)
        groups: list[list[int]] = []
        for k in range(ny):
            for g in groups:
                if channels[g[0]].same_as(channels[k]):
                    g.append(k)
                    break
            else:
                groups.append([k])
        select = (
            self.n_terms is not None
            or self.err_tol is not None
            or self.criterion is not None
            or self.selection == "simulation"
        )
        self.selection_paths_ = None
        paths: list = [None] * ny
        for g in groups:
            X = regression_matrix(u, y, channels[g[0]], start)
            _check_terms_finite(X, u, y, g)
            if not select:
                coef = solve(X, y[start:, g], rcond=self.rcond)
                for j, k in enumerate(g):
                    coefs[k] = np.ascontiguousarray(coef[:, j])
                continue
            for k in g:
                idx, errs[k], paths[k] = self._select_terms(X, channels[k], k, u, y, start)
                coefs[k] = np.ascontiguousarray(solve(X[:, idx], y[start:, k], rcond=self.rcond))
                final_channels[k] = dataclasses.replace(channels[k], terms=channels[k].terms[idx])
        if self.selection == "simulation":
            self.selection_paths_ = tuple(paths) if select else None
            return tuple(final_channels), tuple(coefs), None
        return tuple(final_channels), tuple(coefs), (tuple(errs) if select else None)

    def _select_terms(self, X, ch, k, u, y, start):
        """Selected column indices of channel k, their ERR (FROLS) and the path (SEMP)."""
        if self.selection == "simulation":
            path = simulation_selection(
                X,
                ch,
                k,
                u,
                y,
                start,
                n_terms=self.n_terms,
                criterion=self.criterion or "bic",
                bound=float(self.bound_[k]),
                budget=self._selection_budget(),
                deadline=getattr(self, "_deadline", None),
            )
            return path.selected, None, path
        target = y[start:, k]
        sel = forward_regression(X, target, n_terms=self.n_terms, err_tol=self.err_tol)
        idx, err = sel.selected, sel.err
        if self.criterion is not None:
            n = criterion_path(X, target, idx, err, self.criterion)
            idx, err = idx[:n], err[:n]
        return idx, err, None

    def _selection_budget(self) -> float | None:
        """Seconds free-run selection may plan for: the time left before the fit's deadline (at
        most the default budget), None (the default budget) without one."""
        deadline = getattr(self, "_deadline", None)
        if deadline is None:
            return None
        left = deadline - time.perf_counter()
        return max(min(left, SELECTION_BUDGET_S), 1e-3)

    def _install(self, channels, coefs, errs="keep"):
        """Set the fitted structure and coefficients; the free-run plan is compiled now."""
        self.channels_ = tuple(channels)
        self.coef_ = tuple(np.ascontiguousarray(c, dtype=np.float64) for c in coefs)
        if errs != "keep":
            self.err_ = errs
        self.n_terms_ = np.array([ch.n_terms for ch in self.channels_])
        self._plan = compile_plan(self.channels_, self.coef_, self.n_outputs_, self.n_inputs_)

    # ------------------------------------------------------------------ simulation focus
    def _refine(self, u, y, feasible=None) -> None:
        """Levenberg-Marquardt on the free-run error from the current (least-squares) coef_,
        every accepted step ``feasible`` when given (see :func:`~.output_error.refine`)."""
        flat = FlatModel.from_channels(self.channels_, self.n_outputs_, self.n_inputs_)
        res = refine(
            flat,
            np.concatenate(self.coef_),
            u,
            y,
            horizon=self.horizon,
            max_iter=self.max_iter,
            bound=self.bound_,
            holdout=self.holdout,
            feasible=feasible,
            deadline=getattr(self, "_deadline", None),
        )
        self.refinement_, self.coef_std_ = res, None
        if not np.isfinite(res.cost):
            return
        self._install(self.channels_, flat.split(res.theta))
        if res.covariance is not None:
            std = np.sqrt(np.clip(np.diag(res.covariance), 0.0, None))
            self.coef_std_ = flat.split(std)

    def _free_run_divergence(self, u, y, scale: float):
        """None when the free run on ``scale * u`` stays bounded, started both from the record's
        first measured outputs and from a zero past (what ``simulate(u)`` does).

        A model linear in its past outputs with every pole inside the unit circle is stable:
        bounded inputs give bounded outputs whatever the start, so only the record's own start
        is checked (a zero past can give a large but decaying start-up transient when the
        coefficients are large and cancel, which is not a divergence)."""
        starts = [y[: self.max_lag_]]
        if not (self.is_output_affine() and self.pole_radius() < 1.0):
            starts.append(None)
        for y0 in starts:
            try:
                simulate_plan(self._plan, scale * u, y0, self.bound_, self.output_names_)
            except SimulationDivergedError as exc:
                return exc
        return None

    def _enforce_stability(self, u, y) -> None:
        """The stability contract (see the class docstring, ``stability_margin``)."""
        remedy = None
        div = self._free_run_divergence(u, y, 1.0)
        if div is not None and self.focus == "prediction":
            raise UnstableModelError(
                f"the least-squares model's free run diverges on its own identification input "
                f"({div.channel_name!r} at sample {div.sample}). Fit with focus='simulation' "
                "(output-error refinement), lower the degree, or use kind='input-polynomial' "
                "(past outputs enter linearly).",
                div,
            )
        tried = None
        if self.focus == "simulation" and not self._bounded(u, y):
            remedy, tried = self._remedy(u, y)
            div = self._free_run_divergence(u, y, 1.0)
        if div is not None:
            raise UnstableModelError(
                "no bounded model found: the free run diverges on the identification input "
                f"({div.channel_name!r} at sample {div.sample}) even after simulation-error "
                "refinement, damping or dropping the non-linear output feedback and contracting "
                "the poles. Lower the order or degree, or check the record for drift and "
                "outliers.",
                div,
            )
        margin = self.stability_margin
        at_margin = self._free_run_divergence(u, y, margin) if margin != 1.0 else None
        self.stability_ = {"input": True, "margin": at_margin is None, "remedy": remedy}
        if tried is not None:
            self.stability_["tried"] = tried
        if at_margin is not None:
            warnings.warn(
                f"the fitted model's free run diverges at {margin:g}x the identification input "
                f"({at_margin.channel_name!r} at sample {at_margin.sample}): keep the model's "
                "use within the identification amplitude, or lower the degree",
                StabilityWarning,
                stacklevel=3,
            )

    def _bounded(self, u, y) -> bool:
        """Bounded free run on the identification input and at the stability margin."""
        return all(self._free_run_divergence(u, y, s) is None for s in {1.0, self.stability_margin})

    def _remedy(self, u, y) -> tuple[str | None, list[dict]]:
        """Simulation focus, free run not bounded at 1x or at the margin: the remedies of
        :meth:`_tried_remedies` when terms feed past outputs back non-linearly, the bounded one
        that validates best kept; then (none bounded, or no such terms) the poles of a linear
        autoregression contracted. Returns what was done (None: nothing helped) and the
        report of every remedy tried."""
        masks = [
            ~np.array([_is_output_affine_term(ch, row, self.n_outputs_) for row in ch.terms])
            for ch in self.channels_
        ]
        tried, done = [], []
        if any(m.any() for m in masks):
            runs = self._tried_remedies(u, y, masks)
            tried = [report for report, _ in runs]
            ok = [i for i, r in enumerate(tried) if r["bounded"]]
            last = len(runs) - 1  # the drop: kept on a tie (fewer terms) or when none is bounded
            score = "bic" if self.holdout == 0 else "validation_error"
            best = min(ok, key=lambda i: (tried[i][score], i != last), default=last)
            self._restore(runs[best][1])
            for i, r in enumerate(tried):
                r["chosen"] = i == best
            pick = tried[best]
            done.append(pick["remedy"])
            if pick["bounded"]:
                where = "held-out" if self.holdout > 0 else "whole-record (by BIC)"
                return (
                    f"{pick['remedy']} ({where} free-run error {pick['validation_error']:.3g}; "
                    f"the best bounded of {len(tried)} remedies tried, see stability_['tried'])",
                    tried,
                )
        if self.is_output_affine() and self.pole_radius() > 0.995:
            self.contraction_ = self.stabilise(min(self.max_radius or 0.995, 0.995))
            done.append(f"poles contracted by {self.contraction_:.4f}")
        return "; ".join(done) or None, tried

    def _tried_remedies(self, u, y, masks) -> list[tuple[dict, tuple]]:
        """The stability remedies for a model with non-linear output feedback (``masks``: its
        terms per channel), each as (report, fitted state), in this order (the drop is the
        last; it is fitted before (b), which starts from it):

        (a) *damping*: the non-linear output-feedback coefficients scaled by the first factor
            of :data:`DAMPING_FACTORS` whose free run is bounded (:meth:`_feasibility`: at 1x,
            at the margin and with headroom beyond it), then the simulation-error refinement
            with every accepted step so bounded: a descent inside the bounded set;
        (c) *drop*: those terms dropped, the rest refitted by least squares and refined (what
            the contract did alone before);
        (b) *regrow*: the drop's model with the dropped terms restored at zero coefficients,
            refined with every step bounded: its training error can only fall below the drop's
            (when the drop is bounded).

        Each report: ``remedy`` (what was done), ``bounded`` (the contract's check and the
        held-out probes of :meth:`_tried`), ``validation_error`` (:meth:`_validation_error`;
        inf when not bounded)."""
        ny, nu = self.n_outputs_, self.n_inputs_
        start = self._state()
        flat = FlatModel.from_channels(self.channels_, ny, nu)
        nl = np.concatenate(masks)
        theta0 = np.concatenate(self.coef_)
        feasible = self._feasibility(flat, u, y)
        probes = _probe_inputs(u, self.stability_margin)
        runs = []
        for f in DAMPING_FACTORS:
            theta = np.where(nl, f * theta0, theta0)
            if feasible(theta):
                self._install(self.channels_, flat.split(theta))
                self._refine(u, y, feasible)
                what = f"damped the non-linear output feedback x{f:g}, refined bounded"
                runs.append(self._tried(what, u, y, probes))
                break
        else:
            what = f"damping the non-linear output feedback (down to x{DAMPING_FACTORS[-1]:g})"
            report = {"remedy": what, "bounded": False, "validation_error": np.inf}
            runs.append(({**report, "bic": np.inf} if self.holdout == 0 else report, None))
        self._restore(start)
        kept = tuple(
            dataclasses.replace(ch, terms=ch.terms[~m])
            for ch, m in zip(self.channels_, masks, strict=True)
        )
        self._install(*self._least_squares_fixed(u, y, kept))
        self._refine(u, y)
        what = "dropped the non-linear output feedback, refitted and refined"
        drop = self._tried(what, u, y, probes)
        theta = np.zeros(flat.n_params)
        theta[~nl] = np.concatenate(self.coef_)
        if drop[0]["bounded"] and feasible(theta):
            self._install(start[0], flat.split(theta), start[2])
            self._refine(u, y, feasible)
            what = "regrew the non-linear output feedback from the drop's model, refined bounded"
            runs.append(self._tried(what, u, y, probes))
        return [*runs, drop]

    def _state(self) -> tuple:
        """The fitted state a remedy changes (see :meth:`_restore`)."""
        return self.channels_, self.coef_, self.err_, self.refinement_, self.coef_std_

    def _restore(self, state: tuple) -> None:
        channels, coefs, errs, self.refinement_, self.coef_std_ = state
        self._install(channels, coefs, errs)

    def _tried(self, what: str, u, y, probes) -> tuple[dict, tuple]:
        """(report, state) of the current model as a remedy (see :meth:`_tried_remedies`).

        ``bounded``: the contract's check (:meth:`_bounded`) and a bounded free run from a zero
        past on each of the ``probes`` (``_probe_inputs`` at the margin). The probes are
        held out of the bounded refinement: a refinement that runs to the edge of the inputs it
        is constrained on is bounded there by construction, and only inputs it never saw show
        whether the model is bounded at that amplitude or only on those waveforms."""
        bounded = self._bounded(u, y)
        try:
            for probe in probes if bounded else ():
                simulate_plan(self.plan_, probe, None, self.bound_, self.output_names_)
        except SimulationDivergedError:
            bounded = False
        report = {
            "remedy": what,
            "bounded": bounded,
            "validation_error": self._validation_error(u, y) if bounded else np.inf,
        }
        if self.holdout == 0:
            report["bic"] = self._free_run_bic(u, y) if bounded else np.inf
        return report, self._state()

    def _feasibility(self, flat: FlatModel, u, y):
        """``feasible(theta)``: the free run of ``flat`` with ``theta`` bounded within
        ``bound_`` on ``u`` and ``stability_margin * u`` (the contract), and on ``h *
        stability_margin`` times ``u`` and ``u`` reversed in time (``h``:
        :data:`REMEDY_HEADROOM`), each from the record's first measured outputs and from a zero
        past.

        A refinement constrained to this set runs to its edge; the headroom and the second
        waveform (reversal keeps the amplitudes and the power spectrum) put that edge beyond
        the margin, so that the refined model is not left on the edge of its basin of
        attraction at the margin, where the held-out probes of :meth:`_tried` (and other inputs
        of that amplitude) would see it diverge."""
        ny, nu, names = self.n_outputs_, self.n_inputs_, self.output_names_
        m = self.stability_margin
        h = REMEDY_HEADROOM * m
        rev = np.ascontiguousarray(u[::-1])
        inputs = [u, h * u, h * rev] if m == 1.0 else [u, m * u, h * u, h * rev]
        runs = [(us, y0) for us in inputs for y0 in (y[: flat.max_lag], None)]

        def feasible(theta) -> bool:
            plan = compile_plan(flat.channels, flat.split(theta), ny, nu)
            try:
                for us, y0 in runs:
                    simulate_plan(plan, us, y0, self.bound_, names)
            except SimulationDivergedError:
                return False
            return True

        return feasible

    def _validation_error(self, u, y) -> float:
        """Free-run error on the refinement's held-out end (the last ``holdout`` of the record;
        the whole record when ``holdout`` is 0), started from its measured first outputs: RMS
        over samples and outputs of the error divided by each output's standard deviation on
        the record; inf when the free run leaves ``bound_``."""
        N, p = u.shape[0], self.max_lag_
        cut = max(round(N * (1.0 - self.holdout)), p) if self.holdout > 0 else p
        e = self._free_run_residuals(u, y, cut)
        if e is None:
            return np.inf
        std = y[p:].std(axis=0)
        return float(np.sqrt(np.mean((e / np.where(std > 0, std, 1.0)) ** 2)))

    def _free_run_residuals(self, u, y, cut: int):
        """``y[cut:]`` minus the free run from the measured outputs before ``cut`` (None when
        it leaves ``bound_``)."""
        p = self.max_lag_
        try:
            sim = simulate_plan(
                self.plan_, u[cut - p :], y[cut - p : cut], self.bound_, self.output_names_
            )
        except SimulationDivergedError:
            return None
        return y[cut:] - sim[p:]

    def _free_run_bic(self, u, y) -> float:
        """BIC of the free-run residuals over the record (:func:`~.validation.criterion_value`,
        every coefficient counted): the remedies' score when nothing is held out."""
        e = self._free_run_residuals(u, y, self.max_lag_)
        if e is None:
            return np.inf
        try:
            return criterion_value("bic", e, int(self.n_terms_.sum()))
        except IdentificationError:  # an exact free run (V = 0) or too few samples
            return -np.inf if not np.any(e) else np.inf

    def _least_squares_fixed(self, u, y, channels):
        """Least squares on a given structure (no selection)."""
        solve = get_solver(self.solver)
        coefs = []
        for k, ch in enumerate(channels):
            X = regression_matrix(u, y, ch, self.max_lag_)
            coefs.append(np.ascontiguousarray(solve(X, y[self.max_lag_ :, k], rcond=self.rcond)))
        return channels, coefs, None

    def is_output_affine(self) -> bool:
        """True when past outputs enter only linearly (ARX, ``kind="input-polynomial"``, or a
        selected model without output products, and no function of a past output): then the
        free run is a linear recursion driven by the inputs, with poles :meth:`pole_radius`
        can bound."""
        try:
            self._output_lag_terms()
        except IdentificationError:
            return False
        return True

    def _output_lag_terms(self):
        """(channel, term, source output, lag) of every autoregressive (output-lag) term."""
        self._check_fitted()
        ny = self.n_outputs_
        out = []
        for k, ch in enumerate(self.channels_):
            for t, row in enumerate(ch.terms):
                factors = [i - 1 for i in row if i > 0]
                outs = [i for i in factors if ch.regressors[i, 0] < ny]
                if not outs:
                    continue
                if len(factors) > 1:
                    raise IdentificationError(
                        "the model has products with past outputs: its poles are not defined "
                        "(only models linear in the outputs, e.g. ARX or kind='input-polynomial')"
                    )
                if ch.functions[outs[0]] != 0:
                    raise IdentificationError(
                        "the model has non-polynomial functions of past outputs "
                        f"(function_sources={self.function_sources!r}): its poles are not "
                        "defined (only models linear in the outputs)"
                    )
                out.append((k, t, *ch.regressors[outs[0]]))
        return out

    def pole_radius(self) -> float:
        """Spectral radius of the autoregressive part: the largest pole magnitude (< 1: stable).

        The poles are the eigenvalues of the block companion matrix of the output-lag
        coefficient matrices ``A_1 .. A_p`` (ny x ny each)."""
        ny, p = self.n_outputs_, self.max_lag_
        if p == 0:
            return 0.0
        comp = np.zeros((ny * p, ny * p))
        for k, t, src, lag in self._output_lag_terms():
            comp[k, (lag - 1) * ny + src] += self.coef_[k][t]
        comp[ny:, :-ny] = np.eye(ny * (p - 1))
        return float(np.max(np.abs(np.linalg.eigvals(comp)))) if comp.size else 0.0

    def stabilise(self, max_radius: float = 0.995) -> float:
        """Contract the poles radially so none lies outside ``max_radius``; returns the factor.

        Every output-lag coefficient matrix ``A_l`` becomes ``rho**l A_l``, which scales every
        pole by exactly ``rho`` (``rho = max_radius / pole_radius()``, 1 when already inside):
        the LPC "bandwidth expansion". It is how an inverse model with near-integrator poles
        (an acceleration response inverted to a displacement drive) is kept bounded: a pole at
        ``z = 1.002`` becomes a leaky integrator whose corner lies below the identification band.

        Parameters
        ----------
        max_radius : float, optional
            Largest pole radius allowed, in (0, 1]; default 0.995.
        """
        if not 0 < max_radius <= 1:
            raise IdentificationError(f"max_radius must lie in (0, 1], got {max_radius!r}")
        radius = self.pole_radius()
        if radius <= max_radius:
            return 1.0
        rho = max_radius / radius
        coef = [np.array(c, dtype=float) for c in self.coef_]
        for k, t, _src, lag in self._output_lag_terms():
            coef[k][t] *= rho**lag
        self._install(self.channels_, coef)
        return rho

    # ------------------------------------------------------------------ use
    def _check_fitted(self):
        if not hasattr(self, "coef_"):
            raise IdentificationError(
                f"this {type(self).__name__} is not fitted yet; call fit(u, y)"
            )

    @property
    def plan_(self):
        """Compiled free-run plan (built on first use)."""
        self._check_fitted()
        if self._plan is None:
            self._plan = compile_plan(self.channels_, self.coef_, self.n_outputs_, self.n_inputs_)
        return self._plan

    def simulate(self, u, y0=None, *, initial_state=None, bound=None) -> np.ndarray:
        """Free-run simulation (Algorithm 5.2): outputs fed back, shape (N, ny).

        Three starts: a zero past (the default), a window of *measured* first outputs (``y0``:
        the result begins with them, simulation starts after them), or a past *before* sample
        0 (``initial_state``, e.g. :meth:`estimate_initial_state`'s: every sample is
        simulated). Give at most one of ``y0`` and ``initial_state``.

        Parameters
        ----------
        u : array (N, nu) or (N,)
            Input record.
        y0 : array (L, ny) or (L,), L >= max_lag_, optional
            Initialisation window of measured outputs (nonlinear_benchmarks' convention, e.g.
            ``y0 = y[:50]``): the first ``L`` samples of the result are ``y0`` and simulation
            starts at sample ``L`` from its last ``max_lag_`` samples (the same numbers, bit for
            bit, as ``simulate(u[L - max_lag_:], y0=y0[-max_lag_:])``). Default: zero past
            (inputs and outputs before sample 0 are zero) and every sample is simulated.
        initial_state : array (max_lag_, ny) or (max_lag_,), optional (keyword only)
            The outputs ``y(-max_lag_) .. y(-1)`` before sample 0, oldest first (the inputs
            before sample 0 are zero): every sample 0 .. N-1 is simulated from this past. An
            all-zero state gives exactly the default zero-past run. Use
            ``simulate(u, initial_state=model.estimate_initial_state(u, y))`` to start from
            the past that best explains the measured first outputs when no measured window
            should be copied into the result.
        bound : float or array (ny,), optional
            Magnitude bound per channel; default ``bound_``. ``np.inf`` checks finiteness only.

        Raises
        ------
        SimulationDivergedError
            when an output leaves the bound or becomes non-finite (names channel and sample).
        IdentificationError
            when both ``y0`` and ``initial_state`` are given, or either has the wrong shape.
        """
        self._check_fitted()
        u = as_signal(u, "u", n_channels=self.n_inputs_)
        if initial_state is not None:
            if y0 is not None:
                raise IdentificationError(
                    "give y0 (measured first outputs, copied into the result) or "
                    "initial_state (the past before sample 0), not both"
                )
            state = self._check_initial_state(initial_state)
            return self._run_from_state(u, state, self._bound(bound))
        if y0 is not None:
            y0 = check_initial_outputs(y0, u, self.max_lag_, self.n_outputs_)
        return simulate_plan(self.plan_, u, y0, self._bound(bound), self.output_names_)

    def _check_initial_state(self, state) -> np.ndarray:
        p, ny = self.max_lag_, self.n_outputs_
        a = np.asarray(state, dtype=np.float64)
        if a.ndim == 1 and ny == 1:
            a = a[:, None]
        if a.shape != (p, ny):
            raise IdentificationError(
                f"initial_state must have shape (max_lag_, ny) = {(p, ny)} (the outputs "
                f"y(-{p}) .. y(-1) before sample 0, oldest first), got {a.shape}"
            )
        if not np.all(np.isfinite(a)):
            raise IdentificationError("initial_state contains NaN or inf")
        return a

    def _run_from_state(self, u, state, bound) -> np.ndarray:
        """Free run of every sample of ``u`` from the past outputs ``state`` (p, ny) and a zero
        past input (the zero-past run's padding with ``state`` in the output rows)."""
        p = self.max_lag_
        U = np.zeros((u.shape[0] + p, self.n_inputs_))
        U[p:] = u
        try:
            return simulate_plan(self.plan_, U, state, bound, self.output_names_)[p:]
        except SimulationDivergedError as exc:
            raise SimulationDivergedError(
                exc.channel, exc.channel_name, exc.sample - p, exc.value, exc.bound
            ) from None

    def estimate_initial_state(self, u, y, *, n_fit: int | None = None) -> np.ndarray:
        """The past outputs before sample 0 whose free run best fits the first measured outputs.

        Returns the (max_lag_, ny) array ``y(-max_lag_) .. y(-1)`` (oldest first) minimising
        the weighted squared free-run error ``sum_{t < n_fit} sum_k ((y_k(t) - yhat_k(t)) /
        std(y_k[:n_fit]))^2`` of ``simulate(u[:n_fit], initial_state=x)``; **the inputs before
        sample 0 are taken as zero** (as in the zero-past run), so the estimated outputs also
        absorb the effect of the unknown past inputs where the model allows (a linear model
        whose last output-lag coefficient matrix is non-singular can represent any past).

        When every term holds at most one past output, untransformed (ARX,
        ``kind="input-polynomial"``, also ``y*u`` products), the free run is affine in the
        state and the estimate is one linear least-squares solution (past outputs no term
        reaches are returned as 0). Otherwise :func:`scipy.optimize.least_squares` refines it
        from zero and from that linear estimate, and the better fit is kept.

        The state is identifiable when the first ``n_fit`` free-run outputs depend on every
        component: e.g. for ARX ``y(t) = sum_i a_i y(t-i) + ...`` with ``max_lag_ = na``, the
        first ``na`` outputs are a triangular map of ``y(-na) .. y(-1)`` with ``a_na`` on its
        diagonal, so any ``a_na != 0`` makes it unique.

        Parameters
        ----------
        u : array (N, nu) or (N,)
            Input record starting at sample 0.
        y : array (N, ny) or (N,)
            Measured outputs, time-aligned with ``u``.
        n_fit : int, optional (keyword only)
            Number of first samples fitted, ``max_lag_ <= n_fit <= N``. Default ``min(N,
            max(50, 2 max_lag_))``: the 50 samples nonlinear_benchmarks' initialisation windows
            use.

        Raises
        ------
        IdentificationError
            On a bad ``n_fit``, mismatched records, or a free run from a zero past that is not
            bounded over the fitted samples for a model affine in its state.
        """
        self._check_fitted()
        u = as_signal(u, "u", n_channels=self.n_inputs_)
        y = as_signal(y, "y", n_channels=self.n_outputs_)
        check_same_length(u, y, "u", "y")
        p, N = self.max_lag_, u.shape[0]
        if n_fit is None:
            n_fit = min(N, max(50, 2 * p))
        if (
            not isinstance(n_fit, (int, np.integer))
            or isinstance(n_fit, bool)
            or not max(p, 1) <= n_fit <= N
        ):
            raise IdentificationError(
                f"n_fit must be an integer number of samples in [max(max_lag_, 1), N] = "
                f"[{max(p, 1)}, {N}], got {n_fit!r}"
            )
        bound, uf = self.bound_, u[:n_fit]

        def run(state):
            try:
                return self._run_from_state(uf, state, bound)
            except SimulationDivergedError:
                return None

        return estimate_state(run, y[:n_fit], p, affine=self._state_affine())

    def _state_affine(self) -> bool:
        """True when every term holds at most one past-output factor, untransformed: the free
        run is then affine in its initial state."""
        ny = self.n_outputs_
        for ch in self.channels_:
            is_out = np.concatenate([[False], ch.regressors[:, 0] < ny])
            out_fun = np.concatenate([[False], (ch.regressors[:, 0] < ny) & ch.transformed])
            if np.any(is_out[ch.terms].sum(axis=1) > 1) or np.any(out_fun[ch.terms]):
                return False
        return True

    def _bound(self, bound) -> np.ndarray:
        if bound is None:
            bound = self.bound_
        bound = np.broadcast_to(np.asarray(bound, dtype=np.float64), (self.n_outputs_,)).copy()
        if np.any(np.isnan(bound)) or np.any(bound <= 0):
            raise IdentificationError(f"bound must be positive, got {bound}")
        return bound

    def predict(self, u, y, *, steps_ahead: int | None = 1, bound=None) -> np.ndarray:
        """Prediction from measured inputs and outputs, shape (N, ny): one step ahead by
        default, k steps ahead, or a free run (SysIdentPy's ``steps_ahead``).

        .. note:: **The default differs from SysIdentPy's.** SysIdentPy's ``predict`` defaults
           to ``steps_ahead=None``, a free run; here the default is ``steps_ahead=1`` (what
           ``predict(u, y)`` has always returned). One-step-ahead errors are far smaller than
           free-run errors: to score a model as SysIdentPy's default does, pass
           ``steps_ahead=None`` (or call :meth:`simulate`).

        The first ``max_lag_`` samples cannot be predicted and are copies of ``y`` (as in
        SysIdentPy).

        Parameters
        ----------
        u : array (N, nu) or (N,)
            Measured inputs.
        y : array (N, ny) or (N,)
            Measured outputs, time-aligned with ``u``; N > ``max_lag_``.
        steps_ahead : None, 1 or int k > 1 (keyword only)
            ``1``: one-step-ahead prediction (every regressor from measured data).
            ``None``: free-run simulation from the first ``max_lag_`` measured outputs,
            exactly ``simulate(u, y0=y[:max_lag_])``.
            ``k``: k-step-ahead prediction as SysIdentPy's: from sample ``max_lag_`` on the
            record is cut into windows of k samples (the last one may be shorter); each window
            is a free run re-initialised from the measured outputs just before it, so sample
            ``max_lag_ + j k + i`` is predicted ``i + 1`` steps ahead (``i < k``). A ``k`` of at
            least ``N - max_lag_`` is the free run.
        bound : float or array (ny,), optional
            For ``None`` and ``k > 1`` (free runs): as for :meth:`simulate`, default
            ``bound_``. The one-step prediction only checks finiteness.

        Raises
        ------
        SimulationDivergedError
            ``kind = "one-step prediction"`` when a one-step prediction is not finite (the data
            are so large that the model's terms overflow: the result never holds NaN or inf);
            ``"free-run simulation"`` / ``"k-step prediction"`` when a free run leaves
            ``bound``.
        """
        self._check_fitted()
        steps = check_steps_ahead(steps_ahead)
        u = as_signal(u, "u", n_channels=self.n_inputs_)
        y = as_signal(y, "y", n_channels=self.n_outputs_)
        check_same_length(u, y, "u", "y")
        p = self.max_lag_
        if u.shape[0] <= p:
            raise IdentificationError(f"need more than max_lag_ = {p} samples to predict")
        if steps is None:
            return self.simulate(u, y0=y[:p], bound=bound)
        if steps > 1:
            return predict_plan_k_step(
                self.plan_, u, y, steps, self._bound(bound), self.output_names_
            )
        out = y.copy()
        X, shared_with = None, None
        with np.errstate(over="ignore", invalid="ignore"):  # overflow is reported below
            for k, ch in enumerate(self.channels_):
                if shared_with is None or not ch.same_as(shared_with):
                    X, shared_with = regression_matrix(u, y, ch, p), ch  # reuse equal structures
                out[p:, k] = X @ self.coef_[k]
        bad = ~np.isfinite(out[p:])
        if bad.any():
            t, k = np.argwhere(bad)[0]
            raise SimulationDivergedError(
                k, self.output_names_[k], p + t, out[p + t, k], np.inf, "one-step prediction"
            )
        return out

    def term_names(self) -> list[list[str]]:
        """Term names per output channel, e.g. ``['y1(t-1)', 'u1(t)', 'y1(t-1)*u2(t)', ...]``."""
        self._check_fitted()
        return [ch.term_names(self.output_names_, self.input_names_) for ch in self.channels_]

    def describe(self) -> str:
        """Multi-line summary: per channel order, degree, number of terms (and of the
        non-polynomial function terms)."""
        self._check_fitted()
        lines = [
            f"{type(self).__name__}: {self.n_inputs_} input(s) {self.input_names_}, "
            f"{self.n_outputs_} output(s) {self.output_names_}, kind={self.kind!r}"
        ]
        if self.functions:
            lines.append(
                f"  regressor functions {list(self.functions)} on {self.function_sources} "
                f"('auto' breakpoints: {list(AUTO_BREAKPOINTS)} x the source's std)"
            )
        for k, ch in enumerate(self.channels_):
            line = (
                f"  {self.output_names_[k]}: order {ch.order}, degree {ch.degree}, "
                f"{ch.n_regressors} regressors, {ch.n_terms} terms, max lag {ch.max_lag}"
            )
            if ch.transformed.any():
                fterms = np.concatenate([[False], ch.transformed])[ch.terms].any(axis=1)
                codes = ch.functions[np.unique(ch.terms[fterms]).clip(1) - 1]
                used = sorted({FUNCTIONS[c] for c in codes if c})
                line += f"; {int(fterms.sum())} function terms ({', '.join(used) or 'none'})"
            lines.append(line)
        remedy = getattr(self, "stability_", {}).get("remedy")
        if remedy:
            lines.append(f"  stability contract: {remedy}")
        return "\n".join(lines)

    # ------------------------------------------------------------------ persistence
    def _params(self) -> dict:
        def plain(v):
            if isinstance(v, np.ndarray):
                return v.tolist()
            if isinstance(v, (tuple, list)):
                return [plain(x) for x in v]
            if isinstance(v, np.integer):
                return int(v)
            return v

        if callable(self.solver):
            solver = getattr(self.solver, "__name__", "qr")
        else:
            solver = self.solver
        return {
            "order": plain(self.order),
            "degree": plain(self.degree),
            "na": plain(self.na),
            "nb": plain(self.nb),
            "nk": plain(self.nk),
            "lags": self.lags,
            "kind": self.kind,
            "constant": self.constant,
            "solver": solver,
            "rcond": self.rcond,
            "n_terms": plain(self.n_terms),
            "err_tol": self.err_tol,
            "bound_factor": self.bound_factor,
            "focus": self.focus,
            "horizon": self.horizon,
            "max_iter": self.max_iter,
            "holdout": self.holdout,
            "stability_margin": self.stability_margin,
            "max_radius": self.max_radius,
            "selection": self.selection,
            "criterion": self.criterion,
            "functions": plain(self.functions),
            "function_sources": self.function_sources,
        }

    def save(self, path) -> Path:
        """Save the fitted model to a single ``.npz`` file (exact round trip); returns the path.

        The file is replaced atomically (temporary ``.NAME.tmp-XXXXXXXX`` in the same folder,
        ``fsync``, rename): a kill during the save leaves the previous file or the new one.

        Parameters
        ----------
        path : str or os.PathLike
            Target file; ``.npz`` is appended when the name has another suffix or none.
        """
        self._check_fitted()
        path = npz_path(path)
        with atomic_write(path) as f:  # a kill leaves the old file or the new one
            np.savez(f, **self._file_arrays())
        return path

    def _file_arrays(self) -> dict[str, np.ndarray]:
        """The arrays of the model file (``meta`` and one set per output channel): what
        :meth:`save` writes and composite models (split spectra, error signal) embed."""
        self._check_fitted()
        meta = {
            "format": "vrig-identification-model",
            "version": _FORMAT_VERSION,
            "class": type(self).__name__,
            "params": self._params(),
            "ny": self.n_outputs_,
            "nu": self.n_inputs_,
            "input_names": list(self.input_names_),
            "output_names": list(self.output_names_),
            "max_lag": self.max_lag_,
            "orders": [ch.order for ch in self.channels_],
        }
        arrays = {"meta": np.array(json.dumps(meta)), "bound": self.bound_}
        for k, ch in enumerate(self.channels_):
            arrays[f"regressors_{k}"] = ch.regressors
            arrays[f"terms_{k}"] = ch.terms
            arrays[f"functions_{k}"] = ch.functions
            arrays[f"breakpoints_{k}"] = ch.breakpoints
            arrays[f"coef_{k}"] = self.coef_[k]
            if self.err_ is not None:
                arrays[f"err_{k}"] = self.err_[k]
            if getattr(self, "coef_std_", None) is not None:
                arrays[f"coef_std_{k}"] = self.coef_std_[k]
        return arrays

    @classmethod
    def load(cls, path):
        """Load a model written by :meth:`save`.

        The file is checked before it is used: a regular file of at most
        ``MAX_MODEL_FILE_BYTES`` (1 GiB), a valid ``.npz`` whose arrays are as large as their
        headers claim, the model description (format, version, class, parameters, channel
        counts and names) and every channel's structure against it (regressor sources and lags
        in range, term indices, coefficient count, finite coefficients, positive bounds).

        Parameters
        ----------
        path : str or os.PathLike
            A file written by :meth:`save` (``.npz`` appended when missing).

        Raises
        ------
        FileNotFoundError
            If there is no such file.
        ModelFileError
            If the file is not such a model: truncated, corrupt, foreign, tampered, of a newer
            format version, not a regular file (FIFO, device) or too large.
        """
        path = Path(path)
        if not path.exists():
            raise FileNotFoundError(f"no model file at {path}")
        arrays = read_npz(
            path, limit=MAX_MODEL_FILE_BYTES, error=lambda detail: ModelFileError(path, detail)
        )
        return model_from_arrays(arrays, path)

    def __repr__(self) -> str:
        p = self._params()
        shown = {k: v for k, v in p.items() if v is not None and k != "bound_factor"}
        return f"{type(self).__name__}({', '.join(f'{k}={v!r}' for k, v in shown.items())})"


MAX_MODEL_FILE_BYTES = 2**30
"""Largest model file :meth:`Narx.load` reads (1 GiB)."""


def npz_path(path) -> Path:
    """``path`` with the ``.npz`` suffix model files carry (added when missing).

    Parameters
    ----------
    path : str or os.PathLike
        A model file name.
    """
    path = Path(path)
    if path.suffix != ".npz":
        path = path.with_suffix(path.suffix + ".npz") if path.suffix else path.with_suffix(".npz")
    return path


def model_from_arrays(arrays: dict, path: Path):
    """The Narx/Arx stored in ``arrays`` (a model file's, or one part of a composite model
    file's), checked (see :meth:`Narx.load`); raises :class:`ModelFileError` naming ``path``.

    Parameters
    ----------
    arrays : dict of str to ndarray
        The arrays of a model file (or of one part of a composite model file).
    path : Path
        The file they were read from, named in the error when they are not a valid model.
    """
    meta = _model_meta(arrays, path)
    target = {"Narx": Narx, "Arx": Arx}[meta["class"]]
    params = dict(meta["params"])
    if target is Arx:
        params.pop("degree", None)
        params.pop("kind", None)
    try:
        model = target(**params)
        _install_loaded(model, arrays, meta)
    except (IdentificationError, TypeError, ValueError) as exc:
        if isinstance(exc, ModelFileError):
            raise
        raise ModelFileError(path, f"{type(exc).__name__}: {exc}") from None
    return model


def _model_meta(arrays: dict, path: Path) -> dict:
    """The checked ``meta`` description of a model file (see :meth:`Narx.load`)."""

    def bad(detail: str) -> ModelFileError:
        return ModelFileError(path, detail)

    raw = arrays.get("meta")
    if raw is None or raw.dtype.kind != "U" or raw.shape != ():
        raise bad(f"not a vrig identification model (no meta; arrays {sorted(arrays)[:8]})")
    try:
        meta = json.loads(str(raw))
    except ValueError as exc:
        raise bad(f"meta is not JSON ({exc})") from None
    if not isinstance(meta, dict) or meta.get("format") != "vrig-identification-model":
        raise bad("not a vrig identification model")
    version = meta.get("version", 1)
    if not isinstance(version, int) or version > _FORMAT_VERSION:
        raise bad(
            f"model format version {version!r}, newer than this package reads "
            f"({_FORMAT_VERSION}); update the identification package"
        )
    if meta.get("class") not in ("Narx", "Arx"):
        raise bad(f"unknown model class {meta.get('class')!r}")
    counts = [meta.get(k) for k in ("ny", "nu", "max_lag")]
    if not all(isinstance(c, int) and not isinstance(c, bool) and c >= 0 for c in counts):
        raise bad(f"ny, nu, max_lag must be integers >= 0, got {counts}")
    ny, nu, _ = counts
    if not 1 <= ny <= len(arrays) or nu < 1:  # each output channel has its own arrays
        raise bad(f"ny = {ny}, nu = {nu} do not match the {len(arrays)} arrays of the file")
    for key, n in (("output_names", ny), ("input_names", nu)):
        names = meta.get(key)
        if not (
            isinstance(names, list) and len(names) == n and all(isinstance(x, str) for x in names)
        ):
            raise bad(f"{key} must list {n} names")
    orders = meta.get("orders")
    if not (
        isinstance(orders, list)
        and len(orders) == ny
        and all(o is None or (type(o) is int and o >= 0) for o in orders)
    ):
        raise bad(f"orders must hold one order (integer >= 0 or null) per output ({ny})")
    if not isinstance(meta.get("params"), dict):
        raise bad("params must be a mapping of the model's parameters")
    return meta


def _int_table(arrays: dict, key: str, ncols: int | None) -> np.ndarray:
    a = arrays[key]
    if a.dtype.kind not in "iu" or a.ndim != 2 or (ncols is not None and a.shape[1] != ncols):
        raise IdentificationError(f"{key} must be an integer table, got {a.dtype} {a.shape}")
    return a


def _install_loaded(model, arrays: dict, meta: dict) -> None:
    """Give ``model`` the fitted state stored in a model file, checking it on the way."""
    ny, nu, max_lag = meta["ny"], meta["nu"], meta["max_lag"]
    need = ["bound"] + [f"{n}_{k}" for k in range(ny) for n in ("regressors", "terms", "coef")]
    missing = [key for key in need if key not in arrays]
    if missing:
        raise IdentificationError(f"array(s) {', '.join(missing[:6])} missing")
    channels, coefs = [], []
    for k in range(ny):
        regs = _int_table(arrays, f"regressors_{k}", 2)
        src, lag = regs[:, 0], regs[:, 1]
        if regs.size and (src.min() < 0 or src.max() >= ny + nu or lag.min() < 0):
            raise IdentificationError(f"regressors_{k}: source or lag out of range")
        if np.any((src < ny) & (lag < 1)) or (lag.size and lag.max() > max_lag):
            raise IdentificationError(f"regressors_{k}: output lag < 1 or lag > max_lag")
        has_f = f"functions_{k}" in arrays  # format 1 files have no functions (identity)
        ch = ChannelStructure(
            regs,
            _int_table(arrays, f"terms_{k}", None),
            meta["orders"][k],
            arrays[f"functions_{k}"] if has_f else None,
            arrays.get(f"breakpoints_{k}") if has_f else None,
        )
        coef = arrays[f"coef_{k}"]
        if coef.dtype.kind != "f" or coef.shape != (ch.n_terms,) or not np.all(np.isfinite(coef)):
            raise IdentificationError(f"coef_{k} must hold {ch.n_terms} finite coefficients")
        for extra in ("err", "coef_std"):
            a = arrays.get(f"{extra}_{k}")
            if a is not None and a.shape != (ch.n_terms,):
                raise IdentificationError(f"{extra}_{k} must hold {ch.n_terms} values")
        channels.append(ch)
        coefs.append(np.array(coef, dtype=np.float64))
    bound = arrays["bound"]
    if bound.dtype.kind != "f" or bound.shape != (ny,) or not np.all(bound > 0):
        raise IdentificationError(f"bound must hold {ny} positive numbers")
    model.channels_, model.coef_ = tuple(channels), tuple(coefs)
    model.err_ = _optional(arrays, "err", ny)
    model.coef_std_ = _optional(arrays, "coef_std", ny)
    model.bound_ = np.array(bound, dtype=np.float64)
    model.n_terms_ = np.array([ch.n_terms for ch in channels])
    model.max_lag_ = max_lag
    model.n_inputs_, model.n_outputs_ = nu, ny
    model.input_names_ = tuple(meta["input_names"])
    model.output_names_ = tuple(meta["output_names"])
    model._plan = None
    model.refinement_ = None
    model.fit_time_ = float("nan")


def _optional(arrays: dict, name: str, ny: int):
    if f"{name}_0" not in arrays:
        return None
    return tuple(np.array(arrays[f"{name}_{k}"]) for k in range(ny))


class Arx(Narx):
    """Linear ARX model (eq. 4-8 / 4-13), full-order MIMO structure: ``Narx(degree=1)``.

    Adds :meth:`to_statespace`, the MIMO discrete state-space form of eq. 4-14.

    Parameters
    ----------
    order : int or sequence of int, optional
        Full-order model order n_k per output channel (na = n_k, nb = n_k + 1, nk = 0), as for
        :class:`Narx`. Give either ``order`` or ``na``/``nb``/``nk``.
    na, nb, nk : int, sequence or 2-D table, optional
        Explicit ARX orders instead of ``order`` (output lags 1..na, input lags nk..nk + nb - 1,
        in samples), as for :class:`Narx`.
    lags : {"text", "sysidentpy"}
        Lag convention of ``order``: input lags 0..n (the text's, default) or 1..n
        (SysIdentPy's ``xlag=n``), as for :class:`Narx`.
    constant : bool
        Include a constant term.
    solver : str or callable
        Least-squares solver (a name in :data:`~identification.solvers.SOLVERS` or a function).
    rcond : float, optional
        Relative singular-value threshold for rank decisions (default ``max(N, M) * eps``).
    n_terms : int, optional
        Select at most this many terms per channel (by ``selection``).
    err_tol : float, optional
        With FROLS, stop when the unexplained output fraction drops below this.
    bound_factor : float
        Free-run divergence bound: ``bound_factor * max|y|`` of the identification output.
    focus : {"prediction", "simulation"}
        Minimise the one-step error (least squares) or the free-run error (output-error
        refinement), as for :class:`Narx`.
    horizon : int, optional
        With ``focus="simulation"``: a truncated horizon in samples (default the whole record).
    max_iter : int
        With ``focus="simulation"``: Levenberg-Marquardt iterations per horizon stage.
    holdout : float
        With ``focus="simulation"``: fraction of the record (its end) held out for early stopping.
    stability_margin : float
        The free run is checked on the identification input and on this multiple of it.
    max_radius : float, optional
        Contract the fitted poles inside this radius (:meth:`Narx.stabilise`); None: untouched.
    selection : {"frols", "simulation"}
        How terms are chosen: one-step error reduction ratio or free-run error (SEMP).
    criterion : {"aic", "aicc", "bic", "fpe", "press"}, optional
        Choose the number of terms along the selection path by this criterion.
    functions : None
        Must be None or empty: ARX takes no regressor functions (use ``Narx(degree=1,
        functions=...)``); anything else raises :class:`IdentificationError`.
    function_sources : str
        Accepted for the same signature as :class:`Narx` and ignored (no functions).
    """

    def __init__(
        self,
        order=None,
        *,
        na=None,
        nb=None,
        nk=None,
        lags: str = "text",
        constant: bool = False,
        solver="qr",
        rcond=None,
        n_terms=None,
        err_tol=None,
        bound_factor: float = 1e3,
        focus: str = "prediction",
        horizon: int | None = None,
        max_iter: int = 50,
        holdout: float = 0.2,
        stability_margin: float = 1.5,
        max_radius: float | None = None,
        selection: str = "frols",
        criterion: str | None = None,
        functions=None,
        function_sources: str = "inputs",
    ):
        if functions:
            raise IdentificationError(
                "Arx is linear and takes no regressor functions; for non-polynomial terms use "
                f"Narx(..., degree=1, functions={functions!r})"
            )
        super().__init__(
            order,
            1,
            na=na,
            nb=nb,
            nk=nk,
            lags=lags,
            kind="full",
            constant=constant,
            solver=solver,
            rcond=rcond,
            n_terms=n_terms,
            err_tol=err_tol,
            bound_factor=bound_factor,
            focus=focus,
            horizon=horizon,
            max_iter=max_iter,
            holdout=holdout,
            stability_margin=stability_margin,
            max_radius=max_radius,
            selection=selection,
            criterion=criterion,
        )

    def to_statespace(self, dt: float = 1.0):
        """Discrete MIMO state-space model (eq. 4-14) as a ``control.StateSpace``.

        State ``x(t) = [y(t-1); ...; y(t-p); u(t-1); ...; u(t-p)]`` with p the largest lag
        (a non-minimal but exact realisation): ``x(t+1) = A x(t) + B u(t)``,
        ``y(t) = C x(t) + D u(t)``. Simulating it from ``x = 0`` equals :meth:`simulate`.

        Parameters
        ----------
        dt : float, optional
            Sample time of the state-space model in s (> 0; default 1.0, i.e. time in samples).
        """
        import control

        self._check_fitted()
        if self.constant:
            raise IdentificationError("a model with a constant term has no linear state-space form")
        if any(ch.transformed.any() for ch in self.channels_):
            raise IdentificationError(
                "a model with non-polynomial regressor functions has no linear state-space form"
            )
        if not dt > 0:
            raise IdentificationError(f"dt must be > 0, got {dt!r}")
        ny, nu, p = self.n_outputs_, self.n_inputs_, self.max_lag_
        n = p * (ny + nu)
        C = np.zeros((ny, n))
        D = np.zeros((ny, nu))
        for k, (ch, coef) in enumerate(zip(self.channels_, self.coef_, strict=True)):
            for row, c in zip(ch.terms, coef, strict=True):
                src, lag = ch.regressors[row[-1] - 1]
                if src < ny:
                    C[k, (lag - 1) * ny + src] += c
                elif lag == 0:
                    D[k, src - ny] += c
                else:
                    C[k, p * ny + (lag - 1) * nu + (src - ny)] += c
        A = np.zeros((n, n))
        B = np.zeros((n, nu))
        if p:
            A[:ny] = C
            B[:ny] = D
            A[ny : p * ny, : (p - 1) * ny] = np.eye((p - 1) * ny)
            B[p * ny : p * ny + nu] = np.eye(nu)
            A[p * ny + nu :, p * ny : p * ny + (p - 1) * nu] = np.eye((p - 1) * nu)
        return control.ss(
            A,
            B,
            C,
            D,
            dt,
            inputs=list(self.input_names_),
            outputs=list(self.output_names_),
        )
