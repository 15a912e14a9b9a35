"""The curve model ln R' = polynomial(ln F') and its order rule."""

from __future__ import annotations

import numpy as np
import pytest
from numpy.polynomial import polynomial

from g2tom.fitting.curve_model import evaluate_curve, fit_curve, tolerance_band
from g2tom.fitting.powerlaw import fit_power_law

FORCE = np.geomspace(0.5, 19.0, 16)  # F' over the paper's fitted loads


def _barber_like(force: np.ndarray) -> np.ndarray:
    """R' whose local exponent -d ln R'/d ln F' = 0.38 + 0.34 exp(-(u - u0)/1.09) falls 0.72 -> 0.39."""
    u = np.log(force) - np.log(force[0])
    return 0.6 * np.exp(-0.38 * u + 0.34 * 1.09 * (np.exp(-u / 1.09) - 1.0))


def test_barber_like_curve_has_the_stated_exponents():
    local = -np.gradient(np.log(_barber_like(FORCE)), np.log(FORCE), edge_order=2)
    assert local[0] == pytest.approx(0.72, abs=0.01) and local[-1] == pytest.approx(0.39, abs=0.01)


def test_power_law_is_order_one():
    y = 0.8 * FORCE**-0.31
    fit = fit_curve(FORCE, y, 0.03)
    assert fit.order == 1 and fit.within == 1
    np.testing.assert_allclose(fit.coefficients, [np.log(0.8), -0.31, 0.0, 0.0], atol=1e-12)
    assert fit.max_error < 1e-12


def test_recovers_a_cubic_in_log_force():
    c = np.array([0.2, -0.5, 0.12, -0.03])
    y = np.exp(polynomial.polyval(np.log(FORCE), c))
    fit = fit_curve(FORCE, y, 0.001, max_order=4)
    assert fit.order == 3 and fit.within == 1  # no lower order is within 0.1 %
    np.testing.assert_allclose(fit.coefficients, np.append(c, 0.0), atol=1e-10)
    np.testing.assert_allclose(evaluate_curve(fit.coefficients, FORCE), np.log(y), atol=1e-12)


def test_barber_like_curve_within_three_percent():
    y = _barber_like(FORCE)
    power = fit_power_law(FORCE, y)
    assert np.max(np.abs(np.expm1(power.residual))) > 0.05  # the power law misses it
    fit = fit_curve(FORCE, y, 0.03)
    assert fit.within == 1 and fit.order in (2, 3) and fit.max_error <= 0.03
    model = np.exp(evaluate_curve(fit.coefficients, FORCE))
    assert np.max(np.abs(model / y - 1)) == pytest.approx(fit.max_error, rel=1e-12)


def test_interval_widens_the_band():
    """A noisy power law: 3 % alone needs a high order, its intervals accept the line."""
    rng = np.random.default_rng(3)
    truth = 0.8 * FORCE**-0.31
    y = truth * np.exp(0.06 * rng.standard_normal(FORCE.size))
    interval = np.stack([0.8 * y, 1.2 * y], axis=-1)  # +-20 %: the noise is 6 % RMS
    tight = fit_curve(FORCE, y, 0.03)
    loose = fit_curve(FORCE, y, 0.03, interval)
    assert tight.within == 0 and tight.order == 3
    assert loose.within == 2 and loose.order == 1  # within the intervals only
    lower, upper = tolerance_band(y, 0.03, interval)
    np.testing.assert_allclose(lower, np.log(np.minimum(0.97, interval[:, 0] / y)), rtol=1e-14)
    np.testing.assert_allclose(upper, np.log(np.maximum(1.03, interval[:, 1] / y)), rtol=1e-14)


def test_vectorized_over_cells_with_masks_and_gaps():
    y = np.stack([0.8 * FORCE**-0.31, _barber_like(FORCE), np.full(FORCE.size, np.nan)])
    y[1, 3] = np.inf  # an open-circuit mean: not fitted
    mask = FORCE >= 0.6
    fit = fit_curve(FORCE, y, 0.03, mask=mask)
    assert fit.coefficients.shape == (3, 4) and np.all(np.isnan(fit.coefficients[2]))
    assert list(fit.order) == [1, fit.order[1], 0] and fit.order[1] >= 2
    assert list(fit.n_points) == [mask.sum(), mask.sum() - 1, 0]
    assert np.all(np.isnan(fit.residual[:, ~mask])) and np.isnan(fit.max_error[2])
    alone = fit_curve(FORCE, y[1], 0.03, mask=mask)
    np.testing.assert_array_equal(alone.coefficients, fit.coefficients[1])


def test_the_tolerance_comes_before_the_interval():
    """A curved mean whose intervals would pass the power law still gets its shape to 3 %."""
    y = _barber_like(FORCE)
    interval = np.stack([0.7 * y, 1.3 * y], axis=-1)
    fit = fit_curve(FORCE, y, 0.03, interval)
    assert fit.within == 1 and fit.order >= 2 and fit.max_error <= 0.03


def test_order_never_exceeds_the_points():
    x, y = FORCE[:3], _barber_like(FORCE)[:3] * np.array([1.0, 1.2, 1.0])
    fit = fit_curve(x, y, 0.01, max_order=4)
    assert fit.order == 2 and fit.within == 1 and fit.max_error < 1e-12  # interpolates the three


@pytest.mark.parametrize(("call", "message"), [
    (lambda: fit_curve(FORCE, FORCE, 0.03, max_order=0), "max_order = 0 is out of range"),
    (lambda: tolerance_band(FORCE, 0.0), "relative = 0.0 is out of range"),
])
def test_bad_arguments(call, message):
    with pytest.raises(ValueError, match=message):
        call()


def test_interpolation_error_of_a_grid_of_curves():
    """Zero for values linear in both coordinates; for a quadratic in u, the leave-one-out error of
    linear interpolation from the two neighbours is h^2 a / ... = a (h_-) (h_+) exactly."""
    from g2tom.fitting.curve_model import interpolation_error

    u, v = np.array([0.0, 1.0, 3.0, 4.0]), np.array([0.0, 0.5, 2.0])
    steps = np.array([1.0, 2.0])
    linear = 0.3 * u[:, None, None] - 1.2 * v[None, :, None] + steps
    np.testing.assert_allclose(interpolation_error(linear, u, v), 0.0, atol=1e-14)
    quad = 0.5 * u[:, None, None] ** 2 + 0.0 * v[None, :, None] + 0.0 * steps
    got = interpolation_error(quad, u, v)
    inner = 0.5 * np.array([1.0 * 2.0, 2.0 * 1.0])  # a h_- h_+ at u = 1 and u = 3
    expected_u = np.array([inner[0], inner[0], inner[1], inner[1]])  # edges take the nearest interior
    np.testing.assert_allclose(got, (expected_u / np.sqrt(2.0))[:, None] * np.ones(3), rtol=1e-12)
    assert np.isnan(interpolation_error(quad[:2, :2], u[:2], v[:2])).all()
