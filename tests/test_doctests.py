"""The docstring examples of ``vrig`` and ``identification`` run as doctests.

Examples that need a rig run or data that is not there are marked ``# doctest: +SKIP`` in the
docstring (with what they need in the comment); every other ``>>>`` line runs here and must give
the output the docstring shows. The same run as ``python -m pytest --doctest-modules vrig
identification``, kept in the default test suite.
"""

from __future__ import annotations

import doctest
import importlib
import pkgutil

import pytest

import identification
import vrig

PACKAGES = (vrig, identification)


def _modules():
    names = []
    for pkg in PACKAGES:
        names.append(pkg.__name__)
        for info in pkgutil.walk_packages(pkg.__path__, prefix=pkg.__name__ + "."):
            if info.name.rsplit(".", 1)[-1] != "__main__":
                names.append(info.name)
    return sorted(names)


MODULES = _modules()


@pytest.mark.parametrize("name", MODULES)
def test_docstring_examples(name):
    module = importlib.import_module(name)
    finder = doctest.DocTestFinder(exclude_empty=True)
    runner = doctest.DocTestRunner(optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
    for test in finder.find(module, name):  # globals: a copy of the module's, as pytest does
        runner.run(test)
    result = runner.summarize(verbose=False)
    assert result.failed == 0, f"{result.failed} of {result.attempted} doctest examples failed in {name}"


def test_some_examples_really_run():
    """Guard against a run that silently tests nothing: count the examples not marked +SKIP
    (TimeHistory, term_count, the package docstrings' imports, ...)."""
    finder = doctest.DocTestFinder(exclude_empty=True)
    runnable = sum(
        1
        for name in MODULES
        for test in finder.find(importlib.import_module(name), name)
        for example in test.examples
        if not example.options.get(doctest.SKIP)
    )
    assert runnable >= 5
