"""Compiled kernels (numba): term expansion and the free-run recursion.

Internal module: callers validate inputs. Arrays are contiguous; integer tables are int64.
Regressors may pass through static functions (codes and breakpoints of
:mod:`identification._transforms`); models without them take the plain paths.
"""

from __future__ import annotations

import numba as nb
import numpy as np

from ._transforms import apply

__all__ = ["expand_terms", "free_run", "input_coefficients", "windowed_free_run"]


@nb.njit(cache=True, nogil=True)
def expand_terms(Z, terms, out):  # pragma: no cover - compiled
    """Fill ``out[:, m]`` with the product of the columns ``Z[:, terms[m, :]]``.

    ``Z`` (rows, R + 1) is Fortran-ordered with ``Z[:, 0] == 1``; ``out`` (rows, >= M) is
    Fortran-ordered. Factors equal to 0 (the constant) are skipped, so a linear term is a copy.
    Factors are multiplied left to right, as :func:`free_run` does.
    """
    rows = Z.shape[0]
    M = terms.shape[0]
    L = terms.shape[1]
    for m in range(M):
        first = -1
        for f in range(L):
            if terms[m, f] != 0:
                first = f
                break
        if first < 0:
            for i in range(rows):
                out[i, m] = 1.0
            continue
        a = terms[m, first]
        for i in range(rows):
            out[i, m] = Z[i, a]
        for f in range(first + 1, L):
            b = terms[m, f]
            for i in range(rows):
                out[i, m] *= Z[i, b]


@nb.njit(cache=True, nogil=True)
def input_coefficients(
    U, t0, t1, reg_src, reg_lag, reg_fun, reg_bp, parent, factor, e_mono, e_col, e_coef, columns, A
):  # pragma: no cover
    """Input-dependent coefficients ``A[t - t0, col]`` of the output monomials, t in [t0, t1).

    Input regressor r is ``g(U[t - reg_lag[r], reg_src[r]])`` with ``g`` the function
    ``reg_fun[r]`` (breakpoint ``reg_bp[r]``; 0 = identity, a plain copy); input monomial i is
    ``P[:, parent[i]] * Z[:, factor[i]]`` (monomial 0 = 1, ``Z[:, 0] = 1``); entry e adds
    ``e_coef[e] * P[:, e_mono[e]]`` to column ``e_col[e]`` of ``A``. ``A`` is Fortran-ordered;
    the listed ``columns`` are zeroed first. Every loop runs along time, so it vectorises.
    """
    n = t1 - t0
    R = reg_src.shape[0]
    Z = np.empty((R + 1, n))
    for i in range(n):
        Z[0, i] = 1.0
    for r in range(R):
        s = reg_src[r]
        base = t0 - reg_lag[r]
        code = reg_fun[r]
        if code == 0:
            for i in range(n):
                Z[r + 1, i] = U[base + i, s]
        else:
            b = reg_bp[r]
            for i in range(n):
                Z[r + 1, i] = apply(code, b, U[base + i, s])
    P = np.empty((parent.shape[0], n))
    for i in range(n):
        P[0, i] = 1.0
    for m in range(1, parent.shape[0]):
        p = parent[m]
        f = factor[m]
        for i in range(n):
            P[m, i] = P[p, i] * Z[f, i]
    for c in columns:
        for i in range(n):
            A[i, c] = 0.0
    for e in range(e_mono.shape[0]):
        c = e_col[e]
        mi = e_mono[e]
        w = e_coef[e]
        for i in range(n):
            A[i, c] += w * P[mi, i]


@nb.njit(cache=True, nogil=True)
def free_run(
    Y, start, stop, A, reg_src, reg_lag, reg_fun, reg_bp, reg_ptr, parent, factor, mono_ptr, bound
):  # pragma: no cover
    """Free-run recursion of a MIMO polynomial NARX model written as a polynomial in past outputs.

    ``Y`` (N, ny) C-ordered: rows ``< start`` hold past outputs; rows ``start .. stop-1`` are
    computed. Channel ``k`` has output regressors ``reg_ptr[k]:reg_ptr[k+1]`` (output index, lag
    >= 1) and output monomials ``mono_ptr[k]:mono_ptr[k+1]``; monomial 0 of each channel is the
    constant and monomial ``m`` is ``mono[parent[m]] * z[factor[m]]`` with ``z[0] = 1``,
    ``z[r + 1]`` = output regressor r passed through its function ``reg_fun[r]`` (breakpoint
    ``reg_bp[r]``; when every code is 0 the plain copy loop runs). ``A[t - start, m]`` is the coefficient of monomial m at
    time t: everything that depends only on the inputs, precomputed outside the recursion, so
    the loop costs one multiplication and one multiply-add per distinct output monomial.
    Returns ``(-1, -1)`` or the (channel, sample) where ``|y|`` exceeded ``bound[channel]`` or
    became non-finite (that value is left in ``Y``).
    """
    ny = Y.shape[1]
    max_r = 0
    max_m = 0
    for k in range(ny):
        max_r = max(max_r, reg_ptr[k + 1] - reg_ptr[k])
        max_m = max(max_m, mono_ptr[k + 1] - mono_ptr[k])
    plain = True
    for r in range(reg_fun.shape[0]):
        if reg_fun[r] != 0:
            plain = False
    z = np.empty(max_r + 1)
    mono = np.empty(max_m)
    z[0] = 1.0
    mono[0] = 1.0
    for t in range(start, stop):
        row = t - start
        for k in range(ny):
            r0 = reg_ptr[k]
            if plain:
                for r in range(reg_ptr[k + 1] - r0):
                    z[r + 1] = Y[t - reg_lag[r0 + r], reg_src[r0 + r]]
            else:
                for r in range(reg_ptr[k + 1] - r0):
                    x = Y[t - reg_lag[r0 + r], reg_src[r0 + r]]
                    z[r + 1] = apply(reg_fun[r0 + r], reg_bp[r0 + r], x)
            m0 = mono_ptr[k]
            nm = mono_ptr[k + 1] - m0
            par = parent[m0 : m0 + nm]
            fac = factor[m0 : m0 + nm]
            coef = A[row, m0 : m0 + nm]
            for m in range(1, nm):
                mono[m] = mono[par[m]] * z[fac[m]]
            acc = 0.0
            for m in range(nm):
                acc += coef[m] * mono[m]
            Y[t, k] = acc
            mag = abs(acc)
            if not (mag <= bound[k]) or mag == np.inf:  # also catches nan
                return k, t
    return -1, -1


@nb.njit(cache=True, nogil=True)
def windowed_free_run(
    Y, Ymeas, start, stop, k, p, A, S, reg_src, reg_lag, reg_fun, reg_bp, reg_ptr, parent, factor,
    mono_ptr, bound,
):  # pragma: no cover
    """k-step-ahead prediction: :func:`free_run` restarted from measured outputs every k rows.

    Windows start at ``start, start + k, ...`` (< ``stop``); the window at ``i`` copies the
    measured rows ``Ymeas[i - p : i]`` into the scratch ``S`` (>= p + k rows), runs the free run
    over ``min(k, stop - i)`` rows and writes them to ``Y[i : ...]``. ``A[t - start]`` holds the
    input coefficients of row t (as for :func:`free_run`). Each window's arithmetic is exactly
    that of a free run started at ``i`` from ``Ymeas[i - p : i]``. Returns ``(-1, -1)`` or the
    (channel, row of ``Y``) where the bound was left (that value is left in ``Y``).
    """
    ny = Y.shape[1]
    for i in range(start, stop, k):
        n = min(k, stop - i)
        for r in range(p):
            for c in range(ny):
                S[r, c] = Ymeas[i - p + r, c]
        ch, t = free_run(
            S, p, p + n, A[i - start : i - start + n], reg_src, reg_lag, reg_fun, reg_bp,
            reg_ptr, parent, factor, mono_ptr, bound,
        )
        last = n if ch < 0 else t - p + 1
        for r in range(last):
            for c in range(ny):
                Y[i + r, c] = S[p + r, c]
        if ch >= 0:
            return ch, i + t - p
    return -1, -1
