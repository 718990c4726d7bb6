"""The README's and the documentation pages' Python examples run as written (issue 15: "its
examples run as written"; issue 25 moved most of the README's examples into docs/*.md pages).

Every ```python block of README.md and of docs/*.md is run, as it stands, in a fresh interpreter
in an empty working directory (the examples write e.g. ``results/my-test``), with this checkout
first on the path. An HTML comment on the line before a block changes how it is run:

* ``<!-- docs: slow (REASON) -->``: the block is a ``slow`` test (``-m slow``; CI runs it);
* ``<!-- docs: skip-exec (REASON) -->``: the block is not run (say why; keep these rare).

The blocks marked today are listed in ``MARKED`` so that a new marker is a visible change.
``models/README.md``'s minimal user rig is written out as its blocks stand and the README's main
command is run on it.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]
README = ROOT / "README.md"
PAGES = [README, *sorted((ROOT / "docs").glob("*.md"))]
BLOCK = re.compile(r"(?:<!--\s*docs:\s*(?P<mark>slow|skip-exec)\b(?P<why>[^>]*)-->\s*\n)?```python\n(?P<code>.*?)```", re.S)
TIMEOUT = 600  # s, per block (the slowest, the gym training example, trains a policy)

# (page, first line of the block, marker): every marked block, so a new skip or slow marker shows
MARKED = {
    ("docs/reconstruction.md", "import vrig", "slow"),  # a 30 s record, 5 iterations
    ("docs/gym.md", "import sys", "slow"),  # the gym example trains a policy
}


def readme_blocks(page: Path = README) -> list[tuple[str, str, str]]:
    """(code, marker, reason) of every ```python block of ``page``, in order."""
    text = page.read_text(encoding="utf-8")
    return [(m["code"], m["mark"] or "", (m["why"] or "").strip()) for m in BLOCK.finditer(text)]


def _all_blocks() -> list[tuple[str, str, str, str]]:
    """(page, code, marker, reason) of every page's ```python blocks."""
    return [
        (page.relative_to(ROOT).as_posix(), *block)
        for page in PAGES
        for block in readme_blocks(page)
    ]


def _params():
    params = []
    for i, (page, code, mark, why) in enumerate(_all_blocks()):
        first = code.strip().splitlines()[0]
        marks = []
        if mark == "slow":
            marks.append(pytest.mark.slow)
        elif mark == "skip-exec":
            marks.append(pytest.mark.skip(reason=f"{page} marks it skip-exec {why}"))
        params.append(pytest.param(code, id=f"{page}-block{i}-{first[:30]}", marks=marks))
    return params


def test_readme_has_python_examples_and_the_marked_ones_are_known():
    assert readme_blocks(), "the README's Python example was not found (```python fences)"
    blocks = _all_blocks()
    assert len(blocks) >= 6, "the pages' Python examples were not found (```python fences)"
    marked = {(page, code.strip().splitlines()[0], mark) for page, code, mark, _ in blocks if mark}
    assert marked == MARKED, f"docs markers changed: {marked ^ MARKED}"


def test_readme_links_the_docs():
    text = README.read_text(encoding="utf-8")
    assert 'pip install -e ".[docs]" && mkdocs serve' in text


@pytest.mark.parametrize("code", _params())
def test_readme_block_runs(code, tmp_path):
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT), env.get("PYTHONPATH", "")]).rstrip(os.pathsep)
    env.setdefault("MPLBACKEND", "Agg")
    env.setdefault("OPENBLAS_NUM_THREADS", "1")
    script = tmp_path / "block.py"
    script.write_text(code, encoding="utf-8")
    done = subprocess.run(
        [sys.executable, str(script)],
        cwd=tmp_path,
        env=env,
        capture_output=True,
        text=True,
        timeout=TIMEOUT,
    )
    assert done.returncode == 0, (
        f"example failed (exit {done.returncode}):\n{code}\n--- stderr ---\n{done.stderr[-4000:]}"
    )


# ---------------------------------------------------------------------------------------------
# models/README.md's "minimal user rig" (issue 25): the README's main command on it
# ---------------------------------------------------------------------------------------------
MODELS_README = ROOT / "models" / "README.md"


def _own_rig_files(folder: Path) -> Path:
    """Write models/README.md's minimal user rig (its ```xml and ```json blocks, as written, the
    include path set to vrig.rigs.COMMON_DIR as its comment says) into ``folder``."""
    from vrig.rigs import COMMON_DIR

    text = MODELS_README.read_text(encoding="utf-8")
    start = text.index("A minimal user rig")
    xml = re.search(r"```xml\n(.*?)```", text[start:], re.S)[1]
    side_car = re.search(r"```json\n(.*?)```", text[start:], re.S)[1]
    placeholder = "/path/to/vrig/models/common/hydraulic.xml"
    assert placeholder in xml, "the example's include line changed: update this test"
    xml = xml.replace(placeholder, (Path(COMMON_DIR) / "hydraulic.xml").as_posix())
    (folder / "my_rig.xml").write_text(xml, encoding="utf-8")
    (folder / "my_rig.rig.json").write_text(side_car, encoding="utf-8")
    return folder / "my_rig.xml"


def test_the_own_rig_example_runs_the_readmes_main_command(tmp_path):
    """``vrig reconstruct --rig my_rig.xml --method arx`` (the README's main command) on the
    example rig, its side-car without a "reconstruction" block (default band 0-fs/4 = 0-125 Hz):
    the pseudo-field desired response tripped the accelerometer's 200 m/s^2 range at every level
    the rule allowed (10 % of the drive's full scale, halved four times: 0.625 %) and the command
    failed (exit 1) before anything was identified."""
    _own_rig_files(tmp_path)
    env = dict(os.environ, PYTHONPATH=str(ROOT), OPENBLAS_NUM_THREADS="1", MPLBACKEND="Agg")
    code = "import sys; from vrig.cli import main; sys.exit(main(sys.argv[1:]))"
    argv = ["reconstruct", "--rig", "my_rig.xml", "--method", "arx"]
    done = subprocess.run(
        [sys.executable, "-c", code, *argv], cwd=tmp_path, env=env, capture_output=True,
        text=True, timeout=TIMEOUT,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr[-3000:]
    assert "best      IT" in done.stdout
    assert (tmp_path / "results" / "my_rig-arx" / "summary.json").is_file()


class _RangeLimitedRig:
    """A one-drive rig whose response is its drive, tripping above ``trip_rms`` [m rms]."""

    fs, name = 200.0, "stub"

    def __init__(self, trip_rms: float):
        from types import SimpleNamespace

        self.trip_rms = trip_rms
        self.inputs = [SimpleNamespace(name="disp", unit="m", full_scale=1.0)]
        self.outputs = [SimpleNamespace(name="acc", unit="m/s^2", full_scale=1e6)]

    def run(self, drive, seed=None):
        import vrig

        rms = float(np.sqrt(np.mean(drive.data**2)))
        if rms > self.trip_rms:
            raise vrig.RigLimitError("transducer range", "acc", 0.0, rms, self.trip_rms, "m/s^2")
        return vrig.TimeHistory(drive.data.copy(), drive.fs, ["acc"], ["m/s^2"])


def test_the_pseudo_field_level_halves_until_the_rig_runs():
    """The level starts at 10 % of the drive's full scale and is halved until the drive and
    1.5 times it run: a rig that takes 0.5 % rms (1.5 x the level <= 0.5 %) gets 10 % / 32 (the
    fifth halving; the rule used to stop at the fourth and raise)."""
    import vrig

    drive, _ = vrig.pseudo_field(_RangeLimitedRig(0.005), (0.0, 40.0), 10.0, seed=0)
    fade = 0.935  # the 1 s fades of a 10 s record lower the RMS by sqrt(1 - 0.625 * 0.2)
    assert np.sqrt(np.mean(drive.data**2)) == pytest.approx(0.1 / 32 * fade, rel=0.02)
    with pytest.raises(vrig.RigLimitError):  # below 1/1024 of the start: the rig's trip, raised
        vrig.pseudo_field(_RangeLimitedRig(0.1 / 2048), (0.0, 40.0), 10.0, seed=0)
