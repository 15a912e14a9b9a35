"""Log-log least squares and bootstrap helpers."""

from __future__ import annotations

import numpy as np
import pytest

from g2tom.fitting import powerlaw


def test_exact_power_law_vectorized() -> None:
    x = np.geomspace(0.5, 20, 9)
    alpha = np.array([[1.0], [2.5]])
    gamma = np.array([[0.2], [0.6]])
    fit = powerlaw.fit_power_law(x, alpha * x**-gamma)
    np.testing.assert_allclose(fit.alpha, alpha[:, 0], rtol=1e-12)
    np.testing.assert_allclose(fit.gamma, gamma[:, 0], rtol=1e-12)
    assert np.all(fit.residual_rms < 1e-12)


def test_mask_and_non_finite_points_are_skipped() -> None:
    x = np.geomspace(0.5, 20, 6)
    y = 3.0 * x**-0.4
    y_bad = y.copy()
    y_bad[0] = 1e9  # masked out
    y_bad[1] = np.nan  # not finite
    y_bad[2] = np.inf
    mask = np.array([False, True, True, True, True, True])
    fit = powerlaw.fit_power_law(x, y_bad, mask)
    assert fit.alpha == pytest.approx(3.0) and fit.gamma == pytest.approx(0.4)
    assert fit.n_points == 3
    assert np.isnan(fit.residual[0])


def test_too_few_points_give_nan() -> None:
    fit = powerlaw.fit_power_law([1.0, 2.0], [np.nan, 1.0])
    assert np.isnan(fit.alpha) and np.isnan(fit.gamma)


def test_resample_counts_rows_sum_to_n() -> None:
    counts = powerlaw.resample_counts(7, 100, np.random.default_rng(0))
    assert counts.shape == (100, 7) and np.all(counts.sum(1) == 7)


def test_bootstrap_means_match_explicit_resampling() -> None:
    rng = np.random.default_rng(3)
    values = rng.lognormal(size=(2, 3, 6))
    values[0, 0, 2] = np.inf
    counts = powerlaw.resample_counts(6, 5, rng)
    geo = powerlaw.bootstrap_log_mean(values, counts, geometric=True)
    ari = powerlaw.bootstrap_log_mean(values, counts, geometric=False)
    med = powerlaw.bootstrap_median(values, counts)
    for b, row in enumerate(counts):
        sample = values[..., np.repeat(np.arange(6), row)]
        finite = np.where(np.isfinite(sample), sample, np.nan)
        np.testing.assert_allclose(geo[..., b], np.exp(np.nanmean(np.log(finite), -1)))
        np.testing.assert_allclose(ari[..., b], np.nanmean(finite, -1))
        np.testing.assert_allclose(med[..., b][1:], np.median(sample, -1)[1:])


def test_quantile_with_inf_matches_numpy_when_finite() -> None:
    values = np.random.default_rng(1).normal(size=(4, 11))
    for q in (0.0, 0.16, 0.5, 0.84, 1.0):
        np.testing.assert_allclose(powerlaw.quantile_with_inf(values, q), np.quantile(values, q, axis=-1))


def test_percentile_interval() -> None:
    samples = np.arange(1001.0)
    lo, hi = powerlaw.percentile_interval(samples, 0.9)
    assert lo == pytest.approx(50.0) and hi == pytest.approx(950.0)
    with pytest.raises(ValueError, match="confidence"):
        powerlaw.percentile_interval(samples, 1.5)
