"""One BLAS thread per benchmark process, unless the environment says otherwise.

The runner computes records in parallel worker processes (one per core by default) and runs
the thesis reproduction in a process of its own; each would otherwise start as many OpenBLAS
threads as the machine has cores. On the 2-core box that is 4-6 BLAS threads on 2 cores, and
the many small least-squares solves of a fit (a lead search, SEMP) then spend their time
handing work between threads that wait for a core: a ``narx-sim`` record took 2.7-5x longer
with 2 BLAS threads than with one, at 4-5x the CPU time, while other jobs loaded the box, and
its record was the same to the last bit (``benchmarks/README.md``, Runner). The parallelism is
across records, not inside one.

:func:`one_blas_thread` sets ``OPENBLAS_NUM_THREADS``, ``OMP_NUM_THREADS`` and
``MKL_NUM_THREADS`` to 1 where they are not set, for the processes started afterwards (and for
this one, if it has not loaded NumPy yet). A value the user set is kept: e.g.
``OPENBLAS_NUM_THREADS=2 python -m benchmarks.thesis_tables --quick``. This module imports
nothing that loads a BLAS.
"""

from __future__ import annotations

import os

__all__ = ["BLAS_THREAD_VARS", "one_blas_thread"]

BLAS_THREAD_VARS = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")
"""The environment variables that size the BLAS/OpenMP thread pools (read when a BLAS loads)."""


def one_blas_thread() -> dict[str, str]:
    """Set each of :data:`BLAS_THREAD_VARS` to ``"1"`` unless it is set already.

    Returns
    -------
    dict
        ``{variable: value}`` now in force (the user's where given).
    """
    for name in BLAS_THREAD_VARS:
        os.environ.setdefault(name, "1")
    return {name: os.environ[name] for name in BLAS_THREAD_VARS}
