"""Running records: the results store (atomic, resumable) and the three backends.

The store is a folder: ``settings.json`` (the run settings the records were made with) and
``records/<id>.json``, one file per finished record, written atomically (temporary file in the
same folder, ``fsync``, ``os.replace``). A re-run skips every record whose file exists with the
same settings, so an interrupted run resumes where it stopped; a half-written temporary file
left by a kill is ignored and removed, and a record file that is not a finished, well-formed
record of this run (cut short, tampered with, another record's, another run's, NaN scores:
:func:`~.record.check_record`) is recomputed.

Backends: ``serial`` (this process), ``process`` (default: a ``ProcessPoolExecutor`` with the
*spawn* start method, safest with MuJoCo and numba; its workers die with the runner, even on a
``kill -9``: :func:`~.lifetime.die_with_parent`; each uses one BLAS thread unless
``OPENBLAS_NUM_THREADS`` etc. are set: :mod:`benchmarks.threads`) and ``ray`` (an existing Ray cluster with
``--address``, else a local one). Every backend runs the same pure function
:func:`~.record.compute_record` on the same keys, so the records are identical; only the
parent process writes files.

Progress: one line per finished record (``log``, stdout) and, while records run, a status line
on stderr every :data:`HEARTBEAT_S` seconds in which none finished (how many are done, how long
the run has taken), so a long record never leaves the terminal silent.
"""

from __future__ import annotations

import json
import multiprocessing
import os
import sys
import threading
import time
from collections.abc import Callable, Iterable
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import asdict
from pathlib import Path

from ..threads import one_blas_thread
from .lifetime import die_with_parent
from .record import SCHEMA, RecordKey, Settings, check_record, compute_record, record_id

__all__ = ["BACKENDS", "SettingsMismatchError", "Store", "execute", "write_atomic"]

BACKENDS = ("process", "serial", "ray")
HEARTBEAT_S = 20.0
"""Seconds without a finished record after which the runner prints a status line (stderr)."""


class SettingsMismatchError(ValueError):
    """The results folder holds records made with other settings."""


def write_atomic(path: Path, text: str) -> None:
    """Write ``text`` to ``path`` atomically (temporary file + ``os.replace``)."""
    path = Path(path)
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    with open(tmp, "w", encoding="utf-8") as fh:
        fh.write(text)
        fh.flush()
        os.fsync(fh.fileno())
    os.replace(tmp, path)


class Store:
    """The results folder of a run."""

    def __init__(self, out: Path):
        self.out = Path(out)
        self.records_dir = self.out / "records"

    def prepare(self, settings: Settings, *, overwrite: bool = False) -> None:
        """Create the folder; refuse (or with ``overwrite`` clear) records of other settings."""
        self.records_dir.mkdir(parents=True, exist_ok=True)
        for tmp in self.records_dir.glob(".*.tmp"):  # left by a killed run
            tmp.unlink(missing_ok=True)
        path = self.out / "settings.json"
        wanted = {"schema": SCHEMA, **asdict(settings)}
        if path.exists():
            have = json.loads(path.read_text())
            if have != wanted:
                if not overwrite:
                    raise SettingsMismatchError(
                        f"{self.out} holds records made with other settings ({have}); use "
                        "another --out, or --overwrite to delete them"
                    )
                for f in self.records_dir.glob("*.json"):
                    f.unlink()
        elif overwrite:
            for f in self.records_dir.glob("*.json"):
                f.unlink()
        write_atomic(path, json.dumps(wanted, indent=1) + "\n")

    def path(self, key: RecordKey) -> Path:
        return self.records_dir / f"{record_id(key)}.json"

    def load(self, key: RecordKey) -> dict | None:
        """The parsed file of ``key``'s record (None if missing or not JSON; not validated)."""
        try:
            return json.loads(self.path(key).read_text())
        except (OSError, ValueError):
            return None

    def finished(self, key: RecordKey, settings: Settings) -> bool:
        """Whether the store holds a finished, well-formed record of ``key`` made with
        ``settings`` (:func:`~.record.check_record`); anything else is recomputed."""
        return check_record(self.load(key), key, settings) is None

    def write(self, record: dict) -> Path:
        path = self.records_dir / f"{record['id']}.json"
        write_atomic(path, json.dumps(record, indent=1, ensure_ascii=False) + "\n")
        return path

    def all_records(self, settings: Settings | None = None) -> list[dict]:
        """Every well-formed record in the store (made with ``settings``, when given) whose
        file name is its id; malformed or foreign files are left out (see :meth:`rejected`)."""
        return [rec for _f, rec, why in self._scan(settings) if why is None]

    def rejected(self, settings: Settings | None = None) -> dict[str, str]:
        """``{file name: why}`` of the record files :meth:`all_records` leaves out."""
        return {f.name: why for f, _rec, why in self._scan(settings) if why is not None}

    def _scan(self, settings):
        for f in sorted(self.records_dir.glob("*.json")):
            try:
                rec = json.loads(f.read_text())
            except (OSError, ValueError) as exc:
                yield f, None, f"unreadable ({type(exc).__name__})"
                continue
            why = check_record(rec, None, settings)
            if why is None and f.stem != rec["id"]:
                why = f"holds the record {rec['id']}"
            yield f, rec, why


# ---------------------------------------------------------------------------------------------
# backends
# ---------------------------------------------------------------------------------------------
def _serial(keys, settings, specs, workers, address, on_done):
    for key in keys:
        on_done(compute_record(key, settings, specs))


def _process(keys, settings, specs, workers, address, on_done):
    one_blas_thread()  # the workers are the parallelism: one BLAS thread each (threads.py)
    ctx = multiprocessing.get_context("spawn")
    pool = ProcessPoolExecutor(
        max_workers=max(1, min(workers, len(keys))),
        mp_context=ctx,
        initializer=die_with_parent,  # a kill -9 of the runner ends its workers (lifetime.py)
        initargs=(os.getpid(),),
    )
    try:
        futures = [pool.submit(compute_record, k, settings, specs) for k in keys]
        for fut in as_completed(futures):
            on_done(fut.result())
    except BaseException:  # Ctrl-C / SIGTERM: do not leave workers running orphaned
        procs = list((getattr(pool, "_processes", None) or {}).values())
        pool.shutdown(wait=False, cancel_futures=True)
        for proc in procs:
            proc.terminate()
        raise
    pool.shutdown()


def _ray(keys, settings, specs, workers, address, on_done):
    try:
        import ray
    except ImportError:
        raise RuntimeError(
            "--backend ray needs Ray: pip install 'vrig[ray]' (or pip install 'ray>=2.9')"
        ) from None
    import benchmarks

    started_here = False
    if not ray.is_initialized():
        # ship the benchmarks package (the runner and its plugins) to the workers; vrig itself
        # must be installed on every node of the cluster
        runtime_env = {"py_modules": [str(Path(benchmarks.__file__).parent)]}
        kw = {"address": address} if address else {"num_cpus": workers}
        ray.init(
            runtime_env=runtime_env,
            include_dashboard=False,
            log_to_driver=False,
            configure_logging=False,
            **kw,
        )
        started_here = True
    try:
        task = ray.remote(compute_record).options(num_cpus=1, max_retries=0)
        pending = [task.remote(k, settings, specs) for k in keys]
        while pending:
            done, pending = ray.wait(pending, num_returns=1)
            on_done(ray.get(done[0]))
    finally:
        if started_here:
            ray.shutdown()


class _Heartbeat(threading.Thread):
    """A daemon thread printing ``benchmarks: k of N records done, T s ...`` on stderr after
    every :data:`HEARTBEAT_S` seconds in which no record finished."""

    def __init__(self, total: int, done: list, t0: float):
        super().__init__(daemon=True, name="benchmarks-heartbeat")
        self.total, self.done, self.t0 = total, done, t0
        self.last = time.perf_counter()
        self.finished = threading.Event()

    def touch(self) -> None:
        """A record finished (its own line was printed): restart the silence count."""
        self.last = time.perf_counter()

    def run(self) -> None:
        while not self.finished.wait(min(1.0, HEARTBEAT_S / 4)):
            now = time.perf_counter()
            if now - self.last >= HEARTBEAT_S:
                print(
                    f"benchmarks: {len(self.done)} of {self.total} records done, running for "
                    f"{now - self.t0:.0f} s ...",
                    file=sys.stderr,
                    flush=True,
                )
                self.last = now

    def stop(self) -> None:
        """End the thread (the backend returned or raised)."""
        self.finished.set()
        self.join(timeout=5)


def _pct(x) -> str:
    return "n/a" if x is None else f"{x:.1f} %"


_BACKEND_FUNCS = {"serial": _serial, "process": _process, "ray": _ray}


def execute(
    keys: Iterable[RecordKey],
    settings: Settings,
    store: Store,
    *,
    plugin_specs=(),
    backend: str = "process",
    workers: int | None = None,
    address: str | None = None,
    log: Callable[[str], None] | None = print,
) -> dict:
    """Run the records of ``keys`` that ``store`` does not hold yet; write each as it finishes.

    Returns ``{"computed": [ids], "skipped": [ids], "failed": [ids], "wall_s": float}``.
    """
    if backend not in _BACKEND_FUNCS:
        raise ValueError(f"backend must be one of {BACKENDS}, got {backend!r}")
    keys = sorted(set(keys))
    todo = [k for k in keys if not store.finished(k, settings)]
    skipped = [record_id(k) for k in keys if k not in set(todo)]
    workers = workers or os.cpu_count() or 1
    summary = {"computed": [], "skipped": skipped, "failed": [], "wall_s": 0.0}
    if log:
        log(
            f"{len(keys)} records: {len(skipped)} already done, {len(todo)} to run "
            f"({backend} backend" + (f", {workers} workers)" if backend != "serial" else ")")
        )
    t0 = time.perf_counter()
    beat = _Heartbeat(len(todo), summary["computed"], t0) if log and todo else None

    def on_done(rec: dict) -> None:
        if beat:
            beat.touch()
        store.write(rec)
        summary["computed"].append(rec["id"])
        if rec["status"] != "ok":
            summary["failed"].append(rec["id"])
        if log:
            n = len(summary["computed"])
            if rec["status"] == "ok":
                what = f"ok, η0 IT00 {_pct(rec['eta0_it00'])} -> best {_pct(rec['eta0_best'])}"
            else:
                err = rec["error"]
                what = f"FAILED ({err['stage']}: {err['type']}: {err['message'][:90]})"
            log(f"[{n}/{len(todo)}] {rec['id']}: {what} ({rec['timing']['record_s']:.1f} s)")
            sys.stdout.flush()

    if todo:
        if beat:
            beat.start()
        try:
            _BACKEND_FUNCS[backend](todo, settings, list(plugin_specs), workers, address, on_done)
        finally:
            if beat:
                beat.stop()
    summary["wall_s"] = time.perf_counter() - t0
    return summary
