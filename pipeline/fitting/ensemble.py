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
"""

from __future__ import annotations

import numpy as np

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
    from scipy import stats  # here: half a second to import, and most commands that import this module never call it

    return float(stats.norm.ppf(0.5 * (1.0 + confidence)))


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


def prefix_controlled_half_width(t: np.ndarray, u: np.ndarray, z: float) -> np.ndarray:
    """:func:`prefix_half_width` of ``t`` adjusted by the control ``u`` (known mean): ``z`` times the
    standard error of ``mean(t) - b (mean(u) - E u)``, from the residual variance of ``t`` after its
    least-squares regression on ``u``, over every prefix of the realizations.

    Parameters
    ----------
    t, u
        Statistics and their controls on the last axis (..., r); a realization where either is NaN
        (an open circuit) is skipped.
    z
        Normal quantile of the confidence level.

    Returns
    -------
    numpy.ndarray
        Shape (..., r): entry n - 1 for the first n realizations (NaN below three finite ones);
        where ``u`` does not vary, the plain one with n - 2 degrees of freedom.
    """
    count, (tc, uc) = _prefix_sums(t, u)
    st, su = np.cumsum(tc, axis=-1), np.cumsum(uc, axis=-1)
    stt, suu, stu = (np.cumsum(a * b, axis=-1) for a, b in ((tc, tc), (uc, uc), (tc, uc)))
    with np.errstate(divide="ignore", invalid="ignore"):
        var_t = (stt - st**2 / count) / (count - 1)
        var_u = (suu - su**2 / count) / (count - 1)
        cov = (stu - st * su / count) / (count - 1)
        explained = np.where(var_u > 1e-300, cov**2 / np.where(var_u > 1e-300, var_u, 1.0), 0.0)
        residual = np.maximum(var_t - explained, 0.0) * (count - 1) / (count - 2)
        out = z * np.sqrt(residual / count)
    return np.where(count >= 3, out, np.nan)


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
