"""A rig run stops at its first interlock trip, as a real rig's interlock stops it (issue 33).

The trip record is read after each chunk and no chunk is simulated after the one that holds the
first trip; an instability detected in the part played (before the trip, or after it within its
chunk) takes precedence and is reported as such. The constructed rig: ``servo_mass`` (a table
on one servo-hydraulic actuator, a sprung mass on it) with a stroke interlock at 20 mm and a
second, direct drive ``kick``: a motor on the sprung mass with a gear of 1e12 N per volt, so a
kick of 0.5 V asks MuJoCo for ~1e11 m/s^2 and it reports ``mjWARN_BADQACC`` at that very step —
an instability placed at a chosen time of the drive.
"""

from __future__ import annotations

import json
import math
import threading
from pathlib import Path

import numpy as np
import pytest

import vrig
from vrig.desired import pseudo_field as field
from vrig.rigs import hydraulics, mujoco_rig

DATA = Path(__file__).parent / "data"
HYDRAULIC_XML = Path(__file__).parents[1] / "models" / "common" / "hydraulic.xml"
START = 0.5  # the 30 mm, 0.5 Hz sine starts here; it passes the 20 mm stroke ~0.23 s later
CHUNK = 0.5  # chunks of 500 samples; with the 0.3 s settling period the trip (~1033 samples
# into the run) lies in the third chunk, which ends 1.2 s into the drive

# The stroke trip of this drive as the code before the change (commit 83cad8a) reported it, for
# any chunk length (it played the whole drive): kind, channel, time [s], value [m].
TRIP_AT_START_COMMIT = ("stroke", "table_disp", 0.7333333333333333, 0.020001792861815457)


class StepCounter:
    """Stands in for ``mujoco.rollout`` in :mod:`vrig.rigs.mujoco_rig`: counts the rollout calls
    and the physics steps asked for (from every thread) and plays them."""

    def __init__(self, real):
        self._real, self._lock = real, threading.Lock()
        self.calls = self.steps = 0

    def rollout(self, model, data, initial_state, control, **kwargs):
        with self._lock:
            self.calls += 1
            self.steps += control.shape[1]
        return self._real.rollout(model, data, initial_state, control, **kwargs)


@pytest.fixture
def counter(monkeypatch):
    c = StepCounter(mujoco_rig.rollout)
    monkeypatch.setattr(mujoco_rig, "rollout", c)
    return c


@pytest.fixture(scope="module")
def rig(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("kick")
    xml = (DATA / "servo_mass.xml").read_text()
    xml = xml.replace("../../models/common/hydraulic.xml", str(HYDRAULIC_XML))
    kick = '  <motor name="kick" joint="spring" gear="1e12"/>\n  </actuator>'
    (tmp / "kick.xml").write_text(xml.replace("</actuator>", kick))
    desc = json.loads((DATA / "servo_mass.rig.json").read_text())
    desc["mjcf"] = str(tmp / "kick.xml")
    desc["inputs"].append(
        {"name": "kick", "unit": "V", "full_scale": 1.0, "kind": "direct", "actuator": "kick",
         "noise_rms": 0.0}
    )  # fmt: skip
    (tmp / "kick.rig.json").write_text(json.dumps(desc))
    return vrig.load_rig(tmp / "kick.rig.json", stroke=0.02, fidelity="fast")


def _drive(rig, kick_at=None, seconds=4.0):
    """The stroke-tripping sine on the table and, from ``kick_at`` [s] on, a 0.5 V kick."""
    t = np.arange(round(seconds * rig.fs)) / rig.fs
    table = np.where(t >= START, 0.03 * np.sin(2 * np.pi * 0.5 * (t - START)), 0.0)
    kick = np.zeros_like(t) if kick_at is None else np.where(t >= kick_at, 0.5, 0.0)
    return np.column_stack([table, kick])


def _trip(exc):
    return (exc.kind, exc.channel, exc.time, exc.value)


def _run(rig, drive, chunk):
    try:
        return rig.run(drive, seed=3, chunk_seconds=chunk)
    except (vrig.RigLimitError, vrig.SimulationInstabilityError) as exc:
        return exc


def test_the_first_trip_is_the_one_the_full_run_reported_before_the_change(rig):
    for chunk in (CHUNK, 0.013, math.inf):
        with pytest.raises(vrig.RigLimitError, match="stroke limit") as err:
            rig.run(_drive(rig), seed=3, chunk_seconds=chunk)
        assert _trip(err.value) == TRIP_AT_START_COMMIT
    # independent of the code: the command passes 20 mm at START + asin(2/3) / pi (servo lag)
    assert err.value.time == pytest.approx(START + np.arcsin(0.02 / 0.03) / np.pi, abs=0.02)


def test_a_trip_stops_the_run_at_the_end_of_its_chunk(rig, counter):
    with pytest.raises(vrig.RigLimitError):
        rig.run(_drive(rig), seed=3, chunk_seconds=CHUNK)
    settle, chunk = round(rig.description.settle_time * rig.fs), round(CHUNK * rig.fs)
    trip_sample = settle + round(TRIP_AT_START_COMMIT[2] * rig.fs)  # samples into the run
    chunks = trip_sample // chunk + 1  # the trip's chunk is the last one played
    assert counter.calls == chunks == 3  # of 9
    assert counter.steps == chunks * chunk * rig.decimation
    counter.calls = counter.steps = 0
    rig.run(_drive(rig) * [0.5, 0.0], seed=3, chunk_seconds=CHUNK)  # 15 mm: no trip
    whole = settle + _drive(rig).shape[0]
    assert counter.calls == math.ceil(whole / chunk) and counter.steps == whole * rig.decimation


@pytest.mark.parametrize(
    "kick_at, chunk, calls",
    [(3.0, CHUNK, 3), (0.75, 0.013, 80)],  # 0.013 s: the trip's chunk ends at 1.040 s of the run
    ids=["a kick 1.8 s after the trip's chunk", "a kick after the trip's short chunk"],
)
def test_an_instability_after_the_trips_chunk_is_never_reached(rig, counter, kick_at, chunk, calls):
    """The kick would blow the model up (as the whole drive in one piece shows); the run stops
    at the end of the trip's chunk first, so the trip is reported: the drive's without a kick."""
    drive = _drive(rig, kick_at=kick_at)
    with pytest.raises(vrig.SimulationInstabilityError, match="mjWARN_BADQACC"):
        rig.run(drive, seed=3, chunk_seconds=math.inf)
    counter.calls = 0
    with pytest.raises(vrig.RigLimitError) as err:
        rig.run(drive, seed=3, chunk_seconds=chunk)
    assert _trip(err.value) == TRIP_AT_START_COMMIT
    assert counter.calls == calls


@pytest.mark.parametrize(
    "kick_at", [0.2, 0.75], ids=["before the trip", "after it within its chunk"]
)
def test_an_instability_in_the_part_played_is_reported_as_unstable(rig, kick_at):
    for chunk in (CHUNK, math.inf):
        with pytest.raises(vrig.SimulationInstabilityError, match="mjWARN_BADQACC") as err:
            rig.run(_drive(rig, kick_at=kick_at), seed=3, chunk_seconds=chunk)
        # the step MuJoCo refused: where the kick (linearly interpolated) starts
        t = float(str(err.value).split("t = ")[1].split(" s")[0])
        assert kick_at - 1 / rig.fs <= t <= kick_at
        assert (hydraulics.trip_record(rig.data) is not None) == (kick_at > 0.7333)


@pytest.mark.parametrize("threads", [1, 2])
def test_a_batch_stops_each_tripping_run_as_a_single_run_does(rig, counter, threads):
    drives = [
        _drive(rig, kick_at=3.0),  # trips, the instability later is not reached
        _drive(rig) * [0.5, 0.0],  # plays to the end
        _drive(rig, kick_at=0.2),  # unstable before the trip
        _drive(rig),  # trips
        _drive(rig, kick_at=0.75),  # unstable within the trip's chunk
    ]
    single, single_steps = [], []
    for d in drives:
        counter.steps = 0
        single.append(_run(rig, d, CHUNK))
        single_steps.append(counter.steps)
    counter.steps = 0
    got = rig.run_batch(drives, seeds=[3] * len(drives), threads=threads,
                        chunk_seconds=CHUNK, return_exceptions=True)  # fmt: skip
    assert counter.steps == sum(single_steps)
    kinds = [type(r).__name__ for r in got]
    assert kinds == ["RigLimitError", "TimeHistory", "SimulationInstabilityError",
                     "RigLimitError", "SimulationInstabilityError"]  # fmt: skip
    assert [type(r) for r in single] == [type(r) for r in got]
    assert _trip(got[0]) == _trip(got[3]) == _trip(single[0]) == TRIP_AT_START_COMMIT
    assert np.array_equal(got[1].data, single[1].data)
    assert [str(r) for r in got[2::2]] == [str(r) for r in single[2::2]]


def test_pseudo_fields_fail_on_a_twin_whose_blow_up_trips_first(monkeypatch):
    """``unstable.xml`` (a 1e14 N/m spring at a 10 ms step) trips its force interlock one step
    before MuJoCo reports the blow-up: the instability wins, and pseudo_field(s) fail at the
    first level instead of retrying at half the level."""
    with pytest.warns(RuntimeWarning, match="stability limit"):
        twin = vrig.load_rig(DATA / "unstable.xml", fidelity="fast")
    with pytest.raises(vrig.SimulationInstabilityError):
        twin.run(np.zeros(200))
    kind, _, step, _, _ = hydraulics.trip_record(twin.data)
    assert kind == "force" and step * twin.timestep < 0.02  # the blow-up is at t = 0.02 s
    calls = []
    run, run_batch = twin.run, twin.run_batch

    def counted(play):
        def wrapper(drives, **kwargs):
            calls.append(len(drives) if isinstance(drives, list) else 1)
            return play(drives, **kwargs)

        return wrapper

    monkeypatch.setattr(twin, "run_batch", counted(run_batch))
    monkeypatch.setattr(twin, "run", counted(run))
    got = field.pseudo_fields(twin, (1.0, 10.0), 2.0, [0, 1], threads=2)
    assert all(isinstance(r, vrig.SimulationInstabilityError) for r in got)
    assert calls == [2]  # one batch of the two seeds' first level: no 1.5x check, no retry
    calls.clear()
    with pytest.raises(vrig.SimulationInstabilityError):
        field.pseudo_field(twin, (1.0, 10.0), 2.0, seed=0)
    assert calls == [1]
