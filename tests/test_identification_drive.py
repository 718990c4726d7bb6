"""The one identification drive (:mod:`vrig.reconstruction.id_drive`): the level halved while the
rig refuses or trips, the same records for the engine, its matched probe and the target check.

The truths: a stub rig whose interlock trips above a known RMS (so the number of halvings is
known in advance: the first level at or below the threshold is ``rms / 2**k`` for the smallest
such ``k``), the drive limits' own check, and the PSD shape's definition (a triangular drive over
the identification band).
"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

import vrig
from vrig.errors import RigLimitError, SimulationInstabilityError
from vrig.reconstruction import DriveIteration
from vrig.reconstruction.id_drive import ID_ATTEMPTS, identification_run
from vrig.timehistory import TimeHistory

FS = 200.0


class _TrippingRig:
    """One drive, one response (the drive itself); the interlock trips while the drive's RMS
    exceeds ``trip_rms`` (a force limit proportional to the stroke), and counts its runs."""

    name = "tripping"
    fs = FS
    bandwidth = (0.0, 20.0)
    defaults = None

    def __init__(self, trip_rms: float, unstable: bool = False):
        self.inputs = (SimpleNamespace(name="x", unit="m", full_scale=0.01, limits=None),)
        self.outputs = (SimpleNamespace(name="y", unit="N", full_scale=1.0),)
        self.trip_rms, self.unstable, self.runs = trip_rms, unstable, []

    def run(self, drive, seed=None):
        x = np.asarray(drive.data)
        rms = float(np.sqrt(np.mean(x**2)))
        self.runs.append(rms)
        if self.unstable:
            raise SimulationInstabilityError("the twin blew up")
        if rms > self.trip_rms:
            raise RigLimitError("force", "y", 1.0, rms, self.trip_rms, "N")
        return TimeHistory(x.copy(), FS, ["y"], ["N"])


def _limits_check(monkeypatch):
    """The stub has no actuator limits beyond full scale: the check sees a plain full scale."""
    from vrig.reconstruction import id_drive

    monkeypatch.setattr(id_drive, "check_drive_limits", lambda *a, **k: None)


@pytest.mark.parametrize("halvings", [0, 1, 3, 6])
def test_the_level_is_halved_until_the_rig_takes_it(halvings, monkeypatch):
    _limits_check(monkeypatch)
    rms0 = 0.0005
    rig = _TrippingRig(trip_rms=rms0 / 2**halvings * 1.0001)
    run = identification_run(rig, (0.0, 20.0), 4000, rms0, seed=3)
    assert run.halvings == halvings and len(rig.runs) == halvings + 1
    np.testing.assert_allclose(run.rms, [rms0 / 2**halvings], rtol=1e-15)
    # the drive's RMS is the level asked for (random phases, exact RMS by construction)
    assert np.sqrt(np.mean(run.drive.data**2)) == pytest.approx(rms0 / 2**halvings, rel=1e-9)
    assert (run.last_trip is None) == (halvings == 0)
    # every try draws the same phases: the drive taken is the first one, scaled
    first = identification_run(_TrippingRig(1.0), (0.0, 20.0), 4000, rms0, seed=3).drive
    np.testing.assert_allclose(run.drive.data, first.data / 2**halvings, rtol=1e-12, atol=0)


def test_a_rig_that_trips_at_every_level_raises_the_last_trip(monkeypatch):
    _limits_check(monkeypatch)
    rig = _TrippingRig(trip_rms=0.0)
    with pytest.raises(RigLimitError, match="force limit"):
        identification_run(rig, (0.0, 20.0), 4000, 0.0005, seed=0)
    assert len(rig.runs) == ID_ATTEMPTS == 11  # down to 1/1024 of the level (60 dB)


def test_an_unstable_twin_is_not_retried_at_a_lower_level(monkeypatch):
    _limits_check(monkeypatch)
    rig = _TrippingRig(trip_rms=1.0, unstable=True)
    with pytest.raises(SimulationInstabilityError):
        identification_run(rig, (0.0, 20.0), 4000, 0.0005, seed=0)
    assert len(rig.runs) == 1


def test_a_drive_beyond_full_scale_is_refused_and_halved_before_it_is_sent():
    rig = vrig.load_rig("shock-absorber", fidelity="fast")
    full = rig.inputs[0].full_scale
    run = identification_run(rig, (0.0, 10.0), 2000, 0.9 * full, seed=1)  # peaks > full scale
    assert run.halvings >= 1  # refused (beyond full scale) or tripped, then halved
    assert np.abs(run.drive.data).max() <= full


def test_the_engine_and_the_target_check_identify_from_it_through_the_halvings():
    """A level beyond what the rig takes: the engine halves as the function does (the same
    records, bit for bit) and says how often; the target check sees the same records."""
    rig = vrig.load_rig("shock-absorber", fidelity="fast")
    full = rig.inputs[0].full_scale
    desired = rig.run(identification_run(rig, (0.0, 10.0), 2000, 0.05 * full, seed=9).drive)
    engine = DriveIteration(rig, desired, method="arx", id_rms=0.9 * full, id_seed=2)
    engine.identify()
    run = identification_run(rig, engine.band, 2000, 0.9 * full, seed=2)
    assert run.halvings >= 1
    np.testing.assert_array_equal(engine.id_drive.data, run.drive.data)
    np.testing.assert_array_equal(engine.id_response.data, run.response.data)
    assert f"halved {run.halvings}x" in engine.id_report["reason"]
