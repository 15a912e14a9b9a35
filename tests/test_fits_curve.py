"""The fits stage's curve model and its fit range in F'."""

from __future__ import annotations

import numpy as np
import pytest

from g2tom.config import ConfigError
from g2tom.before_work import load_scenario
from g2tom.stages import fits
from tests.conftest import SMALL_OVERRIDES
from tests.test_fits_stage import assert_labelled, synthetic_cube, true_alpha, true_gamma

#: 16 load steps from 20 N to 5 kN, 10 of them at F >= 200 N.
SCENARIO = load_scenario("paper_gt", {**SMALL_OVERRIDES, "loading.n_delta": 16})
CURVATURE = 0.06  # ln R' gains CURVATURE (ln F')^2: the power law misses it by > 3 %


def _curved_cube(noise: float):
    cube = synthetic_cube(SCENARIO, noise=noise)
    bend = np.exp(CURVATURE * np.log(cube["force_normalized"]) ** 2)
    cube["resistance"] = cube["resistance"] * bend
    cube["resistance_clean"] = cube["resistance_clean"] * bend
    return cube


def test_noise_free_curve_is_recovered_exactly():
    """ln R' = ln alpha - gamma ln F' + c (ln F')^2: order 2 with exactly those coefficients."""
    ds = fits.build(SCENARIO, _curved_cube(0.0))
    lam, xi = np.asarray(SCENARIO.oxide.lambda_), np.asarray(SCENARIO.oxide.xi)
    assert np.all(ds["curve_order"] == 2) and np.all(ds["curve_within"] == 1)
    coef = ds["curve_coefficients"].transpose("xi", "lambda", "power").values
    np.testing.assert_allclose(coef[..., 0], np.log(true_alpha(lam, xi).T), atol=1e-9)
    np.testing.assert_allclose(coef[..., 1], -true_gamma(lam, xi).T, atol=1e-9)
    np.testing.assert_allclose(coef[..., 2], CURVATURE, atol=1e-9)
    np.testing.assert_allclose(coef[..., 3], 0.0)
    assert float(ds["curve_max_error"].max()) < 1e-9
    assert float(np.abs(np.expm1(ds["fit_residual"])).max()) > 0.03  # what the power law misses
    assert int(ds["curve_order_clean"]) == 2
    np.testing.assert_allclose(ds["curve_coefficients_clean"].values, [np.log(0.8), -0.23, CURVATURE, 0.0],
                               atol=1e-9)


def test_power_law_cube_is_order_one():
    ds = fits.build(SCENARIO, synthetic_cube(SCENARIO, noise=0.0))
    assert np.all(ds["curve_order"] == 1) and int(ds["curve_order_clean"]) == 1
    np.testing.assert_allclose(np.exp(ds["curve_coefficients"].sel(power=0)), ds["alpha"], rtol=1e-9)
    np.testing.assert_allclose(-ds["curve_coefficients"].sel(power=1), ds["gamma"], rtol=1e-9)


def test_noisy_curves_keep_their_promise():
    """Every cell marked within is inside max(3 %, the step's interval) at every fitted step,
    recomputed from the stored coefficients and intervals; the others reached the top order."""
    ds = fits.build(SCENARIO, _curved_cube(0.3))
    fitted = ds["fitted"].values.astype(bool)
    gm = ds["geometric_mean_normalized"].transpose("xi", "lambda", "delta").values[..., fitted]
    ci = ds["geometric_mean_normalized_ci"].transpose("xi", "lambda", "delta", "bound").values[..., fitted, :]
    assert np.all(np.isnan(ds["geometric_mean_normalized_ci"].values[:, :, ~fitted]))
    # the interval of a geometric mean of 8 log-normal samples (sigma 0.3): half-width ~ 1.96 * 0.3 / sqrt(8)
    half = 0.5 * np.log(ci[..., 1] / ci[..., 0])
    assert np.median(half) == pytest.approx(1.96 * 0.3 / np.sqrt(8), rel=0.3)
    coef = ds["curve_coefficients"].transpose("xi", "lambda", "power").values
    lx = np.log(ds["force_normalized"].values[fitted])
    model = np.exp(sum(coef[..., k, None] * lx**k for k in range(coef.shape[-1])))
    close = np.abs(model / gm - 1) <= 0.03
    inside = close | ((model >= ci[..., 0]) & (model <= ci[..., 1]))
    level = ds["curve_within"].values
    assert np.all(close.all(-1)[level == 1])
    within = level > 0
    # independent noise at every step (harsher than a cube, whose realizations are smooth in F):
    # some cells' means stray outside a 95 % interval at one of the 10 steps
    assert within.any() and not within.all()
    assert np.all(inside[within]) and not np.any(inside[~within].all(-1))
    assert np.all(ds["curve_order"].values[~within] == SCENARIO.fits.curve_max_order)
    np.testing.assert_allclose(ds["curve_max_error"], np.abs(model / gm - 1).max(-1), rtol=1e-9)


def test_fit_range_in_normalized_force_selects_the_same_steps():
    cube = synthetic_cube(SCENARIO, noise=0.1)
    k = 9
    by_newtons = load_scenario("paper_gt", {**SMALL_OVERRIDES, "loading.n_delta": 16,
                                         "fits.fit_range": "force", "fits.min_force": float(cube["force"][k])})
    by_normalized = load_scenario("paper_gt", {**SMALL_OVERRIDES, "loading.n_delta": 16,
                                            "fits.fit_range": "force_normalized",
                                            "fits.min_force_normalized": float(cube["force_normalized"][k])})
    a, b = fits.build(by_newtons, cube), fits.build(by_normalized, cube)
    assert a["fitted"].values.tolist() == [0] * k + [1] * (16 - k) == b["fitted"].values.tolist()
    for name in ("alpha", "gamma", "alpha_ci", "curve_coefficients", "geometric_mean_normalized_ci"):
        np.testing.assert_array_equal(a[name].values, b[name].values)
    assert b.attrs["fit_range"] == f"F' >= {by_normalized.fits.min_force_normalized:g}"
    assert "F'" in b["fitted"].attrs["long_name"]


def test_unreachable_normalized_range_is_a_config_error():
    scenario = load_scenario("paper_gt", {**SMALL_OVERRIDES, "fits.fit_range": "force_normalized",
                                       "fits.min_force_normalized": 1e6})
    with pytest.raises(ConfigError, match="fits.min_force_normalized = 1e.06 is out of range"):
        fits.build(scenario, synthetic_cube(scenario))


def test_curve_outputs_are_labelled():
    assert_labelled(fits.build(SCENARIO, _curved_cube(0.1)))


def test_curves_of_realizations_smooth_in_force_are_all_within():
    """Each realization a smooth curve times its own factor (as in a cube): every cell within 3 %."""
    cube = _curved_cube(0.0)
    rng = np.random.default_rng(11)
    factor = np.exp(0.3 * rng.standard_normal(cube["resistance"].shape[:2] + (1, cube.sizes["realization"])))
    cube["resistance"] = cube["resistance"] * factor
    ds = fits.build(SCENARIO, cube)
    assert np.all(ds["curve_within"] == 1) and np.all(ds["curve_order"] == 2)
    assert float(ds["curve_max_error"].max()) < 1e-9
