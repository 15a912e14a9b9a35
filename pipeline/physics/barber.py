"""Barber's conductance bounds for a rough Hertzian contact, extended to oxides (Sect. 2.3).

Barber's construction bounds the stiffness (hence the conductance) of a rough sphere on a
flat between two smooth Hertzian force branches that first touch a height ``s`` apart. In
the normalization of Eq. 8 (force by ``E* sqrt(R* s^3) / 2``, conductance by
``sqrt(R* s) / (2 rho*)``) the bounds follow parametrically from ``x`` through Eq. 6:

* upper bound: ``x`` in [0, 1] (``S`` falls from 1/3 to 0),
* lower bound: ``x`` in [1, inf) (``S`` grows from 0 without bound),

with ``F' = 8/3 (x^2/S)^(3/2)`` and ``kappa' = 4/sqrt(S)``. ``F'(x)`` is monotone on each
branch (``d(x^2/S)/dx`` has the sign of ``1 - x^3``), so a load ``F'`` maps to exactly one
``x`` per branch, found here by vectorized bisection.

Note on Eq. 7 as printed: the root ``1/2 + cos(theta)`` lies in [1, 3/2] and the root
``1/2 + cos(theta - 2 pi/3)`` in [0, 1], so by the branch ranges quoted in the text the
labels ``x_+`` and ``x_-`` of Eq. 7 are swapped; the bounds below follow the text.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

__all__ = [
    "oxide_factor",
    "shape_parameter",
    "clean_bounds",
    "oxide_bounds",
    "p_average",
    "p_average_sigma",
]

_BISECTION_STEPS = 80


def oxide_factor(xi: ArrayLike) -> np.ndarray:
    """Conductance factor f(xi) of an annular conducting ring (Eq. 4, exactly as printed).

    Parameters
    ----------
    xi
        Oxide fraction, dimensionless, in [0, 1].

    Returns
    -------
    numpy.ndarray
        f(xi), dimensionless; f(0) = 1.
    """
    xi = _check_fraction(xi)
    pi2 = np.pi**2
    return (
        1.0
        - 4.0 / (2.0 * pi2) * xi**1.5
        - 8.0 / (15.0 * pi2) * xi**2.5
        - 16.0 / (27.0 * pi2) * xi**3
        - 92.0 / (315.0 * pi2) * xi**3.5
        - 416.0 / (675.0 * pi2) * xi**4
    )


def shape_parameter(x: ArrayLike) -> np.ndarray:
    """S(x) = (2 x^3 - 3 x^2 + 1) / 3 of Eq. 6, dimensionless."""
    x = np.asarray(x, dtype=float)
    return (2.0 * x**3 - 3.0 * x**2 + 1.0) / 3.0


def _force(x: np.ndarray) -> np.ndarray:
    """Normalized force F'(x) = 8/3 (x^2 / S)^(3/2) along Barber's parametric curve."""
    with np.errstate(divide="ignore", invalid="ignore"):
        return 8.0 / 3.0 * (x**2 / shape_parameter(x)) ** 1.5


def _solve_branch(force: np.ndarray, upper: bool) -> np.ndarray:
    """S on one branch for normalized loads ``force`` (F' > 0), by bisection.

    The upper branch is searched in x in [0, 1]; the lower branch in u = 1/x in (0, 1].
    """
    lo = np.zeros_like(force)
    hi = np.ones_like(force)
    for _ in range(_BISECTION_STEPS):
        mid = 0.5 * (lo + hi)
        x = mid if upper else 1.0 / np.maximum(mid, 1e-300)
        # F'(x) rises with x on the upper branch and with u = 1/x on the lower one.
        too_big = _force(x) > force
        hi = np.where(too_big, mid, hi)
        lo = np.where(too_big, lo, mid)
    mid = 0.5 * (lo + hi)
    x = mid if upper else 1.0 / mid
    return shape_parameter(x)


def clean_bounds(force: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """Barber's clean-surface conductance bounds (Eq. 8) at given normalized loads.

    Parameters
    ----------
    force
        F' = 2 F / (E* sqrt(R* s^3)), dimensionless, > 0.

    Returns
    -------
    tuple of numpy.ndarray
        ``(kappa_upper, kappa_lower)``: kappa' = 2 rho* kappa / sqrt(R* s) = 4 / sqrt(S),
        dimensionless.
    """
    force = _check_force(force)
    s_upper = _solve_branch(force, upper=True)
    s_lower = _solve_branch(force, upper=False)
    return 4.0 / np.sqrt(s_upper), 4.0 / np.sqrt(s_lower)


def oxide_bounds(force: ArrayLike, xi: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """Oxide-extended bounds of Eq. 9: ``4 f(xi)/sqrt(S+)`` and ``4 sqrt((1 - xi)/S-)``.

    Parameters
    ----------
    force
        F' normalized with ``s`` (Eq. 8), dimensionless, > 0.
    xi
        Oxide fraction in [0, 1], broadcast against ``force``.

    Returns
    -------
    tuple of numpy.ndarray
        ``(kappa_upper, kappa_lower)``, dimensionless.
    """
    upper, lower = clean_bounds(force)
    xi = _check_fraction(xi)
    return upper * oxide_factor(xi), lower * np.sqrt(1.0 - xi)


def p_average(force: ArrayLike, xi: ArrayLike, p: float) -> np.ndarray:
    """Generalized p-average of the oxide-extended bounds (Eq. 10).

    Parameters
    ----------
    force
        F' normalized with ``s``, dimensionless, > 0.
    xi
        Oxide fraction in [0, 1].
    p
        Order of the mean: 1 arithmetic, 0 geometric (the limit p -> 0), -1 harmonic.

    Returns
    -------
    numpy.ndarray
        <kappa'>_p, dimensionless.
    """
    if not np.isfinite(p):
        raise ValueError(f"p = {p} is out of range: must be finite")
    upper, lower = oxide_bounds(force, xi)
    if p == 0.0:
        return np.sqrt(upper * lower)
    return (0.5 * (upper**p + lower**p)) ** (1.0 / p)


def p_average_sigma(
    force_sigma: ArrayLike, xi: ArrayLike, p: float, s_over_sigma: float
) -> np.ndarray:
    """Eq. 10 expressed in the sigma normalization of G2TOM (Eq. 25), for ``s = c sigma``.

    Parameters
    ----------
    force_sigma
        F' = 2 F / (E* sqrt(R* sigma^3)), dimensionless, > 0.
    xi
        Oxide fraction in [0, 1].
    p
        Order of the mean (see :func:`p_average`).
    s_over_sigma
        Barber's height parameter ``s`` in units of sigma, > 0.

    Returns
    -------
    numpy.ndarray
        kappa' = 2 rho* kappa / sqrt(R* sigma) = 1 / R', dimensionless.
    """
    if not (np.isfinite(s_over_sigma) and s_over_sigma > 0):
        raise ValueError(f"s_over_sigma = {s_over_sigma} is out of range: must be > 0")
    force_s = np.asarray(force_sigma, dtype=float) * s_over_sigma**-1.5
    return p_average(force_s, xi, p) * np.sqrt(s_over_sigma)


def _check_fraction(xi: ArrayLike) -> np.ndarray:
    xi = np.asarray(xi, dtype=float)
    if np.any(~np.isfinite(xi)) or np.any((xi < 0.0) | (xi > 1.0)):
        raise ValueError(f"xi = {xi} is out of range: must be in [0, 1]")
    return xi


def _check_force(force: ArrayLike) -> np.ndarray:
    force = np.asarray(force, dtype=float)
    if np.any(~np.isfinite(force)) or np.any(force <= 0.0):
        raise ValueError(f"force = {force} is out of range: the normalized load must be > 0")
    return force
