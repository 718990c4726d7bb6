"""Road inputs (issue 22, deliverables 1 and 4b): ISO 8608 profiles, events, wheel inputs and a
displacement road from a measured acceleration, each against independent truth: the standard's
table and PSD law, the isotropic-surface coherence, the events' documented dimensions and
geometry, the moving average's sinc gain, a wheelbase delay, and the analytic double integral."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from scipy import signal, special

from vrig import TimeHistory
from vrig.roads import (
    EVENTS,
    ROAD_CLASSES,
    add_events,
    iso8608_gd0,
    iso8608_profile,
    road_event,
    road_from_acceleration,
    road_input,
)

# ISO 8608 Table (degree of roughness, Gd(n0) at n0 = 0.1 cycles/m, 1e-6 m^3): geometric means;
# class limits at 32 * 4^k. Typed from the standard's table, not computed.
ISO8608_MEAN = {
    "A": 16,
    "B": 64,
    "C": 256,
    "D": 1024,
    "E": 4096,
    "F": 16384,
    "G": 65536,
    "H": 262144,
}
ISO8608_LIMITS = [32, 128, 512, 2048, 8192, 32768, 131072]  # A|B, B|C, ..., G|H
N0 = 0.1
SEEDS = range(8)
SAMPLES = Path(__file__).resolve().parents[2] / "shared" / "external-data" / "rpc3-samples"
BELGIAN = SAMPLES / "acc_Belgium_road(half)_20Kph_Pass02_DATA7.rsp"


# ---------------------------------------------------------------- ISO 8608 classes


def test_gd0_is_the_standards_geometric_mean_and_lies_between_the_class_limits():
    assert ROAD_CLASSES == tuple("ABCDEFGH")
    for k, c in enumerate(ROAD_CLASSES):
        assert iso8608_gd0(c) == pytest.approx(ISO8608_MEAN[c] * 1e-6, rel=1e-12)
        lower = ISO8608_LIMITS[k - 1] if k > 0 else 0.0
        upper = ISO8608_LIMITS[k] if k < len(ISO8608_LIMITS) else np.inf
        assert lower * 1e-6 < iso8608_gd0(c) < upper * 1e-6
        if 0 < k < len(ISO8608_LIMITS):  # the geometric mean of the class's limits
            assert iso8608_gd0(c) == pytest.approx(np.sqrt(lower * upper) * 1e-6, rel=1e-12)
    assert iso8608_gd0("c") == iso8608_gd0("C")


def _welch_mean(road_class, *, length=2000.0, dx=0.05, nperseg=4096):
    psds = []
    for seed in SEEDS:
        _, z = iso8608_profile(road_class, length, dx=dx, seed=seed, tracks=1)
        n, p = signal.welch(z[:, 0], fs=1.0 / dx, nperseg=nperseg)
        psds.append(p)
    return n, np.mean(psds, axis=0)


def test_class_c_profile_psd_follows_the_iso_law_within_15_percent():
    n, p = _welch_mean("C")
    band = (n >= 0.05) & (n <= 2.0)
    gd0 = ISO8608_MEAN["C"] * 1e-6
    # a log-log fit: intercept at n0 and slope
    design = np.column_stack([np.ones(band.sum()), np.log(n[band] / N0)])
    (log_gd0, slope), *_ = np.linalg.lstsq(design, np.log(p[band]), rcond=None)
    assert np.exp(log_gd0) == pytest.approx(gd0, rel=0.15)
    assert slope == pytest.approx(-2.0, rel=0.15)
    # and every octave band's average against the analytic law
    for lo in (0.05, 0.1, 0.2, 0.4, 0.8):
        b = (n >= lo) & (n < 2 * lo)
        ratio = np.mean(p[b] / (gd0 * (n[b] / N0) ** -2.0))
        assert ratio == pytest.approx(1.0, abs=0.15), (lo, ratio)


def test_waviness_sets_the_slope():
    psds = []
    for seed in range(4):
        _, z = iso8608_profile("D", 1000.0, waviness=2.5, seed=seed, tracks=1)
        n, p = signal.welch(z[:, 0], fs=20.0, nperseg=2048)
        psds.append(p)
    band = (n >= 0.05) & (n <= 2.0)
    slope = np.polyfit(np.log(n[band]), np.log(np.mean(psds, axis=0)[band]), 1)[0]
    assert slope == pytest.approx(-2.5, rel=0.15)


def test_every_class_is_four_times_the_previous():
    n, prev = _welch_mean("A", length=1000.0, nperseg=2048)
    band = (n >= 0.05) & (n <= 2.0)
    for c in ROAD_CLASSES[1:]:
        _, psd = _welch_mean(c, length=1000.0, nperseg=2048)
        assert np.mean(psd[band]) / np.mean(prev[band]) == pytest.approx(4.0, rel=1e-9)
        prev = psd
    # the generated variance against the analytic integral of Gd(n) over the band (w = 2):
    # Gd0 n0^2 (1/n_min - 1/n_max), n_min = 0.01 (the default for long profiles), n_max = Nyquist
    for c in ("A", "C", "F"):
        _, z = iso8608_profile(c, 2000.0, dx=0.05, seed=3, tracks=1)
        n = np.arange(20, 20000) / 2000.0  # the lines k / L in [0.01, Nyquist 10) cycles/m
        lines = np.sum(ISO8608_MEAN[c] * 1e-6 * (n / N0) ** -2.0) / 2000.0  # sum Gd(n_k) dn
        assert np.mean(z[:-1, 0] ** 2) == pytest.approx(lines, rel=1e-9)  # Parseval, exactly
        analytic = ISO8608_MEAN[c] * 1e-6 * N0**2 * (1 / 0.01 - 1 / 10.0)
        assert np.mean(z[:-1, 0] ** 2) == pytest.approx(analytic, rel=0.05)


def test_profile_shape_mean_periodicity_and_grid():
    x, z = iso8608_profile("B", 50.0, dx=0.1, seed=4, tracks=3)
    assert x.shape == (501,) and z.shape == (501, 3)
    assert x[0] == 0.0 and x[-1] == pytest.approx(50.0)
    np.testing.assert_allclose(np.diff(x), 0.1, rtol=1e-12)
    np.testing.assert_array_equal(z[-1], z[0])
    assert np.all(np.abs(z[:-1].mean(axis=0)) < 1e-12 * np.abs(z).max())


def test_profiles_are_bit_reproducible_and_seeds_differ():
    a = iso8608_profile("C", 200.0, seed=7)
    b = iso8608_profile("C", 200.0, seed=7)
    c = iso8608_profile("C", 200.0, seed=8)
    np.testing.assert_array_equal(a[0], b[0])
    np.testing.assert_array_equal(a[1], b[1])
    assert not np.allclose(a[1], c[1])
    g = iso8608_profile("C", 200.0, seed=np.random.default_rng(7))
    np.testing.assert_array_equal(g[1], a[1])


# ---------------------------------------------------------------- left / right coherence


def _cross_spectra(coherence, **kw):
    pxy = pxx = pyy = 0.0
    for seed in SEEDS:
        _, z = iso8608_profile("C", 2000.0, seed=seed, coherence=coherence, **kw)
        n, a = signal.csd(z[:, 0], z[:, 1], fs=20.0, nperseg=1024)
        pxy = pxy + a
        pxx = pxx + signal.welch(z[:, 0], fs=20.0, nperseg=1024)[1]
        pyy = pyy + signal.welch(z[:, 1], fs=20.0, nperseg=1024)[1]
    return n, pxy, pxx, pyy


def test_isotropic_tracks_have_the_dodds_robson_coherence():
    """w = 2: the real coherence of parallel tracks B apart is zeta K1(zeta), zeta = 2 pi n B."""
    n, pxy, pxx, pyy = _cross_spectra("isotropic", track_width=1.8)
    rho_hat = pxy.real / np.sqrt(pxx * pyy)
    zeta = 2 * np.pi * n * 1.8
    for lo, hi in ((0.015, 0.03), (0.03, 0.06), (0.06, 0.12), (0.12, 0.25), (0.5, 2.0)):
        b = (n >= lo) & (n < hi)
        expected = np.mean(zeta[b] * special.kv(1, zeta[b]))
        assert np.mean(rho_hat[b]) == pytest.approx(expected, abs=0.05), (lo, hi)
    # quadrature part ~ 0: the surface is isotropic, no lag between the tracks
    assert np.abs(np.mean((pxy.imag / np.sqrt(pxx * pyy))[(n > 0.01) & (n < 2)])) < 0.03


def test_independent_tracks_are_incoherent_and_identical_tracks_equal():
    n, pxy, pxx, pyy = _cross_spectra("independent")
    msc = np.abs(pxy) ** 2 / (pxx * pyy)
    assert np.mean(msc[(n > 0.01) & (n < 5)]) < 0.01  # 8 x 77 averaged segments: bias ~ 0.002
    _, a = iso8608_profile("C", 300.0, seed=2, coherence=None)
    _, b = iso8608_profile("C", 300.0, seed=2, coherence="independent")
    np.testing.assert_array_equal(a, b)
    _, z = iso8608_profile("C", 300.0, seed=2, coherence="identical", tracks=3)
    np.testing.assert_array_equal(z[:, 0], z[:, 1])
    np.testing.assert_array_equal(z[:, 0], z[:, 2])


def test_track_zero_does_not_depend_on_the_coherence_model():
    zs = [
        iso8608_profile("C", 300.0, seed=5, coherence=c)[1][:, 0]
        for c in ("isotropic", "independent", "identical")
    ]
    np.testing.assert_array_equal(zs[0], zs[1])
    np.testing.assert_array_equal(zs[0], zs[2])


# ---------------------------------------------------------------- events


def _support(x, z):
    nz = np.flatnonzero(np.abs(z) > 1e-12)
    return x[nz[0] - 1], x[nz[-1] + 1]  # the last zero before, the first zero after


DX = 0.005


def test_slow_ditch_has_its_depth_length_and_cosine_shape():
    x, z = road_event("slow-ditch", dx=DX)
    assert z.min() == pytest.approx(-0.15, abs=1e-9)
    assert x[np.argmin(z)] == pytest.approx(1.5, abs=DX)
    start, end = _support(x, z)
    assert (start, end) == (pytest.approx(0.0, abs=DX), pytest.approx(3.0, abs=DX))
    x, z = road_event("slow-ditch", dx=DX, depth=0.2, length=4.0)
    assert z.min() == pytest.approx(-0.2, abs=1e-9) and x[-1] == pytest.approx(4.0)
    np.testing.assert_allclose(z[x <= 1.0 + 1e-9][-1], -0.1, atol=1e-9)  # half depth at L/4


def test_pothole_has_its_depth_opening_and_edges():
    x, z = road_event("pothole", dx=DX)
    assert z.min() == pytest.approx(-0.05, abs=1e-12)
    start, end = _support(x, z)
    assert end - start == pytest.approx(0.5, abs=2 * DX)
    bottom = x[np.isclose(z, -0.05)]
    assert bottom[0] == pytest.approx(0.05, abs=DX) and bottom[-1] == pytest.approx(0.45, abs=DX)


def test_speed_bump_is_a_round_top_hump_of_its_height_and_length():
    x, z = road_event("speed-bump", dx=DX)
    assert z.max() == pytest.approx(0.075, abs=1e-9)
    start, end = _support(x, z)
    assert end - start == pytest.approx(3.7, abs=2 * DX)
    # round-top: every point of the hump on one circle through its ends and its crest
    radius = (3.7**2 / 4 + 0.075**2) / (2 * 0.075)
    on = (x > 0) & (x < 3.7)
    np.testing.assert_allclose(
        (x[on] - 1.85) ** 2 + (z[on] + radius - 0.075) ** 2, radius**2, rtol=1e-9
    )
    x, z = road_event("speed-bump", dx=DX, profile="sinusoidal", height=0.1)
    np.testing.assert_allclose(z, 0.1 * np.sin(np.pi * x / 3.7) ** 2, atol=1e-12)


def test_kerb_strike_has_its_height_and_ramp():
    x, z = road_event("kerb-strike", dx=DX)
    assert z.max() == pytest.approx(0.10, abs=1e-12)
    top = x[np.isclose(z, 0.10)]
    assert top[0] == pytest.approx(0.03, abs=DX)  # the kerb face: 0.03 m ramp
    assert top[-1] == pytest.approx(1.0 - 0.03, abs=DX)
    assert x[-1] == pytest.approx(1.0) and z[-1] == 0.0


def test_belgian_pave_has_its_block_spacing_and_height_range():
    x, z = road_event("belgian-pave", dx=DX, length=15.0)
    # each sett's flat top is a run of equal samples; their centres are one spacing apart
    flat = np.flatnonzero(np.abs(np.diff(z)) < 1e-15)
    runs = np.split(flat, np.flatnonzero(np.diff(flat) > 1) + 1)
    centres = np.array([x[r].mean() + DX / 2 for r in runs if r.size >= 5])
    assert centres.size == 100  # 15 m / 0.15 m
    np.testing.assert_allclose(np.diff(centres), 0.15, atol=DX)
    tops = np.array([z[r[0]] for r in runs if r.size >= 5])
    assert np.all(np.abs(tops) <= 0.012) and np.ptp(tops) > 0.018
    assert np.std(tops) == pytest.approx(0.012 / np.sqrt(3), rel=0.25)  # uniform +-0.012
    assert z.min() >= -0.012 - 0.005 - 1e-12  # a joint falls joint_depth below its block


def test_events_validate_kind_and_dimensions():
    assert set(EVENTS) == {"slow-ditch", "pothole", "speed-bump", "kerb-strike", "belgian-pave"}
    with pytest.raises(ValueError, match="unknown road event 'ramp'"):
        road_event("ramp")
    with pytest.raises(ValueError, match="slow-ditch has no dimension 'height'"):
        road_event("slow-ditch", height=0.1)
    with pytest.raises(ValueError, match="slow-ditch depth must be > 0"):
        road_event("slow-ditch", depth=-0.1)
    with pytest.raises(ValueError, match="pothole length must be finite"):
        road_event("pothole", length=float("nan"))
    with pytest.raises(ValueError, match="dx must be > 0"):
        road_event("pothole", dx=0.0)
    with pytest.raises(ValueError, match="profile must be 'round-top' or 'sinusoidal'"):
        road_event("speed-bump", profile="flat-top")


def test_add_events_places_each_event_on_its_tracks():
    x, z = iso8608_profile("B", 100.0, dx=0.01, seed=1)
    events = [
        ("slow-ditch", 10.0),
        ("kerb-strike", 30.0, {"height": 0.12}),
        {"kind": "belgian-pave", "at": 50.0, "length": 9.0},
        {"kind": "pothole", "at": 80.0, "tracks": 1},
    ]
    out = add_events(x, z, events)
    assert out.shape == z.shape and not np.shares_memory(out, z)
    d = out - z
    for lo, hi, tracks in ((10, 13, (0, 1)), (30, 31, (0,)), (50, 59, (0, 1)), (80, 80.5, (1,))):
        seg = (x >= lo) & (x <= hi)
        for j in (0, 1):
            assert (np.abs(d[seg, j]).max() > 0) == (j in tracks), (lo, j)
    ditch = (x >= 10) & (x <= 13)
    np.testing.assert_allclose(
        d[ditch, 0], road_event("slow-ditch", dx=0.01)[1][: ditch.sum()], atol=1e-12
    )
    assert d[(x >= 30) & (x <= 31), 0].max() == pytest.approx(0.12)
    pave = (x >= 50) & (x <= 59)
    assert not np.allclose(d[pave, 0], d[pave, 1])  # independent block heights per track
    quiet = (
        (x < 10)
        | ((x > 13) & (x < 30))
        | ((x > 31) & (x < 50))
        | ((x > 59) & (x < 80))
        | (x > 80.5)
    )
    assert np.abs(d[quiet]).max() == 0.0
    np.testing.assert_array_equal(add_events(x, z, events), out)  # reproducible
    one = add_events(x, z[:, 0], [("speed-bump", 5.0)])
    assert one.shape == (x.size,)


def test_add_events_refuses_events_off_the_profile_and_bad_items():
    x, z = iso8608_profile("B", 20.0, seed=1)
    with pytest.raises(ValueError, match="does not fit on the profile"):
        add_events(x, z, [("slow-ditch", 18.0)])
    with pytest.raises(ValueError, match="does not fit on the profile"):
        add_events(x, z, [("pothole", -1.0)])
    with pytest.raises(ValueError, match="unknown road event"):
        add_events(x, z, [("crater", 1.0)])
    with pytest.raises(ValueError, match=r"event tracks must be indices 0\.\.1"):
        add_events(x, z, [{"kind": "pothole", "at": 1.0, "tracks": [2]}])
    with pytest.raises(ValueError, match="needs 'kind' and 'at'"):
        add_events(x, z, [{"kind": "pothole"}])
    with pytest.raises(ValueError, match="z must have shape"):
        add_events(x, z[:-1], [])


# ---------------------------------------------------------------- wheel inputs


def _sine_profile(wavelength=2.5, amplitude=0.01, dx=0.01, length=100.0):
    x = np.arange(round(length / dx) + 1) * dx
    return x, amplitude * np.sin(2 * np.pi * x / wavelength)


@pytest.mark.parametrize("contact_length", [0.0, 0.2, 0.8])
def test_a_sinusoidal_road_gives_a_sinusoid_attenuated_by_the_sinc_of_the_contact_length(
    contact_length,
):
    lam, a, v_kmh, fs = 2.5, 0.01, 36.0, 200.0
    th = road_input(_sine_profile(lam, a), v_kmh, fs, contact_length=contact_length)
    assert th.names == ("track_1",) and th.units == ("m",) and th.fs == fs
    v = v_kmh / 3.6
    p0 = contact_length / 2  # the documented start: front axle at x0 + max offset + Lc/2
    gain = np.sinc(contact_length / lam)  # numpy's sinc is sin(pi u)/(pi u)
    expected = a * gain * np.sin(2 * np.pi * (p0 + v * th.time) / lam)
    np.testing.assert_allclose(th.data[:, 0], expected, rtol=0, atol=1e-3 * a)
    # the frequency is v / lambda
    spectrum = np.abs(np.fft.rfft(th.data[:, 0] * np.hanning(th.n_samples)))
    f = np.fft.rfftfreq(th.n_samples, 1 / fs)
    assert f[np.argmax(spectrum)] == pytest.approx(v / lam, abs=fs / th.n_samples)


def test_the_rear_wheel_sees_the_same_track_offset_over_v_later_and_the_length_is_what_fits():
    x, z = iso8608_profile("C", 60.0, dx=0.02, seed=3)
    wheels = {"LF": (0, 0.0), "RF": (1, 0.0), "LR": (0, 2.5), "RR": (1, 2.5)}
    th = road_input((x, z), 36.0, 200.0, wheels=wheels)  # 10 m/s: 2.5 m is 0.25 s, 50 samples
    assert th.names == ("LF", "RF", "LR", "RR") and th.units == ("m",) * 4
    np.testing.assert_allclose(th["LR"].data[50:], th["LF"].data[:-50], rtol=0, atol=1e-12)
    np.testing.assert_allclose(th["RR"].data[50:], th["RF"].data[:-50], rtol=0, atol=1e-12)
    assert not np.allclose(th["LF"].data, th["RF"].data)
    # record length: (60 m - 2.5 m offset - 0.2 m contact) at 10 m/s and 200 Hz, plus the first
    assert th.n_samples == int(np.floor((60.0 - 2.5 - 0.2) / 10.0 * 200.0 + 1e-9)) + 1
    named = road_input((x, z), 36.0, 200.0, wheels=wheels, names=["a", "b", "c", "d"])
    assert named.names == ("a", "b", "c", "d")
    np.testing.assert_array_equal(named.data, th.data)


def test_road_input_sees_an_event_at_its_time():
    x = np.arange(0, 40.0 + 1e-9, 0.01)
    z = add_events(x, np.zeros((x.size, 1)), [("speed-bump", 20.0, {"profile": "sinusoidal"})])
    th = road_input((x, z), 18.0, 100.0, contact_length=0.0)  # 5 m/s
    crest_time = (20.0 + 3.7 / 2) / 5.0
    assert th.time[np.argmax(th.data[:, 0])] == pytest.approx(crest_time, abs=0.01)
    assert th.data[:, 0].max() == pytest.approx(0.075, abs=1e-6)


# ---------------------------------------------------------------- measured road


def _band_limited_displacement(fs=200.0, seconds=60.0):
    t = np.arange(round(fs * seconds)) / fs
    parts = [(0.010, 1.5, 0.3), (0.004, 3.1, 1.1), (0.001, 7.3, 2.0), (0.0002, 18.0, 0.5)]
    d = sum(a * np.sin(2 * np.pi * f * t + p) for a, f, p in parts)
    acc = sum(-a * (2 * np.pi * f) ** 2 * np.sin(2 * np.pi * f * t + p) for a, f, p in parts)
    return t, d, acc


@pytest.mark.parametrize("unit_g, offset", [(False, 0.0), (True, 0.0), (True, 0.05)])
def test_road_from_acceleration_recovers_a_known_displacement(unit_g, offset):
    fs = 200.0
    t, d, acc = _band_limited_displacement(fs)
    scale = 9.80665 if unit_g else 1.0
    th = TimeHistory((acc + offset) / scale, fs, ["LF"], ["g" if unit_g else "m/s^2"])
    out = road_from_acceleration(th, band=(0.5, None), unit_g=unit_g)
    assert out.names == ("LF",) and out.units == ("m",) and out.fs == fs
    inner = slice(round(2 * fs), len(t) - round(2 * fs))  # beyond the faded 1/band[0] = 2 s ends
    err = np.sqrt(np.mean((out.data[inner, 0] - d[inner]) ** 2)) / np.sqrt(np.mean(d[inner] ** 2))
    assert err < 0.02
    assert out.data[0, 0] == 0.0 and out.data[-1, 0] == 0.0  # faded in and out


def test_road_from_acceleration_low_pass_removes_content_above_the_band():
    fs = 200.0
    t, d, acc = _band_limited_displacement(fs)
    out = road_from_acceleration(
        TimeHistory(acc, fs, ["a"], ["m/s^2"]), band=(0.5, 10.0), unit_g=False
    )
    inner = slice(round(2 * fs), len(t) - round(2 * fs))
    f, p = signal.welch(out.data[inner, 0], fs=fs, nperseg=4096)
    _, p_in = signal.welch(d[inner], fs=fs, nperseg=4096)
    k18 = np.argmin(np.abs(f - 18.0))
    assert p[k18] < 1e-3 * p_in[k18]  # zero-phase order 4 at 10 Hz: power x 8e-5 at 18 Hz
    k3 = np.argmin(np.abs(f - 3.1))
    assert p[k3] == pytest.approx(p_in[k3], rel=0.05)


def test_road_from_acceleration_bad_input():
    th = TimeHistory(np.zeros((4000, 1)), 200.0, ["a"], ["g"])
    with pytest.raises(TypeError, match="acc must be a TimeHistory"):
        road_from_acceleration(np.zeros(100))
    with pytest.raises(ValueError, match="band low edge must be > 0"):
        road_from_acceleration(th, band=(0.0, None))
    with pytest.raises(ValueError, match="0 < low < high < fs/2"):
        road_from_acceleration(th, band=(0.5, 150.0))
    with pytest.raises(ValueError, match="shorter than four periods"):
        road_from_acceleration(th[:300], band=(0.5, None))
    with pytest.raises(ValueError, match="is in 'g' but unit_g=False"):
        road_from_acceleration(th, unit_g=False)
    si = TimeHistory(np.zeros((4000, 1)), 200.0, ["a"], ["m/s^2"])
    with pytest.raises(ValueError, match="is in 'm/s\\^2' but unit_g=True"):
        road_from_acceleration(si)


@pytest.mark.skipif(not BELGIAN.exists(), reason="rpc3-samples not present")
def test_the_belgian_record_becomes_a_finite_road_of_plausible_size():
    from vrig.io import read

    acc = read(BELGIAN)
    road = road_from_acceleration(acc, band=(0.5, 40.0))
    assert road.names == acc.names and road.units == ("m",) * 6 and road.fs == acc.fs
    rms = np.sqrt(np.mean(road.data**2, axis=0))
    assert np.all(np.isfinite(road.data)) and np.all((rms > 1e-3) & (rms < 0.1))  # mm to cm


# ---------------------------------------------------------------- bad input


@pytest.mark.parametrize(
    "kwargs, message",
    [
        (dict(road_class="I"), "unknown ISO 8608 road class 'I'"),
        (dict(road_class=3), "unknown ISO 8608 road class 3"),
        (dict(length=0.0), "length must be > 0"),
        (dict(length=-5.0), "length must be > 0"),
        (dict(length=float("nan")), "length must be finite"),
        (dict(dx=0.0), "dx must be > 0"),
        (dict(dx=float("inf")), "dx must be finite"),
        (dict(length=0.5), "it needs at least 16"),
        (dict(waviness=0.0), "waviness must be > 0"),
        (dict(tracks=0), "tracks must be an integer >= 1"),
        (dict(coherence="full"), "coherence must be one of"),
        (dict(track_width=-1.0), "track_width must be > 0"),
        (dict(n_min=20.0), "at or above the Nyquist"),
    ],
)
def test_iso8608_profile_bad_input(kwargs, message):
    args = dict(road_class="C", length=100.0) | kwargs
    road_class, length = args.pop("road_class"), args.pop("length")
    with pytest.raises(ValueError, match=message):
        iso8608_profile(road_class, length, **args)


def test_road_input_bad_input():
    profile = _sine_profile(length=20.0)
    cases = [
        (dict(speed_kmh=0.0), "speed_kmh must be > 0"),
        (dict(speed_kmh=-30.0), "speed_kmh must be > 0"),
        (dict(speed_kmh=float("nan")), "speed_kmh must be finite"),
        (dict(fs=0.0), "fs must be > 0"),
        (dict(contact_length=-0.1), "contact_length must be >= 0"),
        (dict(wheels={"front": (0, 0.0), "rear": (0, 25.0)}), "too short for wheel offsets"),
        (dict(wheels={"x": (1, 0.0)}), r"track must be an index 0\.\.0"),
        (dict(wheels={"x": 0}), "expected \\(track index, offset m\\)"),
        (dict(wheels={}), "non-empty mapping"),
        (dict(names=["a", "b"]), "2 names for 1 wheels"),
    ]
    for kwargs, message in cases:
        args = dict(speed_kmh=50.0, fs=100.0) | kwargs
        speed, fs = args.pop("speed_kmh"), args.pop("fs")
        with pytest.raises(ValueError, match=message):
            road_input(profile, speed, fs, **args)
    x, z = profile
    with pytest.raises(ValueError, match="profile contains NaN"):
        road_input((x, np.where(x > 5, np.nan, z)), 50.0, 100.0)
    with pytest.raises(ValueError, match="strictly increasing"):
        road_input((x[::-1], z), 50.0, 100.0)
    with pytest.raises(ValueError, match="profile must be a tuple"):
        road_input(z, 50.0, 100.0)
