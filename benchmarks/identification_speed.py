"""Identification speed of vrig's ``identification`` package, compared with SysIdentPy 0.9.0.

Run from the repository root::

    python -m benchmarks.identification_speed            # problems A, B, C and S
    python -m benchmarks.identification_speed --quick    # problems A, C and S, fewer repetitions
    python -m benchmarks.identification_speed --problems S   # only problem S

Problem A (SISO cubic NARX, the classic SysIdentPy example)
    ``y(t) = 0.2 y(t-1) + 0.1 y(t-1) x(t-1) + 0.9 x(t-2) + e(t)``, ``x ~ U(-1, 1)``,
    ``e ~ N(0, 0.001^2)``; 10,000 identification and 3,000 validation samples. Candidate
    structure: 4 output lags, 5 input lags (1..5), degree 3, constant: 220 terms, all of them
    used by both libraries. Measured: fit time of vrig (every solver, and FROLS ordering all 220
    terms) and of SysIdentPy ``FROLS`` + ``LeastSquares``, the speed-up, free-run simulation
    throughput, the 10-step-ahead prediction throughput on 100,000 samples (SysIdentPy's
    ``steps_ahead=10``) and the free-run accuracy (RRSE) of both models on the validation record.

Problem B (7 x 7 quadratic inverse NARX of order 4)
    A random stable 7-input, 7-output quadratic NARX system is driven by band-limited noise for
    20,000 samples; its noisy response is the input and its drive the output of a full-order
    ``Narx(order=4, degree=2)`` inverse model (2,079 terms per channel, one shared QR
    factorisation). Measured: fit time, and one bare ``numpy.linalg.qr(X, mode="r")`` of the
    20,000 x 2,079 regression matrix for reference.

Problem C (simulation-accurate NARX: output-error refinement and free-run selection)
    Problem A's system with **output** noise (5 % of the output RMS added after the recursion,
    as a transducer adds it): ``Narx(focus="simulation")`` refinement of the same 220-term
    cubic model (default early stopping on a 20 % holdout, and to convergence with
    ``holdout=0``), SEMP free-run term selection (``selection="simulation"``, BIC) over the 220
    candidates, and the refinement of a SISO order-4 quadratic *inverse* model (the reference
    text's damper inverse, 54 terms) fitted from the noisy response of a random stable
    quadratic NARX system back to its drive. Accuracy is the free-run RRSE on a fresh
    validation record against the noise-free output; SysIdentPy (no simulation focus) is run
    on the same data: its FROLS + least-squares model of the same 220 terms, and its FROLS
    with BIC order selection.

Problem S (fast free-run selection: SEMP, old vs new in the same run)
    ``selection="simulation"`` scored by the exhaustive reference scorer (old: ``lstsq``,
    ``compile_plan`` and ``simulate_plan`` per candidate subset,
    ``identification.free_run_selection.screening(None)``) and by the compiled scorer (new, the
    default), one after the other on the same data: (1) problem C's 220-candidate selection;
    (2) the inverse of the elastomeric-damper quick benchmark record (the runner's ``narx-sim``
    method, ``InverseNarx(4, 2, kind="full", focus="simulation", selection="simulation")``,
    fitted to the identification records the quick record's reconstruction fits: rig
    ``elastomeric-damper`` at ``fidelity="fast"``, seed 0, the quick settings' 12 s pseudo-field
    target); (3) a 2-input order-3 cubic ``Narx(order=3, degree=3)`` (363 candidates) on 5,000
    samples of a Wiener-Hammerstein system with a slowly varying second input that scales its
    gain (not in the model class: the path is long), 5 % output noise. Figures: wall time of
    the selections (every ``simulation_selection`` call of the fit, lead search included), of
    the whole fit, the speed-up, and the free-run error of the selected model. The new scorer's
    figures are the minimum of ``--repeats`` fits; the old one's of as many on (1) and of one
    fit on (2) and (3) (minutes), which ``--quick`` leaves out. The old scorer's time depends strongly on the BLAS threads
    (many small ``lstsq`` calls): see ``thread_env`` in the JSON file.

Both libraries see the same data in the same process. Each time is the minimum wall-clock
time of at least ``--repeats`` calls (more for sub-second operations, until 2 s have been spent),
after a warm-up call that loads the compiled numba kernels. The table is printed and written as
JSON to ``results/identification_speed.json``.
"""

from __future__ import annotations

import argparse
import contextlib
import datetime
import json
import math
import os
import platform
import sys
import time
import warnings
from collections.abc import Callable
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any, TypeVar

import numba
import numpy as np
import scipy

from identification import Narx, band_limited_noise, metrics, random_narx, regression_matrix
from identification.free_run_selection import screening
from identification.solvers import SOLVERS
from vrig.files import atomic_write

T = TypeVar("T")

RESULTS_PATH = Path(__file__).resolve().parent.parent / "results" / "identification_speed.json"
SKIP_SYSIDENTPY = "skipped: sysidentpy not installed (pip install -e .[bench])"

# Problem A: SISO cubic NARX
A_N_ID, A_N_VAL, A_N_SIM = 10_000, 3_000, 1_000_000
A_NOISE_STD = 1e-3
A_YLAG, A_XLAG, A_DEGREE, A_N_TERMS = 4, 5, 3, 220
A_SEED = 20240601
A_N_KSTEP, A_KSTEP = 100_000, 10  # k-step-ahead prediction: record length, horizon k

# Problem B: 7 x 7 quadratic inverse NARX
B_CHANNELS, B_ORDER, B_DEGREE, B_N_TERMS = 7, 4, 2, 2079
B_N = 20_000
B_NOISE = 0.01  # response measurement noise, fraction of its RMS (keeps X full rank)
B_SEED = 7

# Problem C: output-error refinement and free-run selection
C_OUTPUT_NOISE = 0.05  # fraction of the output RMS, added after the recursion
C_INV_ORDER, C_INV_DEGREE, C_INV_TERMS = 4, 2, 54
TARGET_C_REFINE_S = 3.0
TARGET_C_INVERSE_S = 1.0
TARGET_C_SELECT_S = 10.0

# Problem S: fast free-run selection, old (exhaustive reference scorer) vs new
S_DAMPER_RIG, S_DAMPER_METHOD = "elastomeric-damper", "narx-sim"
S_CUBIC_N, S_CUBIC_N_VAL, S_CUBIC_SEED = 5_000, 3_000, 3
TARGET_S_SPEEDUP = 10.0
TARGET_S_CUBIC_S = 30.0

# Targets, and SysIdentPy's earlier figures on the reference machine
TARGET_SPEEDUP = 20.0
TARGET_SIM_RATE = 3e6
TARGET_RRSE = 0.01
TARGET_B_FIT_S = 20.0
SYSIDENTPY_FIT_BEFORE = "earlier on the reference machine: 3.67 s"
SYSIDENTPY_SIM_BEFORE = "earlier on the reference machine: ~12.3 k samples/s"


@dataclass
class Figure:
    """One measured figure: a row of the table and an entry of the JSON file."""

    problem: str
    key: str
    label: str
    value: float | None
    unit: str
    op: str = ""  # ">=" or "<=" when the figure has a target
    target: float | None = None
    status: str = ""  # PASS, MISS, SKIP, or "" (informational)
    note: str = ""


class Report:
    """Collects :class:`Figure` rows; decides PASS/MISS against the targets."""

    def __init__(self) -> None:
        self.figures: list[Figure] = []

    def add(
        self,
        problem: str,
        key: str,
        label: str,
        value: float,
        unit: str,
        *,
        at_least: float | None = None,
        at_most: float | None = None,
        note: str = "",
    ) -> float:
        op, target, status = "", None, ""
        if at_least is not None:
            op, target = ">=", at_least
            status = "PASS" if value >= at_least else "MISS"
        elif at_most is not None:
            op, target = "<=", at_most
            status = "PASS" if value <= at_most else "MISS"
        self.figures.append(
            Figure(problem, key, label, float(value), unit, op, target, status, note)
        )
        return value

    def skip(self, problem: str, key: str, label: str) -> None:
        self.figures.append(Figure(problem, key, label, None, "", status="SKIP"))

    @property
    def missed(self) -> list[Figure]:
        return [f for f in self.figures if f.status == "MISS"]


def best_of(
    fn: Callable[[], T], repeats: int, *, min_time: float = 2.0, max_calls: int = 50
) -> tuple[float, T]:
    """Minimum wall-clock time over calls of ``fn``, and the last result.

    ``fn`` is called ``repeats`` times, and more (up to ``max_calls``) while the calls so far
    took less than ``min_time`` seconds in total: fast operations get more samples, which makes
    their minimum robust on a busy machine at little cost.
    """
    best, spent, calls = math.inf, 0.0, 0
    result: T | None = None
    while calls < max(repeats, 1) or (spent < min_time and calls < max_calls):
        t0 = time.perf_counter()
        result = fn()
        elapsed = time.perf_counter() - t0
        best, spent, calls = min(best, elapsed), spent + elapsed, calls + 1
    assert result is not None
    return best, result


def progress(message: str) -> None:
    print(f"... {message}", file=sys.stderr, flush=True)


# ---------------------------------------------------------------------------------- data
def narx_example_data(n: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """Input ``x`` (n, 1) and output ``y`` (n, 1) of SysIdentPy's classic example system."""
    rng = np.random.default_rng(seed)
    x = rng.uniform(-1.0, 1.0, n)
    e = rng.normal(0.0, A_NOISE_STD, n)
    y = np.zeros(n)
    for t in range(2, n):  # the true system: the only per-sample Python loop of the benchmark
        y[t] = 0.2 * y[t - 1] + 0.1 * y[t - 1] * x[t - 1] + 0.9 * x[t - 2] + e[t]
    return x[:, None], y[:, None]


def inverse_problem_data(n: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """Noisy response (n, 7) and drive (n, 7) of a random stable quadratic 7 x 7 NARX system."""
    rng = np.random.default_rng(seed)
    system = random_narx(B_CHANNELS, B_CHANNELS, 2, 2, seed=rng)
    drive = band_limited_noise(n, B_CHANNELS, cutoff=0.3, seed=rng)
    response = system.simulate(drive)
    response += B_NOISE * response.std(axis=0) * rng.standard_normal(response.shape)
    return response, drive


# ---------------------------------------------------------------------------------- SysIdentPy
class SysIdentPy:
    """The SysIdentPy 0.9.0 counterpart of problem A's vrig model."""

    def __init__(self) -> None:
        import sysidentpy
        from sysidentpy.basis_function import Polynomial
        from sysidentpy.model_structure_selection import FROLS
        from sysidentpy.parameter_estimation import LeastSquares

        self.version: str = getattr(sysidentpy, "__version__", "unknown")
        self._frols, self._polynomial, self._least_squares = FROLS, Polynomial, LeastSquares

    def model(self) -> Any:
        """FROLS with all 220 candidate terms kept, ordinary least squares."""
        return self._frols(
            order_selection=False,
            n_terms=A_N_TERMS,
            ylag=A_YLAG,
            xlag=A_XLAG,
            basis_function=self._polynomial(degree=A_DEGREE),
            estimator=self._least_squares(),
            model_type="NARMAX",
        )

    @classmethod
    def load(cls) -> SysIdentPy | None:
        try:
            return cls()
        except ImportError:
            return None


# ---------------------------------------------------------------------------------- problems
def vrig_model(**kwargs: Any) -> Narx:
    """Problem A's candidate structure: lags y 1..4, u 1..5, cubic, with constant (220 terms)."""
    return Narx(na=A_YLAG, nb=A_XLAG, nk=1, degree=A_DEGREE, constant=True, **kwargs)


def problem_a(report: Report, repeats: int, sip: SysIdentPy | None) -> None:
    progress("problem A: data")
    u, y = narx_example_data(A_N_ID + A_N_VAL, A_SEED)
    u_id, y_id, u_val, y_val = u[:A_N_ID], y[:A_N_ID], u[A_N_ID:], y[A_N_ID:]
    u_long = np.random.default_rng(A_SEED + 1).uniform(-1.0, 1.0, (A_N_SIM, 1))
    vrig_model().fit(u_id, y_id).simulate(u_val)  # warm-up: load the compiled kernels

    def free_run(model: Narx) -> np.ndarray:
        # same initial conditions as SysIdentPy's free run: the first max_lag measured outputs
        return model.simulate(u_val, y0=y_val[: model.max_lag_])

    progress("problem A: vrig fits")
    fit_s: dict[str, float] = {}
    rrse: dict[str, float] = {}
    models: dict[str, Narx] = {}
    for name in SOLVERS:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            fit_s[name], models[name] = best_of(
                lambda name=name: vrig_model(solver=name).fit(u_id, y_id), repeats
            )
        if models[name].n_terms_[0] != A_N_TERMS:
            raise RuntimeError(f"vrig model has {models[name].n_terms_[0]} terms, not {A_N_TERMS}")
        rrse[name] = float(metrics.rrse(y_val, free_run(models[name]))[0])
        label = (
            "vrig fit, full QR (solver='qr', default)"
            if name == "qr"
            else (f"vrig fit, solver={name!r}")
        )
        notes = sorted({type(w.message).__name__ for w in caught})
        report.add("A", f"vrig_fit_s.{name}", label, fit_s[name], "s", note=", ".join(notes))
    t_frols, frols = best_of(lambda: vrig_model(n_terms=A_N_TERMS).fit(u_id, y_id), repeats)
    if frols.n_terms_[0] != A_N_TERMS:
        raise RuntimeError(f"vrig FROLS kept {frols.n_terms_[0]} terms, not {A_N_TERMS}")
    report.add(
        "A", "vrig_fit_s.frols", f"vrig fit, FROLS ordering all {A_N_TERMS} terms", t_frols, "s"
    )

    model = models["qr"]
    progress("problem A: vrig simulation")
    t_long, _ = best_of(lambda: model.simulate(u_long), repeats)
    report.add(
        "A",
        "vrig_simulate_rate.long",
        f"vrig free run, {A_N_SIM:,} samples",
        A_N_SIM / t_long,
        "samples/s",
        at_least=TARGET_SIM_RATE,
    )
    t_val, y_vrig = best_of(lambda: free_run(model), repeats)
    report.add(
        "A",
        "vrig_simulate_rate.validation",
        f"vrig free run, {A_N_VAL:,} samples",
        A_N_VAL / t_val,
        "samples/s",
        at_least=TARGET_SIM_RATE,
    )
    report.add(
        "A",
        "vrig_rrse",
        "vrig free-run RRSE on validation (solver='qr')",
        rrse["qr"],
        "",
        at_most=TARGET_RRSE,
    )
    spread = max(rrse.values()) - min(rrse.values())
    report.add("A", "vrig_rrse_spread", "RRSE spread over the six solvers", spread, "")
    _problem_a_k_step(report, repeats, model, u_long[:A_N_KSTEP])

    if sip is None:
        report.skip("A", "sysidentpy", SKIP_SYSIDENTPY)
        return
    progress(f"problem A: SysIdentPy {sip.version} fits (several seconds each)")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        t_sip, smodel = best_of(lambda: sip.model().fit(X=u_id, y=y_id), repeats)
        if len(smodel.final_model) != A_N_TERMS:
            raise RuntimeError(f"SysIdentPy kept {len(smodel.final_model)} terms, not {A_N_TERMS}")
        progress("problem A: SysIdentPy free run")
        t_sip_sim, y_sip = best_of(
            lambda: smodel.predict(X=u_val, y=y_val, steps_ahead=None), repeats
        )
    y_sip = np.asarray(y_sip).reshape(-1, 1)
    report.add(
        "A",
        "sysidentpy_fit_s",
        f"SysIdentPy {sip.version} fit, FROLS + LeastSquares",
        t_sip,
        "s",
        note=SYSIDENTPY_FIT_BEFORE,
    )
    report.add(
        "A",
        "speedup.fit_qr",
        "speed-up, fit: vrig qr vs SysIdentPy",
        t_sip / fit_s["qr"],
        "x",
        at_least=TARGET_SPEEDUP,
    )
    report.add(
        "A", "speedup.fit_frols", "speed-up, fit: vrig FROLS vs SysIdentPy", t_sip / t_frols, "x"
    )
    report.add(
        "A",
        "sysidentpy_simulate_rate",
        f"SysIdentPy free run, {A_N_VAL:,} samples",
        A_N_VAL / t_sip_sim,
        "samples/s",
        note=SYSIDENTPY_SIM_BEFORE,
    )
    report.add(
        "A", "speedup.simulate", "speed-up, free run (validation record)", t_sip_sim / t_val, "x"
    )
    report.add(
        "A",
        "sysidentpy_rrse",
        "SysIdentPy free-run RRSE on validation",
        float(metrics.rrse(y_val, y_sip)[0]),
        "",
        at_most=TARGET_RRSE,
    )
    report.add(
        "A",
        "max_abs_diff",
        "max |y_vrig - y_SysIdentPy|, free run",
        float(np.max(np.abs(y_vrig - y_sip))),
        "",
    )


def _problem_a_k_step(report: Report, repeats: int, model: Narx, u: np.ndarray) -> None:
    """k-step-ahead prediction (SysIdentPy's ``predict(steps_ahead=k)``) of a noisy record:
    one compiled call runs every window of a block (no Python loop per window or sample)."""
    progress(f"problem A: vrig {A_KSTEP}-step-ahead prediction")
    y = model.simulate(u)
    y = y + 0.01 * y.std() * np.random.default_rng(A_SEED + 2).standard_normal(y.shape)
    model.predict(u[:1000], y[:1000], steps_ahead=A_KSTEP)  # warm-up: compile the kernel
    t_k, _ = best_of(lambda: model.predict(u, y, steps_ahead=A_KSTEP), repeats)
    report.add(
        "A",
        "vrig_predict_rate.k_step",
        f"vrig {A_KSTEP}-step-ahead prediction, {len(u):,} samples",
        len(u) / t_k,
        "samples/s",
        note=f"{len(u) / A_KSTEP:,.0f} windows re-initialised from measured outputs",
    )


def problem_b(report: Report, repeats: int) -> None:
    progress("problem B: data (random stable 7 x 7 NARX system)")
    response, drive = inverse_problem_data(B_N, B_SEED)

    def fit() -> Narx:
        return Narx(order=B_ORDER, degree=B_DEGREE).fit(response, drive)

    progress("problem B: fits")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        t_fit, inverse = best_of(fit, repeats)
    if np.any(inverse.n_terms_ != B_N_TERMS):
        raise RuntimeError(f"inverse model has {inverse.n_terms_} terms, not {B_N_TERMS}")
    notes = ", ".join(sorted({type(w.message).__name__ for w in caught}))
    label = f"vrig fit, 7x7 quadratic inverse NARX, {B_N_TERMS} terms, {B_N:,} samples"
    report.add("B", "vrig_fit_s", label, t_fit, "s", at_most=TARGET_B_FIT_S, note=notes)

    progress("problem B: bare numpy QR")
    channel, start = inverse.channels_[0], inverse.max_lag_
    t_reg, X = best_of(lambda: regression_matrix(response, drive, channel, start), repeats)
    report.add(
        "B",
        "regression_matrix_s",
        f"  regression matrix {X.shape[0]:,} x {X.shape[1]:,}",
        t_reg,
        "s",
    )
    t_qr, _ = best_of(lambda: np.linalg.qr(X, mode="r"), repeats)
    report.add("B", "numpy_qr_s", '  numpy.linalg.qr(X, mode="r"), reference', t_qr, "s")
    report.add("B", "fit_over_qr", "  fit time / bare QR time", t_fit / t_qr, "x")


def output_noise_data(seed: int):
    """Problem A's system, noise-free, and the same with 5 % output noise: (u, y_clean, y)."""
    u, y = narx_example_data(A_N_ID + A_N_VAL, seed)
    clean = np.zeros_like(y)  # the system without its equation noise
    x = u[:, 0]
    for t in range(2, x.size):
        clean[t, 0] = 0.2 * clean[t - 1, 0] + 0.1 * clean[t - 1, 0] * x[t - 1] + 0.9 * x[t - 2]
    rng = np.random.default_rng(seed + 2)
    noisy = clean + C_OUTPUT_NOISE * clean.std() * rng.standard_normal(clean.shape)
    return u, clean, noisy


def _rrse_clean(model: Narx, u_val, y_clean) -> float:
    try:
        sim = model.simulate(u_val, y0=y_clean[: model.max_lag_])
    except Exception:  # a diverging free run is the figure
        return float("inf")
    return float(metrics.rrse(y_clean, sim)[0])


def problem_c(report: Report, repeats: int, sip: SysIdentPy | None) -> None:
    progress("problem C: output-noise data")
    u, clean, noisy = output_noise_data(A_SEED)
    u_id, y_id = u[:A_N_ID], noisy[:A_N_ID]
    u_val, y_val = u[A_N_ID:], clean[A_N_ID:]
    quiet = warnings.catch_warnings()
    with quiet:
        warnings.simplefilter("ignore")
        vrig_model(focus="simulation").fit(u_id[:2000], y_id[:2000])  # warm-up (kernels)
        ls = vrig_model().fit(u_id, y_id)
        progress("problem C: simulation-error refinement, 220 terms")
        t_oe, oe = best_of(lambda: vrig_model(focus="simulation").fit(u_id, y_id), repeats)
        t_conv, conv = best_of(
            lambda: vrig_model(focus="simulation", holdout=0.0).fit(u_id, y_id), 1
        )
        progress("problem C: free-run (SEMP) selection over 220 candidates")
        t_sel, semp = best_of(lambda: vrig_model(selection="simulation").fit(u_id, y_id), 1)
        t_both, both = best_of(
            lambda: vrig_model(selection="simulation", focus="simulation").fit(u_id, y_id), 1
        )
    label = f"vrig refinement, {A_N_TERMS} terms, {A_N_ID:,} samples (fit incl. LS)"
    report.add(
        "C",
        "oe_fit_s",
        label,
        t_oe,
        "s",
        at_most=TARGET_C_REFINE_S,
        note=f"{oe.refinement_.iterations} LM iterations, early stop on 20 % holdout",
    )
    report.add(
        "C",
        "oe_fit_s.converged",
        "  the same to convergence (holdout=0)",
        t_conv,
        "s",
        note=f"{conv.refinement_.iterations} LM iterations"
        + (f"; {conv.stability_['remedy']}" if conv.stability_["remedy"] else ""),
    )
    report.add(
        "C",
        "semp_fit_s",
        f"vrig SEMP selection over {A_N_TERMS} candidates (BIC)",
        t_sel,
        "s",
        at_most=TARGET_C_SELECT_S,
        note=f"chose {int(semp.n_terms_[0])} terms: {', '.join(semp.term_names()[0])}",
    )
    for key, name, m in (
        ("ls", "least squares (prediction)", ls),
        ("oe", "simulation focus", oe),
        ("oe_conv", "simulation focus, converged", conv),
        ("semp", "SEMP selection", semp),
        ("semp_oe", f"SEMP + simulation focus ({t_both:.2f} s)", both),
    ):
        report.add(
            "C",
            f"rrse.{key}",
            f"  free-run RRSE vs noise-free validation, vrig {name}",
            _rrse_clean(m, u_val, y_val),
            "",
        )
    _problem_c_inverse(report, repeats)
    if sip is None:
        report.skip("C", "sysidentpy", SKIP_SYSIDENTPY)
        return
    progress("problem C: SysIdentPy on the same noisy data")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for key, kw in (
            ("all", {"order_selection": False, "n_terms": A_N_TERMS}),
            ("bic", {"order_selection": True, "info_criteria": "bic", "n_info_values": 30}),
        ):
            model = sip._frols(
                ylag=A_YLAG,
                xlag=A_XLAG,
                basis_function=sip._polynomial(degree=A_DEGREE),
                estimator=sip._least_squares(),
                model_type="NARMAX",
                **kw,
            )
            t_fit, _ = best_of(lambda model=model: model.fit(X=u_id, y=y_id), 1)
            sim = np.asarray(model.predict(X=u_val, y=y_val, steps_ahead=None)).reshape(-1, 1)
            rrse = float(metrics.rrse(y_val, sim)[0]) if np.all(np.isfinite(sim)) else np.inf
            report.add(
                "C",
                f"sysidentpy_rrse.{key}",
                f"  SysIdentPy {sip.version} FROLS ({key}), free-run RRSE",
                rrse,
                "",
                note=f"{len(model.final_model)} terms, fit {t_fit:.2f} s",
            )


def _problem_c_inverse(report: Report, repeats: int) -> None:
    progress("problem C: SISO order-4 quadratic inverse refinement")
    rng = np.random.default_rng(A_SEED + 3)
    system = random_narx(1, 1, 2, 2, seed=rng)
    drive = band_limited_noise(A_N_ID, 1, cutoff=0.3, seed=rng)
    response = system.simulate(drive)
    response += C_OUTPUT_NOISE * response.std() * rng.standard_normal(response.shape)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        t_inv, inv = best_of(
            lambda: Narx(order=C_INV_ORDER, degree=C_INV_DEGREE, focus="simulation").fit(
                response[1:], drive[:-1]
            ),
            repeats,
        )
    if inv.n_terms_[0] != C_INV_TERMS and not inv.stability_["remedy"]:
        raise RuntimeError(f"inverse model has {inv.n_terms_[0]} terms, not {C_INV_TERMS}")
    report.add(
        "C",
        "oe_inverse_fit_s",
        f"vrig refinement, SISO order-4 quadratic inverse ({C_INV_TERMS} terms), "
        f"{A_N_ID:,} samples",
        t_inv,
        "s",
        at_most=TARGET_C_INVERSE_S,
        note=f"{inv.refinement_.iterations} LM iterations"
        + (f"; {inv.stability_['remedy']}" if inv.stability_["remedy"] else ""),
    )


# ---------------------------------------------------------------------------------- problem S
@contextlib.contextmanager
def selection_timer():
    """Wall time and count of every free-run selection (``simulation_selection``, one call per
    output channel and fit) that ``Narx.fit`` makes inside the block: ``{"s": ..., "calls": ...}``.
    """
    from identification import models

    inner = models.simulation_selection
    spent = {"s": 0.0, "calls": 0}

    def timed(*args: Any, **kwargs: Any) -> Any:
        t0 = time.perf_counter()
        try:
            return inner(*args, **kwargs)
        finally:
            spent["s"] += time.perf_counter() - t0
            spent["calls"] += 1

    models.simulation_selection = timed
    try:
        yield spent
    finally:
        models.simulation_selection = inner


@dataclass
class OldNew:
    """One SEMP problem fitted by the old (exhaustive) and the new (compiled) scorer."""

    fit_s: dict[str, float]  # "old"/"new": wall time of the whole fit
    select_s: dict[str, float]  # "old"/"new": wall time of its selections
    models: dict[str, Any]
    calls: int


def old_and_new(fit: Callable[[], T], repeats: int, *, old_repeats: int = 1) -> OldNew:
    """``fit()`` with the compiled scorer (``repeats`` calls), then with the exhaustive
    reference (``old_repeats`` calls; 0: not at all); each figure is the minimum over the calls.
    """
    out = OldNew({}, {}, {}, 0)
    for name, screen, calls in (("new", "auto", repeats), ("old", None, old_repeats)):
        for _ in range(calls):
            progress(f"problem S: {name} scorer")
            with warnings.catch_warnings(), screening(screen), selection_timer() as spent:
                warnings.simplefilter("ignore")
                t0 = time.perf_counter()
                out.models[name] = fit()
                elapsed = time.perf_counter() - t0
            if spent["calls"] == 0:
                raise RuntimeError("no free-run selection was timed: Narx.fit no longer calls it")
            out.fit_s[name] = min(out.fit_s.get(name, math.inf), elapsed)
            out.select_s[name] = min(out.select_s.get(name, math.inf), spent["s"])
            out.calls = spent["calls"]
    return out


def _report_old_new(
    report: Report, key: str, what: str, r: OldNew, *, at_most: float | None = None
) -> None:
    note = f"{r.calls} selection(s)"
    report.add("S", f"{key}.new_s", f"{what}: SEMP, new (compiled scorer)", r.select_s["new"],
               "s", at_most=at_most, note=f"{note}; whole fit {r.fit_s['new']:.2f} s")  # fmt: skip
    if "old" not in r.select_s:
        report.skip("S", f"{key}.old_s", f"  {what}: old scorer (full run only)")
        return
    report.add("S", f"{key}.old_s", "  the same, old (exhaustive reference scorer)",
               r.select_s["old"], "s", note=f"whole fit {r.fit_s['old']:.2f} s")  # fmt: skip
    report.add("S", f"{key}.speedup", "  speed-up of the selections, old / new",
               r.select_s["old"] / r.select_s["new"], "x", at_least=TARGET_S_SPEEDUP)  # fmt: skip
    report.add("S", f"{key}.speedup_fit", "  speed-up of the whole fit, old / new",
               r.fit_s["old"] / r.fit_s["new"], "x")  # fmt: skip


def _same_terms(r: OldNew, names: Callable[[Any], list]) -> str:
    if "old" not in r.models:
        return ""
    same = names(r.models["old"]) == names(r.models["new"])
    return "the same terms as old" if same else "terms differ from old"


def problem_s(report: Report, repeats: int, quick: bool) -> None:
    """Fast free-run selection, old vs new in the same run (see the module docstring)."""
    progress("problem S: warm-up (compiled scorer)")
    u, clean, noisy = output_noise_data(A_SEED)
    u_id, y_id, u_val, y_val = u[:A_N_ID], noisy[:A_N_ID], u[A_N_ID:], clean[A_N_ID:]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        vrig_model(selection="simulation").fit(u_id[:1000], y_id[:1000])
    progress(f"problem S: SEMP over {A_N_TERMS} candidates")
    r = old_and_new(lambda: vrig_model(selection="simulation").fit(u_id, y_id), repeats,
                    old_repeats=repeats)  # fmt: skip
    what = f"{A_N_TERMS} candidates, {A_N_ID:,} samples"
    _report_old_new(report, "semp220", what, r)
    same = _same_terms(r, lambda m: m.term_names())
    for name, m in r.models.items():
        report.add("S", f"semp220.rrse.{name}", f"  free-run RRSE vs noise-free validation, {name}",
                   _rrse_clean(m, u_val, y_val), "", note=same if name == "new" else "")  # fmt: skip
    _problem_s_damper(report, repeats, quick)
    _problem_s_cubic(report, repeats, quick)


def damper_records():
    """The identification records (IDDRV, IDRES at the model rate) the inverse of the quick
    benchmark's elastomeric-damper record is fitted to, made as the runner makes them."""
    from benchmarks.runner.cli import QUICK
    from benchmarks.runner.record import _load_rig, _target
    from vrig.reconstruction.engine import DriveIteration

    class Captured(Exception):
        pass

    class Capture:  # a method that keeps the records it is identified from, then stops
        def identify(self, iddrv, idres):
            self.records = (iddrv, idres)
            raise Captured

        def drive(self, response):  # pragma: no cover - never reached
            raise Captured

    band, desired, _ = _target(S_DAMPER_RIG, QUICK.fidelity, QUICK.seconds, 0, None,
                               "pseudo-field")  # fmt: skip
    rig = _load_rig(S_DAMPER_RIG, 0, QUICK.fidelity, None)
    capture = Capture()
    try:
        DriveIteration(rig, desired, QUICK.iteration(capture, band, 0)).identify()
    except Captured:
        pass
    return rig, band, capture.records


def _problem_s_damper(report: Report, repeats: int, quick: bool) -> None:
    from benchmarks.runner.registry import get_method

    progress("problem S: damper quick record's identification records")
    rig, band, (iddrv, idres) = damper_records()

    def fit():
        method = get_method(S_DAMPER_METHOD).make(rig, band)
        method.identify(iddrv, idres)
        return method

    r = old_and_new(fit, repeats, old_repeats=0 if quick else 1)
    what = f"damper quick record's inverse ({S_DAMPER_METHOD}, {iddrv.n_samples:,} samples)"
    _report_old_new(report, "damper", what, r)
    same = _same_terms(r, lambda m: (m.fitted_lead(), m.inverse.model.term_names()))
    for name, m in r.models.items():
        pred = np.asarray(m.drive(idres), dtype=float).reshape(iddrv.data.shape)
        eta0 = float(np.mean(metrics.qantim_fit_dc(iddrv.data, pred)))
        report.add("S", f"damper.eta0.{name}", f"  free-run drive error eta0 % (in-sample), {name}",
                   eta0, "", note=(same + "; " if name == "new" and same else "")
                   + m.describe())  # fmt: skip


def two_input_cubic_data(n: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """Inputs (n, 2) and noise-free output (n, 1) of problem S's 2-input system.

    ``u1`` band-limited noise (cutoff 0.2 of Nyquist), ``u2`` a slow low-pass of another
    (gain 5); ``v = H1(u1)``, ``w = tanh(1.5 v) (1 + 0.4 tanh(u2))``, ``y = H2(w)`` with
    ``H1 = (0.5 + 0.3 q^-1) / (1 - 0.6 q^-1)`` and ``H2 = (0.4 + 0.2 q^-1) / (1 - 0.9 q^-1 +
    0.3 q^-2)``: a Wiener-Hammerstein system whose gain the second input scales.
    """
    from scipy import signal

    rng = np.random.default_rng(seed)
    u = band_limited_noise(n, 2, cutoff=0.2, seed=rng)
    u[:, 1] = 5.0 * signal.lfilter([0.02], [1.0, -0.98], u[:, 1])
    v = signal.lfilter([0.5, 0.3], [1.0, -0.6], u[:, 0])
    w = np.tanh(1.5 * v) * (1.0 + 0.4 * np.tanh(u[:, 1]))
    return u, signal.lfilter([0.4, 0.2], [1.0, -0.9, 0.3], w)[:, None]


def _problem_s_cubic(report: Report, repeats: int, quick: bool) -> None:
    progress(f"problem S: 2-input order-3 cubic, {S_CUBIC_N:,} samples")
    u, clean = two_input_cubic_data(S_CUBIC_N + S_CUBIC_N_VAL, S_CUBIC_SEED)
    rng = np.random.default_rng(S_CUBIC_SEED + 1)
    noisy = clean + C_OUTPUT_NOISE * clean.std() * rng.standard_normal(clean.shape)
    u_id, y_id = u[:S_CUBIC_N], noisy[:S_CUBIC_N]
    u_val, y_val = u[S_CUBIC_N:], clean[S_CUBIC_N:]
    r = old_and_new(lambda: Narx(order=3, degree=3, selection="simulation").fit(u_id, y_id),
                    repeats, old_repeats=0 if quick else 1)  # fmt: skip
    what = f"2-input order-3 cubic, {S_CUBIC_N:,} samples"
    _report_old_new(report, "cubic2", what, r, at_most=TARGET_S_CUBIC_S)
    same = _same_terms(r, lambda m: m.term_names())
    for name, m in r.models.items():
        path = m.selection_paths_[0]
        note = f"{int(m.n_terms_[0])} of 363 terms, path of {len(path.steps)} steps"
        report.add("S", f"cubic2.rrse_id.{name}", f"  free-run RRSE, identification record, {name}",
                   _rrse_clean(m, u_id, y_id), "", note=note)  # fmt: skip
        report.add("S", f"cubic2.rrse_val.{name}", f"  free-run RRSE vs noise-free validation, "
                   f"{name}", _rrse_clean(m, u_val, y_val), "",
                   note=same if name == "new" else "")  # fmt: skip


# ---------------------------------------------------------------------------------- output
def format_value(value: float | None, unit: str) -> str:
    if value is None:
        return "-"
    if unit == "samples/s":
        if value >= 1e6:
            return f"{value / 1e6:.2f} M samples/s"
        return f"{value / 1e3:.1f} k samples/s"
    if unit == "s":
        return f"{value:.3f} s"
    if unit == "x":
        return f"{value:.1f} x"
    return f"{value:.3g}"


def print_table(figures: list[Figure]) -> None:
    rows = [("", "measurement", "value", "target", "status")]
    for f in figures:
        target = f"{f.op} {format_value(f.target, f.unit)}" if f.op else ""
        rows.append((f.problem, f.label, format_value(f.value, f.unit), target, f.status))
    widths = [max(len(r[i]) for r in rows) for i in range(5)]
    for n, row in enumerate(rows):
        line = "  ".join(
            cell.rjust(w) if i in (2, 3) else cell.ljust(w)
            for i, (cell, w) in enumerate(zip(row, widths, strict=True))
        )
        notes = figures[n - 1].note if n else "note"
        print(f"{line}  {notes}".rstrip())
        if n == 0:
            print("-" * (sum(widths) + 2 * len(widths) + 4))


def environment(sip: SysIdentPy | None) -> dict[str, Any]:
    threads = {
        k: os.environ[k]
        for k in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")
        if k in os.environ
    }
    try:
        blas = np.show_config(mode="dicts")["Build Dependencies"]["blas"]["name"]
    except Exception:  # pragma: no cover - depends on the numpy build
        blas = "unknown"
    return {
        "python": platform.python_version(),
        "numpy": np.__version__,
        "scipy": scipy.__version__,
        "numba": numba.__version__,
        "sysidentpy": sip.version if sip else None,
        "blas": blas,
        "thread_env": threads,
        "cpu_count": os.cpu_count(),
        "machine": platform.machine(),
        "processor": platform.processor(),
        "platform": platform.platform(),
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="problems A, C, S, 2 repetitions")
    parser.add_argument(
        "--problems", default="ABCS", help="which problems to run, e.g. 'S' (default: all)"
    )
    parser.add_argument("--repeats", type=int, help="repetitions per timing (default 3, quick 2)")
    parser.add_argument("--output", type=Path, default=RESULTS_PATH, help="JSON results file")
    parser.add_argument("--strict", action="store_true", help="exit with status 1 on a MISS")
    args = parser.parse_args(argv)
    repeats = args.repeats or (2 if args.quick else 3)

    sip = SysIdentPy.load()
    report = Report()
    started = time.perf_counter()
    wanted = args.problems.upper()
    if "A" in wanted:
        problem_a(report, repeats, sip)
    if "C" in wanted:
        problem_c(report, repeats, sip)
    if "B" in wanted and not args.quick:
        problem_b(report, repeats)
    if "S" in wanted:
        problem_s(report, repeats, args.quick)
    elapsed = time.perf_counter() - started

    print_table(report.figures)
    if sip is None:
        print(f"\nSysIdentPy comparison {SKIP_SYSIDENTPY}")
    print(f"\n{len(report.missed)} target(s) missed; benchmark took {elapsed:.0f} s")

    args.output.parent.mkdir(parents=True, exist_ok=True)
    payload = {
        "benchmark": "identification_speed",
        "date": datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds"),
        "quick": args.quick,
        "repeats": repeats,
        "environment": environment(sip),
        "figures": [asdict(f) for f in report.figures],
        "missed": [f.key for f in report.missed],
    }
    with atomic_write(args.output, "w", encoding="utf-8") as f:
        f.write(json.dumps(payload, indent=2) + "\n")
    print(f"results written to {args.output}")
    return 1 if args.strict and report.missed else 0


if __name__ == "__main__":
    sys.exit(main())
