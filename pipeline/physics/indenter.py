"""Axisymmetric indenter profiles: the initial gap above the tip, as a function of radius."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from g2tom.physics.hertz import hertz_radius

__all__ = ["SHAPES", "profile", "smooth_contact_radius"]

SHAPES: tuple[str, ...] = ("sphere", "cone", "flat_punch")


def _positive(name: str, value: float, unit: str) -> None:
    if not (np.isfinite(value) and value > 0):
        raise ValueError(f"{name} = {float(value)!r} is out of range: must be > 0 ({unit})")


def profile(
    r: ArrayLike,
    shape: str = "sphere",
    *,
    radius: float = 10e-3,
    cone_angle: float = 0.01,
    punch_radius: float = 1e-3,
    edge_radius: float = 10e-3,
) -> np.ndarray:
    """Height of the undeformed indenter surface above its lowest point, z(r) >= 0.

    Parameters
    ----------
    r
        Radial coordinate, m (>= 0).
    shape
        ``"sphere"``: paraboloid r^2 / (2 R) (Hertz's approximation of a sphere);
        ``"cone"``: r tan(angle); ``"flat_punch"``: flat for r <= b, then a parabolic
        rounded edge (r - b)^2 / (2 R_e).
    radius
        Sphere radius R*, m.
    cone_angle
        Angle between the cone flank and the flat, rad, in (0, pi/2).
    punch_radius
        Radius b of the punch's flat face, m.
    edge_radius
        Radius R_e of the rounded edge, m.

    Returns
    -------
    numpy.ndarray
        z(r) in m, same shape as ``r``.
    """
    r = np.asarray(r, dtype=float)
    if shape == "sphere":
        _positive("radius", radius, "m")
        return r * r / (2.0 * radius)
    if shape == "cone":
        if not (0 < cone_angle < np.pi / 2):
            raise ValueError(f"cone_angle = {float(cone_angle)!r} is out of range: must be in (0, pi/2) (rad)")
        return r * np.tan(cone_angle)
    if shape == "flat_punch":
        _positive("punch_radius", punch_radius, "m")
        _positive("edge_radius", edge_radius, "m")
        excess = np.maximum(r - punch_radius, 0.0)
        return excess * excess / (2.0 * edge_radius)
    raise ValueError(f"shape = {shape!r} is not allowed: must be one of {', '.join(SHAPES)}")


def smooth_contact_radius(
    force: ArrayLike,
    e_star: float,
    shape: str = "sphere",
    *,
    radius: float = 10e-3,
    cone_angle: float = 0.01,
    punch_radius: float = 1e-3,
) -> np.ndarray:
    """Contact radius of the smooth indenter on an elastic half-space at ``force``, m.

    Sphere: Hertz, ``a = (3 F R* / (4 E*))^(1/3)``; cone: Love (1939), ``F = (pi/2) E* a^2
    tan(angle)``; flat punch: the face's radius ``b`` (its rounded edge is left out: it
    carries little of the force while the face is flat on the half-space).

    Parameters
    ----------
    force
        Normal force F, N (>= 0).
    e_star
        Contact modulus E*, Pa.
    shape, radius, cone_angle, punch_radius
        As in :func:`profile`.
    """
    force = np.asarray(force, dtype=float)
    if np.any(force < 0):
        raise ValueError(f"force = {float(np.min(force)):g} is out of range: must be >= 0 (N)")
    _positive("e_star", e_star, "Pa")
    if shape == "sphere":
        _positive("radius", radius, "m")
        return hertz_radius(force, radius, e_star)
    if shape == "cone":
        if not (0 < cone_angle < np.pi / 2):
            raise ValueError(f"cone_angle = {float(cone_angle)!r} is out of range: must be in (0, pi/2) (rad)")
        return np.sqrt(2.0 * force / (np.pi * e_star * np.tan(cone_angle)))
    if shape == "flat_punch":
        _positive("punch_radius", punch_radius, "m")
        return np.full_like(force, float(punch_radius))
    raise ValueError(f"shape = {shape!r} is not allowed: must be one of {', '.join(SHAPES)}")
