"""The non-linearity severity axis (``load_rig(name, severity=s)``, side-car ``"severity"``).

Truth used here: the side-car's own documented values (a play or polynomial coefficient × s, a
slip displacement / s), MuJoCo's compiled model (what the physics actually runs with), and the
physics of a linearised rig: at severity 0 the rig has no non-linear element in its operating
range, so a NARX that contains the ARX (all linear lags, least squares, non-linear terms admitted
only when BIC says they pay) can gain nothing over the ARX; the linear error grows with severity.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

import vrig
from vrig.errors import ReconstructionError, RigParameterError
from vrig.rigs import rig_path, severity_rigs

NONLINEAR = ["elastomeric-damper", "motorcycle-rear", "radiator", "shock-absorber"]

# The text's linear procedure per rig: benchmarks.calibrate.CALIBRATIONS for the calibrated rigs;
# for the motorcycle, Table 3.5's single-transducer row (inverse ARX(4) on the spring strain,
# 0-30 Hz) judged on both channels the table reports.
MOTORCYCLE = {
    "band": (0.0, 30.0),
    "arx_order": 4,
    "responses": ["spring_strain"],
    "channels": ["spring_strain", "spindle_acc"],
}


def _thesis(name):
    return json.loads(rig_path(name).read_text())["variants"]["thesis"]["parameters"]


def test_the_non_linear_rigs_have_a_severity_axis_and_the_linear_ones_refuse_it():
    # fuel-tank-2ch since issue 23 (its progressive buffers and snubbers, tests/
    # test_rig_fuel_tank_2ch_split_and_severity.py); not in NONLINEAR: on it the linear error is not monotonic in the
    # severity (IT00 125 / 44 / 82 % at s = 0 / 1 / 2: its README, "Severity axis")
    assert set(NONLINEAR) | {"fuel-tank-2ch"} <= set(severity_rigs())
    for name in ("fuel-tank-7ch", "shaker"):  # linear in their operating range
        assert name not in severity_rigs()
        with pytest.raises(RigParameterError, match="no severity axis") as exc:
            vrig.load_rig(name, severity=0.5)
        assert exc.value.key == "severity"
    assert vrig.load_rig("fuel-tank-7ch").severity is None


@pytest.mark.parametrize("bad", [-0.1, 2.5, math.nan, math.inf, "1"])
def test_severity_outside_its_range_is_refused(bad):
    with pytest.raises(RigParameterError, match="severity"):
        vrig.load_rig("shock-absorber", severity=bad)


def test_shock_absorber_free_play_scales_with_severity_in_the_compiled_model():
    play = _thesis("shock-absorber")["free_play"]
    for s in (0.0, 0.5, 1.0, 2.0):
        rig = vrig.load_rig("shock-absorber", variant="thesis", severity=s)
        assert rig.severity == s
        assert rig.parameters["free_play"] == pytest.approx(play * s)
        t = rig.model.tendon("bush").id
        lo, hi = rig.model.tendon_lengthspring[t]  # the dead band is [-play, +play]
        assert (lo, hi) == pytest.approx((-play * s, play * s), abs=1e-15)
    assert vrig.load_rig("shock-absorber", variant="thesis").severity == 1.0


def test_severity_scales_after_the_overrides():
    rig = vrig.load_rig("shock-absorber", variant="thesis", free_play=1e-3, severity=0.5)
    assert rig.parameters["free_play"] == pytest.approx(0.5e-3)


def test_damper_severity_zero_is_the_linearised_mount():
    """s = 0: no quadratic/cubic stiffness, the Iwan sliders stuck (springyield 0 = elastic);
    s = 2: twice the polynomial terms and half the slip displacements of the side-car."""
    raw = json.loads(rig_path("elastomeric-damper").read_text())
    slips = [r["scale"] for r in raw["parameters"]["iwan_slip_scale"]["apply"]]
    thesis = _thesis("elastomeric-damper")
    zero = vrig.load_rig("elastomeric-damper", variant="thesis", severity=0)
    j = zero.model.joint("mount").id
    k1 = raw["parameters"]["linear_stiffness"]["value"]
    assert zero.model.jnt_stiffness[j] == pytest.approx(k1)
    assert np.all(zero.model.jnt_stiffnesspoly[j] == 0)
    for i in range(1, 5):
        assert zero.model.tendon_springyield[zero.model.tendon(f"iwan{i}").id] == 0
    two = vrig.load_rig("elastomeric-damper", variant="thesis", severity=2)
    assert two.model.jnt_stiffnesspoly[j][:2] == pytest.approx(
        [2 * thesis["quadratic_stiffness"], 2 * thesis["cubic_stiffness"]]
    )
    for i, slip in enumerate(slips, start=1):
        y = two.model.tendon_springyield[two.model.tendon(f"iwan{i}").id]
        assert y == pytest.approx(slip * thesis["iwan_slip_scale"] / 2)


def test_linearised_damper_responds_in_proportion_to_its_drive():
    """Superposition holds on the linearised mount (s = 0) and fails on the calibrated one:
    doubling a noise-free drive doubles the load within the hydraulics' own small
    non-linearity."""
    def ratio(s):
        rig = vrig.load_rig(
            "elastomeric-damper", variant="thesis", severity=s, valve_noise=0.0, load_noise=0.0
        )
        n = round(2.0 * rig.fs)
        t = np.arange(n) / rig.fs
        x = 2e-3 * np.sin(2 * np.pi * 4 * t) * np.sin(np.pi * t / t[-1]) ** 2
        one = rig.run(x[:, None], seed=1).data[:, 0]
        two = rig.run(2 * x[:, None], seed=1).data[:, 0]
        return np.linalg.norm(two - 2 * one) / np.linalg.norm(2 * one)

    assert ratio(0.0) < 0.02
    assert ratio(1.0) > 5 * ratio(0.0)


def test_side_car_severity_must_scale_documented_numeric_parameters(tmp_path):
    spec = rig_path("shock-absorber")
    d = json.loads(spec.read_text())
    d["mjcf"] = str((spec.parent / d["mjcf"]).resolve())
    for scales, match in (({"mounting": "proportional"}, "numeric"), ({"free_ply": "proportional"}, "free_ply")):
        d["severity"] = {"description": "x", "scales": scales}
        path = tmp_path / "s.rig.json"
        path.write_text(json.dumps(d))
        with pytest.raises(RigParameterError, match=match):
            vrig.load_rig(path)
    d["severity"] = {"description": "x", "scales": {"free_play": "quadratic"}}
    path.write_text(json.dumps(d))
    with pytest.raises(RigParameterError, match="quadratic"):
        vrig.load_rig(path)


# --------------------------------------------------------- reconstruction on the severity axis

_CACHE: dict = {}


def _eta(name, severity, method="arx", variant=None):
    """IT00 η0 [%] of the text's procedure (quick settings of benchmarks.calibrate) on the
    calibrated twin (where there is one; else ``variant``, None: the default) at ``severity``:
    the mean over the channels the text reports."""
    key = (name, severity, method, variant)
    if key not in _CACHE:
        from benchmarks import calibrate
        from vrig.reconstruction import InverseNarx

        cal = calibrate.CALIBRATIONS.get(name)
        if cal is None or cal["target"] is None:  # no linear baseline (motorcycle: Table 3.2 only)
            cal = MOTORCYCLE
        if variant is None:
            variant = "thesis" if name in calibrate.CALIBRATIONS else None
        rig = vrig.load_rig(name, seed=0, variant=variant, severity=severity)
        if method == "arx":
            m = calibrate._arx(cal)
        else:  # contains the ARX: all linear lags; quadratic terms of the inputs if BIC admits
            kw = {"responses": cal["responses"]} if cal.get("responses") else {}
            m = InverseNarx(cal["arx_order"], 2, kind="input-polynomial", criterion="bic", **kw)
        try:
            errors = calibrate._reconstruct(rig, cal, m)[0]
        except ReconstructionError:  # IT00's drive tripped an interlock: worse than any figure
            _CACHE[key] = math.inf
            return _CACHE[key]
        channels = calibrate._channels(cal, rig)
        _CACHE[key] = sum(errors[c] for c in channels) / len(channels)
    return _CACHE[key]


@pytest.mark.parametrize("name", NONLINEAR)
def test_linearised_twin_gives_a_narx_nothing_to_win(name):
    arx, narx = _eta(name, 0.0), _eta(name, 0.0, "narx")
    assert abs(narx - arx) <= 0.10 * arx, (arx, narx)


GROWTH_CASES = [
    *(pytest.param(n, None, id=n) for n in NONLINEAR if n != "motorcycle-rear"),
    pytest.param("motorcycle-rear", "mild", id="motorcycle-rear-mild"),
    # a finding (issue 23), not hidden: on the default digressive damper the mean IT00 error
    # peaks at s = 1 (24.5, 58.4, 51.3 % at s = 0, 1, 2; README "Severity axis"): doubling the
    # bleed asymmetry leaves 800 N s/m in compression and the blow-off at its 0.05 floor
    pytest.param(
        "motorcycle-rear", None, id="motorcycle-rear-digressive",
        marks=pytest.mark.xfail(strict=True, reason="the digressive motorcycle's linear error "
                                "peaks at s = 1 (README 'Severity axis')"),
    ),
]  # fmt: skip


@pytest.mark.parametrize("name, variant", GROWTH_CASES)
def test_linear_error_grows_with_severity(name, variant):
    e = [_eta(name, s, variant=variant) for s in (0.0, 1.0, 2.0)]
    assert e[0] < e[1] < e[2], e


def test_motorcycle_severity_zero_bonds_the_tyre_and_symmetrises_the_damping():
    """s = 0: the tyre's tension spring equals its compression spring (a bonded, linear
    contact: the two dead-band springs of the compiled model add up to one spring about the free
    radius) and both damper strokes carry the mean damping; s = 2: twice the asymmetry."""
    raw = json.loads(rig_path("motorcycle-rear").read_text())["parameters"]
    k = raw["tyre_stiffness"]["value"]
    cc, cr = raw["compression_damping"]["value"], raw["rebound_damping"]["value"]
    zero = vrig.load_rig("motorcycle-rear", variant="mild", severity=0)  # the bilinear actuators
    m = zero.model
    push, pull = m.tendon("tyre").id, m.tendon("tyre_tension").id
    assert m.tendon_stiffness[push] == m.tendon_stiffness[pull] == pytest.approx(k)
    assert m.tendon_lengthspring[push][0] == pytest.approx(m.tendon_lengthspring[pull][1])
    comp, reb = m.actuator("damper_compression").id, m.actuator("damper_rebound").id
    assert -m.actuator_biasprm[comp][2] == pytest.approx((cc + cr) / 2)
    assert -m.actuator_biasprm[reb][2] == pytest.approx((cc + cr) / 2)
    one = vrig.load_rig("motorcycle-rear").model
    assert one.tendon_stiffness[one.tendon("tyre_tension").id] == 0  # the real contact lifts off
    two = vrig.load_rig("motorcycle-rear", severity=2).parameters
    mean, half = (cc + cr) / 2, (cr - cc) / 2
    assert (two["compression_damping"], two["rebound_damping"]) == pytest.approx(
        (mean - 2 * half, mean + 2 * half)
    )
    assert two["tyre_tension_stiffness"] == 0  # kept at its minimum, not negative


def test_motorcycle_severity_scales_the_default_dampers_blow_off():
    """The default (digressive) damper: s = 0 takes the knee away (blow-off ratios 1: one slope
    per stroke, the mean bleed both ways), s = 2 doubles the blow-off's departure from 1, kept at
    the documented minimum; knees and the series compliance (linear) are not scaled."""
    raw = json.loads(rig_path("motorcycle-rear").read_text())
    variant = raw["variants"][raw["default_variant"]]["parameters"]
    floor = raw["parameters"]["blowoff_ratio_rebound"]["minimum"]
    for key in ("blowoff_ratio_compression", "blowoff_ratio_rebound"):
        assert variant[key] < 1.0  # the default is digressive
        assert vrig.load_rig("motorcycle-rear", severity=0).parameters[key] == 1.0
        assert vrig.load_rig("motorcycle-rear", severity=0.5).parameters[key] == pytest.approx(
            1.0 + 0.5 * (variant[key] - 1.0)
        )
        two = vrig.load_rig("motorcycle-rear", severity=2).parameters
        assert two[key] == pytest.approx(max(floor, 1.0 + 2.0 * (variant[key] - 1.0)))
    zero = vrig.load_rig("motorcycle-rear", severity=0)
    assert zero.parameters["series_stiffness"] == variant["series_stiffness"]
    assert zero.parameters["knee_velocity_rebound"] == variant["knee_velocity_rebound"]
    assert not any(zero.model.actuator(i).name.endswith("_bleed") for i in range(zero.model.nu))


def test_arx_inverse_of_the_linearised_damper_is_as_good_as_the_frf_inverse():
    """On the linear rig (s = 0) a time-domain ARX inverse and the frequency-domain FRF inverse
    model the same linear system: their IT00 errors agree (FRF: ~5 %). The automatic lead must
    not settle on a lead shorter than the rig's delay whose inverse only stays bounded with
    contracted poles (before: lead 3 -> 36-70 %, lead 2 with ARX(6) -> 220 %)."""
    from vrig.desired.pseudo_field import pseudo_field
    from vrig.reconstruction import InverseArx, InverseFrf
    from vrig.reconstruction.defaults import default_band

    rig = vrig.load_rig("elastomeric-damper", seed=0, fidelity="fast", severity=0.0)
    band = default_band(rig)
    _drive, desired = pseudo_field(rig, band, 12.0, seed=0)

    def it00(method):
        res = vrig.reconstruct(rig, desired, method=method, iterations=0, bandwidth=band, seed=0)
        return float(np.mean(res.errors[0]))

    arx, frf = it00(InverseArx(4)), it00(InverseFrf())
    assert arx <= 1.5 * frf, (arx, frf)
    assert it00(InverseArx(6)) <= 1.5 * frf
