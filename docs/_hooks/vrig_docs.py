"""MkDocs hooks of the vrig site: pages generated at build time from the code itself.

* ``<!-- vrig:cli-help -->`` in a page becomes the ``--help`` text of ``vrig`` and of each of its
  sub-commands, taken from the argparse parser the CLI really uses (so it cannot go stale);
* ``<!-- vrig:rigs-table -->`` becomes a table of the shipped rigs read from their side-car files
  (``models/<rig>/<rig>.rig.json``, validated by :func:`vrig.rigs.spec.read_description`).
"""

from __future__ import annotations

import argparse
import io
import os
import re
from contextlib import redirect_stdout

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


def on_page_content(html: str, page, config, files) -> str:
    return _ROLE.sub(_role, html)
