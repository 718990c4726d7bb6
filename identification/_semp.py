"""The compiled scorer of free-run selection (SEMP): least squares from the Gram matrix, free
runs read from the term table, candidates scored in threads; and the size estimate.

:mod:`identification.free_run_selection` runs the SEMP path (forward step by free-run error,
pruning); this module scores its candidate subsets. What is computed, and how it differs from
the reference scorer (``lstsq`` + :func:`~identification.simulation.compile_plan` +
:func:`~identification.simulation.simulate_plan` per subset):

* **Least squares.** The columns of ``X`` are scaled to unit norm; the rows of the scaled Gram
  matrix ``G = Xs' Xs`` of the selected terms are computed once each (one ``X' x_j`` product
  when term j joins), with ``b = Xs' y``. A forward step solves every candidate's model
  ``S + {j}`` at once from the Cholesky factor ``L`` of ``G[S, S]`` (a bordered solve:
  ``w_j = L^-1 G[S, j]``, pivot ``d_j = 1 - |w_j|^2``, ``theta_j = (b_j - w_j' L^-1 b_S) / d_j``,
  ``theta_S = G[S, S]^-1 (b_S - G[S, j] theta_j)``): the normal equations of the same least
  squares problem. A candidate whose pivot is below :data:`PIVOT_TOL` (nearly a combination of
  the selected terms: the normal equations would lose accuracy), or a step whose ``G[S, S]``
  has such a pivot, is solved by ``numpy.linalg.lstsq`` on ``X`` as the reference does.
* **Free run.** :mod:`identification._semp_kernels` evaluates the subset from the term table
  (input-only factors precomputed once), with the same start, bound and divergence rule. The
  candidates of a forward step run in lockstep groups of :data:`GROUP` (in the order of their
  one-step error-reduction ratio, orthogonalised against the selected terms as FROLS computes
  it, so that good runs finish first), the removals of a pruning likewise (a removal is the
  selected model with that coefficient 0); groups are split over ``workers`` threads (the
  kernels release the GIL). A run is abandoned once its running squared error exceeds the
  best finished one of the step (or the score that would end the path; for a removal, the
  current score): it could not be chosen. The chosen candidate, its score and every pruning
  decision are those of an exhaustive scoring, up to rounding (sums in another order).
* **Shortlist** (only when asked, or when the size estimate exceeds the budget): a forward step
  scores by free run only the ``shortlist`` candidates of largest one-step error-reduction ratio.

Internal module.
"""

from __future__ import annotations

import math
import os
from concurrent.futures import ThreadPoolExecutor

import numpy as np

from ._kernels import expand_terms
from ._semp_kernels import (
    cholesky,
    column_dots,
    gram_row,
    score_groups,
    solve_lower,
    solve_upper_t,
    subset_free_run,
)
from .budget import check_allocation, product
from .regression import lagged_regressors
from .structure import ChannelStructure

__all__ = [
    "GRAM_RATE",
    "PIVOT_TOL",
    "TERM_RATE",
    "CompiledScorer",
    "estimate_seconds",
    "path_work",
    "scaled_lstsq",
]

PIVOT_TOL = 1e-8
"""Smallest relative pivot (energy of a scaled column left after projecting it on the selected
ones) solved through the Gram matrix; below it ``lstsq`` is used."""

TERM_RATE = 4e8
"""Nominal operations per second of one core in the compiled free run (a term of a subset at
one sample costs a multiply-add plus one multiplication per output factor). The kernel ran at
0.6e9 to 1.2e9 per second on the loaded 2-core development box: the estimate is an upper bound
(before early abandonment, and before the scoring threads share the work)."""

GROUP = 16
"""Subsets run in lockstep: consecutive candidates of a forward step (in the order of their
one-step error-reduction ratio), or removals of a pruning."""

GRAM_RATE = 1.5e9
"""Nominal multiply-adds per second of one core in the least squares' passes over the regression
matrix (vectorised dot products; 2.2e9 to 3e9 per second measured on the loaded box)."""

_SLACK = 1e-9  # relative margin on an abandonment cap: rounding never abandons a tie


def path_work(n_candidates: int, n_steps: int, shortlist: int | None = None) -> int:
    """Subset-terms per sample of a SEMP path: the sum over forward steps k = 1 .. ``n_steps``
    of (candidates scored) x k terms, plus the k - 1 pruning runs of k - 1 terms.

    Parameters
    ----------
    n_candidates : int
        Candidate terms M.
    n_steps : int
        Longest path (terms).
    shortlist : int, optional
        Candidates scored per forward step (default: all that are left).
    """
    work = 0
    for k in range(1, n_steps + 1):
        scored = n_candidates - k + 1
        if shortlist is not None:
            scored = min(scored, shortlist)
        work += scored * k + (k - 1) ** 2
    return work


def estimate_seconds(
    n_samples: int, n_candidates: int, n_steps: int, cost: float, shortlist: int | None = None
) -> float:
    """Single-core seconds of a SEMP path by the compiled scorer, at :data:`TERM_RATE`: an upper
    bound (no run abandoned early, every step scored, the longest path). The free runs cost
    ``n_samples * cost * path_work(...)`` operations (at :data:`TERM_RATE`); the least squares
    ``(n_steps + 2) * n_samples * n_candidates`` multiply-adds (a Gram row per selected term,
    the column norms and ``X' y``, at :data:`GRAM_RATE`), which no shortlist reduces.

    Parameters
    ----------
    n_samples : int
        Samples of each free run.
    n_candidates : int
        Candidate terms M.
    n_steps : int
        Longest path (terms).
    cost : float
        Mean cost of one term at one sample (1 + its output factors).
    shortlist : int, optional
        Candidates scored per forward step (default: all that are left).
    """
    runs = n_samples * cost * path_work(n_candidates, n_steps, shortlist)
    gram = (n_steps + 2) * n_samples * n_candidates
    return runs / TERM_RATE + gram / GRAM_RATE


def scaled_lstsq(A: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``numpy.linalg.lstsq`` of ``A x = b`` with the columns of ``A`` scaled to unit norm
    (zero columns left as they are), as the solvers of :mod:`identification.solvers` scale
    them: the default ``rcond`` cut is then relative to well-scaled columns, not to the largest
    one (unscaled, a column 1e12 times smaller than another is cut as if it were null).

    Parameters
    ----------
    A : ndarray (N, k)
        Regression matrix.
    b : ndarray (N,)
        Target.
    """
    norm = np.linalg.norm(A, axis=0)
    norm[norm == 0] = 1.0
    coef, *_ = np.linalg.lstsq(A / norm, b, rcond=None)
    return coef / norm


def _cho_solve(L: np.ndarray, B: np.ndarray) -> np.ndarray:
    """``(L L')^-1 B`` for a lower Cholesky factor ``L`` (a new array)."""
    out = np.array(B, dtype=np.float64, order="C")
    solve_lower(L, out)
    solve_upper_t(L, out)
    return out


def _term_tables(siso: ChannelStructure, inputs, yk, start: int):
    """Output factors of every term and the input-only parts of the output-dependent ones.

    Returns ``src`` (M,), ``nfac`` (M,), ``fac`` (M, L), the fed-back regressors' ``lag``,
    ``fun``, ``bp`` and ``Q`` (N - start, nq) Fortran-ordered (see
    :func:`~identification._semp_kernels.subset_free_run`).
    """
    regs, terms = siso.regressors, siso.terms
    own = np.flatnonzero(regs[:, 0] == 0)  # the channel's own output: fed back
    local = np.full(siso.n_regressors + 1, -1, dtype=np.int64)
    local[own + 1] = np.arange(own.size)
    is_out = local[terms] >= 0  # (M, L)
    nfac = is_out.sum(axis=1).astype(np.int64)
    fac = np.zeros(terms.shape, dtype=np.int64)
    for j in np.flatnonzero(nfac):
        fac[j, : nfac[j]] = local[terms[j][is_out[j]]]
    dependent = np.flatnonzero(nfac)
    parts = np.sort(np.where(is_out, 0, terms)[dependent], axis=1)
    uniq, inv = np.unique(parts, axis=0, return_inverse=True)
    if uniq.shape[0] == 0:
        uniq = np.zeros((1, terms.shape[1]), dtype=np.int64)
    rows = inputs.shape[0] - start
    check_allocation(
        product(rows, uniq.shape[0], 8),
        f"SEMP's input factors ({rows:,} rows x {uniq.shape[0]:,} columns x 8 bytes)",
        "use a lower degree or order, or a shorter record",
    )
    Z = lagged_regressors(inputs, yk[:, None], regs, start, siso.functions, siso.breakpoints)
    Q = np.empty((rows, uniq.shape[0]), order="F")
    expand_terms(Z, np.ascontiguousarray(uniq, dtype=np.int64), Q)
    src = np.arange(terms.shape[0], dtype=np.int64)
    src[dependent] = -1 - np.asarray(inv, dtype=np.int64).ravel()
    rec = (regs[own, 1], siso.functions[own], siso.breakpoints[own])
    lag, fun, bp = (np.ascontiguousarray(a) for a in rec)
    return src, nfac, fac, lag.astype(np.int64), fun.astype(np.int64), bp.astype(float), Q


class CompiledScorer:
    """Scores SEMP subsets of one channel (see the module docstring).

    Parameters
    ----------
    siso : ChannelStructure
        The channel as a single-output structure (own output: source 0).
    X : ndarray (N - start, M)
        The candidate regression matrix (one step, measured outputs).
    inputs : ndarray (N, n)
        The single-output view's inputs (other outputs as measured, then the inputs).
    yk : ndarray (N,)
        The channel's measured output.
    start : int
        First simulated sample.
    bound : float
        Free-run bound (a run leaving it scores inf).
    shortlist : int, optional
        Candidates scored by free run per forward step (default: all).
    workers : int, optional
        Threads scoring candidates (default: the CPU count).
    """

    def __init__(self, siso, X, inputs, yk, start, bound, *, shortlist=None, workers=None):
        self.X = np.asfortranarray(X, dtype=np.float64)
        self.n, self.M = self.X.shape
        self.start, self.bound = int(start), float(bound)
        self.y0 = np.ascontiguousarray(yk, dtype=np.float64)
        self.target = np.ascontiguousarray(self.y0[start:])
        self.tables = _term_tables(siso, inputs, self.y0, start)
        self.cost = 1.0 + float(self.tables[1].mean()) if self.M else 1.0
        norm2 = np.einsum("ij,ij->j", self.X, self.X)
        self.usable = norm2 > 0
        self.scale = np.where(self.usable, 1.0 / np.sqrt(np.where(self.usable, norm2, 1.0)), 0.0)
        self.b = np.empty(self.M)
        column_dots(self.X, self.target, self.b)  # X' y (no BLAS threads: see the kernels)
        self.b *= self.scale
        self.yy = float(self.target @ self.target)
        self._rows: dict[int, np.ndarray] = {}
        self.shortlist = shortlist
        self.workers = max(1, int(workers or os.cpu_count() or 1))
        self._pool: ThreadPoolExecutor | None = None  # started on the first parallel step

    def close(self) -> None:
        """Stop the scoring threads."""
        if self._pool is not None:
            self._pool.shutdown()
            self._pool = None

    # ------------------------------------------------------------------ least squares
    def _row(self, j: int) -> np.ndarray:
        """Row j of the scaled Gram matrix (computed once)."""
        row = self._rows.get(j)
        if row is None:
            row = np.empty(self.M)
            gram_row(self.X, j, self.scale, row)
            self._rows[j] = row
        return row

    def _factor(self, cols) -> np.ndarray | None:
        """Lower Cholesky factor of the scaled ``G[cols, cols]``; None when a pivot is below
        :data:`PIVOT_TOL` (ill-conditioned: use lstsq)."""
        G = np.array([self._row(j)[cols] for j in cols])
        L = np.empty_like(G)
        return L if cholesky(G, L) >= PIVOT_TOL else None

    def _lstsq(self, cols) -> np.ndarray:
        return scaled_lstsq(self.X[:, cols], self.target)

    def solve(self, cols) -> np.ndarray:
        """Least-squares coefficients of the terms ``cols`` (unscaled)."""
        cols = np.asarray(cols, dtype=np.int64)
        L = self._factor(cols)
        if L is None:
            return self._lstsq(cols)
        return _cho_solve(L, self.b[cols][:, None])[:, 0] * self.scale[cols]

    def _removals(self, selected: list, drop: list) -> np.ndarray:
        """Coefficients (len(drop), k - 1) of the models ``selected`` without each term of
        ``drop``: from ``P = G[S, S]^-1`` and ``theta = P b_S``, dropping term i gives
        ``theta - theta_i / P_ii * P[:, i]`` (then without entry i)."""
        S = np.asarray(selected, dtype=np.int64)
        L = self._factor(S)
        if L is None:
            return np.array([self.solve([c for c in selected if c != i]) for i in drop])
        P = _cho_solve(L, np.eye(S.size))
        theta = np.einsum("ij,j->i", P, self.b[S])
        out = np.empty((len(drop), S.size - 1))
        for r, i in enumerate(drop):
            a = selected.index(i)
            full = (theta - theta[a] / P[a, a] * P[:, a]) * self.scale[S]
            out[r] = np.delete(full, a)
        return out

    def _bordered(self, S: np.ndarray, cand: np.ndarray):
        """Coefficients (C, k + 1) of every model ``S + {j}`` (j in ``cand``), in that column
        order, and each candidate's one-step error-reduction ratio."""
        k = S.size
        coefs = np.empty((cand.size, k + 1))
        if k == 0:
            theta = self.b[cand]
            coefs[:, 0] = theta * self.scale[cand]
            return coefs, theta**2 / self.yy
        L = self._factor(S)
        if L is None:  # the selected set itself is ill-conditioned: every candidate by lstsq
            for c, j in enumerate(cand):
                coefs[c] = self._lstsq(np.append(S, j))
            return coefs, np.zeros(cand.size)
        W = np.array([self._row(i)[cand] for i in S])  # G[S, cand]: (k, C)
        solve_lower(L, W)
        z = self.b[S][:, None].copy()
        solve_lower(L, z)
        d2 = 1.0 - np.einsum("ij,ij->j", W, W)
        num = self.b[cand] - np.einsum("ij,i->j", W, z[:, 0])
        good = d2 >= PIVOT_TOL
        theta_j = np.where(good, num / np.where(good, d2, 1.0), 0.0)
        V = W.copy()
        solve_upper_t(L, V)
        solve_upper_t(L, z)
        theta0 = z[:, 0]
        coefs[:, :k] = (theta0[:, None] - V * theta_j).T * self.scale[S]
        coefs[:, k] = theta_j * self.scale[cand]
        for c in np.flatnonzero(~good):  # nearly collinear with S: as the reference solves it
            coefs[c] = self._lstsq(np.append(S, cand[c]))
        err = np.where(good, num**2 / np.where(good, d2, 1.0), 0.0) / self.yy
        return coefs, err

    # ------------------------------------------------------------------ free runs
    def _run_groups(self, S, terms, coefs, ptr, cap: float, lower: bool) -> np.ndarray:
        """Sums of squared errors of the rows of ``terms``/``coefs`` (see
        :func:`~identification._semp_kernels.score_groups`), groups split over the threads."""
        out = np.full(terms.shape[0], np.inf)
        t = self.tables
        best = np.array([cap])

        def run(part):
            score_groups(self.y0, self.start, self.X, t[6], *t[:6], S, terms, coefs, ptr, part,
                         self.target, self.bound, best, lower, out)  # fmt: skip

        groups = np.arange(ptr.size - 1, dtype=np.int64)
        if self.workers == 1 or groups.size < 2:
            run(groups)
            return out
        if self._pool is None:
            self._pool = ThreadPoolExecutor(self.workers, thread_name_prefix="semp")
        parts = [groups[w :: self.workers] for w in range(self.workers)]
        for f in [self._pool.submit(run, p) for p in parts if p.size]:
            f.result()
        return out

    def forward(self, selected, cap: float):
        """The forward step: ``(j, mse)`` of the candidate whose least-squares model with
        ``selected`` has the smallest free-run MSE, or ``(-1, inf)`` when none is bounded and
        at most ``cap`` (an MSE)."""
        S = np.asarray(selected, dtype=np.int64)
        free = self.usable.copy()
        free[S] = False
        cand = np.flatnonzero(free)
        if cand.size == 0:
            return -1, np.inf
        coefs, err = self._bordered(S, cand)
        order = np.argsort(-err, kind="stable")
        if self.shortlist is not None:
            order = order[: self.shortlist]
        ptr = np.append(np.arange(0, order.size, GROUP), order.size).astype(np.int64)
        rows = order
        sse_cap = cap * self.n * (1.0 + _SLACK) if math.isfinite(cap) else np.inf
        sse = np.full(cand.size, np.inf)
        sse[rows] = self._run_groups(
            S, cand[rows], np.ascontiguousarray(coefs[rows]), ptr, sse_cap, True
        )
        c = int(np.argmin(sse))
        if not np.isfinite(sse[c]):
            return -1, np.inf
        return int(cand[c]), float(sse[c]) / self.n

    def prune(self, selected: list, current: float):
        """SEMP pruning: for each term but the last (in order), drop it when the model without
        it has a free-run MSE at most ``current``; returns ``(selected, current)``. The models
        without a term run as the selected model with that term's coefficient 0."""
        pending = list(selected[:-1])
        while pending:
            S = np.asarray(selected, dtype=np.int64)
            coefs = np.zeros((len(pending), S.size))
            rest = self._removals(selected, pending)
            for r, i in enumerate(pending):
                keep = S != i
                coefs[r, keep] = rest[r]
            ptr = np.append(np.arange(0, len(pending), GROUP), len(pending)).astype(np.int64)
            terms = np.full(len(pending), -1, dtype=np.int64)
            sse = self._run_groups(S, terms, coefs, ptr, current * self.n * (1 + _SLACK), False)
            mse = sse / self.n
            accepted = np.flatnonzero(mse <= current)
            if accepted.size == 0:
                break
            a = int(accepted[0])
            selected, current = [c for c in selected if c != pending[a]], float(mse[a])
            pending = pending[a + 1 :]
        return selected, current

    def residual(self, cols) -> np.ndarray:
        """Free-run residual of the least-squares model on ``cols``."""
        cols = np.asarray(cols, dtype=np.int64)
        coef = self.solve(cols)
        y = self.y0.copy()
        t = self.tables
        subset_free_run(
            y, self.start, self.X, t[6], *t[:3], *t[3:6], cols, coef, self.target, self.bound,
            np.inf,
        )
        return self.target - y[self.start :]
