"""Overlapping contact discs split by their power cells: closed forms, a raster of the cells, derivatives."""

from __future__ import annotations

import numpy as np
import pytest

from g2tom.physics.cap_overlap import owned_area_derivatives, owned_areas


def lens(a: float, b: float, d: float) -> float:
    """Area of the intersection of two discs of radii a, b at distance d (closed form)."""
    alpha = np.arccos((d * d + a * a - b * b) / (2 * d * a))
    beta = np.arccos((d * d + b * b - a * a) / (2 * d * b))
    return a * a * (alpha - np.sin(2 * alpha) / 2) + b * b * (beta - np.sin(2 * beta) / 2)


def raster_owned(x, y, a, n=2400):
    """The slow reference: every pixel of a fine raster goes to the disc of least power |p - x_i|^2 - a_i^2
    among those that hold it."""
    lo, hi = min((x - a).min(), (y - a).min()), max((x + a).max(), (y + a).max())
    c = np.linspace(lo, hi, n)
    pixel = c[1] - c[0]
    least = np.full((n, n), np.inf)
    owner = np.full((n, n), -1)
    for i in range(x.size):  # each disc's bounding box of pixels
        cols = slice(*np.searchsorted(c, [x[i] - a[i], x[i] + a[i]]))
        rows = slice(*np.searchsorted(c, [y[i] - a[i], y[i] + a[i]]))
        power = (c[cols][None, :] - x[i]) ** 2 + (c[rows][:, None] - y[i]) ** 2 - a[i] ** 2
        box, who = least[rows, cols], owner[rows, cols]
        wins = (power <= 0) & (power < box)
        box[wins], who[wins] = power[wins], i
    return np.bincount(owner[owner >= 0], minlength=x.size) * pixel * pixel, pixel


def test_two_discs_share_their_lens_along_the_radical_line():
    """Two overlapping discs: the owned areas sum to the union, 2 pi a^2 + pi b^2 - lens, and each is its
    disc less the segment beyond the radical line (equal discs: half of the union each)."""
    x, y = np.array([0.0, 1.0]), np.array([0.0, 0.0])
    equal = owned_areas(x, y, np.array([1.0, 1.0]))
    np.testing.assert_allclose(equal, np.pi - lens(1.0, 1.0, 1.0) / 2, rtol=1e-14)
    a, b, d = 1.0, 0.6, 1.2
    owned = owned_areas(np.array([0.0, d]), y, np.array([a, b]))
    np.testing.assert_allclose(owned.sum(), np.pi * (a * a + b * b) - lens(a, b, d), rtol=1e-14)
    c = (d * d + a * a - b * b) / (2 * d)  # the radical line's distance from the first centre
    segment = a * a * np.arccos(c / a) - c * np.sqrt(a * a - c * c)
    np.testing.assert_allclose(owned[0], np.pi * a * a - segment, rtol=1e-14)


def test_apart_and_swallowed_discs():
    """Discs that do not overlap own their whole area; a disc whose every point is nearer in power to a
    larger one owns nothing; a disc of radius 0 owns nothing and clips nothing."""
    x, y, a = np.array([0.0, 3.0, 0.4, 7.0]), np.array([0.0, 0.0, 0.0, 0.0]), np.array([2.0, 0.9, 0.5, 0.0])
    owned = owned_areas(x, y, a)  # the first two are 3 apart with radii 2 and 0.9: they do not overlap
    np.testing.assert_array_equal(owned, [np.pi * 4.0, np.pi * 0.81, 0.0, 0.0])
    apart = owned_areas(np.array([0.0, 5.0]), np.array([0.0, 0.0]), np.array([1.0, 2.0]))
    np.testing.assert_array_equal(apart, np.pi * np.array([1.0, 4.0]))


def test_owned_areas_are_the_power_cells_of_a_raster():
    """300 random discs, many overlapping several others: each owned area within the raster's pixel
    error of the raster's count of the pixels whose least power is that disc's."""
    rng = np.random.default_rng(7)
    x, y, a = rng.uniform(0, 10, 300), rng.uniform(0, 10, 300), rng.uniform(0.1, 0.9, 300)
    owned = owned_areas(x, y, a)
    reference, pixel = raster_owned(x, y, a)
    perimeter = 2 * np.pi * a + 10 * a  # the disc's circle and its radical chords, generously
    np.testing.assert_array_less(np.abs(owned - reference), 2 * perimeter * pixel)
    assert abs(owned.sum() - reference.sum()) < 1e-3 * reference.sum()
    assert np.count_nonzero(owned < np.pi * a * a * (1 - 1e-12)) > 150  # most discs overlap


def test_derivatives_are_those_of_the_areas():
    """dA_i/da_j from the free arcs and shared chords equals central differences of the areas."""
    rng = np.random.default_rng(3)
    n = 120
    x, y, a = rng.uniform(0, 6, n), rng.uniform(0, 6, n), rng.uniform(0.1, 0.8, n)
    _, own, rows, cols, values = owned_area_derivatives(x, y, a)
    exact = np.diag(own)
    exact[rows, cols] += values
    step = 1e-6
    numeric = np.empty((n, n))
    for j in range(n):
        e = np.zeros(n)
        e[j] = step
        numeric[:, j] = (owned_areas(x, y, a + e) - owned_areas(x, y, a - e)) / (2 * step)
    np.testing.assert_allclose(exact, numeric, rtol=0, atol=1e-7 * np.abs(exact).max())
    assert rows.size > n  # many shared chords


def test_a_lone_disc_grows_by_its_circle():
    """Alone, dA/da = 2 pi a and no other derivative."""
    area, own, rows, *_ = owned_area_derivatives(np.array([0.0]), np.array([0.0]), np.array([0.7]))
    assert area[0] == pytest.approx(np.pi * 0.49, rel=1e-15) and own[0] == pytest.approx(2 * np.pi * 0.7, rel=1e-15)
    assert rows.size == 0


def test_shapes_are_checked():
    with pytest.raises(ValueError, match="one shape"):
        owned_areas(np.zeros(3), np.zeros(2), np.ones(3))
