"""The geometric mean of R over realizations with a control variate, and its bootstrap.

At each load step, realization r gives ``y_r = ln R_r`` where it conducts (``c_r = 1``; an open
circuit has ``c_r = 0``) and its control ``x_r`` (the spots' radius-weighted clean share,
:func:`g2tom.models.discrete_cube.weighted_clean_share`), whose expectation ``p`` over all
realizations is known exactly (:func:`g2tom.physics.oxide_marginal.clean_probability`). The
geometric mean is over the conducting realizations, E[y | c = 1] = E[y c] / E[c], so numerator and
denominator are each adjusted by the control:

    (mean(y c) - b_n (mean(x) - p)) / (mean(c) - b_d (mean(x) - p)),
    b_n = cov(x, y c) / var(x),  b_d = cov(x, c) / var(x).

Without open circuits the denominator is 1 and this is ``mean(y) - b (mean(x) - p)``, whose
variance is that of mean(y) times 1 - rho^2 (rho the correlation of x and y); with them, the
share of conducting realizations, itself strongly tied to the clean share, is adjusted alike. The
estimate is consistent, its bias O(1/n) (b and the ratio come from the same realizations).

Bootstrap resamples are multiplicity tables (:func:`g2tom.fitting.powerlaw.resample_counts`):
each resample's means and covariances come from weighted sums, so the whole table is a few matrix
products, as for the plain mean (:func:`g2tom.fitting.powerlaw.bootstrap_log_mean`).
"""

from __future__ import annotations

import numpy as np

from g2tom.fitting.powerlaw import bootstrap_log_mean

__all__ = ["controllable", "bootstrap_controlled_mean", "controlled_mean", "MIN_CONTROL_VARIANCE"]

#: Least variance of the control (its values are shares in [0, 1]) for the slopes to be estimated.
MIN_CONTROL_VARIANCE = 1e-12


def controllable(values: np.ndarray, control: np.ndarray) -> np.ndarray:
    """Where the control variate applies: at least three realizations (last axis), every control
    finite, the controls varying and some realization conducting. Shape ``values.shape[:-1]``."""
    finite = np.all(np.isfinite(control), axis=-1)
    spread = np.var(np.where(np.isfinite(control), control, 0.0), axis=-1)
    conducting = np.any(np.isfinite(values) & (values > 0), axis=-1)
    return finite & conducting & (values.shape[-1] >= 3) & (spread > MIN_CONTROL_VARIANCE)


def bootstrap_controlled_mean(values: np.ndarray, control: np.ndarray, expected: np.ndarray,
                              counts: np.ndarray) -> np.ndarray:
    """Geometric means of every bootstrap resample, with the control variate where it applies.

    Parameters
    ----------
    values
        R (any positive unit; +inf an open circuit) on the last axis, shape (..., n).
    control
        The realizations' controls, shape (..., n).
    expected
        The controls' exact expectation, shape broadcasting to ``values.shape[:-1]``.
    counts
        Multiplicities from :func:`g2tom.fitting.powerlaw.resample_counts`, shape (b, n).

    Returns
    -------
    numpy.ndarray
        Shape (..., b): the adjusted ratio of the module docstring, exponentiated, where
        :func:`controllable` and the adjusted share of conducting realizations is positive; else
        the plain geometric mean of the resample's conducting realizations.
    """
    plain = bootstrap_log_mean(values, counts, True)
    use = controllable(values, control)
    if not use.any():
        return plain
    conducts = np.isfinite(values) & (values > 0)
    with np.errstate(divide="ignore", invalid="ignore"):
        y = np.where(use[..., None] & conducts, np.log(values), 0.0)
    c = np.where(use[..., None], conducts, 0.0)
    x = np.where(use[..., None], control, 0.0)
    weights = counts.T.astype(float)
    n = weights.sum(axis=0)

    def centred(a: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The sample's mean (kept) and the deviations from it (the weighted moments do not cancel)."""
        mean = a.mean(axis=-1, keepdims=True)
        return mean, a - mean

    (y0, yc), (c0, cc), (x0, xc) = centred(y), centred(c), centred(x)
    mean_y, mean_c, mean_x = (yc @ weights) / n, (cc @ weights) / n, (xc @ weights) / n
    var = ((xc * xc) @ weights) / n - mean_x**2
    ok = var > MIN_CONTROL_VARIANCE
    safe = np.where(ok, var, 1.0)
    slope_y = np.where(ok, (((xc * yc) @ weights) / n - mean_x * mean_y) / safe, 0.0)
    slope_c = np.where(ok, (((xc * cc) @ weights) / n - mean_x * mean_c) / safe, 0.0)
    shift = x0 + mean_x - np.broadcast_to(np.asarray(expected, float), use.shape)[..., None]
    numerator = y0 + mean_y - slope_y * shift
    denominator = c0 + mean_c - slope_c * shift
    good = use[..., None] & (denominator > 0)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        controlled = np.exp(numerator / np.where(good, denominator, 1.0))
    return np.where(good, controlled, plain)


def controlled_mean(values: np.ndarray, control: np.ndarray, expected: np.ndarray) -> np.ndarray:
    """The geometric mean over the last axis with the control variate where it applies (the sample
    itself as the one resample of :func:`bootstrap_controlled_mean`); shape ``values.shape[:-1]``."""
    return bootstrap_controlled_mean(values, control, expected, np.ones((1, values.shape[-1]), int))[..., 0]
