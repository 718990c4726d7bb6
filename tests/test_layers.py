"""The three floors: ``benchmarks -> vrig -> identification`` (issue 14, acceptance: "no import of
``benchmarks`` from ``vrig/``"). Read with :mod:`ast` (every import statement, at any depth: a
lazy import inside a function counts too), plus one import-time check in a fresh interpreter.
"""

from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

FORBIDDEN = {
    "identification": {"vrig", "benchmarks", "mujoco", "gymnasium"},
    "vrig": {"benchmarks"},
}
"""Top-level packages each floor must not import."""


def _imports(path: Path):
    """(line, top-level module) of every import in ``path`` (relative imports excluded)."""
    tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for alias in node.names:
                yield node.lineno, alias.name.split(".")[0]
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            yield node.lineno, node.module.split(".")[0]


@pytest.mark.parametrize("package", sorted(FORBIDDEN))
def test_no_floor_imports_a_floor_above_it(package):
    bad = [
        f"{path.relative_to(ROOT)}:{line}: imports {module}"
        for path in sorted((ROOT / package).rglob("*.py"))
        for line, module in _imports(path)
        if module in FORBIDDEN[package]
    ]
    assert not bad, "\n".join(bad)


def test_the_ast_scan_sees_a_lazy_import(tmp_path):
    """The scan itself: an import inside a function body is found."""
    f = tmp_path / "m.py"
    f.write_text("def g():\n    from benchmarks.runner import cli\n    import vrig.io as io\n")
    assert list(_imports(f)) == [(2, "benchmarks"), (3, "vrig")]


def test_importing_identification_loads_neither_vrig_nor_mujoco():
    code = (
        "import sys, identification; "
        "bad = sorted(m for m in ('vrig', 'mujoco', 'benchmarks', 'gymnasium') if m in sys.modules); "
        "print(bad); sys.exit(1 if bad else 0)"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, timeout=120
    )
    assert out.returncode == 0, out.stdout + out.stderr
