"""Identification demo: a generated non-linear MIMO system identified and simulated.

Run with ``vrig demo`` (or ``python -m vrig.demo``): a quick look at the identification library
on its own; it prints per-channel free-run errors (QanTiM η0, eq. 5-28) and the timings of the
fit and the free-run simulation.
"""

from __future__ import annotations

import time
import warnings

import numpy as np

from identification import Narx, band_limited_noise, metrics, random_narx
from identification.errors import IllConditionedWarning, RankDeficiencyWarning, StabilityWarning

__all__ = ["MAX_SAMPLES", "MIN_SAMPLES", "run_demo"]

MIN_SAMPLES = 2000
"""Shortest demo record: the cubic model has 454 terms per output."""
MAX_SAMPLES = 100_000  # the cubic model regresses on 454 terms per output
"""Longest demo record: its regression matrix (375,000 identification rows x 454 terms x 8 bytes =
1.3 GB) stays within the identification package's 2 GiB memory budget per array."""


_FIT_WARNINGS = (StabilityWarning, RankDeficiencyWarning, IllConditionedWarning)


def _row(cells, widths):
    return "  ".join(f"{c:>{w}}" for c, w in zip(cells, widths, strict=True))


def run_demo(*, seed: int = 0, n_samples: int = 20_000, noise: float = 0.01) -> dict:
    """Identify a random stable 3-output, 2-input cubic NARX (order 2) and print the figures.

    Returns the figures as a dict (errors in %, times in seconds).

    Parameters
    ----------
    seed : int, optional
        Seed of the random model, input and noise.
    n_samples : int, optional
        Length of the identification record (``MIN_SAMPLES .. MAX_SAMPLES``).
    noise : float, optional
        Output noise RMS as a fraction of each output's standard deviation, in [0, 1).

    Raises
    ------
    ValueError
        ``n_samples`` outside ``MIN_SAMPLES .. MAX_SAMPLES``, or ``noise`` outside [0, 1),
        checked before anything is generated.
    """
    if (
        not isinstance(n_samples, (int, np.integer))
        or isinstance(n_samples, bool)
        or not MIN_SAMPLES <= n_samples <= MAX_SAMPLES
    ):
        raise ValueError(
            f"n_samples must be an integer >= {MIN_SAMPLES} and <= {MAX_SAMPLES:,} (the "
            f"regression matrix of a longer record exceeds the memory budget), got {n_samples!r}"
        )
    if not (np.isfinite(noise) and 0 <= noise < 1):
        raise ValueError(f"noise must be a fraction in [0, 1), got {noise!r}")
    rng = np.random.default_rng(seed)
    truth = random_narx(3, 2, 2, 3, seed=rng)
    u = band_limited_noise(n_samples, 2, cutoff=0.3, seed=rng)
    y_clean = truth.simulate(u)
    y = y_clean + noise * y_clean.std(axis=0) * rng.standard_normal(y_clean.shape)
    n_id = n_samples * 3 // 4

    print(
        f"system: random stable NARX, 2 inputs -> 3 outputs, order 2, cubic "
        f"({truth.n_terms_[0]} terms per output), {noise:.0%} output noise, seed {seed}"
    )
    print(f"data:   {n_id} identification + {n_samples - n_id} validation samples\n")

    t0 = time.perf_counter()
    with warnings.catch_warnings(record=True) as caught:  # reported below, as one line each
        warnings.simplefilter("always")
        model = Narx(order=2, degree=3).fit(u[:n_id], y[:n_id])
    t_fit = time.perf_counter() - t0
    notes = _notes(caught)
    t0 = time.perf_counter()
    # free run from the validation record's own first outputs (no start-up transient)
    y_sim = model.simulate(u[n_id:], y0=y[n_id : n_id + model.max_lag_])
    t_sim = time.perf_counter() - t0
    eta0 = metrics.qantim_fit_dc(y_clean[n_id:], y_sim)
    fit = metrics.fit_percent(y_clean[n_id:], y_sim)

    widths = (8, 8, 14, 10)
    print("forward model, free run on validation data (against the noise-free output)")
    print(_row(("channel", "terms", "η0 eq.5-28 %", "fit %"), widths))
    for k in range(3):
        print(
            _row(
                (model.output_names_[k], model.n_terms_[k], f"{eta0[k]:.3f}", f"{fit[k]:.2f}"),
                widths,
            )
        )
    print(
        f"\nfit:        {t_fit * 1e3:8.1f} ms  ({n_id} samples, solver 'qr', "
        "one factorisation for all 3 outputs)"
    )
    print(
        f"free run:   {t_sim * 1e3:8.1f} ms  ({(n_samples - n_id) / t_sim / 1e6:.2f} M samples/s)"
    )
    for note in notes:
        print(f"note:       {note}")
    return {
        "eta0": eta0.tolist(),
        "fit_percent": fit.tolist(),
        "t_fit": t_fit,
        "t_sim": t_sim,
        "warnings": notes,
    }


def _notes(caught) -> list[str]:
    """The identification warnings of the fit as one line each (``StabilityWarning: ...``);
    any other warning is passed on unchanged."""
    notes = []
    for w in caught:
        if issubclass(w.category, _FIT_WARNINGS):
            notes.append(f"{w.category.__name__}: " + " ".join(str(w.message).split()))
        else:
            warnings.warn_explicit(w.message, w.category, w.filename, w.lineno, source=w.source)
    return notes


if __name__ == "__main__":  # pragma: no cover
    run_demo()
