"""Rattlesnake transient control laws as vrig methods (issue 26, deliverable 2).

The laws are the pseudo-inverse law of ``tests/rattlesnake_laws.py`` in Rattlesnake's three forms
(function, generator, class), written from its published description. The rig is a 2 x 2 LTI
system of scipy filters whose FRF, and so whose exact inverse, is known in closed form: the
adapter's FRF is checked against the closed form, the law's drive against the drive that made
the desired response.
"""

from __future__ import annotations

import copy
import pickle
from pathlib import Path

import numpy as np
import pytest
import rattlesnake_laws as laws
from scipy import signal

import vrig
from vrig.reconstruction import RattlesnakeLaw, method_spec, reconstruct
from vrig.reconstruction.rattlesnake import FUNCTION_ARGUMENTS as _FUNCTION_ARGS
from vrig.signals import random_drive, triangular_psd

LAWS = Path(__file__).with_name("rattlesnake_laws.py")
FORMS = {"pinv_function": "function", "pinv_generator": "generator", "PinvClass": "class"}
FS = 200.0
BAND = (0.0, 20.0)


class _LtiRig:
    """Two drives, two responses: ``y1 = 0.4 z^-1 / (1 - 0.6 z^-1) u1 + 0.3 u2``,
    ``y2 = 0.5 z^-1 / (1 - 0.5 z^-1) u2 - 0.2 u1``; noise-free."""

    name = "lti-2x2"
    fs = FS
    bandwidth = BAND

    def __init__(self):
        from vrig.rigs import ChannelSpec

        self.inputs = tuple(ChannelSpec(n, "m", 1.0, "direct") for n in ("u1", "u2"))
        self.outputs = tuple(ChannelSpec(n, "N", 100.0, "load_cell") for n in ("y1", "y2"))

    def run(self, drive, *, seed=None):
        u = np.asarray(getattr(drive, "data", drive), dtype=float)
        y1 = signal.lfilter([0.0, 0.4], [1.0, -0.6], u[:, 0]) + 0.3 * u[:, 1]
        y2 = signal.lfilter([0.0, 0.5], [1.0, -0.5], u[:, 1]) - 0.2 * u[:, 0]
        return vrig.TimeHistory(np.column_stack([y1, y2]), self.fs, ["y1", "y2"], ["N", "N"])


def _frf(f_hz: np.ndarray) -> np.ndarray:
    """The rig's FRF (F, 2, 2) in closed form."""
    z = np.exp(-2j * np.pi * f_hz / FS)
    h = np.empty((f_hz.size, 2, 2), dtype=complex)
    h[:, 0, 0] = 0.4 * z / (1 - 0.6 * z)
    h[:, 0, 1] = 0.3
    h[:, 1, 0] = -0.2
    h[:, 1, 1] = 0.5 * z / (1 - 0.5 * z)
    return h


def _drive(seed: int, top_hz: float) -> vrig.TimeHistory:
    return random_drive(
        triangular_psd((0.0, top_hz)), 4000, FS, rms=0.05, seed=seed, channels=2, names=["u1", "u2"]
    )


@pytest.fixture(scope="module")
def case():
    rig = _LtiRig()
    id_drive = _drive(1, 25.0)
    truth = _drive(3, 15.0)  # the drive the desired response is the rig's response to
    return rig, id_drive, rig.run(id_drive), truth, rig.run(truth)


def _identified(name: str, case, **options) -> RattlesnakeLaw:
    _, iddrv, idres, _, _ = case
    method = method_spec(f"rattlesnake:{LAWS}:{name}", **options).method
    method.identify(iddrv, idres)
    return method


def _relative_error(x: np.ndarray, truth: np.ndarray, edge: int = 200) -> np.ndarray:
    """RMS of ``x - truth`` over RMS of ``truth``, per channel, the first and last ``edge``
    samples left out (the law's circular transform wraps the record's ends)."""
    e, t = x[edge:-edge] - truth[edge:-edge], truth[edge:-edge]
    return np.sqrt(np.mean(e**2, axis=0) / np.mean(t**2, axis=0))


# ---------------------------------------------------------------------------------------------
# the law's inputs and drive against the closed form
# ---------------------------------------------------------------------------------------------
@pytest.mark.parametrize("name", sorted(FORMS))
def test_each_form_inverts_the_lti_rig(name, case):
    # the pseudo-inverse of the exact FRF gives back the drive that made the desired response:
    # with the H1 estimate, within 2 % RMS on both channels
    method = _identified(name, case)
    assert method.form == FORMS[name]
    _, _, _, truth, desired = case
    drive = method.drive(desired)
    assert drive.shape == truth.data.shape
    assert np.all(_relative_error(drive, truth.data) < 0.02)


def test_the_three_forms_give_the_same_drive(case):
    _, _, _, _, desired = case
    drives = [_identified(name, case).drive(desired) for name in sorted(FORMS)]
    for d in drives[1:]:
        np.testing.assert_allclose(d, drives[0], rtol=0, atol=1e-12)


def test_the_law_is_given_vrigs_identification(case):
    _, iddrv, _, _, desired = case
    laws.CALLS.clear()
    # the law object itself (the file loaded by name is a module of its own, with its own CALLS)
    method = RattlesnakeLaw(laws.recording_function, nperseg=256, extra_parameters="rcond: 1e-4")
    method.identify(iddrv, case[2])
    method.drive(desired)
    (args,) = laws.CALLS
    got = dict(zip(vrig.reconstruction.rattlesnake.FUNCTION_ARGUMENTS, args, strict=True))
    assert got["sample_rate"] == FS and got["frequency_spacing"] == FS / 256
    np.testing.assert_array_equal(got["specification_signals"], desired.data.T)
    h = got["transfer_function"]
    f = np.arange(h.shape[0]) * got["frequency_spacing"]
    assert h.shape == (129, 2, 2)
    # inside the identification drive's band; not the DC line (Welch removes each frame's mean)
    inside = (f > 0) & (f <= 20.0)
    assert np.max(np.abs(h[inside] - _frf(f[inside]))) < 0.02
    assert np.all(got["multiple_coherence"][inside] > 0.99)  # noise-free and linear
    assert got["sysid_reference_cpsd"].shape == (129, 2, 2)
    assert got["sysid_response_cpsd"].shape == got["noise_response_cpsd"].shape == (129, 2, 2)
    assert not np.any(got["noise_reference_cpsd"])  # vrig's drive is known exactly
    # the CPSD of the identification drive integrates to its variance (Parseval, one-sided)
    var = np.real(np.trapezoid(np.einsum("fii->fi", got["sysid_reference_cpsd"]), f, axis=0))
    np.testing.assert_allclose(var, np.var(iddrv.data, axis=0), rtol=0.05)
    assert got["frames"] == got["total_frames"] == 1 + (4000 - 256) // 128
    assert got["output_oversample_factor"] == 1 and got["extra_parameters"] == "rcond: 1e-4"
    assert got["last_excitation_signals"] is None and got["last_response_signals"] is None


def test_the_iteration_gives_the_law_the_last_drive_and_response(case):
    rig, _, _, _, desired = case
    laws.CALLS.clear()
    res = reconstruct(
        rig,
        desired,
        method=RattlesnakeLaw(laws.recording_function),
        iterations=1,
        gain=1.0,
        bandwidth=BAND,
        seed=0,
    )
    first, later = laws.CALLS[0], laws.CALLS[-1]
    assert first[13] is None and first[14] is None  # IT00DRV: nothing played yet
    # the correction after IT00: the drive played and its processed response (model rate =
    # rig rate here), channels first
    np.testing.assert_allclose(later[13], res.drives[0].data.T, rtol=0, atol=1e-12)
    np.testing.assert_allclose(later[14], res.responses[0].data.T, rtol=0, atol=1e-12)


@pytest.mark.parametrize("name", sorted(FORMS))
def test_reconstruction_with_each_form_converges_on_the_lti_rig(name, case):
    # a linear rig and a model within 1 % of it: the error falls at every iteration (gain 1,
    # a contraction) and ends below 2 %
    rig, _, _, _, desired = case
    res = reconstruct(
        rig, desired, method=f"rattlesnake:{LAWS}:{name}", iterations=3, gain=1.0, bandwidth=BAND,
        seed=0,
    )  # fmt: skip
    eta = res.errors.mean(axis=1)
    assert np.all(np.diff(eta) < 0), eta
    assert eta[-1] < 2.0


def test_an_oversampled_law_is_taken_at_every_kth_sample(case):
    _, _, _, _, desired = case
    plain = _identified("pinv_function", case).drive(desired)
    over = _identified("pinv_function", case, oversample=2).drive(desired)
    # the same band-limited drive, but for its Nyquist line (the n-sample inverse FFT keeps its
    # real part, the 2n-sample one all of it): the difference is c (-1)^t, one c per channel
    alternating = (over - plain) * (-1.0) ** np.arange(plain.shape[0])[:, None]
    np.testing.assert_allclose(
        alternating, np.broadcast_to(alternating[:1], plain.shape), atol=1e-12
    )
    assert np.all(np.abs(alternating[0]) < 1e-3 * np.abs(plain).max(axis=0))


@pytest.mark.parametrize("name", ["pinv_generator", "PinvClass"])
def test_a_live_law_survives_copy_and_pickle(name, case):
    # the env's model cache deep-copies the identified method; the runner may pickle it
    _, _, _, _, desired = case
    method = _identified(name, case)
    want = method.drive(desired)  # a generator / object is live now
    for other in (copy.deepcopy(method), pickle.loads(pickle.dumps(method))):
        np.testing.assert_array_equal(other.drive(desired), want)


def test_a_class_law_is_told_of_a_new_identification(case):
    _, iddrv, idres, _, desired = case
    method = _identified("PinvClass", case)
    method.drive(desired)
    (live,) = method._live.values()
    method.identify(iddrv, idres)
    assert live.updates == 2  # __init__, then system_id_update


# ---------------------------------------------------------------------------------------------
# malformed laws: clear errors naming the law and what was expected
# ---------------------------------------------------------------------------------------------
@pytest.mark.parametrize(
    ("source", "error", "match"),
    [
        ("no_such_file.py:law", ValueError, "no_such_file.py.*no such file"),
        (f"{LAWS}:no_such_law", ValueError, "defines no 'no_such_law'.*pinv_function"),
        (f"{LAWS}", ValueError, r"rattlesnake:<file.py>:<name>"),
        (f"{LAWS}:too_few_arguments", TypeError, "too_few_arguments.*function law must take"),
        (f"{LAWS}:NoControl", TypeError, "NoControl.*needs the methods.*no control"),
        (f"{LAWS}:NOT_A_LAW", TypeError, "NOT_A_LAW.*int.*expected a function"),
    ],
)
def test_a_malformed_law_is_refused_when_loaded(source, error, match):
    with pytest.raises(error, match=match):
        method_spec(f"rattlesnake:{source}")


def test_a_law_file_that_fails_to_import_says_why(tmp_path):
    bad = tmp_path / "broken.py"
    bad.write_text("def law(:\n")
    with pytest.raises(ValueError, match=r"broken\.py.*could not be loaded: SyntaxError"):
        method_spec(f"rattlesnake:{bad}:law")


@pytest.mark.parametrize(
    ("name", "match"),
    [
        ("wrong_shape", r"wrong_shape.*returned shape \(4000, 1\).*expected.*\(2, 4000\)"),
        ("not_finite", "not_finite.*non-finite"),
    ],
)
def test_a_law_returning_a_bad_drive_is_a_value_error(name, match, case):
    _, _, _, _, desired = case
    with pytest.raises(ValueError, match=match):
        _identified(name, case).drive(desired)


def test_vocabulary_options_do_not_apply_to_a_law():
    with pytest.raises(ValueError, match="order does not apply to a Rattlesnake control law"):
        method_spec(f"rattlesnake:{LAWS}:pinv_function", order=4)


def test_the_cli_refuses_a_missing_law_file_as_a_usage_error(tmp_path, capsys):
    from vrig.cli import main

    argv = ["reconstruct", "--rig", "shaker", "--method", "rattlesnake:nowhere.py:law"]
    assert main([*argv, "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert err.startswith("vrig reconstruct: ") and "nowhere.py" in err and "no such file" in err
    assert not (tmp_path / "o").exists()


# ----------------------------------------------- issue 35, item 3: the law's options and errors
_RAISING_LAW = """
def law(sample_rate, specification_signals, frequency_spacing, transfer_function,
        noise_response_cpsd, noise_reference_cpsd, sysid_response_cpsd, sysid_reference_cpsd,
        multiple_coherence, frames, total_frames, output_oversample_factor, extra_parameters,
        last_excitation_signals, last_response_signals):
    spacing = sample_rate / frequency_spacing  # the frame length the law was given
    raise RuntimeError(f"got [{extra_parameters}] nperseg {spacing:g} x{output_oversample_factor}")
"""
_RAISING_LINE = 7  # the raise above, counted in the file written below (line 1 is empty)


def _cli_run(tmp_path, *extra):
    from vrig.cli import main

    (tmp_path / "raising.py").write_text(_RAISING_LAW, encoding="utf-8")
    argv = ["reconstruct", "--rig", "shaker", "--method",
            f"rattlesnake:{tmp_path / 'raising.py'}:law", "--seconds", "4", "--iterations", "1",
            "--out", str(tmp_path / "o"), *extra]  # fmt: skip
    return main(argv)


def test_a_law_error_names_the_laws_file_and_line_and_no_option_it_refuses(tmp_path, capsys):
    """A law that raises: the run fails (exit 1) with the law's own error, its file:line, and
    no hint about --order (an option a law refuses)."""
    params = tmp_path / "params.txt"
    params.write_text("Kp=0.5, rcond=1e-3", encoding="utf-8")
    code = _cli_run(tmp_path, "--law-parameters", f"@{params}", "--law-nperseg", "128",
                    "--law-oversample", "2")  # fmt: skip
    err = capsys.readouterr().err
    assert code == 7, err  # failed before any iteration: the law computes IT00DRV
    assert "RuntimeError: got [Kp=0.5, rcond=1e-3] nperseg 128 x2" in err
    assert f"raising.py:{_RAISING_LINE} in law" in err
    assert "--order" not in err


def test_law_options_are_refused_for_other_methods_and_unreadable_files(tmp_path, capsys):
    from vrig.cli import main

    argv = ["reconstruct", "--rig", "shaker", "--method", "arx", "--out", str(tmp_path / "a")]
    assert main([*argv, "--law-parameters", "x"]) == 2
    assert "--law-parameters applies to --method rattlesnake:FILE.py:NAME only" in (
        capsys.readouterr().err
    )
    assert _cli_run(tmp_path, "--law-parameters", f"@{tmp_path / 'missing.txt'}") == 2
    assert "cannot read it" in capsys.readouterr().err


def test_a_law_that_exits_or_changes_directory_loses_nothing(tmp_path, monkeypatch, case):
    """User code misbehaving: sys.exit inside a law is the law's error (the run goes on to
    save its folder, no interpreter exit); a law's os.chdir is undone after each call."""
    import os

    from vrig.errors import ControlLawError

    args = ", ".join(a for a in _FUNCTION_ARGS)
    law = tmp_path / "rude.py"
    law.write_text(
        f"import os, sys\ndef exits({args}):\n    sys.exit(3)\n"
        f"def moves({args}):\n    os.chdir({str(tmp_path)!r})\n    raise RuntimeError('moved')\n",
        encoding="utf-8",
    )
    here = tmp_path / "here"
    here.mkdir()
    monkeypatch.chdir(here)
    _, iddrv, idres, _, desired = case
    for name, match in (("exits", "SystemExit"), ("moves", "moved")):
        method = method_spec(f"rattlesnake:{law}:{name}").method
        method.identify(iddrv, idres)
        with pytest.raises(ControlLawError, match=match):
            method.drive(desired)
        assert os.getcwd() == str(here)
