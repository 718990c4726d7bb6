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
accepted pruning, since the sum only grows. :func:`score_groups` runs groups of subsets in
lockstep (the subsets of a forward step share the selected terms), vectorised over the group.

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
    "column_dots",
    "gram_row",
    "score_groups",
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


@nb.njit(cache=True, nogil=True, fastmath={"reassoc", "contract"})
def column_dots(X, v, out):  # pragma: no cover - compiled
    """``out[c] = X[:, c] . v`` (``X`` Fortran-ordered): ``X' v`` without a BLAS call."""
    n, M = X.shape
    for c in range(M):
        acc = 0.0
        for i in range(n):
            acc += X[i, c] * v[i]
        out[c] = acc


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



# ------------------------------------------------------------------ lockstep groups
# The subsets of a forward step are the selected terms S plus one candidate each: a group of
# them runs in lockstep, every per-sample loop running over the group's members (contiguous
# arrays), which the compiler vectorises. The members differ by the coefficients and by their
# candidate term: its input-only factor and its output factors (gathered per member; a missing
# factor is a row of ones).
_SMALL_GROUP = 4  # groups smaller than this run one subset at a time


@nb.njit(cache=True, nogil=True)
def _group_layout(src, nfac, fac, lag, S, owns):  # pragma: no cover - compiled
    """Tables of a group's program. The terms S: ``X`` column (-1: output-dependent), ``Q``
    column, factor count and factors as rows of ``z``; the members' terms ``owns``: factor rows
    (padded with the row of ones, ``used.size``); ``used``: the fed-back regressors (rows of
    ``z``) the program needs."""
    k, G, D, R = S.shape[0], owns.shape[0], fac.shape[1], lag.shape[0]
    need = np.zeros(R, dtype=np.bool_)
    for j in S:
        for f in range(nfac[j]):
            need[fac[j, f]] = True
    for j in owns:
        for f in range(nfac[j]):
            need[fac[j, f]] = True
    used = np.flatnonzero(need)
    row = np.zeros(R, dtype=np.int64)
    for r in range(used.shape[0]):
        row[used[r]] = r
    xcol = np.full(k, -1, dtype=np.int64)
    qcol = np.zeros(k, dtype=np.int64)
    nf = np.zeros(k, dtype=np.int64)
    frow = np.zeros((k, D), dtype=np.int64)
    for m in range(k):
        j = S[m]
        if nfac[j] == 0:
            xcol[m] = src[j]
        else:
            qcol[m] = -1 - src[j]
        nf[m] = nfac[j]
        for f in range(nfac[j]):
            frow[m, f] = row[fac[j, f]]
    ofr = np.full((D, G), used.shape[0], dtype=np.int64)
    for g in range(G):
        for f in range(nfac[owns[g]]):
            ofr[f, g] = row[fac[owns[g], f]]
    return xcol, qcol, nf, frow, ofr, used


@nb.njit(cache=True, nogil=True, fastmath={"reassoc", "contract"})
def _group_block(X, Q, b0, b1, xcol, own_src, th, c, B):  # pragma: no cover - compiled
    """Rows ``b0 .. b1 - 1``: ``B[i, g]`` the members' own input-only factors (column
    ``own_src[g]`` of ``X``, or of ``Q`` when negative), ``c[i, g]`` the sum of the input-only
    terms of S (coefficients ``th[m, g]``)."""
    G = th.shape[1]
    for i in range(b1 - b0):
        for g in range(G):
            c[i, g] = 0.0
    for g in range(own_src.shape[0]):
        s = own_src[g]
        for i in range(b1 - b0):
            B[i, g] = X[b0 + i, s] if s >= 0 else Q[b0 + i, -1 - s]
    for m in range(xcol.shape[0]):
        if xcol[m] >= 0:
            col = xcol[m]
            for i in range(b1 - b0):
                x = X[b0 + i, col]
                for g in range(G):
                    c[i, g] += th[m, g] * x


@nb.njit(cache=True, nogil=True, fastmath={"reassoc", "contract"})
def _group_run(
    y0, start, X, Q, lag, fun, bp, layout, own_src, th, own_w, target, bound, cap, sse
):  # pragma: no cover - compiled
    """Free runs of one group in lockstep (``th`` (k, G): the coefficients of S; ``own_w``
    (G,): of each member's own term, or empty); ``sse[g]``: the sum of squared errors, or
    ``inf`` (left ``bound``, not finite, or above ``cap``: checked at each block's end)."""
    xcol, qcol, nf, frow, ofr, used = layout
    G, k, nu, D = th.shape[1], xcol.shape[0], used.shape[0], ofr.shape[0]
    n = y0.shape[0] - start
    L = 1
    for r in range(nu):
        L = max(L, lag[used[r]] + 1)
    ring = np.empty((L, G))  # y(t) of every member at row t % L
    for t in range(max(start - L, 0), start):
        for g in range(G):
            ring[t % L, g] = y0[t]
    plain = True
    for r in range(nu):
        plain &= fun[used[r]] == 0
    z = np.ones((nu + 1, G))  # the last row stays 1: a missing factor
    c, B = np.empty((_BLOCK, G)), np.empty((_BLOCK, G))
    acc, v = np.empty(G), np.empty(G)
    bad = np.zeros(G, dtype=np.bool_)
    sse[:] = 0.0
    for b0 in range(0, n, _BLOCK):
        b1 = min(b0 + _BLOCK, n)
        _group_block(X, Q, b0, b1, xcol, own_src, th, c, B)
        for i in range(b0, b1):
            t = start + i
            for r in range(nu):
                slot = (t - lag[used[r]]) % L
                for g in range(G):
                    x = ring[slot, g]
                    z[r, g] = x if plain else apply(fun[used[r]], bp[used[r]], x)
            for g in range(G):
                acc[g] = c[i - b0, g]
            for m in range(k):
                if xcol[m] < 0:
                    q = Q[i, qcol[m]]
                    for g in range(G):
                        v[g] = q
                    for f in range(nf[m]):
                        zr = frow[m, f]
                        for g in range(G):
                            v[g] *= z[zr, g]
                    for g in range(G):
                        acc[g] += th[m, g] * v[g]
            if own_w.shape[0]:
                for g in range(G):
                    v[g] = B[i - b0, g]
                for f in range(D):
                    for g in range(G):
                        v[g] *= z[ofr[f, g], g]
                for g in range(G):
                    acc[g] += own_w[g] * v[g]
            slot = t % L
            for g in range(G):
                a = acc[g]
                ring[slot, g] = a
                mag = abs(a)
                bad[g] |= not (mag <= bound) or mag == np.inf  # also catches nan
                e = target[i] - a
                sse[g] += e * e
        live = 0
        for g in range(G):
            if bad[g] or sse[g] > cap:
                sse[g] = np.inf
            else:
                live += 1
        if live == 0:
            return


@nb.njit(cache=True, nogil=True)
def score_groups(
    y0, start, X, Q, src, nfac, fac, lag, fun, bp, S, terms, coefs, ptr, order, target, bound,
    best, lower, out,
):  # pragma: no cover - compiled
    """Sums of squared free-run errors of groups of subsets, each group run in lockstep.

    Row ``c`` of ``terms``/``coefs``/``out`` is a subset: the terms ``S`` (coefficients
    ``coefs[c, :S.size]``) plus, when ``terms[c] >= 0``, the term ``terms[c]`` (coefficient
    ``coefs[c, S.size]``); group ``q`` is rows ``ptr[q] .. ptr[q + 1] - 1`` (their extra terms
    all present or all absent). The groups ``order`` are run in turn, each from the measured
    past ``y0[:start]`` (as :func:`subset_free_run`); runs whose sum exceeds ``best[0]`` are
    abandoned (``inf``, checked at block ends). With ``lower`` a finished group lowers
    ``best[0]`` to its smallest sum (``best`` may be shared by concurrent calls: every value
    written is a finished run's sum).
    """
    k = S.shape[0]
    y = np.empty(y0.shape[0])
    y[:start] = y0[:start]
    for q in order:
        a, b = ptr[q], ptr[q + 1]
        G = b - a
        if G < _SMALL_GROUP:  # too few to gain from lockstep: one run each
            for c in range(a, b):
                sel = np.append(S, terms[c]) if terms[c] >= 0 else S
                v = subset_free_run(y, start, X, Q, src, nfac, fac, lag, fun, bp, sel,
                                    coefs[c, : sel.shape[0]], target, bound, best[0])  # fmt: skip
                out[c] = v
                if lower and v < best[0]:
                    best[0] = v
            continue
        owns = terms[a:b].copy() if terms[a] >= 0 else np.empty(0, dtype=np.int64)
        layout = _group_layout(src, nfac, fac, lag, S, owns)
        th = np.empty((k, G))
        own_w = np.zeros(owns.shape[0])
        own_src = np.empty(owns.shape[0], dtype=np.int64)
        for g in range(G):
            for m in range(k):
                th[m, g] = coefs[a + g, m]
        for g in range(owns.shape[0]):
            own_src[g] = src[owns[g]]
            own_w[g] = coefs[a + g, k]
        sse = np.empty(G)
        _group_run(y0, start, X, Q, lag, fun, bp, layout, own_src, th, own_w, target, bound,
                   best[0], sse)  # fmt: skip
        for g in range(G):
            out[a + g] = sse[g]
            if lower and sse[g] < best[0]:
                best[0] = sse[g]
