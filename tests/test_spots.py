"""Spot discretisation (Sect. 2.5.2) and the Holm–Greenwood radius (Eq. 13)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from g2tom.physics import spots
from g2tom.physics.interaction import pair_sum_points


def test_holm_greenwood_two_spots():
    """Two equal spots at distance d: alpha_HG = pi (2a)^2 / (2 * 2a^2/d) = pi d."""
    radii = np.zeros((4, 4))
    radii[0, 0] = radii[0, 3] = 1e-6
    assert spots.holm_greenwood_radius(radii, 2.0) == pytest.approx(math.pi * 6.0, rel=1e-12)
    assert np.isnan(spots.holm_greenwood_radius(np.eye(1)[None], 1.0))


@settings(max_examples=20, deadline=None)
@given(arrays(np.float64, st.tuples(st.integers(1, 3), st.integers(2, 7)).map(lambda t: (t[0], t[1], t[1])),
              elements=st.one_of(st.just(0.0), st.floats(1e-3, 10))), st.floats(0.1, 5.0))
def test_holm_greenwood_matches_the_double_sum(radii, cell):
    n = radii.shape[-1]
    yy, xx = np.meshgrid(np.arange(n) * cell, np.arange(n) * cell, indexing="ij")
    for a, alpha in zip(radii, spots.holm_greenwood_radius(radii, cell)):
        pairs = pair_sum_points(xx.ravel(), yy.ravel(), a.ravel())
        if np.count_nonzero(a) >= 2:
            assert alpha == pytest.approx(math.pi * a.sum() ** 2 / (2 * pairs), rel=1e-10)
        else:
            assert np.isnan(alpha)


def test_spot_areas_and_radii():
    area = spots.spot_areas(np.array([0.0, 0.5]), 2.0)
    np.testing.assert_allclose(area, [0.0, 2.0])
    np.testing.assert_allclose(spots.spot_radii(area), [0.0, math.sqrt(2.0 / math.pi)])


def test_cell_radii():
    x = np.array([-1.0, 0.0, 1.0])
    r = spots.cell_radii(x, x)
    assert r.shape == (3, 3) and r[1, 1] == 0 and r[0, 0] == pytest.approx(math.sqrt(2))


def test_smooth_interpolation_reproduces_even_cubic_fields():
    r = np.linspace(0, 2, 11)
    values = np.stack([1 + r**2, 3 - r**2 + 0.5 * r**3])
    rc = np.array([[0.05, 0.33], [1.27, 1.99]])
    out = spots.interpolate_smooth(r, values, rc)
    assert out.shape == (2, 2, 2)
    np.testing.assert_allclose(out[0], 1 + rc**2, rtol=1e-13)
    np.testing.assert_allclose(out[1], 3 - rc**2 + 0.5 * rc**3, rtol=1e-13)


def test_linear_interpolation():
    r = np.linspace(0, 2, 3)
    out = spots.interpolate_linear(r, np.array([[0.0, 1.0, 4.0]]), np.array([0.5, 1.5]))
    np.testing.assert_allclose(out, [[0.5, 2.5]])


@pytest.mark.parametrize("interp", [spots.interpolate_smooth, spots.interpolate_linear])
def test_cells_outside_radial_domain(interp):
    with pytest.raises(ValueError, match="cell radius 2.5 m is out of range"):
        interp(np.linspace(0, 2, 5), np.ones(5), np.array([1.0, 2.5]))
