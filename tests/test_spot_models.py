"""Spot discretizations: expected radii against quadrature, asperity draws against their mean."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import integrate

from g2tom.physics import spot_models
from g2tom.physics.asperity import asperity_integral

SIGMA, ETA, BETA = 20e-6, 2e8, 30e-6


def _quadrature_radius(h: float) -> float:
    """int_h^inf sqrt(beta (z - h)) phi(z) dz by adaptive quadrature (the GW tail, in units of sigma)."""
    def integrand(t: float) -> float:  # t = (z - h) / sigma
        x = h / SIGMA + t
        return np.sqrt(BETA * SIGMA * t) * np.exp(-0.5 * x * x) / np.sqrt(2.0 * np.pi)
    value, _ = integrate.quad(integrand, 0.0, np.inf, epsabs=0.0, epsrel=1e-12, limit=200)
    return value


@pytest.mark.parametrize("h_sigma", [-3.0, -1.0, 0.0, 0.7, 2.0, 4.5, 8.0])
def test_expected_radius_is_the_quadrature_of_sqrt_beta_d(h_sigma):
    got = float(spot_models.expected_radius(h_sigma * SIGMA, SIGMA, BETA))
    assert got == pytest.approx(_quadrature_radius(h_sigma * SIGMA), rel=1e-8)


def test_asperity_radii_average_to_the_expected_radius():
    """Monte Carlo over 10^6 drawn asperities: the mean radius is sqrt(beta) F_1/2(h) within 4 standard errors."""
    z = np.concatenate([spot_models.heights(5, k, 250, SIGMA).ravel() for k in range(16)])
    for h_sigma in (-1.0, 0.5, 2.0):
        radii = spot_models.asperity_radius(z, h_sigma * SIGMA, BETA)
        expected = float(spot_models.expected_radius(h_sigma * SIGMA, SIGMA, BETA))
        assert abs(radii.mean() - expected) <= 4.0 * radii.std() / np.sqrt(z.size)
        assert np.mean(radii > 0) == pytest.approx(0.5 * math.erfc(h_sigma / math.sqrt(2)), abs=4e-3)


def test_heights_reproducible_independent_and_gaussian():
    first = spot_models.heights(11, 3, 40, SIGMA)
    np.testing.assert_array_equal(first, spot_models.heights(11, 3, 40, SIGMA))
    others = [spot_models.heights(11, k, 40, SIGMA) for k in (0, 1, 2, 4)] + [spot_models.heights(12, 3, 40, SIGMA)]
    for other in others:
        assert abs(np.corrcoef(first.ravel(), other.ravel())[0, 1]) < 0.1
    # Not the oxide field's stream of the same seed and index (its entropy is the seed alone).
    oxide_like = np.random.default_rng(np.random.SeedSequence(11, spawn_key=(3,))).standard_normal((40, 40))
    assert not np.allclose(first / SIGMA, oxide_like)
    assert first.std() == pytest.approx(SIGMA, rel=0.1) and abs(first.mean()) < 0.1 * SIGMA


def test_asperity_radius_is_zero_where_the_asperity_does_not_touch():
    z = np.array([-1.0, 0.0, 1.0, 2.0]) * SIGMA
    got = spot_models.asperity_radius(z, SIGMA, BETA)
    np.testing.assert_array_equal(got[:2], 0.0)
    np.testing.assert_allclose(got[2:], [0.0, np.sqrt(BETA * SIGMA)], rtol=1e-15, atol=0)


def test_cell_radius_by_discretization():
    h = np.linspace(-3, 6, 7) * SIGMA
    mean_area = spot_models.cell_radius(h, "mean_area", SIGMA, ETA, BETA)
    np.testing.assert_allclose(mean_area, np.sqrt(BETA * asperity_integral(h, SIGMA, 1.0)), rtol=1e-13)
    expected = spot_models.cell_radius(h, "expected", SIGMA, ETA, BETA)
    np.testing.assert_array_equal(expected, spot_models.cell_radius(h, "asperities", SIGMA, ETA, BETA))
    # Jensen: the mean-area spot overstates the expected sum of radii, more so where few cells touch.
    ratio = mean_area / expected
    assert np.all(ratio > 1) and np.all(np.diff(ratio) > 0)
    with pytest.raises(ValueError, match="spots = 'disc'"):
        spot_models.cell_radius(h, "disc", SIGMA, ETA, BETA)


def test_nearest_cells_maps_points_to_their_cell_and_drops_the_outside():
    centres = np.array([-2.0, -1.0, 0.0, 1.0, 2.0])  # pitch 1: the window is [-2.5, 2.5]
    x = np.array([0.0, 0.49, 0.51, -2.49, 2.6, 1.2])
    y = np.array([0.0, 0.0, -0.6, 2.4, 0.0, -3.0])
    cells = spot_models.nearest_cells(x, y, centres)
    np.testing.assert_array_equal(cells, [2 * 5 + 2, 2 * 5 + 2, 1 * 5 + 3, 4 * 5 + 0, -1, -1])


def test_placed_radius_sums_each_cells_asperities_as_a_loop_does():
    rng = np.random.default_rng(3)
    n, beta = 6, 2e-5
    z = rng.normal(0.0, 1e-6, size=80)
    cells = rng.integers(-1, n * n, size=80)  # some dropped (-1)
    separation = rng.normal(0.0, 1e-6, size=(3, n, n))
    out = spot_models.placed_radius(z, cells, separation, beta)
    loop = np.zeros((3, n * n))
    for k in range(3):
        h = separation[k].ravel()
        for zj, c in zip(z, cells):
            if c >= 0 and zj > h[c]:
                loop[k, c] += math.sqrt(beta * (zj - h[c]))
    np.testing.assert_allclose(out, loop.reshape(3, n, n), rtol=1e-14, atol=0)
    assert (out == 0).any() and (out > 0).any()


def test_placed_radius_of_poisson_asperities_averages_to_the_expected_radius():
    # one asperity per cell on average at any position: E[sum of radii in a cell] = sqrt(beta) F_1/2(h)
    rng = np.random.default_rng(11)
    n, sigma, beta = 300, 1e-6, 5e-5
    centres = np.arange(n) - (n - 1) / 2.0
    count = rng.poisson(n * n)
    x, y = rng.uniform(-n / 2.0, n / 2.0, size=(2, count))
    z = rng.normal(0.0, sigma, size=count)
    h = np.array([-0.5, 0.5, 1.0]) * sigma
    separation = np.broadcast_to(h[:, None, None], (3, n, n))
    out = spot_models.placed_radius(z, spot_models.nearest_cells(x, y, centres), separation, beta)
    expected = spot_models.expected_radius(h, sigma, beta)
    # standard error of the mean over 9e4 cells, sqrt(beta F_1) / (sqrt(beta) F_1/2 * 300): 0.43, 0.66 and
    # 0.93 % at these h; 3 % is over 3 standard errors (a radius summed wrongly, e.g. as areas, is far off)
    np.testing.assert_allclose(out.mean(axis=(1, 2)), expected, rtol=0.03)


def test_placed_radius_refuses_a_cell_beyond_the_map():
    with pytest.raises(ValueError, match="beyond the 4 cells"):
        spot_models.placed_radius([1.0], np.array([4]), np.zeros((2, 2)), 1.0)
