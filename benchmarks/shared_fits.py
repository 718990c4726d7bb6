"""A reconstruction method whose fit is shared with other runs on the same identification records.

A thesis table runs each of its rows twice, on the text's kind of desired response and on a
pseudo-field record beside it (:mod:`benchmarks.thesis_tables`). The default identification does
not depend on the desired response (the same identification drive, seed, level and length on the
same rig), so both runs fit the same inverse on the same records: the second fit is a copy of the
first. :class:`SharedFit` makes that explicit instead of paying for it twice: it wraps a method,
and its ``identify`` looks the identification records up (by their bytes, sampling rate, names
and units) under a *tag* naming the method's configuration. On a hit it takes a deep copy of the
method fitted the first time (or raises the error that fit raised); on a miss it fits and keeps a
copy. Records that differ in any sample (an identification matched to the target, another rig,
variant or severity, a drive halved after a trip) miss, so nothing is shared that a fit would not
reproduce: the fits are deterministic functions of their records.
"""

from __future__ import annotations

import copy
import hashlib

import numpy as np

__all__ = ["SharedFit", "records_digest"]


def records_digest(*records) -> str:
    """SHA-256 over the samples, sampling rate, names and units of ``records`` (TimeHistory).

    Parameters
    ----------
    *records : TimeHistory
        The records (e.g. the processed identification drive and response).

    Returns
    -------
    str
        Hex digest: equal only for records equal in every sample and label.
    """
    h = hashlib.sha256()
    for th in records:
        data = np.ascontiguousarray(th.data, dtype=float)
        h.update(repr((data.shape, float(th.fs), list(th.names), list(th.units))).encode())
        h.update(data.tobytes())
    return h.hexdigest()


class SharedFit:
    """A method (``identify``/``drive``) whose fits are shared through ``store``.

    Parameters
    ----------
    method : Method
        A fresh, unfitted method object (``identify(iddrv, idres)``, ``drive(response)``).
    tag : hashable
        Names the method's configuration: two ``SharedFit`` share a fit only when their tags
        are equal *and* their identification records are (:func:`records_digest`).
    store : dict
        Shared between the wrappers whose fits may be reused: ``{(tag, digest): fitted method
        or the exception its fit raised}``.

    Every other attribute (``describe``, ``model_size``, ``fitted_lead``, ...) is the wrapped
    method's. ``shared`` counts the fits taken from ``store`` instead of computed.
    """

    def __init__(self, method, tag, store: dict):
        self.method = method
        self.tag = tag
        self.store = store
        self.shared = 0

    def identify(self, iddrv, idres) -> None:
        """Fit on (``iddrv``, ``idres``), or take the fit made on the same records under the
        same tag (a deep copy; a fit that raised raises the same error again)."""
        key = (self.tag, records_digest(iddrv, idres))
        hit = self.store.get(key)
        if hit is None:
            try:
                self.method.identify(iddrv, idres)
            except Exception as exc:
                self.store[key] = exc
                raise
            self.store[key] = copy.deepcopy(self.method)
            return
        self.shared += 1
        if isinstance(hit, Exception):
            raise hit
        self.method = copy.deepcopy(hit)

    def drive(self, response):
        """The wrapped method's drive for ``response``."""
        return self.method.drive(response)

    def describe(self) -> str:
        """The wrapped method's description."""
        return self.method.describe()

    def __getattr__(self, name):
        if name.startswith("__") or name == "method":  # copy/pickle probe before __init__
            raise AttributeError(name)
        return getattr(self.method, name)
