"""From the continuous Greenwood–Tripp fields to discrete spots (Sect. 2.5.2) and Eq. 13.

One asperity spot per cell of side 1/sqrt(eta), at the cell centre, with area
A_i = A*(r_i) dx^2 and radius a_i = sqrt(A_i / pi).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike
from scipy.interpolate import CubicSpline

from g2tom.physics.interaction import interaction_sum

__all__ = [
    "cell_radii",
    "check_inside",
    "interpolate_smooth",
    "interpolate_linear",
    "spot_areas",
    "spot_radii",
    "holm_greenwood_radius",
]


def cell_radii(x: ArrayLike, y: ArrayLike) -> np.ndarray:
    """Distance of every cell centre from the axis, shape (len(y), len(x)), m."""
    return np.hypot(np.asarray(x, float)[None, :], np.asarray(y, float)[:, None])


def check_inside(r_nodes: np.ndarray, r_cells: np.ndarray) -> None:
    """Raise ValueError if a cell radius lies beyond the last radial node."""
    if np.max(r_cells) > r_nodes[-1]:
        raise ValueError(
            f"cell radius {np.max(r_cells):.6g} m is out of range: the window corners must lie "
            f"inside the radial domain r <= {r_nodes[-1]:.6g} m (raise contact.r_max or lower contact.window)"
        )


def interpolate_smooth(r_nodes: ArrayLike, values: ArrayLike, r_cells: ArrayLike) -> np.ndarray:
    """Cubic spline of an axisymmetric field (zero slope on the axis) at the cell radii.

    Parameters
    ----------
    r_nodes
        Radial nodes, m, from 0.
    values
        Field at the nodes, shape (..., n_nodes) (e.g. the displacement, m).
    r_cells
        Cell radii, m, any shape, all <= r_nodes[-1].

    Returns
    -------
    numpy.ndarray
        Shape values.shape[:-1] + r_cells.shape.
    """
    r_nodes, r_cells = np.asarray(r_nodes, float), np.asarray(r_cells, float)
    check_inside(r_nodes, r_cells)
    values = np.asarray(values, float)
    axis_slope = (1, np.zeros(values.shape[:-1]))
    spline = CubicSpline(r_nodes, values, axis=-1, bc_type=(axis_slope, "not-a-knot"))
    return spline(r_cells)


def interpolate_linear(r_nodes: ArrayLike, values: ArrayLike, r_cells: ArrayLike) -> np.ndarray:
    """Piecewise-linear interpolation of nodal values (..., n_nodes) to the cell radii."""
    r_nodes, r_cells = np.asarray(r_nodes, float), np.asarray(r_cells, float)
    check_inside(r_nodes, r_cells)
    values = np.asarray(values, float)
    flat = values.reshape(-1, values.shape[-1])
    out = np.stack([np.interp(r_cells, r_nodes, row) for row in flat])
    return out.reshape(values.shape[:-1] + r_cells.shape)


def spot_areas(area_fraction: ArrayLike, cell_size: float) -> np.ndarray:
    """Spot areas A_i = A*(r_i) dx^2, m^2."""
    return np.asarray(area_fraction, float) * cell_size**2


def spot_radii(areas: ArrayLike) -> np.ndarray:
    """Spot radii a_i = sqrt(A_i / pi), m."""
    return np.sqrt(np.asarray(areas, float) / np.pi)


def holm_greenwood_radius(radii: ArrayLike, cell_size: float) -> np.ndarray:
    """Holm–Greenwood radius alpha_HG = pi (sum a)^2 / (2 sum_{i != j} a_i a_j / d_ij) (Eq. 13), m.

    Parameters
    ----------
    radii
        Spot radii on a square cell grid, shape (..., n, n), m.
    cell_size
        Cell pitch, m.

    Returns
    -------
    numpy.ndarray
        Shape radii.shape[:-2]; NaN where fewer than two spots have a nonzero radius. The pair
        sum is the exact one of the resistance stage (:func:`g2tom.physics.interaction.interaction_sum`).
    """
    a = np.asarray(radii, float)
    total = np.sum(a, axis=(-2, -1))
    pairs = interaction_sum(a.reshape((-1,) + a.shape[-2:]), cell_size).reshape(a.shape[:-2])
    ok = np.count_nonzero(a, axis=(-2, -1)) >= 2
    return np.where(ok, np.pi * total**2 / (2.0 * np.where(ok, pairs, 1.0)), np.nan)
