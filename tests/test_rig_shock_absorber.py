"""Shock-absorber rig: free play (dead band) with rubber bushes, none with the threaded mount.

Truth from the side-car's documented parameters (models/shock-absorber/shock-absorber.rig.json,
README): the datasheet-typical ``mild`` values and the calibrated ``thesis`` variant (the default,
issue 12). The dead band at a reversal is 2 x ``free_play`` of the variant loaded."""

from __future__ import annotations

import json

import numpy as np
import pytest
from scipy import signal

import vrig
from identification import band_limited_noise
from vrig.rigs import rig_path

SPEC = json.loads(rig_path("shock-absorber").read_text())
VARIANTS = ["mild", "thesis"]
THRESHOLD = 0.3  # the load counts as "moving" beyond 30 % of its swing about the mid-level


def _p(name, variant):
    """A documented parameter of ``variant`` from the side-car (the variant's value, else the
    documented default)."""
    values = SPEC.get("variants", {}).get(variant, {}).get("parameters", {})
    return float(values.get(name, SPEC["parameters"][name]["value"]))


def test_the_documented_free_play():
    assert _p("free_play", "mild") == 0.0005  # README: ±0.5 mm (1 mm total)
    assert _p("bush_stiffness", "mild") == 3e6
    assert _p("free_play", "thesis") > _p("free_play", "mild")  # the calibrated worn bush


def _reversal_widths(mounting, variant):
    """At each reversal of a slow triangle (1 Hz, ±5 mm: 20 mm/s): the displacement travelled
    while the load stays within ±30 % of its swing about the mid-level, and the swing.

    The windows around a reversal are sized from the documented play: the load settles once
    the actuator has travelled the whole dead band (2 x free_play) plus a margin."""
    # the play's geometry is measured here, so without the controller's 1/f noise (issue 23:
    # 0.1 mm rms on `thesis`, a run-to-run variation of the drive, not of the bush) and with the
    # datasheet-typical linear 12 kN s/m dashpot: the estimator below takes the load's midpoint
    # as the dead band's centre (`thesis`'s rebound is 3x its compression) and needs the damper
    # force at 20 mm/s well above the 60 N seal friction (`thesis`'s 6 kN s/m bleed gives 120 N)
    rig = vrig.load_rig(
        "shock-absorber",
        mounting=mounting,
        variant=variant,
        control_noise=0.0,
        damping=12000.0,
        rebound_ratio=1.0,
    )
    assert rig.variant == variant
    fs = rig.fs
    t = np.arange(int(6 * fs)) / fs
    drive = 0.005 * signal.sawtooth(2 * np.pi * 1.0 * t, 0.5)
    load = rig.run(drive, seed=1).channel("damper_load")
    v = np.diff(drive)
    speed = 0.02 / fs  # 20 mm/s in metres per sample
    band = int(np.ceil(2 * _p("free_play", variant) / speed))  # samples to cross the play
    a = max(80, band + 40)  # the settled load after the reversal: [i + a, i + a + 80)
    b = a + 80
    reversals = np.flatnonzero(np.sign(v[1:]) != np.sign(v[:-1])) + 1
    widths = []
    for i in reversals[1:-1]:
        before, after = np.median(load[i - 120 : i - 40]), np.median(load[i + a : i + b])
        level = (load[i - 120 : i + b] - (before + after) / 2) / ((after - before) / 2)
        x = drive[i - 120 : i + b]
        j0 = np.flatnonzero(level[:125] < -THRESHOLD)[-1]
        j1 = np.flatnonzero(level[120:] > THRESHOLD)[0] + 120
        widths.append((abs(x[j1] - x[j0]), abs(after - before)))
    return np.array(widths)


@pytest.mark.parametrize("variant", VARIANTS)
def test_rubber_bush_free_play_shows_the_documented_dead_band(variant):
    bush = _reversal_widths("rubber-bush", variant)
    rigid = _reversal_widths("threaded", variant)[:, 0].mean()  # the rest of the transition
    # besides the play, the load swing inside the thresholds compresses the rubber elastically
    elastic = 2 * THRESHOLD * bush[:, 1].mean() / _p("bush_stiffness", variant)
    assert bush[:, 0].mean() - rigid - elastic == pytest.approx(
        2 * _p("free_play", variant), rel=0.10
    )


@pytest.mark.parametrize("variant", VARIANTS)
def test_threaded_mounting_has_no_dead_band(variant):
    width = _reversal_widths("threaded", variant)[:, 0].mean()
    assert width < 0.2 * 2 * _p("free_play", "mild") <= 0.2 * 2 * _p("free_play", variant)


@pytest.mark.parametrize("variant", ["mild"])  # thesis: the valve law, tests/test_element_damper.py
def test_random_drive_runs_cleanly_and_load_follows_damping(variant):
    rig = vrig.load_rig("shock-absorber", mounting="threaded", variant=variant)
    d = 0.003 * band_limited_noise(2 * 500, 1, cutoff=10 / 250, seed=2)
    out = rig.run(d, seed=0)
    assert out.names == ("damper_load",) and out.units == ("N",)
    assert np.all(np.isfinite(out.data))
    # rigidly mounted, the load is c v + k x + friction: least squares on (v, x, sign v)
    # recovers the documented damping coefficient
    v = np.gradient(d[:, 0]) * rig.fs
    X = np.column_stack([v, d[:, 0], np.sign(v), np.ones_like(v)])[100:]
    coef, *_ = np.linalg.lstsq(X, out.data[100:, 0], rcond=None)
    assert coef[0] == pytest.approx(_p("damping", variant), rel=0.15)
    assert _p("damping", variant) == 12000.0  # README: 12 kN s/m, not calibrated
