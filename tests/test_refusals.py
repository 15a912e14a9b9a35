"""Refusals blame the input the user can act on: the indenter when it makes the contact's grid huge,
and the plan of ``g2tom validate --max-realizations`` stays cheap for any allowed value."""

from __future__ import annotations

import dataclasses
import re
import time

import numpy as np
import pytest

from g2tom.before_work import load_scenario
from g2tom.before_work.domains import check_cell_count
from g2tom.cli.main import main
from g2tom.config import ConfigError

MEMORY = 16.0 * 2**30  # a fixed machine, so the refusals do not depend on the one running the test


@pytest.mark.parametrize(
    ("overrides", "blamed", "direction"),
    [
        ({"indenter.shape": "cone", "indenter.cone_angle": 1e-6}, "indenter.cone_angle = 1e-06 (rad)", ">="),
        ({"indenter.radius": 1e3}, "indenter.radius = 1000 (m)", "<="),
        ({"indenter.shape": "flat_punch", "indenter.punch_radius": 100.0}, "indenter.punch_radius = 100 (m)", "<="),
        ({"roughness.eta": 1e16}, "roughness.eta = 1e+16", "<="),
    ],
)
def test_a_huge_grid_blames_the_parameter_that_makes_it(overrides, blamed, direction) -> None:
    with pytest.raises(ConfigError) as err:
        check_cell_count(load_scenario("paper", overrides), MEMORY)
    message = str(err.value)
    assert message.startswith(f"{blamed} is out of range for this machine"), message
    fit = re.search(rf"it must be {direction} about ([0-9.e+-]+)", message)
    assert fit, message
    if not blamed.startswith("roughness"):  # the value named fits
        name = blamed.split(" = ")[0]
        check_cell_count(load_scenario("paper", {**overrides, name: float(fit.group(1)) * (1.01 if direction == ">=" else 0.99)}),
                         MEMORY)
        assert "(or roughness.eta <= about" in message


def test_near_flat_cone_refused_by_plan_naming_the_cone(capsys) -> None:
    assert main(["plan", "--set", "indenter.shape=cone", "--set", "indenter.cone_angle=1e-6"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("g2tom: error: indenter.cone_angle = 1e-06 (rad) is out of range") and err.count("\n") == 1


def _quick_set_and_loads():
    from g2tom.reference.validate import chosen_set

    vset = chosen_set(True, "gw")
    return vset, np.geomspace(0.0752, 18.8, len(vset.deltas))


def test_validate_plan_counts_its_cases_without_building_them() -> None:
    from g2tom.reference import cases, cost

    vset, f = _quick_set_and_loads()
    est = cost.estimate(vset, f, 2, 5.0)
    built = [c for k, (n, p) in enumerate(zip(est.ensemble_counts, est.ensemble_pairs))
             for c in (cases.ensemble_cases(vset, k, range(n)) if n > p else [])
             + cases.pair_cases(vset, k, range(len(vset.realizations), p))]
    assert est.ensemble == len(built)
    assert est.seconds_part2 == pytest.approx(sum(cost.case_seconds(vset, c, float(f[c.load])) for c in built), rel=1e-12)


def test_validate_plan_stays_cheap_at_any_ensemble_cap() -> None:
    from g2tom.reference import cost

    vset, f = _quick_set_and_loads()
    start = time.perf_counter()
    huge = cost.estimate(dataclasses.replace(vset, max_ensemble=10**12), f, 2, 5.0)
    assert time.perf_counter() - start < 2.0
    small = cost.estimate(dataclasses.replace(vset, max_ensemble=10**4), f, 2, 5.0)
    assert huge.wall_cap > 10**7 * small.wall_cap  # part 2's bound grows with the cap (10**8 x), counted, not built
