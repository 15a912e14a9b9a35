"""Domains from the solution: auto windows and radial domains, and refused truncations."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from g2tom.before_work import domains
from g2tom.config import AUTO, ConfigError, ResolvedScenario, Scenario
from g2tom.before_work import load_scenario
from g2tom.before_work.domains import resolve
from g2tom.physics import constriction
from g2tom.physics.spot_geometry import SpotGeometry
from g2tom.stages import contact

FAST = {"loading.n_delta": 4, "contact.n_radial": 240}
SHAPES = {
    "sphere": {},
    "cone": {"indenter.shape": "cone", "indenter.cone_angle": 0.1},
    "flat punch": {"indenter.shape": "flat_punch"},
}


def _clean_resistance(scenario) -> np.ndarray:
    """Resistance of the oxide-free surface on the whole window (no cropping), per approach."""
    ds = contact.build(scenario)
    a = ds["spot_radius"].transpose("delta", "y", "x").values
    n = a.shape[-1]
    mask = np.ones((1, n, n), dtype=bool)
    spots = SpotGeometry.whole_window(a, a, scenario.cell_size)
    return constriction.resistance(mask, spots, scenario.material.rho).resistance[0]


@pytest.mark.parametrize("overrides", SHAPES.values(), ids=SHAPES.keys())
def test_auto_window_gives_the_resistance_of_a_much_larger_window(overrides):
    auto = resolve(load_scenario("paper_gt", {**FAST, **overrides}))
    big = resolve(load_scenario("paper_gt", {**FAST, **overrides, "contact.window": 1.6 * auto.contact.window}))
    assert big.n_cells >= 1.5 * auto.n_cells
    # the same radial domain (the larger one) for both, so only the window differs
    same_domain = Scenario.of(auto, contact=dataclasses.replace(auto.contact, r_max=big.contact.r_max))
    r_auto, r_big = _clean_resistance(same_domain), _clean_resistance(big)
    tol = auto.cube.crop_tolerance
    np.testing.assert_allclose(r_auto, r_big, rtol=tol, atol=0)
    # and the window is not wastefully large: two cells fewer on each side exceed the tolerance
    d = domains.domains(auto)
    assert d.n_cells_needed == auto.n_cells
    smaller = dataclasses.replace(auto.contact, window=(auto.n_cells - 4) * auto.cell_size / auto.indenter.radius)
    with pytest.raises(ConfigError, match="contact.window = .* truncates the contact"):
        resolve(Scenario.of(auto, contact=smaller))


def test_auto_radial_domain_holds_the_window_and_the_pressure():
    s = resolve(load_scenario("paper_gt", FAST))
    corner = np.sqrt(2.0) * (s.n_cells - 1) / 2.0 * s.cell_size
    assert corner + domains.MARGIN_CELLS * s.cell_size <= s.contact.r_max * s.indenter.radius
    ds = contact.build(s)
    p = ds["pressure"].isel(delta=-1).values
    assert p[-1] <= s.cube.crop_tolerance * p[0]


@pytest.mark.parametrize("overrides", SHAPES.values(), ids=SHAPES.keys())
def test_too_small_explicit_window_is_refused_with_the_value_needed(overrides):
    auto = resolve(load_scenario("paper_gt", {**FAST, **overrides}))
    needed = domains.domains(auto).window_needed
    small = load_scenario("paper_gt", {**FAST, **overrides, "contact.window": 0.5 * auto.contact.window})
    with pytest.raises(ConfigError) as err:
        resolve(small)
    assert f"it must be >= {domains._round_up(needed):.4g} (R*" in str(err.value)


def test_explicit_values_are_kept_exactly_and_hashes_use_resolved_values():
    published = load_scenario("published")
    assert Scenario.of(resolve(published)) == published  # both explicit: bit-for-bit the same values
    paper = load_scenario("paper_gt")
    assert paper.contact.window == AUTO and paper.contact.r_max == AUTO
    resolved = resolve(paper)
    same = load_scenario("paper_gt", {"contact.window": resolved.contact.window,
                                   "contact.r_max": resolved.contact.r_max})
    assert resolved.config_hash("oxide") == same.config_hash("oxide")
    assert resolved.config_hash("cube") == same.config_hash("cube")


def test_resolve_gives_a_resolved_scenario_and_is_idempotent():
    for name in ("paper_gt", "published"):  # auto domains, and both explicit
        scenario = load_scenario(name, FAST)
        resolved = resolve(scenario)
        assert type(scenario) is Scenario and type(resolved) is ResolvedScenario
        again = resolve(resolved)
        assert type(again) is ResolvedScenario and again == resolved
    assert resolved.n_cells == 57  # published: 0.4 R* sqrt(eta) = 56.6 cells -> the nearest odd count


def test_replace_keeps_the_resolved_type_and_of_drops_it(small):
    fewer = dataclasses.replace(small, oxide=dataclasses.replace(small.oxide, xi=[0.5]))
    assert type(fewer) is ResolvedScenario and fewer.n_cells == small.n_cells
    plain = Scenario.of(small, contact=dataclasses.replace(small.contact, window=AUTO))
    assert type(plain) is Scenario and plain.flat() == {**small.flat(), "contact.window": AUTO}
    assert type(resolve(plain)) is ResolvedScenario


def test_only_a_resolved_scenario_has_a_cell_count(paper):
    for name in ("paper", "published"):  # auto domains, and both explicit but not resolved
        with pytest.raises(AttributeError, match="n_cells"):
            load_scenario(name).n_cells
    assert paper.n_cells == resolve(load_scenario("paper")).n_cells == 49


def test_cheap_cell_estimate_bounds_the_resolved_count():
    for eta in (2e8, 3.2e9):
        s = load_scenario("paper_gt", {**FAST, "roughness.eta": eta})
        n = resolve(s).n_cells
        assert n <= domains.estimate_cells(s) <= 1.3 * n
