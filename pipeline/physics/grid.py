"""The square cell grid of pitch 1/sqrt(eta) on which contact spots and oxide fields live."""

from __future__ import annotations

import numpy as np

__all__ = ["cell_centres"]


def cell_centres(n_cells: int, cell_size: float) -> np.ndarray:
    """Cell-centre coordinates along one axis, symmetric about the indenter axis.

    Parameters
    ----------
    n_cells
        Cells along one side of the window (odd keeps a cell centred on the axis).
    cell_size
        Cell pitch 1/sqrt(eta), in m.

    Returns
    -------
    numpy.ndarray
        Shape (n_cells,), in m, ascending; the same array serves as ``x`` and ``y``.
    """
    if n_cells < 1:
        raise ValueError(f"n_cells = {n_cells} is out of range: must be >= 1")
    if not (cell_size > 0 and np.isfinite(cell_size)):
        raise ValueError(f"cell_size = {cell_size} is out of range: must be > 0 (m)")
    return (np.arange(n_cells) - (n_cells - 1) / 2.0) * cell_size
