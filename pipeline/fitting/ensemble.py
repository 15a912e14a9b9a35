"""How many realizations an ensemble needs: the fast stopping rule of the adaptive ensemble.

The geometric-mean fit ``log alpha_hat = mean_s(y) - slope mean_s(log x)`` over the fitted load
steps s is LINEAR in ``y_s = mean_r log R_{s,r}``: ``log alpha_hat = sum_s c_s y_s`` with the
least-squares weights ``c`` of :func:`fit_weights` (``sum c_s = 1``). Hence ``log alpha_hat`` is
the mean over realizations of the per-realization statistic ``t_r = sum_s c_s log R_{s,r}``, and
its standard error is exactly ``std(t_r) / sqrt(n)``; the same holds for gamma with the slope
weights. A normalization ``R' = R / scale`` only shifts ``t_r`` by ``-log scale``.

Open circuits (``R = +inf``) are left out of ``t_r`` (the geometric mean is over conducting
realizations): the rule then uses the finite statistics only, an approximation that the stage
notes; the fits stage's bootstrap gives the final intervals.

With a control variate the fits' per-step estimate is a ratio adjusted by the control
(:mod:`g2tom.fitting.control_variate`); :func:`prefix_controlled_half_width` is its linearized
half-width, in which open circuits count (they move the conducting share the control adjusts).
"""

from __future__ import annotations

import numpy as np
from scipy import special

from g2tom.fitting.control_variate import MIN_CONTROL_VARIANCE

__all__ = ["fit_weights", "statistic", "prefix_half_width", "prefix_controlled_half_width", "stop_count", "z_value",
           "log_standard_error", "mean_half_width"]


def fit_weights(log_x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Least-squares weights of intercept and exponent of ``log y = log alpha - gamma log x``.

    Parameters
    ----------
    log_x
        Natural log of the fitted abscissae (e.g. F'), shape (n_steps,), at least two distinct.

    Returns
    -------
    tuple of numpy.ndarray
        ``(c_alpha, c_gamma)``, each shape (n_steps,): ``log alpha = c_alpha @ log y`` and
        ``gamma = c_gamma @ log y``.
    """
    log_x = np.asarray(log_x, float)
    centred = log_x - log_x.mean()
    sxx = centred @ centred
    if log_x.size < 2 or not sxx > 0:
        raise ValueError("fit_weights needs at least two distinct abscissae")
    c_gamma = -centred / sxx
    c_alpha = 1.0 / log_x.size - log_x.mean() * centred / sxx
    return c_alpha, c_gamma


def statistic(log_r: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """Per-realization statistic ``t_r = sum_s c_s log R_{s,r}``.

    Parameters
    ----------
    log_r
        ``log R`` with the fitted steps on axis -2 and realizations on axis -1 (..., s, r);
        +inf for an open circuit.
    weights
        ``c`` from :func:`fit_weights`, shape (s,).

    Returns
    -------
    numpy.ndarray
        Shape (..., r); NaN where a realization is open at a fitted step.
    """
    with np.errstate(invalid="ignore"):
        t = np.einsum("s,...sr->...r", weights, log_r)
    return np.where(np.isfinite(t), t, np.nan)


def z_value(confidence: float) -> float:
    """Two-sided normal quantile of a confidence level (1.96 for 0.95)."""
    return float(special.ndtri(0.5 * (1.0 + confidence)))


def prefix_half_width(t: np.ndarray, z: float) -> np.ndarray:
    """Half-width ``z std(t[:n]) / sqrt(n_finite)`` of the mean over every prefix n of the realizations.

    Parameters
    ----------
    t
        Statistics on the last axis (..., r); NaN values (open circuits) are skipped.
    z
        Normal quantile of the confidence level.

    Returns
    -------
    numpy.ndarray
        Shape (..., r): entry n - 1 is the half-width of the first n realizations (NaN below
        two finite values). For ``t`` of :func:`statistic` with ``c_alpha`` this is the
        half-width of ``log alpha``; ``sinh`` of it is alpha's relative half-width.
    """
    count, (centred,) = _prefix_sums(t)
    s1 = np.cumsum(centred, axis=-1)
    s2 = np.cumsum(centred**2, axis=-1)
    with np.errstate(divide="ignore", invalid="ignore"):
        var = (s2 - s1**2 / count) / (count - 1)
        out = z * np.sqrt(np.maximum(var, 0.0) / count)
    return np.where(count >= 2, out, np.nan)


def _prefix_sums(*columns: np.ndarray) -> tuple[np.ndarray, list[np.ndarray]]:
    """Running count of the realizations where every column is finite, and each column's running sum
    over them, after shifting by its mean over the first (up to 16) of them: the shift depends on
    those realizations only, so every prefix's result is fixed, and it keeps the sums conditioned."""
    finite = np.all([np.isfinite(c) for c in columns], axis=0)
    count = np.cumsum(finite, axis=-1)
    head = slice(0, min(finite.shape[-1], 16))
    out = []
    for column in columns:
        value = np.where(finite, column, 0.0)
        with np.errstate(invalid="ignore", divide="ignore"):
            shift = value[..., head].sum(-1, keepdims=True) / finite[..., head].sum(-1, keepdims=True)
        out.append(np.where(finite, value - np.where(np.isfinite(shift), shift, 0.0), 0.0))
    return count, out


def prefix_controlled_half_width(resistance: np.ndarray, control: np.ndarray, expected: float,
                                 weights: np.ndarray, z: float, first: int = 1,
                                 block: int = 256) -> np.ndarray:
    """Half-width of ``sum_s w_s m_s`` over every prefix of the realizations, ``m_s`` the fits'
    control-variate estimate of the log geometric mean at step s.

    ``m_s = (mean(y c) - b_n (mean(x) - p)) / (mean(c) - b_d (mean(x) - p))`` (y = ln R, c = 1 where
    the realization conducts, x its control, p the control's exact expectation; the slopes
    ``b_n = cov(x, y c) / var(x)``, ``b_d = cov(x, c) / var(x)`` from the same realizations, 0
    where the control does not vary) is :func:`g2tom.fitting.control_variate.controlled_mean`, step
    by step. Its linearization: with ``D_s`` the denominator, the realization r contributes
    ``e_sr = (y_sr c_sr - m_s c_sr - (b_n - m_s b_d) x_sr) / D_s``, so the standard error of
    ``sum_s w_s m_s`` is ``std_r(sum_s w_s e_sr) / sqrt(n)``: the residual of the ratio's influence
    after its regression on the control, open circuits counted (they move the share of conducting
    realizations, which the control adjusts too). Every prefix's covariance of (y c, c, x) over the
    steps comes from running sums of their products, ``block`` prefixes at a time.

    Parameters
    ----------
    resistance
        R in ohm, shape (s, r): the steps and the realizations in order; +inf an open circuit.
        Every entry computed (no NaN).
    control
        The realizations' controls, shape (s, r), finite.
    expected
        The controls' exact expectation p.
    weights
        Step weights, shape (k, s) or (s,) (e.g. ``c_alpha`` and ``c_gamma`` of :func:`fit_weights`).
    z
        Normal quantile of the confidence level.
    first
        Smallest prefix wanted (>= 1): the entries of shorter prefixes are NaN and cost nothing.
    block
        Prefixes handled together (memory ~ block (3 s)^2 doubles).

    Returns
    -------
    numpy.ndarray
        Shape (k, r) ((r,) for one weight vector): entry n - 1 is the half-width with the first n
        realizations; NaN below three realizations, below ``first``, and where a step has no
        conducting realization or a non-positive adjusted share of them.
    """
    w = np.atleast_2d(np.asarray(weights, float))
    conducts = np.isfinite(resistance) & (resistance > 0)
    y = np.where(conducts, np.log(np.where(conducts, resistance, 1.0)), 0.0)
    values = np.concatenate([y, conducts.astype(float), np.asarray(control, float)])
    steps, n = resistance.shape
    # Shifted by the first realizations' means: conditioned sums, every prefix's result unchanged.
    shift = values[:, : min(n, 16)].mean(axis=1, keepdims=True)
    values = values - shift
    sums = np.cumsum(values, axis=1)
    out = np.full((w.shape[0], n), np.nan)
    start = max(first, 1) - 1
    running = values[:, :start] @ values[:, :start].T
    ys, cs, xs = (slice(k * steps, (k + 1) * steps) for k in range(3))
    for begin in range(start, n, block):
        stop = min(begin + block, n)
        part = values[:, begin:stop]
        products = running + np.cumsum(np.einsum("ir,jr->rij", part, part), axis=0)
        running = products[-1]
        count = np.arange(begin + 1, stop + 1, dtype=float)[:, None]
        total = sums[:, begin:stop].T
        with np.errstate(divide="ignore", invalid="ignore"):
            cov = (products - total[:, :, None] * total[:, None, :] / count[:, :, None]) / (count[:, :, None] - 1)
            mean = total / count + shift[:, 0]
            var_x = np.diagonal(cov[:, xs, xs], axis1=1, axis2=2)
            varies = var_x > MIN_CONTROL_VARIANCE
            safe = np.where(varies, var_x, 1.0)
            slope_y = np.where(varies, np.diagonal(cov[:, ys, xs], axis1=1, axis2=2) / safe, 0.0)
            slope_c = np.where(varies, np.diagonal(cov[:, cs, xs], axis1=1, axis2=2) / safe, 0.0)
            offset = mean[:, xs] - expected
            share = mean[:, cs] - slope_c * offset
            m = (mean[:, ys] - slope_y * offset) / share
            scale = w[:, None, :] / share
            coefficients = np.concatenate([scale, -scale * m, -scale * (slope_y - m * slope_c)], axis=2)
            variance = np.einsum("kbi,bij,kbj->kb", coefficients, cov, coefficients)
            width = z * np.sqrt(np.maximum(variance, 0.0) / count[:, 0])
        valid = (count[:, 0] >= 3) & np.all((mean[:, cs] > 0) & (share > 0), axis=1)
        out[:, begin:stop] = np.where(valid, width, np.nan)
    return out[0] if np.ndim(weights) == 1 else out


def stop_count(half_width: np.ndarray, target: float, n_min: int) -> int | None:
    """Smallest prefix n >= n_min at which every row's half-width is <= target, else None.

    Parameters
    ----------
    half_width
        Relative half-widths, shape (rows, r), from :func:`prefix_half_width` (after ``sinh``).
    target
        Target half-width, in (0, 1).
    n_min
        Fewest realizations allowed.

    Returns
    -------
    int or None
        The count, or None if no prefix up to ``r`` qualifies. It depends only on the first n
        realizations, so computing further realizations never changes it.
    """
    ok = np.all(half_width <= target, axis=0)
    ok[: max(n_min, 1) - 1] = False
    hits = np.flatnonzero(ok)
    return int(hits[0]) + 1 if hits.size else None


def log_standard_error(values: np.ndarray, axis: int = -1) -> np.ndarray:
    """Standard error of the mean of ``ln values`` along ``axis``: the standard error of the log of
    their geometric mean, ``std(ln v, ddof=1) / sqrt(n)`` over the finite positive values.

    NaN where fewer than two values count. For a ratio g2tom / reference over paired realizations,
    it is the standard error of the log of the geometric-mean ratio (the pairing's own scatter);
    for two independent ensembles, the squares of each one's add.
    """
    values = np.moveaxis(np.asarray(values, dtype=float), axis, -1)
    ok = np.isfinite(values) & (values > 0)
    count = ok.sum(axis=-1)
    logs = np.where(ok, np.log(np.where(ok, values, 1.0)), 0.0)
    with np.errstate(invalid="ignore", divide="ignore"):
        mean = logs.sum(axis=-1) / count
        var = np.where(ok, (logs - mean[..., None]) ** 2, 0.0).sum(axis=-1) / (count - 1)
        return np.where(count >= 2, np.sqrt(var / count), np.nan)


def mean_half_width(values: np.ndarray, z: float) -> np.ndarray:
    """Relative half-width ``z std(v, ddof=1) / (sqrt(n) mean(v))`` of the mean of ``values`` over axis 0.

    Parameters
    ----------
    values
        Samples on axis 0 (e.g. a pool's surfaces), any further axes kept; NaN entries (not
        sampled) are skipped.
    z
        Normal quantile of the confidence level.

    Returns
    -------
    numpy.ndarray
        Shape ``values.shape[1:]``; NaN where fewer than two values count or their mean is not
        positive (no relative width).
    """
    values = np.asarray(values, dtype=float)
    ok = np.isfinite(values)
    count = ok.sum(axis=0)
    filled = np.where(ok, values, 0.0)
    with np.errstate(invalid="ignore", divide="ignore"):
        mean = filled.sum(axis=0) / count
        var = np.where(ok, (filled - mean) ** 2, 0.0).sum(axis=0) / (count - 1)
        out = z * np.sqrt(var / count) / mean
    return np.where((count >= 2) & (mean > 0), out, np.nan)
