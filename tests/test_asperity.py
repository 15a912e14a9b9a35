"""F_n(h) against adaptive quadrature, its tails, and the 1/2 missing from Eq. 21 as printed."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import quad
from scipy.special import erfc

from g2tom.physics.asperity import (
    area_fraction,
    asperity_integral,
    asperity_integral_slope,
    asperity_pressure,
    log_asperity_integral,
)

ORDERS = (0.5, 1.0, 1.5)
X_GRID = np.concatenate([np.linspace(-40, 40, 33), [-12.1, -11.9, 11.9, 12.1, 12.5, -12.5, 0.3, -0.7]])


def _log_reference(x: float, n: float) -> float:
    """log f_n(x) by adaptive quadrature; for x >= 0 the factor phi(x) is taken out exactly."""
    if x < 0:
        f = lambda z: (z - x) ** n * math.exp(-z * z / 2)  # noqa: E731
        core, _ = quad(f, x, 12.0, points=[min(-1.0, x / 2), 0.0, 1.0] if x < -1 else None,
                       epsabs=0, epsrel=1e-13, limit=400)
        val = core + quad(f, 12.0, np.inf, epsabs=0, epsrel=1e-13)[0]
        return math.log(val) - 0.5 * math.log(2 * math.pi)
    val, _ = quad(lambda t: t**n * math.exp(-x * t - t * t / 2), 0, np.inf,
                  epsabs=0, epsrel=1e-13, limit=400)
    return math.log(val) - x * x / 2 - 0.5 * math.log(2 * math.pi)


@pytest.mark.parametrize("n", ORDERS)
def test_matches_quadrature_over_pm40_sigma(n):
    got = log_asperity_integral(X_GRID, n)
    ref = np.array([_log_reference(x, n) for x in X_GRID])
    np.testing.assert_allclose(got, ref, rtol=0, atol=1e-10)


@pytest.mark.parametrize("n", ORDERS)
def test_dimensional_form_scales_with_sigma(n):
    sigma = 20e-6
    h = np.array([-3.0, 0.0, 2.0]) * sigma
    ref = np.array([math.exp(_log_reference(x, n)) for x in h / sigma]) * sigma**n
    np.testing.assert_allclose(asperity_integral(h, sigma, n), ref, rtol=1e-12)


def test_f1_closed_form_needs_the_half():
    x = np.array([-2.0, -0.5, 0.0, 0.5, 2.0])
    ref = np.array([math.exp(_log_reference(v, 1.0)) for v in x])
    phi = np.exp(-x * x / 2) / math.sqrt(2 * math.pi)
    corrected = phi - x * 0.5 * erfc(x / math.sqrt(2))
    printed = phi - x * erfc(x / math.sqrt(2))  # Eq. 21 as printed
    np.testing.assert_allclose(corrected, ref, rtol=1e-13)
    np.testing.assert_allclose(asperity_integral(x, 1.0, 1.0), ref, rtol=1e-13)
    assert not np.allclose(printed, ref, rtol=1e-3)


@pytest.mark.parametrize("n", ORDERS)
def test_tails_finite_positive_monotone(n):
    x = np.concatenate([-np.logspace(8, -3, 400), np.logspace(-3, 8, 400)])
    logs = log_asperity_integral(x, n)
    assert np.all(np.isfinite(logs))
    assert np.all(np.diff(logs) < 0)
    f = asperity_integral(np.array([-1e6, -40, 0, 30, 37]), 1.0, n)
    assert np.all(np.isfinite(f)) and np.all(f > 0) and np.all(np.diff(f) < 0)
    # polynomial-dominated lower tail: f_n(x) -> |x|^n
    np.testing.assert_allclose(log_asperity_integral(np.array([-1e6]), n), n * math.log(1e6), rtol=1e-12)


def test_derivative_identity():
    """-dp/dh = 2 eta E* sqrt(beta) F_{1/2}(h), from d F_{3/2} / dh = -(3/2) F_{1/2}."""
    sigma, eta, beta, e_star = 20e-6, 2e8, 30e-6, 1.15e11
    h = np.linspace(-4, 6, 11) * sigma
    step = 1e-6 * sigma
    numeric = -(asperity_pressure(h + step, sigma, eta, beta, e_star)
                - asperity_pressure(h - step, sigma, eta, beta, e_star)) / (2 * step)
    stiffness = 2.0 * eta * e_star * np.sqrt(beta) * asperity_integral(h, sigma, 0.5)
    np.testing.assert_allclose(stiffness, numeric, rtol=1e-6)


def test_area_fraction_prefactor():
    sigma, eta, beta = 20e-6, 2e8, 30e-6
    expected = math.pi * eta * beta * sigma / math.sqrt(2 * math.pi)
    np.testing.assert_allclose(area_fraction(0.0, sigma, eta, beta), expected, rtol=1e-14)


@pytest.mark.parametrize("n", [-1.0, -2.0, float("nan")])
def test_bad_order(n):
    with pytest.raises(ValueError, match="n = .* out of range"):
        log_asperity_integral([0.0], n)


@pytest.mark.parametrize("sigma", [0.0, -1.0, float("inf")])
def test_bad_sigma(sigma):
    with pytest.raises(ValueError, match="sigma = .* out of range"):
        asperity_integral([0.0], sigma, 1.5)


@pytest.mark.parametrize("n", [0.5, 1.0, 1.5])
def test_slope_is_minus_the_derivative(n):
    x = np.array([-30.0, -3.0, -0.4, 0.0, 0.7, 4.0, 11.0, 13.0])
    step = 1e-5
    f = lambda y: np.exp(log_asperity_integral(y, n))  # noqa: E731
    numeric = -(f(x + step) - f(x - step)) / (2 * step)
    np.testing.assert_allclose(asperity_integral_slope(x, n), numeric, rtol=1e-6)


@pytest.mark.parametrize("n", [0.5, 1.5])
def test_repeated_separations_give_pbdv_own_bits(n):
    """The central range evaluates scipy's D_v once per distinct separation: a symmetric cell grid
    (each value up to eight times, +0 and -0 among them) gets exactly pbdv's values (tolerance 0)."""
    from scipy.special import gammaln, pbdv

    c = np.arange(-6, 7) * 0.37
    x = np.concatenate([np.hypot(c[None, :], c[:, None]).ravel() - 2.0, [0.0, -0.0]])
    expected = gammaln(n + 1.0) - 0.5 * np.log(2.0 * np.pi) - 0.25 * x * x + np.log(pbdv(-n - 1.0, x)[0])
    assert np.array_equal(log_asperity_integral(x, n).view(np.int64), expected.view(np.int64))
