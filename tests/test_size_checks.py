"""Sizes are checked before anything is allocated (issue #11, item 4).

Every case the issue lists (a degree-10 NARX on 4 inputs / 3 outputs, term counts with a huge
degree or order, a demo of 1e9 samples) must be refused within a fraction of a second, with a
message that names the size; the expected sizes are computed here independently (math.comb).
"""

from __future__ import annotations

import math
import tracemalloc

import numpy as np
import pytest

import identification.budget
import vrig
from identification import (
    IdentificationError,
    InsufficientDataError,
    MemoryBudgetError,
    Narx,
    band_limited_noise,
    forward_regression,
    regression_matrix,
    term_count,
)
from identification.output_error import FlatModel, refine
from identification.structure import full_order_regressors, polynomial_terms
from vrig.cli import main
from vrig.signals import flat_psd, random_drive, sine_sweep

ALLOCATED = 64 * 2**20  # bytes: a refusal allocates nothing large (traced peak)


def _refused(call, error=IdentificationError):
    """Run ``call``; it must raise ``error`` before allocating anything large (the traced
    peak stays below ALLOCATED; speed belongs in benchmarks/). Returns the message."""
    tracemalloc.start()
    try:
        with pytest.raises(error) as info:
            call()
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < ALLOCATED
    return str(info.value)


def _sci(n: int) -> str:
    """``n`` as the three significant digits and exponent of its decimal form."""
    s = str(n)
    return f"{s[0]}.{s[1:3]}e+{len(s) - 1}"


def test_term_count_with_a_huge_degree_is_refused_naming_the_count():
    # R = 3*4 + 4*5 = 32 regressors; today: RecursionError
    msg = _refused(lambda: term_count(3, 4, 4, 10**4))
    assert _sci(math.comb(32 + 10**4, 10**4) - 1) in msg and "terms" in msg
    assert "GiB" in msg


def test_term_count_with_a_huge_order_is_refused_naming_the_count():
    # R = 10**6 + 10**6 + 1; today: hangs in the nested sums
    msg = _refused(lambda: term_count(1, 1, 10**6, 3))
    assert _sci(math.comb(2 * 10**6 + 1 + 3, 3) - 1) in msg and "terms" in msg


def test_a_degree_10_narx_on_4_inputs_and_3_outputs_is_refused_before_building():
    rng = np.random.default_rng(0)
    u, y = rng.standard_normal((3000, 4)), rng.standard_normal((3000, 3))
    msg = _refused(lambda: Narx(order=4, degree=10).fit(u, y))
    assert f"{math.comb(42, 10) - 1:,} terms" in msg  # 1.5e9 (today: killed for memory)
    assert "regression matrix" in msg and "GiB" in msg and "degree" in msg


def test_polynomial_terms_refuses_a_table_beyond_the_budget_without_enumerating():
    regs = full_order_regressors(3, 4, 4)
    msg = _refused(lambda: polynomial_terms(regs, 10))
    assert f"{math.comb(42, 10) - 1:,} terms x 10 factors" in msg


def test_an_order_beyond_the_record_is_refused_before_the_regressors_are_built():
    rng = np.random.default_rng(1)
    u, y = rng.standard_normal(500), rng.standard_normal(500)
    msg = _refused(lambda: Narx(order=10**7, degree=2).fit(u, y), InsufficientDataError)
    assert "10000000" in msg and "500" in msg
    msg = _refused(lambda: Narx(na=1, nb=2, nk=10**15).fit(u, y), InsufficientDataError)
    assert "1000000000000001" in msg


def test_fit_checks_rows_x_terms_x_8_bytes_against_the_one_budget(monkeypatch):
    # order 2, cubic, 3 outputs and 2 inputs: R = 12, C(15, 3) - 1 = 454 terms per channel;
    # 20000 samples minus the largest lag 2: a regression matrix of 19998 x 454 x 8 = 72.6 MB
    monkeypatch.setattr(identification.budget, "MEMORY_BUDGET_BYTES", 64 * 2**20)
    rng = np.random.default_rng(2)
    u, y = rng.standard_normal((20_000, 2)), rng.standard_normal((20_000, 3))
    # MemoryBudgetError: an IdentificationError a caller can tell apart (and retry with less data)
    msg = _refused(lambda: Narx(order=2, degree=3).fit(u, y), error=MemoryBudgetError)
    assert "19,998 rows x 454 terms x 8 bytes" in msg
    assert f"{19_998 * 454 * 8 / 2**20:.3g} MiB" in msg and "64 MiB" in msg
    assert "shorter" in msg  # what to change


def test_every_large_array_obeys_the_same_budget(monkeypatch):
    rng = np.random.default_rng(3)
    u, y = rng.standard_normal((4000, 1)), rng.standard_normal((4000, 1))
    # R = 2 + 3 = 5 regressors, C(7, 2) - 1 = 20 terms: X is 3998 x 20 x 8 bytes = 640 kB
    model = Narx(order=2, degree=2).fit(u, y)
    ch = model.channels_[0]
    X = regression_matrix(u, y, ch, 2)
    flat = FlatModel.from_channels(model.channels_, 1, 1)
    monkeypatch.setattr(identification.budget, "MEMORY_BUDGET_BYTES", 100_000)
    assert "3,998 rows x 20 terms" in _refused(lambda: regression_matrix(u, y, ch, 2))
    assert "3,998 rows x 20 candidate terms" in _refused(lambda: forward_regression(X, y[2:, 0]))
    msg = _refused(lambda: refine(flat, np.concatenate(model.coef_), u, y))
    assert "Jacobian (3,998 residuals x 20 parameters" in msg


def test_generated_signals_are_bounded_before_allocation():
    msg = _refused(lambda: band_limited_noise(10**9, 2))
    assert "1,000,000,000 samples x 2 channels" in msg
    msg = _refused(lambda: random_drive(flat_psd((0, 10)), 10**10, 100.0), ValueError)
    assert "10,000,000,000 samples" in msg
    msg = _refused(lambda: sine_sweep(1, 10, 1e9, 1000.0), ValueError)
    assert "1,000,000,000,000 samples" in msg
    with pytest.raises(ValueError, match="n_samples must be an integer"):
        random_drive(flat_psd((0, 10)), 1e3, 100.0)
    with pytest.raises(ValueError, match="duration"):
        sine_sweep(1, 10, float("nan"), 1000.0)


def _refused_exit(call) -> int:
    """``call()``'s exit status, checking it allocated nothing large on the way."""
    tracemalloc.start()
    try:
        status = call()
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < ALLOCATED
    return status


@pytest.mark.parametrize("samples", ["1e9", "1000000000"])
def test_demo_refuses_a_record_beyond_its_bound(capsys, samples):
    assert _refused_exit(lambda: main(["demo", "--samples", samples])) == 2
    err = capsys.readouterr().err
    assert "--samples must be >= 2000 and <= 100000" in err and "1000000000" in err


def test_cli_seeds_must_be_non_negative(capsys):
    assert main(["demo", "--seed", "-1"]) == 2
    assert "--seed must be an integer >= 0, got -1" in capsys.readouterr().err


def test_reconstruct_refuses_a_desired_record_longer_than_an_hour(tmp_path, capsys, monkeypatch):
    n = 3601 * 500  # the shaker runs at 500 Hz
    desired = vrig.TimeHistory(np.zeros(n), 500.0, ["shaft_acc"], ["m/s^2"])
    path = desired.save(tmp_path / "long.npz")

    def never(*_args, **_kwargs):
        raise AssertionError("the rig was run for a refused record")

    monkeypatch.setattr(vrig.rigs.MujocoRig, "run", never)  # nothing may be played
    code = main(
        ["reconstruct", "--rig", "shaker", "--desired", str(path), "--out", str(tmp_path / "out")]
    )
    assert code == 2
    err = capsys.readouterr().err
    assert "3601 s long" in err and "at most 3600 s" in err and "--seconds" in err
