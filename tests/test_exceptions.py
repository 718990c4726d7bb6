"""One exception root per package: ``vrig.VrigError`` and ``identification.IdentificationError``.

The classes are found by introspection (every module of both packages is imported and searched),
so a new public exception class that forgets its root, or has no built-in base for
``except ValueError``/``except RuntimeError`` code to catch, fails here.
"""

from __future__ import annotations

import importlib
import inspect
import pickle
import pkgutil

import pytest

import identification
import vrig
from identification import IdentificationError
from vrig import VrigError

ROOTS = {"vrig": VrigError, "identification": IdentificationError}

# the built-in base each class had before the roots existed (the interface users may catch)
FORMER_BASES = {
    "vrig.errors.RigLimitError": RuntimeError,
    "vrig.errors.SimulationInstabilityError": RuntimeError,
    "vrig.errors.RigModelError": ValueError,
    "vrig.errors.RigParameterError": ValueError,
    "vrig.errors.ReconstructionError": RuntimeError,
    "vrig.errors.FileFormatError": ValueError,
    "identification.errors.IdentificationError": ValueError,
    "identification.errors.InsufficientDataError": ValueError,
    "identification.errors.ModelFileError": ValueError,
    "identification.errors.UnstableModelError": ValueError,
    "identification.errors.SimulationDivergedError": ArithmeticError,
}

# interrupts, not errors: a KeyboardInterrupt only (never an Exception, so ``except Exception`` and
# ``except ERRORS`` never swallow a Ctrl-C), with what was done attached
INTERRUPTS = {"vrig.errors.ReconstructionInterrupted": KeyboardInterrupt}

# built-in exception types a package class may take as its second base
_BUILTIN_BASES = tuple(
    t
    for t in vars(__import__("builtins")).values()
    if inspect.isclass(t) and issubclass(t, Exception) and t is not Exception
)


def _public_exceptions(package) -> dict[str, type]:
    """Every public exception class (not a warning) defined in ``package``, by qualified name."""
    modules = [package]  # every module, private ones too (a class may be re-exported)
    for info in pkgutil.walk_packages(package.__path__, package.__name__ + "."):
        if info.name.rpartition(".")[2] != "__main__":  # running it would run the program
            modules.append(importlib.import_module(info.name))
    found = {}
    for module in modules:
        for name, obj in vars(module).items():
            if (
                inspect.isclass(obj)
                and issubclass(obj, BaseException)
                and not issubclass(obj, Warning)
                and obj.__module__.split(".")[0] == package.__name__
                and not name.startswith("_")
                and not obj.__name__.startswith("_")
            ):
                found[f"{obj.__module__}.{obj.__qualname__}"] = obj
    return found


EXCEPTIONS = {**_public_exceptions(vrig), **_public_exceptions(identification)}


def test_the_search_finds_every_class_that_existed_before_the_roots():
    assert set(FORMER_BASES) <= set(EXCEPTIONS)
    assert {"vrig.errors.VrigError"} <= set(EXCEPTIONS)


@pytest.mark.parametrize("qualname", sorted(EXCEPTIONS))
def test_every_exception_derives_from_its_package_root(qualname):
    cls = EXCEPTIONS[qualname]
    if qualname in INTERRUPTS:
        assert issubclass(cls, INTERRUPTS[qualname]) and not issubclass(cls, Exception)
        return
    assert issubclass(cls, ROOTS[cls.__module__.split(".")[0]]), qualname


@pytest.mark.parametrize("qualname", sorted(EXCEPTIONS))
def test_every_exception_keeps_a_built_in_base(qualname):
    cls = EXCEPTIONS[qualname]
    if cls is VrigError or qualname in INTERRUPTS:  # the root is a plain Exception
        return
    assert issubclass(cls, _BUILTIN_BASES), f"{qualname} has no built-in base: {cls.__mro__}"
    if qualname in FORMER_BASES:
        assert issubclass(cls, FORMER_BASES[qualname]), qualname


def test_the_roots_are_exported():
    assert vrig.VrigError is VrigError and "VrigError" in vrig.__all__
    assert vrig.ERRORS == (VrigError, IdentificationError) and "ERRORS" in vrig.__all__
    assert "IdentificationError" in identification.__all__
    assert not issubclass(VrigError, (ValueError, RuntimeError, ArithmeticError))


def test_simulation_diverged_is_an_identification_and_an_arithmetic_error():
    exc = identification.SimulationDivergedError(1, "y1", 42, float("inf"), 1e6)
    for base in (IdentificationError, ArithmeticError, ValueError):
        with pytest.raises(base):
            raise exc
    copy = pickle.loads(pickle.dumps(exc))  # still picklable (worker processes)
    assert type(copy) is type(exc) and str(copy) == str(exc) and copy.sample == 42


def test_errors_tuple_catches_either_package():
    for exc in (
        vrig.RigLimitError("stroke", "act0", 1.5, 0.2, 0.1, "m"),
        vrig.RigParameterError("bad", key="moving_mass"),
        identification.InsufficientDataError("few samples"),
        identification.SimulationDivergedError(0, "y0", 3, float("nan"), 1.0),
    ):
        with pytest.raises(vrig.ERRORS):
            raise exc


def test_identification_does_not_need_vrig_for_its_root():
    assert IdentificationError.__module__ == "identification.errors"
    assert all(b.__module__ == "builtins" for b in IdentificationError.__mro__[1:])


@pytest.mark.parametrize("qualname", sorted(EXCEPTIONS))
def test_cli_maps_every_exception_to_exit_1_or_2_never_to_a_bug(qualname, monkeypatch, capsys):
    """A rig description error, a results folder that cannot be used or that another writer
    holds is bad input (2); results that could not be written are a failed run (1); every other
    vrig or identification error is a failed run (1) with the usual hint; none is reported as an
    unexpected error (3); an interrupt is one line and 130."""
    from vrig import cli
    from vrig.errors import ResultsFolderError, ResultsNotSavedError

    cls = EXCEPTIONS[qualname]
    exc = cls.__new__(cls, "boom")  # bypass each class's own constructor arguments
    exc.args = ("boom",)  # (OSError subclasses with their own __init__ leave it to __init__)

    def command(args):
        raise exc

    monkeypatch.setitem(cli._COMMANDS, "rigs", command)
    code = cli.main(["rigs"])
    err = capsys.readouterr().err
    if qualname in INTERRUPTS:
        assert (code, err) == (130, "vrig rigs: interrupted\n")
    elif issubclass(cls, (vrig.RigModelError, vrig.FolderLockedError, ResultsFolderError)):
        assert (code, err) == (2, "vrig rigs: boom\n")
    elif issubclass(cls, ResultsNotSavedError):  # its message says what was (not) saved
        assert (code, err) == (1, "vrig rigs: failed: boom\n")
    elif issubclass(cls, vrig.errors.ControlLawError):  # the law's error: no vrig option hinted
        assert (code, err) == (1, "vrig rigs: failed: boom\n")
    else:
        hint = " (try a narrower --band, a lower --order or --gain, or a smaller desired response)"
        assert (code, err) == (1, f"vrig rigs: failed: boom{hint}\n")
