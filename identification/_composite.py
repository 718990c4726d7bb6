"""Files of composite models (internal): several Narx/Arx parts in one ``.npz`` model file.

A composite model (:class:`~identification.SplitSpectraModel`,
:class:`~identification.ErrorSignalModel`) is saved as one model file of the same format as a
:class:`~identification.Narx` (format ``"vrig-identification-model"``, version 2, written
atomically, read with the guarded reader): its ``meta`` names the composite class, its
parameters and its parts, and each part's arrays are stored under ``"<part>.<array>"`` exactly
as that part's own model file would hold them (checked the same way when loaded).
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from ._files import atomic_write, read_npz
from .errors import ModelFileError
from .models import _FORMAT_VERSION, MAX_MODEL_FILE_BYTES, model_from_arrays, npz_path

__all__ = ["load_composite", "save_composite"]

_FORMAT = "vrig-identification-model"


def save_composite(path, class_name: str, params: dict, parts: dict) -> Path:
    """Write ``parts`` ({name: fitted Narx/Arx}) and ``params`` (JSON-able) to one model file;
    returns the path (``.npz`` added when missing)."""
    path = npz_path(path)
    meta = {
        "format": _FORMAT,
        "version": _FORMAT_VERSION,
        "class": class_name,
        "params": params,
        "parts": list(parts),
    }
    arrays = {"meta": np.array(json.dumps(meta))}
    for name, model in parts.items():
        for key, value in model._file_arrays().items():
            arrays[f"{name}.{key}"] = value
    with atomic_write(path) as f:  # a kill leaves the old file or the new one
        np.savez(f, **arrays)
    return path


def load_composite(path, class_name: str, part_names: tuple) -> tuple[dict, dict]:
    """``(params, {part: model})`` of a file written by :func:`save_composite`.

    Raises
    ------
    FileNotFoundError
        If there is no such file.
    ModelFileError
        If the file is not a ``class_name`` model file (truncated, corrupt, foreign, another
        model class, a newer format version, a part missing or not a valid model).
    """
    path = Path(path)
    if not path.exists():
        raise FileNotFoundError(f"no model file at {path}")
    arrays = read_npz(
        path, limit=MAX_MODEL_FILE_BYTES, error=lambda detail: ModelFileError(path, detail)
    )
    raw = arrays.get("meta")
    if raw is None or raw.dtype.kind != "U" or raw.shape != ():
        raise ModelFileError(path, "not a vrig identification model (no meta)")
    try:
        meta = json.loads(str(raw))
    except ValueError as exc:
        raise ModelFileError(path, f"meta is not JSON ({exc})") from None
    if not isinstance(meta, dict) or meta.get("format") != _FORMAT:
        raise ModelFileError(path, "not a vrig identification model")
    version = meta.get("version")
    if not isinstance(version, int) or version > _FORMAT_VERSION:
        raise ModelFileError(
            path,
            f"model format version {version!r}, newer than this package reads "
            f"({_FORMAT_VERSION}); update the identification package",
        )
    if meta.get("class") != class_name:
        raise ModelFileError(
            path,
            f"it holds a {meta.get('class')!r} model; expected {class_name} "
            "(load it with that class's load)",
        )
    if meta.get("parts") != list(part_names):
        raise ModelFileError(path, f"parts must be {list(part_names)}, got {meta.get('parts')!r}")
    if not isinstance(meta.get("params"), dict):
        raise ModelFileError(path, "params must be a mapping of the model's parameters")
    models = {}
    for name in part_names:
        prefix = f"{name}."
        sub = {k[len(prefix) :]: v for k, v in arrays.items() if k.startswith(prefix)}
        if not sub:
            raise ModelFileError(path, f"part {name!r} missing")
        try:
            models[name] = model_from_arrays(sub, path)
        except ModelFileError as exc:
            raise ModelFileError(path, f"part {name!r}: {exc.detail}") from None
    return meta["params"], models
