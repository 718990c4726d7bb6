"""Nothing lost, nothing silently wrong (issue #11): atomic writes under kill -9.

The kill tests start a child process (fork) that rewrites one file in a loop, alternating two
versions, and kill it with SIGKILL by its PID at random moments; after every kill the file must
read back as exactly one of the two versions.
"""

from __future__ import annotations

import multiprocessing
import os
import random
import signal
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from identification import Narx
from vrig import TimeHistory
from vrig.files import is_temporary
from vrig.io import read_csv, read_mat, read_rpc3, write_csv, write_mat, write_rpc3

needs_fork = pytest.mark.skipif(
    sys.platform != "linux", reason="kill tests fork a child process (Linux)"
)

KILLS = 8  # kill -9 per format


def _rewrite_forever(write, path, versions, ready) -> None:
    ready.set()
    i = 1
    while True:
        write(path, versions[i % 2])
        i += 1


def _signature(path: Path):
    try:
        st = os.stat(path)
    except FileNotFoundError:
        return None
    return st.st_ino, st.st_size, st.st_mtime_ns


def _wait_for_change(path: Path, timeout: float) -> None:
    """Return as soon as ``path`` changes (inode, size or mtime), or after ``timeout``."""
    before = _signature(path)
    end = time.perf_counter() + timeout
    while _signature(path) == before and time.perf_counter() < end:
        pass


def _kill_while_rewriting(path: Path, write, versions, *, seed: int):
    """Write ``versions[0]``, then KILLS times: fork a child rewriting ``path`` in a loop and
    SIGKILL it, alternately at the first visible change of ``path`` (an in-place writer has just
    truncated it) and after a random delay (up to three write times); yield after each kill."""
    ctx = multiprocessing.get_context("fork")
    write(path, versions[0])
    t0 = time.perf_counter()
    write(path, versions[0])
    t_write = time.perf_counter() - t0
    rng = random.Random(seed)
    for i in range(KILLS):
        ready = ctx.Event()
        child = ctx.Process(target=_rewrite_forever, args=(write, path, versions, ready))
        child.daemon = True
        child.start()
        try:
            assert ready.wait(60), "the child process did not start"
            if i % 2:
                _wait_for_change(path, timeout=10 * t_write + 1.0)
            else:
                time.sleep(rng.uniform(0.2, 3.0) * t_write)
        finally:
            os.kill(child.pid, signal.SIGKILL)
            child.join()
        assert child.exitcode == -signal.SIGKILL
        leftovers = [p.name for p in path.parent.iterdir() if p != path]
        assert all(is_temporary(name) for name in leftovers), leftovers
        yield


def _histories(n: int, n_channels: int = 4) -> tuple[TimeHistory, TimeHistory]:
    """Two float32-exact records of the same shape and different content."""
    rng = np.random.default_rng(n)
    names = [f"ch{k}" for k in range(n_channels)]
    return tuple(
        TimeHistory(
            rng.standard_normal((n, n_channels)).astype(np.float32), 512.0, names, ["m"] * 4
        )
        for _ in range(2)
    )


def _which(back: TimeHistory, versions) -> int:
    """Index of the version ``back`` equals exactly (fails when it equals neither)."""
    for i, v in enumerate(versions):
        if (
            back.data.shape == v.data.shape
            and np.array_equal(back.data, v.data)
            and back.names == v.names
            and back.units == v.units
            and back.fs == v.fs
        ):
            return i
    raise AssertionError("the file holds neither the old nor the new content")


# ------------------------------------------------------------------------------ kill -9, writers
@needs_fork
@pytest.mark.parametrize(
    ("suffix", "n", "write", "reader"),
    [
        (".rsp", 200_000, write_rpc3, read_rpc3),
        (".csv", 8_000, write_csv, read_csv),
        (".mat", 200_000, write_mat, read_mat),
        (".npz", 200_000, lambda p, th: th.save(p), TimeHistory.load),
    ],
    ids=["rsp", "csv", "mat", "npz"],
)
def test_kill_during_a_rewrite_leaves_the_old_or_the_new_file(tmp_path, suffix, n, write, reader):
    versions = _histories(n)
    path = tmp_path / f"record{suffix}"
    seen = set()
    for _ in _kill_while_rewriting(path, write, versions, seed=n):
        seen.add(_which(reader(path), versions))
    assert seen  # every kill left a readable, whole version


@pytest.fixture(scope="module")
def two_models():
    rng = np.random.default_rng(3)
    u = rng.standard_normal((3000, 2))
    y = np.zeros((3000, 1))
    for t in range(2, 3000):
        y[t] = 0.5 * y[t - 1] - 0.2 * y[t - 2] + u[t - 1, 0] + 0.3 * u[t - 1, 1] * u[t - 2, 0]
    return tuple(  # noisy outputs: the lagged-output terms are not exactly dependent
        Narx(order=3, degree=3).fit(u, y + 0.01 * rng.standard_normal(y.shape)) for _ in range(2)
    )


@needs_fork
def test_kill_during_a_model_save_leaves_the_old_or_the_new_model(tmp_path, two_models):
    path = tmp_path / "model.npz"
    for _ in _kill_while_rewriting(path, lambda p, m: m.save(p), two_models, seed=1):
        back = Narx.load(path)
        same = [
            all(np.array_equal(c, d) for c, d in zip(back.coef_, m.coef_, strict=True))
            and np.array_equal(back.bound_, m.bound_)
            for m in two_models
        ]
        assert any(same), "the model file holds neither the old nor the new model"
