"""Compiled free run with its parameter sensitivity (the output-error Jacobian).

For a condensed MIMO NARX model ``y_k(t) = sum_m theta_m phi_m(z_k(t))`` whose regressors
``z_k`` contain past *simulated* outputs, the derivative of the free run with respect to the
coefficients ``S(t) = d yhat(t) / d theta`` (ny x P) obeys the linear recursion

    S_k(t) = e_k phi(t)  +  sum_{r in output regressors of k}  g_kr(t) * S_{src(r)}(t - lag(r))

with ``g_kr(t) = d F_k / d yhat_src(r)(t - lag(r))``, the model's own partial derivative along the
simulated trajectory (``e_k phi(t)``: the channel's term values in its own parameter block). No
finite differences. With a *horizon* H the record is cut into segments of H samples; each
segment restarts from the measured outputs (the past before it is data, with zero sensitivity):
H = 1 is the one-step-ahead (least-squares) cost, H >= N the pure output-error cost.

Internal module: callers validate inputs. Arrays are contiguous; integer tables are int64.
"""

from __future__ import annotations

import numba as nb
import numpy as np

from ._transforms import apply, derivative

__all__ = ["simulate_with_sensitivity"]


@nb.njit(cache=True, nogil=True)
def _widest_channel(reg_ptr, term_ptr, ny):  # pragma: no cover - compiled
    """Largest number of regressors and of terms of any channel (work-array sizes)."""
    max_r = 0
    max_m = 0
    for k in range(ny):
        max_r = max(max_r, reg_ptr[k + 1] - reg_ptr[k])
        max_m = max(max_m, term_ptr[k + 1] - term_ptr[k])
    return max_r, max_m


@nb.njit(cache=True, nogil=True)
def _restart_segment(Ym, Yw, S, t, p, ring, want_sens):  # pragma: no cover - compiled
    """Segment start at ``t``: the ``p`` samples before it are measured data, sensitivity zero."""
    ny = Ym.shape[1]
    P = S.shape[2]
    for lag in range(1, p + 1):
        for k in range(ny):
            Yw[t - lag, k] = Ym[t - lag, k]
        if want_sens:
            slot = (t - lag) % ring
            for k in range(ny):
                for j in range(P):
                    S[slot, k, j] = 0.0


@nb.njit(cache=True, nogil=True)
def _load_regressors(
    U, Yw, t, ny, r0, nr, reg_src, reg_lag, reg_fn, reg_bp, z, dz, is_out, g
):  # pragma: no cover - compiled
    """Channel regressors ``z[1..nr]`` at ``t`` (and ``dz`` of output ones); clears ``g``."""
    for r in range(nr):
        src = reg_src[r0 + r]
        lag = reg_lag[r0 + r]
        fn = reg_fn[r0 + r]
        bp = reg_bp[r0 + r]
        if src < ny:
            raw = Yw[t - lag, src]
            is_out[r + 1] = True
            dz[r + 1] = derivative(fn, bp, raw)
        else:
            raw = U[t - lag, src - ny]
            is_out[r + 1] = False
        z[r + 1] = apply(fn, bp, raw)
        g[r + 1] = 0.0


@nb.njit(cache=True, nogil=True)
def _channel_output(terms, m0, nm, theta, z, dz, is_out, phi, g, want_sens):  # pragma: no cover
    """Channel prediction ``sum_m theta_m phi_m``; fills ``phi`` and (``want_sens``) ``g``."""
    L = terms.shape[1]
    acc = 0.0
    for m in range(nm):
        v = 1.0
        for f in range(L):
            v *= z[terms[m0 + m, f]]
        phi[m] = v
        acc += theta[m0 + m] * v
        if want_sens:
            # d phi_m / d z_i for every output factor i: product of the other factors
            for f in range(L):
                i = terms[m0 + m, f]
                if i == 0 or not is_out[i]:
                    continue
                other = 1.0
                for f2 in range(L):
                    if f2 != f:
                        other *= z[terms[m0 + m, f2]]
                g[i] += theta[m0 + m] * other * dz[i]
    return acc


@nb.njit(cache=True, nogil=True)
def _propagate_sensitivity(
    S, J, row, t, k, cur, ring, m0, nm, r0, nr, reg_src, reg_lag, phi, g, w
):  # pragma: no cover - compiled
    """``S_k(t) = e_k phi(t) + sum_r g_kr S_src(r)(t - lag(r))`` and its weighted Jacobian row."""
    P = S.shape[2]
    for j in range(P):
        S[cur, k, j] = 0.0
    for m in range(nm):
        S[cur, k, m0 + m] = phi[m]
    for r in range(nr):
        gr = g[r + 1]
        if gr == 0.0:
            continue
        src = reg_src[r0 + r]
        prev = (t - reg_lag[r0 + r]) % ring
        for j in range(P):
            S[cur, k, j] += gr * S[prev, src, j]
    for j in range(P):
        J[row, j] = w * S[cur, k, j]


@nb.njit(cache=True, nogil=True)
def simulate_with_sensitivity(
    U,
    Ym,
    start,
    horizon,
    reg_src,
    reg_lag,
    reg_fn,
    reg_bp,
    reg_ptr,
    terms,
    term_ptr,
    theta,
    weight,
    bound,
    want_sens,
    Yhat,
    E,
    J,
):  # pragma: no cover - compiled
    """Segment-wise free run from measured outputs, residuals and (optionally) the Jacobian.

    ``U`` (N, nu), ``Ym`` (N, ny) measured. Channel k has regressors ``reg_ptr[k]:reg_ptr[k+1]``
    (source, lag, function code, breakpoint; sources < ny are outputs) and terms (= parameters)
    ``term_ptr[k]:term_ptr[k+1]``, rows of ``terms`` indexing ``[1, z_1 .. z_R]`` of the channel.
    Times ``start .. N-1`` are simulated; a segment restarts every ``horizon`` samples.
    Writes ``Yhat[t]``, the weighted residuals ``E[(t - start) * ny + k] = w_k (y - yhat)`` and,
    when ``want_sens``, the weighted Jacobian rows ``J[...] = w_k d yhat_k(t) / d theta``.
    Returns ``(-1, -1)`` or the (channel, sample) where ``|yhat|`` left ``bound`` (or became
    non-finite); the outputs after it are not computed.
    """
    N, ny = Ym.shape
    P = theta.shape[0]
    p = start
    ring = p + 1
    Yw = np.empty((N, ny))
    S = np.zeros((ring, ny, P if want_sens else 1))
    max_r, max_m = _widest_channel(reg_ptr, term_ptr, ny)
    z = np.empty(max_r + 1)
    dz = np.zeros(max_r + 1)
    is_out = np.zeros(max_r + 1, dtype=np.bool_)
    g = np.zeros(max_r + 1)
    phi = np.empty(max_m)
    z[0] = 1.0
    for t in range(p, N):
        if (t - p) % horizon == 0:  # segment start: the past is measured data
            _restart_segment(Ym, Yw, S, t, p, ring, want_sens)
        cur = t % ring
        for k in range(ny):
            r0 = reg_ptr[k]
            nr = reg_ptr[k + 1] - r0
            _load_regressors(
                U, Yw, t, ny, r0, nr, reg_src, reg_lag, reg_fn, reg_bp, z, dz, is_out, g
            )
            m0 = term_ptr[k]
            nm = term_ptr[k + 1] - m0
            acc = _channel_output(terms, m0, nm, theta, z, dz, is_out, phi, g, want_sens)
            Yw[t, k] = acc
            Yhat[t, k] = acc
            row = (t - p) * ny + k
            E[row] = weight[k] * (Ym[t, k] - acc)
            if not (abs(acc) <= bound[k]):  # also catches nan
                return k, t
            if want_sens:
                _propagate_sensitivity(
                    S, J, row, t, k, cur, ring, m0, nm, r0, nr, reg_src, reg_lag, phi, g, weight[k]
                )
    return -1, -1
