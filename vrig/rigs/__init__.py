"""Virtual test rigs: MuJoCo models of the reference text's rigs behind one small interface.

>>> import vrig
>>> vrig.list_rigs()                                    # doctest: +SKIP
>>> rig = vrig.load_rig("shock-absorber", seed=0)       # doctest: +SKIP
>>> response = rig.run(drive)                           # doctest: +SKIP
"""

from __future__ import annotations

from pathlib import Path

from ..errors import RigModelError
from .daq import AntiAliasFilter, Transducer
from .file_rig import FileRig
from .hydraulics import HydraulicActuator
from .mujoco_rig import FAST_MARGIN, MujocoRig, _batch_seeds, _models_dir
from .protocol import DescribedRig, Rig
from .spec import ChannelSpec, MethodDefaults, RigDefaults, read_description
from .subset import OutputSubset

__all__ = [
    "COMMON_DIR",
    "FAST_MARGIN",
    "AntiAliasFilter",
    "ChannelSpec",
    "DescribedRig",
    "FileRig",
    "HydraulicActuator",
    "MethodDefaults",
    "MujocoRig",
    "OutputSubset",
    "Rig",
    "RigDefaults",
    "Transducer",
    "list_rigs",
    "load_rig",
    "rig_path",
    "run_batch",
    "severity_rigs",
]


COMMON_DIR = _models_dir() / "common"
"""Folder of the shared MJCF parts (``hydraulic.xml``) to include from a user's rig."""


def list_rigs() -> list[str]:
    """Names of the rigs shipped in ``models/`` (folders with a ``<name>.rig.json``)."""
    root = _models_dir()
    return sorted(p.name for p in root.iterdir() if (p / f"{p.name}.rig.json").exists())


def severity_rigs() -> list[str]:
    """Names of the shipped rigs with a non-linearity severity axis (``load_rig(name,
    severity=s)``; side-car ``"severity"``); the others are linear in their operating range."""
    return [n for n in list_rigs() if read_description(rig_path(n)).severity is not None]


def rig_path(name: str) -> Path:
    """The side-car description file of a shipped rig.

    Parameters
    ----------
    name : str
        A shipped rig's name (see :func:`list_rigs`).
    """
    path = _models_dir() / name / f"{name}.rig.json"
    if not path.exists():
        raise ValueError(f"unknown rig {name!r}; available rigs: {list_rigs()}")
    return path


def load_rig(
    name_or_path,
    *,
    seed: int = 0,
    fidelity: str = "full",
    variant: str | None = None,
    severity: float | None = None,
    **overrides,
) -> MujocoRig:
    """Load a shipped rig by name, or a user's rig from an MJCF or side-car path.

    Parameters
    ----------
    name_or_path : str or path
        A name from :func:`list_rigs`, a ``*.rig.json`` side-car file, or an MJCF ``.xml`` file
        with a side-car ``<stem>.rig.json`` next to it (see ``models/README.md``).
    seed : int
        Noise seed of the rig.
    fidelity : {"full", "fast"}
        ``"fast"``: a larger physics timestep for cheap exploratory runs (up to twice the
        documented one, within the model's stability margin; see :class:`MujocoRig`).
    variant : str, optional
        A named parameter set from the side-car's ``"variants"`` (``rig.describe()`` lists
        them), e.g. ``"thesis"``; ``None`` (default): the rig's default variant (its
        side-car's ``default_variant``); ``"mild"``: the documented parameter values. An
        unknown name is a :class:`~vrig.errors.RigParameterError` naming the variants.
    severity : float, optional
        Non-linearity severity in [0, 2] for a rig with a severity axis
        (:func:`severity_rigs`): 0 the linearised rig, 1 (default) the rig as loaded, 2 twice
        as non-linear; it scales the rig's non-linear elements after the variant and overrides.
    **overrides
        Documented rig parameters (``rig.describe()`` lists them); they win over the variant.
    """
    text = str(name_or_path)
    if text.endswith(".json"):
        path = Path(text)
    elif text.endswith(".xml"):
        path = Path(text).with_suffix(".rig.json")
        if not path.exists():
            raise RigModelError(
                f"{text}: a user rig needs its side-car description {path.name} next to the MJCF "
                "(which actuators are drives, which sensors are responses, units and limits; see "
                "models/README.md)"
            )
    else:
        path = rig_path(text)
    if not path.exists():
        raise FileNotFoundError(f"no rig description at {path}")
    return MujocoRig(
        read_description(path),
        seed=seed,
        fidelity=fidelity,
        variant=variant,
        severity=severity,
        **overrides,
    )


def run_batch(rig, drives, *, seeds=None, threads=None, return_exceptions=False, then=None) -> list:
    """Play ``drives`` on any rig: ``rig.run_batch`` when it has one (a :class:`MujocoRig`:
    across threads), an :class:`OutputSubset`'s wrapped rig's batch (its channels selected),
    else one ``rig.run`` after another. Result ``i`` is ``rig.run(drives[i], seed=seeds[i])``.

    Parameters
    ----------
    rig : Rig
        Any rig (:class:`~vrig.rigs.Rig` protocol).
    drives : sequence of ndarray or TimeHistory
        The drives, as for ``rig.run``.
    seeds : sequence of int or None, optional
        One noise seed per drive (None: the rig's own choice, in drive order).
    threads : int, optional
        Worker threads of a batched rig (see :meth:`MujocoRig.run_batch`); ignored by a rig
        that plays one drive at a time.
    return_exceptions : bool
        False: raise the first failing drive's exception (lowest index) once every drive has
        been played; True: return each failure in its slot.
    then : callable, optional
        ``then(i, response)`` of each drive that played: its value (or the exception it
        raises) takes slot ``i``. A :class:`MujocoRig` calls it in the worker thread right
        after the run (:meth:`MujocoRig.run_batch`); any other rig after its run.

    Returns
    -------
    list of TimeHistory (or Exception, with ``return_exceptions=True``)
    """
    drives = list(drives)
    if then is not None and not callable(then):
        raise TypeError(f"then must be callable or None, got {type(then).__name__}")
    if isinstance(rig, OutputSubset):
        names = rig.names
        inner = (lambda i, r: r[names]) if then is None else (lambda i, r: then(i, r[names]))
        results = run_batch(rig.rig, drives, seeds=seeds, threads=threads,
                            return_exceptions=True, then=inner)  # fmt: skip
    elif callable(getattr(rig, "run_batch", None)):
        if then is None or isinstance(rig, MujocoRig):  # a MujocoRig calls then in its workers
            extra = {} if then is None else {"then": then}
            return rig.run_batch(drives, seeds=seeds, threads=threads,
                                 return_exceptions=return_exceptions, **extra)  # fmt: skip
        results = rig.run_batch(drives, seeds=seeds, threads=threads, return_exceptions=True)
        results = [_then(then, i, r) for i, r in enumerate(results)]
    else:
        results = []
        played = zip(drives, _batch_seeds(seeds, len(drives)), strict=True)
        for i, (drive, seed) in enumerate(played):
            try:
                results.append(_then(then, i, rig.run(drive, seed=seed)))
            except Exception as exc:  # in its slot, like a batched rig's
                results.append(exc)
    if not return_exceptions:
        failed = next((r for r in results if isinstance(r, BaseException)), None)
        if failed is not None:
            raise failed
    return results


def _then(then, i: int, result):
    """``then(i, result)`` for a drive that played (its exception in the slot), else ``result``."""
    if then is None or isinstance(result, BaseException):
        return result
    try:
        return then(i, result)
    except Exception as exc:
        return exc
