"""Shock-absorber rig: free play (dead band) with rubber bushes, none with the threaded mount."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import signal

import vrig
from identification import band_limited_noise

FREE_PLAY = 0.0005  # documented half-width [m] (models/shock-absorber/README.md)
K_BUSH = 3e6  # documented rubber stiffness beyond the play [N/m]
THRESHOLD = 0.3  # the load counts as "moving" beyond 30 % of its swing about the mid-level


def _reversal_widths(mounting):
    """At each reversal of a slow triangle (1 Hz, ±5 mm: 20 mm/s): the displacement travelled
    while the load stays within ±30 % of its swing about the mid-level, and the swing."""
    rig = vrig.load_rig("shock-absorber", mounting=mounting)
    fs = rig.fs
    t = np.arange(int(6 * fs)) / fs
    drive = 0.005 * signal.sawtooth(2 * np.pi * 1.0 * t, 0.5)
    load = rig.run(drive, seed=1).channel("damper_load")
    v = np.diff(drive)
    reversals = np.flatnonzero(np.sign(v[1:]) != np.sign(v[:-1])) + 1
    widths = []
    for i in reversals[1:-1]:
        before, after = np.median(load[i - 120 : i - 40]), np.median(load[i + 80 : i + 160])
        level = (load[i - 120 : i + 160] - (before + after) / 2) / ((after - before) / 2)
        x = drive[i - 120 : i + 160]
        j0 = np.flatnonzero(level[:125] < -THRESHOLD)[-1]
        j1 = np.flatnonzero(level[120:] > THRESHOLD)[0] + 120
        widths.append((abs(x[j1] - x[j0]), abs(after - before)))
    return np.array(widths)


def test_rubber_bush_free_play_shows_the_documented_dead_band():
    bush = _reversal_widths("rubber-bush")
    rigid = _reversal_widths("threaded")[:, 0].mean()  # the rest of the load path's transition
    # besides the play, the load swing inside the thresholds compresses the rubber elastically
    elastic = 2 * THRESHOLD * bush[:, 1].mean() / K_BUSH
    assert bush[:, 0].mean() - rigid - elastic == pytest.approx(2 * FREE_PLAY, rel=0.10)


def test_threaded_mounting_has_no_dead_band():
    assert _reversal_widths("threaded")[:, 0].mean() < 0.2 * 2 * FREE_PLAY


def test_random_drive_runs_cleanly_and_load_follows_damping():
    rig = vrig.load_rig("shock-absorber", mounting="threaded")
    d = 0.003 * band_limited_noise(2 * 500, 1, cutoff=10 / 250, seed=2)
    out = rig.run(d, seed=0)
    assert out.names == ("damper_load",) and out.units == ("N",)
    assert np.all(np.isfinite(out.data))
    # rigidly mounted, the load is c v + k x + friction: least squares on (v, x, sign v)
    # recovers the documented damping coefficient
    v = np.gradient(d[:, 0]) * rig.fs
    X = np.column_stack([v, d[:, 0], np.sign(v), np.ones_like(v)])[100:]
    coef, *_ = np.linalg.lstsq(X, out.data[100:, 0], rcond=None)
    assert coef[0] == pytest.approx(12000.0, rel=0.15)
