#!/usr/bin/env bash
# The wheel works as installed (issue 15, deliverable 6): build it from a copy of the checkout,
# install it in a fresh virtual environment (its dependencies from the configured index, through
# the pip cache) and, from a directory OUTSIDE the checkout, run what the README promises an installed
# package does: `vrig --version`, `vrig rigs`, `vrig describe`, the Python API and the main
# command `vrig reconstruct --rig shock-absorber --method arx` (shortened: 10 s record, 2
# iterations). Exits non-zero, saying which step failed, if any of it does not work.
#
#   bash .ci/wheel_check.sh            # in a temporary folder, removed at the end
#   bash .ci/wheel_check.sh DIR        # in DIR, emptied first and kept (what .ci/run does: on a
#                                      # busy disk, removing the ~670 MB venv took 60 s)
# python3 (or $PYTHON) builds the wheel and makes the venv; the venv keeps the pip that Python
# bundles (an old pip installs the wheel too).
set -euo pipefail

ROOT="$(cd "$(dirname "$0")/.." && pwd)"
PY="${PYTHON:-python3}"
if [ $# -ge 1 ]; then
    WORK="$(mkdir -p "$1" && cd "$1" && pwd)"
    rm -rf "${WORK:?}"/{src,dist,venv,outside}
else
    WORK="$(mktemp -d "${TMPDIR:-/tmp}/vrig-wheel-check.XXXXXXXX")"
    trap 'rm -rf "$WORK"' EXIT
fi
export OPENBLAS_NUM_THREADS="${OPENBLAS_NUM_THREADS:-1}" PIP_DISABLE_PIP_VERSION_CHECK=1

step() { printf 'wheel check [%3d s]: %s\n' "$SECONDS" "$*"; }
fail() { printf 'wheel check FAILED: %s\n' "$*" >&2; exit 1; }

expected="$(sed -n 's/^__version__ = "\([^"]*\)"$/\1/p' "$ROOT/vrig/__init__.py")"
[ -n "$expected" ] || fail "no __version__ = \"...\" line in vrig/__init__.py"

# Build from a copy of the files git knows (tracked or new, not ignored): an in-tree build would
# leave build/ and *.egg-info in the checkout, and a stale build/lib could put deleted files in
# the wheel.
step "building the wheel (version $expected)"
mkdir -p "$WORK/src"
git -C "$ROOT" ls-files -z --cached --others --exclude-standard \
    | while IFS= read -r -d '' f; do [ -f "$ROOT/$f" ] && printf '%s\0' "$f"; done \
    | (cd "$ROOT" && xargs -0 cp --parents -t "$WORK/src")
"$PY" -m pip wheel --no-deps -q -w "$WORK/dist" "$WORK/src" || fail "pip wheel did not build"
wheels=("$WORK"/dist/vrig-"$expected"-py3-none-any.whl)
[ -f "${wheels[0]}" ] || fail "no vrig-$expected-py3-none-any.whl in $(ls "$WORK/dist")"

step "installing it in a fresh venv"
"$PY" -m venv "$WORK/venv"
VPY="$WORK/venv/bin/python"
"$VPY" -m pip install -q "${wheels[0]}" || fail "pip could not install the wheel"

mkdir -p "$WORK/outside"
cd "$WORK/outside"  # nothing of the checkout is importable from here
VRIG="$WORK/venv/bin/vrig"

step "vrig --version"
got="$("$VRIG" --version)" || fail "vrig --version exited non-zero"
[ "$got" = "vrig $expected" ] || fail "vrig --version printed '$got', expected 'vrig $expected'"

step "vrig rigs, vrig describe shock-absorber"
"$VRIG" rigs >rigs.txt || fail "vrig rigs exited non-zero"
for rig in elastomeric-damper shaker shock-absorber radiator fuel-tank-2ch fuel-tank-7ch \
    motorcycle-rear light-truck-front pneumatic-trailer; do
    grep -q -- "$rig" rigs.txt || fail "vrig rigs does not list $rig: $(cat rigs.txt)"
done
"$VRIG" describe shock-absorber >/dev/null || fail "vrig describe shock-absorber exited non-zero"

step "the Python API from the installed package"
"$VPY" - "$WORK/venv" <<'EOF' || fail "the installed package's Python API"
import sys
from importlib import metadata, resources
from pathlib import Path

import gymnasium as gym
import identification
import vrig

venv = Path(sys.argv[1]).resolve()
for module in (vrig, identification):  # imported from the venv, not from a checkout
    assert venv in Path(module.__file__).resolve().parents, module.__file__
    assert resources.files(module.__name__).joinpath("py.typed").is_file(), module.__name__
assert vrig.__version__ == metadata.version("vrig"), (vrig.__version__, metadata.version("vrig"))
assert any(p.name == "LICENSE" for p in metadata.files("vrig")), "LICENSE not installed"
rig = vrig.load_rig("shock-absorber", seed=0, fidelity="fast")
drive = 0.002 * identification.band_limited_noise(int(2 * rig.fs), 1, cutoff=0.02, seed=1)
assert rig.run(drive).data.shape[0] == drive.shape[0]
env = gym.make("vrig/ShockAbsorber-v2", fast=True)
env.reset(seed=0)
env.close()
print(f"wheel check: python API ok (vrig {vrig.__version__} from {Path(vrig.__file__).parent})")
EOF

step "vrig reconstruct --rig shock-absorber --method arx --seconds 10 --iterations 2"
start=$SECONDS
rc=0
"$VRIG" reconstruct --rig shock-absorber --method arx --seconds 10 --iterations 2 >reconstruct.txt \
    2>reconstruct.err || rc=$?
[ "$rc" -eq 0 ] || { cat reconstruct.txt reconstruct.err >&2; fail "vrig reconstruct exited $rc"; }
out="$WORK/outside/results/shock-absorber-arx"
[ -d "$out" ] || fail "vrig reconstruct wrote no results folder $out"
[ -f "$out/summary.json" ] || fail "no summary.json in $out: $(ls "$out")"
step "ok: vrig reconstruct took $((SECONDS - start)) s, wrote $(find "$out" -type f | wc -l) files"
