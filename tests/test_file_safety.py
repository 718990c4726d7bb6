"""Nothing lost, nothing silently wrong (issue #11): atomic writes under kill -9, and readers
that refuse truncated, foreign, tampered or endless files with one clear error naming the file.

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
from vrig.io import read, read_csv, read_mat, read_rpc3, write, write_csv, write_mat, write_rpc3

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


# ------------------------------------------------------------------------------ readers
def _cap_memory(extra: int = 1 << 30) -> None:
    """Limit this (child) process's address space to its current size plus ``extra`` bytes."""
    import resource

    with open("/proc/self/status") as f:
        vm = next(int(line.split()[1]) * 1024 for line in f if line.startswith("VmSize:"))
    resource.setrlimit(resource.RLIMIT_AS, (vm + extra, resource.RLIM_INFINITY))


def _in_child(fn, *args, timeout: float = 20.0) -> tuple[str, str]:
    """Run ``fn(*args)`` in a forked child with capped memory: ``("returned", "")``, the
    exception's ``(type name, message)``, ``("crashed", signal)`` or ``("hung", "")``."""
    ctx = multiprocessing.get_context("fork")
    receive, send = ctx.Pipe(duplex=False)

    def run():
        _cap_memory()
        try:
            fn(*args)
            send.send(("returned", ""))
        except BaseException as exc:
            send.send((type(exc).__name__, str(exc)))

    child = ctx.Process(target=run, daemon=True)
    child.start()
    send.close()
    try:
        if not receive.poll(timeout):
            return ("hung", "")
        try:
            return receive.recv()
        except EOFError:
            child.join()
            return ("crashed", f"exit code {child.exitcode}")
    finally:
        if child.is_alive():
            os.kill(child.pid, signal.SIGKILL)
        child.join()


def _good(tmp_path: Path, suffix: str) -> Path:
    th = TimeHistory(np.arange(40.0).reshape(20, 2), 100.0, ["a", "b"], ["m", "N"])
    return write(tmp_path / f"good{suffix}", th)


SUFFIXES = [".rsp", ".csv", ".mat", ".npz"]
FORMATS = {".rsp": "RPC III", ".csv": "CSV", ".mat": "MATLAB .mat", ".npz": "vrig TimeHistory .npz"}


@needs_fork
@pytest.mark.parametrize("suffix", SUFFIXES)
def test_a_fifo_is_refused_at_once_not_waited_on(tmp_path, suffix):
    path = tmp_path / f"pipe{suffix}"
    os.mkfifo(path)  # no writer: opening it for reading blocks forever
    kind, message = _in_child(read, path, timeout=5.0)
    assert kind == "FileFormatError", (kind, message)
    assert str(path) in message and "FIFO" in message


@needs_fork
@pytest.mark.parametrize("suffix", SUFFIXES)
def test_an_endless_file_behind_a_symlink_is_refused(tmp_path, suffix):
    path = tmp_path / f"zero{suffix}"
    path.symlink_to("/dev/zero")  # reading it never ends
    kind, message = _in_child(read, path, timeout=10.0)
    assert kind == "FileFormatError", (kind, message)
    assert str(path) in message and "character device" in message


@needs_fork
@pytest.mark.parametrize("suffix", SUFFIXES)
def test_a_file_beyond_the_documented_size_limit_is_refused(tmp_path, suffix):
    from vrig.files import MAX_FILE_BYTES

    assert MAX_FILE_BYTES == 2 * 1024**3  # the documented limit
    path = _good(tmp_path, suffix)
    with open(path, "r+b") as f:
        f.truncate(MAX_FILE_BYTES + 1)  # sparse: no disk space used
    kind, message = _in_child(read, path, timeout=10.0)
    assert kind == "FileFormatError", (kind, message)
    assert str(path) in message and str(MAX_FILE_BYTES) in message


@pytest.mark.parametrize("suffix", SUFFIXES)
def test_read_errors_name_the_file_and_the_format(tmp_path, suffix):
    from vrig.errors import FileFormatError

    path = tmp_path / f"junk{suffix}"
    path.write_bytes(b"\x89PNG\r\n\x1a\n" + bytes(range(256)) * 4)  # a foreign binary file
    with pytest.raises(FileFormatError) as info:
        read(path)
    assert info.value.path == str(path) and info.value.format == FORMATS[suffix]
    assert str(path) in str(info.value) and FORMATS[suffix] in str(info.value)


@pytest.mark.parametrize("cut", [0.1, 0.5, 0.99])
def test_a_truncated_timehistory_npz_is_a_file_format_error(tmp_path, cut):
    from vrig.errors import FileFormatError

    th = TimeHistory(np.random.default_rng(0).standard_normal((500, 3)), 50.0)
    raw = th.save(tmp_path / "a.npz").read_bytes()
    path = tmp_path / "cut.npz"
    path.write_bytes(raw[: int(cut * len(raw))])
    with pytest.raises(FileFormatError, match=r"cut\.npz"):
        TimeHistory.load(path)


def test_an_npz_without_fs_is_a_file_format_error_naming_fs(tmp_path):
    import json

    from vrig.errors import FileFormatError

    meta = {"format": "vrig-timehistory", "version": 1, "names": ["a"], "units": ["m"]}
    path = tmp_path / "nofs.npz"
    np.savez(path, data=np.ones((10, 1)), meta=np.array(json.dumps(meta)))
    with pytest.raises(FileFormatError, match=r"nofs\.npz.*meta has no fs"):
        TimeHistory.load(path)
    np.savez(path, data=np.ones((10, 1)))  # a foreign .npz: data only
    with pytest.raises(FileFormatError, match=r"nofs\.npz.*no meta array"):
        read(path)


def test_a_tampered_npz_header_cannot_make_the_reader_allocate(tmp_path):
    """An array header claiming 10**12 samples in a 1 kB member: refused before allocating."""
    import zipfile

    from vrig.errors import FileFormatError

    path = TimeHistory(np.ones((100, 1)), 10.0).save(tmp_path / "a.npz")
    with zipfile.ZipFile(path) as z:
        members = {n: z.read(n) for n in z.namelist()}
    members["data.npy"] = members["data.npy"].replace(b"(100, 1)", b"(10000000000, 100)")
    with zipfile.ZipFile(path, "w") as z:
        for name, raw in members.items():
            z.writestr(name, raw)
    with pytest.raises(FileFormatError, match="declares shape"):
        TimeHistory.load(path)


# ------------------------------------------------------------------------------ CSV encodings
def test_a_csv_with_a_utf8_byte_order_mark_is_read_correctly(tmp_path):
    path = tmp_path / "excel.csv"
    path.write_bytes(b"\xef\xbb\xbftime,F [N],T [\xc2\xb0C]\n0,1.5,20\n0.5,2.5,21\n1.0,3.5,22\n")
    th = read_csv(path)
    assert th.names == ("F", "T") and th.units == ("N", "°C") and th.fs == 2.0
    np.testing.assert_array_equal(th.data, [[1.5, 20], [2.5, 21], [3.5, 22]])


def test_a_latin1_csv_is_refused_naming_the_file_and_the_byte(tmp_path):
    from vrig.errors import FileFormatError

    path = tmp_path / "latin1.csv"
    path.write_bytes("time,T [°C]\n0,20\n0.5,21\n".encode("latin-1"))
    with pytest.raises(FileFormatError) as info:
        read_csv(path)
    text = str(info.value)
    assert str(path) in text and "not UTF-8" in text and "0xb0" in text and "line 1" in text


def test_a_csv_header_beyond_the_csv_field_limit_is_a_file_format_error(tmp_path):
    from vrig.errors import FileFormatError

    path = tmp_path / "wide.csv"
    path.write_text('time,"' + "x" * 140_000 + '"\n0,1\n1,2\n')  # csv module limit: 131072
    with pytest.raises(FileFormatError, match=r"wide\.csv.*header row"):
        read_csv(path)


@pytest.mark.parametrize("encoding", ["utf-16", "utf-16-be", "utf-32"])
def test_a_utf16_or_utf32_csv_is_refused_naming_the_encoding(tmp_path, encoding):
    from vrig.errors import FileFormatError

    path = tmp_path / "wide.csv"
    path.write_bytes("time,x\n0,1\n0.5,2\n".encode(encoding))
    name = "UTF-32" if "32" in encoding else "UTF-16"
    with pytest.raises(FileFormatError) as info:
        read_csv(path)
    text = str(info.value)
    assert str(path) in text and (name in text or "NUL byte" in text)  # utf-16-be has no BOM


# ------------------------------------------------------------------------------ MATLAB files
def _mat_v73(path: Path) -> Path:
    """The first bytes of a MATLAB v7.3 file: the 128-byte MAT header (version 0x0200) in the
    512-byte user block of an HDF5 file, then the HDF5 superblock signature."""
    text = b"MATLAB 7.3 MAT-file, Platform: GLNXA64, Created on: Mon Nov 24 03:00:00 2025 HDF5 schema 1.00 ."
    header = text.ljust(116, b" ") + b" " * 8 + b"\x00\x02" + b"IM"
    path.write_bytes(header.ljust(512, b"\0") + b"\x89HDF\r\n\x1a\n" + bytes(1024))
    return path


def test_a_matlab_v73_file_is_refused_with_advice(tmp_path):
    from vrig.errors import FileFormatError

    path = _mat_v73(tmp_path / "v73.mat")
    with pytest.raises(FileFormatError) as info:
        read_mat(path)
    assert str(path) in str(info.value) and "v7.3" in str(info.value) and "-v7" in str(info.value)


def _complex_flag_without_imaginary_part(tmp_path: Path) -> Path:
    """write_mat's file with the complex flag set on ``fs`` (two bytes flipped by a fuzzer):
    SciPy reads the next variable's matrix tag as the imaginary part's data type."""
    path = write_mat(tmp_path / "c.mat", TimeHistory(np.ones((5, 2)), 100.0))
    buf = bytearray(path.read_bytes())
    name = buf.index((2 << 16 | 1).to_bytes(4, "little") + b"fs\0\0")  # small miINT8 "fs"
    buf[name - 24 + 1] |= 0x08  # array flags word of fs: complex
    path.write_bytes(bytes(buf))
    return path


def _char_array_without_dimensions(tmp_path: Path) -> Path:
    """A level-5 file whose ``units`` is a char array with an empty dimensions element."""

    def element(mdtype: int, data: bytes) -> bytes:
        return (mdtype.to_bytes(4, "little") + len(data).to_bytes(4, "little") + data).ljust(
            8 + -(-len(data) // 8) * 8, b"\0"
        )

    flags = element(6, (4).to_bytes(4, "little") + bytes(4))  # miUINT32: class 4 (char)
    body = flags + element(5, b"") + element(1, b"units") + element(4, b"N\0")
    header = b"MATLAB 5.0 MAT-file".ljust(116, b" ") + bytes(8) + b"\x00\x01IM"
    path = tmp_path / "d.mat"
    path.write_bytes(header + element(14, body))
    return path


@needs_fork
@pytest.mark.parametrize(
    "make", [_complex_flag_without_imaginary_part, _char_array_without_dimensions]
)
def test_corrupt_mat_files_that_crash_scipy_are_refused(tmp_path, make):
    """Both files make ``scipy.io.loadmat`` (1.17) die with a segmentation fault; read_mat
    must raise instead (run in a child process so that a crash fails the test, not the run)."""
    path = make(tmp_path)
    kind, message = _in_child(read_mat, path)
    assert kind == "FileFormatError", (kind, message)
    assert str(path) in message


# ------------------------------------------------------------------------------ model files
def _saved_model(tmp_path: Path, two_models) -> tuple[Path, dict]:
    path = two_models[0].save(tmp_path / "m.npz")
    with np.load(path) as f:
        arrays = {k: f[k] for k in f.files}
    return path, arrays


@pytest.mark.parametrize("cut", [0.0, 0.3, 0.9])
def test_a_truncated_model_file_is_a_model_file_error(tmp_path, two_models, cut):
    from identification import ModelFileError

    path, _ = _saved_model(tmp_path, two_models)
    raw = path.read_bytes()
    path.write_bytes(raw[: int(cut * len(raw))])
    with pytest.raises(ModelFileError, match=r"m\.npz"):
        Narx.load(path)


@pytest.mark.parametrize("what", ["png", "pickle", "npy"])
def test_a_foreign_file_is_a_model_file_error(tmp_path, what):
    import pickle

    from identification import ModelFileError

    path = tmp_path / "foreign.npz"
    if what == "png":
        path.write_bytes(b"\x89PNG\r\n\x1a\n" + bytes(200))
    elif what == "pickle":
        path.write_bytes(pickle.dumps({"coef": [1.0, 2.0]}))
    else:  # a plain .npy array under an .npz name
        with open(path, "wb") as f:
            np.save(f, np.ones(5))
    with pytest.raises(ModelFileError, match=r"foreign\.npz"):
        Narx.load(path)


def _tamper_meta(arrays, **changes):
    import json

    meta = json.loads(str(arrays["meta"]))
    meta.update(changes)
    arrays["meta"] = np.array(json.dumps(meta))


TAMPERING = {
    "source out of range": lambda a: a["regressors_0"].__setitem__((0, 0), 7),
    "negative lag": lambda a: a["regressors_0"].__setitem__((-1, 1), -3),
    "lag beyond max_lag": lambda a: a["regressors_0"].__setitem__((-1, 1), 50),
    "coefficients missing": lambda a: a.__setitem__("coef_0", a["coef_0"][:-2]),
    "NaN coefficient": lambda a: a["coef_0"].__setitem__(0, np.nan),
    "term index out of range": lambda a: a["terms_0"].__setitem__((-1, -1), 999),
    "float regressor table": lambda a: a.__setitem__("regressors_0", a["regressors_0"] + 0.5),
    "zero bound": lambda a: a["bound"].__setitem__(0, 0.0),
    "more outputs than arrays": lambda a: _tamper_meta(a, ny=10**9),
    "wrong name count": lambda a: _tamper_meta(a, input_names=["u1"]),
    "unknown parameter": lambda a: _tamper_meta(a, params={"order": 3, "colour": "red"}),
    "order not an integer": lambda a: _tamper_meta(a, orders=["three"]),
    "meta not JSON": lambda a: a.__setitem__("meta", np.array("{not json")),
}


@pytest.mark.parametrize("how", list(TAMPERING))
def test_a_tampered_model_file_is_a_model_file_error(tmp_path, two_models, how):
    from identification import ModelFileError

    path, arrays = _saved_model(tmp_path, two_models)
    arrays = {k: np.array(v) for k, v in arrays.items()}
    TAMPERING[how](arrays)
    np.savez(path, **arrays)
    with pytest.raises(ModelFileError, match=r"m\.npz"):
        Narx.load(path)


@needs_fork
def test_a_model_fifo_or_endless_file_is_refused(tmp_path):
    fifo = tmp_path / "pipe.npz"
    os.mkfifo(fifo)
    zero = tmp_path / "zero.npz"
    zero.symlink_to("/dev/zero")
    for path in (fifo, zero):
        kind, message = _in_child(Narx.load, path, timeout=5.0)
        assert kind == "ModelFileError", (path, kind, message)
        assert str(path) in message and "not a regular file" in message


def test_predict_never_returns_inf_or_nan(two_models):
    from identification import SimulationDivergedError

    model = two_models[0]
    rng = np.random.default_rng(5)
    u = rng.standard_normal((300, 2))
    y = rng.standard_normal((300, 1))
    assert np.all(np.isfinite(model.predict(u, y)))
    u[200, 1] = 1e120  # cubic terms overflow to inf (and inf * 0 to NaN)
    with pytest.raises(SimulationDivergedError) as info:
        model.predict(u, y)
    err = info.value
    assert err.kind == "one-step prediction" and 200 <= err.sample <= 203
    assert not np.isfinite(err.value) and "one-step prediction" in str(err)


def _directory_offset_too_large(raw: bytes) -> bytes:
    """End-of-central-directory record claims the directory starts 1000 bytes later than it
    does: zipfile then seeks to a negative member offset (EINVAL)."""
    end = raw.rindex(b"PK\x05\x06")
    offset = int.from_bytes(raw[end + 16 : end + 20], "little")
    return raw[: end + 16] + (offset + 1000).to_bytes(4, "little") + raw[end + 20 :]


def _unclosed_npy_header(raw: bytes) -> bytes:
    """A member's .npy header dict loses its closing bracket (numpy's tokenize fallback raises
    TokenError, which is not a ValueError)."""
    import io
    import zipfile

    out = io.BytesIO()
    with zipfile.ZipFile(io.BytesIO(raw)) as src, zipfile.ZipFile(out, "w") as dst:
        for name in src.namelist():
            data = src.read(name)
            if name == src.namelist()[-1]:
                data = data.replace(b"), }", b"   }", 1)
            dst.writestr(name, data)
    return out.getvalue()


@pytest.mark.parametrize("corrupt", [_directory_offset_too_large, _unclosed_npy_header])
@pytest.mark.parametrize("kind", ["timehistory", "model"])
def test_corrupt_zip_structures_are_file_errors(tmp_path, two_models, corrupt, kind):
    from identification import ModelFileError
    from vrig.errors import FileFormatError

    if kind == "timehistory":
        path = TimeHistory(np.ones((50, 2)), 10.0).save(tmp_path / "z.npz")
        load, error = TimeHistory.load, FileFormatError
    else:
        path = two_models[0].save(tmp_path / "z.npz")
        load, error = Narx.load, ModelFileError
    raw = corrupt(path.read_bytes())
    assert raw != path.read_bytes()
    path.write_bytes(raw)
    with pytest.raises(error, match=r"z\.npz"):
        load(path)
