"""Height maps before their moments are taken (:mod:`g2tom.physics.surface_spectrum`):
checked (:func:`~g2tom.physics.roughness.validated_heights`) and detrended (:func:`~g2tom.physics.roughness.detrend`, the least-squares plane)."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

__all__ = ["detrend", "validated_heights"]


def detrend(heights: ArrayLike) -> np.ndarray:
    """Heights minus their least-squares plane, same shape, same unit.

    Undefined (NaN) pixels stay NaN and take no part in the fit: the plane of a map with an
    irregular field of view is that of its measured pixels.
    """
    z = np.asarray(heights, dtype=float)
    ny, nx = z.shape
    y, x = np.mgrid[0:ny, 0:nx]
    design = np.column_stack([np.ones(z.size), x.ravel(), y.ravel()])
    defined = np.isfinite(z.ravel())
    if defined.all():
        coef, *_ = np.linalg.lstsq(design, z.ravel(), rcond=None)
    else:
        coef, *_ = np.linalg.lstsq(design[defined], z.ravel()[defined], rcond=None)
    return z - (design @ coef).reshape(z.shape)


def validated_heights(heights: ArrayLike) -> np.ndarray:
    """A height map as a float array, checked: real, numeric, 2-D, at least 3 x 3, finite.

    Raises
    ------
    ValueError
        Naming what is wrong with the map.
    """
    raw = np.asarray(heights)
    if np.iscomplexobj(raw):
        raise ValueError(f"height map is complex-valued ({raw.dtype}): heights must be real numbers (m)")
    if raw.dtype.kind not in "biuf":
        raise ValueError(f"height map holds {raw.dtype} values: heights must be real numbers (m)")
    z = raw.astype(float)
    if z.ndim != 2:
        raise ValueError(f"height map has shape {z.shape}: must be a 2-D array")
    if min(z.shape) < 3:
        raise ValueError(f"height map has shape {z.shape}: must be at least 3 x 3 pixels")
    if not np.all(np.isfinite(z)):
        raise ValueError(f"height map holds {int(np.sum(~np.isfinite(z)))} non-finite values")
    return z
