"""The documentation site's own hooks (docs/_hooks/vrig_docs.py) and the quiet tutorials (issue 25,
item 9): a tutorial's table of contents keeps the code of its headings and links to anchors that
exist; a stderr box (a warning, a progress bar) in an executed tutorial is a warning of the build,
so the strict build fails on it; importing vrig in a Jupyter kernel warns about nothing.

The strict build itself (``mkdocs build --strict``, executing every tutorial) runs in CI
(.ci/run), not here: it takes minutes.
"""

from __future__ import annotations

import html as html_lib
import importlib.util
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
TUTORIALS = sorted((ROOT / "docs" / "tutorials").glob("*.py"))


def _hooks():
    spec = importlib.util.spec_from_file_location("vrig_docs", ROOT / "docs/_hooks/vrig_docs.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


pytest.importorskip("mkdocs")  # the docs extra: pip install -e ".[docs]"
yaml = pytest.importorskip("yaml")  # comes with mkdocs
hooks = _hooks()

# what nbconvert (through mkdocs-jupyter) makes of a notebook: a heading with an id and an anchor
# link, a heading with inline code, a stderr output area (with a nested block)
NOTEBOOK_HTML = """
<h1 id="the-title">The title<a class="anchor-link" href="#the-title">¶</a></h1>
<p>text</p>
<h2 id="1-with-vrigreconstruct">1. With <code>vrig.reconstruct</code>, and more<a class="anchor-link"
 href="#1-with-vrigreconstruct">¶</a></h2>
<h3 id="a-detail">A detail<a class="anchor-link" href="#a-detail">¶</a></h3>
<h2 id="2-next">2. Next<a class="anchor-link" href="#2-next">¶</a></h2>
<div class="jp-RenderedText jp-OutputArea-output" data-mime-type="application/vnd.jupyter.stdout">
<pre>ordinary output</pre></div>
<div class="jp-RenderedText jp-OutputArea-output" data-mime-type="application/vnd.jupyter.stderr">
<pre>/home/x/tqdm/auto.py:21: TqdmWarning: <div>IProgress</div> not found</pre></div>
<p>after</p>
"""


def test_toc_tokens_keep_the_code_of_a_heading_and_its_real_anchor():
    (title,) = hooks.heading_toc_tokens(NOTEBOOK_HTML)
    assert (title["level"], title["id"], title["name"]) == (1, "the-title", "The title")
    first, second = title["children"]
    assert first["name"] == "1. With vrig.reconstruct, and more"  # the code text is kept
    assert first["id"] == "1-with-vrigreconstruct"  # the anchor the page really has
    assert [c["name"] for c in first["children"]] == ["A detail"]
    assert second["name"] == "2. Next" and second["children"] == []


def test_stderr_boxes_are_found_with_their_text():
    assert hooks.stderr_boxes(NOTEBOOK_HTML) == [
        "/home/x/tqdm/auto.py:21: TqdmWarning: IProgress not found"
    ]
    assert hooks.stderr_boxes(NOTEBOOK_HTML.replace("jupyter.stderr", "jupyter.stdout")) == []


def test_a_stderr_box_in_a_tutorial_is_a_build_warning(caplog):
    """``on_page_content`` logs a warning (which ``--strict`` turns into a failed build) naming
    the tutorial and quoting the box, and replaces the notebook's table of contents."""

    class File:
        src_uri = "tutorials/example.py"

    class Page:
        file = File()
        toc = None

    page = Page()
    with caplog.at_level("WARNING", logger="mkdocs"):
        hooks.on_page_content(NOTEBOOK_HTML, page=page, config={}, files=None)
    (record,) = [r for r in caplog.records if r.levelname == "WARNING"]
    assert record.name.startswith("mkdocs.")  # counted by mkdocs build --strict
    assert "tutorials/example.py" in record.getMessage()
    assert "TqdmWarning" in record.getMessage()
    assert [item.title for item in page.toc] == ["The title"]
    caplog.clear()
    quiet = Page()
    hooks.on_page_content(NOTEBOOK_HTML.replace("stderr", "stdout"), page=quiet, config={}, files=None)
    assert not [r for r in caplog.records if r.levelname == "WARNING"]


def test_the_site_uses_the_hooks_and_keeps_code_in_the_navigation():
    text = (ROOT / "mkdocs.yml").read_text(encoding="utf-8")
    text = re.sub(r"!ENV \[[^\]]*\]", "true", text)  # a YAML tag of MkDocs
    config = yaml.safe_load(text)
    assert config["strict"] is True
    assert "docs/_hooks/vrig_docs.py" in config["hooks"]
    names = [p if isinstance(p, str) else next(iter(p)) for p in config["plugins"]]
    assert "typeset" in names  # Material's: <code> in the navigation
    assert names.index("typeset") < names.index("mkdocs-jupyter")


@pytest.mark.parametrize("path", TUTORIALS, ids=[p.stem for p in TUTORIALS])
def test_every_tutorial_heading_is_in_its_toc_with_its_code(path):
    """Convert the tutorial (not executed) as mkdocs-jupyter does and build its table of
    contents from the rendered headings: every Markdown heading of the tutorial is there, inline
    code text included, each linking to an id of the page."""
    jupytext = pytest.importorskip("jupytext")
    convert = pytest.importorskip("mkdocs_jupyter.convert")
    html = convert.nb2html(str(path), execute=False)
    ids = set(re.findall(r'<h[1-6][^>]*\sid="([^"]+)"', html))

    def flat(tokens):
        for t in tokens:
            yield t
            yield from flat(t["children"])

    toc = list(flat(hooks.heading_toc_tokens(html)))
    names = [html_lib.unescape(t["name"]) for t in toc]
    assert {t["id"] for t in toc} <= ids
    notebook = jupytext.read(path)
    wanted = [  # the heading's text: code spans and emphasis as plain text
        re.sub(r"`([^`]*)`|\*\*?([^*]*)\*\*?", lambda g: g.group(1) or g.group(2), m.group(1))
        for cell in notebook.cells
        if cell.cell_type == "markdown"
        for m in re.finditer(r"^#{1,6}\s+(.+?)\s*$", cell.source, re.M)
    ]
    assert wanted
    missing = [h for h in wanted if h not in names]
    assert not missing, (missing, names)


@pytest.mark.skipif(importlib.util.find_spec("ipykernel") is None, reason="no ipykernel")
def test_importing_vrig_in_a_jupyter_kernel_warns_about_nothing(tmp_path):
    """Inside a kernel (``ipykernel.zmqshell`` imported) ``tqdm.auto`` looks for ipywidgets and
    warns "IProgress not found" (a pink box in every executed tutorial): vrig's bars and status
    lines are plain tqdm, so importing vrig and showing progress warns about nothing."""
    code = """
import warnings
import ipykernel.zmqshell  # what tqdm.autonotebook takes for a Jupyter kernel
warnings.simplefilter("always")
with warnings.catch_warnings(record=True) as caught:
    import vrig, vrig.cli, vrig.linearity, vrig.progress, vrig.reconstruction.iteration
    with vrig.progress.enabled():
        with vrig.progress.bar(2, desc="runs") as b:
            b.update(2)
        vrig.progress.status("identifying")
tqdm_warnings = [str(w.message) for w in caught if "tqdm" in w.category.__module__]
print(repr(tqdm_warnings))
"""
    env = dict(os.environ, PYTHONPATH=str(ROOT), OPENBLAS_NUM_THREADS="1")
    done = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, cwd=tmp_path, env=env,
        timeout=300,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr[-3000:]
    assert done.stdout.strip().splitlines()[-1] == "[]", done.stdout
    assert "IProgress" not in done.stderr
