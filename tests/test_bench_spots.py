"""The spots benchmark: Barber's check of Greenwood-Tripp's grid discretizations, on any scenario."""

from __future__ import annotations

import numpy as np

from g2tom.before_work.domains import resolve
from g2tom.bench import spots
from g2tom.before_work import load_scenario
from tests.conftest import SMALL_OVERRIDES


def test_a_discrete_scenario_benchmarks_greenwood_tripps_three_discretizations(monkeypatch) -> None:
    """On the discrete default the benchmark solved the discrete pool once per discretization and
    gave the same ratios three times (the pool's against Greenwood-Tripp's K: 1.43 at the paper's
    lightest load); it must check each grid discretization on Greenwood-Tripp's contact, as on paper_gt."""
    monkeypatch.setattr(spots, "_per_map_seconds", lambda scenario, contact_ds: 1.0)  # the ratios, not the timing
    discrete = spots.run(resolve(load_scenario("paper", {**SMALL_OVERRIDES, "contact.surfaces": 4})))
    grid = spots.run(resolve(load_scenario("paper_gt", SMALL_OVERRIDES)))
    for name in ("mean_area", "expected", "asperities"):
        for model, ratio in grid[name]["barber_ratio"].items():
            np.testing.assert_allclose(discrete[name]["barber_ratio"][model], ratio, rtol=1e-9, err_msg=name)
    expected = np.asarray(discrete["expected"]["barber_ratio"]["greenwood"])
    mean_area = np.asarray(discrete["mean_area"]["barber_ratio"]["greenwood"])
    assert np.max(np.abs(expected - 1.0)) <= spots.TARGETS["expected"]  # Barber-consistent spots
    assert np.max(np.abs(mean_area - 1.0)) > 0.1  # the paper's mean-area spots are not: the three differ
    assert discrete["met"]["expected_greenwood"]
