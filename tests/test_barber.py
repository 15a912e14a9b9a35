"""Barber's bounds and their oxide extension (Sect. 2.3, Eqs. 4-10)."""

from __future__ import annotations

import numpy as np
import pytest

from g2tom.physics import barber


def test_f_of_zero_is_one() -> None:
    assert barber.oxide_factor(0.0) == 1.0


def test_f_as_printed() -> None:
    xi = 0.5
    pi2 = np.pi**2
    expected = 1 - 2 / pi2 * xi**1.5 - 8 / (15 * pi2) * xi**2.5 - 16 / (27 * pi2) * xi**3 \
        - 92 / (315 * pi2) * xi**3.5 - 416 / (675 * pi2) * xi**4
    assert barber.oxide_factor(xi) == pytest.approx(expected, rel=1e-14)
    assert np.all(np.diff(barber.oxide_factor(np.linspace(0, 1, 11))) < 0)


def test_eq7_roots_solve_eq6() -> None:
    """Eq. 7's two roots, x_plus = 1/2 + cos(theta) in [1, 3/2] and x_minus = 1/2 + cos(theta - 2 pi/3)
    in [0, 1] with theta = arccos(6 S - 1) / 3, solve Eq. 6 (labels swapped as printed, see barber)."""
    S = np.linspace(0.0, 1.0 / 3.0, 41)
    theta = np.arccos(np.clip(6.0 * S - 1.0, -1.0, 1.0)) / 3.0
    x_plus, x_minus = 0.5 + np.cos(theta), 0.5 + np.cos(theta - 2.0 * np.pi / 3.0)
    np.testing.assert_allclose(barber.shape_parameter(x_plus), S, atol=1e-13)
    np.testing.assert_allclose(barber.shape_parameter(x_minus), S, atol=1e-13)
    assert np.all((x_plus >= 1 - 1e-12) & (x_plus <= 1.5 + 1e-12))
    assert np.all((x_minus >= -1e-12) & (x_minus <= 1 + 1e-12))


def test_bounds_follow_the_parametric_curve() -> None:
    # pick x on each branch, compute F' and kappa' by Eq. 8 and recover them
    for x in (0.3, 0.7, 0.95):
        S = barber.shape_parameter(x)
        force = 8 / 3 * (x**2 / S) ** 1.5
        upper, _ = barber.clean_bounds(force)
        assert upper == pytest.approx(4 / np.sqrt(S), rel=1e-10)
    for x in (1.05, 1.5, 4.0):
        S = barber.shape_parameter(x)
        force = 8 / 3 * (x**2 / S) ** 1.5
        _, lower = barber.clean_bounds(force)
        assert lower == pytest.approx(4 / np.sqrt(S), rel=1e-10)


def test_clean_bounds_bracket_their_mean() -> None:
    force = np.geomspace(1e-3, 1e3, 50)
    upper, lower = barber.clean_bounds(force)
    assert np.all(lower < upper)
    for p in (-1.0, 0.0, 0.6, 1.0):
        mean = barber.p_average(force, 0.0, p)
        assert np.all((lower <= mean) & (mean <= upper))
    assert np.all(np.diff(upper) > 0) and np.all(np.diff(lower) > 0)


def test_oxide_lowers_both_bounds() -> None:
    force = np.geomspace(0.1, 100, 7)
    up0, lo0 = barber.oxide_bounds(force, 0.0)
    up, lo = barber.oxide_bounds(force, 0.5)
    np.testing.assert_allclose(up, up0 * barber.oxide_factor(0.5))
    np.testing.assert_allclose(lo, lo0 * np.sqrt(0.5))


def test_p_to_zero_is_geometric_mean() -> None:
    force = np.geomspace(0.1, 100, 7)
    up, lo = barber.oxide_bounds(force, 0.3)
    geometric = np.sqrt(up * lo)
    np.testing.assert_allclose(barber.p_average(force, 0.3, 0.0), geometric, rtol=1e-14)
    np.testing.assert_allclose(barber.p_average(force, 0.3, 1e-7), geometric, rtol=1e-6)
    np.testing.assert_allclose(barber.p_average(force, 0.3, 1.0), 0.5 * (up + lo), rtol=1e-14)


def test_sigma_normalization() -> None:
    force = np.array([0.5, 2.0, 16.0])
    # s = sigma: the two normalizations coincide
    np.testing.assert_allclose(barber.p_average_sigma(force, 0.3, 0.6, 1.0), barber.p_average(force, 0.3, 0.6))
    # s = 2 sigma, through physical units: F from F'_sigma, F'_s from F, kappa from kappa'_s
    e_star, r_star, rho, sigma = 1.15e11, 0.01, 7.2e-7, 2e-5
    s = 2.0 * sigma
    f_newton = force * e_star * np.sqrt(r_star * sigma**3) / 2
    kappa = barber.p_average(2 * f_newton / (e_star * np.sqrt(r_star * s**3)), 0.3, 0.0) * np.sqrt(r_star * s) / (2 * rho)
    np.testing.assert_allclose(barber.p_average_sigma(force, 0.3, 0.0, 2.0), 2 * rho * kappa / np.sqrt(r_star * sigma))


def test_bad_input() -> None:
    with pytest.raises(ValueError, match="xi"):
        barber.oxide_factor(1.5)
    with pytest.raises(ValueError, match="force"):
        barber.clean_bounds([1.0, -1.0])
