"""Hertz's smooth sphere-on-flat contact: the reference the rough solution is compared with."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

__all__ = [
    "hertz_radius",
    "hertz_force",
    "hertz_approach",
    "hertz_pressure",
    "hertz_displacement",
    "roughness_parameter",
]


def hertz_radius(force: ArrayLike, radius: float, e_star: float) -> np.ndarray:
    """Contact radius a = (3 F R* / (4 E*))^(1/3), m, for a force F (N) >= 0."""
    force = np.asarray(force, dtype=float)
    if np.any(force < 0):
        raise ValueError(f"force = {float(np.min(force)):g} is out of range: must be >= 0 (N)")
    return np.cbrt(3.0 * force * radius / (4.0 * e_star))


def hertz_force(approach: ArrayLike, radius: float, e_star: float) -> np.ndarray:
    """Force F = (4/3) E* sqrt(R*) d^(3/2), N, for an approach d >= 0 (m); 0 for d < 0."""
    d = np.maximum(np.asarray(approach, dtype=float), 0.0)
    return 4.0 / 3.0 * e_star * np.sqrt(radius) * d**1.5


def hertz_approach(a: ArrayLike, radius: float) -> np.ndarray:
    """Rigid-body approach d = a^2 / R*, m, for a contact radius a (m)."""
    return np.asarray(a, dtype=float) ** 2 / radius


def _peak_pressure(a: np.ndarray, force: np.ndarray) -> np.ndarray:
    """p0 = 3F / (2 pi a^2), Pa; 0 where there is no contact (a = 0)."""
    loaded = a > 0
    return np.where(loaded, 3.0 * force / (2.0 * np.pi * np.where(loaded, a, 1.0) ** 2), 0.0)


def hertz_pressure(r: ArrayLike, a: ArrayLike, force: ArrayLike) -> np.ndarray:
    """Pressure p0 sqrt(1 - r^2/a^2) inside r < a, 0 outside, p0 = 3F/(2 pi a^2); Pa.

    ``a`` (m) and ``force`` (N) broadcast against each other (e.g. shape (n_delta, 1)) and
    ``r`` (m). Zero everywhere for an unloaded contact (a = 0).
    """
    r, a, force = np.asarray(r, float), np.asarray(a, float), np.asarray(force, float)
    ratio = r / np.where(a > 0, a, 1.0)
    inside = np.sqrt(np.clip(1.0 - ratio**2, 0.0, None))
    return _peak_pressure(a, force) * inside


def hertz_displacement(r: ArrayLike, a: ArrayLike, force: ArrayLike, e_star: float) -> np.ndarray:
    """Total normal displacement of both surfaces under the Hertz pressure, m.

    Inside: pi p0 (2a^2 - r^2) / (4 a E*); outside:
    p0 [(2a^2 - r^2) arcsin(a/r) + a sqrt(r^2 - a^2)] / (2 a E*). ``r``, ``a`` in m,
    ``force`` in N, ``e_star`` in Pa; zero for an unloaded contact (a = 0).
    """
    r, a, force = np.asarray(r, float), np.asarray(a, float), np.asarray(force, float)
    p0 = _peak_pressure(a, force)
    loaded = a > 0
    a = np.where(loaded, a, 1.0)  # unloaded: p0 = 0, so any finite radius gives u = 0
    inside = np.pi * p0 * (2 * a**2 - r**2) / (4.0 * a * e_star)
    ratio = np.clip(a / np.maximum(r, a), 0.0, 1.0)
    outside = p0 * ((2 * a**2 - r**2) * np.arcsin(ratio) + a * np.sqrt(np.maximum(r**2 - a**2, 0.0))) / (
        2.0 * a * e_star
    )
    return np.where(r <= a, inside, outside)


def roughness_parameter(sigma: float, radius: float, a: ArrayLike) -> np.ndarray:
    """Roughness parameter alpha = sigma R* / a^2 (Sect. 2.5.1), dimensionless; +inf for a = 0.

    ``sigma`` and ``radius`` (R*) and the Hertz radius ``a`` in m.
    """
    with np.errstate(divide="ignore"):
        return sigma * radius / np.asarray(a, dtype=float) ** 2
