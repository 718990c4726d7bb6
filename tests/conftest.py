"""Shared fixtures: seeded data from known generating systems."""

from __future__ import annotations

import numpy as np
import pytest

from identification import band_limited_noise, random_narx


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
