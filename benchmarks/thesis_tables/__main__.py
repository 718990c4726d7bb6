"""``python -m benchmarks.thesis_tables``: one BLAS thread before NumPy loads
(:mod:`benchmarks.threads`), then :func:`benchmarks.thesis_tables.report.main`."""

from benchmarks.threads import one_blas_thread

one_blas_thread()

from benchmarks.thesis_tables.report import main  # noqa: E402  (after the BLAS threads are set)

raise SystemExit(main())
