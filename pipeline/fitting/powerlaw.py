"""Power laws y = alpha x^-gamma fitted by least squares in log-log, and bootstrap helpers.

Every function is vectorized over leading axes: the last axis holds the points of one fit
(load steps) or the samples of one reduction (realizations). Points that are masked out,
non-finite or non-positive do not enter a fit.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

__all__ = [
    "PowerLawFit",
    "fit_power_law",
    "resample_counts",
    "bootstrap_log_mean",
    "bootstrap_median",
    "quantile_with_inf",
    "percentile_interval",
]


@dataclass(frozen=True)
class PowerLawFit:
    """Result of :func:`fit_power_law`; each attribute has the leading shape of the input.

    Attributes
    ----------
    alpha
        Prefactor, in the units of y (x is taken as dimensionless).
    gamma
        Decay exponent, dimensionless.
    residual
        Residuals log y - log(alpha x^-gamma) at every point (NaN where not fitted),
        natural log, shape of the input.
    residual_rms
        Root-mean-square of the fitted residuals, natural log.
    n_points
        Number of points that entered each fit.
    """

    alpha: np.ndarray
    gamma: np.ndarray
    residual: np.ndarray
    residual_rms: np.ndarray
    n_points: np.ndarray


def fit_power_law(x: ArrayLike, y: ArrayLike, mask: ArrayLike | None = None) -> PowerLawFit:
    """Least-squares fit of ``log y = log alpha - gamma log x`` along the last axis.

    Parameters
    ----------
    x
        Abscissae (e.g. normalized force F'), > 0, shape (..., n) or (n,).
    y
        Ordinates (e.g. normalized resistance R'), shape (..., n).
    mask
        Points allowed in the fit, broadcast against ``y``; default all.

    Returns
    -------
    PowerLawFit
        alpha and gamma are NaN where fewer than two distinct points remain.
    """
    x = np.asarray(x, dtype=float)
    y = np.asarray(y, dtype=float)
    x, y = np.broadcast_arrays(x, y)
    use = np.ones(y.shape, bool) if mask is None else np.broadcast_to(np.asarray(mask, bool), y.shape)
    with np.errstate(divide="ignore", invalid="ignore"):
        lx = np.log(x)
        ly = np.log(y)
    use = use & np.isfinite(lx) & np.isfinite(ly)
    weight = use.astype(float)
    lx0 = np.where(use, lx, 0.0)
    ly0 = np.where(use, ly, 0.0)
    n = weight.sum(-1)
    with np.errstate(divide="ignore", invalid="ignore"):
        mx = lx0.sum(-1) / n
        my = ly0.sum(-1) / n
        dx = np.where(use, lx0 - mx[..., None], 0.0)
        dy = np.where(use, ly0 - my[..., None], 0.0)
        sxx = (dx * dx).sum(-1)
        slope = (dx * dy).sum(-1) / sxx
        ok = (n >= 2) & (sxx > 0)
        slope = np.where(ok, slope, np.nan)
        intercept = my - slope * mx
        residual = np.where(use, ly - (intercept[..., None] + slope[..., None] * lx), np.nan)
        rms = np.sqrt(np.nansum(residual**2, -1) / n)
    return PowerLawFit(np.exp(intercept), -slope, residual, np.where(ok, rms, np.nan), n.astype(int))


def resample_counts(n_samples: int, n_resamples: int, rng: np.random.Generator) -> np.ndarray:
    """Bootstrap resamples as multiplicity counts.

    Parameters
    ----------
    n_samples
        Number of samples (realizations) drawn from, >= 1.
    n_resamples
        Number of bootstrap resamples, >= 1.
    rng
        Random generator.

    Returns
    -------
    numpy.ndarray
        Shape (n_resamples, n_samples), int: how often each sample is drawn; rows sum to
        ``n_samples``.
    """
    if n_samples < 1 or n_resamples < 1:
        raise ValueError(
            f"n_samples = {n_samples}, n_resamples = {n_resamples}: both must be >= 1"
        )
    draws = rng.integers(0, n_samples, size=(n_resamples, n_samples))
    counts = np.zeros((n_resamples, n_samples), dtype=np.int64)
    np.add.at(counts, (np.arange(n_resamples)[:, None], draws), 1)
    return counts


def bootstrap_log_mean(values: np.ndarray, counts: np.ndarray, geometric: bool) -> np.ndarray:
    """Geometric or arithmetic means over the finite samples of every bootstrap resample.

    Parameters
    ----------
    values
        Samples on the last axis, shape (..., n); +inf (open circuits) and NaN are excluded.
    counts
        Multiplicities from :func:`resample_counts`, shape (b, n).
    geometric
        Geometric mean if True, arithmetic mean otherwise.

    Returns
    -------
    numpy.ndarray
        Shape (..., b); NaN where a resample holds no finite sample.
    """
    finite = np.isfinite(values)
    with np.errstate(divide="ignore", invalid="ignore"):
        data = np.log(values) if geometric else values
    data = np.where(finite, data, 0.0)
    weights = counts.T.astype(float)
    total = data @ weights
    number = finite.astype(float) @ weights
    with np.errstate(divide="ignore", invalid="ignore"):
        mean = total / number
    return np.exp(mean) if geometric else mean


def bootstrap_median(values: np.ndarray, counts: np.ndarray) -> np.ndarray:
    """Medians over all samples (+inf included) of every bootstrap resample.

    Parameters
    ----------
    values
        Samples on the last axis, shape (..., n).
    counts
        Multiplicities from :func:`resample_counts`, shape (b, n).

    Returns
    -------
    numpy.ndarray
        Shape (..., b).
    """
    out = np.empty(values.shape[:-1] + (counts.shape[0],))
    index = np.arange(values.shape[-1])
    for b, row in enumerate(counts):
        sample = values[..., np.repeat(index, row)]
        out[..., b] = quantile_with_inf(sample, 0.5)
    return out


def quantile_with_inf(values: np.ndarray, q: float) -> np.ndarray:
    """Linear-interpolation quantile (numpy's default) along the last axis, +inf allowed.

    An interpolation that reaches an infinite neighbour with a positive weight is +inf;
    one that sits exactly on a finite sample is that sample. NaN samples are not allowed.

    Parameters
    ----------
    values
        Samples on the last axis, shape (..., n), no NaN.
    q
        Quantile in [0, 1].

    Returns
    -------
    numpy.ndarray
        Shape (...).
    """
    ordered = np.sort(values, axis=-1)
    position = q * (ordered.shape[-1] - 1)
    below = int(np.floor(position))
    above = min(below + 1, ordered.shape[-1] - 1)
    frac = position - below
    low = ordered[..., below]
    high = ordered[..., above]
    if frac == 0.0:
        return low
    with np.errstate(invalid="ignore"):
        mixed = low + frac * (high - low)
    return np.where(np.isinf(high), np.inf, mixed)


def percentile_interval(samples: np.ndarray, confidence: float) -> np.ndarray:
    """Percentile bootstrap interval over the last axis, ignoring NaN resamples.

    Parameters
    ----------
    samples
        Bootstrap estimates on the last axis, shape (..., b).
    confidence
        Confidence level in (0, 1), e.g. 0.95.

    Returns
    -------
    numpy.ndarray
        Shape (..., 2): lower and upper limits.
    """
    if not 0.0 < confidence < 1.0:
        raise ValueError(f"confidence = {confidence} is out of range: must be in (0, 1)")
    tail = 0.5 * (1.0 - confidence)
    limits = np.nanquantile(samples, [tail, 1.0 - tail], axis=-1)
    return np.moveaxis(limits, 0, -1)
