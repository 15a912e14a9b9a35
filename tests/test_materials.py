"""Named materials, the hardness parameter and the plasticity index."""

from __future__ import annotations

import math

import pytest

from g2tom.config import read_scenario
from g2tom.config.declare import ConfigError
from g2tom.config.materials import MATERIALS
from g2tom.physics import plasticity


def test_named_pair_gives_the_tables_effective_values() -> None:
    s = read_scenario("paper", {"material.bodies": ["hard_gold", "copper"]})
    gold, copper = MATERIALS["hard_gold"], MATERIALS["copper"]
    e_star = 1.0 / ((1 - gold.nu**2) / gold.E + (1 - copper.nu**2) / copper.E)
    assert s.material.E_star == pytest.approx(e_star, rel=1e-14)
    assert s.material.rho == pytest.approx((gold.rho + copper.rho) / 2, rel=1e-14)
    assert s.material.hardness == min(gold.hardness, copper.hardness) == copper.hardness


def test_one_name_means_both_bodies_and_hard_gold_is_the_handbook_pair() -> None:
    s = read_scenario("paper", {"material.bodies": ["hard_gold"]})
    assert s.material.E_star == pytest.approx(47.96e9, rel=1e-3)  # 79 GPa, nu 0.42: E / (2 (1 - nu^2))
    assert s.material.hardness == 1.5e9


def test_explicit_values_win_over_the_bodies() -> None:
    s = read_scenario("paper", {"material.bodies": ["gold"], "material.rho": 1e-8, "material.hardness": 3e9})
    assert (s.material.rho, s.material.hardness) == (1e-8, 3e9)
    assert s.material.E_star == pytest.approx(MATERIALS["gold"].E / (2 * (1 - MATERIALS["gold"].nu ** 2)))
    by_e = read_scenario("paper", {"material.bodies": ["gold"], "material.E": 1e11, "material.nu": 0.25})
    assert by_e.material.modulus is None and by_e.material.E_star == pytest.approx(1e11 / (2 * (1 - 0.0625)))


def test_a_scenario_without_hardness_is_elastic_and_keeps_its_hashes() -> None:
    s = read_scenario("paper")
    assert s.material.hardness is None and s.material.modulus is None and s.material.bodies == []
    set_none = read_scenario("paper", {"material.hardness": "none"})
    assert set_none.config_hash("contact") == s.config_hash("contact")
    assert read_scenario("paper", {"material.hardness": 2e9}).config_hash("contact") != s.config_hash("contact")


@pytest.mark.parametrize("overrides, message", [
    ({"material.bodies": ["gld"]}, r"material.bodies\[0\] = 'gld' is not allowed: must be one of 'gold', 'hard_gold'"),
    ({"material.hardness": 0}, r"material.hardness = 0 is out of range: must be > 0 and <= 1e\+12, or 'none' \(Pa\)"),
    ({"material.hardness": -2e9}, r"material.hardness = -2000000000.0 is out of range"),
    ({"material.bodies": ["gold", "tin", "steel"]}, r"names 3 bodies: must name one \(both bodies\) or two"),
])
def test_bad_material_is_one_clear_line(overrides, message) -> None:
    with pytest.raises(ConfigError, match=message):
        read_scenario("paper", overrides)


def test_plasticity_index_and_first_yield_of_table_1_steel() -> None:
    e_star, h, sigma, beta = 115e9, 2e9, 20e-6, 30e-6
    assert plasticity.plasticity_index(e_star, h, sigma, beta) == pytest.approx(46.95, abs=0.01)
    omega = plasticity.yield_interference(beta, e_star, h)
    assert omega == pytest.approx(22.39e-9, rel=1e-3)
    # at first yield the Hertz peak pressure 2 E* a / (pi beta) equals H and the Hertz force is F_c
    a = math.sqrt(beta * omega)
    assert 2 * e_star * a / (math.pi * beta) == pytest.approx(h, rel=1e-12)
    assert 4 / 3 * e_star * math.sqrt(beta) * omega**1.5 == pytest.approx(plasticity.yield_force(beta, e_star, h), rel=1e-12)


def test_the_seed_that_draws_the_pool_enters_the_contact_hash() -> None:
    """The discrete pool's surfaces come from oxide.seed: a contact.nc of another seed is not current."""
    assert read_scenario("paper", {"oxide.seed": 1}).config_hash("contact") != read_scenario("paper").config_hash("contact")
