"""Curve model: ln R' as a low-order polynomial in ln F', fitted per curve to its own tolerance.

Eq. 25's power law is the polynomial of order 1, ``ln R' = ln alpha - gamma ln F'``, and it
misses curved resistance-force laws (Barber's clean curve has a local exponent falling from
0.72 to 0.39 over the paper's loads). The curve model

    ln y = sum_{k=0}^{p} c_k (ln x)^k

is fitted by weighted least squares in ln y, each point weighted by the inverse square of the
half-width of its band (below), and the order is chosen by one rule, **the smallest order
p = 1, 2, ..., max_order whose curve lies inside every fitted point's band**, applied first
with the relative tolerance alone (3 %: ``ln 0.97 <= ln y_model - ln y <= ln 1.03``) and, only
where no order meets that, with max(tolerance, the point's confidence interval
``[lo, hi]``): ``min(ln 0.97, ln(lo / y)) <= ln y_model - ln y <= max(ln 1.03, ln(hi / y))``
(:func:`tolerance_band`). So a mean curve that is smooth to 3 % gets its shape to 3 %, even
where its intervals are wider (they are, when realizations differ mostly by a factor common
to all loads); the interval only excuses the noise of a mean curve that is not smooth. Where
no order meets either band, ``max_order`` is kept and the curve is marked as missing its
tolerance. The order never exceeds the number of fitted points minus 1. Powers of ln x are
not centred, so that order 1 reads as the power law (``c_0 = ln alpha``, ``c_1 = -gamma``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

__all__ = ["CurveFit", "tolerance_band", "fit_curve", "evaluate_curve", "interpolation_error"]


@dataclass(frozen=True)
class CurveFit:
    """Result of :func:`fit_curve`; leading shape (...) of the input curves.

    Attributes
    ----------
    coefficients
        c_0 ... c_max_order of ln y in powers of ln x, shape (..., max_order + 1); 0 above
        the chosen order, NaN where the curve has fewer than two fitted points.
    order
        Chosen order p (int; 0 where no fit).
    residual
        ln y_model - ln y at every point, NaN where not fitted, shape (..., n).
    max_error
        Largest relative error |y_model / y - 1| over the fitted points.
    within
        Which band the curve lies inside at every fitted point (int8): 1 the relative tolerance,
        2 only max(tolerance, interval), 0 neither (or no fit).
    n_points
        Points that entered the fit.
    """

    coefficients: np.ndarray
    order: np.ndarray
    residual: np.ndarray
    max_error: np.ndarray
    within: np.ndarray
    n_points: np.ndarray


def tolerance_band(y: ArrayLike, relative: float, interval: ArrayLike | None = None) -> tuple[np.ndarray, np.ndarray]:
    """The band ``(lower, upper)`` in ln y of "within max(relative, the point's interval)".

    Parameters
    ----------
    y
        The curve's values, > 0, shape (..., n).
    relative
        Relative error always allowed, in (0, 1) (0.03 for 3 %).
    interval
        Confidence interval of each value, shape (..., n, 2) as (lower, upper) limits; None
        (a deterministic curve) allows ``relative`` only. NaN limits count as no interval.

    Returns
    -------
    tuple of numpy.ndarray
        ``lower < 0 < upper``, each of the shape of ``y``.
    """
    if not 0 < relative < 1:
        raise ValueError(f"relative = {relative!r} is out of range: must be in (0, 1)")
    y = np.asarray(y, dtype=float)
    lower = np.full(y.shape, np.log1p(-relative))
    upper = np.full(y.shape, np.log1p(relative))
    if interval is not None:
        interval = np.asarray(interval, dtype=float)
        with np.errstate(divide="ignore", invalid="ignore"):
            lo, hi = np.log(interval[..., 0] / y), np.log(interval[..., 1] / y)
        lower = np.fmin(lower, lo)
        upper = np.fmax(upper, hi)
    return lower, upper


def evaluate_curve(coefficients: ArrayLike, x: ArrayLike) -> np.ndarray:
    """ln y of the curve at the abscissae ``x`` (> 0), by Horner's rule.

    Parameters
    ----------
    coefficients
        Shape (..., p + 1), ascending powers of ln x.
    x
        Abscissae, broadcast against the leading shape plus a trailing axis of points.

    Returns
    -------
    numpy.ndarray
        ln y, shape broadcast(coefficients[..., :1], x).
    """
    c = np.asarray(coefficients, dtype=float)
    lx = np.log(np.asarray(x, dtype=float))
    out = np.zeros(np.broadcast_shapes(c.shape[:-1] + (1,), lx.shape))
    for k in range(c.shape[-1] - 1, -1, -1):
        out = out * lx + c[..., k : k + 1]
    return out


def _lowest_order(lx: np.ndarray, ly: np.ndarray, lower: np.ndarray, upper: np.ndarray,
                  top: int) -> tuple[np.ndarray, bool]:
    """Coefficients of the lowest order <= top inside the band (else of order ``top``) and whether inside."""
    weight = 2.0 / (upper - lower)  # 1 / half-width of the band (0 for an unbounded one)
    for order in range(1, top + 1):
        basis = lx[:, None] ** np.arange(order + 1)
        c, *_ = np.linalg.lstsq(basis * weight[:, None], ly * weight, rcond=None)
        res = basis @ c - ly
        if np.all((res >= lower) & (res <= upper)):
            return c, True
    return c, False


def fit_curve(x: ArrayLike, y: ArrayLike, tolerance: float, interval: ArrayLike | None = None,
              mask: ArrayLike | None = None, max_order: int = 3) -> CurveFit:
    """Fit the curve model to every curve along the last axis (see the module docstring).

    Parameters
    ----------
    x
        Abscissae (e.g. F'), > 0, shape (n,) or broadcastable to ``y``.
    y
        Ordinates (e.g. the mean R'), shape (..., n); non-finite or non-positive values do not
        enter the fit.
    tolerance
        Relative error of y always allowed, in (0, 1) (0.03 for 3 %).
    interval
        Confidence interval of each value, shape (..., n, 2) as (lower, upper) limits, or None
        (a deterministic curve: the tolerance alone).
    mask
        Points allowed in the fit, broadcast against ``y``; default all.
    max_order
        Highest order tried, >= 1.

    Returns
    -------
    CurveFit
    """
    if max_order < 1:
        raise ValueError(f"max_order = {max_order!r} is out of range: must be >= 1")
    y = np.asarray(y, dtype=float)
    x = np.broadcast_to(np.asarray(x, dtype=float), y.shape)
    bands = [tolerance_band(y, tolerance)]
    if interval is not None:
        bands.append(tolerance_band(y, tolerance, interval))
    use = np.ones(y.shape, bool) if mask is None else np.broadcast_to(np.asarray(mask, bool), y.shape)
    with np.errstate(divide="ignore", invalid="ignore"):
        lx, ly = np.log(x), np.log(y)
    use = use & np.isfinite(lx) & np.isfinite(ly)
    lead = y.shape[:-1]
    coefficients = np.full(lead + (max_order + 1,), np.nan)
    order = np.zeros(lead, int)
    within = np.zeros(lead, np.int8)
    for idx in np.ndindex(lead):
        sel = use[idx]
        if np.unique(lx[idx][sel]).size < 2:
            continue
        for level, (lower, upper) in enumerate(bands, start=1):
            c, ok = _lowest_order(lx[idx][sel], ly[idx][sel], lower[idx][sel], upper[idx][sel],
                                  min(max_order, int(sel.sum()) - 1))
            if ok:
                break
        coefficients[idx] = np.concatenate([c, np.zeros(max_order + 1 - c.size)])
        order[idx] = c.size - 1
        within[idx] = level if ok else 0
    with np.errstate(invalid="ignore"):
        residual = np.where(use, evaluate_curve(np.nan_to_num(coefficients), x) - ly, np.nan)
    residual = np.where(np.isnan(coefficients[..., :1]), np.nan, residual)
    fitted = np.isfinite(residual)
    error = np.where(fitted, np.abs(np.expm1(np.where(fitted, residual, 0.0))), -np.inf)
    max_error = np.where(fitted.any(-1), error.max(-1, initial=-np.inf), np.nan)
    return CurveFit(coefficients, order, residual, max_error, within, fitted.sum(-1))


def interpolation_error(values: ArrayLike, u: ArrayLike, v: ArrayLike) -> np.ndarray:
    """Leave-one-out error of linear interpolation on a grid of curves, per grid node.

    Each node's values (its curve at the fitted steps) are predicted by linear interpolation in
    ``u`` from its two neighbours along the first axis, and in ``v`` along the second; the node's
    error is the root mean square over the available directions of the largest absolute
    difference over the steps. A node on an edge has no neighbour on one side: it takes the
    error of the nearest interior node along that axis (none when the axis has fewer than 3
    nodes: NaN).

    Parameters
    ----------
    values
        Shape (len(u), len(v), steps): e.g. ln R' of each (lambda, xi) cell at the fitted steps.
    u, v
        Strictly increasing coordinates of the grid's axes (e.g. w = ln lambda, z = -ln(1 - xi)).

    Returns
    -------
    numpy.ndarray
        Shape (len(u), len(v)), in the unit of ``values`` (ln R': a relative error).
    """
    y = np.asarray(values, dtype=float)
    squares, counts = np.zeros(y.shape[:2]), np.zeros(y.shape[:2])
    for axis, coord in ((0, np.asarray(u, float)), (1, np.asarray(v, float))):
        n = coord.size
        if n < 3:
            continue
        moved = np.moveaxis(y, axis, 0)
        t = ((coord[1:-1] - coord[:-2]) / (coord[2:] - coord[:-2]))[:, None, None]
        guess = (1.0 - t) * moved[:-2] + t * moved[2:]
        inner = np.max(np.abs(guess - moved[1:-1]), axis=-1)  # (n - 2, other axis)
        error = np.concatenate([inner[:1], inner, inner[-1:]])  # edges take the nearest interior node
        squares += np.moveaxis(error, 0, axis) ** 2
        counts += 1.0
    with np.errstate(invalid="ignore"):
        return np.where(counts > 0, np.sqrt(squares / np.maximum(counts, 1.0)), np.nan)
