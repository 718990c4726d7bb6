"""The Rig and Method contracts (typing.Protocol): every shipped rig class and registered method
satisfies its protocol, a user's class written only against a protocol works with
vrig.reconstruct and with the benchmark runner, and the runner uses only the protocols."""

from __future__ import annotations

import ast
import inspect
from pathlib import Path
from typing import ClassVar

import numpy as np
import pytest

import vrig
from benchmarks.runner import record as record_module
from benchmarks.runner.record import RecordKey, Settings, compute_record
from benchmarks.runner.registry import (
    _REGISTRY,
    default_plugin_specs,
    get_method,
    load_plugins,
    method_names,
    register_method,
)
from vrig.reconstruction import (
    InverseArx,
    InverseFrf,
    InverseModelMethod,
    InverseNarx,
    Method,
    SizedMethod,
    SplitSpectra,
    reconstruct,
)
from vrig.rigs import ChannelSpec, DescribedRig, FileRig, MujocoRig, OutputSubset, Rig
from vrig.signals import flat_psd, random_drive
from vrig.timehistory import TimeHistory

ROOT = Path(__file__).resolve().parents[1]
FS = 512.0


def _positional(func) -> list[str]:
    """Names of the parameters a bound method takes positionally."""
    kinds = (inspect.Parameter.POSITIONAL_ONLY, inspect.Parameter.POSITIONAL_OR_KEYWORD)
    return [p.name for p in inspect.signature(func).parameters.values() if p.kind in kinds]


def _accepts_seed_keyword(run) -> bool:
    params = inspect.signature(run).parameters
    seed = params.get("seed")
    if seed is not None:
        return seed.kind != inspect.Parameter.POSITIONAL_ONLY and seed.default is None
    return any(p.kind == inspect.Parameter.VAR_KEYWORD for p in params.values())


def _check_method_signatures(method) -> None:
    assert len(_positional(method.identify)) == 2, "identify(iddrv, idres)"
    assert len(_positional(method.drive)) == 1, "drive(response)"
    assert _positional(method.describe) == [], "describe()"


# ---------------------------------------------------------------------------------------------
# rigs
# ---------------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def shock():
    return vrig.load_rig("shock-absorber", fidelity="fast")


def _file_rig(tmp_path) -> FileRig:
    ch_in = ChannelSpec("act", "m", 0.01, "hydraulic")
    ch_out = ChannelSpec("load", "N", 1000.0, "load_cell")
    return FileRig(tmp_path, [ch_in], [ch_out], FS, respond=lambda p: p)


def test_every_shipped_rig_class_is_a_rig(shock, tmp_path):
    subset = OutputSubset(shock, [shock.outputs[0].name])
    rigs = {MujocoRig: shock, FileRig: _file_rig(tmp_path), OutputSubset: subset}
    for cls, rig in rigs.items():
        assert isinstance(rig, cls)
        assert isinstance(rig, Rig), cls.__name__
        assert _accepts_seed_keyword(rig.run), f"{cls.__name__}.run(drive, *, seed=None)"
        assert len(_positional(rig.run)) == 1, f"{cls.__name__}.run(drive, ...)"
        assert isinstance(rig.name, str) and rig.fs > 0
        assert all(isinstance(c, ChannelSpec) for c in (*rig.inputs, *rig.outputs))
        lo, hi = rig.bandwidth
        assert 0 <= lo < hi <= rig.fs / 2
    assert isinstance(shock, DescribedRig) and isinstance(subset, DescribedRig)
    assert _positional(shock.describe) == []
    assert not isinstance(_file_rig(tmp_path), DescribedRig)  # FileRig has no describe()


def test_an_object_without_run_is_not_a_rig(tmp_path):
    class NoRun:
        name, fs, inputs, outputs, bandwidth = "x", FS, (), (), (0.0, 10.0)

    assert not isinstance(NoRun(), Rig)
    assert not isinstance(object(), Rig)


# ---------------------------------------------------------------------------------------------
# methods
# ---------------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def all_methods():
    """The shipped methods: the built-ins and those of benchmarks/plugins (other tests register
    deliberately broken ones in the same process)."""
    specs = default_plugin_specs()
    load_plugins(specs)
    shipped = {"builtin"} | {name for _kind, name, _src in specs}
    return [n for n in method_names() if get_method(n).origin in shipped]


def test_every_registered_method_is_a_method(shock, all_methods):
    band = shock.bandwidth
    assert {"arx", "narx", "narx-ip", "error-signal", "split", "frf", "fir"} <= set(all_methods)
    for name in all_methods:
        plugin = get_method(name)
        for obj in (plugin.make(shock, band), plugin.make_forward(shock, band)):
            assert isinstance(obj, Method), f"{name}: {type(obj).__name__}"
            _check_method_signatures(obj)
            assert isinstance(obj, SizedMethod), f"{name}: {type(obj).__name__} has no model_size"
    for name in ("arx", "narx", "narx-ip", "narx-sim", "error-signal", "split"):
        assert isinstance(get_method(name).make(shock, band), InverseModelMethod), name
    assert not isinstance(InverseFrf(), InverseModelMethod)  # no lead: a frequency-domain inverse


def _siso_records(n=4096, delay=3, seed=0):
    """A known linear SISO system: y(t) = 0.5 y(t-1) + u(t - delay)."""
    u = np.random.default_rng(seed).standard_normal(n)
    y = np.zeros(n)
    for t in range(n):
        y[t] = (0.5 * y[t - 1] if t else 0.0) + (u[t - delay] if t >= delay else 0.0)
    return (
        TimeHistory(u[:, None], FS, ["u"], ["V"]),
        TimeHistory(y[:, None], FS, ["y"], ["V"]),
    )


def test_lead_capability_fixes_and_reports_the_lead():
    u, y = _siso_records()
    m = InverseArx(2)
    assert m.fitted_lead() is None and m.model_size() is None  # not identified
    m.set_lead(5)
    m.identify(u, y)
    assert m.fitted_lead() == 5  # the lead it was told to use, no search
    # full-order SISO ARX(n) inverse (eq. 4-15): n past drives + n + 1 responses = 2n + 1 terms
    assert m.model_size() == 2 * 2 + 1
    with pytest.raises(ValueError, match="lead"):
        m.set_lead(-1)
    with pytest.raises(ValueError, match="lead"):
        m.set_lead(1.5)


def test_split_spectra_lead_and_size_are_its_bands():
    u, y = _siso_records()
    s = SplitSpectra(40.0, low=InverseArx(2), high=InverseNarx(2, 2))
    assert s.fitted_lead() == {"low": None, "high": None}
    assert s.model_size() is None
    s.set_lead({"low": 4, "high": 6})
    s.identify(u, y)
    assert s.fitted_lead() == {"low": 4, "high": 6}
    assert s.model_size() == s.low.model_size() + s.high.model_size()
    s.set_lead(0)  # one value for both bands
    assert (s.low.lead, s.high.lead) == (0, 0)
    with pytest.raises(ValueError, match="bands"):
        s.set_lead({"middle": 1})
    frf_bands = SplitSpectra(40.0, low=InverseFrf(nperseg=64), high=InverseArx(2))
    frf_bands.set_lead({"low": 3, "high": 2})  # the FRF band has no lead: left alone
    assert frf_bands.high.lead == 2 and frf_bands.fitted_lead()["low"] is None


def test_frf_size_is_two_reals_per_inverse_frf_entry():
    u, y = _siso_records()
    m = InverseFrf(nperseg=256)
    m.identify(u, y)
    # Welch, 256-sample segments: 256 // 2 + 1 one-sided lines, 1 x 1 complex inverse each
    assert m.model_size() == 2 * (256 // 2 + 1)


# ---------------------------------------------------------------------------------------------
# a user's method written only against the protocol
# ---------------------------------------------------------------------------------------------
class GainInverse:
    """A static least-squares inverse: drive = response @ G (a user class, protocol only)."""

    def identify(self, iddrv, idres):
        self.g, *_ = np.linalg.lstsq(idres.data, iddrv.data, rcond=None)

    def drive(self, response):
        return response.data @ self.g

    def describe(self):
        return f"static gain inverse {self.g.ravel().tolist()}"


class LeadUser(GainInverse):
    """A user inverse with the lead capability and nothing else of vrig's classes (no ``lead``
    or ``max_lead`` attributes): records what the runner asks of it."""

    calls: ClassVar[list] = []

    def __init__(self, role):
        self.role = role
        self._lead = "auto"

    def identify(self, iddrv, idres):
        super().identify(iddrv, idres)
        self._fitted = 7 if self._lead == "auto" else self._lead

    def fitted_lead(self):
        return getattr(self, "_fitted", None)

    def set_lead(self, lead):
        LeadUser.calls.append((self.role, lead))
        self._lead = lead

    def model_size(self):
        return int(self.g.size)


def test_a_user_method_written_against_the_protocol_reconstructs():
    rig = vrig.load_rig("shaker", seed=0)
    d = random_drive(
        flat_psd((0.0, 50.0)), int(8 * rig.fs), rig.fs, rms=0.5, seed=7,
        names=[c.name for c in rig.inputs], unit="V",
    )  # fmt: skip
    desired = rig.run(d, seed=99)
    method = GainInverse()
    assert isinstance(method, Method) and not isinstance(method, SizedMethod)
    res = reconstruct(rig, desired, method=method, iterations=1, bandwidth=(10.0, 60.0), seed=1)
    assert res.errors.shape == (2, 1) and np.all(np.isfinite(res.errors))
    assert res.method is method and method.describe().startswith("static gain inverse")


SETTINGS = Settings(seconds=4.0, iterations=1, fidelity="fast")


@pytest.fixture
def user_methods():
    register_method("proto-gain", lambda: GainInverse(), description="protocol test")
    register_method(
        "proto-lead",
        lambda: LeadUser("inverse"),
        forward=lambda: LeadUser("forward"),
        description="protocol test",
    )
    yield
    _REGISTRY.pop("proto-gain", None)
    _REGISTRY.pop("proto-lead", None)


def test_the_runner_records_a_user_method(user_methods):
    rec = compute_record(RecordKey("shock-absorber", "proto-gain", 0, 0), SETTINGS)
    assert rec["status"] == "ok", rec["error"]
    assert rec["method_description"].startswith("static gain inverse")
    assert rec["model_size"] is None  # no model_size(): not a SizedMethod
    assert rec["inverse_model_error"] is not None and rec["normal_model_error"] is not None


def test_the_runner_pins_leads_through_the_protocol(user_methods):
    LeadUser.calls.clear()
    rec = compute_record(RecordKey("shock-absorber", "proto-lead", 0, 0), SETTINGS)
    assert rec["status"] == "ok", rec["error"]
    assert rec["model_size"] == 1  # 1 response x 1 drive gain
    # the fresh inverse of the modelling error keeps the reconstruction's lead (7, searched),
    # the forward model is made causal
    assert LeadUser.calls == [("inverse", 7), ("forward", 0)]


def test_the_runner_uses_only_public_names_and_no_attribute_poking():
    for path in sorted((ROOT / "benchmarks" / "runner").glob("*.py")):
        tree = ast.parse(path.read_text())
        for node in ast.walk(tree):
            if isinstance(node, ast.ImportFrom) and (node.module or "").startswith(
                ("vrig", "identification")
            ):
                private = [a.name for a in node.names if a.name.startswith("_")]
                assert not private, f"{path.name} imports private {private} from {node.module}"
    source = inspect.getsource(record_module)
    assert "hasattr(" not in source
