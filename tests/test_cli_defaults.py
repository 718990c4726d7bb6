"""Issue 15, deliverable 1 (and the CLI part of 7): the best iteration is never worse than IT00 on
any channel, a tolerance stop, per-rig and per-method defaults from the side-car, the engine's
default band = the CLI's, ``--strategy``/``--tolerance``/``--method error-signal``, and the CSV
format said when a plain numeric CSV is refused.

The best-iteration rule is checked on constructed η0 tables (the truth written out by hand), the
tolerance stop on a noise-free linear rig against the stated rule (stop at the first iteration
where every channel is at or below the tolerance), the side-car reading against the side-car
text written in the test.
"""

from __future__ import annotations

import json
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
from scipy import signal

import vrig
from vrig import cli
from vrig.reconstruction import IterationSettings
from vrig.reconstruction.result import best_iteration
from vrig.rigs import ChannelSpec, RigDefaults
from vrig.rigs.spec import MethodDefaults, read_defaults
from vrig.signals import random_drive, triangular_psd


# --------------------------------------------------------------------------- best iteration
@pytest.mark.parametrize(
    ("errors", "want"),
    [
        # IT02 has the smallest mean (25) but channel 2 got worse than IT00 (40 > 30): IT01
        ([[50, 30], [20, 29], [5, 45]], 1),
        # the motorcycle case of issue 15: a strain channel 73 -> 82 % at the lowest mean
        ([[90, 73], [40, 82], [60, 70]], 2),
        # every later iteration makes some channel worse: IT00 is kept
        ([[10, 10], [1, 11], [12, 2]], 0),
        # equal to IT00 on a channel is not worse
        ([[10, 10], [10, 5], [9, 9]], 1),
        # a NaN η0 disqualifies its iteration
        ([[10, 10], [1, np.nan], [9, 9]], 2),
        # the plain rule where no channel gets worse: smallest mean, earliest on a tie
        ([[10, 10], [5, 5], [4, 6], [3, 3], [3, 3]], 3),
        ([[10, 10]], 0),
    ],
)
def test_best_iteration_never_picks_a_channel_worse_than_it00(errors, want):
    assert best_iteration(np.array(errors, float)) == want


def test_best_iteration_of_no_iteration_is_minus_one():
    assert best_iteration(np.empty((0, 2))) == -1


# --------------------------------------------------------------------------- tolerance stop
class _LinearRig:
    """One drive, two responses: first-order low-passes of the drive plus a little seeded noise."""

    name = "linear-2"
    fs = 200.0
    bandwidth = (0.0, 20.0)

    def __init__(self, defaults=None):
        self.inputs = (ChannelSpec("u", "m", 1.0, "direct"),)
        self.outputs = (
            ChannelSpec("y1", "N", 100.0, "load_cell"),
            ChannelSpec("y2", "N", 100.0, "load_cell"),
        )
        if defaults is not None:
            self.defaults = defaults

    def run(self, drive, *, seed=None):
        u = np.asarray(getattr(drive, "data", drive), float)[:, 0]
        y1 = signal.lfilter([0.2], [1.0, -0.8], u)
        y2 = signal.lfilter([0.3], [1.0, -0.7], u)
        y = np.column_stack([y1, y2]) + 1e-5 * np.random.default_rng(seed).standard_normal((u.size, 2))
        return vrig.TimeHistory(y, self.fs, ["y1", "y2"], ["N", "N"])


def _desired(rig, seconds=10.0):
    d = random_drive(
        triangular_psd((0.0, 15.0)), int(seconds * rig.fs), rig.fs, rms=0.05, seed=11, names=["u"]
    )
    return rig.run(d, seed=99)


def test_the_tolerance_stops_at_the_first_iteration_within_it():
    rig = _LinearRig()
    desired = _desired(rig)
    free = vrig.reconstruct(rig, desired, method="arx", iterations=6, gain=0.5)
    assert free.stopped == "" and len(free.errors) == 7
    worst = free.errors.max(axis=1)  # the channel that decides the stop, per iteration
    k = int(np.argmin(worst))
    assert k > 0 and worst[k] < worst[0]
    tol = float(worst[k])
    first = int(np.argmax(worst <= tol))  # the rule: the first iteration within the tolerance
    stopped = vrig.reconstruct(rig, desired, method="arx", iterations=6, gain=0.5, tolerance=tol)
    assert len(stopped.errors) == first + 1
    assert "converged" in stopped.stopped
    np.testing.assert_array_equal(stopped.errors, free.errors[: first + 1])
    # a tolerance above IT00's worst channel: stop at IT00
    at0 = vrig.reconstruct(
        rig, desired, method="arx", iterations=6, gain=0.5, tolerance=float(worst[0]) + 1.0
    )
    assert len(at0.errors) == 1 and at0.stopped.startswith("IT00: converged")


@pytest.mark.parametrize("value", [0.0, -1.0, np.inf, np.nan, True, "1"])
def test_a_bad_tolerance_is_refused(value):
    with pytest.raises(ValueError, match="tolerance"):
        IterationSettings(tolerance=value)


# --------------------------------------------------------------------------- default band
def test_reconstruct_uses_the_side_car_band_like_the_cli():
    rig = _LinearRig(RigDefaults(band=(2.0, 12.0)))
    result = vrig.reconstruct(rig, _desired(rig), method="arx", iterations=0)
    assert result.bandwidth == (2.0, 12.0)
    assert tuple(result.bandwidth) == vrig.reconstruction.defaults.default_band(rig)
    plain = _LinearRig()  # no side-car defaults: the test band
    assert vrig.reconstruct(plain, _desired(plain), iterations=0).bandwidth == (0.0, 20.0)


def test_the_shakers_engine_band_is_its_side_car_band():
    shaker = vrig.load_rig("shaker")
    raw = json.loads((vrig.rigs.rig_path("shaker")).read_text())
    band = tuple(raw["reconstruction"]["band"])
    it = vrig.reconstruction.DriveIteration(shaker, _shaker_desired(shaker))
    assert it.band == band != tuple(shaker.bandwidth)


def _shaker_desired(rig):
    n = int(4 * rig.fs)
    t = np.arange(n) / rig.fs
    y = 0.5 * np.sin(2 * np.pi * 30 * t)[:, None]
    return vrig.TimeHistory(y, rig.fs, [c.name for c in rig.outputs], [c.unit for c in rig.outputs])


# --------------------------------------------------------------------------- side-car
def _side_car(tmp_path, block):
    path = tmp_path / "x.rig.json"
    path.write_text(json.dumps({"fs": 500, "reconstruction": block}))
    return path


def test_per_method_defaults_are_read_from_the_side_car(tmp_path):
    block = {
        "description": "why",
        "gain": 0.6,
        "id_rms": 0.02,
        "methods": {
            "narx": {"description": "why narx", "order": 3, "degree": 3, "gain": 0.4},
            "split": {"description": "why split", "split_hz": 8.0, "id_rms": 0.01},
            "frf": {"description": "the text", "unsupported": "Table 3.4: 46 %"},
        },
    }
    d = read_defaults(_side_car(tmp_path, block))
    assert d.gain == 0.6 and d.id_rms == 0.02
    assert d.method("narx") == MethodDefaults("why narx", order=3, degree=3, gain=0.4)
    assert d.method("split").split_hz == 8.0 and d.method("split").id_rms == 0.01
    assert d.method("frf").unsupported == "Table 3.4: 46 %"
    assert d.method("arx") == MethodDefaults()  # none set


@pytest.mark.parametrize(
    "block",
    [
        {"methods": {"fancy": {"description": "x"}}},  # unknown method
        {"methods": {"narx": {"order": 3}}},  # no description
        {"methods": {"narx": {"description": "x", "speed": 3}}},  # unknown key
        {"methods": {"narx": {"description": "x", "order": 0}}},
        {"methods": {"split": {"description": "x", "split_hz": 300.0}}},  # beyond fs/2
        {"id_rms": 0.02},  # without the description of why
        {"description": "x", "id_rms": 0.8},
    ],
)
def test_bad_method_defaults_are_refused(tmp_path, block):
    with pytest.raises(vrig.errors.RigParameterError):
        read_defaults(_side_car(tmp_path, block))


def test_every_shipped_side_car_method_default_says_why():
    for name in vrig.list_rigs():
        d = vrig.rigs.spec.read_defaults(vrig.rigs.rig_path(name))
        for method, m in d.methods.items():
            assert m.description.strip(), (name, method)


# --------------------------------------------------------------------------- the CLI
def _args(**kw):
    base = dict(
        method="arx", gain=None, order=None, degree=None, split_hz=None, strategy="fixed",
        tolerance=None, iterations=5, band=None, seed=0,
    )  # fmt: skip
    return SimpleNamespace(**{**base, **kw})


def _rig(defaults):
    return SimpleNamespace(
        name="r",
        defaults=defaults,
        bandwidth=(0.0, 20.0),
        fs=100.0,
        inputs=(ChannelSpec("a", "m", 0.05, "direct"), ChannelSpec("b", "m", 0.2, "direct")),
    )


def test_cli_defaults_come_from_the_method_then_the_rig_then_the_global_ones():
    from vrig.reconstruction.defaults import DEFAULT_GAIN

    d = RigDefaults(
        gain=0.6,
        id_rms=0.02,
        methods={"narx": MethodDefaults("why", order=3, degree=3, gain=0.4, id_rms=0.01)},
    )
    r = cli._resolve(_args(method="narx"), _rig(d))
    assert (r.settings.gain, r.method.order, r.method.degree) == (0.4, 3, 3)
    assert r.settings.id_rms == pytest.approx((0.01 * 0.05, 0.01 * 0.2))  # of full scale
    r = cli._resolve(_args(method="arx"), _rig(d))
    assert (r.settings.gain, r.method.order) == (0.6, 4)  # InverseArx's own order
    assert r.settings.id_rms == pytest.approx((0.02 * 0.05, 0.02 * 0.2))
    r = cli._resolve(_args(method="narx", gain=1.0, order=5), _rig(d))  # the user's flags win
    assert (r.settings.gain, r.method.order, r.method.degree) == (1.0, 5, 3)
    r = cli._resolve(_args(), _rig(RigDefaults()))
    assert r.settings.gain == DEFAULT_GAIN == 0.8  # the documented global gain
    assert r.settings.id_rms == pytest.approx((0.05 * 0.05, 0.05 * 0.2))  # 5 % of full scale
    assert r.settings.strategy == "fixed" and r.settings.tolerance is None


def test_an_unsupported_method_warns_in_one_line_and_takes_its_defaults(capsys):
    text = "full-spectrum models fail here\n  (Table 3.4: 46 % / 46 %)"
    methods = {"narx": MethodDefaults("text", order=3, degree=2, gain=0.4, unsupported=text)}
    r = cli._resolve(_args(method="narx"), _rig(RigDefaults(methods=methods)))  # it runs
    assert (r.settings.gain, r.method.order, r.method.degree) == (0.4, 3, 2)  # its defaults
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 1 and err[0].startswith("warning: ")
    assert '"full-spectrum models fail here (Table 3.4: 46 % / 46 %)"' in err[0]  # quoted
    assert "running it anyway" in err[0]


def test_a_supported_method_prints_no_warning(capsys):
    methods = {"narx": MethodDefaults("text", unsupported="Table 3.4")}
    cli._resolve(_args(method="arx"), _rig(RigDefaults(methods=methods)))
    assert "warning" not in capsys.readouterr().err


def test_a_method_the_shipped_side_car_marks_unsupported_runs_from_the_cli(tmp_path, capsys):
    # the fuel tank's side-car (read as plain JSON) marks frf unsupported (reference text Table
    # 3.4); the command warns once, quoting it, and plays its iterations
    car = json.loads((Path(vrig.rigs.rig_path("fuel-tank-2ch"))).read_text())
    reason = car["reconstruction"]["methods"]["frf"]["unsupported"]
    out = tmp_path / "o"
    argv = ["reconstruct", "--rig", "fuel-tank-2ch", "--method", "frf", "--seconds", "4"]
    code = cli.main([*argv, "--iterations", "1", "--out", str(out)])
    captured = capsys.readouterr()
    warned = [x for x in captured.err.splitlines() if x.startswith("warning: ")]
    assert len(warned) == 1 and f'"{reason}"' in warned[0]
    assert code in (cli.ExitCode.OK, cli.ExitCode.STOPPED_INTERLOCK), captured.err
    assert (out / "IT00RES.rsp").is_file()  # IT00 was played


def test_reconstruct_parser_has_strategy_tolerance_and_error_signal():
    args = cli._parser().parse_args(
        ["reconstruct", "--rig", "shaker", "--method", "error-signal", "--strategy", "adaptive",
         "--tolerance", "2.5"]
    )
    assert (args.method, args.strategy, args.tolerance) == ("error-signal", "adaptive", 2.5)
    text = cli._parser()._subparsers._group_actions[0].choices["reconstruct"].format_help()
    assert "time,<name> [<unit>]" in " ".join(text.split())


def test_cli_settings_carry_strategy_tolerance_and_the_method(monkeypatch, tmp_path):
    seen = {}

    def fake(rig, field, settings, **kw):
        seen["settings"] = settings
        raise ValueError("stop here")

    monkeypatch.setattr(vrig.reconstruction, "reconstruct", fake)
    monkeypatch.setattr(cli, "_read_field", lambda args, rig, band: (None, "x", {}))
    code = cli.main(
        ["reconstruct", "--rig", "shaker", "--method", "error-signal", "--strategy", "adaptive",
         "--tolerance", "3", "--out", str(tmp_path / "o")]
    )
    assert code == cli.ExitCode.BAD_INPUT  # a ValueError from reconstruct() is bad input
    resolved = seen["settings"]  # resolved once, before the run: the engine uses it as it is
    s = resolved.settings
    assert (s.strategy, s.tolerance) == ("adaptive", 3.0)
    assert s.method == "error-signal" and resolved.method.name == "error-signal"


def test_a_plain_numeric_csv_is_refused_with_the_expected_format(tmp_path, capsys):
    path = tmp_path / "plain.csv"
    path.write_text("0.1\n0.2\n0.3\n")
    code = cli.main(["reconstruct", "--rig", "shaker", "--desired", str(path), "--out",
                     str(tmp_path / "o")])
    err = capsys.readouterr().err
    assert code == cli.EXIT_USAGE
    assert "no header row" in err and "time,<name> [<unit>]" in err


# --------------------------------------------------------------------------- README alternatives
@pytest.mark.parametrize(
    "options",
    [
        # README "other methods", each in place of method="arx", order=4
        {"method": "narx", "order": 4, "degree": 2},
        {"method": vrig.reconstruction.InverseNarx(4, 2)},
        {
            "method": vrig.reconstruction.SplitSpectra(
                3.0, vrig.reconstruction.InverseNarx(4, 2), vrig.reconstruction.InverseArx(4)
            )
        },
        {"method": "frf"},
        {"method": "error-signal"},
    ],
)
def test_the_readme_alternative_methods_are_valid_settings(options):
    s = IterationSettings.build(iterations=5, gain=0.8, bandwidth=(0.0, 10.0), seed=0, **options)
    vrig.reconstruction.make_method(s.method, **s.method_options)


@pytest.mark.parametrize(
    ("method", "options", "match"),
    [
        ("frf", {"order": 4}, r"'frf' takes no option 'order'; its options: nperseg"),
        ("arx", {"degre": 2}, r"'arx'.*degre"),
    ],
)
def test_an_option_a_method_does_not_take_is_a_value_error(method, options, match):
    with pytest.raises(ValueError, match=match):
        vrig.reconstruction.make_method(method, **options)
