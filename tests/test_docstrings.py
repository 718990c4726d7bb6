"""Every public function, class and method of ``identification/`` and ``vrig/`` has a docstring
(issue 14, acceptance: "every public function and method documented").

Public: a name without a leading underscore, in a module whose path has no component with one
(``__init__.py`` counts as public), methods and properties of public classes included, dunder
methods not (a class documents its constructor). The source is read with :mod:`ast`, never
imported. Only the presence of a non-empty docstring is checked today, not its numpydoc sections
(python-control's ``test_docstrings`` checks the Parameters section against the signature).
"""

from __future__ import annotations

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("identification", "vrig")

# Documentation debt found when this test was written (issue 14): public definitions without a
# docstring. The list may only shrink: a new public definition needs a docstring, and an entry
# that gained one (or was renamed or removed) must be deleted here (the last test says which).
UNDOCUMENTED = {
    ("identification/error_model.py", "ErrorSignalModel.describe"),
    ("identification/free_run_selection.py", "SelectionPath.selected"),
    ("identification/free_run_selection.py", "check_criterion"),
    ("identification/output_error.py", "FlatModel.from_channels"),
    ("identification/output_error.py", "FlatModel.n_params"),
    ("identification/simulation.py", "SimulationPlan.n_output_monomials"),
    ("identification/split_spectra.py", "SplitSpectraModel.describe"),
    ("identification/structure.py", "ChannelStructure.n_regressors"),
    ("identification/structure.py", "ChannelStructure.n_terms"),
    ("identification/structure.py", "ChannelStructure.max_lag"),
    ("vrig/envs/drive_iteration.py", "ActionLayout.n_gains"),
    ("vrig/envs/drive_iteration.py", "ActionLayout.size"),
    ("vrig/envs/drive_iteration.py", "DriveIterationEnv.reset"),
    ("vrig/envs/drive_iteration.py", "DriveIterationEnv.step"),
    ("vrig/envs/drive_iteration.py", "DriveIterationEnv.close"),
    ("vrig/envs/task.py", "IterationTask.n_bands"),
    ("vrig/envs/task.py", "IterationTask.observation_space"),
    ("vrig/envs/task.py", "IterationTask.drive_energy"),
    ("vrig/envs/task.py", "IterationTask.success"),
    ("vrig/policies.py", "Policy.reidentify"),
    ("vrig/policies.py", "FixedGain.gains"),
    ("vrig/policies.py", "DecreasingGain.gains"),
    ("vrig/policies.py", "AdaptiveBandGain.reset"),
    ("vrig/policies.py", "AdaptiveBandGain.gains"),
    ("vrig/policies.py", "BandRatioPolicy.n_params"),
    ("vrig/policies.py", "BandRatioPolicy.gains"),
    ("vrig/reconstruction/methods.py", "SplitSpectra.identify"),
    ("vrig/reconstruction/methods.py", "SplitSpectra.drive"),
    ("vrig/reconstruction/methods.py", "SplitSpectra.describe"),
    ("vrig/reconstruction/methods.py", "InverseFrf.identify"),
    ("vrig/rigs/daq.py", "AntiAliasFilter.sos"),
    ("vrig/rigs/mujoco_rig.py", "MujocoRig.name"),
    ("vrig/rigs/mujoco_rig.py", "MujocoRig.inputs"),
    ("vrig/rigs/mujoco_rig.py", "MujocoRig.outputs"),
    ("vrig/rigs/mujoco_rig.py", "MujocoRig.input_defs"),
    ("vrig/rigs/mujoco_rig.py", "MujocoRig.output_defs"),
    ("vrig/rigs/mujoco_rig.py", "MujocoRig.description"),
    ("vrig/rigs/spec.py", "InputDef"),
    ("vrig/rigs/spec.py", "OutputDef"),
    ("vrig/rigs/subset.py", "OutputSubset.name"),
    ("vrig/timehistory.py", "TimeHistory.n_samples"),
    ("vrig/timehistory.py", "TimeHistory.n_channels"),
    ("vrig/timehistory.py", "TimeHistory.dt"),
    ("vrig/timehistory.py", "TimeHistory.index"),
}


def _is_public_module(rel: Path) -> bool:
    return not any(p.startswith("_") and p not in ("__init__.py", "__main__.py") for p in rel.parts)


def public_definitions(source: str) -> dict[str, bool]:
    """Qualified name -> has a non-empty docstring, for every public function, class and method
    (of a public class, at any nesting of classes) in ``source``."""
    found: dict[str, bool] = {}

    def visit(body: list[ast.stmt], prefix: str) -> None:
        for node in body:
            if not isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
                continue
            if node.name.startswith("_"):
                continue
            name = prefix + node.name
            doc = ast.get_docstring(node)
            found[name] = found.get(name, False) or bool(doc and doc.strip())
            if isinstance(node, ast.ClassDef):
                visit(node.body, name + ".")

    visit(ast.parse(source).body, "")
    return found


def _package_definitions() -> dict[tuple[str, str], bool]:
    found = {}
    for top in PACKAGES:
        for path in sorted((ROOT / top).rglob("*.py")):
            rel = path.relative_to(ROOT)
            if "__pycache__" in rel.parts or not _is_public_module(rel):
                continue
            for name, documented in public_definitions(path.read_text(encoding="utf-8")).items():
                found[rel.as_posix(), name] = documented
    return found


def test_public_definitions_are_found_and_private_ones_skipped():
    src = (
        'def f():\n    """Doc."""\n\ndef g():\n    pass\n\ndef _h():\n    pass\n\n'
        "class C:\n    def __init__(self):\n        pass\n\n    @property\n"
        "    def p(self):\n        return 1\n\n    def _q(self):\n        pass\n\n"
        '    class D:\n        """ """\n'
    )
    expected = {"f": True, "g": False, "C": False, "C.p": False, "C.D": False}
    assert public_definitions(src) == expected
    assert _is_public_module(Path("vrig/io/__init__.py"))
    assert not _is_public_module(Path("identification/_sensitivity.py"))


def test_every_public_function_and_method_has_a_docstring():
    found = _package_definitions()
    assert len(found) > 300, "too few public definitions found: wrong root?"
    missing = sorted(key for key, documented in found.items() if not documented)
    new = [key for key in missing if key not in UNDOCUMENTED]
    assert not new, "public definitions without a docstring: " + ", ".join(
        f"{f}:{name}" for f, name in new
    )


def test_the_documentation_debt_list_holds_only_undocumented_definitions():
    found = _package_definitions()
    stale = sorted(key for key in UNDOCUMENTED if found.get(key, True))
    assert not stale, f"documented (or gone) now: remove from UNDOCUMENTED: {stale}"
