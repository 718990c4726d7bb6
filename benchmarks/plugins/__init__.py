"""Method plugins of the benchmark runner: every module here is loaded by ``python -m benchmarks``.

A plugin module calls :func:`benchmarks.runner.register_method` (see ``inverse_fir.py``, the
README example, and ``sysidentpy_frols.py``, active when SysIdentPy is installed).
"""
