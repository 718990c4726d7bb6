"""What an installed vrig is made of (issue 15, deliverable 6).

The wheel ships every source package: pyproject lists packages by name, so a new subpackage that
is not listed would silently be missing from an installed vrig (found when vrig.io became a
package). It also ships the licence, the ``py.typed`` markers (PEP 561) and every rig model file;
the version is written in one place. The fast tests read pyproject.toml against the files on
disk (setuptools' package-data patterns are globs relative to the package directory); the slow
test builds the wheel once and reads its file list and metadata. CI installs the built wheel in
a fresh venv and runs the README's main command from outside the checkout (.ci/wheel_check.sh).
"""

from __future__ import annotations

import ast
import re
import shutil
import subprocess
import sys
import tomllib
import zipfile
from pathlib import Path

import pytest

import vrig
from vrig.cli import main

ROOT = Path(__file__).resolve().parents[1]
PYPROJECT = tomllib.loads((ROOT / "pyproject.toml").read_text())
SETUPTOOLS = PYPROJECT["tool"]["setuptools"]
PEP440 = re.compile(r"^\d+(\.\d+)*((a|b|rc)\d+)?(\.post\d+)?(\.dev\d+)?$")  # public versions


def _package_dir(package: str) -> Path:
    """The source folder of ``package`` under [tool.setuptools.package-dir]."""
    mapped = SETUPTOOLS.get("package-dir", {})
    return ROOT / mapped.get(package, package.replace(".", "/"))


def _shipped_data(package: str) -> set[Path]:
    """Files of ``package`` that its [tool.setuptools.package-data] patterns select."""
    patterns = SETUPTOOLS.get("package-data", {}).get(package, [])
    folder = _package_dir(package)
    return {p for pattern in patterns for p in folder.glob(pattern) if p.is_file()}


def test_every_source_package_is_listed_in_pyproject():
    listed = set(SETUPTOOLS["packages"])
    found = {
        ".".join(init.parent.relative_to(ROOT).parts)
        for top in ("identification", "vrig")
        for init in (ROOT / top).rglob("__init__.py")
        if "__pycache__" not in init.parts
    }
    assert found, "no package found: wrong root"
    missing = sorted(found - listed)
    assert not missing, f"packages missing from pyproject [tool.setuptools] packages: {missing}"


def test_every_model_file_is_package_data():
    """Every non-Python file under models/ (MJCF, side-cars, schema, READMEs) is selected."""
    models = _package_dir("vrig.models")
    on_disk = {
        p
        for p in models.rglob("*")
        if p.is_file() and p.suffix not in (".py", ".pyc") and "__pycache__" not in p.parts
    }
    assert {p.name for p in on_disk} >= {"rig.schema.json", "shock-absorber.xml", "hydraulic.xml"}
    missing = sorted(str(p.relative_to(ROOT)) for p in on_disk - _shipped_data("vrig.models"))
    assert not missing, f"model files not in [tool.setuptools.package-data] vrig.models: {missing}"


@pytest.mark.parametrize("package", ["vrig", "identification"])
def test_py_typed_marker_exists_and_ships(package):
    marker = _package_dir(package) / "py.typed"
    assert marker.is_file(), f"{marker} missing (PEP 561)"
    assert marker in _shipped_data(package), f"{package}/py.typed not in package-data"


def test_mit_licence_file_and_pep639_metadata():
    text = (ROOT / "LICENSE").read_text()
    assert text.startswith("MIT License")
    assert "Copyright (c) 2026 the vrig developers" in text
    assert "WITHOUT WARRANTY OF ANY KIND" in text
    project = PYPROJECT["project"]
    assert project["license"] == "MIT"  # an SPDX expression (PEP 639), not a {text = ...} table
    assert project["license-files"] == ["LICENSE"]
    # PEP 639: the licence classifiers are superseded by the expression (setuptools refuses both)
    assert not [c for c in project["classifiers"] if c.startswith("License ::")]
    # setuptools reads `license` as an SPDX string and `license-files` from version 77 on
    pins = [r for r in PYPROJECT["build-system"]["requires"] if r.startswith("setuptools")]
    assert pins, "no setuptools build requirement"
    minimum = re.fullmatch(r"setuptools>=(\d+)(\.\d+)*", pins[0])
    assert minimum and int(minimum.group(1)) >= 77, pins


def test_classifiers_match_requires_python():
    project = PYPROJECT["project"]
    assert project["requires-python"] == ">=3.11"
    classifiers = set(project["classifiers"])
    assert {
        "Programming Language :: Python :: 3.11",
        "Programming Language :: Python :: 3.12",
        "Operating System :: OS Independent",
        "Intended Audience :: Science/Research",
        "Topic :: Scientific/Engineering",
        "Typing :: Typed",
    } <= classifiers
    assert not {c for c in classifiers if re.search(r"Python :: 3\.([0-9]|10)$", c)}


def test_the_version_is_written_once():
    """pyproject takes it from vrig.__version__; no other source file assigns a version."""
    project = PYPROJECT["project"]
    assert "version" not in project and "version" in project["dynamic"]
    assert SETUPTOOLS["dynamic"]["version"] == {"attr": "vrig.__version__"}
    assert PEP440.match(vrig.__version__), vrig.__version__
    writers = []
    for top in ("vrig", "identification"):
        for path in sorted((ROOT / top).rglob("*.py")):
            for node in ast.walk(ast.parse(path.read_text(), filename=str(path))):
                targets = node.targets if isinstance(node, ast.Assign) else []
                if isinstance(node, ast.AnnAssign):
                    targets = [node.target]
                if any(isinstance(t, ast.Name) and t.id == "__version__" for t in targets):
                    writers.append(f"{path.relative_to(ROOT)}:{node.lineno}")
    assert [w.split(":")[0] for w in writers] == ["vrig/__init__.py"], writers
    # setuptools reads the attribute statically (the build has no numpy or MuJoCo): a literal
    init = ast.parse((ROOT / "vrig" / "__init__.py").read_text())
    literal = [
        n.value.value
        for n in init.body
        if isinstance(n, ast.Assign)
        and any(isinstance(t, ast.Name) and t.id == "__version__" for t in n.targets)
        and isinstance(n.value, ast.Constant)
    ]
    assert literal == [vrig.__version__]


def test_vrig_version_prints_the_version_and_exits_0(capsys):
    with pytest.raises(SystemExit) as stop:
        main(["--version"])
    assert stop.value.code == 0
    assert capsys.readouterr().out == f"vrig {vrig.__version__}\n"


def test_changelog_has_an_entry_for_the_version():
    text = (ROOT / "CHANGELOG.md").read_text()
    assert text.startswith("# Changelog")
    assert "Keep a Changelog" in text
    assert re.search(rf"^## \[{re.escape(vrig.__version__)}\]", text, re.M), (
        f"CHANGELOG.md has no '## [{vrig.__version__}]' entry"
    )
    assert re.search(r"^### Added$", text, re.M)


def test_ci_runs_the_wheel_check():
    script = ROOT / ".ci" / "wheel_check.sh"
    assert script.is_file()
    run = (ROOT / ".ci" / "run").read_text()
    assert re.search(r"^\s*bash \.ci/wheel_check\.sh\b", run, re.M), "the wheel check is not in CI"
    assert "mkdocs build --strict" in run, "the docs build is not in CI"
    body = script.read_text()
    for command in (
        '"$VRIG" --version',
        '"$VRIG" rigs',
        '"$VRIG" reconstruct --rig shock-absorber',
    ):
        assert command in body, command


def _copy_sources(dest: Path) -> Path:
    """The files a build reads, copied (an in-tree build leaves build/ and *.egg-info)."""
    dest.mkdir()
    for name in ("pyproject.toml", "README.md", "LICENSE", "vrig_console.py"):
        shutil.copy2(ROOT / name, dest / name)
    ignore = shutil.ignore_patterns("__pycache__", "*.pyc")
    for folder in ("vrig", "identification", "models"):
        shutil.copytree(ROOT / folder, dest / folder, ignore=ignore)
    return dest


# what setuptools prints when a folder it takes for a package carries data (issue 25: three boxed
# warnings, ~40 lines each, on every `pip install -e .`) or any other deprecation of the config
SETUPTOOLS_NOISE = ("is absent from the `packages` configuration", "SetuptoolsDeprecationWarning")


def test_package_data_is_exactly_the_listed_patterns():
    """No implicit package data: the model folders are data, not packages (see pyproject)."""
    assert SETUPTOOLS["include-package-data"] is False


def _pip(*args: str) -> str:
    """Run pip verbosely (the build backend's output is shown only with -v); its output."""
    done = subprocess.run(
        [sys.executable, "-m", "pip", *args, "-v"],
        capture_output=True,
        text=True,
        timeout=600,
    )
    out = done.stdout + done.stderr
    assert done.returncode == 0, out[-4000:]
    return out


def _noise(output: str) -> list[str]:
    return [line for line in output.splitlines() if any(n in line for n in SETUPTOOLS_NOISE)]


@pytest.mark.slow
def test_editable_install_prints_no_setuptools_warning(tmp_path):
    """`pip install -e .` (into a scratch prefix, isolated build: needs the package index).
    ``--ignore-installed``: without it pip uninstalls the vrig this interpreter runs from."""
    src = _copy_sources(tmp_path / "src")
    prefix = str(tmp_path / "prefix")
    out = _pip("install", "-e", str(src), "--no-deps", "--ignore-installed", "--prefix", prefix)
    assert "Successfully installed vrig" in out
    assert "uninstall" not in out.lower(), "pip touched the running environment's vrig"
    assert not _noise(out), _noise(out)


@pytest.mark.slow
def test_built_wheel_contents_and_metadata(tmp_path):
    """Build the wheel (pip, isolated build: needs the package index for setuptools) and read it;
    the build prints no setuptools warning."""
    src = _copy_sources(tmp_path / "src")
    dist = tmp_path / "dist"
    out = _pip("wheel", "--no-deps", "-w", str(dist), str(src))
    assert not _noise(out), _noise(out)
    (wheel,) = dist.glob("vrig-*.whl")
    assert wheel.name == f"vrig-{vrig.__version__}-py3-none-any.whl"
    names = set(zipfile.ZipFile(wheel).namelist())
    info = f"vrig-{vrig.__version__}.dist-info"
    assert {f"{info}/licenses/LICENSE", "vrig/py.typed", "identification/py.typed"} <= names
    models = ROOT / "models"
    expected = {
        "vrig/models/" + p.relative_to(models).as_posix()
        for p in models.rglob("*")
        if p.is_file() and "__pycache__" not in p.parts and p.suffix != ".pyc"
    }
    assert expected <= names, sorted(expected - names)
    for top in ("vrig", "identification"):
        modules = {p.relative_to(ROOT).as_posix() for p in (ROOT / top).rglob("*.py")}
        assert modules <= names, sorted(modules - names)
    metadata = zipfile.ZipFile(wheel).read(f"{info}/METADATA").decode()
    assert f"\nVersion: {vrig.__version__}\n" in metadata
    assert "\nLicense-Expression: MIT\n" in metadata
    assert "\nLicense-File: LICENSE\n" in metadata
    entry_points = zipfile.ZipFile(wheel).read(f"{info}/entry_points.txt").decode()
    assert "vrig = vrig_console:main" in entry_points
    assert "vrig_console.py" in names
