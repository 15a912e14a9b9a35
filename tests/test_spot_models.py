"""Spot discretizations: expected radii against quadrature, asperity draws against their mean."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import integrate

from pipeline.physics import spot_models
from pipeline.physics.asperity import asperity_integral

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
