"""MkDocs hooks of the vrig site: pages generated at build time from the code itself, and two
checks of the executed tutorials.

* ``<!-- vrig:cli-help -->`` in a page becomes the ``--help`` text of ``vrig`` and of each of its
  sub-commands, taken from the argparse parser the CLI really uses (so it cannot go stale);
* ``<!-- vrig:rigs-table -->`` becomes a table of the shipped rigs read from their side-car files
  (``models/<rig>/<rig>.rig.json``, validated by :func:`vrig.rigs.spec.read_description`);
* a tutorial (a notebook page of mkdocs-jupyter) gets its table of contents from its rendered
  headings: mkdocs-jupyter builds it from a Markdown copy with every inline code span deleted, so
  a heading such as "5. The same with `vrig.reconstruct`" lost its code in the navigation and its
  link pointed at an anchor that does not exist. Material's ``typeset`` plugin (mkdocs.yml) then
  keeps the code formatting of every heading in the navigation, on every page;
* an executed tutorial whose output has a stderr box (a warning, a progress bar, a traceback
  allowed through) is a warning of the build, so ``mkdocs build --strict`` fails on it.
"""

from __future__ import annotations

import argparse
import html as html_lib
import io
import logging
import os
import re
from contextlib import redirect_stdout
from html.parser import HTMLParser

from markdown.extensions.toc import nest_toc_tokens
from mkdocs.plugins import event_priority
from mkdocs.structure.toc import get_toc

log = logging.getLogger("mkdocs.hooks.vrig_docs")  # under "mkdocs": counted by --strict

CLI_MARK = "<!-- vrig:cli-help -->"
RIGS_MARK = "<!-- vrig:rigs-table -->"


def _help(parser: argparse.ArgumentParser) -> str:
    os.environ.setdefault("COLUMNS", "100")  # argparse wraps to the terminal width: fix it
    buf = io.StringIO()
    with redirect_stdout(buf):
        parser.print_help()
    return buf.getvalue().rstrip()


def cli_markdown() -> str:
    from vrig.cli import _parser

    parser = _parser()
    parts = ["```text", "$ vrig --help", _help(parser), "```"]
    subs = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    for name, sub in subs.choices.items():
        parts += ["", f"## `vrig {name}`", "", "```text", f"$ vrig {name} --help", _help(sub), "```"]
    return "\n".join(parts)


def _cell(text) -> str:
    return str(text).replace("|", "\\|").replace("\n", " ")


def rigs_markdown() -> str:
    from vrig.rigs import list_rigs, rig_path
    from vrig.rigs.spec import read_description

    rows = [
        "| rig | what it is | drives | responses | fs [Hz] | test band [Hz] | default variant "
        "| gain | gym id |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for name in list_rigs():
        d = read_description(rig_path(name))
        drives = ", ".join(f"`{c.spec.name}` [{c.spec.unit}]" for c in d.inputs)
        responses = ", ".join(f"`{c.spec.name}` [{c.spec.unit}]" for c in d.outputs)
        lo, hi = d.bandwidth
        gain = d.defaults.gain if d.defaults.gain is not None else "0.8 (global)"
        gym = f"`{d.defaults.gym_id}`" if d.defaults.gym_id else "—"
        rows.append(
            f"| `{name}` | {_cell(d.title)} | {drives} | {responses} | {d.fs:g} | {lo:g}–{hi:g} "
            f"| `{d.default_variant}` | {gain} | {gym} |"
        )
    return "\n".join(rows)


def on_page_markdown(markdown: str, page, config, files) -> str:
    if CLI_MARK in markdown:
        markdown = markdown.replace(CLI_MARK, cli_markdown())
    if RIGS_MARK in markdown:
        markdown = markdown.replace(RIGS_MARK, rigs_markdown())
    return markdown


# Docstrings use Sphinx roles (:class:`~vrig.X`, :func:`reconstruct`, ...), which Markdown renders
# as ":class:<code>~vrig.X</code>". Turn them into autorefs cross-references (resolved by
# mkdocs-autorefs after every page is rendered; "optional": an object that has no page of its own
# stays plain code instead of failing the strict build).
_ROLE = re.compile(r":(?:class|func|meth|mod|attr|data|exc|obj|py:\w+):<code>(~?)([^<]+)</code>")


def _role(match: re.Match) -> str:
    tilde, target = match.groups()
    target = target.strip()
    if target.startswith("."):
        target = target[1:]
    shown = target.rsplit(".", 1)[-1] if tilde else target
    return f'<autoref identifier="{target}" optional><code>{shown}</code></autoref>'


STDERR_MIME = "application/vnd.jupyter.stderr"  # nbconvert's class of a stderr output area
_HEADING = re.compile(r"h([1-6])")


class _Scan(HTMLParser):
    """The headings with an id (level, id, text without the anchor link's pilcrow) and the text
    of every stderr output area of a page's HTML."""

    def __init__(self) -> None:
        super().__init__(convert_charrefs=True)
        self.headings: list[tuple[int, str, str]] = []
        self.stderr: list[str] = []
        self._heading: list | None = None  # [level, id, text parts] while inside a heading
        self._anchor = 0  # depth inside an anchor link of a heading
        self._box = 0  # div depth inside a stderr area (0: outside)

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        if self._box:
            self._box += tag == "div"
        elif tag == "div" and a.get("data-mime-type") == STDERR_MIME:
            self._box = 1
            self.stderr.append("")
        m = _HEADING.fullmatch(tag)
        if m and a.get("id"):
            self._heading = [int(m.group(1)), a["id"], []]
        elif self._heading is not None and tag == "a":
            self._anchor += "anchor-link" in (a.get("class") or "") or self._anchor > 0

    def handle_endtag(self, tag):
        if self._box and tag == "div":
            self._box -= 1
        if self._heading is not None and tag == "a" and self._anchor:
            self._anchor -= 1
        elif self._heading is not None and _HEADING.fullmatch(tag):
            level, anchor, parts = self._heading
            self.headings.append((level, anchor, " ".join("".join(parts).split())))
            self._heading = None

    def handle_data(self, data):
        if self._box:
            self.stderr[-1] += data
        if self._heading is not None and not self._anchor:
            self._heading[2].append(data)


def heading_toc_tokens(html: str) -> list[dict]:
    """Table-of-contents tokens (nested, as Python-Markdown's ``toc`` makes them) of the
    headings with an id in ``html``: their ids are the page's own anchors.

    Parameters
    ----------
    html : str
        A rendered page.

    Returns
    -------
    list of dict
        ``{"level", "id", "name", "children"}`` per top heading (``name`` is HTML-escaped text).
    """
    scan = _Scan()
    scan.feed(html)
    flat = [
        {"level": level, "id": anchor, "name": html_lib.escape(text), "children": []}
        for level, anchor, text in scan.headings
    ]
    return nest_toc_tokens(flat)


def stderr_boxes(html: str) -> list[str]:
    """The text of every stderr output area (nbconvert's pink box) of a rendered notebook.

    Parameters
    ----------
    html : str
        A rendered notebook page.

    Returns
    -------
    list of str
        One entry per box, whitespace-collapsed.
    """
    scan = _Scan()
    scan.feed(html)
    return [" ".join(text.split()) for text in scan.stderr]


def _is_notebook(page) -> bool:
    return page.file.src_uri.endswith((".py", ".ipynb"))


@event_priority(100)  # before Material's typeset plugin reads page.toc
def on_page_content(html: str, page, config, files) -> str:
    if _is_notebook(page):
        page.toc = get_toc(heading_toc_tokens(html))
        for text in stderr_boxes(html):
            log.warning(
                "%s: an executed cell wrote to stderr (a warning box on the page): %s",
                page.file.src_uri,
                text[:300],
            )
    return _ROLE.sub(_role, html)
