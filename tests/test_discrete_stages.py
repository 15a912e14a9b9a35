"""Discrete spots through the stages: the contact pool, the cube's spot rules, Barber per surface."""

from __future__ import annotations

import numpy as np
import pytest

from g2tom.compute import ComputeOptions
from g2tom import config
from g2tom.before_work import load_scenario
from g2tom.before_work.domains import resolve
from g2tom.physics import oxide_band
from g2tom.physics.discrete_contact import interaction_kernel
from g2tom.physics.discrete_resistance import resistances
from g2tom.physics.spot_share import DEFAULT_RINGS
from g2tom.scene import bands
from g2tom.models import discrete_cube, discrete_pool
from g2tom.stages import contact, cube, oxide
from tests.conftest import SMALL_OVERRIDES

QUIET = ComputeOptions(progress=False)
DISCRETE = {**SMALL_OVERRIDES, "contact.model": "discrete", "contact.surfaces": 5, "oxide.xi": [0.5],
            "oxide.lambda": [1.0, 9.0], "oxide.n_realizations": 7, "cube.model": "point"}


@pytest.fixture(scope="module")
def scene():
    return resolve(load_scenario("paper", {**DISCRETE, "oxide.spot_rule": "disc"}))


@pytest.fixture(scope="module")
def pool(scene):
    return contact.build(scene, QUIET)


def test_pool_holds_each_surface_at_the_forces_with_barber_exact(scene, pool):
    assert pool.sizes["surface"] == 5 and pool.attrs["model"] == "discrete"
    assert np.all(pool["discrete_residual"].values <= 1e-10)
    assert np.all(np.diff(pool["discrete_approach"].values, axis=1) < 0)  # more force, more approach
    # the light steps touch on a few asperities, the heavy ones on many
    touching = (pool["asperity_radius"] > 0).sum("spot")
    assert touching.isel(delta=0).max() <= 12 and touching.isel(delta=-1).min() >= 20
    for s in range(5):
        m = int(pool["spot_count"][s])
        x, y = pool["asperity_x"].values[s, :m], pool["asperity_y"].values[s, :m]
        kernel = interaction_kernel(x, y, pool.attrs["coupling_floor"])
        r = resistances(kernel, pool["asperity_radius"].values[s, :, :m], scene.material.rho)
        np.testing.assert_allclose(1.0 / r, pool["discrete_barber_conductance"].values[s], rtol=1e-8)


def test_pool_is_independent_of_the_chunking(scene, pool, monkeypatch):
    monkeypatch.setattr(discrete_pool, "CHUNK", 2)
    again = contact.build(scene, ComputeOptions(progress=False, workers=1))
    for name in ("asperity_x", "asperity_radius", "discrete_approach", "discrete_stiffness"):
        np.testing.assert_array_equal(again[name].values, pool[name].values)


def test_disc_with_every_spot_clean_equals_centre():
    scene = resolve(load_scenario("paper", DISCRETE))
    modes = bands(scene)[0]
    coeffs = oxide_band.coefficients(modes, oxide_band.field_stream(1, 1.0, 0))
    x, y = np.array([0.0, 1e-4, -2e-4]), np.array([0.0, 5e-5, 1e-4])
    radius = np.array([[1e-5, 0.0, 2e-5], [3e-5, 1e-5, 4e-5]])
    clean = np.array([np.inf], np.float32)
    for rule in ("centre", "disc"):
        share = discrete_cube.clean_shares(modes, coeffs, x, y, radius, clean, rule, scene.cell_size)
        np.testing.assert_array_equal(share[0], radius > 0)


def test_disc_rings_follow_the_spot_size():
    l_o = 1e-4
    np.testing.assert_array_equal(discrete_cube.rings(np.array([1e-9, l_o / 16, l_o / 2, 5 * l_o]), l_o),
                                  [1, 1, DEFAULT_RINGS, DEFAULT_RINGS])


def test_cube_on_discrete_spots(scene, pool):
    ox = oxide.build(scene, QUIET)
    out = cube.build(scene, pool, ox, QUIET)
    assert out.attrs["spot_rule"] == "disc"
    r = out["resistance"].values
    clean = out["resistance_clean"].values
    finite = np.isfinite(r)
    assert finite.any() and np.all(r[finite] > 0)
    # oxide removes conductance: every oxidized entry is at least its surface's clean resistance
    pool_clean = discrete_cube.clean_pool(discrete_cube.DiscretePool.of(pool), scene.material.rho, "point")
    surface_clean = pool_clean["resistance"][np.arange(r.shape[-1]) % 5]  # (realization, delta)
    assert np.all(r[finite] >= np.broadcast_to(surface_clean.T, r.shape)[finite] * (1 - 1e-9))
    # Barber on the pool: the clean point model against K / (E* rho*), surface by surface on average
    np.testing.assert_allclose(out["conductance_clean_point"].values,
                               pool["discrete_barber_conductance"].mean("surface").values, rtol=1e-8)
    # chunking changes nothing
    smaller = load_scenario("paper", {**DISCRETE, "oxide.spot_rule": "disc", "cube.chunk": 2})
    again = cube.build(resolve(smaller), pool, ox, QUIET)
    np.testing.assert_array_equal(again["resistance"].values, r)


def test_centre_rule_switches_whole_spots(scene, pool):
    centre = resolve(load_scenario("paper", {**DISCRETE, "oxide.spot_rule": "centre"}))
    ox = oxide.build(centre, QUIET)
    out = cube.build(centre, pool, ox, QUIET)
    disc = cube.build(scene, pool, ox, QUIET)
    # the same fields and surfaces: the rules differ, the clean surface does not
    np.testing.assert_array_equal(out["resistance_clean"].values, disc["resistance_clean"].values)
    assert not np.array_equal(out["resistance"].values, disc["resistance"].values)



def test_segment_rule_conducts_more_than_disc_on_the_same_shares(scene, pool):
    """The segment rule counts the same clean shares as disc and gives each cut spot a larger
    radius (h(f) >= sqrt(f)): the same clean surface, every oxidized resistance at most disc's,
    some strictly lower, the same open circuits."""
    segment = resolve(load_scenario("paper", {**DISCRETE, "oxide.spot_rule": "segment"}))
    ox = oxide.build(segment, QUIET)
    out = cube.build(segment, pool, ox, QUIET)
    disc = cube.build(scene, pool, ox, QUIET)
    assert out.attrs["spot_rule"] == "segment"
    np.testing.assert_array_equal(out["resistance_clean"].values, disc["resistance_clean"].values)
    r, d = out["resistance"].values, disc["resistance"].values
    np.testing.assert_array_equal(np.isfinite(r), np.isfinite(d))
    finite = np.isfinite(d)
    assert np.all(r[finite] <= d[finite] * (1 + 1e-12)) and np.any(r[finite] < d[finite] * (1 - 1e-3))


def test_pool_variables_are_the_schemas(pool):
    from g2tom.stages.schema import matches

    for name in ("spot_count", "asperity_x", "asperity_radius", "discrete_approach", "discrete_barber_conductance",
                 "surface", "spot"):
        var = pool[name]
        assert matches("contact", name, var.dims, var.attrs), name


def test_pool_kernels_are_made_once_per_surface_and_exact(pool):
    surfaces = discrete_cube.DiscretePool.of(pool)
    first = surfaces.kernel(3)
    x, y, _ = surfaces.spots(3)
    np.testing.assert_array_equal(first, interaction_kernel(x, y, surfaces.floor))
    assert surfaces.groups(3 + surfaces.size) == [(3, None)]  # realization k + S meets surface k again
    assert surfaces.kernel(3) is first
    assert surfaces == discrete_cube.DiscretePool.of(pool)  # the cache is not part of the pool's value


def test_pool_kernels_beyond_the_cache_budget_are_made_again_equal(pool, monkeypatch):
    surfaces = discrete_cube.DiscretePool.of(pool)
    one = surfaces.kernel(0).nbytes
    monkeypatch.setattr(config, "KERNEL_CACHE_BYTES", one + surfaces.kernel(1).nbytes)
    kept = [surfaces.kernel(k) for k in range(surfaces.size)]
    assert len(surfaces._kernels) == 2  # surfaces 0 and 1 fit the budget; the others are not kept
    again = surfaces.kernel(2)
    assert again is not kept[2]
    np.testing.assert_array_equal(again, kept[2])
    assert surfaces.kernel(0) is kept[0]
