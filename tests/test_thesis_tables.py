"""benchmarks.thesis_tables: which variant each table runs on (``--variant``), which row is the
one the calibrated twin was calibrated on (from ``benchmarks.calibrate.CALIBRATIONS``) and the
verdicts on synthetic numbers. No rig is run here (the real tables take minutes: run
``python -m benchmarks.thesis_tables --quick``)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from benchmarks import calibrate, thesis_tables
from benchmarks.thesis_tables import (
    TABLES,
    calibrated_row,
    calibrated_verdict,
    gain_verdicts,
    resolve_severity,
    resolve_variant,
)
from vrig.rigs import list_rigs, rig_path


def _raw(rig):
    return json.loads(rig_path(rig).read_text())


def _table(rig):
    return next(t for t in TABLES if t.rig == rig)


# ------------------------------------------------------------------------------ --variant


@pytest.mark.parametrize("rig", list_rigs())
def test_a_variant_resolves_to_the_rigs_own_or_its_default(rig):
    """Read from the side-car itself: "thesis" where the side-car has a "thesis" variant, else
    its default_variant ("mild" when it names none); no name: the default."""
    raw = _raw(rig)
    default = raw.get("default_variant", "mild")
    has_thesis = "thesis" in raw.get("variants", {})
    assert resolve_variant(rig, "thesis") == ("thesis" if has_thesis else default)
    assert resolve_variant(rig, None) == default
    assert resolve_variant(rig, "mild") == "mild"


def test_the_four_calibrated_rigs_have_thesis_and_the_motorcycle_does_not():
    for rig in ("elastomeric-damper", "shock-absorber", "radiator", "fuel-tank-2ch"):
        assert resolve_variant(rig, "thesis") == "thesis"
    assert resolve_variant("motorcycle-rear", "thesis") == _raw("motorcycle-rear").get(
        "default_variant", "mild"
    )


def test_severity_only_reaches_the_rigs_with_a_severity_axis():
    for rig in list_rigs():
        has_axis = "severity" in _raw(rig)
        assert resolve_severity(rig, 0.5) == (0.5 if has_axis else None)
        assert resolve_severity(rig, None) is None


class _Calls(list):
    def __init__(self):
        super().__init__()
        self.normal = []
        self.targets = []  # (rig, variant, target) of every table run


def _fake_runs(monkeypatch):
    """thesis_report with the rig work replaced: records (rig, variant, severity) per run
    (the normal tables' runs, also with the drive level, in ``calls.normal``)."""
    calls = _Calls()

    def run_table(table, *, variant, severity, target="pseudo-field", **_kw):
        calls.targets.append((table.rig, variant, target))
        if target == "pseudo-field":  # one call per setting on the pseudo-field target
            calls.append((table.rig, variant, severity))
        return [[10.0 + len(calls.targets)] * len(table.channels) for _ in table.rows]

    monkeypatch.setattr(thesis_tables.run, "run_table", run_table)
    monkeypatch.setattr(
        thesis_tables.run,
        "table_3_7",
        lambda *, variant, **_kw: calls.append(("fuel-tank-7ch", variant, None)) or ([], {}),
    )
    monkeypatch.setattr(thesis_tables.render, "_markdown_3_7", lambda names, out, setting: setting)
    monkeypatch.setattr(thesis_tables.run, "belgian_road_example", lambda **_kw: "")

    def run_normal_table(table, *, level, variant, severity, **_kw):
        calls.normal.append((table.name.split(":")[0], variant, severity, level))
        vals = [[20.0 - k] * len(table.channels) for k in range(len(table.rows))]
        return vals, [""] * len(table.rows), "1 m"

    monkeypatch.setattr(thesis_tables.run, "run_normal_table", run_normal_table)
    return calls


def test_several_variants_run_each_table_per_variant_the_rig_has(tmp_path, monkeypatch):
    calls = _fake_runs(monkeypatch)
    text = thesis_tables.thesis_report(
        tmp_path, True, log=lambda *_: None, variants=["mild", "thesis"]
    )
    for rig in (
        "elastomeric-damper", "shock-absorber", "radiator", "fuel-tank-2ch", "motorcycle-rear"
    ):  # fmt: skip
        assert [(v, s) for r, v, s in calls if r == rig] == [("mild", None), ("thesis", None)]
    assert (
        "vrig(mild, field:rough-road) spring_strain [%] | vrig(mild, pseudo-field) spring_strain "
        "[%] | vrig(thesis, field:rough-road) spring_strain [%] | vrig(thesis, pseudo-field) "
        "spring_strain [%] | text spring_strain" in text
    )
    damper = text[text.index("### Table 6.3") : text.index("### Table 6.16")]
    assert (
        "vrig(mild, field:slow-ditch) ran on variant 'mild' with a field:slow-ditch desired "
        "response; vrig(mild, pseudo-field) ran on variant 'mild' with a pseudo-field desired "
        "response; vrig(thesis, field:slow-ditch) ran on variant 'thesis'" in damper
    )
    assert (tmp_path / "thesis_reproduction_mild_thesis.md").read_text() == text


def test_no_variant_runs_each_rigs_default_once_into_the_default_report(tmp_path, monkeypatch):
    calls = _fake_runs(monkeypatch)
    thesis_tables.thesis_report(tmp_path, True, log=lambda *_: None)
    for table in TABLES:
        assert [(v, s) for r, v, s in calls if r == table.rig] == [
            (_raw(table.rig).get("default_variant", "mild"), None)
        ]
    assert (tmp_path / "thesis_reproduction.md").exists()


def test_severity_is_passed_to_the_severity_rigs_and_named_in_the_heading(tmp_path, monkeypatch):
    calls = _fake_runs(monkeypatch)
    text = thesis_tables.thesis_report(
        tmp_path, True, log=lambda *_: None, variants=["thesis"], severity=1.5
    )
    assert ("shock-absorber", "thesis", 1.5) in calls
    assert ("fuel-tank-2ch", "thesis", 1.5) in calls  # a severity rig since issue 23
    assert {s for name, _v, s, _lvl in calls.normal if name == "Table 6.7"} == {None}  # linear
    assert "variant 'thesis', severity 1.5" in text
    assert (tmp_path / "thesis_reproduction_thesis_s1.5.md").exists()


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["--variant", "no-such-variant"], "unknown variant(s) ['no-such-variant']"),
        (["--variant", "mild", "mild"], "variant named twice"),
        (["--severity", "3"], "severity must lie in [0, 2], got 3.0"),
    ],
)
def test_bad_variant_or_severity_is_refused_before_any_run(
    argv, message, tmp_path, monkeypatch, capsys
):
    calls = _fake_runs(monkeypatch)
    with pytest.raises(SystemExit) as exc:
        thesis_tables.main(["--out", str(tmp_path), *argv])
    assert exc.value.code == 2 and calls == []
    assert message in capsys.readouterr().err


# ------------------------------------------------------------------- calibrated vs predicted


def test_the_calibrated_row_is_the_calibrations_linear_baseline():
    """Each calibrated rig's table marks exactly the inverse ARX of the calibration's order and
    responses at IT00 (and its text figure is the calibration's target); the motorcycle,
    calibrated on its repeatability number alone (no linear baseline), has none."""
    from vrig.reconstruction import InverseArx

    for table in TABLES:
        i = calibrated_row(table)
        cal = calibrate.CALIBRATIONS.get(table.rig)
        if cal is None or cal["target"] is None:  # motorcycle: Table 3.2's number only
            assert i is None
            continue
        row = table.rows[i]
        method = row.method()
        assert isinstance(method, InverseArx) and method.order == cal["arx_order"]
        assert row.iteration == 0 and tuple(table.band) == tuple(cal["band"])
        assert (list(method.responses) if method.responses else None) == cal.get("responses")
        for c in cal.get("channels") or table.channels[:1]:
            assert row.thesis[table.channels.index(c)] == cal["target"]
    with_baseline = {n for n, c in calibrate.CALIBRATIONS.items() if c["target"] is not None}
    assert {t.rig for t in TABLES if calibrated_row(t) is not None} == with_baseline


def test_the_marking_follows_calibrations_not_a_copy(monkeypatch):
    damper = _table("elastomeric-damper")
    cals = dict(calibrate.CALIBRATIONS)
    monkeypatch.setattr(calibrate, "CALIBRATIONS", cals)
    cals["elastomeric-damper"] = {**cals["elastomeric-damper"], "arx_order": 4}
    with pytest.raises(ValueError, match="no row is the linear baseline"):
        calibrated_row(damper)
    cals["elastomeric-damper"] = {**calibrate.CALIBRATIONS["elastomeric-damper"], "target": 50.0}
    cals["elastomeric-damper"]["arx_order"] = 6
    with pytest.raises(ValueError, match="calibrated on 50 %"):
        calibrated_row(damper)
    del cals["elastomeric-damper"]
    assert calibrated_row(damper) is None
    cals["motorcycle-rear"] = {"band": (0.0, 30.0), "arx_order": 4, "target": 56.0,
                               "responses": ["spring_strain"]}  # fmt: skip
    assert calibrated_row(_table("motorcycle-rear")) == 0


def test_the_report_marks_the_calibrated_row_and_predictions(tmp_path, monkeypatch):
    _fake_runs(monkeypatch)
    text = thesis_tables.thesis_report(tmp_path, True, log=lambda *_: None, variants=["thesis"])
    assert "| QanTiM 6th order (inverse) | CALIBRATED ON |" in text
    assert "| NARX 4th order quadratic (inverse), simulation focus | predicted |" in text
    assert "| Broad spectrum, strain gauge simulation | predicted |" in text  # not calibrated
    on_baseline = [c for c in calibrate.CALIBRATIONS.values() if c["target"] is not None]
    assert text.count("CALIBRATED ON |") == len(on_baseline)


# ----------------------------------------------------------------- verdicts, synthetic numbers


def _values(table, first, second, rest=5.0):
    """Synthetic values: row 0 ``first``, row 1 ``second``, the others ``rest`` (per channel)."""
    n = len(table.channels)
    out = [[first] * n, [second] * n] + [[rest] * n for _ in table.rows[2:]]
    return out


@pytest.mark.parametrize(
    ("eta", "within"),
    [(57.0, True), (43.0, True), (42.5, False), (71.0, True), (71.5, False)],
)
def test_the_calibrated_verdict_is_the_25_percent_band_of_the_texts_57(eta, within):
    """Table 6.3's text figure 57 %: ±25 % relative is 42.75-71.25 %."""
    verdict = calibrated_verdict(
        _table("elastomeric-damper"), _values(_table("elastomeric-damper"), eta, 20.0)
    )
    assert ("within" in verdict) is within and ("OUTSIDE" in verdict) is (not within)
    assert "42.8-71.2 %" in verdict


def test_the_calibrated_verdict_needs_every_objective_channel():
    """Table 3.4 is calibrated on both channels (46 % each): one channel out is out."""
    table = _table("fuel-tank-2ch")
    vals = _values(table, 46.0, 20.0)
    assert "within" in calibrated_verdict(table, vals)
    vals[0] = [46.0, 60.0]  # aft 60 % > 57.5 %
    assert "OUTSIDE" in calibrated_verdict(table, vals)


def test_the_calibrated_verdict_on_another_variant_is_a_comparison():
    table = _table("shock-absorber")
    assert "not the calibrated 'thesis'" in calibrated_verdict(
        table, _values(table, 27.0, 17.0), "mild"
    )
    assert "no row calibrated on" in calibrated_verdict(_table("motorcycle-rear"), [[1.0, 1.0]] * 3)
    failed = ["RigLimitError: tripped", *_values(table, 27.0, 17.0)[1:]]
    assert "failed" in calibrated_verdict(table, failed)


@pytest.mark.parametrize(
    ("arx", "narx", "size"),
    [
        # the text: 57 -> 24 %, a gain of 33 pts = 57.9 % of its baseline
        (60.0, 60.0 * (1 - 33 / 57), "as the text's"),
        (40.0, 40.0 * (1 - 1.2 * 33 / 57), "as the text's"),  # 1.2 x: inside ±25 %
        (60.0, 60.0 * (1 - 0.5 * 33 / 57), "smaller (0.50 x the text's)"),
        (60.0, 60.0 * (1 - 1.5 * 33 / 57), "larger (1.50 x the text's)"),
        (60.0, 61.0, "none (not below the baseline)"),
    ],
)
def test_the_nonlinear_gain_is_judged_as_a_fraction_of_the_baseline(arx, narx, size):
    table = _table("elastomeric-damper")
    (verdict,) = gain_verdicts(table, _values(table, arx, narx), 0)
    assert verdict.startswith("NARX 4th order quadratic (inverse), simulation focus, damper_load")
    assert "the text's 33 pts (58% of 57 %)" in verdict
    assert verdict.endswith(size)


def test_gains_cover_every_text_row_and_channel_the_text_reports():
    """Table 6.12: NARX (top tank) and non-square NARX (top tank only: the text gives no
    linear base-acceleration figure); Table 6.16: IT05 and NARX; a failed row is no verdict."""
    radiator = _table("radiator")
    verdicts = gain_verdicts(radiator, _values(radiator, 35.0, 16.0, 14.0), 0)
    assert len(verdicts) == 2 and all(", toptank_acc: " in v for v in verdicts)
    assert all(v.endswith("as the text's") for v in verdicts)  # 19/35 and 21/35 exactly
    shock = _table("shock-absorber")
    vals = _values(shock, 27.0, 17.0, 18.0)
    vals[2] = "UnstableModelError: diverged"
    v_it05, v_narx = gain_verdicts(shock, vals, 0)
    assert v_it05.endswith("as the text's") and "not comparable" in v_narx


def test_a_loss_the_text_also_has_is_as_the_texts():
    """Table 3.5: the accelerometer alone is worse on the strain channel (56 -> 78 %)."""
    table = _table("motorcycle-rear")
    vals = [[56.0, 51.0], [78.0, 31.0], [50.0, 29.0]]  # the text's own figures
    verdicts = gain_verdicts(table, vals, 0)
    assert len(verdicts) == 4 and all(v.endswith("as the text's") for v in verdicts)
    vals[1] = [40.0, 31.0]  # better than the strain gauge: the opposite of the text
    assert gain_verdicts(table, vals, 0)[0].endswith("opposite to the text's")


# ------------------------------------------------- normal (forward) models: Tables 6.5-6.10


def _normal(prefix):
    return next(t for t in thesis_tables.NORMAL_TABLES if t.name.startswith(prefix))


def test_the_normal_tables_carry_the_texts_channels_and_figures():
    """Tables 6.4-6.10 of the text: inputs, outputs and modelling errors (6.10: plots only)."""
    t65, t67 = _normal("Table 6.5"), _normal("Table 6.7")
    t69, t610 = _normal("Table 6.9"), _normal("Table 6.10")
    assert (t65.rig, t65.inputs, t65.channels) == (
        "elastomeric-damper", ["actuator_disp"], ["damper_load"]
    )
    assert [r.thesis for r in t65.verdict_rows()] == [(67,), (35,)]
    assert (t67.rig, t67.inputs, t67.channels) == (
        "pneumatic-trailer", ["air_pressure"], ["arm_strain"]
    )
    assert [r.thesis for r in t67.verdict_rows()] == [(95,), (34,)]
    forces = ["Fx", "Fy", "Fz", "Mx", "My", "Mz"]
    assert (t69.rig, t69.inputs, t69.channels) == (
        "light-truck-front", forces, ["ubj_longitudinal"]
    )
    assert [r.thesis for r in t69.verdict_rows()] == [(46,), (34,)]
    assert t610.inputs == forces and len(t610.channels) == 9
    assert all(t is None for r in t610.rows for t in r.thesis)
    for t in (t65, t67, t69, t610):
        assert tuple(t.band) == (0.0, 25.0)  # every system summary: 0 Hz to 25 Hz


@pytest.mark.parametrize("prefix", ["Table 6.5", "Table 6.7", "Table 6.9", "Table 6.10"])
def test_the_normal_tables_channels_exist_on_their_rigs(prefix):
    table = _normal(prefix)
    raw = _raw(table.rig)
    names = {c["name"] for c in raw["inputs"]} | {c["name"] for c in raw["outputs"]}
    assert set(table.inputs) <= names and set(table.channels) <= names


def test_the_normal_models_are_the_texts_structures():
    from identification import Arx, ErrorSignalModel, Narx

    esm = _normal("Table 6.5").rows[1].model(250.0)
    assert isinstance(esm, ErrorSignalModel)
    assert type(esm.linear) is Arx and esm.linear.order == 3
    assert (esm.nonlinear.order, esm.nonlinear.degree) == (2, 2)
    arx, narx = (r.model(250.0) for r in _normal("Table 6.7").verdict_rows())
    assert type(arx) is Arx and arx.order == 5
    assert type(narx) is Narx and (narx.order, narx.degree) == (3, 2)
    for prefix in ("Table 6.9", "Table 6.10"):
        split = _normal(prefix).rows[1].model(200.0)
        assert split.split_hz == 2.0
        assert (split.low.order, split.low.degree) == (0, 2)  # static quadratic
        assert type(split.high) is Arx and split.high.order == 2


@pytest.mark.filterwarnings("ignore::identification.RankDeficiencyWarning")
def test_the_forward_split_is_exact_on_a_static_linear_gain():
    """y = 2 u1 - u2 (static, linear): each band's model is exact, so the sum is."""
    import numpy as np

    rng = np.random.default_rng(0)
    u = rng.standard_normal((2000, 2))
    y = (2 * u[:, 0] - u[:, 1])[:, None]
    model = _normal("Table 6.9").rows[1].model(200.0).fit(u, y)
    v = rng.standard_normal((1000, 2))
    assert np.allclose(model.simulate(v), (2 * v[:, 0] - v[:, 1])[:, None], atol=1e-8)


def test_the_normal_verdicts_on_synthetic_numbers():
    t67, t610 = _normal("Table 6.7"), _normal("Table 6.10")
    assert "same ordering" in thesis_tables._verdict(t67, [[95.0], [34.0], [50.0]])
    assert "different ordering" in thesis_tables._verdict(t67, [[30.0], [34.0], [50.0]])
    assert "not comparable" in thesis_tables._verdict(t67, [[95.0], "UnstableModelError: x", [1.0]])
    arx9, split9 = [10.0] * 9, [9.0] * 8 + [15.0]  # mean 9.67 < 10
    assert "same ordering" in thesis_tables._verdict(t610, [arx9, split9])
    assert "different ordering" in thesis_tables._verdict(t610, [arx9, [9.0] * 8 + [30.0]])
    (gain,) = gain_verdicts(t67, [[95.0], [34.0], [20.0]], 0)
    assert gain.endswith("as the text's")


def test_the_report_has_the_normal_tables_per_variant_and_level(tmp_path, monkeypatch):
    calls = _fake_runs(monkeypatch)
    text = thesis_tables.thesis_report(tmp_path, True, log=lambda *_: None)
    for prefix in ("Table 6.5", "Table 6.7", "Table 6.9", "Table 6.10"):
        assert f"### {prefix}:" in text
        levels = [lv for name, _v, _s, lv in calls.normal if name == prefix]
        assert levels == list(_normal(prefix).levels)
    assert "| QanTiM 5th order (normal) | arm_strain | 20.0 | 20.0 | 95 |" in text


# ------------------------------------------------------------- physics claims (rig runs)


@pytest.mark.slow
def test_narx_beats_arx_on_the_pneumatic_pressure_to_strain():
    """The text's Table 6.7 ordering, on the twin, both models fitted for simulation (a fair
    comparison: the least-squares ARX's 90 % is a fitting artefact): the air spring's gas law
    and the buffer make pressure -> strain non-linear."""
    table = _normal("Table 6.7")
    for level in table.levels:
        values, _notes, _rms = thesis_tables.run_normal_table(
            table, seconds=30.0, level=level, log=lambda *_: None
        )
        arx_ls, narx, arx_sim = (v[0] for v in values)
        assert narx < arx_sim and narx < arx_ls


def test_each_table_runs_on_the_texts_kind_of_target_and_on_pseudo_field(tmp_path, monkeypatch):
    """Issue 22: 6.3 the slow ditch, 6.12 a road record, 3.4/3.5 road simulations (service
    records of the field twins), 6.16 pseudo-field as the text's; pseudo-field beside each."""
    calls = _fake_runs(monkeypatch)
    thesis_tables.thesis_report(tmp_path, True, log=lambda *_: None)
    texts = {
        "elastomeric-damper": "field:slow-ditch", "radiator": "field:truck-front",
        "fuel-tank-2ch": "field:chassis-road", "motorcycle-rear": "field:rough-road",
    }  # fmt: skip
    for table in TABLES:
        ran = [t for r, _v, t in calls.targets if r == table.rig]
        want = [texts[table.rig], "pseudo-field"] if table.rig in texts else ["pseudo-field"]
        assert ran == want, table.name


# ------------------------------------------------------------------ shared fits, run times


class _Gain:
    """A method fitting one least-squares gain drive = g * response; counts its fits."""

    def __init__(self, fits: list):
        self.fits, self.gain = fits, None

    def identify(self, iddrv, idres):
        self.fits.append(idres.data.copy())
        if np.any(idres.data < 0):
            raise ValueError("no gain for a negative response")
        x, y = idres.data[:, 0], iddrv.data[:, 0]
        self.gain = float(x @ y / (x @ x))

    def drive(self, response):
        return self.gain * response.data

    def describe(self):
        return f"gain {self.gain:g}"


def _records(response, gain=2.0):
    from vrig.timehistory import TimeHistory

    r = np.asarray(response, float)[:, None]
    return TimeHistory(gain * r, 100.0, ["d"], ["m"]), TimeHistory(r, 100.0, ["r"], ["N"])


def test_a_shared_fit_is_reused_only_on_equal_records_under_the_same_tag():
    from benchmarks.shared_fits import SharedFit

    fits, store = [], {}
    ramp = np.linspace(1.0, 2.0, 50)
    first = SharedFit(_Gain(fits), "row", store)
    first.identify(*_records(ramp))
    second = SharedFit(_Gain(fits), "row", store)
    second.identify(*_records(ramp.copy()))  # equal records, other objects: no second fit
    assert len(fits) == 1 and second.shared == 1 and second.method is not first.method
    assert second.gain == pytest.approx(2.0) and second.describe() == "gain 2"
    np.testing.assert_allclose(second.drive(_records(ramp)[1]), 2.0 * ramp[:, None])
    bumped = ramp.copy()
    bumped[17] += 1e-12  # one sample differs: fitted again
    SharedFit(_Gain(fits), "row", store).identify(*_records(bumped))
    SharedFit(_Gain(fits), "other row", store).identify(*_records(ramp))  # another tag
    assert len(fits) == 3
    for _ in range(2):  # a fit that raised raises again, without fitting again
        with pytest.raises(ValueError, match="negative"):
            SharedFit(_Gain(fits), "row", store).identify(*_records(-ramp))
    assert len(fits) == 4


def test_a_tables_two_targets_share_the_fit_of_equal_identification_records(monkeypatch):
    """The default identification does not depend on the target: a row fits once for both
    targets; an id_match row (records matched to each target) fits once per target."""
    import types

    import vrig
    from benchmarks.thesis_tables import Row, Table

    fits = []
    targets = {"field:road": 3.0, "pseudo-field": 5.0}

    def reconstruct(rig, desired, *, method, id_match=False, **_kw):
        level = float(desired.data[0, 0]) if id_match else 1.0  # matched: the target's level
        method.identify(*_records(level * np.linspace(1.0, 2.0, 40)))
        return types.SimpleNamespace(
            method=method, errors=[[100 * abs(method.gain - 2.0)]], desired=desired
        )

    monkeypatch.setattr(vrig, "load_rig", lambda name, **_kw: types.SimpleNamespace(name=name))
    monkeypatch.setattr(vrig, "reconstruct", reconstruct)
    monkeypatch.setattr(
        thesis_tables.run,
        "_desired",
        lambda rig, band, seconds, cache, target: _records(np.full(40, targets[target]))[1],
    )
    table = Table(
        "Table X", "shaker", (0.0, 10.0), ["r"],
        [Row("default", lambda: _Gain(fits)), Row("matched", lambda: _Gain(fits),
                                                  options={"id_match": True})],
        "True", "",
    )  # fmt: skip
    cache, logged = {}, []
    for target in targets:
        values = thesis_tables.run_table(
            table, seconds=1.0, id_seconds=1.0, cache=cache, target=target, log=logged.append
        )
        assert values == [[pytest.approx(0.0)], [pytest.approx(0.0)]]  # the gain 2 of the data
    assert len(fits) == 3  # default: once; matched: once per target
    shared = [ln for ln in logged if "fit shared" in ln]
    assert len(shared) == 1 and shared[0].startswith("  default:")


def test_the_run_ends_with_each_tables_wall_time_and_the_total(tmp_path, monkeypatch, capsys):
    _fake_runs(monkeypatch)
    assert thesis_tables.main(["--quick", "--out", str(tmp_path)]) == 0
    lines = capsys.readouterr().out.rstrip().splitlines()
    assert lines[-1].startswith("wall time ") and lines[-1].endswith("the whole run")
    head = lines.index("wall time per table (slowest first):")
    names = [ln.split("%  ", 1)[1] for ln in lines[head + 1 : -1]]
    want = [t.name.split(":")[0] for t in TABLES + thesis_tables.NORMAL_TABLES]
    assert sorted(names) == sorted([*want, "Table 3.7", "Belgian road"])
    report = (tmp_path / "thesis_reproduction.md").read_text().rstrip().splitlines()[-1]
    assert report.startswith("_wall time per table: ") and all(n in report for n in want)


def test_quick_leaves_out_only_vrig_rows_and_says_so_in_their_cells(monkeypatch):
    """--quick runs every row of the text (so every verdict) and leaves out only the rows
    marked full-run-only: Table 6.16's two SEMP rows, whose cells then say so."""
    import types

    import vrig
    from benchmarks.thesis_tables import NOT_IN_QUICK, Row, Table

    left_out = [(t.name.split(":")[0], r.label) for t in TABLES for r in t.rows if not r.quick]
    assert [name for name, _ in left_out] == ["Table 6.16"] * 2
    assert all(label.startswith("vrig:") for _, label in left_out)  # no text figure lost
    semp = {  # rows whose terms are chosen by free run (SEMP)
        r.label
        for t in TABLES
        for r in t.rows
        if callable(r.method) and r.method().options().get("selection") == "simulation"
    }
    assert {label for _, label in left_out} <= semp

    fits = []

    def reconstruct(rig, desired, *, method, **_kw):
        method.identify(*_records(np.linspace(1.0, 2.0, 40)))
        return types.SimpleNamespace(method=method, errors=[[0.0]], desired=desired)

    monkeypatch.setattr(vrig, "load_rig", lambda name, **_kw: types.SimpleNamespace(name=name))
    monkeypatch.setattr(vrig, "reconstruct", reconstruct)
    monkeypatch.setattr(thesis_tables.run, "_desired", lambda *_a: _records(np.ones(40))[1])
    table = Table(
        "Table X", "shaker", (0.0, 10.0), ["r"],
        [Row("text row", lambda: _Gain(fits)), Row("vrig: slow", lambda: _Gain(fits), quick=False)],
        "True", "",
    )  # fmt: skip
    kw = {"seconds": 1.0, "id_seconds": 1.0, "log": lambda *_: None}
    assert thesis_tables.run_table(table, cache={}, quick=True, **kw) == [[0.0], NOT_IN_QUICK]
    assert len(fits) == 1  # the slow row was not fitted
    assert thesis_tables.run_table(table, cache={}, **kw) == [[0.0], [0.0]]
    assert len(fits) == 3  # the full report fits both
