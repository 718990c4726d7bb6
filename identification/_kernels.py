"""Compiled kernels (numba): term expansion and the free-run recursion.

Internal module: callers validate inputs. Arrays are contiguous; integer tables are int64.
"""

from __future__ import annotations

import numba as nb
import numpy as np

__all__ = ["expand_terms", "free_run"]


@nb.njit(cache=True, parallel=True, nogil=True)
def expand_terms(Z, terms, out):  # pragma: no cover - compiled
    """Fill ``out[:, m]`` with the product of the columns ``Z[:, terms[m, :]]``.

    ``Z`` (rows, R + 1) is Fortran-ordered with ``Z[:, 0] == 1``; ``out`` (rows, >= M) is
    Fortran-ordered. Factors equal to 0 (the constant) are skipped, so a linear term is a copy.
    Factors are multiplied left to right, as :func:`free_run` does.
    """
    rows = Z.shape[0]
    M = terms.shape[0]
    L = terms.shape[1]
    for m in nb.prange(M):
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
def free_run(U, Y, start, reg_src, reg_lag, reg_ptr, parent, factor, coef, mono_ptr, bound):  # pragma: no cover
    """Free-run (simulation) of a MIMO polynomial NARX model, Algorithm 5.2.

    ``U`` (N, nu) inputs, ``Y`` (N, ny) outputs, C-ordered; rows ``< start`` of ``Y`` hold the
    initial conditions and rows ``>= start`` are overwritten. Channel ``k`` has regressors
    ``reg_ptr[k]:reg_ptr[k+1]`` (source, lag; sources ``>= ny`` are inputs) and monomials
    ``mono_ptr[k]:mono_ptr[k+1]``; the first monomial of every channel is the constant 1, and
    monomial ``m`` is ``mono[parent[m]] * z[factor[m]]`` (``z[0] = 1``, ``z[r + 1]`` = regressor r),
    so each term costs one multiplication. Returns ``(-1, -1)`` on success or the (channel, sample)
    where ``|y|`` exceeded ``bound[channel]`` or became non-finite (that value is left in ``Y``).
    """
    N = U.shape[0]
    ny = Y.shape[1]
    max_r = 0
    max_m = 0
    for k in range(ny):
        max_r = max(max_r, reg_ptr[k + 1] - reg_ptr[k])
        max_m = max(max_m, mono_ptr[k + 1] - mono_ptr[k])
    z = np.empty(max_r + 1)
    mono = np.empty(max_m)
    z[0] = 1.0
    mono[0] = 1.0
    for t in range(start, N):
        for k in range(ny):
            r0 = reg_ptr[k]
            for r in range(r0, reg_ptr[k + 1]):
                s = reg_src[r]
                if s < ny:
                    z[r - r0 + 1] = Y[t - reg_lag[r], s]
                else:
                    z[r - r0 + 1] = U[t - reg_lag[r], s - ny]
            m0 = mono_ptr[k]
            acc = coef[m0]
            for m in range(m0 + 1, mono_ptr[k + 1]):
                v = mono[parent[m]] * z[factor[m]]
                mono[m - m0] = v
                acc += coef[m] * v
            Y[t, k] = acc
            if not (abs(acc) <= bound[k]):
                return k, t
    return -1, -1
