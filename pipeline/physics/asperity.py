"""Greenwood–Williamson asperity integrals for Gaussian asperity heights.

For asperity heights z ~ N(0, sigma^2) and a separation h of the mean planes,

    F_n(h) = integral_h^inf (z - h)^n phi(z) dz
           = sigma^n Gamma(n + 1) / sqrt(2 pi) exp(-x^2 / 4) D_{-n-1}(x),   x = h / sigma,

with D the parabolic cylinder function. F_{3/2} gives the asperity pressure (Eq. 16) and
F_1 the real contact-area fraction (Eqs. 20-21). The evaluation works in logarithms so that
both tails stay finite and accurate: for |x| > ``_X_TAIL`` it switches to the asymptotic
series (exponentially small tail for h >> sigma, polynomial-dominated form for h << -sigma).
Between them it uses ``scipy.special.pbdv`` (n != 1) or the erfc closed form (n = 1).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike
from scipy.special import erfc, erfcx, gammaln, pbdv

__all__ = [
    "log_asperity_integral",
    "asperity_integral",
    "asperity_integral_slope",
    "area_fraction",
    "asperity_pressure",
]

#: |h/sigma| beyond which the asymptotic series are used (relative error < 1e-13 there).
_X_TAIL = 12.0
#: Terms of the asymptotic series.
_N_TERMS = 16
_LOG_SQRT_2PI = 0.5 * np.log(2.0 * np.pi)


def _check_order(n: float) -> None:
    if not (np.isfinite(n) and n > -1.0):
        raise ValueError(f"n = {n!r} is out of range: the asperity integral needs n > -1")


def _log_upper_tail(x: np.ndarray, n: float) -> np.ndarray:
    """log f_n(x) for x >> 1: Gamma(n+1)/sqrt(2 pi) x^-(n+1) e^{-x^2/2} sum_k ..."""
    nu = n + 1.0
    series = np.ones_like(x)
    term = np.ones_like(x)
    for k in range(_N_TERMS):
        term = -term * (nu + 2 * k) * (nu + 2 * k + 1) / ((k + 1) * 2.0 * x * x)
        series = series + term
    return gammaln(nu) - _LOG_SQRT_2PI - nu * np.log(x) - 0.5 * x * x + np.log(series)


def _log_lower_tail(x: np.ndarray, n: float) -> np.ndarray:
    """log f_n(x) for x << -1: |x|^n sum_k C(n, 2k) (2k-1)!! x^-2k (the moments of (z - x)^n)."""
    series = np.ones_like(x)
    coef = 1.0
    for k in range(1, _N_TERMS):
        # C(n, 2k) (2k-1)!! from C(n, 2k-2) (2k-3)!!
        coef *= (n - 2 * k + 2) * (n - 2 * k + 1) / ((2 * k) * (2 * k - 1)) * (2 * k - 1)
        series = series + coef / x ** (2 * k)
    return n * np.log(-x) + np.log(series)


def _log_central(x: np.ndarray, n: float) -> np.ndarray:
    """log f_n(x) for |x| <= _X_TAIL from the closed forms."""
    if n == 1.0:
        # f_1 = phi(x) - x erfc(x / sqrt 2) / 2, written with erfcx so that x > 0 keeps its digits
        y = x / np.sqrt(2.0)
        bracket = np.where(
            x <= 0,
            np.exp(-0.5 * x * x) / np.sqrt(2.0 * np.pi) - 0.5 * x * erfc(y),
            np.exp(-0.5 * x * x) * (1.0 / np.sqrt(2.0 * np.pi) - 0.5 * x * erfcx(y)),
        )
        return np.log(bracket)
    return gammaln(n + 1.0) - _LOG_SQRT_2PI - 0.25 * x * x + np.log(_distinct_pbdv(-n - 1.0, x))


def _distinct_pbdv(v: float, x: np.ndarray) -> np.ndarray:
    """D_v(x) of ``scipy.special.pbdv``, evaluated once per distinct x (dimensionless, 1-D).

    The cell grids repeat each separation up to eight times (the square window's symmetry about
    the axis); the distinct values are found by their bits, so every value is pbdv's own.
    """
    x = np.ascontiguousarray(x, dtype=float)
    _, first, inverse = np.unique(x.view(np.int64), return_index=True, return_inverse=True)
    return pbdv(v, x[first])[0][inverse]


def log_asperity_integral(x: ArrayLike, n: float) -> np.ndarray:
    """Logarithm of the normalized asperity integral f_n(x) = F_n(sigma x) / sigma^n.

    Parameters
    ----------
    x
        Separation in units of sigma, any real value (dimensionless).
    n
        Order of the integral, n > -1 (1/2, 1 and 3/2 are used).

    Returns
    -------
    numpy.ndarray
        log f_n(x), finite for every finite x (f_n > 0 always).
    """
    _check_order(n)
    x = np.asarray(x, dtype=float)
    out = np.empty_like(x)
    hi = x > _X_TAIL
    lo = x < -_X_TAIL
    mid = ~(hi | lo)
    out[hi] = _log_upper_tail(x[hi], n)
    out[lo] = _log_lower_tail(x[lo], n)
    out[mid] = _log_central(x[mid], n)
    return out


def asperity_integral_slope(x: ArrayLike, n: float) -> np.ndarray:
    """-d f_n / dx = n f_{n-1}(x), the slope of the normalized asperity integral.

    Parameters
    ----------
    x
        Separation in units of sigma, any real value (dimensionless).
    n
        Order, n > 0 (so that n - 1 > -1).

    Returns
    -------
    numpy.ndarray
        Positive, dimensionless (f_n falls as the separation grows).
    """
    return n * np.exp(log_asperity_integral(x, n - 1.0))


def asperity_integral(h: ArrayLike, sigma: float, n: float) -> np.ndarray:
    """F_n(h) = integral_h^inf (z - h)^n phi(z) dz for Gaussian heights of std ``sigma``.

    Parameters
    ----------
    h
        Separation of the mean planes, m (any real value).
    sigma
        Standard deviation of asperity heights, m (> 0).
    n
        Order, n > -1.

    Returns
    -------
    numpy.ndarray
        F_n(h) in m^n: positive, decreasing in h; it underflows to 0 only where the true
        value is below the smallest double (h > ~37 sigma), see :func:`log_asperity_integral`.
    """
    if not (np.isfinite(sigma) and sigma > 0):
        raise ValueError(f"sigma = {sigma!r} is out of range: must be > 0 (m)")
    x = np.asarray(h, dtype=float) / sigma
    return sigma**n * np.exp(log_asperity_integral(x, n))


def area_fraction(h: ArrayLike, sigma: float, eta: float, beta: float) -> np.ndarray:
    """Real contact-area fraction A*(h) = pi eta beta F_1(h) (Eqs. 20-21, with the 1/2).

    Parameters
    ----------
    h
        Separation, m.
    sigma, eta, beta
        Height std (m), asperity density (m^-2), asperity tip radius (m).

    Returns
    -------
    numpy.ndarray
        Dimensionless area fraction.
    """
    return np.pi * eta * beta * asperity_integral(h, sigma, 1.0)


def asperity_pressure(h: ArrayLike, sigma: float, eta: float, beta: float, e_star: float) -> np.ndarray:
    """Mean asperity pressure p(h) = (4/3) eta E* sqrt(beta) F_{3/2}(h) (Eq. 16), in Pa."""
    return (4.0 / 3.0) * eta * e_star * np.sqrt(beta) * asperity_integral(h, sigma, 1.5)
