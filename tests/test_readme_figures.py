"""The README a newcomer reads first (issue 25, item 8): short, the two commands first, and every
time figure it or the documentation pages quote says which command prints it.

A *time figure* is a number with a time unit (``13 s``, ``~25 s``, ``5.3 min``, ``4-9 s``,
``10-minute``, ``two minutes``). Most of them are measurements that go stale (the quick benchmark
was quoted at "3.7 min" long after it took 15), so each must name its source in the same sentence
(or table row, or code line): a command in backticks that exists - ``vrig SUBCOMMAND`` (a real
sub-command), ``python -m benchmarks.MODULE`` (a real module), ``python -m pytest``, ``mkdocs
...``, ``pip ...``, ``bash FILE`` - or a footnote ``[^id]`` whose text names one; in a shell
block a command line is its own source. Two kinds are not measurements and need no source: the
length of a signal or a setting (``a 30 s record``, ``4 s targets``, ``a 0.25 s taper``: the
number is followed by one of :data:`DURATION_NOUNS`) and a default or budget setting
(``default 60 s``). ``tests/test_readme.py`` runs the Python examples of the same pages.
"""

from __future__ import annotations

import argparse
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
README = ROOT / "README.md"
PAGES = [README, *sorted((ROOT / "docs").glob("*.md"))]
MAX_LINES = 200
COMMANDS = (
    'pip install -e . && vrig reconstruct --rig shock-absorber --method arx',
    'pip install -e ".[test]" && python -m pytest -q',
)

_NUMBER = r"(?:\d+(?:\.\d+)?(?:\s*[-–]\s*\d+(?:\.\d+)?)?)"
_WORDS = r"(?:one|two|three|four|five|six|seven|eight|nine|ten|twenty|thirty|a few|a couple of)"
_UNIT = r"(?:ms|s|min|h|secs?|seconds?|minutes?|hours?)"
TIME_FIGURE = re.compile(
    rf"(?<![\w.])(?:{_NUMBER}[\s-]?|{_WORDS}[\s-]){_UNIT}(?![\w/²])", re.IGNORECASE
)
DURATION_NOUNS = (
    "record", "records", "drive", "drives", "target", "targets", "window", "windows", "probe",
    "taper", "ramp", "fade", "fade-in", "fade-out", "segment", "segments", "signal", "signals",
    "chunk", "chunks", "pseudo-field", "excitation", "recording", "tour",
)  # fmt: skip
SETTING_WORDS = ("default", "budget")  # "(--budget, default 60 s)": a setting, not a measurement
COMMAND = re.compile(r"`((?:vrig|python|pip|mkdocs|bash|pytest)(?:\s[^`]*)?)`")  # not vrig.io
FOOTNOTE_REF = re.compile(r"\[\^([\w-]+)\](?!:)")
FOOTNOTE_DEF = re.compile(r"^\[\^([\w-]+)\]:(.*(?:\n(?: {4}|\t).*)*)", re.M)
FENCE = re.compile(r"^```(\w*)\n(.*?)^```", re.S | re.M)


def _subcommands() -> set[str]:
    from vrig.cli import _parser

    parser = _parser()
    subs = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return set(subs.choices)


def command_exists(command: str) -> bool:
    """Whether a quoted command names something that exists in this checkout."""
    words = command.split()
    if words[0] == "vrig":
        return len(words) == 1 or words[1].startswith("-") or words[1] in _subcommands()
    if words[:2] == ["python", "-m"] and len(words) > 2:
        module = words[2]
        if module == "pytest":
            return True
        path = ROOT.joinpath(*module.split("."))
        return path.with_suffix(".py").is_file() or (path / "__main__.py").is_file()
    if words[0] == "bash":
        return len(words) > 1 and (ROOT / words[1]).is_file()
    return words[0] in ("pip", "mkdocs", "pytest", "python")


def _units(text: str) -> list[tuple[str, str]]:
    """``(kind, text)`` units a figure's source must share: ``"prose"`` sentences and table
    rows, ``"shell"`` lines of shell/text blocks, ``"code"`` lines of other code blocks."""
    units, last = [], 0
    for m in FENCE.finditer(text):
        units += _prose_units(text[last : m.start()])
        kind = "shell" if m.group(1) in ("", "bash", "sh", "console", "text") else "code"
        units += [(kind, line) for line in m.group(2).splitlines()]
        last = m.end()
    return units + _prose_units(text[last:])


def _prose_units(text: str) -> list[tuple[str, str]]:
    units = []
    for block in re.split(r"\n\s*\n", text):
        if FOOTNOTE_DEF.match(block.strip()):
            continue  # a footnote's own text is checked where it is referenced
        rows = block.splitlines()
        if rows and all(r.lstrip().startswith("|") for r in rows):
            units += [("prose", r) for r in rows]
            continue
        items = re.split(r"\n(?=\s*(?:[*-]|\d+\.)\s)", block)  # list items apart
        for item in items:
            flat = " ".join(item.split())
            units += [("prose", s) for s in re.split(r"(?<=[.!?])\s+(?=[A-Z*`(\[])", flat)]
    return units


def _is_duration(unit: str, match: re.Match) -> bool:
    after = re.match(r"[\s-]*([\w-]+)", unit[match.end() :])
    if after and after.group(1).lower() in DURATION_NOUNS:
        return True
    before = unit[: match.start()].lower().split()
    return bool(before) and before[-1].strip("(,`-:") in SETTING_WORDS


def unsourced_time_figures(text: str) -> list[str]:
    """The time figures of a Markdown page that name no source (see the module doc), each with
    its sentence; also every named source that does not exist."""
    footnotes = {k: v for k, v in FOOTNOTE_DEF.findall(text)}
    problems = []
    for kind, unit in _units(text):
        bare = re.sub(r"`[^`]*`", lambda m: " " * len(m.group()), unit)  # code is not prose
        if kind == "code":
            bare = unit.split("#", 1)[1] if "#" in unit else ""
        figures = [m for m in TIME_FIGURE.finditer(bare) if not _is_duration(bare, m)]
        if not figures:
            continue
        sources = COMMAND.findall(unit)
        for ref in FOOTNOTE_REF.findall(unit):
            sources += COMMAND.findall(footnotes.get(ref, ""))
        if kind == "shell" and re.match(r"\s*(vrig|python|pip|mkdocs|bash|pytest)\b", unit):
            sources.append(unit.split("#", 1)[0].strip())
        if not sources:
            problems.append(f"{[m.group() for m in figures]} without a source: {unit.strip()}")
        problems += [f"source {s!r} does not exist: {unit.strip()}" for s in sources
                     if not command_exists(s)]  # fmt: skip
    return problems


# ------------------------------------------------------------------ the checker on known cases
@pytest.mark.parametrize(
    "text",
    [
        "The quick benchmark takes 3.7 min.",
        "The main job runs in about 20 s here.",
        "A 10-iteration episode takes 0.6-1.0 s.",
        "The docs build takes about two minutes.",
        "Speed:\n\n| run | time |\n|---|---|\n| quick | 5.3 min |",
        "```bash\n# 48 records: 5.3 min\n```",
        "It took 20 s (`python -m benchmarks.no_such_module` prints it).",
        "It took 20 s (`vrig no-such-command`).",
    ],
)
def test_the_checker_finds_an_unsourced_or_unreal_figure(text):
    assert unsourced_time_figures(text), text


@pytest.mark.parametrize(
    "text",
    [
        "The run takes ~13 s (`vrig reconstruct --rig shock-absorber --method arx` prints `time`).",
        "A 30 s record, 4 s targets, a 0.25 s taper and a 10-minute record are lengths.",
        "The search keeps to a budget (`--budget`, default 60 s).",
        "It took 5 min.[^t]\n\n[^t]: `python -m benchmarks.thesis_tables --quick` prints it.",
        "```bash\npython -m benchmarks run --quick   # prints its wall time (target 5 min)\n```",
        "The filter runs at 12 kN s/m and 9.81 m/s² over 2 seeds (`vrig.spectra.frf_h1`).",
        "## A 5-minute tour",
    ],
)
def test_the_checker_accepts_a_sourced_figure_or_a_length(text):
    assert not unsourced_time_figures(text), unsourced_time_figures(text)


# ------------------------------------------------------------------ the pages
@pytest.mark.parametrize("page", PAGES, ids=[p.relative_to(ROOT).as_posix() for p in PAGES])
def test_every_time_figure_names_the_command_that_prints_it(page):
    problems = unsourced_time_figures(page.read_text(encoding="utf-8"))
    assert not problems, "\n".join(problems)


TUTORIALS = sorted((ROOT / "docs" / "tutorials").glob("*.py"))


@pytest.mark.parametrize("path", TUTORIALS, ids=[p.stem for p in TUTORIALS])
def test_every_time_figure_of_a_tutorials_text_names_its_source(path):
    """The same rule for the prose (Markdown cells) of the executed tutorials; what their code
    cells print is measured on every build."""
    jupytext = pytest.importorskip("jupytext")  # the docs extra
    notebook = jupytext.read(path)
    prose = "\n\n".join(c.source for c in notebook.cells if c.cell_type == "markdown")
    problems = unsourced_time_figures(prose)
    assert not problems, "\n".join(problems)


def test_readme_is_short_and_starts_with_the_two_commands():
    text = README.read_text(encoding="utf-8")
    lines = text.splitlines()
    assert len(lines) <= MAX_LINES, f"README.md has {len(lines)} lines (at most {MAX_LINES})"
    assert lines[0] == "# vrig"
    start = next(i for i, line in enumerate(lines) if line.strip())  # the title
    rest = [line for line in lines[start + 1 :] if line.strip()]
    assert rest[0] == "```bash", "the first thing after the title is the commands block"
    block = rest[1 : rest.index("```")]
    assert [line.split("#")[0].strip() for line in block] == list(COMMANDS)


def test_readme_links_resolve():
    text = README.read_text(encoding="utf-8")
    links = re.findall(r"\]\(([^)#\s]+)(?:#[^)]*)?\)", text)
    local = [link for link in links if "://" not in link]
    assert local, "the README links into the documentation"
    missing = [link for link in local if not (ROOT / link).exists()]
    assert not missing, missing


# ------------------------------------------------------------------ the README's own figures
@pytest.mark.slow
def test_the_readme_quotes_what_the_main_job_and_its_example_print(tmp_path, capsys):
    """The main job's table and best line, and the NarxSearch example's figures, are what the
    code prints today (both are deterministic: the search tries its grid and its widening well
    within its budget)."""
    from vrig.cli import main

    text = README.read_text(encoding="utf-8")
    table = re.search(r"```text\n(iteration .*?)```", text, re.S).group(1)
    quoted = [line for line in table.splitlines() if line.strip()]
    assert main(["reconstruct", "--rig", "shock-absorber", "--method", "arx",
                 "--out", str(tmp_path / "main")]) == 0  # fmt: skip
    printed = capsys.readouterr().out.splitlines()
    missing = [line for line in quoted if line not in printed]
    assert not missing, f"README lines the main job no longer prints: {missing}"

    code = re.search(r"```python\n(.*?)```", text, re.S).group(1)
    import contextlib
    import io

    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        exec(compile(code, "README block", "exec"), {})
    out = out.getvalue()
    claims = re.search(r"What it prints: (.*?)\n\n", text, re.S).group(1)
    n = re.search(r"(\d+) candidates", claims).group(1)
    ok = re.search(r"(\d+)\s+validated", claims).group(1)
    assert f"{n} candidates" in out and f"{ok} validated" in out
    eta0 = re.search(r"within ([\d.]+) % \(η0\)", " ".join(claims.split())).group(1)
    assert f"noise-free output: {eta0} %" in out
