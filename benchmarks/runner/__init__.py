"""The reconstruction benchmark runner (``python -m benchmarks run``, ``vrig bench``).

Records (rig × method × desired response × seed, × severity and target when asked) are pure
functions of their key; they run in parallel (processes by default, or Ray) and are written one
file each, atomically, so a run resumes after an interrupt. See ``benchmarks/README.md`` (section Runner).
"""

from .execute import BACKENDS, Store, execute
from .record import RecordKey, Settings, compute_record, record_id, strip_timing
from .registry import MethodPlugin, get_method, load_plugins, method_names, register_method
from .report import leaderboard, write_outputs

__all__ = [
    "BACKENDS",
    "MethodPlugin",
    "RecordKey",
    "Settings",
    "Store",
    "compute_record",
    "execute",
    "get_method",
    "leaderboard",
    "load_plugins",
    "method_names",
    "record_id",
    "register_method",
    "strip_timing",
    "write_outputs",
]
