"""A reconstruction on disk: the QanTiM test folder (reference text App. G, DESIGN §4).

:class:`TestFolder` writes every record of a :class:`~vrig.reconstruction.ReconstructionResult`
under its QanTiM name, so a run can be inspected with any RPC III tool and later resumed:

=============  ========================================================================
IDDRV, IDRES   identification drive and (raw) response
FIELD01        the measured (or pseudo-) field response, when given
DESRES01       the desired response (processed: GPREPRO over the simulation bandwidth)
ITxxDRV        the drive of iteration xx (IT00DRV = inverse model of DESRES)
RITxxRES       the raw rig response to ITxxDRV
ITxxRES        the processed response (compared with DESRES01)
FINDRV01       the best iteration's drive
FINRES01       the best iteration's processed response
REFUSEDxx      a drive refused before it was sent (xx the iteration, ``ID`` identification)
TRIPPEDxx      a drive that tripped the rig (interlock or unstable simulation)
=============  ========================================================================

A reconstruction that failed before any iteration was played (the result of a
:class:`~vrig.ReconstructionError`) is saved too: the identification records and model that were
made, the refused or tripped drive, and the summary with ``iterations_run`` -1 and
``best_iteration`` null.

plus the inverse model(s) (``model.npz``; ``model_low.npz``/``model_high.npz`` for split
spectra; see :meth:`identification.Narx.load`), ``summary.json`` (method, bandwidth,
per-iteration errors, best iteration, stop reason and ``stop_kind``
(:data:`~vrig.reconstruction.result.STOP_KINDS`), rig, files) and, with ``plots=True``, the
plots of :func:`vrig.plots.save_reconstruction_plots`, drawn into the new folder before it is
swapped in (records and plots are replaced together: never new records beside old plots).

Channel labels a format cannot hold as they are (a unit ``µε`` in an RPC III header, which holds
latin-1 text: written ``ue`` by :func:`vrig.io.rpc3.rpc3_text`; a unit with ``[`` or a line
break in a CSV header: written with ``(``/``)`` and spaces) are written in that form, and the
originals are kept in ``summary.json`` (``labels``: record -> original ``names`` and ``units``);
:meth:`TestFolder.read` gives the originals back. Nothing about a label can make a save fail.

Records are RPC III by default (drives ``.drv`` with ``TIME_TYPE = DRIVE``, responses ``.rsp``,
``FLOATING_POINT``: float32, so they read back to float32 precision), or ``.csv``, ``.mat`` or
``.npz`` (exact). An existing non-empty folder is never overwritten unless ``overwrite=True``,
and then it is replaced in one swap: the new folder is written beside it (``.NAME.tmp-XXXXXXXX``)
and renamed into place only when complete, so an interrupted save (exception, Ctrl-C, kill -9)
leaves the previous folder whole (see :func:`vrig.files.staged_directory`; a kill between the two
renames of the swap leaves it as ``.NAME.old-XXXXXXXX``, which the next :class:`TestFolder`
access renames back). Hidden ``.NAME.tmp-XXXXXXXX`` folders and files are debris of a killed
save and never read as data; the next save of the folder deletes them. A save holds the folder's
lock (:func:`vrig.files.folder_lock`, ``.NAME.vrig-lock`` beside it): a second writer waits for
it (``lock_timeout`` seconds) or fails before writing anything, and no reader puts an old folder
back while a save is under way.

>>> folder = TestFolder("results/shock-absorber-arx")          # doctest: +SKIP
>>> folder.save(result, field=field, rig=rig)                  # doctest: +SKIP
>>> folder.load_iteration(3).response                          # doctest: +SKIP
"""

from __future__ import annotations

import datetime
import json
import os
import re
import time
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from . import io
from .errors import FileFormatError
from .files import (
    LOCK_WAIT_S,
    atomic_write,
    folder_lock,
    is_temporary,
    read_bytes,
    recover_directory,
    staged_directory,
)
from .reconstruction.protocol import InverseModelMethod, Method, SavableMethod
from .timehistory import TimeHistory

__all__ = ["FORMATS", "IterationRecord", "TestFolder"]

FORMATS = ("rsp", "csv", "mat", "npz")
"""Record formats of :meth:`TestFolder.save` (``rsp``: RPC III ``.drv``/``.rsp``)."""

SUMMARY = "summary.json"
_FORMAT_ID = "vrig-testfolder"
_VERSION = 1
# QanTiM record names; the order of the patterns is the order of the process
_NAME_PATTERNS = (
    r"DESDRV",
    r"IDDRV",
    r"IDRES",
    r"FIELD\d\d",
    r"FIELDDRV\d\d",  # the road inputs of a field twin's record FIELDnn (vrig.service)
    r"DESRES\d\d",
    r"R?IT\d\d(?:DRV|RES)",
    r"FINDRV\d\d",
    r"FINRES\d\d",
    r"(?:REFUSED|TRIPPED)(?:\d\d|ID)",
)
_RECORD = re.compile(
    r"^(" + "|".join(_NAME_PATTERNS) + r")\.(drv|rsp|csv|mat|npz)$", flags=re.IGNORECASE
)
_MODEL = re.compile(r"^model(_low|_high)?\.npz$")
_PLOTS = frozenset(
    (
        "overlay.png",
        "overlay_zoom.png",
        "psd.png",
        "error_vs_iteration.png",
        "drive_vs_limits.png",
        "refused_drive_vs_limits.png",
        "tripped_drive_vs_limits.png",
    )
)  # what vrig.plots.save_reconstruction_plots may write: they describe the records


def _is_drive(name: str) -> bool:
    n = name.upper()
    return "DRV" in n or n.startswith(("REFUSED", "TRIPPED"))


def _order_key(name: str) -> tuple:
    """Process order: IDDRV, IDRES, FIELD, DESRES, IT00DRV, RIT00RES, IT00RES, IT01..., FIN."""
    n = name.upper()
    m = re.fullmatch(r"(R?)IT(\d\d)(DRV|RES)", n)
    if m:
        within = 0 if m.group(3) == "DRV" else (1 if m.group(1) else 2)
        return (5, int(m.group(2)), within, n)
    for rank, prefix in enumerate(("DESDRV", "IDDRV", "IDRES", "FIELD", "DESRES"), start=0):
        if n.startswith(prefix):
            return (rank, 0, 0, n)
    if n.startswith(("REFUSED", "TRIPPED")):
        return (7, 0, 0, n)
    return (6, 0, 0 if n.startswith("FINDRV") else 1, n)


def _plain(value):
    """JSON-safe copy (numpy scalars/arrays to lists, non-finite floats to None)."""
    if isinstance(value, Mapping):
        return {str(k): _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    if isinstance(value, np.ndarray):
        return _plain(value.tolist())
    if isinstance(value, (np.integer,)):
        return int(value)
    if isinstance(value, (float, np.floating)):
        v = float(value)
        return v if np.isfinite(v) else None
    if isinstance(value, (str, int, bool)) or value is None:
        return value
    return str(value)


def _inverse_models(method) -> dict:
    """``{file stem: model}`` of a method (:class:`~vrig.reconstruction.SavableMethod`: ``model``,
    or ``model_low``/``model_high`` for split spectra); ``{}`` for any other method."""
    return method.fitted_models() if isinstance(method, SavableMethod) else {}


def _method_summary(method) -> dict:
    """Name, class, description, options and lead of a method (band methods nested)."""
    out = {"name": getattr(method, "name", type(method).__name__), "class": type(method).__name__}
    try:
        out["description"] = method.describe()
    except Exception:  # a user method without describe(), or not identified
        out["description"] = type(method).__name__
    if isinstance(method, SavableMethod):
        for key, value in method.options().items():
            out[key] = _method_summary(value) if isinstance(value, Method) else _plain(value)
    report = getattr(method, "search_report", None)
    if callable(report) and report() is not None:
        out["search_report"] = report().splitlines()  # the structure search, one row per line
    if isinstance(method, InverseModelMethod):
        lead = method.fitted_lead()
        if isinstance(lead, int):
            out["lead"] = lead
    return out


def _not_ours(name: str) -> bool:
    """Files of a folder that :meth:`TestFolder.save` keeps when it replaces the folder: not a
    record, model, summary, plot of the records or temporary (a lock file of a folder inside it
    is kept: hard-linked, the same file, so its lock holds on)."""
    if name.endswith(".vrig-lock"):
        return True
    ours = _RECORD.match(name) or _MODEL.match(name) or name in _PLOTS or name == SUMMARY
    return not (ours or is_temporary(name))


def _records(result, field, extra: dict) -> dict[str, TimeHistory]:
    """The QanTiM records of a reconstruction, ``{name: TimeHistory}``."""
    todo: dict[str, TimeHistory] = {
        name: th
        for name, th in (("IDDRV", result.id_drive), ("IDRES", result.id_response))
        if th is not None
    }
    if field is not None:
        todo["FIELD01"] = field
    todo["DESRES01"] = result.desired
    for it, (drv, raw, res) in enumerate(
        zip(result.drives, result.raw_responses, result.responses, strict=True)
    ):
        todo[f"IT{it:02d}DRV"] = drv
        todo[f"RIT{it:02d}RES"] = raw
        todo[f"IT{it:02d}RES"] = res
    if result.drives:
        todo["FINDRV01"] = result.final_drive
        todo["FINRES01"] = result.final_response
    if getattr(result, "rejected_drive", None) is not None:
        todo[result.rejected_name] = result.rejected_drive
    for name, th in extra.items():
        todo[name.upper()] = th
    return todo


def _storable(th: TimeHistory, fmt: str) -> tuple[TimeHistory, tuple[list, list] | None]:
    """``(record as written, (names, units) the file reads back with)``; ``None`` for the
    formats that keep any label. RPC III: the labels :func:`~vrig.io.rpc3.rpc3_text` stores,
    cut to the header's 95 bytes; CSV: line breaks as spaces, ``[``/``]`` of units as
    ``(``/``)``."""
    if fmt == "rsp":
        names = [io.rpc3.rpc3_text(n)[:95] for n in th.names]
        units = [io.rpc3.rpc3_text(u)[:95] for u in th.units]
    elif fmt == "csv":
        names = [_utf8(" ".join(n.splitlines())) for n in th.names]
        units = [_utf8(" ".join(u.splitlines())).replace("[", "(").replace("]", ")") for u in th.units]
    else:
        return th, None
    names = _distinct(names)
    out = th
    if names != list(th.names) or units != list(th.units):
        out = TimeHistory(th.data, th.fs, names, units)
    return out, (io.rpc3.rpc3_labels(out) if fmt == "rsp" else (names, units))


def _utf8(text: str) -> str:
    """``text`` as UTF-8 can hold it (a lone surrogate, e.g. from an ``.npz``, as ``\\udxxx``)."""
    return text.encode("utf-8", "backslashreplace").decode("utf-8")


def _summary_text(summary: dict) -> str:
    """``summary.json``'s text: UTF-8 as it reads, or all escaped when a label holds a lone
    surrogate UTF-8 cannot encode (``json`` reads either back to the same strings)."""
    text = json.dumps(summary, indent=2, ensure_ascii=False) + "\n"
    try:
        text.encode("utf-8")
    except UnicodeEncodeError:
        text = json.dumps(summary, indent=2) + "\n"
    return text


def _distinct(names: list[str]) -> list[str]:
    """Names that a change of form made equal, numbered apart (``_2``, ``_2_1``...) within 95
    characters."""
    out: list[str] = []
    for k, name in enumerate(names):
        candidate, j = name, 0
        while candidate in out or (candidate != name and candidate in names[k + 1 :]):
            tag = f"_{k + 1}" + (f"_{j}" if j else "")
            candidate, j = name[: 95 - len(tag)] + tag, j + 1
        out.append(candidate)
    return out


def _write(folder: Path, name: str, th: TimeHistory, fmt: str) -> tuple[Path, dict | None]:
    """Write one record; ``(file, original labels)`` where the file holds other labels than
    ``th`` (``{"names": [...], "units": [...]}``), else ``(file, None)``."""
    th_out, back = _storable(th, fmt)
    path = _write_file(folder, name, th_out, fmt)
    if back is None or (list(back[0]) == list(th.names) and list(back[1]) == list(th.units)):
        return path, None
    return path, {"names": list(th.names), "units": list(th.units)}


def _write_file(folder: Path, name: str, th: TimeHistory, fmt: str) -> Path:
    if fmt == "rsp":
        drive = _is_drive(name)
        return io.write_rpc3(
            folder / f"{name}.{'drv' if drive else 'rsp'}",
            th,
            data_type="FLOATING_POINT",
            time_type="DRIVE" if drive else "RESPONSE",
            extra_header={"OPERATION": f"vrig {name}"},
        )
    return io.write(folder / f"{name}.{fmt}", th)


def _save_models(folder: Path, method) -> tuple[dict, str]:
    """Save the method's inverse model(s) into ``folder``: ``({stem: info}, note)``."""
    inverses = _inverse_models(method)
    if not inverses:
        return {}, (
            f"the method {type(method).__name__} has no time-domain inverse model "
            "to save (frequency-domain or user method): not saved"
        )
    models = {}
    for stem, inverse in inverses.items():
        path = inverse.model.save(folder / f"{stem}.npz")
        models[stem] = {"file": path.name, "lead": int(getattr(inverse, "lead_", 0))}
    return models, (
        "inverse model(s) from responses to drives: identification.Arx/Narx.load(file); "
        "the drive at t is modelled from responses up to t + lead samples, at the "
        "model sample rate"
    )


def _summary(result, rig, fmt: str, files: dict, models: dict, model_note: str, settings) -> dict:
    """The contents of ``summary.json`` (see :meth:`TestFolder.summary`)."""
    decimation = int(result.decimation)
    decimation_note = "recorded by reconstruct"
    errors = np.asarray(result.errors)
    n_run = errors.shape[0]
    best = int(result.best_iteration) if n_run else None
    candidates = (result.id_drive, getattr(result, "rejected_drive", None), *result.drives)
    drives = next((th for th in candidates if th is not None), None)
    return {
        "format": _FORMAT_ID,
        "version": _VERSION,
        "created": datetime.datetime.now().isoformat(timespec="seconds"),
        "rig": None if rig is None else (rig if isinstance(rig, str) else rig.name),
        "method": _method_summary(result.method),
        "bandwidth_hz": _plain(result.bandwidth),
        "fs": result.desired.fs,
        "n_samples": result.desired.n_samples,
        "duration_s": result.desired.duration,
        "model_decimation": int(decimation),
        "model_fs": result.desired.fs / int(decimation),
        "model_decimation_note": decimation_note,
        "gain": _plain(result.gain),
        "strategy": result.strategy,
        "seed": int(result.seed),
        "drives": None
        if drives is None
        else {"names": list(drives.names), "units": list(drives.units)},
        "responses": {"names": list(result.desired.names), "units": list(result.desired.units)},
        "iterations_run": n_run - 1,
        "best_iteration": best,
        "stopped": result.stopped,
        "stop_reason": result.stopped or f"completed all {n_run - 1} iterations",
        "stop_kind": getattr(result, "stop_kind", "") or None,
        "rejected": getattr(result, "rejected_name", "") or None,
        "best": None
        if best is None
        else {
            "eta0_percent": _plain(errors[best]),
            "rms_error_percent": _plain(np.asarray(result.rms_errors)[best]),
            "damage_ratio": _plain(np.asarray(result.damage_ratio)[best]),
        },
        "errors": {
            "eta0_percent": _plain(errors),
            "rms_error_percent": _plain(result.rms_errors),
            "damage_ratio": _plain(result.damage_ratio),
        },
        "table": result.table().splitlines(),
        "record_format": fmt,
        "files": files,
        "models": models,
        "model_note": model_note,
        "settings": _plain(dict(settings or {})),
        "resolved": _plain(dict(getattr(result, "resolved", None) or {})),
        "identification": _plain(getattr(result, "identification", None)),
        "updates": _plain(list(getattr(result, "updates", None) or [])),
    }


def _extra_entries(summary: dict, extra: Mapping | None) -> dict:
    """``extra`` as summary entries: keys the summary has already are refused."""
    extra = dict(extra or {})
    clash = sorted(set(extra) & set(summary))
    if clash:
        raise ValueError(f"summary_extra may not replace the summary's own entries {clash}")
    return _plain(extra)


def _identity(path: Path) -> tuple[int, int] | None:
    """The folder's ``(device, inode)``: every save swaps in a new folder (None when missing)."""
    try:
        st = os.stat(path)
    except OSError:
        return None
    return st.st_dev, st.st_ino


def _mid_swap(path: Path) -> bool:
    """Whether a save may be between the two renames of its swap (the folder missing, an old
    one set aside)."""
    path = Path(os.path.realpath(path))
    if os.path.lexists(path):
        return False
    prefix = f".{path.name[:200]}.old-"
    try:
        return any(e.name.startswith(prefix) for e in os.scandir(path.parent or "."))
    except OSError:
        return False


def _checked_records(fmt: str, records: Mapping | None, field) -> dict:
    """The further records of :meth:`TestFolder.save`, checked with its other arguments."""
    if fmt not in FORMATS:
        raise ValueError(f"fmt must be one of {FORMATS}, got {fmt!r}")
    extra = dict(records or {})
    for name, th in extra.items():
        if not _RECORD.match(f"{name}.npz"):
            raise ValueError(
                f"record name {name!r} is not a QanTiM name (IDDRV, FIELDnn, DESDRV, ...)"
            )
        if not isinstance(th, TimeHistory):
            raise TypeError(f"record {name!r} must be a TimeHistory")
    if field is not None and not isinstance(field, TimeHistory):
        raise TypeError("field must be a TimeHistory")
    return extra


def _draw(result, rig, folder: Path) -> list[str]:
    """Draw the plots of ``result`` into ``folder``; their file names."""
    from .plots import save_reconstruction_plots
    from .progress import status

    status("drawing the plots (overlay, zoom, PSD, error per iteration, drive vs limits) ...")
    rig = None if rig is None or isinstance(rig, str) else rig
    return [p.name for p in save_reconstruction_plots(result, folder, rig=rig)]


@dataclass(frozen=True)
class IterationRecord:
    """The records and scores of one iteration read back from a test folder.

    Attributes
    ----------
    index : int
        Iteration number xx.
    drive, raw_response, response : TimeHistory
        ITxxDRV, RITxxRES and ITxxRES.
    eta0, rms_error, damage_ratio : ndarray (n_outputs,)
        η0 [%], RMS error [%] and pseudo-damage ratio of ITxxRES against DESRES (from the
        summary).
    """

    index: int
    drive: TimeHistory
    raw_response: TimeHistory
    response: TimeHistory
    eta0: np.ndarray
    rms_error: np.ndarray
    damage_ratio: np.ndarray


class TestFolder:
    """A QanTiM test folder (see the module docstring).

    Parameters
    ----------
    path : str or Path
        The folder; :meth:`save` creates it.
    """

    __test__ = False  # not a pytest test class despite its name

    def __init__(self, path):
        self.path = Path(path)

    def __repr__(self) -> str:
        return f"TestFolder({str(self.path)!r})"

    # ------------------------------------------------------------------ writing
    def save(
        self,
        result,
        *,
        field: TimeHistory | None = None,
        fmt: str = "rsp",
        rig=None,
        records: Mapping[str, TimeHistory] | None = None,
        settings: Mapping | None = None,
        overwrite: bool = False,
        summary_extra: Mapping | None = None,
        plots: bool = False,
        lock_timeout: float = LOCK_WAIT_S,
    ) -> list[Path]:
        """Write a reconstruction as QanTiM files and ``summary.json`` (and its plots).

        The whole folder is written beside the target (``.NAME.tmp-XXXXXXXX``) and swapped in
        at the end (:func:`vrig.files.staged_directory`): an exception, Ctrl-C, kill or full
        disk during the save leaves an existing folder as it was, byte for byte, and a new one
        unmade. The save holds the folder's lock (:func:`vrig.files.folder_lock`).

        Parameters
        ----------
        result : ReconstructionResult
            The reconstruction to write (or the result of a :class:`~vrig.ReconstructionError`
            or :class:`~vrig.ReconstructionInterrupted`).
        field : TimeHistory, optional
            The field (or pseudo-field) response the desired response was made from: FIELD01.
        fmt : {"rsp", "csv", "mat", "npz"}
            Record format; ``"rsp"`` writes RPC III drives as ``.drv`` and responses as ``.rsp``
            (``FLOATING_POINT``).
        rig : rig or str, optional
            The rig (or its name), recorded in the summary; a rig also gives the plots their
            drive limits.
        records : mapping of str to TimeHistory, optional
            Further records under QanTiM names, e.g. ``{"DESDRV": drive}`` (the drive that made a
            pseudo-field response, §6.5).
        settings : mapping, optional
            Run settings to keep in the summary (gain, seed, command line...).
        overwrite : bool
            Allow replacing a non-empty folder: the QanTiM records, models, summary and plots of
            a previous save are replaced by the new ones (a previous plot the new save does not
            draw is removed with the records it showed); other files (notes...) are kept.
        summary_extra : mapping, optional
            Further top-level entries of ``summary.json`` (JSON-able), e.g. ``{"target_check":
            ...}`` (:func:`vrig.desired.reachability.check_target`); a key the summary has already is refused.
        plots : bool
            Also draw the plots of :func:`vrig.plots.save_reconstruction_plots` into the new
            folder (before the swap; listed in the summary's ``plots``).
        lock_timeout : float
            Seconds to wait while another writer holds the folder's lock (``0``: fail at once).

        Returns
        -------
        list of Path
            The files written, in process order (records, models, plots), ``summary.json`` last.

        Raises
        ------
        FileExistsError
            If the folder exists and is not empty and ``overwrite`` is false, or the path is a
            file.
        FolderLockedError
            If another writer still holds the folder's lock after ``lock_timeout`` seconds
            (nothing is written).
        ValueError
            For an unknown ``fmt`` or a record name that is not a QanTiM name.
        """
        extra = _checked_records(fmt, records, field)
        with folder_lock(self.path, timeout=lock_timeout):
            self._check_target(overwrite)
            with staged_directory(self.path, keep=_not_ours) as staging:
                files, labels = self._write_records(staging, _records(result, field, extra), fmt)
                models, model_note = _save_models(staging, result.method)
                drawn = _draw(result, rig, staging) if plots else []
                summary = _summary(result, rig, fmt, files, models, model_note, settings)
                summary["labels"] = labels
                summary["plots"] = drawn
                summary.update(_extra_entries(summary, summary_extra))
                with atomic_write(staging / SUMMARY, "w", encoding="utf-8") as f:
                    f.write(_summary_text(summary))
        names = [*files.values(), *(m["file"] for m in models.values()), *drawn, SUMMARY]
        return [self.path / n for n in names]

    def _check_target(self, overwrite: bool) -> None:
        p = self.path
        recover_directory(p)
        if p.exists() and not p.is_dir():
            raise FileExistsError(f"{p} exists and is not a folder")
        if p.is_dir() and any(p.iterdir()) and not overwrite:
            raise FileExistsError(
                f"test folder {p} is not empty; pass overwrite=True to replace its records, "
                "or choose another folder"
            )

    def _write_records(self, folder: Path, todo: dict, fmt: str) -> tuple[dict, dict]:
        """Write the records into ``folder`` in process order: ``({name: file name},
        {name: original labels}`` of the records whose file holds other labels)."""
        files, labels = {}, {}
        for name in sorted(todo, key=_order_key):
            path, original = _write(folder, name, todo[name], fmt)
            files[name] = path.name
            if original is not None:
                labels[name] = original
        return files, labels

    # ------------------------------------------------------------------ reading
    def files(self) -> dict[str, Path]:
        """QanTiM records in the folder, ``{name: path}`` in process order (IDDRV, IDRES,
        FIELD01, DESRES01, IT00DRV, RIT00RES, IT00RES, ..., FINDRV01, FINRES01)."""
        recover_directory(self.path)
        if not self.path.is_dir():
            raise FileNotFoundError(f"no test folder at {self.path}")
        found = {}
        for f in self.path.iterdir():
            m = _RECORD.match(f.name)
            if m and f.is_file():
                name = m.group(1).upper()
                if name in found:
                    raise ValueError(
                        f"{self.path}: record {name} is stored twice ({found[name].name}, {f.name})"
                    )
                found[name] = f
        return {k: found[k] for k in sorted(found, key=_order_key)}

    def read(self, name: str) -> TimeHistory:
        """One record by QanTiM name (``"IDDRV"``, ``"IT03RES"``, ``"FINDRV01"``...), with its
        original channel names and units (``summary.json``'s ``labels``, for the labels its
        file could not hold as they were: a unit ``µε`` in an RPC III header).

        Parameters
        ----------
        name : str
            A QanTiM record name.
        """
        return self._one_version(lambda: self._read(name))

    def _read(self, name: str) -> TimeHistory:
        files = self.files()
        key = name.upper()
        if key not in files:
            raise KeyError(f"{self.path} holds no record {name!r}; records: {list(files)}")
        th = io.read(files[key])
        original = self._labels().get(key)
        if (
            isinstance(original, dict)
            and len(original.get("names") or ()) == th.n_channels
            and len(original.get("units") or ()) == th.n_channels
        ):
            th = TimeHistory(th.data, th.fs, original["names"], original["units"])
        return th

    def _labels(self) -> dict:
        """``summary.json``'s ``labels`` (``{}`` without a readable summary: a folder another
        tool wrote)."""
        try:
            labels = self.summary().get("labels")
        except (FileNotFoundError, FileFormatError):
            return {}
        return labels if isinstance(labels, dict) else {}

    def _one_version(self, read):
        """``read()`` from one version of the folder: when a save swapped the folder while it
        read (the folder's identity changed, or a file vanished with the old folder), read again
        (at most 50 times)."""
        for _ in range(50):
            before = _identity(self.path)
            try:
                out = read()
            except (OSError, KeyError, IndexError, ValueError):
                if _identity(self.path) == before and not _mid_swap(self.path):
                    raise
                time.sleep(0.005)
                continue
            if _identity(self.path) == before:
                return out
        return read()  # the folder changes all the time: the last try's result or error

    def summary(self) -> dict:
        """The contents of ``summary.json``.

        Raises
        ------
        FileNotFoundError
            If the folder has no summary.
        FileFormatError
            If the summary is not a vrig test-folder summary (not JSON, truncated, foreign).
        """
        recover_directory(self.path)
        path = self.path / SUMMARY
        if not path.exists():
            raise FileNotFoundError(f"{self.path} has no {SUMMARY} (not a vrig test folder?)")
        fmt = "vrig test-folder summary"
        try:
            data = json.loads(read_bytes(path, fmt).decode("utf-8"))
        except ValueError as exc:  # JSONDecodeError and UnicodeDecodeError are ValueErrors
            if isinstance(exc, FileFormatError):
                raise
            raise FileFormatError(path, fmt, f"not UTF-8 JSON ({exc})") from None
        if not isinstance(data, dict) or data.get("format") != _FORMAT_ID:
            raise FileFormatError(path, fmt, f'no "format": "{_FORMAT_ID}" entry')
        return data

    @property
    def iterations(self) -> list[int]:
        """Iteration numbers with a stored drive (ITxxDRV)."""
        return sorted(
            int(m.group(1)) for k in self.files() if (m := re.fullmatch(r"IT(\d\d)DRV", k))
        )

    def load_iteration(self, xx: int) -> IterationRecord:
        """ITxxDRV, RITxxRES, ITxxRES and the iteration's scores.

        Parameters
        ----------
        xx : int
            Iteration number, 0..99 (0: IT00).
        """
        if not isinstance(xx, (int, np.integer)) or not 0 <= xx <= 99:
            raise ValueError(f"iteration must be an integer 0..99, got {xx!r}")
        return self._one_version(lambda: self._load_iteration(xx))

    def _load_iteration(self, xx: int) -> IterationRecord:
        its = self.iterations
        if xx not in its:
            raise KeyError(f"{self.path} holds no iteration {xx:02d}; iterations: {its}")
        summary = self.summary()
        errs = summary["errors"]

        def row(key):
            return np.array([np.nan if v is None else v for v in errs[key][xx]], dtype=float)

        return IterationRecord(
            index=int(xx),
            drive=self._read(f"IT{xx:02d}DRV"),
            raw_response=self._read(f"RIT{xx:02d}RES"),
            response=self._read(f"IT{xx:02d}RES"),
            eta0=row("eta0_percent"),
            rms_error=row("rms_error_percent"),
            damage_ratio=row("damage_ratio"),
        )

    def load_models(self) -> dict:
        """The saved inverse model(s), ``{stem: (model, lead)}`` (empty when none was saved)."""
        return self._one_version(self._load_models)

    def _load_models(self) -> dict:
        from identification import Narx

        out = {}
        for stem, info in self.summary().get("models", {}).items():
            out[stem] = (Narx.load(self.path / info["file"]), int(info["lead"]))
        return out
