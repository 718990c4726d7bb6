"""Condensed NARX model structure: lagged regressors and polynomial term index tables.

The thesis stores each output channel's model as ``Mpar_k`` (eq. 5-23): coefficients, order,
degree and the index tables Π2, Π3 of the quadratic and cubic combinations of the linear terms.
Here the same idea is generalised to any degree:

* ``regressors`` (R, 2): the linear regressors of the channel as (source, lag) pairs. Sources
  ``0 .. ny-1`` are the outputs y1..y_ny, sources ``ny .. ny+nu-1`` the inputs u1..u_nu.
* ``terms`` (M, L): one row per model term, the indices of its L factors into the vector
  ``z = [1, x_1, ..., x_R]``; index 0 is the constant factor 1, so a row ``(0, 0, 5)`` of a cubic
  model is the linear term x_5 and ``(0, 0, 0)`` is the constant. Rows are non-decreasing.

With full-order regressors (eq. 4-15 / 5-3) and all combinations, the term order is the thesis's:
linear terms first, then quadratic, cubic, ... each in lexicographic order of their factors
(Appendix E; Algorithm B.5's P1/P2 index vectors).

Non-polynomial terms (§7.4.1: dead band, backlash-like saturation): each regressor may enter
through a static function ``x -> g(x)`` (``functions``/``breakpoints``, codes of
:data:`identification._transforms.FUNCTIONS`); ``z`` then holds ``g(x)``. A transformed
regressor is a row of its own, with the same (source, lag) as a plain one.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ._transforms import FUNCTIONS, NEEDS_BREAKPOINT
from .budget import check_allocation, product
from .errors import IdentificationError

__all__ = [
    "AUTO_BREAKPOINTS",
    "FUNCTION_SOURCES",
    "TERM_KINDS",
    "ChannelStructure",
    "explicit_regressors",
    "format_count",
    "full_order_regressors",
    "function_regressors",
    "function_specs",
    "polynomial_term_count",
    "polynomial_terms",
    "term_count",
    "term_count_combinatorial",
]

TERM_KINDS = ("full", "pure", "quasi-static", "input-polynomial")
FUNCTION_SOURCES = ("inputs", "outputs", "all")
#: ``("deadzone", "auto")`` / ``("saturation", "auto")``: breakpoints at these multiples of the
#: source channel's standard deviation on the identification data
AUTO_BREAKPOINTS = (0.25, 0.5, 1.0)
_PLAIN_FUNCTIONS = tuple(n for n in FUNCTIONS[1:] if n not in NEEDS_BREAKPOINT)
_ALLOWED = (
    f"{', '.join(repr(n) for n in _PLAIN_FUNCTIONS)}, "
    f"{', '.join(f'({n!r}, b)' for n in NEEDS_BREAKPOINT)} with b > 0 or 'auto'"
)


_BREAKPOINT_CODES = tuple(FUNCTIONS.index(name) for name in NEEDS_BREAKPOINT)


@dataclass(frozen=True, eq=False)
class ChannelStructure:
    """Structure of one output channel: regressors, their functions and the term table.

    Parameters
    ----------
    regressors : ndarray of int, shape (R, 2)
        (source, lag) of each regressor; sources < ny are outputs, the rest inputs.
    terms : ndarray of int, shape (M, L)
        Factor indices of each term into ``[1, x_1 .. x_R]`` (0 = constant factor).
    order : int or None
        The full-order model order n_k when the regressors were built by eq. 5-3, else None.
    functions : ndarray of int, shape (R,), optional
        Static function of each regressor, a code of
        :data:`identification._transforms.FUNCTIONS` (default 0: identity, ``x_r`` itself).
    breakpoints : ndarray of float, shape (R,), optional
        Breakpoint ``b`` of each regressor's function: finite and > 0 for ``deadzone`` and
        ``saturation``, 0 for the others (default all 0).
    """

    regressors: np.ndarray
    terms: np.ndarray
    order: int | None = None
    functions: np.ndarray | None = None
    breakpoints: np.ndarray | None = None

    def __post_init__(self):
        regs = np.ascontiguousarray(self.regressors, dtype=np.int64).reshape(-1, 2)
        terms = np.ascontiguousarray(self.terms, dtype=np.int64)
        if terms.ndim != 2 or terms.shape[1] < 1:
            raise IdentificationError("terms must be a 2-D index table (n_terms, degree)")
        if terms.size and (terms.min() < 0 or terms.max() > regs.shape[0]):
            raise IdentificationError("term factor index out of range of the regressors")
        if terms.shape[1] > 1 and np.any(np.diff(terms, axis=1) < 0):
            raise IdentificationError("term factor indices must be non-decreasing along each row")
        funs, bps = _checked_functions(self.functions, self.breakpoints, regs.shape[0])
        for name, a in (("regressors", regs), ("terms", terms), ("functions", funs)):
            a.setflags(write=False)
            object.__setattr__(self, name, a)
        bps.setflags(write=False)
        object.__setattr__(self, "breakpoints", bps)

    @property
    def degree(self) -> int:
        """Polynomial degree L_k (number of factors per term)."""
        return int(self.terms.shape[1])

    @property
    def n_regressors(self) -> int:
        """Number of regressors (R)."""
        return int(self.regressors.shape[0])

    @property
    def n_terms(self) -> int:
        """Number of terms (coefficients) of the channel."""
        return int(self.terms.shape[0])

    @property
    def max_lag(self) -> int:
        """Largest lag of any regressor, in samples (0 for a static model)."""
        return int(self.regressors[:, 1].max()) if self.regressors.size else 0

    @property
    def transformed(self) -> np.ndarray:
        """Boolean mask (R,) of the regressors that enter through a non-identity function."""
        return self.functions != 0

    def same_as(self, other: ChannelStructure) -> bool:
        """True when both channels have identical regressors, functions and terms (one shared
        regression matrix).

        Parameters
        ----------
        other : ChannelStructure
            The structure to compare with.
        """
        return (
            np.array_equal(self.regressors, other.regressors)
            and np.array_equal(self.functions, other.functions)
            and np.array_equal(self.breakpoints, other.breakpoints)
            and np.array_equal(self.terms, other.terms)
        )

    def regressor_names(self, output_names, input_names) -> list[str]:
        """Regressor names, e.g. ``y1(t-1)``, ``abs(u1(t))``, ``deadzone(u1(t-1), 0.1)``.

        Parameters
        ----------
        output_names, input_names : sequence of str
            Names of the output and input channels the regressors' sources index.
        """
        ny = len(output_names)
        names = []
        for (src, lag), code, b in zip(
            self.regressors, self.functions, self.breakpoints, strict=True
        ):
            base = output_names[src] if src < ny else input_names[src - ny]
            name = f"{base}(t)" if lag == 0 else f"{base}(t-{lag})"
            if code in _BREAKPOINT_CODES:
                name = f"{FUNCTIONS[code]}({name}, {b:.6g})"
            elif code != 0:
                name = f"{FUNCTIONS[code]}({name})"
            names.append(name)
        return names

    def term_names(self, output_names, input_names) -> list[str]:
        """Human-readable term names, e.g. ``y1(t-1)*u2(t)``; the constant is ``1``.

        Parameters
        ----------
        output_names, input_names : sequence of str
            Names of the output and input channels the regressors' sources index.
        """
        regs = self.regressor_names(output_names, input_names)
        out = []
        for row in self.terms:
            factors = [regs[i - 1] for i in row if i > 0]
            out.append("*".join(factors) if factors else "1")
        return out


def _checked_functions(functions, breakpoints, R: int) -> tuple[np.ndarray, np.ndarray]:
    """Validated (R,) int64 function codes and (R,) float64 breakpoints (defaults: zeros)."""
    if functions is None:
        funs = np.zeros(R, dtype=np.int64)
    else:
        raw = np.asarray(functions)
        if raw.shape != (R,) or (raw.size and raw.dtype.kind not in "iu"):
            raise IdentificationError(
                f"functions must hold one integer code per regressor ({R}), got shape {raw.shape} "
                f"and dtype {raw.dtype}"
            )
        funs = np.ascontiguousarray(raw, dtype=np.int64)
        if funs.size and (funs.min() < 0 or funs.max() >= len(FUNCTIONS)):
            raise IdentificationError(
                f"function codes must lie in 0..{len(FUNCTIONS) - 1} "
                f"({', '.join(f'{i} {n}' for i, n in enumerate(FUNCTIONS))}), got {raw.tolist()}"
            )
    if breakpoints is None:
        bps = np.zeros(R)
    else:
        raw = np.asarray(breakpoints)
        if raw.shape != (R,) or (raw.size and raw.dtype.kind not in "iuf"):
            raise IdentificationError(
                f"breakpoints must hold one number per regressor ({R}), got shape {raw.shape}"
            )
        bps = np.array(raw, dtype=np.float64)
    if not np.all(np.isfinite(bps)):
        raise IdentificationError(f"breakpoints must be finite, got {bps.tolist()}")
    needs = np.isin(funs, _BREAKPOINT_CODES)
    if np.any(needs & ~(bps > 0)):
        raise IdentificationError(
            f"{' and '.join(NEEDS_BREAKPOINT)} regressors need a breakpoint > 0, got "
            f"{bps[needs].tolist()}"
        )
    if np.any(~needs & (bps != 0)):
        raise IdentificationError(
            "breakpoints must be 0 for regressors whose function takes none "
            f"({', '.join(n for n in FUNCTIONS if n not in NEEDS_BREAKPOINT)})"
        )
    return funs, bps


def _ranges(starts: np.ndarray, counts: np.ndarray) -> np.ndarray:
    """Concatenation of ``arange(s, s + c)`` for each (s, c), without a Python loop."""
    counts = np.asarray(counts, dtype=np.int64)
    starts = np.asarray(starts, dtype=np.int64)
    offsets = np.cumsum(counts) - counts
    return np.arange(int(counts.sum()), dtype=np.int64) - np.repeat(offsets - starts, counts)


def _check_regressor_table(R: int) -> None:
    check_allocation(
        product(R, 2, 8),
        f"the regressor table ({R:,} regressors x 2 x 8 bytes)",
        "lower the model order (the number of lags)",
    )


def full_order_regressors(ny: int, nu: int, order: int) -> np.ndarray:
    """Linear regressors of the full-order structure (eq. 4-15 / 5-3) for one output channel.

    ``y_1(t-1) .. y_1(t-n), ..., y_ny(t-n), u_1(t) .. u_1(t-n), ..., u_nu(t-n)``:
    na = n for every output, nb = n + 1 terms for every input, nk = 0.

    Parameters
    ----------
    ny, nu : int
        Numbers of output and input channels.
    order : int
        The model order n (output lags 1..n, input lags 0..n, in samples).
    """
    if order < 0:
        raise IdentificationError(f"order must be >= 0, got {order}")
    n = int(order)
    _check_regressor_table(ny * n + nu * (n + 1))
    out_rows = np.column_stack([np.repeat(np.arange(ny), n), np.tile(np.arange(1, n + 1), ny)])
    in_rows = np.column_stack(
        [np.repeat(np.arange(ny, ny + nu), n + 1), np.tile(np.arange(n + 1), nu)]
    )
    return np.concatenate([out_rows, in_rows]).astype(np.int64).reshape(-1, 2)


def explicit_regressors(ny: int, nu: int, na, nb, nk) -> np.ndarray:
    """Linear regressors from explicit ARX orders for one output channel.

    ``na[i]`` output lags 1..na[i] of output i; ``nb[j]`` input terms of input j starting at delay
    ``nk[j]``: lags nk[j] .. nk[j] + nb[j] - 1 (MATLAB ``arx`` convention).

    Parameters
    ----------
    ny, nu : int
        Numbers of output and input channels.
    na : array_like of int (ny,)
        Output lags per output channel (lags 1..na[i], in samples).
    nb : array_like of int (nu,)
        Input terms per input channel.
    nk : array_like of int (nu,)
        Input delay per input channel, in samples.
    """
    na = np.asarray(na, dtype=np.int64).reshape(ny)
    nb = np.asarray(nb, dtype=np.int64).reshape(nu)
    nk = np.asarray(nk, dtype=np.int64).reshape(nu)
    _check_regressor_table(int(na.sum()) + int(nb.sum()))
    out_rows = np.column_stack([np.repeat(np.arange(ny), na), _ranges(np.ones(ny), na)])
    in_rows = np.column_stack([np.repeat(np.arange(ny, ny + nu), nb), _ranges(nk, nb)])
    return np.concatenate([out_rows, in_rows]).astype(np.int64).reshape(-1, 2)


_MAX_COUNT_DIGITS = 4000  # term counts beyond 10**4000 are refused without being computed


def _log10_comb(n: int, k: int) -> float:
    """log10 of C(n, k), from the product formula (inf when it is astronomically large)."""
    k = min(k, n - k)
    if k <= 0:
        return 0.0
    if k > 10**6 or n > 1e300:  # C(n, k) >= 2**k: far beyond any count worth computing
        return math.inf
    i = np.arange(k, dtype=np.float64)
    return float(np.sum(np.log10((float(n) - i) / (i + 1.0))))


def _comb(n: int, k: int, what: str) -> int:
    """``C(n, k)`` exactly; refuses (naming ``what``) a value with more than 4000 digits, which
    no model could hold and whose exact computation alone would take long."""
    log10 = _log10_comb(n, k)
    if log10 > _MAX_COUNT_DIGITS:
        size = "more than 1e1000000" if not math.isfinite(log10) else f"about 1e{log10:.0f}"
        raise IdentificationError(
            f"{what} has {size} terms, far beyond any memory: lower the order or the degree"
        )
    return math.comb(n, k)


def format_count(n: int) -> str:
    """A (possibly huge) integer count, readable: ``1,471,442,973`` or ``3.45e+92``.

    Parameters
    ----------
    n : int
        A count (a Python int of any size).
    """
    s = str(int(n))
    if len(s) <= 16:
        return f"{int(n):,}"
    return f"{s[0]}.{s[1:3]}e+{len(s) - 1}"


def polynomial_term_count(
    regressors: np.ndarray, degree: int, *, kind: str = "full", constant: bool = False, ny: int = 0
) -> int:
    """Number of rows :func:`polynomial_terms` returns, in closed form (nothing is enumerated).

    ``"full"``: ``C(R + L, L) - 1`` (eq. 5-10); ``"pure"``: ``R L``; ``"quasi-static"``:
    ``R + S (L - 1)`` with S the lag-0 input regressors; ``"input-polynomial"``: ``R + C(I + L, L)
    - 1 - I`` with I the input regressors; plus 1 with ``constant``. Same arguments as
    :func:`polynomial_terms`.

    Parameters
    ----------
    regressors : ndarray (R, 2) of int
        ``(source, lag)`` of each regressor (source < ny: an output).
    degree : int
        Polynomial degree L >= 1.
    kind : {"full", "pure", "quasi-static", "input-polynomial"}, optional
        Term set (see :func:`polynomial_terms`).
    constant : bool, optional
        Count the constant term.
    ny : int, optional
        Number of output channels (sources below it are outputs).
    """
    R, L = int(regressors.shape[0]), int(degree)
    what = f"a {kind!r} structure of degree {L} on {R:,} regressors"
    if kind == "full":
        count = _comb(R + L, L, what) - 1
    elif kind == "pure":
        count = R * L
    elif kind == "quasi-static":
        static = int(np.count_nonzero((regressors[:, 0] >= ny) & (regressors[:, 1] == 0)))
        count = R + static * (L - 1)
    else:  # input-polynomial
        n_in = int(np.count_nonzero(regressors[:, 0] >= ny))
        count = R + _comb(n_in + L, L, what) - 1 - n_in
    return count + int(bool(constant))


def _nondecreasing_rows(n_values: int, length: int) -> np.ndarray:
    """Every non-decreasing sequence of ``length`` values from ``0 .. n_values - 1``, in
    lexicographic order (the rows of ``itertools.combinations_with_replacement(range(n_values),
    length)``), built column by column without a Python loop over the rows.

    The table of length l + 1 is, for each first value a, the value a followed by the rows of the
    length-l table whose first value is >= a (a suffix of that table, which is sorted)."""
    values = np.arange(n_values, dtype=np.int64)
    table = values[:, None]
    for _ in range(length - 1):
        start = np.searchsorted(table[:, 0], values, side="left")
        counts = table.shape[0] - start
        rows = _ranges(start, counts)
        table = np.column_stack([np.repeat(values, counts), table[rows]])
    return table


def _padded(factors: np.ndarray, L: int) -> np.ndarray:
    """Factor table (n, d) -> (n, L) with the constant factor 0 in front."""
    out = np.zeros((factors.shape[0], L), dtype=np.int64)
    out[:, L - factors.shape[1] :] = factors
    return out


def polynomial_terms(
    regressors: np.ndarray, degree: int, *, kind: str = "full", constant: bool = False, ny: int = 0
) -> np.ndarray:
    """Term index table for a channel with the given linear regressors.

    Parameters
    ----------
    regressors : ndarray (R, 2)
        The channel's (source, lag) table.
    degree : int
        Polynomial degree L >= 1.
    kind : {"full", "pure", "quasi-static", "input-polynomial"}
        ``"full"``: every monomial of degree 1..L of the regressors (eq. 5-8).
        ``"pure"``: linear terms plus pure powers x_i^2 .. x_i^L, no cross products
        (purely quadratic NARX, eq. 5-24, generalised to degree L).
        ``"quasi-static"``: linear terms plus pure powers of the static (lag-0) input regressors
        only (quasi-static NARX, eq. 5-25).
        ``"input-polynomial"``: linear terms plus every monomial of degree 2..L of the *input*
        regressors only: the outputs enter linearly, so the free run is stable exactly when its
        linear autoregressive part is (useful for inverse models).
    constant : bool
        Add the constant term (first row, all factors 0).
    ny : int
        Number of outputs (needed by ``"quasi-static"`` to tell inputs from outputs).

    Raises
    ------
    IdentificationError
        When the table (terms x L x 8 bytes, counted in closed form by
        :func:`polynomial_term_count` before anything is enumerated) would exceed the memory
        budget (:mod:`identification.budget`).
    """
    if degree < 1:
        raise IdentificationError(f"degree must be >= 1, got {degree}")
    if kind not in TERM_KINDS:
        raise IdentificationError(f"unknown term kind {kind!r}; choose one of {TERM_KINDS}")
    regressors = np.asarray(regressors, dtype=np.int64).reshape(-1, 2)
    R, L = int(regressors.shape[0]), int(degree)
    count = polynomial_term_count(regressors, L, kind=kind, constant=constant, ny=ny)
    check_allocation(
        product(count, L, 8),
        f"the term index table of a {kind!r} structure of degree {L} on {R:,} regressors "
        f"({format_count(count)} terms x {L} factors x 8 bytes)",
        "lower the order or the degree, or choose a smaller term set (kind='pure', "
        "'quasi-static' or 'input-polynomial')",
    )
    if kind == "full":
        # all non-decreasing index rows over [0, 1..R]: the constant, then the linear,
        # quadratic, ... terms, each in lexicographic order: the thesis's ordering.
        combos = _nondecreasing_rows(R + 1, L)
        return combos if constant else combos[1:]
    blocks = [np.zeros((int(bool(constant)), L), dtype=np.int64)]
    blocks.append(_padded(np.arange(1, R + 1, dtype=np.int64)[:, None], L))
    if kind == "input-polynomial":
        inputs = np.flatnonzero(regressors[:, 0] >= ny) + 1
        for d in range(2, L + 1):
            blocks.append(_padded(inputs[_nondecreasing_rows(inputs.size, d)], L))
        return np.concatenate(blocks)
    if kind == "pure":
        powered = np.arange(1, R + 1, dtype=np.int64)
    else:  # quasi-static: lag-0 input regressors
        powered = np.flatnonzero((regressors[:, 0] >= ny) & (regressors[:, 1] == 0)) + 1
    for d in range(2, L + 1):
        blocks.append(_padded(np.repeat(powered[:, None], d, axis=1), L))
    return np.concatenate(blocks)


def _check_counts(ny, nu, order, degree) -> int:
    """Validated arguments of the term-count functions; returns R."""
    for name, v, lo in (("ny", ny, 0), ("nu", nu, 0), ("order", order, 0), ("degree", degree, 1)):
        if not isinstance(v, (int, np.integer)) or isinstance(v, bool) or v < lo:
            raise IdentificationError(f"{name} must be an integer >= {lo}, got {v!r}")
    return int(ny) * int(order) + int(nu) * (int(order) + 1)


def term_count(ny: int, nu: int, order: int, degree: int) -> int:
    """Maximum number of NARX terms of one output channel, eq. 5-10 of the reference text.

    ``M_k = R + sum_{R1=1}^{R} [R1 + sum_{R2=1}^{R1} [R2 + ... + sum_{RL=1}^{R(L-1)} RL]]`` with
    ``R = ny*n_k + nu*(n_k + 1)`` (full-order structure, no constant term). The nested sums
    count the monomials of degree 1..L in R variables, so they are evaluated in closed form,
    ``C(R + L, L) - 1`` (no recursion, no loop over R).

    Parameters
    ----------
    ny, nu : int
        Numbers of output and input channels.
    order : int
        Full-order model order n_k (samples).
    degree : int
        Polynomial degree L >= 1.

    Raises
    ------
    IdentificationError
        When no model of this size can be built: its term index table (M x L x 8 bytes) would
        exceed the memory budget (:mod:`identification.budget`); the message names the count.
        :func:`term_count_combinatorial` returns the bare number for any size.

    Examples
    --------
    >>> term_count(1, 2, 2, 2)   # Example 5.1 / Appendix E
    44
    """
    R = _check_counts(ny, nu, order, degree)
    what = f"term_count(ny={ny}, nu={nu}, order={order}, degree={degree}) (R = {R:,} regressors)"
    count = _comb(R + int(degree), int(degree), what) - 1 if R > 0 else 0
    check_allocation(
        product(count, degree, 8),
        f"{what}: {format_count(count)} terms; their index table (terms x {degree} factors x "
        "8 bytes)",
        "no model of this size can be built; lower the order or the degree",
    )
    return count


def term_count_combinatorial(ny: int, nu: int, order: int, degree: int) -> int:
    """Closed form of eq. 5-10: the number of monomials of degree 1..L in R variables,
    ``C(R + L, L) - 1``, for any size (no memory budget; counts beyond 10^4000 are refused).

    Parameters
    ----------
    ny, nu : int
        Numbers of output and input channels.
    order : int
        Full-order model order n_k (samples).
    degree : int
        Polynomial degree L >= 1.
    """
    R = _check_counts(ny, nu, order, degree)
    what = f"term_count_combinatorial(ny={ny}, nu={nu}, order={order}, degree={degree})"
    return _comb(R + int(degree), int(degree), what) - 1


def _function_spec(spec):
    """One validated spec: ``"abs"``, ``"sign_square"``, ``(name, b)`` with float b or "auto"."""
    if isinstance(spec, str):
        if spec in _PLAIN_FUNCTIONS:
            return spec
        if spec in NEEDS_BREAKPOINT:
            raise IdentificationError(
                f"regressor function {spec!r} needs a breakpoint: give ({spec!r}, b) with b > 0 "
                f"(in the source signal's units) or ({spec!r}, 'auto'), inside the functions "
                f"list; allowed specs: {_ALLOWED}"
            )
        raise IdentificationError(f"unknown regressor function {spec!r}; allowed: {_ALLOWED}")
    if not isinstance(spec, (tuple, list)) or len(spec) != 2 or not isinstance(spec[0], str):
        raise IdentificationError(
            f"a regressor function spec is a name or a (name, breakpoint) pair, got {spec!r}; "
            f"allowed: {_ALLOWED}"
        )
    name, b = spec
    if name in _PLAIN_FUNCTIONS:
        raise IdentificationError(
            f"regressor function {name!r} takes no breakpoint, got {spec!r}; give it as {name!r}"
        )
    if name not in NEEDS_BREAKPOINT:
        raise IdentificationError(f"unknown regressor function {name!r}; allowed: {_ALLOWED}")
    if isinstance(b, str) and b == "auto":
        return (name, "auto")
    if isinstance(b, (bool, np.bool_)) or not isinstance(b, (int, float, np.integer, np.floating)):
        raise IdentificationError(
            f"breakpoint of {name!r} must be a finite number > 0 or 'auto', got {b!r}"
        )
    if not (math.isfinite(b) and b > 0):
        raise IdentificationError(
            f"breakpoint of {name!r} must be a finite number > 0 or 'auto', got {b!r}"
        )
    return (name, float(b))


def function_specs(functions) -> tuple:
    """Validate ``Narx``'s ``functions`` argument; returns the normalised tuple of specs.

    Parameters
    ----------
    functions : sequence or None
        Each item ``"abs"``, ``"sign_square"``, ``("deadzone", b)`` or ``("saturation", b)``
        with ``b`` a finite number > 0 or ``"auto"``.

    Returns
    -------
    tuple
        Names as strings, breakpoint specs as ``(name, float)`` or ``(name, "auto")``; empty
        for None.
    """
    if functions is None:
        return ()
    if isinstance(functions, (str, bytes)) or not isinstance(functions, (tuple, list)):
        raise IdentificationError(
            f"functions must be a list of regressor function specs, e.g. ['abs', "
            f"('deadzone', 0.1)], got {functions!r}; allowed specs: {_ALLOWED}"
        )
    specs = tuple(_function_spec(f) for f in functions)
    for i, spec in enumerate(specs):
        if spec in specs[:i]:
            raise IdentificationError(f"functions lists {spec!r} twice")
    return specs


def function_regressors(
    regressors: np.ndarray, specs, *, sources: str, ny: int, scale: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The transformed regressors a channel gains from its function specs.

    Parameters
    ----------
    regressors : ndarray (R, 2)
        The channel's plain (source, lag) regressors.
    specs : tuple
        Normalised specs from :func:`function_specs`.
    sources : {"inputs", "outputs", "all"}
        Which plain regressors get the function versions.
    ny : int
        Number of outputs (sources below it are outputs).
    scale : ndarray (n_sources,)
        Standard deviation of each source channel, for ``"auto"`` breakpoints (multiples
        :data:`AUTO_BREAKPOINTS` of it). A source with zero deviation gets no "auto" versions.

    Returns
    -------
    regressors (F, 2), functions (F,), breakpoints (F,)
        One row per spec, breakpoint and selected regressor, in that nesting order; exact
        duplicates are dropped.
    """
    if sources not in FUNCTION_SOURCES:
        raise IdentificationError(
            f"function_sources must be one of {FUNCTION_SOURCES}, got {sources!r}"
        )
    is_out = regressors[:, 0] < ny
    pick = {"inputs": ~is_out, "outputs": is_out, "all": np.ones_like(is_out)}[sources]
    chosen = regressors[pick]
    rows: dict[tuple, None] = {}
    for spec in specs:
        name, b = (spec, 0.0) if isinstance(spec, str) else spec
        code = FUNCTIONS.index(name)
        for frac in AUTO_BREAKPOINTS if b == "auto" else (None,):
            for src, lag in chosen:
                bp = b if frac is None else frac * float(scale[src])
                if bp > 0 or name not in NEEDS_BREAKPOINT:
                    rows[(int(src), int(lag), code, float(bp))] = None
    table = list(rows)
    regs = np.array([r[:2] for r in table], dtype=np.int64).reshape(-1, 2)
    funs = np.array([r[2] for r in table], dtype=np.int64)
    bps = np.array([r[3] for r in table], dtype=np.float64)
    return regs, funs, bps
