"""The dimensionless groups mu and Pi: hand values, the inverse, and the invariance they claim."""

from __future__ import annotations

import math

import numpy as np
import pytest

from g2tom.before_work import load_scenario
from g2tom.before_work.domains import resolve
from g2tom.physics.groups import greenwood_tripp_mu, groups, lattice_pi, surface_from_groups
from g2tom.stages import contact, cube, fits, oxide
from tests.conftest import SMALL_OVERRIDES


def test_table1_groups_by_hand() -> None:
    # (8/3) * 2e8 * 20e-6 * sqrt(2 * 10e-3 * 30e-6) = 10666.67 * 7.7460e-4 = 8.2624
    assert greenwood_tripp_mu(20e-6, 2e8, 30e-6, 10e-3) == pytest.approx(8.2624, abs=5e-5)
    assert lattice_pi(20e-6, 2e8, 10e-3) == pytest.approx(40.0, rel=1e-14)


@pytest.mark.parametrize("mu, Pi, sigma, radius", [(8.2624, 40.0, 20e-6, 10e-3), (1.0, 5.0, 1e-7, 1e-3),
                                                   (50.0, 320.0, 1e-6, 3.2e-3)])
def test_round_trip(mu: float, Pi: float, sigma: float, radius: float) -> None:
    s = surface_from_groups(mu, Pi, sigma, radius)
    assert (s.sigma, s.radius) == (sigma, radius)
    g = groups(s.sigma, s.eta, s.beta, s.radius)
    assert g.mu == pytest.approx(mu, rel=1e-13)
    assert g.Pi == pytest.approx(Pi, rel=1e-13)


def test_table1_from_its_groups() -> None:
    s = surface_from_groups(greenwood_tripp_mu(20e-6, 2e8, 30e-6, 10e-3), 40.0, 20e-6, 10e-3)
    assert s.eta == pytest.approx(2e8, rel=1e-13)
    assert s.beta == pytest.approx(30e-6, rel=1e-13)


@pytest.mark.parametrize("bad", [0.0, -1.0, math.inf, math.nan])
def test_bad_values_refused(bad: float) -> None:
    with pytest.raises(ValueError, match="mu = "):
        surface_from_groups(bad, 40.0, 20e-6, 10e-3)
    with pytest.raises(ValueError, match="sigma = "):
        lattice_pi(bad, 2e8, 10e-3)


def _chain(overrides: dict) -> tuple:
    """contact -> oxide -> cube -> fits in memory; R' (xi, lambda, delta, realization), F', fits."""
    s = resolve(load_scenario("paper_gt", overrides))
    c = contact.build(s)
    o = oxide.build(s)
    k = cube.build(s, c, o)
    f = fits.build(s, k)
    return s, k["resistance"].values / s.resistance_scale, k["force_normalized"].values, f


@pytest.fixture(scope="module")
def pair() -> tuple:
    """The small paper scene and one with the same (mu, Pi) but sigma x2, R* x1/2, other E, nu, rho.

    The window and r_max are pinned (in units of R*, so scaled by sqrt(sigma/R*)) to the same
    lattice, and the fit's lower force bound scaled with F's unit, so that only the groups
    can differ.
    """
    base = dict(SMALL_OVERRIDES, **{"oxide.xi": [0.5, 0.8], "oxide.lambda": [1.0, 9.0]})
    auto = resolve(load_scenario("paper_gt", base))  # the auto domains of the first scene, pinned for both
    window, r_max = auto.contact.window, auto.contact.r_max
    base.update({"contact.window": window, "contact.r_max": r_max})
    a = _chain(base)
    sa = a[0]
    g = groups(sa.roughness.sigma, sa.roughness.eta, sa.roughness.beta, sa.indenter.radius)
    other = surface_from_groups(g.mu, g.Pi, sigma=40e-6, radius=5e-3)
    stretch = math.sqrt((other.sigma / other.radius) / (sa.roughness.sigma / sa.indenter.radius))
    b_over = dict(base, **{
        "roughness.sigma": other.sigma, "roughness.eta": other.eta, "roughness.beta": other.beta,
        "indenter.radius": other.radius, "material.E": 7.0e10, "material.nu": 0.25, "material.rho": 2.0e-8,
        "contact.window": window * stretch, "contact.r_max": r_max * stretch,
    })
    b_scene = load_scenario("paper_gt", b_over)
    b_over["fits.min_force"] = sa.fits.min_force * b_scene.force_scale / sa.force_scale
    return a, _chain(b_over)


def test_equal_groups_give_equal_normalized_resistance(pair) -> None:
    (sa, ra, fa, fits_a), (sb, rb, fb, fits_b) = pair
    assert sb.n_cells == sa.n_cells
    assert sb.roughness.sigma != sa.roughness.sigma and sb.material.E != sa.material.E
    np.testing.assert_allclose(fb, fa, rtol=1e-9)
    # the crop tolerance bounds how far two windows' truncations of R can differ
    tol = 2 * sa.cube.crop_tolerance
    np.testing.assert_allclose(rb, ra, rtol=tol)
    np.testing.assert_allclose(fits_b["alpha"].values, fits_a["alpha"].values, rtol=tol)
    np.testing.assert_allclose(fits_b["gamma"].values, fits_a["gamma"].values, rtol=tol, atol=1e-9)


def test_other_groups_give_other_loads(pair) -> None:
    """The check above can fail: mu x2 (beta x4, Pi unchanged) moves F'(delta/sigma) by far more."""
    (sa, _, fa, _), _ = pair
    s = resolve(load_scenario("paper_gt", dict(SMALL_OVERRIDES, **{
        "roughness.beta": 4 * sa.roughness.beta})))
    fb = contact.build(s)["force_normalized"].values
    assert np.min(np.abs(fb / fa - 1.0)) > 0.01
