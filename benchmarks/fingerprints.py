"""Bit-for-bit fingerprints of fixed-seed reconstructions, for refactors that must not change numbers.

    python -m benchmarks.fingerprints --out before.txt      # on the old commit
    python -m benchmarks.fingerprints --compare before.txt  # on the new one: exit 1 on a difference

One line per case: every rig (``fast`` fidelity, rig seed 3) with ARX, the shock absorber with NARX,
FRF and split spectra, the elastomeric damper with the adaptive strategy (6 s pseudo-field target,
10 s identification, 2 iterations, gain 0.5, seed 7), two episodes of two gymnasium environments
at a fixed gain, and every rig x method through the command line (``vrig reconstruct --rig R
--method M --seconds 6 --iterations 1 --format npz``, the rig at ``fast`` fidelity, every other
value the command's default: the side-car's). A line holds the η0 and damage-ratio tables at full
precision (``repr``) and the SHA-256 (first 16 hex digits) of the identification records and of
every drive and raw response (the command line's: of the records its test folder holds). Issue 14
used it to show the architecture changes left every number unchanged; issue 33 that the command
line's figures stayed while the Python API's moved onto the side-car's defaults.

Make the baseline and the comparison with the same BLAS thread setting (``OPENBLAS_NUM_THREADS``):
the multichannel rigs' drives differ in their last bits between one thread and several (the
same code gives 11 lines that differ), while every η0 stays the same.
"""

from __future__ import annotations

import argparse
import hashlib
import sys
from pathlib import Path

import numpy as np

CASES = (
    (None, "arx", "fixed"),  # None: every shipped rig
    ("shock-absorber", "narx", "fixed"),
    ("shock-absorber", "frf", "fixed"),
    ("shock-absorber", "split", "fixed"),
    ("elastomeric-damper", "arx", "adaptive"),
)
OPTIONS = {"split": {"split_hz": 3.0}}
ENVS = ("vrig/ShockAbsorber-v2", "vrig/ElastomericDamper-v2")


def _hash(a) -> str:
    data = np.ascontiguousarray(np.asarray(a, dtype=float)).tobytes()
    return hashlib.sha256(data).hexdigest()[:16]


def reconstruction_line(rig_name: str, method: str, strategy: str) -> str:
    """The fingerprint of one fixed-seed reconstruction (see the module docstring)."""
    import vrig
    from vrig.desired.pseudo_field import pseudo_field
    from vrig.reconstruction.defaults import default_band

    rig = vrig.load_rig(rig_name, seed=3, fidelity="fast")
    band = default_band(rig)
    _drive, desired = pseudo_field(rig, band, 6.0, seed=5)
    try:
        res = vrig.reconstruct(
            rig, desired, method=method, iterations=2, gain=0.5, strategy=strategy,
            id_duration=10.0, seed=7, **OPTIONS.get(method, {}),
        )  # fmt: skip
    except vrig.ReconstructionError as exc:
        return f"{rig_name} {method} {strategy} FAILED {exc.result.stopped}"
    parts = [_hash(d.data) for d in res.drives] + [_hash(r.data) for r in res.raw_responses]
    return (
        f"{rig_name} {method} {strategy} band {band} eta0 {res.errors.tolist()!r} "
        f"dmg {res.damage_ratio.tolist()!r} best {res.best_iteration} stopped {res.stopped!r} "
        f"id {_hash(res.id_drive.data)} {_hash(res.id_response.data)} " + " ".join(parts)
    )


def env_lines(env_id: str) -> list[str]:
    """Two episodes (reset seeds 0 and 1) of ``env_id`` (fast), three steps at gain 0.6."""
    import gymnasium as gym

    import vrig.envs  # noqa: F401  (registers the ids)

    env = gym.make(env_id, fast=True)
    lines = []
    for seed in (0, 1):
        _obs, info = env.reset(seed=seed)
        out = [info["mean_eta0"]]
        for _ in range(3):
            _obs, reward, term, trunc, info = env.step(np.full(env.action_space.shape, 0.6))
            out.append((info["mean_eta0"], reward))
            if term or trunc:
                break
        lines.append(f"{env_id} {seed} {info['field_seed']} {info['run_seed']} {out!r}")
    return lines


def cli_line(rig_name: str, method: str) -> str:
    """The fingerprint of one ``vrig reconstruct`` run (see the module docstring), from the
    test folder it writes: exit code, η0 per iteration (``summary.json``) and the records'
    hashes."""
    import contextlib
    import io
    import json
    import tempfile

    import vrig
    from vrig import cli

    real_load = vrig.load_rig

    def load_rig(*a, **k):
        k.setdefault("fidelity", "fast")
        return real_load(*a, **k)

    with tempfile.TemporaryDirectory(prefix="vrig-fingerprint-") as tmp:
        out = Path(tmp) / "out"
        argv = ["reconstruct", "--rig", rig_name, "--method", method, "--seconds", "6",
                "--iterations", "1", "--format", "npz", "--out", str(out)]  # fmt: skip
        vrig.load_rig = load_rig
        try:
            with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
                code = cli.main(argv)
        finally:
            vrig.load_rig = real_load
        if not (out / "summary.json").is_file():
            return f"cli {rig_name} {method} exit {code} no summary"
        summary = json.loads((out / "summary.json").read_text(encoding="utf-8"))
        errors = summary.get("errors", {})
        errors = [errors.get(k) for k in ("eta0_percent", "damage_ratio")]
        hashes = []
        for name in ("IDDRV", "IDRES", "IT00DRV", "RIT00RES", "IT01DRV", "RIT01RES"):
            path = out / f"{name}.npz"
            if path.is_file():
                with np.load(path) as z:
                    hashes.append(f"{name} {_hash(z['data'])}")
    return f"cli {rig_name} {method} exit {code} eta0 {errors!r} " + " ".join(hashes)


def fingerprints(progress=print):
    """Every fingerprint line, in order; ``progress(line)`` is called as each is made."""
    import vrig
    from vrig.reconstruction.vocabulary import BUILTIN_METHODS

    lines = []
    for rig_name, method, strategy in CASES:
        for name in vrig.list_rigs() if rig_name is None else [rig_name]:
            lines.append(reconstruction_line(name, method, strategy))
            progress(lines[-1])
    for env_id in ENVS:
        for line in env_lines(env_id):
            lines.append(line)
            progress(line)
    for name in vrig.list_rigs():
        for method in BUILTIN_METHODS:
            lines.append(cli_line(name, method))
            progress(lines[-1])
    return lines


def main(argv=None) -> int:
    """Command line: print the fingerprints, write them (``--out``) or compare (``--compare``)."""
    ap = argparse.ArgumentParser(prog="python -m benchmarks.fingerprints", description=__doc__)
    ap.add_argument("--out", type=Path, help="write the fingerprints to this file")
    ap.add_argument("--compare", type=Path, help="compare with an earlier --out file")
    args = ap.parse_args(argv)
    lines = fingerprints(progress=lambda line: print(line[:160], file=sys.stderr, flush=True))
    text = "\n".join(lines) + "\n"
    if args.out is not None:
        from vrig.files import atomic_write

        with atomic_write(args.out, "w") as f:
            f.write(text)
    if args.compare is None:
        if args.out is None:
            sys.stdout.write(text)
        return 0
    old = args.compare.read_text(encoding="utf-8").splitlines()
    diff = [(i, a, b) for i, (a, b) in enumerate(zip(old, lines, strict=False)) if a != b]
    if len(old) != len(lines):
        print(f"{len(old)} lines before, {len(lines)} now")
    for i, a, b in diff:
        print(f"line {i + 1} differs:\n  before {a[:200]}\n  now    {b[:200]}")
    print("identical" if not diff and len(old) == len(lines) else f"{len(diff)} lines differ")
    return 0 if not diff and len(old) == len(lines) else 1


if __name__ == "__main__":
    sys.exit(main())
