"""The full-field reference (g2tom.reference, the `reference` extra): checked before it is trusted.

`make test` installs the extra, so nothing here is skipped: a missing tamaas fails these tests.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from tests.oracles import roughness_parameters
from g2tom.reference import elastic, surfaces
from g2tom.reference.contact import contact_at_force
from g2tom.reference.oxide import field_on_grid, oxide_on_grid
from g2tom.reference.punch import punch_conductance
from g2tom.scene import FieldSource

E_STAR, RHO = 1.154e11, 7.2e-7


def test_smooth_sphere_gives_hertz_force_radius_approach_and_conductance() -> None:
    n, side, radius = 128, 1e-3, 5e-3
    pixel = side / n
    a = 0.3 * side  # 38 pixels
    force = 4.0 * E_STAR * a**3 / (3.0 * radius)
    operator = elastic.free_surface(n, pixel, E_STAR)
    state = contact_at_force(operator, surfaces.sphere(n, pixel, radius), force)
    assert state.force == pytest.approx(force, rel=1e-9)
    assert state.gap_spread < 1e-6 * a**2 / radius  # the gap is closed on the whole contact set
    assert np.sqrt(state.contact.sum() * pixel**2 / np.pi) == pytest.approx(a, rel=0.01)
    assert state.delta == pytest.approx(-(a**2) / radius, rel=0.01)  # g2tom's convention: delta = -a^2/R
    kappa = punch_conductance(operator, state.contact, RHO).conductance
    assert kappa == pytest.approx(2.0 * a / RHO, rel=0.01)


def test_flat_disc_conductance_is_2a_over_rho() -> None:
    n, pixel = 128, 1e-5
    x, y = surfaces.coordinates(n, pixel)
    a = 40.5 * pixel
    disc = np.hypot(x, y) <= a
    result = punch_conductance(elastic.free_surface(n, pixel, E_STAR), disc, RHO)
    a_eff = np.sqrt(disc.sum() / np.pi) * pixel  # the pixelated disc's equal-area radius
    assert result.conductance == pytest.approx(2.0 * a_eff / RHO, rel=0.01)
    assert result.stiffness == pytest.approx(2.0 * a_eff * E_STAR, rel=0.01)
    assert punch_conductance(elastic.free_surface(n, pixel, E_STAR), np.zeros((n, n), bool), RHO).conductance == 0.0


def test_barber_theorem_on_a_rough_sphere() -> None:
    """Punch conductance on the contact set = K / (E* rho*), K = dF/d(-delta) from two nearby loads."""
    n, sigma, eta, beta = 128, 20e-6, 2e8, 60e-6
    pixel = 1.0 / np.sqrt(eta) / 8.0
    asperities = surfaces.gw_asperities(n * pixel, eta, sigma, beta, np.random.default_rng(3))
    heights = surfaces.gw_heights(asperities, n, pixel, -8 * sigma) + surfaces.sphere(n, pixel, 2e-3)
    operator = elastic.free_surface(n, pixel, E_STAR)
    low, mid, high = (contact_at_force(operator, heights, f) for f in (297.0, 300.0, 303.0))
    assert mid.contact.sum() > 100 and not np.array_equal(low.contact, high.contact)  # many spots; the set grows
    stiffness = -(high.force - low.force) / (high.delta - low.delta)
    kappa = punch_conductance(operator, mid.contact, RHO).conductance
    assert kappa == pytest.approx(stiffness / (E_STAR * RHO), rel=0.02)


@pytest.mark.parametrize("lam", [1.0, 5.0])  # window period (folded cell values) and a spectral period
def test_oxide_field_on_the_grid_is_g2toms_field_at_the_cell_centres(small, lam) -> None:
    small = dataclasses.replace(small, oxide=dataclasses.replace(small.oxide, lambda_=[lam]))
    source = FieldSource.of(small)
    n_cells, cell = small.n_cells, small.cell_size
    realization = 5
    psi, threshold = source.fields(0, np.array([realization]))
    # a grid of pitch cell / 3 over the window: its pixel centres include every cell centre
    grid = field_on_grid(source, 0, realization, 3 * n_cells, cell / 3.0)
    np.testing.assert_allclose(grid[1::3, 1::3], psi[0], rtol=0, atol=1e-6)
    masks = oxide_on_grid(source, 0, realization, 3 * n_cells, cell / 3.0)
    np.testing.assert_array_equal(masks[:, 1::3, 1::3], psi[0][None] >= threshold[:, 0, None, None])
    assert 0.3 < masks[1].mean() < 0.7  # xi = 0.5: about half the grid is oxide


@pytest.mark.parametrize("side", [0.3e-3, 1e-3])  # a window inside the surface, and the surface itself
def test_gw_heights_are_the_highest_tip_over_every_asperity(side) -> None:
    """Against the brute-force maximum over all asperities (the same expression, so equal bit for bit)."""
    asperities = surfaces.gw_asperities(1e-3, 2e8, 20e-6, 60e-6, np.random.default_rng(7))
    n, floor = 48, -3 * 20e-6
    pixel = side / n
    x, y = surfaces.coordinates(n, pixel)
    tips = asperities.z[:, None, None] - ((x[None] - asperities.x[:, None, None]) ** 2
                                          + (y[None] - asperities.y[:, None, None]) ** 2) / (2.0 * asperities.beta)
    expected = np.maximum(tips.max(axis=0), floor)
    np.testing.assert_array_equal(surfaces.gw_heights(asperities, n, pixel, floor), expected)


def test_gw_surface_has_the_asked_density_heights_and_tip_radius() -> None:
    eta, sigma, beta, side = 2e8, 20e-6, 60e-6, 6e-3  # 7200 asperities expected
    rng = np.random.default_rng(11)
    asperities = surfaces.gw_asperities(side, eta, sigma, beta, rng)
    expected = eta * side**2
    assert abs(asperities.z.size - expected) < 4.0 * np.sqrt(expected)
    assert abs(np.mean(asperities.z)) < 4.0 * sigma / np.sqrt(expected)
    assert np.std(asperities.z) == pytest.approx(sigma, rel=4.0 * np.sqrt(0.5 / expected))
    assert np.all(np.abs(asperities.x) <= side / 2) and np.all(np.abs(asperities.y) <= side / 2)
    # the rendered surface near the highest tip is the paraboloid of radius beta
    n, pixel = 1024, side / 1024
    heights = surfaces.gw_heights(asperities, n, pixel, -8 * sigma)
    top = int(np.argmax(asperities.z))
    x, y = surfaces.coordinates(n, pixel)
    near = np.hypot(x - asperities.x[top], y - asperities.y[top]) < 5 * pixel
    d2 = (x[near] - asperities.x[top]) ** 2 + (y[near] - asperities.y[top]) ** 2
    slope, intercept = np.polyfit(d2, heights[near], 1)
    assert -1.0 / (2.0 * slope) == pytest.approx(beta, rel=1e-9)
    assert intercept == pytest.approx(asperities.z[top], rel=1e-9)
    assert heights.min() == pytest.approx(-8 * sigma)


def test_random_process_gw_parameters_match_the_spectrum_closed_forms() -> None:
    """roughness.py's finite-difference moments of a synthetic surface against the band's integrals."""
    n, pixel, hurst, rms = 1024, 1e-6, 0.8, 1e-6
    q_low, q_high = 2 * np.pi / (64 * pixel), 2 * np.pi / (24 * pixel)
    heights = surfaces.random_process(n, pixel, hurst, q_low, q_high, rms, np.random.default_rng(2))
    measured = roughness_parameters(heights, pixel)
    m0, m2, m4 = surfaces.spectral_moments_closed_form(hurst, q_low, q_high, rms)
    # finite differences underestimate m2, m4 by ~(q h)^2/4 and /8 at 24 pixels per wavelength (roughness.py)
    assert measured.sigma**2 == pytest.approx(m0, rel=1e-3)
    assert measured.m2 == pytest.approx(m2, rel=0.03)
    assert measured.m4 == pytest.approx(m4, rel=0.03)
    assert measured.eta == pytest.approx(np.sqrt(3) / (18 * np.pi) * m4 / m2, rel=0.02)
    assert measured.beta == pytest.approx(0.737 / np.sqrt(m4), rel=0.02)
    with pytest.raises(ValueError, match="q_low"):
        surfaces.random_process(n, pixel, hurst, q_high, q_low, rms, np.random.default_rng(2))


def test_only_the_reference_package_imports_the_extra() -> None:
    from pathlib import Path

    root = Path(__file__).resolve().parents[1]
    importers = {p.relative_to(root).as_posix() for folder in ("pipeline", "analysis")
                 for p in (root / folder).rglob("*.py") if "import tamaas" in p.read_text()}
    assert importers == {"pipeline/reference/__init__.py", "pipeline/reference/elastic.py"}


def test_random_process_is_one_surface_on_every_grid() -> None:
    """Grids of pitch p and p/3 over one period sample the same continuous surface: every third
    pixel centre of the fine grid (offset 1) is a centre of the coarse grid."""
    period, hurst, rms = 64e-6, 0.8, 1e-6
    q_low, q_high = 2 * np.pi / (32e-6), 2 * np.pi / (8e-6)
    coarse = surfaces.random_process(64, 1e-6, hurst, q_low, q_high, rms, np.random.default_rng(4), period)
    fine = surfaces.random_process(192, 1e-6 / 3, hurst, q_low, q_high, rms, np.random.default_rng(4), period)
    np.testing.assert_allclose(fine[1::3, 1::3], coarse, rtol=0, atol=1e-12 * rms)
    assert np.std(coarse) == pytest.approx(rms, rel=1e-9)  # a whole period: the continuous variance
