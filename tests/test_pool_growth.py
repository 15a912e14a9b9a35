"""A grown discrete pool (``contact.pool_half_width``): more surfaces at the light steps, each solved
at a prefix of the steps, and the cube meeting surface ``k mod`` the pool's size at each step."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from g2tom.before_work.domains import resolve
from g2tom.compute import ComputeOptions
from g2tom import config
from g2tom.before_work import load_scenario
from g2tom.config.scenario import HASH_NEUTRAL
from g2tom.config.scene_sections import Contact
from g2tom.fitting.ensemble import mean_half_width, z_value
from g2tom.scene import FieldSource
from g2tom.models import discrete_cube, discrete_pool
from g2tom.stages import contact, cube, oxide
from tests.test_discrete_stages import DISCRETE

QUIET = ComputeOptions(progress=False)
TARGET = 0.3


@pytest.fixture(scope="module")
def scene():
    return resolve(load_scenario("paper", {**DISCRETE, "oxide.spot_rule": "disc", "contact.pool_half_width": TARGET}))


@pytest.fixture(scope="module")
def grown(scene):
    return contact.build(scene, QUIET)


@pytest.fixture(scope="module")
def full(scene, grown):
    """The same surfaces, every one solved at every step (the fixed pool of their number)."""
    n = grown.sizes["surface"]
    fixed = dataclasses.replace(scene, contact=dataclasses.replace(scene.contact, surfaces=n, pool_half_width=0.0))
    return contact.build(fixed, QUIET)


def test_the_pool_grows_at_the_light_steps_to_the_target(scene, grown):
    steps = grown["surface_steps"].values
    n_delta = grown.sizes["delta"]
    assert steps.size > scene.contact.surfaces
    assert np.all(steps[: scene.contact.surfaces] == n_delta) and np.all(steps[scene.contact.surfaces:] < n_delta)
    assert np.all(np.diff(steps) <= 0)  # the prefixes shrink: at each step the pool is its first surfaces
    stiffness = grown["discrete_stiffness"].values
    assert np.all(np.isnan(stiffness) == (np.arange(n_delta) >= steps[:, None]))
    widths = mean_half_width(stiffness, z_value(config.POOL_CONFIDENCE))
    assert np.all(widths <= TARGET)
    # the fixed pool's first surfaces alone miss it at some light step
    assert np.nanmax(mean_half_width(stiffness[: scene.contact.surfaces], z_value(0.95))) > TARGET


def test_a_prefix_solve_equals_the_full_solve_of_the_same_surface(grown, full):
    steps = grown["surface_steps"].values
    for name in ("asperity_radius", "discrete_stiffness", "discrete_approach"):
        a, b = grown[name].values, full[name].values
        for s in range(steps.size):
            k = steps[s]
            if name == "asperity_radius":  # spots touching within the prefix, in the same order
                m = int(grown["spot_count"][s])
                touching = np.flatnonzero((b[s, :k] > 0).any(axis=0))
                np.testing.assert_array_equal(a[s, :k, :m], b[s, :k][:, touching])
                assert np.all(a[s, k:] == 0)
            else:
                np.testing.assert_array_equal(a[s, :k], b[s, :k])


def test_growth_stops_at_the_cap_and_adds_whole_rounds(monkeypatch):
    """A synthetic pool whose light step never meets the target stops at MAX_SURFACES; the rounds
    solve only up to the last short step."""
    monkeypatch.setattr(config, "MAX_POOL_SURFACES", 40)
    rng = np.random.default_rng(3)
    calls = []

    def surface(steps: int) -> dict[str, np.ndarray]:
        k = np.array([rng.uniform(0.0, 2.0), 1.0 + 1e-3 * rng.standard_normal(), 1.0])[:steps]
        return {"stiffness": k, "unloading_stiffness": k, "delta": np.zeros(steps)}

    def solve(first: int, stop: int, steps: int) -> list[dict[str, np.ndarray]]:
        calls.append((first, stop, steps))
        return [surface(steps) for _ in range(first, stop)]

    pool = discrete_pool.grow_pool([surface(3) for _ in range(4)], 0.05, solve)
    assert len(pool) == 40 and calls[0][0] == 4
    assert all(steps == 1 for _, _, steps in calls)  # only the scattered first step is short
    assert all(b == c for (_, b, _), (c, _, _) in zip(calls, calls[1:]))


def test_the_cube_meets_surface_k_mod_the_pool_size_at_each_step(scene, grown, full):
    ox = oxide.build(scene, QUIET)
    out = cube.build(scene, grown, ox, QUIET)
    sizes = discrete_cube.DiscretePool.of(grown).sizes()
    pool = discrete_cube.DiscretePool.of(full)
    # the clean surface: at each step the mean conductance over the surfaces solved there
    rho = scene.material.rho
    clean = discrete_cube.clean_pool(pool, rho, scene.cube.model)["resistance"]
    expected = [rho / np.mean(rho / clean[: sizes[i], i]) for i in range(sizes.size)]
    np.testing.assert_allclose(out["resistance_clean"].values, expected, rtol=1e-12)
    # an oxidized realization: the same resistance as on the fixed pool of the step's size
    source = FieldSource.of(scene)
    settings = cube.work_settings(scene, grown)[2]
    grown_pool = discrete_cube.DiscretePool.of(grown)
    for k in (0, 3, sizes[0] - 1, sizes[0] + 2):
        got = discrete_cube.discrete_chunk(source, 0, np.array([k]), np.array([0]), grown_pool,
                                           settings)["resistance"][0, :, 0]
        for i, size in enumerate(sizes):
            prefix = dataclasses.replace(pool, x=pool.x[:size], y=pool.y[:size], radius=pool.radius[:size],
                                         count=pool.count[:size], _kernels={})
            want = discrete_cube.discrete_chunk(source, 0, np.array([k]), np.array([0]), prefix, settings)["resistance"]
            np.testing.assert_allclose(got[i], want[0, i, 0], rtol=1e-9)


def test_the_fixed_pool_leaves_every_hash_as_it_was():
    assert HASH_NEUTRAL["contact.pool_half_width"] == Contact().pool_half_width == 0.0


def test_the_plan_models_the_grown_pool_within_a_factor_of_three():
    """``g2tom plan``'s model of a grown pool (g2tom.models.discrete_cost.grown_pool) against
    the contact stage at the lightest step; off, it adds nothing."""
    from g2tom.models.discrete_cost import expected_counts, grown_pool

    scene = resolve(load_scenario("paper", {**DISCRETE, "contact.pool_half_width": 0.1}))
    counts = expected_counts(scene)
    sizes, seconds = grown_pool(scene, *counts)
    assert np.all(np.diff(sizes) <= 0) and sizes[-1] >= scene.contact.surfaces and seconds > 0
    solved = contact.build(scene, QUIET)["surface_steps"].values
    measured = int(np.sum(solved > 0))
    assert measured / 3 <= sizes[0] <= 3 * measured
    off = dataclasses.replace(scene, contact=dataclasses.replace(scene.contact, pool_half_width=0.0))
    assert grown_pool(off, *counts)[1] == 0.0 and np.all(grown_pool(off, *counts)[0] == scene.contact.surfaces)
