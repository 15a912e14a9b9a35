"""Rigid surfaces on a grid: the sphere, GW surfaces and Gaussian random-process surfaces.

Pixel centres lie at ``(i - (n - 1) / 2) * pixel`` along x and y (``grid.cell_centres``), so the
sphere's axis is the grid's centre. Heights are in m, positive towards the elastic half-space.
"""

from __future__ import annotations

import numpy as np

from pipeline.physics.grid import cell_centres

__all__ = ["coordinates", "sphere"]


def coordinates(n: int, pixel: float) -> tuple[np.ndarray, np.ndarray]:
    """Pixel-centre coordinates ``x, y`` (m), each (n, n), indexed ``[y, x]``."""
    c = cell_centres(n, pixel)
    return np.meshgrid(c, c, indexing="xy")


def sphere(n: int, pixel: float, radius: float) -> np.ndarray:
    """Heights of a sphere of ``radius`` (m) with its tip at height 0 on the axis (parabolic, Hertz)."""
    x, y = coordinates(n, pixel)
    return -(x**2 + y**2) / (2.0 * radius)
