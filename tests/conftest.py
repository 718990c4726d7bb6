"""Shared fixtures: seeded data from known generating systems.

Property-based (hypothesis) tests run derandomized by default, so the README's test command
gives the same verdict on every machine; ``HYPOTHESIS_PROFILE=explore python -m pytest ...``
draws fresh random examples (and keeps a failing one in ``.hypothesis/`` to replay): that is how
to hunt for new bad inputs.
"""

from __future__ import annotations

import os

import numpy as np
import pytest
from hypothesis import settings

from identification import band_limited_noise, random_narx

settings.register_profile("deterministic", derandomize=True, database=None, print_blob=True)
settings.register_profile("explore", print_blob=True)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "deterministic"))


@pytest.fixture(scope="session")
def cubic_2x2():
    """A random stable 2-output, 2-input cubic NARX of order 2 and its noise-free data."""
    model = random_narx(2, 2, 2, 3, seed=11)
    u = band_limited_noise(3000, 2, cutoff=0.3, seed=12)
    y = model.simulate(u)
    return model, u, y


@pytest.fixture
def rng():
    return np.random.default_rng(1234)


def pytest_collection_modifyitems(config, items):
    """``@pytest.mark.slow`` tests run only when asked for (``-m slow``)."""
    if "slow" in (config.option.markexpr or ""):
        return
    skip = pytest.mark.skip(reason="slow: run with -m slow")
    for item in items:
        if "slow" in item.keywords:
            item.add_marker(skip)
