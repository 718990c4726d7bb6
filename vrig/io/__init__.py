"""File I/O for time histories: MTS RPC III, CSV, MATLAB ``.mat`` and vrig ``.npz``.

:func:`read` and :func:`write` dispatch on the file suffix:

* ``.rsp``, ``.drv``, ``.tim``: MTS RPC III time history (:func:`read_rpc3`,
  :func:`write_rpc3`);
* ``.csv``: a ``time,<name> [<unit>],...`` table (:func:`read_csv`, :func:`write_csv`);
* ``.mat``: MATLAB variables ``data``, ``fs``, ``names``, ``units`` (:func:`read_mat`,
  :func:`write_mat`);
* ``.npz``: :meth:`TimeHistory.save` / :meth:`TimeHistory.load`.

Layout of the package: one module per format and the dispatch, all names re-exported here
(``vrig.io.read_rpc3`` and ``from vrig.io import read_rpc3`` are the public paths):

* :mod:`vrig.io.rpc3`: RPC III reading (header, then payload) and writing (header, then
  payload); its module docstring documents the file layout and how it was confirmed;
* :mod:`vrig.io.delimited`: CSV;
* :mod:`vrig.io.mat`: MATLAB, with :mod:`vrig.io._mat5`, the structural check that keeps a
  corrupt file from crashing SciPy's reader;
* :mod:`vrig.io.dispatch`: :func:`read` and :func:`write` by suffix.

Safety
------
Writers replace their file atomically (:func:`vrig.files.atomic_write`): a kill or Ctrl-C
during a write leaves the previous file, never a partial one. Readers accept only regular files
of at most :data:`vrig.files.MAX_FILE_BYTES` (no FIFO, device or endless file) and raise
:class:`~vrig.FileFormatError` (a ValueError naming the file and the format) for anything that
is not a valid file of the format: truncated, corrupt, foreign, CSV not in UTF-8 (a UTF-8
byte-order mark is fine), MATLAB v7.3, or holding values a :class:`TimeHistory` refuses.
"""

from .delimited import read_csv, write_csv
from .dispatch import read, write
from .mat import read_mat, write_mat
from .rpc3 import (
    RPC3_SUFFIXES,
    RPC3_TRANSLITERATION,
    read_rpc3,
    read_rpc3_header,
    rpc3_labels,
    rpc3_text,
    write_rpc3,
)

__all__ = [
    "RPC3_SUFFIXES",
    "RPC3_TRANSLITERATION",
    "read",
    "read_csv",
    "read_mat",
    "read_rpc3",
    "read_rpc3_header",
    "rpc3_labels",
    "rpc3_text",
    "write",
    "write_csv",
    "write_mat",
    "write_rpc3",
]
