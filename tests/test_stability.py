"""Numerical stability across extreme but valid scenarios, stage 1 to stage 4."""

from __future__ import annotations

import numpy as np
import pytest

from pipeline.compute import ComputeOptions
from pipeline.config import load_scenario
from pipeline.stages import contact, cube, fits, oxide

FAST = {"contact.n_radial": 240, "loading.n_delta": 8}

EXTREMES = {
    "tiny roughness": {"roughness.sigma": 1e-7},
    "deep and light loads": {"loading.delta_min": -12.0, "loading.delta_max": 6.0},
    "soft material": {"material.E": 1e8},
    "auxetic": {"material.nu": -0.9},
    "dense stiff asperities": {"roughness.eta": 1e10, "roughness.beta": 1e-4, "contact.window": 0.1},
    "blunt cone": {"indenter.shape": "cone", "indenter.cone_angle": 0.02},
    "flat punch": {"indenter.shape": "flat_punch", "indenter.punch_radius": 5e-4, "indenter.edge_radius": 5e-3},
}


@pytest.mark.parametrize("overrides", EXTREMES.values(), ids=EXTREMES.keys())
def test_contact_converges_and_stays_physical(overrides) -> None:
    scenario = load_scenario("paper", {**FAST, **overrides})
    ds = contact.build(scenario)
    force = ds["force"].values
    assert np.all(np.isfinite(force)) and np.all(force > 0)
    assert np.all(np.diff(force) > 0), "force must grow with every approach step"
    assert ds["converged"].values.all()
    assert ds["residual"].max() <= 1e-10
    for name in ("pressure", "separation", "area_fraction", "spot_radius"):
        assert np.isfinite(ds[name].values).all(), name
    assert (ds["pressure"] >= 0).all() and (ds["area_fraction"] >= 0).all()
    # A* = pi eta beta F_1(h) and F_1(h) <= sigma/sqrt(2 pi) + |h| for h <= 0
    rough = scenario.roughness
    bound = np.pi * rough.eta * rough.beta * (rough.sigma / np.sqrt(2 * np.pi) + np.abs(ds["separation"]))
    assert (ds["area_fraction"] <= bound * (1 + 1e-12)).all()


def test_nearly_full_oxide_gives_counted_open_circuits_and_finite_fits() -> None:
    scenario = load_scenario("paper", {
        **FAST, "oxide.xi": [0.5, 0.99], "oxide.lambda": [23.0], "oxide.ensemble": "fixed", "oxide.n_realizations": 40,
        "fits.n_bootstrap": 20,
    })
    quiet = ComputeOptions(progress=False)
    result = cube.build(scenario, contact.build(scenario), oxide.build(scenario, quiet), quiet)
    r = result["resistance"]
    assert not np.isnan(r.values).any()
    open_circuits = np.isinf(r.values)
    assert open_circuits.any(), "xi = 0.99 at lambda = 23 must leave some contacts fully oxidized"
    np.testing.assert_array_equal(open_circuits.sum(axis=-1), result["n_open"].values)
    np.testing.assert_array_equal(open_circuits, result["n_conducting"].values == 0)
    fitted = fits.build(scenario, result)
    assert (fitted["open_probability"].sel(xi=0.99) > 0).any()
    assert np.isfinite(fitted["alpha"].values).all() and np.isfinite(fitted["gamma"].values).all()
    assert (fitted["alpha"].sel(xi=0.99) > fitted["alpha"].sel(xi=0.5)).all()
