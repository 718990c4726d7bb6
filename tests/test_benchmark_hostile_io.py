"""benchmarks.hostile_io (issue 25): the parts of the hostile script that decide its counts.

The script itself runs for minutes (``python -m benchmarks.hostile_io --quick``); here: the
fuzzed-file try accounts for every file and meets the readers' contract (a finite history or a
FileFormatError), the start-up traceback rule tells Python's own start-up from vrig's code, and
the totals add what the sections count.
"""

from __future__ import annotations

import random

import pytest

from benchmarks import hostile_io


def test_fuzzed_files_read_finite_or_are_refused(tmp_path):
    report = hostile_io.fuzz(30, random.Random(1), tmp_path)
    assert report["files"] == 30 * 5 and len(report["formats"]) == 5
    assert report["read (finite)"] + report["refused (FileFormatError)"] == report["files"]
    assert report["raw tracebacks"] == 0 and report["raw by kind"] == {}
    assert report["refused (FileFormatError)"] > 0  # the mutations do reach the checks


def test_the_absurd_header_values_are_refused(tmp_path):
    """Each absurd value the fuzzer plants is one a reader must refuse, not read."""
    import vrig.io
    from vrig.errors import FileFormatError

    base = hostile_io._fuzz_bases(tmp_path)["int.rsp"]
    path = tmp_path / "absurd.rsp"
    for key in (b"PTS_PER_GROUP", b"DELTA_T"):
        i = base.index(key)
        for value in hostile_io._ABSURD[key]:
            buf = bytearray(base)
            buf[i + 32 : i + 80] = value.ljust(48)
            path.write_bytes(bytes(buf))
            with pytest.raises(FileFormatError):
                vrig.io.read(path)


SITE = """Fatal Python error: init_import_site: Failed to import the site module
Traceback (most recent call last):
  File "<frozen site>", line 186, in addpackage
  File "/venv/lib/python3.11/site-packages/__editable___vrig_0_1_0_finder.py", line 7, in <module>
  File "/venv/lib/python3.11/pathlib.py", line 1, in <module>
KeyboardInterrupt
"""
OURS = """Traceback (most recent call last):
  File "<string>", line 1, in <module>
  File "/src/vrig_console.py", line 40, in <module>
KeyboardInterrupt
"""


LAUNCHER = """Traceback (most recent call last):
  File "/tmp/vrig-hostile-x/vrig", line 3, in <module>
    from vrig_console import main
KeyboardInterrupt
"""
PACKAGE = """Traceback (most recent call last):
  File "/venv/bin/vrig", line 8, in <module>
  File "/venv/lib/python3.11/site-packages/vrig/cli.py", line 12, in main
KeyboardInterrupt
"""


def test_a_start_up_traceback_is_told_from_one_of_vrig():
    assert hostile_io._startup(SITE)
    assert hostile_io._startup(LAUNCHER)  # the import system, before vrig_console's first line
    assert not hostile_io._startup(OURS)
    assert not hostile_io._startup(PACKAGE)
    assert not hostile_io._startup("vrig reconstruct: interrupted\n")
