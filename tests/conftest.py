"""Shared fixtures: small scenarios that keep the suite fast."""

from __future__ import annotations

import os

os.environ.setdefault("MPLBACKEND", "Agg")
# One BLAS/OpenMP thread, as the CLI sets: small dense solves are far slower oversubscribed.
for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import pytest  # noqa: E402

from pipeline.config import Scenario, load_scenario  # noqa: E402
from pipeline.before_work.domains import resolve  # noqa: E402

SMALL_OVERRIDES = {
    "loading.n_delta": 6,
    "contact.n_radial": 160,
    "oxide.xi": [0.2, 0.5, 0.8],
    "oxide.lambda": [1.0, 5.0, 13.0],
    "oxide.ensemble": "fixed",
    "oxide.n_realizations": 8,
    "oxide.chunk": 3,
    "cube.chunk": 3,
    "fits.n_bootstrap": 50,
}


@pytest.fixture(scope="session")
def paper() -> Scenario:
    """The default scenario, unchanged."""
    return resolve(load_scenario("paper"))


@pytest.fixture(scope="session")
def small() -> Scenario:
    """The paper scenario shrunk to a few approaches, fractions, lengths and realizations."""
    return resolve(load_scenario("paper", SMALL_OVERRIDES))
