"""The memory budget: sizes are checked before anything large is allocated.

Every identification function that allocates an array whose size follows from the caller's
arguments (the term index table, the regression matrix, forward regression's working copy, the
output-error Jacobian, a generated signal) computes its size first, in Python integers (no
overflow), and refuses it with a :class:`~identification.errors.MemoryBudgetError` (an
:class:`~identification.errors.IdentificationError`) that names
the size and what to change when it exceeds :data:`MEMORY_BUDGET_BYTES`.

The budget bounds each *single* array. A least-squares fit holds the regression matrix and one
working copy of it (the solver's column-scaled copy, or forward regression's orthogonalised
copy), so its peak is about twice the budget.

To allow larger problems on a large machine, assign a new value::

    import identification.budget
    identification.budget.MEMORY_BUDGET_BYTES = 16 * 2**30
"""

from __future__ import annotations

import math

from .errors import MemoryBudgetError

__all__ = ["MEMORY_BUDGET_BYTES", "check_allocation", "format_bytes", "product"]

MEMORY_BUDGET_BYTES = 2 * 2**30
"""Largest single array (in bytes) an identification function allocates: 2 GiB."""


def format_bytes(n: int) -> str:
    """``n`` bytes as a short human-readable size (any size, no float overflow).

    Parameters
    ----------
    n : int
        A size in bytes.
    """
    n = int(n)
    if n < 2**20:
        return f"{n / 2**10:.3g} KiB"
    if n < 2**30:
        return f"{n / 2**20:.3g} MiB"
    digits = len(str(n // 2**30))
    if digits <= 15:
        return f"{n / 2**30:.3g} GiB"
    return f"about 1e{digits - 1} GiB"


def check_allocation(n_bytes: int, what: str, remedy: str) -> None:
    """Raise :class:`~identification.errors.MemoryBudgetError` (an ``IdentificationError``)
    when ``n_bytes`` exceeds :data:`MEMORY_BUDGET_BYTES`.

    Parameters
    ----------
    n_bytes : int
        Size of the array about to be allocated (compute it in Python integers).
    what : str
        What the array is and how its size follows, e.g. ``"the regression matrix (9000 rows x
        454 terms x 8 bytes)"``.
    remedy : str
        What the caller can change to stay within the budget.
    """
    budget = MEMORY_BUDGET_BYTES
    if n_bytes > budget:
        raise MemoryBudgetError(
            f"{what} would take {format_bytes(n_bytes)}, beyond the memory budget of "
            f"{format_bytes(budget)} per array (identification.budget.MEMORY_BUDGET_BYTES): "
            f"{remedy}"
        )


def product(*dims: int) -> int:
    """Exact product of array dimensions as a Python integer (no int64 overflow).

    Parameters
    ----------
    *dims : int
        Array dimensions (numbers of elements along each axis).
    """
    return math.prod(int(d) for d in dims)
