"""The README's and the documentation pages' Python examples run as written (issue 15: "its
examples run as written"; issue 25 moved most of the README's examples into docs/*.md pages).

Every ```python block of README.md and of docs/*.md is run, as it stands, in a fresh interpreter
in an empty working directory (the examples write e.g. ``results/my-test``), with this checkout
first on the path. An HTML comment on the line before a block changes how it is run:

* ``<!-- docs: slow (REASON) -->``: the block is a ``slow`` test (``-m slow``; CI runs it);
* ``<!-- docs: skip-exec (REASON) -->``: the block is not run (say why; keep these rare).

The blocks marked today are listed in ``MARKED`` so that a new marker is a visible change.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

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
