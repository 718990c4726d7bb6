"""Non-linearity detection (issue 13, deliverable 5; reference text §5.8).

Truth: a linear filter is linear and a static cubic is not (by definition); the cubic's mean
level shift under u + b is ``c (mean u³ + 3 b mean u²)`` (algebra); the shaker is linear inside
its range (models/shaker/README.md: "Inside its range the rig is linear"), the calibrated
elastomeric damper is not (quadratic and cubic rubber stiffness, Iwan hysteresis), and the
damper at severity 0 (its non-linear elements scaled to zero) is linear again.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy import signal

import vrig
from vrig.cli import main
from vrig.linearity import (
    K_NOISE,
    Z_MEAN,
    _multiple_coherence,
    check_linearity,
    check_rig_linearity,
    linearity_drives,
)

FS = 200.0
NOISE = 0.01  # additive output noise rms [output unit]; the drive has rms 1


def _records(system, *, seed=0, noise=NOISE):
    """The drives of linearity_drives through ``system`` (starting from rest) + white noise,
    a different noise stream per record."""
    drives = linearity_drives(FS, (0.0, 40.0), 1.0, seconds=8.0, seed=seed)
    rng = np.random.default_rng(seed + 100)
    out = {}
    for key, d in drives.items():
        y = system(d.data[:, 0]) + noise * rng.standard_normal(d.n_samples)
        out[key] = (d, vrig.TimeHistory(y, FS, ["y"], ["N"]))
    return drives, out


def _lowpass(x):
    b, a = signal.butter(2, 15.0, fs=FS)
    return signal.lfilter(b, a, x)


C3 = 0.3


def _cubic(x):
    return x + C3 * x**3


def test_a_linear_filter_is_linear():
    _, records = _records(_lowpass)
    r = check_linearity(records, skip=2.0)
    assert r.verdict == "linear"
    assert r.mean_z[0] < Z_MEAN
    assert max(s["ratio"][0] for s in r.scaling.values()) < K_NOISE
    assert r.coherence_ratio[0] < K_NOISE
    assert not r.evidence["narx"][0]
    assert r.table().splitlines()[-1] == "verdict: linear"
    # the noise floor is measured, not assumed: the per-run noise rms is the added one
    assert r.noise_rms[0] == pytest.approx(NOISE, rel=0.15)


def test_a_static_cubic_is_non_linear():
    drives, records = _records(_cubic)
    r = check_linearity(records, skip=2.0)
    assert r.verdict == "non-linear"
    assert all(bool(v[0]) for v in r.evidence.values()), r.table()
    # the mean-level shift is the algebraic one: c (mean u³ + 3 b mean u²) over the window
    u = drives["u"].data[400:, 0]
    b = drives["b"].data[400, 0]
    expected = C3 * (np.mean(u**3) + 3 * b * np.mean(u**2))
    assert r.mean_delta[0] == pytest.approx(expected, abs=5 * r.mean_se[0])
    # an odd non-linearity passes the -u test and fails the 2u test
    assert r.scaling["-u"]["ratio"][0] < K_NOISE < r.scaling["2u"]["ratio"][0]


def test_multiple_coherence_of_one_drive_is_scipys_coherence(rng):
    x = rng.standard_normal((4000, 1))
    y = _cubic(_lowpass(x[:, 0]))[:, None] + 0.1 * rng.standard_normal((4000, 1))
    f, g, _ = _multiple_coherence(x, y, FS, 256)
    f2, g2 = signal.coherence(x[:, 0], y[:, 0], fs=FS, nperseg=256)
    np.testing.assert_allclose(f, f2)
    np.testing.assert_allclose(g[:, 0], g2, atol=1e-12)


def test_drives_are_what_they_claim():
    d = linearity_drives(FS, (0.0, 40.0), [1.0, 2.0], seconds=4.0, ramp=1.0, settle=1.0)
    u = d["u"].data
    np.testing.assert_array_equal(d["2u"].data, 2 * u)
    np.testing.assert_array_equal(d["-u"].data, -u)
    np.testing.assert_array_equal(d["repeat"].data, u)
    assert not np.any(d["0"].data)
    win = u[400:]  # after ramp + settle: one period, zero mean, the asked rms
    np.testing.assert_allclose(win.mean(axis=0), 0.0, atol=1e-12)
    np.testing.assert_allclose(np.sqrt(np.mean(win**2, axis=0)), [1.0, 2.0])
    np.testing.assert_array_equal(u[200:400], win[-200:])  # the settle is the cyclic tail
    np.testing.assert_allclose(d["b"].data[400:], np.broadcast_to([1.0, 2.0], win.shape))
    np.testing.assert_allclose(d["u+b"].data, u + d["b"].data)


def test_bad_records_are_refused():
    _, records = _records(_lowpass)
    with pytest.raises(ValueError, match="repeat"):
        check_linearity({"u": records["u"]})
    bad = dict(records)
    bad["2u"] = (records["-u"][0].with_data(records["u"][0].data ** 2), records["2u"][1])
    with pytest.raises(ValueError, match="not a scaled copy"):
        check_linearity(bad, skip=2.0)
    with pytest.raises(ValueError, match="constant drive"):  # b's fade-in is not analysable
        check_linearity(records, skip=0.0)
    with pytest.raises(ValueError, match="unknown record"):
        check_linearity({**records, "3u": records["2u"]})
    with pytest.raises(ValueError, match="both 'b' and 'u\\+b'"):
        check_linearity({k: v for k, v in records.items() if k != "b"})


@pytest.mark.parametrize(
    ("name", "kw", "verdict"),
    [
        ("shaker", {}, "linear"),
        ("elastomeric-damper", {}, "non-linear"),  # the default variant: the calibrated thesis
        ("elastomeric-damper", {"severity": 0.0}, "linear"),
    ],
)
def test_rig_verdicts(name, kw, verdict, tmp_path):
    rig = vrig.load_rig(name, fidelity="fast", **kw)
    if name == "elastomeric-damper" and not kw:
        assert rig.variant == "thesis"
    r = check_rig_linearity(rig, seconds=4.0)
    assert r.verdict == verdict, r.table()
    png = r.plot(tmp_path / "linearity.png")
    assert png.read_bytes()[:4] == b"\x89PNG"


def test_cli_prints_the_evidence_and_the_verdict_last(tmp_path, monkeypatch, capsys):
    out = tmp_path / "lin"
    monkeypatch.delenv("VRIG_PROGRESS", raising=False)  # the default: progress on a terminal only
    rc = main(
        ["check-linearity", "--rig", "elastomeric-damper", "--seconds", "3", "--plot", "--out",
         str(out)]
    )  # fmt: skip
    assert rc == 0
    stdout, err = capsys.readouterr()
    # stderr is not a terminal here (captured, like `2> log`): no bar, no carriage return
    assert "\r" not in err and "runs" not in err, err
    lines = stdout.strip().splitlines()
    assert lines[-1] == "verdict: non-linear"
    assert any(ln.startswith("(a) mean level") for ln in lines)
    assert (out / "linearity.png").read_bytes()[:4] == b"\x89PNG"


def test_cli_rejects_bad_arguments(capsys):
    assert main(["check-linearity", "--rig", "shaker", "--level", "0.9"]) == 2
    assert "--level" in capsys.readouterr().err
    assert main(["check-linearity", "--rig", "shaker", "--seconds", "1"]) == 2
    assert main(["check-linearity", "--rig", "nope"]) == 2
    assert "unknown rig" in capsys.readouterr().err
