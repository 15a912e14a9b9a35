"""The biases benchmark takes a step's contact from the contact stage's file where the file holds it:
a smaller pool read from contact.nc equals the pool solved, bit for bit."""

from __future__ import annotations

from pathlib import Path

import pytest
import xarray as xr

from g2tom.before_work import load_scenario
from g2tom.before_work.domains import resolve
from g2tom.bench import biases
from g2tom.compute import ComputeOptions
from g2tom.config import ResolvedScenario
from g2tom.stages import contact
from g2tom.store import read_stage
from tests.conftest import SMALL_OVERRIDES

#: The small scene on the default's discrete pool, of 6 surfaces.
STORED = {**SMALL_OVERRIDES, "contact.surfaces": 6}


@pytest.fixture(scope="module")
def stored(tmp_path_factory) -> tuple[ResolvedScenario, xr.Dataset]:
    """The small discrete scenario and its contact.nc as the contact stage wrote it, read back."""
    scenario = resolve(load_scenario("paper", STORED))
    data = tmp_path_factory.mktemp("data")
    contact.run(scenario, data, ComputeOptions(progress=False))
    return scenario, read_stage(data, "contact", scenario)


@pytest.mark.parametrize("surfaces", [1, 4, 6])  # 1: narrower spots than the file's widest surface
def test_a_pool_read_from_contact_nc_equals_the_pool_solved(stored, surfaces: int) -> None:
    """Tolerance: none. The first surfaces, their spots padded to their own largest count, the
    Greenwood-Tripp fields and the attributes of a solve, without the file's provenance."""
    scenario, dataset = stored
    wanted = resolve(load_scenario("paper", {**STORED, "contact.surfaces": surfaces}))
    read = biases.stored_contact(scenario, dataset, wanted)
    solved = contact.build(wanted)
    xr.testing.assert_identical(read, solved)
    assert all(read[name].values.flags.c_contiguous for name in read.data_vars)  # as fast to read as solved


@pytest.mark.parametrize("change", [
    {"contact.surfaces": 7},  # more surfaces than the file holds
    {"oxide.seed": 1},  # another pool: the surfaces are drawn from the oxide's seed
    {"contact.n_radial": 161},  # another Greenwood-Tripp solve
    {"contact.pool_half_width": 0.05},  # a grown pool is not a prefix of a larger one
    {"contact.model": "greenwood_tripp", "oxide.spot_rule": "centre"},  # no pool at all
])
def test_a_contact_the_file_does_not_hold_is_solved(stored, change: dict) -> None:
    scenario, dataset = stored
    wanted = resolve(load_scenario("paper", {**STORED, "contact.surfaces": 4, **change}))
    assert biases.stored_contact(scenario, dataset, wanted) is None


def test_without_a_current_contact_file_every_step_is_solved(stored, tmp_path: Path) -> None:
    scenario, _ = stored
    assert biases._stored(scenario, None) is None
    assert biases._stored(scenario, tmp_path) is None  # no contact.nc
    other = resolve(load_scenario("paper", {**STORED, "contact.surfaces": 5}))
    contact.run(other, tmp_path, ComputeOptions(progress=False))
    assert biases._stored(scenario, tmp_path) is None  # built for another scenario
    found, dataset = biases._stored(other, tmp_path)
    assert found == other and dataset.sizes["surface"] == 5
