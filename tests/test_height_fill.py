"""Filling undefined pixels in height maps (g2tom.physics.height_fill, issue 31): curvature and harmonic."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.ndimage import gaussian_filter

from g2tom.physics.height_fill import fill_gaps, masked_moments
from g2tom.physics.surface_spectrum import psd_moments

PIXEL = 1e-6  # m
N = 256


def rough_surface(seed: int = 0) -> np.ndarray:
    """Plane waves of 16 ... 64 pixel wavelengths plus a smooth random field and a tilt, m."""
    rng = np.random.default_rng(seed)
    y, x = np.mgrid[0:N, 0:N].astype(float)
    z = np.zeros((N, N))
    for _ in range(6):
        wavelength, direction, phase = rng.uniform(16, 64), rng.uniform(0, np.pi), rng.uniform(0, 2 * np.pi)
        z += rng.uniform(0.5, 1.0) * np.cos(2 * np.pi * (x * np.cos(direction) + y * np.sin(direction)) / wavelength
                                            + phase)
    smooth = gaussian_filter(rng.normal(size=(N, N)), 6.0, mode="wrap")
    z += 0.8 * smooth / smooth.std()
    return 1e-6 * z + 1e-4 * x * PIXEL


def punch_holes(z: np.ndarray, share: float, seed: int = 1) -> np.ndarray:
    """A copy of z with NaN in random discs of radius 1 ... 4 pixels until ``share`` is missing."""
    rng = np.random.default_rng(seed)
    holed = z.copy()
    y, x = np.mgrid[0 : z.shape[0], 0 : z.shape[1]]
    while np.isnan(holed).mean() < share:
        cy, cx, radius = rng.uniform(0, z.shape[0]), rng.uniform(0, z.shape[1]), rng.uniform(1, 4)
        holed[(y - cy) ** 2 + (x - cx) ** 2 <= radius**2] = np.nan
    return holed


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_filled_map_keeps_the_moments(seed: int) -> None:
    z = rough_surface(seed)
    holed = punch_holes(z, 0.05, seed + 1)
    filled, count = fill_gaps(holed)
    missing = np.isnan(holed)
    assert count == missing.sum() and 0.05 <= count / z.size < 0.06
    assert not np.isnan(filled).any()
    np.testing.assert_array_equal(filled[~missing], z[~missing])  # defined pixels untouched, bit for bit
    cutoff = 4 * PIXEL
    before, after = psd_moments(z, (PIXEL, PIXEL), cutoff), psd_moments(filled, (PIXEL, PIXEL), cutoff)
    # the curvature fill: every moment within 2 % (measured: |change| <= 0.16 % on four seeds)
    assert after.rms_height == pytest.approx(before.rms_height, rel=0.02)
    assert after.m2 == pytest.approx(before.m2, rel=0.02)
    assert after.m4 == pytest.approx(before.m4, rel=0.02)
    # the filled pixels themselves: rms error 0.12 of the surface's rms height (holes up to 83 px)
    assert np.sqrt(np.mean((filled[missing] - z[missing]) ** 2)) < 0.15 * before.rms_height
    # the harmonic fill meets the defined pixels with a kink: m4 biased up by 2 ... 4 % here
    harmonic = psd_moments(fill_gaps(holed, "harmonic")[0], (PIXEL, PIXEL), cutoff)
    assert 0.015 < harmonic.m4 / before.m4 - 1 < 0.05


@pytest.mark.parametrize("method, rtol", [("curvature", 1e-7), ("harmonic", 1e-10)])
def test_linear_ramp_is_filled_exactly(method: str, rtol: float) -> None:
    y, x = np.mgrid[0:40, 0:50].astype(float)
    ramp = 3e-6 + 2e-7 * x - 5e-8 * y
    holed = ramp.copy()
    holed[5:20, 10:30] = np.nan
    holed[25:35, 3] = np.nan
    holed[30, 30] = np.nan
    if method == "curvature":  # keeps a tilt across the map's edge too
        holed[0:4, 40:50] = np.nan
    filled, count = fill_gaps(holed, method)
    assert count == 15 * 20 + 10 + 1 + (40 if method == "curvature" else 0)
    # the curvature fill's slope rows (SLOPE_WEIGHT) move it by ~1e-8
    np.testing.assert_allclose(filled, ramp, rtol=rtol, atol=0)


def test_edge_holes_obey_the_maximum_principle() -> None:
    rng = np.random.default_rng(4)
    z = rng.normal(size=(30, 20))
    holed = z.copy()
    holed[0, :] = np.nan  # a whole edge row
    holed[10:30, 15:20] = np.nan  # a corner block
    filled, count = fill_gaps(holed, "harmonic")
    assert count == 20 + 20 * 5
    defined = z[~np.isnan(holed)]
    assert defined.min() <= filled.min() and filled.max() <= defined.max()
    # the equation itself: every filled pixel is the mean of its neighbours inside the map
    padded = np.pad(filled, 1, constant_values=np.nan)
    neighbours = np.stack([padded[:-2, 1:-1], padded[2:, 1:-1], padded[1:-1, :-2], padded[1:-1, 2:]])
    means = np.nanmean(neighbours, axis=0)
    np.testing.assert_allclose(filled[np.isnan(holed)], means[np.isnan(holed)], rtol=0, atol=1e-12)


def test_no_gap_and_single_defined_pixel() -> None:
    z = np.arange(12.0).reshape(3, 4)
    filled, count = fill_gaps(z)
    assert count == 0 and filled is not z
    np.testing.assert_array_equal(filled, z)
    lone = np.full((4, 5), np.nan)
    lone[2, 3] = 7e-6
    for method, rtol in (("harmonic", 1e-12), ("curvature", 1e-6)):  # the slope rows pin the flat fill
        filled, count = fill_gaps(lone, method)
        assert count == 19
        np.testing.assert_allclose(filled, 7e-6, rtol=rtol)


def test_all_missing_or_not_a_map() -> None:
    with pytest.raises(ValueError, match="no defined pixel"):
        fill_gaps(np.full((5, 5), np.nan))
    with pytest.raises(ValueError, match="2-D"):
        fill_gaps(np.array([1.0, np.nan, 2.0]))


def test_masked_moments_of_a_complete_map_are_its_own() -> None:
    z = rough_surface()
    rms, m2, m4 = masked_moments(z, (PIXEL, PIXEL))
    spectral = psd_moments(z, (PIXEL, PIXEL), 4 * PIXEL)
    assert rms == pytest.approx(spectral.rms_height, rel=1e-9)  # the same plane removed
    # finite differences see every wavelength (down to 2 px) through their own transfer
    # function; on this surface (wavelengths >= 16 px) within 5 % (m2) and 15 % (m4)
    assert m2 == pytest.approx(spectral.m2, rel=0.05)
    assert m4 == pytest.approx(spectral.m4, rel=0.15)


def test_masked_moments_skip_the_holes() -> None:
    z = rough_surface()
    holed = punch_holes(z, 0.05)
    full, masked = np.array(masked_moments(z, (PIXEL, PIXEL))), np.array(masked_moments(holed, (PIXEL, PIXEL)))
    np.testing.assert_allclose(masked, full, rtol=0.03)  # holes at random places: a subsample
    # heights varying along x only: the x differences are divided by dx (and y's by dy)
    along_x = np.tile(np.arange(6.0) ** 3, (5, 1))
    unit, wide = masked_moments(along_x, (1.0, 1.0)), masked_moments(along_x, (7.0, 2.0))
    assert wide[1:] == pytest.approx((unit[1] / 4, unit[2] / 16), rel=1e-12)
    across = masked_moments(along_x.T, (2.0, 7.0))
    assert across == pytest.approx(wide, rel=1e-12)
    with pytest.raises(ValueError, match="three defined pixels"):
        masked_moments(np.where(np.indices((6, 6)).sum(axis=0) % 2 == 0, 1.0, np.nan), (PIXEL, PIXEL))
