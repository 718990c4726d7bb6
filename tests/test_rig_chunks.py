"""Long runs in chunks: bit-identical to one piece, memory flat in the record length, interlocks
reported at the right channel and time in a later chunk."""

from __future__ import annotations

import itertools
import json
import math
import tracemalloc
from pathlib import Path

import numpy as np
import pytest

import vrig
from identification import band_limited_noise
from vrig.rigs.daq import Acquisition, AntiAliasFilter, Transducer, acquire

SERVO_MASS = Path(__file__).parent / "data" / "servo_mass.xml"


def _drive(rig, seconds, rms, seed=0):
    cutoff = min(max(rig.bandwidth[1], 5.0), 0.4 * rig.fs) / (rig.fs / 2)
    full = np.array([c.full_scale for c in rig.inputs])
    d = band_limited_noise(round(seconds * rig.fs), len(rig.inputs), cutoff=cutoff, seed=seed)
    return np.clip(d * rms, -full, full)


@pytest.mark.parametrize(
    "name, rms",
    [
        ("shock-absorber", 0.003),  # hydraulic, valve noise, load-cell noise, 16-bit ADC
        ("shaker", 0.3),  # direct drive, amplifier noise, AC-coupled accelerometer, mains
        ("fuel-tank-7ch", 0.0008),  # 7 hydraulic channels, high-pass and mains pickup
    ],
)
def test_a_run_in_chunks_is_bit_identical_to_one_piece(name, rms):
    rig = vrig.load_rig(name)
    d = _drive(rig, 2.5, rms)
    whole = rig.run(d, seed=4, chunk_seconds=math.inf).data
    assert np.array_equal(rig.run(d, seed=4, chunk_seconds=0.7).data, whole)
    # chunks of one DAQ sample (the settling period alone takes hundreds of them)
    assert np.array_equal(rig.run(d[:50], seed=4, chunk_seconds=1 / rig.fs).data, whole[:50])
    assert np.ptp(whole, axis=0).min() > 0  # the drive moved every response


def test_chunks_carry_the_servo_controller_phase(tmp_path):
    """A controller slower than the physics (every 3rd of 5 steps per sample): 0.7 s chunks
    (3500 steps) cut its sample-and-hold cycle; its step count and states carry over."""
    desc = json.loads(SERVO_MASS.with_suffix(".rig.json").read_text())
    desc["mjcf"] = str(SERVO_MASS)
    desc["inputs"][0]["hydraulic"] = {"controller_rate": 5000 / 3}
    desc["inputs"][0]["noise_rms"] = 0.002
    path = tmp_path / "slow_controller.rig.json"
    path.write_text(json.dumps(desc))
    rig = vrig.load_rig(path)
    d = _drive(rig, 2.5, 0.0005)  # 2 mm rms trips the force limit with the slower loop
    whole = rig.run(d, seed=2, chunk_seconds=math.inf).data
    assert np.array_equal(rig.run(d, seed=2, chunk_seconds=0.7).data, whole)


def test_the_daq_chain_fed_in_pieces_gives_the_same_samples():
    rng = np.random.default_rng(0)
    raw = np.cumsum(rng.standard_normal((5000, 3)), axis=0)
    transducers = [
        Transducer(gain=2.0, noise_rms=0.1, highpass_hz=1.0, mains_amplitude=0.3, bits=12),
        Transducer(noise_rms=0.05),
        Transducer(gain=-1.0, highpass_hz=5.0, mains_amplitude=0.1, mains_hz=60.0),
    ]
    kw = {"fs": 500.0, "decimation": 10, "aa": AntiAliasFilter(), "full_scale": [500, 500, 500]}
    whole, _ = acquire(raw, transducers, rng=np.random.default_rng(7), **kw)
    chain = Acquisition(transducers, rng=np.random.default_rng(7), **kw)
    cuts = [0, 1, 37, 40, 1203, 2999, 5000]  # split points off the decimation grid
    pieces = [chain.process(raw[a:b]) for a, b in itertools.pairwise(cuts)]
    assert np.array_equal(np.concatenate(pieces), whole)
    assert whole.shape == (500, 3)


def _traced_peak(rig, drive):
    tracemalloc.start()
    try:
        rig.run(drive, seed=1)
        return tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()


def test_memory_of_a_run_does_not_grow_with_its_length():
    rig = vrig.load_rig("shock-absorber")
    short, long_ = _drive(rig, 4.0, 0.002), _drive(rig, 24.0, 0.002)
    _traced_peak(rig, short)  # warm-up
    growth = _traced_peak(rig, long_) - _traced_peak(rig, short)
    # what has to grow: the 20 s more of sampled response and of the drive's sample grid
    # (2 x 10 000 x 8 bytes); one stored physics step costs >= 3 controls + the state + the
    # sensors (> 100 bytes): 100 000 more steps would add > 10 MB
    assert growth < 0.5e6


def test_a_stroke_trip_in_a_later_chunk_reports_its_channel_and_time():
    rig = vrig.load_rig(SERVO_MASS, stroke=0.02)
    fs = rig.fs
    t = np.arange(int(4 * fs)) / fs
    start = 2.1  # the sine starts in the fourth 0.7 s chunk
    drive = np.where(t >= start, 0.03 * np.sin(2 * np.pi * 0.5 * (t - start)), 0.0)
    errors = []
    for chunk in (0.7, math.inf):
        with pytest.raises(vrig.RigLimitError, match="stroke limit on channel 'table_disp'") as e:
            rig.run(drive, seed=3, chunk_seconds=chunk)
        errors.append(e.value)
    a, b = errors
    assert (a.kind, a.channel, a.time, a.value) == (b.kind, b.channel, b.time, b.value)
    # the commanded position passes the stroke at start + asin(2/3) / pi (within servo lag)
    assert a.time == pytest.approx(start + np.arcsin(0.02 / 0.03) / np.pi, abs=0.02)
    assert abs(a.value) > 0.02


def test_a_transducer_range_trip_in_a_later_chunk_reports_its_channel_and_time(tmp_path):
    desc = json.loads(SERVO_MASS.with_suffix(".rig.json").read_text())
    desc["outputs"][1]["full_scale"] = 5.0  # an accelerometer with a 5 m/s^2 range
    desc["mjcf"] = str(SERVO_MASS)
    path = tmp_path / "small_range.rig.json"
    path.write_text(json.dumps(desc))
    rig = vrig.load_rig(path)
    t = np.arange(3000) / rig.fs
    start = 1.5  # in the third 0.7 s chunk; 15 Hz at 4 mm: 35 m/s^2 peaks on the table
    drive = np.where(t >= start, 0.004 * np.sin(2 * np.pi * 15 * (t - start)), 0.0)
    errors = []
    for chunk in (0.7, math.inf):
        with pytest.raises(
            vrig.RigLimitError, match="transducer range limit on channel 'mass_acc'"
        ) as e:
            rig.run(drive, seed=3, chunk_seconds=chunk)
        errors.append(e.value)
    a, b = errors
    assert (a.kind, a.channel, a.time, a.value) == (b.kind, b.channel, b.time, b.value)
    assert start < a.time < start + 1 / 15  # within the first cycle of the sine
    assert abs(a.value) > 5.0


@pytest.mark.parametrize("bad", [0, -1.0, float("nan"), "1", True])
def test_a_bad_chunk_length_is_refused(bad):
    rig = vrig.load_rig(SERVO_MASS)
    with pytest.raises(ValueError, match="chunk_seconds must be a positive number"):
        rig.run(np.zeros(100), chunk_seconds=bad)
