"""g2tom's oxide field on the reference grid: the same continuous field, thresholded the same way.

g2tom decides a spot's oxide by its field value at the cell centre (``psi >= threshold``). The
field is continuous (a sum of Fourier modes over its period), so the reference evaluates the very
same realization (same seed, lambda and realization index: :class:`FieldSource`) at every pixel
centre and removes ``psi >= threshold`` from the contact set, with g2tom's threshold for that field
(the theoretical quantile, or the field's own empirical quantile over the cell centres).
"""

from __future__ import annotations

import numpy as np

from g2tom.physics import oxide_band, oxide_field
from g2tom.physics.grid import cell_centres
from g2tom.scene import FieldSource

__all__ = ["field_on_grid", "oxide_on_grid"]


def field_on_grid(source: FieldSource, lambda_index: int, realization: int, n: int, pixel: float) -> np.ndarray:
    """The field (float64, (n, n), indexed [y, x]) of one realization at the pixel centres of the grid."""
    lam = source.lambdas[lambda_index]
    modes = source.modes[lambda_index]
    coeffs = oxide_band.coefficients(modes, oxide_band.field_stream(source.seed, lam, realization),
                                      source.amplitudes)
    c = cell_centres(n, pixel)
    return oxide_field.grid_values(modes, coeffs, c, c)


def oxide_on_grid(source: FieldSource, lambda_index: int, realization: int, n: int, pixel: float) -> np.ndarray:
    """Oxide masks (bool, (xi, n, n)) of one realization at every ``source.xi``: ``psi >= threshold``."""
    psi = field_on_grid(source, lambda_index, realization, n, pixel)
    _, threshold = source.fields(lambda_index, np.array([realization]))
    return psi[None] >= threshold[:, 0, None, None].astype(np.float64)
