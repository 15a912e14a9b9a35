"""Measured height maps with undefined pixels (issue 31): harmonic filling, and masked moments.

Optical profilometers leave pixels undefined (NaN) where the light did not come back: steep
flanks, dark or glossy spots. :func:`fill_gaps` gives every NaN pixel the value of the discrete
harmonic (Laplace) interpolant of the defined pixels: with the 4-neighbour stencil, each filled
pixel is the mean of its neighbours inside the map (defined or filled),

    sum_{q ~ p} (z_p - z_q) = 0   for every missing pixel p,

one sparse symmetric positive definite system over the missing pixels, the defined pixels being
Dirichlet data. A missing pixel on the map's edge has fewer neighbours (a zero normal slope
there), so a tilt is reproduced exactly only across holes that do not touch the edge. The
interpolant is the smoothest fill (it minimizes the sum of squared differences over the
missing pixels' links) and obeys the maximum principle (no new peak or valley): inside a hole
it is smoother than the surface was, and it meets the defined pixels with a kink. Measured on a
synthetic surface (wavelengths >= 16 px) with 5 % of the pixels missing in discs of radius
1 ... 4 px, the spectral moments below a 4 px cutoff of the filled map differ from the
complete map's by -0.3 % (rms height), -1 % (m2) and +2 ... +3.5 % (m4, the kinks).

:func:`masked_moments` is the other choice, ignoring the missing pixels: the rms height over the
defined pixels, and m2, m4 from finite differences over the pixel pairs and triples that are
all defined. They are finite-difference estimates (every wavelength down to two pixels, not the
spectral moments below a cutoff), meant for comparing a masked with a filled map by the same
estimator.
"""

from __future__ import annotations

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.linalg import spsolve

__all__ = ["fill_gaps", "masked_moments"]


def fill_gaps(heights: np.ndarray) -> tuple[np.ndarray, int]:
    """The height map with its NaN pixels filled by harmonic interpolation of the defined ones.

    Parameters
    ----------
    heights
        Height map, 2-D, m; NaN marks an undefined pixel (infinite values are left as they are).

    Returns
    -------
    filled : numpy.ndarray
        float64 copy of the map, defined pixels unchanged, NaN pixels filled, m.
    count : int
        Number of filled pixels.

    Raises
    ------
    ValueError
        If the map is not 2-D or no pixel is defined.
    """
    z = np.array(heights, dtype=float)
    if z.ndim != 2:
        raise ValueError(f"height map has shape {z.shape}: must be a 2-D array")
    missing = np.isnan(z)
    count = int(missing.sum())
    if count == 0:
        return z, 0
    if count == z.size:
        raise ValueError(f"height map holds no defined pixel ({z.shape[0]} x {z.shape[1]}, all NaN)")
    index = np.full(z.shape, -1)
    index[missing] = np.arange(count)
    degree = np.zeros(count)
    rhs = np.zeros(count)
    rows, cols = [], []
    ny, nx = z.shape
    # every ordered pair (p, q) of 4-neighbours inside the map: q = p shifted by one pixel
    for p_part, q_part in (
        ((slice(None), slice(0, nx - 1)), (slice(None), slice(1, nx))),
        ((slice(None), slice(1, nx)), (slice(None), slice(0, nx - 1))),
        ((slice(0, ny - 1), slice(None)), (slice(1, ny), slice(None))),
        ((slice(1, ny), slice(None)), (slice(0, ny - 1), slice(None))),
    ):
        p, q, z_q = index[p_part].ravel(), index[q_part].ravel(), z[q_part].ravel()
        unknown = p >= 0
        degree += np.bincount(p[unknown], minlength=count)
        to_missing = unknown & (q >= 0)
        rows.append(p[to_missing])
        cols.append(q[to_missing])
        to_defined = unknown & (q < 0)
        rhs += np.bincount(p[to_defined], weights=z_q[to_defined], minlength=count)
    rows_all, cols_all = np.concatenate(rows), np.concatenate(cols)
    diagonal = np.arange(count)
    matrix = coo_matrix(
        (np.concatenate([degree, -np.ones(rows_all.size)]),
         (np.concatenate([diagonal, rows_all]), np.concatenate([diagonal, cols_all]))),
        shape=(count, count),
    ).tocsc()
    z[missing] = spsolve(matrix, rhs)
    return z, count


def masked_moments(heights: np.ndarray, pixel_size: tuple[float, float],
                   periodic: bool = False) -> tuple[float, float, float]:
    """rms height, m2 and m4 of a map from its defined (non-NaN) pixels only, by finite differences.

    The heights r are the defined heights minus their least-squares plane (their mean if
    ``periodic``); the rms height is that of r, and m2 and m4 are the mean squares of the slope
    ``(r[k+1] - r[k]) / d`` and of the curvature ``(r[k+1] - 2 r[k] + r[k-1]) / d^2`` over the
    pairs and triples of defined pixels, averaged over the x and y directions (an isotropic
    surface's profile moments).

    Parameters
    ----------
    heights
        Height map, 2-D, m; NaN marks an undefined pixel.
    pixel_size
        Pixel pitch (dy, dx), m.
    periodic
        Whether the map is one period of a periodic surface (only its mean is removed).

    Returns
    -------
    tuple of float
        rms height (m), m2 (dimensionless), m4 (m^-2).

    Raises
    ------
    ValueError
        If no pixel triple along x or along y is all defined.
    """
    z = np.asarray(heights, dtype=float)
    defined = ~np.isnan(z)
    yy, xx = np.nonzero(defined)
    if periodic:
        residual = z[defined] - z[defined].mean()
    else:
        design = np.column_stack([np.ones(yy.size), xx, yy])
        coef, *_ = np.linalg.lstsq(design, z[defined], rcond=None)
        residual = z[defined] - design @ coef
    r = np.full(z.shape, np.nan)
    r[defined] = residual
    slopes, curvatures = [], []
    for profiles, step in ((r, pixel_size[1]), (r.T, pixel_size[0])):  # along x, then along y
        slope = np.diff(profiles, axis=1) / step
        curvature = np.diff(profiles, n=2, axis=1) / step**2
        if not np.any(np.isfinite(curvature)):
            raise ValueError("height map has no three defined pixels in a row along x or y: m4 is undefined")
        slopes.append(np.mean(slope[np.isfinite(slope)] ** 2))
        curvatures.append(np.mean(curvature[np.isfinite(curvature)] ** 2))
    return float(np.sqrt(np.mean(residual**2))), float(np.mean(slopes)), float(np.mean(curvatures))
