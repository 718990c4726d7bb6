"""Every vrig and identification exception (and warning) survives pickling (a worker process raising it must
reach the parent intact: issue 16 found a RigLimitError hang a process pool)."""

from __future__ import annotations

import math
import pickle

import pytest

from identification import errors as ie
from vrig import errors as ve

CASES = [
    ve.VrigError("plain"),
    ve.RigLimitError("force", "fore", 1.25, 24400.0, 24000.0, "N", hint="Reduce the drive."),
    ve.RigLimitError("drive", "aft", math.nan, 0.2, 0.1, "m"),
    ve.SimulationInstabilityError("unstable"),
    ve.RigModelError("bad model"),
    ve.RigParameterError("bad value", "kp", 3.0, ">= 0"),
    ve.ReconstructionError(
        "failed before IT00", result={"it": 0}, cause=ValueError("why"), stage="identification"
    ),
    ve.FileFormatError("a.rsp", "RPC III", "truncated"),
    ve.ControlLawError("law raised", law="laws.py:pinv", where="laws.py:12 in pinv"),
    ve.FolderLockedError("results/run is being written", path="results/run", pid=1234),
    ve.ReconstructionInterrupted("interrupted at IT02", result={"it": 2}),
    ve.ResultsFolderError("results folder results/run is a file", path="results/run"),
    ve.ResultsNotSavedError("nothing was saved", path="results/run", result={"it": 1}),
    ve.UnsupportedMethodWarning("method 'arx' on rig 'r': the reference text reports it failing"),
    ie.IdentificationError("plain"),
    ie.InsufficientDataError("too short"),
    ie.MemoryBudgetError("the regression matrix would take 3 GiB"),
    ie.ModelFileError("m.npz", "no coefficients"),
    ie.UnstableModelError("unstable", cause=ValueError("pole")),
    ie.SimulationDivergedError(1, "y1", 42, math.inf, 1e6),
    ie.StabilityWarning("diverges at 1.5x"),
    ie.RankDeficiencyWarning("rank 3 of 4"),
    ie.IllConditionedWarning("condition 1e14"),
]


@pytest.mark.parametrize("error", CASES, ids=lambda e: type(e).__name__)
def test_pickle_round_trip_keeps_type_message_and_attributes(error):
    back = pickle.loads(pickle.dumps(error))
    assert type(back) is type(error)
    assert str(back) == str(error)
    for key, value in vars(error).items():
        got = getattr(back, key)
        if isinstance(value, BaseException):
            assert type(got) is type(value) and str(got) == str(value)
        elif isinstance(value, float) and math.isnan(value):
            assert math.isnan(got)
        else:
            assert got == value, key


def test_every_exception_class_is_covered():
    def classes(module):
        return {
            c
            for c in vars(module).values()
            if isinstance(c, type)
            and issubclass(c, (Exception, KeyboardInterrupt))
            and c.__module__ == module.__name__
        }

    covered = {type(e) for e in CASES}
    assert classes(ve) | classes(ie) <= covered
