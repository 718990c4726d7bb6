"""pytest-benchmark speed suite of the reconstruction pipeline (kept out of the default run).

The hot paths on real rig data — the shock-absorber rig's identification records, processed and
decimated as :class:`vrig.reconstruction.DriveIteration` does, and the inverse NARX(4,
quadratic) of the reconstruction — plus the rig and one complete drive iteration:

* ``regression_build``: the regression matrix of the inverse NARX (one drive channel);
* ``fit``: the inverse NARX fitted with each least-squares solver (same coefficients checked);
* ``free_run``: the fitted inverse model's free run over the desired response;
* ``rig_run``: a 10 s drive played on shock-absorber (full and fast fidelity) and a 5 s drive on
  fuel-tank-7ch;
* ``iteration``: one full reconstruction iteration (correction by the inverse model, drive
  update, limit check, rig run, GPREPRO, η0/RMS/damage scores).

The synthetic-problem suite of the identification package is ``test_identification_speed.py``.
Run both, save, and compare against the previous saved run::

    python -m benchmarks.compare_runs --run        # pytest --benchmark-autosave + compare
"""

from __future__ import annotations

import numpy as np
import pytest

import vrig
from identification import Narx, regression_matrix
from identification.solvers import SOLVERS
from vrig.desired.pseudo_field import pseudo_field
from vrig.reconstruction import DriveIteration
from vrig.reconstruction.defaults import default_band
from vrig.signals import random_drive, triangular_psd


@pytest.fixture(scope="module")
def engine():
    """A shock-absorber reconstruction identified, IT00 played (kernels compiled)."""
    rig = vrig.load_rig("shock-absorber", seed=0)
    band = default_band(rig)
    _drive, desired = pseudo_field(rig, band, 20.0, seed=0)
    it = DriveIteration(rig, desired, method="narx", bandwidth=band, seed=0)
    it.identify()
    drive = it.first_drive()
    _drv, _raw, res, _scores = it.play(drive, 0)
    # the processed model-rate records the inverse model is fitted on (response in, drive out)
    from vrig.processing import gprepro

    u = it.down(gprepro(it.id_response, it.id_band)).data
    y = it.down(gprepro(it.id_drive, it.id_band)).data
    return {"it": it, "drive": drive, "res": res, "u": u, "y": y}


def _drive(rig, seconds: float, fraction: float):
    full = np.array([c.full_scale for c in rig.inputs])
    return random_drive(
        triangular_psd(default_band(rig)),
        round(seconds * rig.fs),
        rig.fs,
        channels=len(rig.inputs),
        rms=fraction * full,
        seed=1,
        names=[c.name for c in rig.inputs],
        unit=rig.inputs[0].unit,
    )


@pytest.mark.benchmark(group="regression_build")
def test_regression_build(benchmark, engine):
    model = Narx(order=4, degree=2).fit(engine["u"], engine["y"])
    ch, start = model.channels_[0], model.max_lag_
    X = benchmark(regression_matrix, engine["u"], engine["y"], ch, start)
    assert X.shape == (engine["u"].shape[0] - start, ch.n_terms)


@pytest.mark.benchmark(group="fit")
@pytest.mark.filterwarnings("ignore::identification.IllConditionedWarning")
@pytest.mark.filterwarnings("ignore::identification.RankDeficiencyWarning")
@pytest.mark.parametrize("solver", sorted(SOLVERS))
def test_fit(benchmark, engine, solver):
    model = benchmark(lambda: Narx(order=4, degree=2, solver=solver).fit(engine["u"], engine["y"]))
    assert np.all(np.isfinite(model.coef_[0]))


@pytest.mark.benchmark(group="free_run")
def test_free_run(benchmark, engine):
    it = engine["it"]
    desres = it.down(it.desres)
    drive = benchmark(it.method.drive, desres)
    assert drive.shape == (desres.n_samples, 1)


@pytest.mark.benchmark(group="rig_run")
@pytest.mark.parametrize(
    "rig_name, fidelity, seconds",
    [
        ("shock-absorber", "full", 10.0),
        ("shock-absorber", "fast", 10.0),
        ("fuel-tank-7ch", "full", 5.0),
    ],
)
def test_rig_run(benchmark, rig_name, fidelity, seconds):
    rig = vrig.load_rig(rig_name, seed=0, fidelity=fidelity)
    drive = _drive(rig, seconds, 0.02)
    rig.run(drive, seed=0)  # warm-up
    out = benchmark.pedantic(rig.run, args=(drive,), kwargs={"seed": 0}, rounds=3, iterations=1)
    assert out.n_samples == drive.n_samples


@pytest.mark.benchmark(group="iteration")
def test_reconstruction_iteration(benchmark, engine):
    it, drive, res = engine["it"], engine["drive"], engine["res"]

    def one_iteration():
        new = it.next_drive(drive, res, 0.8)
        return it.play(new, 1)

    _drv, _raw, _res, (eta0, _rms, _dmg) = benchmark.pedantic(one_iteration, rounds=3, iterations=1)
    assert np.all(np.isfinite(eta0))
