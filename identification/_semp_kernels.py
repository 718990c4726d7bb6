"""Compiled free run of a *subset* of a channel's candidate terms, read from the term table.

Free-run selection (:mod:`identification.free_run_selection`) scores thousands of candidate
term subsets of one output channel, each with its own least-squares coefficients. Compiling a
:class:`~identification.simulation.SimulationPlan` per subset costs more than the free run
itself, so these kernels evaluate the subset directly from tables built once per selection:

* every candidate term is ``b_j(t) * prod_f g_f(y(t - lag_f))``: an input-only factor ``b_j``
  (a column of the regression matrix ``X`` for a term without output factors, else a column of
  ``Q``, the distinct input-only parts of the output-dependent terms, ``Q[:, 0] = 1``) times its
  factors in the channel's own past outputs, passed through their static functions;
* the recursion computes the fed-back regressors ``g_r(y(t - lag_r))`` once per sample, then
  ``y(t) = sum_i coef_i * b_{j_i}(t) * prod z[factors of j_i]`` over the subset's terms.

A run stops early (returns ``inf``) when its output leaves ``bound`` or is not finite (as
:func:`~identification._kernels.free_run` reports divergence) or when its running sum of squared
errors exceeds ``cap``: a run abandoned that way cannot be the best of a forward step nor an
accepted pruning, since the sum only grows.

The free run and the Gram row are compiled with ``fastmath={"reassoc", "contract"}``: sums may
be reordered and fused into multiply-adds (the rounding differs from
:func:`~identification.simulation.simulate_plan`'s by a few units in the last place; the
divergence test on ``nan``/``inf`` is unaffected: no ``nnan``/``ninf`` assumption).

Internal module: callers validate inputs. Arrays are contiguous (``X``, ``Q`` Fortran-ordered);
integer tables are int64.
"""

from __future__ import annotations

import numba as nb
import numpy as np

from ._transforms import apply

__all__ = [
    "cholesky",
    "gram_row",
    "score_subsets",
    "solve_lower",
    "solve_upper_t",
    "subset_free_run",
]


_BLOCK = 256  # samples whose input-only sum is computed (vectorised) ahead of the recursion


@nb.njit(cache=True, nogil=True)
def _program(src, nfac, fac, R, sel, coef):  # pragma: no cover - compiled
    """The subset split for :func:`subset_free_run`: the input-only terms (column of ``X``,
    coefficient), the output-dependent ones (column of ``Q``, coefficient, factor count,
    factors as indices into ``used``) and ``used``, the fed-back regressors they need."""
    K = sel.shape[0]
    D = fac.shape[1]
    n_in = 0
    need = np.zeros(R, dtype=np.bool_)
    for m in range(K):
        j = sel[m]
        if nfac[j] == 0:
            n_in += 1
        for f in range(nfac[j]):
            need[fac[j, f]] = True
    used = np.flatnonzero(need)
    local = np.zeros(R, dtype=np.int64)
    for r in range(used.shape[0]):
        local[used[r]] = r
    n_out = K - n_in
    in_col, in_w = np.empty(n_in, dtype=np.int64), np.empty(n_in)
    out_col, out_w = np.empty(n_out, dtype=np.int64), np.empty(n_out)
    out_nf, out_f = np.empty(n_out, dtype=np.int64), np.zeros((n_out, D), dtype=np.int64)
    a = 0
    for m in range(K):
        j = sel[m]
        if nfac[j] == 0:
            in_col[a], in_w[a] = src[j], coef[m]
            a += 1
        else:
            b = m - a
            out_col[b], out_w[b], out_nf[b] = -1 - src[j], coef[m], nfac[j]
            for f in range(nfac[j]):
                out_f[b, f] = local[fac[j, f]]
    return in_col, in_w, out_col, out_w, out_nf, out_f, used


@nb.njit(cache=True, nogil=True, fastmath={"reassoc", "contract"})
def _input_only_block(y, t0, c, target, bound):  # pragma: no cover - compiled
    """A block of a subset without output-dependent terms: ``y[t0 : t0 + len(c)] = c`` (no
    recursion); returns the block's squared error, ``inf`` if it leaves ``bound``."""
    bad = False
    sse = 0.0
    for i in range(c.shape[0]):
        mag = abs(c[i])
        bad |= not (mag <= bound) or mag == np.inf
        y[t0 + i] = c[i]
        e = target[i] - c[i]
        sse += e * e
    return np.inf if bad else sse


@nb.njit(cache=True, nogil=True, fastmath={"reassoc", "contract"})
def subset_free_run(
    y, start, X, Q, src, nfac, fac, lag, fun, bp, sel, coef, target, bound, cap
):  # pragma: no cover - compiled
    """Free run of the terms ``sel`` (coefficients ``coef``) over rows ``start ..`` of ``y``.

    ``y`` (N,): rows ``< start`` hold the measured past, rows ``start .. N-1`` are overwritten
    with the free run. ``X`` (N - start, M) and ``Q`` (N - start, nq) hold the input-only
    factors of row ``t`` at ``t - start``; term ``j``'s is ``X[:, src[j]]`` when ``src[j] >= 0``
    (a term without output factors) and ``Q[:, -1 - src[j]]`` otherwise; its output factors are
    the regressors ``fac[j, :nfac[j]]``, regressor ``r`` being ``g(y(t - lag[r]))`` with ``g``
    the function ``fun[r]`` (breakpoint ``bp[r]``). ``target`` (N - start,) is the measured
    output. The terms without output factors are summed ahead, a block of samples at a time;
    the recursion adds the others (and evaluates only the regressors they use).

    Returns the sum of squared errors against ``target``, or ``inf`` when the run left
    ``bound`` (or became non-finite) or its running sum exceeded ``cap``.
    """
    n = y.shape[0] - start
    in_col, in_w, out_col, out_w, out_nf, out_f, used = _program(
        src, nfac, fac, lag.shape[0], sel, coef
    )
    plain = True
    for r in used:
        plain &= fun[r] == 0
    z = np.empty(max(used.shape[0], 1))
    c = np.empty(_BLOCK)
    sse = 0.0
    for b0 in range(0, n, _BLOCK):
        b1 = min(b0 + _BLOCK, n)
        c[: b1 - b0] = 0.0
        for m in range(in_col.shape[0]):
            w, col = in_w[m], in_col[m]
            for i in range(b0, b1):
                c[i - b0] += w * X[i, col]
        if out_col.shape[0] == 0:
            sse += _input_only_block(y, start + b0, c[: b1 - b0], target[b0:b1], bound)
            if sse > cap:  # also inf: left the bound
                return np.inf
            continue
        for i in range(b0, b1):
            t = start + i
            for r in range(used.shape[0]):
                v = y[t - lag[used[r]]]
                z[r] = v if plain else apply(fun[used[r]], bp[used[r]], v)
            acc = c[i - b0]
            for m in range(out_col.shape[0]):
                v = Q[i, out_col[m]]
                for f in range(out_nf[m]):
                    v *= z[out_f[m, f]]
                acc += out_w[m] * v
            y[t] = acc
            mag = abs(acc)
            if not (mag <= bound) or mag == np.inf:  # also catches nan
                return np.inf
            e = target[i] - acc
            sse += e * e
            if sse > cap:
                return np.inf
    return sse


@nb.njit(cache=True, nogil=True)
def score_subsets(
    y0, start, X, Q, src, nfac, fac, lag, fun, bp, sets, coefs, sizes, order, target, bound,
    best, out,
):  # pragma: no cover - compiled
    """Sum of squared free-run errors of the subsets ``order`` (indices into ``sets``).

    Subset ``c`` is the terms ``sets[c, :sizes[c]]`` with coefficients ``coefs[c, :sizes[c]]``;
    each run starts from the measured past ``y0[:start]`` (see :func:`subset_free_run`). Runs
    whose sum exceeds ``best[0]`` are abandoned (``out[c] = inf``); a finished run lowers
    ``best[0]`` to its sum. ``best`` may be shared by concurrent calls (threads scoring other
    subsets): every value written to it is a finished run's sum, so it is always an upper bound
    of the smallest sum, and the smallest sum's run is never abandoned.
    """
    y = np.empty(y0.shape[0])
    for r in range(start):
        y[r] = y0[r]
    for c in order:
        k = sizes[c]
        v = subset_free_run(
            y, start, X, Q, src, nfac, fac, lag, fun, bp, sets[c, :k], coefs[c, :k], target,
            bound, best[0],
        )
        out[c] = v
        if v < best[0]:
            best[0] = v


# Small dense linear algebra of the scorer's least squares, compiled: the matrices are k x k
# (k <= the path length) and k x C; a multithreaded BLAS spends more time starting its
# threads than computing them, and competes with the scoring threads.
@nb.njit(cache=True, nogil=True, fastmath={"reassoc", "contract"})
def gram_row(X, j, scale, out):  # pragma: no cover - compiled
    """``out[c] = scale[c] * scale[j] * (X[:, c] . X[:, j])`` (``X`` Fortran-ordered)."""
    n, M = X.shape
    for c in range(M):
        acc = 0.0
        for i in range(n):
            acc += X[i, c] * X[i, j]
        out[c] = acc * scale[c] * scale[j]


@nb.njit(cache=True, nogil=True)
def cholesky(A, L):  # pragma: no cover - compiled
    """Lower Cholesky factor of the symmetric ``A`` (k, k) into ``L``; returns the smallest
    squared pivot ``L[i, i]^2`` (<= 0: not positive definite, ``L`` incomplete)."""
    k = A.shape[0]
    L[:, :] = 0.0
    smallest = np.inf
    for j in range(k):
        d = A[j, j]
        for p in range(j):
            d -= L[j, p] * L[j, p]
        smallest = min(smallest, d)
        if not d > 0.0:
            return d
        L[j, j] = np.sqrt(d)
        for i in range(j + 1, k):
            s = A[i, j]
            for p in range(j):
                s -= L[i, p] * L[j, p]
            L[i, j] = s / L[j, j]
    return smallest


@nb.njit(cache=True, nogil=True)
def solve_lower(L, B):  # pragma: no cover - compiled
    """``B <- L^-1 B`` in place (``L`` lower triangular (k, k), ``B`` (k, C))."""
    k, C = B.shape
    for i in range(k):
        for p in range(i):
            w = L[i, p]
            for c in range(C):
                B[i, c] -= w * B[p, c]
        inv = 1.0 / L[i, i]
        for c in range(C):
            B[i, c] *= inv


@nb.njit(cache=True, nogil=True)
def solve_upper_t(L, B):  # pragma: no cover - compiled
    """``B <- L^-T B`` in place (``L`` lower triangular (k, k), ``B`` (k, C))."""
    k, C = B.shape
    for i in range(k - 1, -1, -1):
        for p in range(i + 1, k):
            w = L[p, i]
            for c in range(C):
                B[i, c] -= w * B[p, c]
        inv = 1.0 / L[i, i]
        for c in range(C):
            B[i, c] *= inv

