"""Least-squares estimators for linear-in-the-parameters models (Section 5.3, Appendix C).

Every estimator is a plain function with one signature::

    coef = solver(X, Y, *, rcond=None)

``X`` is the regression matrix (N, M), ``Y`` the targets (N,) or (N, k) — several output channels
that share ``X`` are solved together with a single factorisation. The result has shape (M,) or
(M, k). Columns are scaled to unit norm before factorising (the solution is unchanged; rank
decisions become scale-free), their norms taken after dividing each by its largest magnitude, so
that neither overflows nor underflows: a least-squares fit is scale-invariant, and records of any
magnitude whose regression terms are finite float64 numbers (e.g. 1e100, or 1e-200) are solved
as well as records of magnitude 1. A rank-deficient problem (relative singular value below ``rcond``,
default ``max(N, M) * eps``) gives a :class:`~identification.errors.RankDeficiencyWarning` naming
the effective rank, and the minimum-norm solution.

* ``qr``          LAPACK blocked Householder QR, ``Q^T Y`` by ``dormqr`` (default; Q never formed)
* ``householder`` Householder triangularisation written out as Algorithm C.8
* ``mgs``         modified Gram-Schmidt, Algorithms C.5 / C.6
* ``cgs``         classical Gram-Schmidt, Algorithm C.4, with one re-orthogonalisation (CGS2)
* ``svd``         SVD pseudo-inverse, eq. C-3..C-7 (LAPACK gelsd)
* ``normal``      normal equations by Cholesky, eq. 5-17; warns when ill-conditioned
"""

from __future__ import annotations

import functools
import warnings

import numpy as np
import scipy.linalg as sla
from scipy.linalg import lapack

from .errors import IdentificationError, IllConditionedWarning, RankDeficiencyWarning

__all__ = ["SOLVERS", "cgs", "get_solver", "householder", "mgs", "normal", "qr", "svd"]

_EPS = np.finfo(np.float64).eps


def _default_rcond(N: int, M: int, rcond: float | None) -> float:
    if rcond is None:
        return max(N, M) * _EPS
    if not (0 <= rcond < 1):
        raise IdentificationError(f"rcond must be in [0, 1), got {rcond}")
    return float(rcond)


def _warn_rank(rank: int, M: int, name: str) -> None:
    warnings.warn(
        f"{name}: regression matrix is rank deficient (effective rank {rank} of {M} terms); "
        "returning the minimum-norm solution. Reduce the model order/degree, remove constant or "
        "duplicated channels, or use a richer identification signal.",
        RankDeficiencyWarning,
        stacklevel=4,
    )


def _solver(func):
    """Validate, scale columns to unit norm, call the core, warn on rank deficiency.

    A core ``func(Xs, Y, tol, norms) -> (coef, rank)`` gets the column-scaled matrix ``Xs`` and
    the column norms, and returns coefficients of the original (unscaled) problem and the
    numerical rank of ``Xs``.
    """

    @functools.wraps(func)
    def wrapper(X, Y, *, rcond: float | None = None):
        X = np.asarray(X, dtype=np.float64)
        Y = np.asarray(Y, dtype=np.float64)
        if X.ndim != 2:
            raise IdentificationError(f"X must be 2-D (N, M), got shape {X.shape}")
        vector = Y.ndim == 1
        if vector:
            Y = Y[:, None]
        if Y.ndim != 2 or Y.shape[0] != X.shape[0]:
            raise IdentificationError(
                f"Y must have shape (N,) or (N, k) with N = {X.shape[0]}, got {Y.shape}"
            )
        N, M = X.shape
        if N < M:
            raise IdentificationError(
                f"{N} equations for {M} unknowns: need at least as many samples as terms"
            )
        if not (np.all(np.isfinite(X)) and np.all(np.isfinite(Y))):
            raise IdentificationError("X and Y must be finite (NaN or inf found)")
        tol = _default_rcond(N, M, rcond)
        Xs, norms, live = _unit_columns(X)
        coef = np.zeros((M, Y.shape[1]))
        rank = 0
        if Xs.shape[1]:
            coef[live], rank = func(Xs, Y, tol, norms)
        if rank < M:
            _warn_rank(rank, M, func.__name__)
        return coef[:, 0] if vector else coef

    return wrapper


def _unit_columns(X: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(Xs, norms, live)``: the non-zero columns of ``X`` (``live``) scaled to unit norm, as a
    Fortran-ordered copy, and their norms.

    Each column is divided by its largest magnitude before its norm is taken (LAPACK ``dnrm2``'s
    idea), so the norm neither overflows nor underflows wherever the column itself is finite:
    regression terms of records of magnitude 1e100 (squares 1e400) or 1e-200 give the same
    scaled problem, hence the same solution up to the scale, as records of magnitude 1.
    """
    peak = np.maximum(X.max(axis=0, initial=0.0), -X.min(axis=0, initial=0.0))
    live = peak > 0
    Xs = np.empty((X.shape[0], int(live.sum())), order="F")
    np.divide(X if np.all(live) else X[:, live], peak[live], out=Xs)
    unit = np.sqrt(np.einsum("ij,ij->j", Xs, Xs))
    Xs /= unit
    return Xs, peak[live] * unit, live


def _truncated_solve(A: np.ndarray, B: np.ndarray, rank: int) -> np.ndarray:
    """Minimum-norm solution of ``A theta ~ B`` keeping the ``rank`` largest singular values."""
    U, s, Vt = sla.svd(A, full_matrices=False, check_finite=False)
    return Vt[:rank].T @ ((U[:, :rank].T @ B) / s[:rank, None])


def _finish_triangular(Rs: np.ndarray, QtY: np.ndarray, tol: float, norms: np.ndarray):
    """Solve ``Rs theta_s = Q^T Y`` for the scaled problem and return the original coefficients.

    If ``Rs`` is numerically singular (relative singular value below ``tol``), the numerical
    rank r is decided on ``Rs`` (scale-free) and the minimum-norm solution of the original
    problem is returned: ``X = Q Rs D`` with ``D = diag(norms)``, and
    ``||X theta - Y||^2 = ||Rs D theta - Q^T Y||^2 + const``, so the rank-r pseudo-inverse of
    the small matrix ``Rs D`` gives it.
    """
    M = Rs.shape[0]
    diag = np.abs(np.diag(Rs))
    ok = diag.min() > tol * diag.max()
    if ok:
        rc, info = lapack.dtrcon(Rs, norm="1", uplo="U", diag="N")
        ok = info == 0 and rc > tol
    if ok:
        return sla.solve_triangular(Rs, QtY, lower=False, check_finite=False) / norms[:, None], M
    s = sla.svd(Rs, compute_uv=False, check_finite=False)
    rank = int(np.sum(s > tol * s[0])) if s[0] > 0 else 0
    if rank == M:
        return sla.solve_triangular(Rs, QtY, lower=False, check_finite=False) / norms[:, None], M
    return _truncated_solve(Rs * norms, QtY, rank), rank


@_solver
def qr(X, Y, tol, norms):
    """Least squares by LAPACK Householder QR (``dgeqrf``, blocked) and ``dormqr`` for ``Q^T Y``.

    Q is never formed; all output channels are solved with the one factorisation. ``X`` (the
    wrapper's scaled copy) is factorised in place.

    Parameters
    ----------
    X : array_like, shape (N, M)
        Regression matrix: N samples (equations) of M terms, N >= M, finite.
    Y : array_like, shape (N,) or (N, k)
        Targets; k output channels that share ``X`` are solved with one factorisation.
    rcond : float, optional
        Relative singular value (of the column-scaled matrix) below which a direction counts as
        zero, in [0, 1); default ``max(N, M) * eps``.
    """
    M = X.shape[1]
    lwork = int(lapack.dgeqrf(X, lwork=-1)[2][0])
    qr_a, tau, _work, info = lapack.dgeqrf(X, lwork=max(lwork, 1), overwrite_a=True)
    if info != 0:  # pragma: no cover - LAPACK argument error
        raise RuntimeError(f"dgeqrf failed with info={info}")
    C = np.asfortranarray(Y)
    lwork = int(lapack.dormqr("L", "T", qr_a, tau, C, lwork=-1)[1][0])
    QtY, _work, info = lapack.dormqr("L", "T", qr_a, tau, C, lwork=max(lwork, 1))
    if info != 0:  # pragma: no cover
        raise RuntimeError(f"dormqr failed with info={info}")
    R = np.triu(qr_a[:M, :M])
    return _finish_triangular(R, QtY[:M], tol, norms)


@_solver
def householder(X, Y, tol, norms):
    """Least squares by explicit Householder reflections on ``[X | Y]`` (Algorithm C.8).

    Parameters
    ----------
    X : array_like, shape (N, M)
        Regression matrix: N samples (equations) of M terms, N >= M, finite.
    Y : array_like, shape (N,) or (N, k)
        Targets; k output channels that share ``X`` are solved with one factorisation.
    rcond : float, optional
        Relative singular value (of the column-scaled matrix) below which a direction counts as
        zero, in [0, 1); default ``max(N, M) * eps``.
    """
    M = X.shape[1]
    A = np.hstack([X, Y])
    for j in range(M):
        col = A[j:, j]
        s = np.linalg.norm(col)
        if s == 0.0:
            continue
        sign = 1.0 if col[0] >= 0 else -1.0
        v = col.copy()
        v[0] += sign * s
        beta = 1.0 / (s * (s + abs(col[0])))
        A[j:, j:] -= np.outer(v, beta * (v @ A[j:, j:]))
    R = np.triu(A[:M, :M])
    return _finish_triangular(R, A[:M, M:], tol, norms)


def _gram_schmidt_to_r(W_norms_sq, Amat, g):
    # X = W A (A unit upper triangular), D = W^T W = diag(d): R = sqrt(D) A, Q^T Y = sqrt(D) g.
    sd = np.sqrt(W_norms_sq)
    return sd[:, None] * Amat, sd[:, None] * g


@_solver
def mgs(X, Y, tol, norms):
    """Least squares by modified Gram-Schmidt orthogonalisation (Algorithms C.5 and C.6).

    Parameters
    ----------
    X : array_like, shape (N, M)
        Regression matrix: N samples (equations) of M terms, N >= M, finite.
    Y : array_like, shape (N,) or (N, k)
        Targets; k output channels that share ``X`` are solved with one factorisation.
    rcond : float, optional
        Relative singular value (of the column-scaled matrix) below which a direction counts as
        zero, in [0, 1); default ``max(N, M) * eps``.
    """
    M = X.shape[1]
    Xk = X.copy()
    Yk = Y.copy()
    Amat = np.eye(M)
    d = np.zeros(M)
    g = np.zeros((M, Y.shape[1]))
    for k in range(M):
        w = Xk[:, k]
        d[k] = w @ w
        if d[k] <= (tol * tol):  # dependent column: leave its row zero (rank-deficient path)
            d[k] = 0.0
            continue
        Amat[k, k + 1 :] = (w @ Xk[:, k + 1 :]) / d[k]
        Xk[:, k + 1 :] -= np.outer(w, Amat[k, k + 1 :])
        g[k] = (w @ Yk) / d[k]
        Yk -= np.outer(w, g[k])
    R, QtY = _gram_schmidt_to_r(d, Amat, g)
    return _finish_triangular(R, QtY, tol, norms)


@_solver
def cgs(X, Y, tol, norms):
    """Least squares by classical Gram-Schmidt orthogonalisation (Algorithm C.4, eq. C-17/C-18).

    Plain classical Gram-Schmidt loses orthogonality in proportion to the condition number
    (the reference text notes its sensitivity to round-off); here each column is orthogonalised
    twice ("twice is enough", CGS2: Giraud, Langou & Rozloznik 2005), which makes it as accurate
    as modified Gram-Schmidt while keeping the classical, matrix-vector form of Algorithm C.4.

    Parameters
    ----------
    X : array_like, shape (N, M)
        Regression matrix: N samples (equations) of M terms, N >= M, finite.
    Y : array_like, shape (N,) or (N, k)
        Targets; k output channels that share ``X`` are solved with one factorisation.
    rcond : float, optional
        Relative singular value (of the column-scaled matrix) below which a direction counts as
        zero, in [0, 1); default ``max(N, M) * eps``.
    """
    M = X.shape[1]
    W = np.empty_like(X)
    Amat = np.eye(M)
    d = np.zeros(M)
    for k in range(M):
        w = X[:, k].copy()
        if k:
            live = d[:k] > 0
            Wl = W[:, :k][:, live]
            for _pass in range(2):
                alpha = (Wl.T @ w) / d[:k][live]
                w -= Wl @ alpha
                Amat[np.flatnonzero(live), k] += alpha
        W[:, k] = w
        d[k] = w @ w
        if d[k] <= (tol * tol):
            d[k] = 0.0
    g = np.zeros((M, Y.shape[1]))
    live = d > 0
    g[live] = (W[:, live].T @ Y) / d[live, None]
    R, QtY = _gram_schmidt_to_r(d, Amat, g)
    return _finish_triangular(R, QtY, tol, norms)


@_solver
def svd(X, Y, tol, norms):
    """Minimum-norm least squares by the SVD pseudo-inverse (eq. C-3 to C-7; LAPACK gelsd).

    Singular values below ``rcond * s_max`` of the column-scaled matrix are treated as zero
    (eq. C-5); with a rank deficiency the minimum-norm solution of the original problem is
    computed from the SVD of the unscaled matrix truncated at that rank.

    Parameters
    ----------
    X : array_like, shape (N, M)
        Regression matrix: N samples (equations) of M terms, N >= M, finite.
    Y : array_like, shape (N,) or (N, k)
        Targets; k output channels that share ``X`` are solved with one factorisation.
    rcond : float, optional
        Relative singular value (of the column-scaled matrix) below which a direction counts as
        zero, in [0, 1); default ``max(N, M) * eps``.
    """
    coef, _res, rank, _s = sla.lstsq(X, Y, cond=tol, lapack_driver="gelsd", check_finite=False)
    if rank == X.shape[1]:
        return coef / norms[:, None], int(rank)
    return _truncated_solve(X * norms, Y, int(rank)), int(rank)


# normal equations lose about log10(cond(X^T X)) digits; warn beyond half the available precision
_NORMAL_WARN_COND = 1.0 / np.sqrt(_EPS)


@_solver
def normal(X, Y, tol, norms):
    """Least squares by the normal equations ``X^T X theta = X^T Y`` (eq. 5-17), Cholesky.

    Squares the condition number: warns with :class:`IllConditionedWarning` when
    cond(X^T X) > 1/sqrt(eps) (more than half the digits lost). When X^T X is not numerically
    positive definite, its eigenvalues below ``rcond`` times the largest are treated as zero
    (the rank the normal equations can resolve) and the minimum-norm solution is returned.

    Parameters
    ----------
    X : array_like, shape (N, M)
        Regression matrix: N samples (equations) of M terms, N >= M, finite.
    Y : array_like, shape (N,) or (N, k)
        Targets; k output channels that share ``X`` are solved with one factorisation.
    rcond : float, optional
        Relative singular value (of the column-scaled matrix) below which a direction counts as
        zero, in [0, 1); default ``max(N, M) * eps``.
    """
    G = X.T @ X
    b = X.T @ Y
    M = X.shape[1]
    rc = 0.0
    try:
        c, lower = sla.cho_factor(G, lower=False, check_finite=False)
        rc, info = lapack.dpocon(c, np.abs(G).sum(axis=0).max())
        if info != 0:  # pragma: no cover
            rc = 0.0
    except np.linalg.LinAlgError:
        pass
    if rc == 0.0 or 1.0 / rc > _NORMAL_WARN_COND:
        cond = "> 1e16" if rc <= _EPS else f"{1.0 / rc:.2e}"
        warnings.warn(
            f"normal: X^T X is ill-conditioned (estimated condition {cond}); the solution may "
            "have lost most of its digits. Use solver='qr'.",
            IllConditionedWarning,
            stacklevel=3,
        )
    if rc > _EPS:
        return sla.cho_solve((c, lower), b, check_finite=False) / norms[:, None], M
    w = np.linalg.eigvalsh(G)
    rank = int(np.sum(w > tol * w.max()))
    Gd = G * np.outer(norms, norms)  # X^T X of the unscaled problem
    wd, V = np.linalg.eigh(Gd)
    keep = np.argsort(wd)[::-1][:rank]
    V = V[:, keep]
    return V @ ((V.T @ (b * norms[:, None])) / wd[keep, None]), rank


SOLVERS = {
    "qr": qr,
    "householder": householder,
    "mgs": mgs,
    "cgs": cgs,
    "svd": svd,
    "normal": normal,
}


def get_solver(name):
    """Return the solver function for ``name`` (or ``name`` itself if it is callable).

    Parameters
    ----------
    name : str or callable
        One of the names in :data:`SOLVERS` (``"qr"``, ``"householder"``, ``"mgs"``, ``"cgs"``,
        ``"svd"``, ``"normal"``), or a solver function ``solver(X, Y, *, rcond=None) -> coef``.
    """
    if callable(name):
        return name
    try:
        return SOLVERS[name]
    except (KeyError, TypeError):
        raise IdentificationError(
            f"unknown solver {name!r}; choose one of {sorted(SOLVERS)} or pass a callable "
            "solver(X, Y, *, rcond=None) -> coef"
        ) from None
