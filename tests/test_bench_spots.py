"""The spots benchmark: Barber's check of Greenwood-Tripp's grid discretizations, on any scenario."""

from __future__ import annotations

import numpy as np
import xarray as xr

from g2tom import contact_solution
from g2tom.before_work.domains import resolve
from g2tom.bench import spots
from g2tom.before_work import load_scenario
from g2tom.stages import contact
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


def test_discretizations_on_one_domain_share_one_solve_equal_to_solving_each(monkeypatch) -> None:
    """expected and asperities resolve to the same window and radial domain: inside shared_solves
    their contact datasets come from one Greenwood-Tripp solve, bit for bit those of two solves."""
    chosen = [spots._with_spots(resolve(load_scenario("paper_gt", SMALL_OVERRIDES)), name)
              for name in ("expected", "asperities")]
    alone = [contact.build(s) for s in chosen]
    solves: list[int] = []
    real = contact_solution._solve
    monkeypatch.setattr(contact_solution, "_solve", lambda *args: solves.append(1) or real(*args))
    with contact_solution.shared_solves():
        shared = [contact.build(s) for s in chosen]
    assert len(solves) == 1
    for one, other in zip(alone, shared):
        xr.testing.assert_identical(one, other)
    contact.build(chosen[0])
    assert len(solves) == 2  # outside the block every build solves
