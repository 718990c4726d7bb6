"""Hostile tries on results folders (issue 25, items 1-4 and the debris of item 6): prints the
counts, expected 0 lost and 0 raw tracebacks.

The tries, each as the issue's hostile testing made them:

* **kills**: a child process saves a test folder over and over (``overwrite=True``) and is
  killed (``SIGKILL``) at a random moment; after each kill the folder must read back whole, the
  old save or the new one, and the next save must delete what the kill left (``.NAME.tmp-*``);
* **concurrent saves**: writer processes save one folder, each save numbered under the
  folder's lock, while reader processes read an iteration (records and summary) in a loop: no
  save may fail or be lost (the number a reader sees never goes down, the last one is the number
  of saves) and no read may mix two saves;
* **interrupts**: ``vrig reconstruct`` (through its console script) gets a ``SIGINT`` at a
  random moment: half in the first 2.5 s (the interpreter's start-up, the import of vrig and
  the rig's load), half anywhere in the run; every run must exit 130 (or 0 when it had
  finished), with one line and no traceback, and an interrupted run's folder must hold the
  iterations its line says it kept. Tracebacks are counted apart for the first 0.1 s: the
  interpreter's own start-up (``site`` and the ``.pth`` files, about 50 ms here) runs before
  any vrig code and prints Python's traceback for an interrupt there;
* **two CLI runs** with ``--overwrite`` on one folder at once: the second is refused (exit 2)
  before it plays anything, the first completes;
  ``vrig repeatability`` and ``vrig check-linearity --plot`` on the folder the first run holds
  are refused the same way (exit 2);
* **µε**: a desired CSV whose unit is ``µε`` is reconstructed and read back with its unit;
* **full disk**: ``os.fsync`` fails with ``ENOSPC`` from the first plot on (in this process):
  no half-written folder, and the line says that nothing was saved;
* **fuzzed files**: RPC III (integer and float), CSV, MAT and NPZ records written by vrig, then
  mutated (random bytes anywhere, header values replaced by absurd numbers such as
  ``PTS_PER_GROUP=1e11`` or ``DELTA_T=1e-308``, truncation) and read by :func:`vrig.io.read`:
  each must read as a finite history (``fs > 0``) or be refused with
  :class:`~vrig.errors.FileFormatError`; anything else (another exception, a non-finite
  result) counts as a raw traceback.

The last lines are the totals: kills, concurrent saves, interrupts and fuzzed files tried, and
what was lost and how many raw tracebacks were seen (both expected 0; the exit code is 1
otherwise). A traceback that Python's own start-up printed before any vrig code ran (an
interrupt inside ``site``'s ``.pth`` files: no frame of vrig's) is counted apart.

Runs in about ten minutes on a loaded two-core box (``--quick``: under three). Not part of the
test run::

    python -m benchmarks.hostile_io [--quick] [--seed 0]
"""

from __future__ import annotations

import argparse
import contextlib
import dataclasses
import errno
import io
import json
import multiprocessing
import os
import random
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
_CONSOLE = (
    "import sys; sys.argv = ['vrig', *sys.argv[1:]]; from vrig_console import main; "
    "sys.exit(main())"
)


def _vrig(argv, cwd: Path) -> subprocess.Popen:
    """``vrig ARGV`` through its console script, this checkout's code."""
    env = {**os.environ, "PYTHONPATH": str(ROOT), "OPENBLAS_NUM_THREADS": "1"}
    env.pop("VRIG_PROGRESS", None)
    return subprocess.Popen(
        [sys.executable, "-c", _CONSOLE, *map(str, argv)], cwd=cwd, env=env, text=True,
        stdout=subprocess.PIPE, stderr=subprocess.PIPE,
    )  # fmt: skip


def _result(seconds: float = 4.0):
    import vrig
    from vrig.desired.pseudo_field import pseudo_field

    rig = vrig.load_rig("shock-absorber", seed=0)
    _, field = pseudo_field(rig, rig.bandwidth, seconds, seed=1)
    return rig, field, vrig.reconstruct(rig, field, method="arx", iterations=2, seed=0)


def _whole(folder) -> bool:
    """The folder holds one whole save: the summary and every record it lists, readable."""
    try:
        summary = folder.summary()
        if set(folder.files()) != set(summary["files"]):
            return False
        for name in summary["files"]:
            folder.read(name)
        return True
    except Exception:
        return False


# ----------------------------------------------------------------------------------- kills
def _save_forever(target: Path, result, ready) -> None:
    from vrig.testfolder import TestFolder

    ready.set()
    fmt = 0
    while True:
        TestFolder(target).save(result, fmt=("rsp", "csv")[fmt % 2], overwrite=True)
        fmt += 1


def kills(result, n: int, rng: random.Random, work: Path) -> dict:
    from vrig.testfolder import TestFolder

    target = work / "killed"
    folder = TestFolder(target)
    t0 = time.perf_counter()
    folder.save(result, fmt="rsp")
    t_save = time.perf_counter() - t0
    ctx = multiprocessing.get_context("fork")
    lost = debris_kept = 0
    for _ in range(n):
        ready = ctx.Event()
        child = ctx.Process(target=_save_forever, args=(target, result, ready), daemon=True)
        child.start()
        ready.wait(60)
        time.sleep(rng.uniform(0.0, 3.0) * t_save)
        os.kill(child.pid, signal.SIGKILL)
        child.join()
        lost += not _whole(folder)
    folder.save(result, fmt="npz", overwrite=True)  # the next save after the last kill
    debris_kept = sum(1 for p in work.iterdir() if p.name.startswith(".killed."))
    return {"kills": n, "lost": lost, "debris left after the next save": debris_kept}


# ------------------------------------------------------------------------ concurrent saves
def _numbered(result, number: int):
    """``result`` marked for a reader: IT00DRV scaled by ``number`` and IT00's first η0 set to
    ``number`` (a read that mixes two saves has a drive and an η0 that disagree)."""
    errors = np.array(result.errors, dtype=float)
    errors[0, 0] = float(number)
    drive = result.drives[0]
    return dataclasses.replace(
        result, drives=[drive.with_data(number * drive.data), *result.drives[1:]], errors=errors
    )


def _writer(target: Path, result, saves: int, failed, tracebacks) -> None:
    from vrig.files import folder_lock
    from vrig.testfolder import TestFolder

    folder = TestFolder(target)
    for _ in range(saves):
        try:
            with folder_lock(target, timeout=60):  # the next number, under the save's lock
                number = int(folder.summary()["errors"]["eta0_percent"][0][0]) + 1
                folder.save(_numbered(result, number), fmt="npz", overwrite=True)
        except OSError:
            with failed.get_lock():
                failed.value += 1
        except Exception:
            with tracebacks.get_lock():
                tracebacks.value += 1


def _reader(target: Path, base: np.ndarray, stop, out) -> None:
    from vrig.testfolder import TestFolder

    reads = mixed = errors = went_back = last = 0
    folder = TestFolder(target)
    while not stop.is_set():
        try:
            rec = folder.load_iteration(0)
        except Exception:
            errors += 1
            continue
        reads += 1
        number = rec.eta0[0]
        mixed += not np.array_equal(rec.drive.data, number * base)
        went_back += number < last
        last = max(last, number)
    out[:] = [reads, mixed, errors, went_back]


def concurrent(result, writers: int, saves: int, readers: int, work: Path) -> dict:
    from vrig.testfolder import TestFolder

    target = work / "shared"
    TestFolder(target).save(_numbered(result, 1), fmt="npz")
    ctx = multiprocessing.get_context("fork")
    failed, tracebacks, stop = ctx.Value("i", 0), ctx.Value("i", 0), ctx.Event()
    outs = [ctx.Array("i", 4) for _ in range(readers)]
    base = result.drives[0].data
    procs = [
        ctx.Process(target=_reader, args=(target, base, stop, o), daemon=True) for o in outs
    ]
    procs += [
        ctx.Process(target=_writer, args=(target, result, saves, failed, tracebacks), daemon=True)
        for _ in range(writers)
    ]
    for p in procs:
        p.start()
    for p in procs[readers:]:
        p.join()
    stop.set()
    for p in procs[:readers]:
        p.join()
    reads, mixed, errors, went_back = (sum(o[i] for o in outs) for i in range(4))
    final = int(TestFolder(target).summary()["errors"]["eta0_percent"][0][0])
    return {
        "saves": writers * saves,
        "saves failed": failed.value,
        "saves lost": writers * saves + 1 - final + went_back,
        "reads": reads,
        "mixed reads": mixed,
        "reads failed": errors,
        "raw tracebacks": tracebacks.value,
    }


# ------------------------------------------------------------------------------ interrupts
def _argv(out: Path, *extra) -> list:
    return ["reconstruct", "--rig", "shock-absorber", "--seconds", "3", "--iterations", "4",
            "--out", out, *extra]  # fmt: skip


def _check_kept(out: Path, err: str) -> bool:
    """An interrupted run's folder holds the iterations its line says it kept (or none)."""
    from vrig.testfolder import TestFolder

    if "kept" not in err and "saved whole" not in err:
        return not out.exists() or _whole(TestFolder(out))
    folder = TestFolder(out)
    if not _whole(folder):
        return False
    summary = folder.summary()
    n = len(folder.iterations)
    if "kept the " in err:
        said = int(err.split("kept the ", 1)[1].split(" ", 1)[0])
        return n == said and summary["iterations_run"] == n - 1
    return summary["iterations_run"] == n - 1


def _startup(err: str) -> bool:
    """A traceback of Python's own start-up: ``site`` and the ``.pth`` files (setuptools'
    editable finder is one) or the launcher's own lines (its imports, the import system finding
    the console module), no frame of vrig's code (``vrig_console.py``, the ``vrig`` and
    ``identification`` packages)."""
    files = [Path(ln.split('"')[1]) for ln in err.splitlines() if ln.lstrip().startswith('File "')]
    ours = [
        f for f in files
        if f.name == "vrig_console.py" or {"vrig", "identification"} & set(f.parent.parts)
    ]  # fmt: skip
    return bool(files) and not ours


def interrupts(n: int, rng: random.Random, work: Path) -> dict:
    t0 = time.perf_counter()
    base = _vrig(_argv(work / "baseline"), work)
    _, err = base.communicate()
    t_run = time.perf_counter() - t0
    assert base.returncode == 0, err
    codes: dict[int, int] = {}
    tracebacks = {"Python's own start-up (no vrig frame)": 0, "vrig": 0}
    swallowed = lost = extra_lines = sent_total = 0
    for i in range(n):
        out = work / f"int{i:02d}"
        when = rng.uniform(0.0, 2.5) if i % 2 == 0 else rng.uniform(0.0, t_run)
        proc = _vrig(_argv(out), work)
        time.sleep(when)
        sent = proc.poll() is None
        if sent:
            proc.send_signal(signal.SIGINT)
        sent_total += sent
        _, err = proc.communicate()
        codes[proc.returncode] = codes.get(proc.returncode, 0) + 1
        if "Traceback" in err or "Exception ignored" in err:
            tracebacks["Python's own start-up (no vrig frame)" if _startup(err) else "vrig"] += 1
        swallowed += sent and proc.returncode == 0
        lines = [ln for ln in err.splitlines() if ln.strip()]
        extra_lines += len(lines) > 1
        lost += not _check_kept(out, err)
    return {
        "runs": n,
        "SIGINT sent (the others had finished)": sent_total,
        "run length [s]": round(t_run, 1),
        "exit codes (-2: killed by SIGINT before Python's handler, shell 130)": dict(
            sorted(codes.items())
        ),
        "raw tracebacks": tracebacks,
        "exit 0 after SIGINT": swallowed,
        "more than one stderr line": extra_lines,
        "lost (folder not as the line says)": lost,
    }


# ---------------------------------------------------------------------------- two CLI runs
def two_runs(work: Path) -> dict:
    """The second run starts once the first holds the folder (a longer first run: 10 s, 20
    iterations, so that it still does when the second has imported vrig)."""
    out = work / "twice"
    long = ["--seconds", "10", "--iterations", "20", "--overwrite"]
    first = _vrig(_argv(out, *long), work)
    lock = work / ".twice.vrig-lock"
    deadline = time.monotonic() + 120
    while not lock.exists() and first.poll() is None and time.monotonic() < deadline:
        time.sleep(0.05)
    second = _vrig(_argv(out, "--overwrite"), work)
    plots = [
        _vrig([command, "--rig", "shock-absorber", "--seconds", "2", *extra, "--out", out], work)
        for command, extra in (("repeatability", ["--runs", "2"]), ("check-linearity", ["--plot"]))
    ]
    _, err2 = second.communicate()
    errs = [p.communicate()[1] for p in plots]
    _, err1 = first.communicate()
    return {
        "first exit": first.returncode,
        "second exit (2: refused up front)": second.returncode,
        "second refused before playing": int("is being written by vrig process" in err2),
        "repeatability, check-linearity exits (2: refused up front)": [p.returncode for p in plots],
        "raw tracebacks": sum("Traceback" in e for e in [err1, err2, *errs]),
    }


# -------------------------------------------------------------------------------------- µε
def strain(field, work: Path) -> dict:
    import vrig
    from vrig.testfolder import TestFolder

    desired = work / "strain.csv"
    vrig.io.write_csv(desired, vrig.TimeHistory(field.data, field.fs, field.names, ["µε"]))
    out = work / "strain"
    proc = _vrig(["reconstruct", "--rig", "shock-absorber", "--desired", desired,
                  "--iterations", "1", "--out", out], work)  # fmt: skip
    _, err = proc.communicate()
    units = TestFolder(out).read("DESRES01").units if out.is_dir() else None
    return {"exit": proc.returncode, "unit read back": units, "raw tracebacks": "Traceback" in err}


# ------------------------------------------------------------------------------- full disk
def full_disk(work: Path) -> dict:
    from vrig.cli import main

    real, state = os.fsync, {"full": False}

    def fsync(fd):
        with contextlib.suppress(OSError):
            state["full"] |= ".png." in os.readlink(f"/proc/self/fd/{fd}")
        if state["full"]:
            raise OSError(errno.ENOSPC, "No space left on device")
        return real(fd)

    out = work / "full"
    err = io.StringIO()
    os.fsync = fsync
    try:
        with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(err):
            code = main([str(a) for a in _argv(out)])
    finally:
        os.fsync = real
    line = err.getvalue().strip()
    return {
        "exit": code,
        "half-written folders": int(out.exists()),
        "debris": sum(1 for p in work.iterdir() if p.name.startswith(".full.")),
        "says nothing was saved": int("nothing was saved" in line),
    }


# ------------------------------------------------------------------------------ fuzzed files
_ABSURD = {  # header values the fuzzing found let numpy errors through, and kin
    b"PTS_PER_GROUP": [b"1e11", b"99999999999", b"-256", b"0"],
    b"PTS_PER_FRAME": [b"1e11", b"0", b"-1", b"2147483648"],
    b"FRAMES": [b"1e11", b"-4", b"0"],
    b"CHANNELS": [b"0", b"100000", b"-3"],
    b"DELTA_T": [b"1e-308", b"1e300", b"0", b"-1e-3", b"nan", b"inf"],
    b"NUM_HEADER_BLOCKS": [b"0", b"100000", b"-1"],
    b"NUM_PARAMS": [b"0", b"100000"],
    b"SCALE.CHAN_1": [b"nan", b"inf", b"1e308", b"0"],
}


def _fuzz_bases(work: Path) -> dict[str, bytes]:
    """One small record per format, written by vrig (3 channels, 1000 samples)."""
    import vrig
    import vrig.io

    rng = np.random.default_rng(5)
    th = vrig.TimeHistory(rng.standard_normal((1000, 3)), 512.0, ["a", "b", "c"], ["N", "m", "V"])
    bases = {}
    for name, kwargs in (("int.rsp", {"data_type": "SHORT_INTEGER"}),
                         ("float.rsp", {"data_type": "FLOATING_POINT"}),
                         ("x.csv", {}), ("x.mat", {}), ("x.npz", {})):  # fmt: skip
        path = work / name
        writer = vrig.io.write_rpc3 if name.endswith(".rsp") else vrig.io.write
        writer(path, th, **kwargs)
        bases[name] = path.read_bytes()
    return bases


def _mutate(buf: bytes, rng: random.Random) -> bytes:
    """Random bytes (mostly in the first 2 KiB: the header), an absurd header value, and/or a
    truncation."""
    out = bytearray(buf)
    how = rng.random()
    if how < 0.4 or not out:
        for _ in range(rng.randint(1, 8)):
            pos = rng.randrange(min(len(out), 2048)) if rng.random() < 0.8 else rng.randrange(len(out))
            out[pos] = rng.choice([rng.randrange(256), *b"0123456789.-+E \0,\n"])
    elif how < 0.7:
        keys = [k for k in _ABSURD if k in out]
        if keys:
            key = rng.choice(keys)
            i = out.index(key)
            value = rng.choice(_ABSURD[key]).ljust(48)[:48]  # the value field of a 128-byte record
            out[i + 32 : i + 32 + len(value)] = value
    if rng.random() < 0.3:
        out = out[: rng.randrange(len(out) + 1)]
    return bytes(out)


def fuzz(n: int, rng: random.Random, work: Path) -> dict:
    """``n`` mutated files per format, each read by :func:`vrig.io.read`."""
    import vrig.io
    from vrig.errors import FileFormatError

    bases = _fuzz_bases(work)
    read = refused = raw = 0
    kinds: dict[str, int] = {}
    for name, base in bases.items():
        path = work / f"fuzz-{name}"
        for _ in range(n):
            path.write_bytes(_mutate(base, rng))
            try:
                th = vrig.io.read(path)
            except FileFormatError:
                refused += 1
                continue
            except Exception as exc:  # (what the count is for)
                raw += 1
                kinds[type(exc).__name__] = kinds.get(type(exc).__name__, 0) + 1
                continue
            ok = np.all(np.isfinite(th.data)) and np.isfinite(th.fs) and th.fs > 0
            read += bool(ok)
            raw += not ok
            if not ok:
                kinds["non-finite result"] = kinds.get("non-finite result", 0) + 1
    return {
        "files": n * len(bases),
        "formats": sorted(bases),
        "read (finite)": read,
        "refused (FileFormatError)": refused,
        "raw tracebacks": raw,
        "raw by kind": kinds,
    }


def _totals(report: dict) -> dict:
    """The issue's counts: tries per kind, lost, raw tracebacks (vrig's)."""
    kill, conc = report["kills"], report["concurrent saves"]
    intr, two = report["interrupts"], report["two CLI runs, --overwrite"]
    strain_, disk, fz = report["µε unit"], report["full disk"], report["fuzzed files"]
    lost = (
        kill["lost"] + conc["saves lost"] + conc["saves failed"] + intr["exit 0 after SIGINT"]
        + intr["lost (folder not as the line says)"] + disk["half-written folders"]
        + (two["first exit"] != 0) + (strain_["exit"] != 0)
    )  # fmt: skip
    raw = (
        conc["raw tracebacks"] + intr["raw tracebacks"]["vrig"] + two["raw tracebacks"]
        + int(strain_["raw tracebacks"]) + fz["raw tracebacks"]
    )  # fmt: skip
    return {
        "kills": kill["kills"],
        "concurrent saves": conc["saves"],
        "interrupts": intr["runs"],
        "fuzzed files": fz["files"],
        "lost": lost,
        "raw tracebacks": raw,
        "Python start-up tracebacks (no vrig code ran yet)": intr["raw tracebacks"][
            "Python's own start-up (no vrig frame)"
        ],
    }


def main(argv=None) -> int:
    p = argparse.ArgumentParser(prog="python -m benchmarks.hostile_io", description=__doc__)
    p.add_argument("--quick", action="store_true", help="fewer tries (under three minutes)")
    p.add_argument("--seed", type=int, default=0, help="random seed of the moments (default 0)")
    args = p.parse_args(argv)
    if sys.platform != "linux":
        print("hostile_io: Linux only (fork, flock, /proc)")
        return 0
    rng = random.Random(args.seed)
    n_kills, n_int, saves, n_fuzz = (8, 6, 6, 400) if args.quick else (24, 14, 15, 5200)
    work = Path(tempfile.mkdtemp(prefix="vrig-hostile-"))
    report = {}
    try:
        t0 = time.perf_counter()
        _, field, result = _result()
        report["kills"] = kills(result, n_kills, rng, work)
        report["concurrent saves"] = concurrent(result, 3, saves, 2, work)
        report["interrupts"] = interrupts(n_int, rng, work)
        report["two CLI runs, --overwrite"] = two_runs(work)
        report["µε unit"] = strain(field, work)
        report["full disk"] = full_disk(work)
        report["fuzzed files"] = fuzz(n_fuzz, rng, work)
        report["seconds"] = round(time.perf_counter() - t0, 1)
    finally:
        shutil.rmtree(work, ignore_errors=True)
    totals = report["totals"] = _totals(report)
    print(json.dumps(report, indent=2, ensure_ascii=False, default=str))
    print(
        f"hostile_io: {totals['kills']} kills, {totals['concurrent saves']} concurrent saves, "
        f"{totals['interrupts']} interrupts, {totals['fuzzed files']} fuzzed files: "
        f"{totals['lost']} lost, {totals['raw tracebacks']} raw tracebacks "
        f"({report['seconds']} s)"
    )
    return 0 if totals["lost"] == 0 and totals["raw tracebacks"] == 0 else 1


if __name__ == "__main__":
    sys.exit(main())
