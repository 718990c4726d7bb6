"""The module map of ``docs/status.md`` is complete: every module of ``vrig/``,
``identification/`` and ``benchmarks/`` has its line (what it is, who calls it), and every line
names a module that exists. Truth: the package folders themselves."""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("vrig", "identification", "benchmarks")


def _modules() -> set[str]:
    """Dotted names of every module and package under the three packages."""
    names = set()
    for package in PACKAGES:
        for path in (ROOT / package).rglob("*.py"):
            parts = list(path.relative_to(ROOT).with_suffix("").parts)
            if parts[-1] == "__init__":
                parts.pop()
            names.add(".".join(parts))
    return names


def _mapped() -> list[str]:
    """The module column of the map's table rows (``| `name` | what | who |``)."""
    text = (ROOT / "docs" / "status.md").read_text(encoding="utf-8")
    cell = r"(?:\\\||[^|\n])+"  # a cell's text: anything but a bare "|" (``\|`` is escaped)
    return re.findall(rf"^\| `([\w.]+)` \|{cell}\|{cell}\|$", text, flags=re.MULTILINE)


def test_every_module_has_one_line_in_the_map():
    mapped = _mapped()
    missing = sorted(_modules() - set(mapped))
    assert not missing, f"docs/status.md's module map lacks: {missing}"
    assert len(mapped) == len(set(mapped)), "a module appears twice in the map"


def test_every_line_of_the_map_names_a_module_that_exists():
    stale = sorted(set(_mapped()) - _modules())
    assert not stale, f"docs/status.md's module map names modules that do not exist: {stale}"
