"""The spots of one window at every load step, as the resistance kernels take them.

Greenwood's closed form (:func:`g2tom.physics.constriction.resistance`), the exact point solve
(:func:`g2tom.physics.point_model.resistance`) and Greenwood's form with films
(:func:`g2tom.physics.point_model.greenwood_resistance`) take a batch of oxide masks, the
resistivity and one :class:`SpotGeometry`: where the spots are, how large, how their interaction is
weighted and how far it may be cropped.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["SpotGeometry"]


@dataclass(frozen=True)
class SpotGeometry:
    """Spot radii and interaction weights per load step on a square cell grid, with their crops.

    Attributes
    ----------
    radius
        Spot radii ``a_i`` per load step, shape (n_delta, n, n) as (step, y, x), in m; 0 means no
        spot. For spots that differ between maps (the kernels' ``groups``): one set per group,
        shape (n_groups, n_delta, n, n).
    weights
        Interaction weights, the shape of ``radius``: the radii themselves (Greenwood's Eq. 13, in
        m) or the cell contact areas (the published code, in m^2).
    pitch
        Cell pitch ``h``, in m.
    crops
        Side of the centred square of cells kept per load step, shape (n_delta,)
        (:func:`g2tom.physics.crops.choose_crops`); ``n`` everywhere keeps the whole window.
    tolerance
        Relative error of ``R`` allowed from cropping, dimensionless: entries whose crop bound
        exceeds it are computed again on the whole window.
    """

    radius: np.ndarray
    weights: np.ndarray
    pitch: float
    crops: np.ndarray
    tolerance: float

    @classmethod
    def whole_window(cls, radius: np.ndarray, weights: np.ndarray, pitch: float) -> SpotGeometry:
        """The spots evaluated on the whole window: every crop ``n`` cells, tolerance 0.

        Parameters
        ----------
        radius, weights
            As the attributes, in m (weights in m or m^2).
        pitch
            Cell pitch, in m.
        """
        return cls(radius, weights, pitch, np.full(radius.shape[-3], radius.shape[-1]), 0.0)

    @classmethod
    def spanning(cls, radius: np.ndarray, weights: np.ndarray, pitch: float) -> SpotGeometry:
        """The spots on the smallest centred squares that hold all of them, tolerance 0: exact.

        A cell whose radius and weight are 0 has no spot (it carries no current and weighs
        nothing), so cropping away the outer rings of cells without spots leaves every sum and
        system as on the whole window (:meth:`whole_window`); the kernels then work on fewer cells
        (light load steps of drawn asperities hold spots only near the centre).

        Parameters
        ----------
        radius, weights
            As the attributes, in m (weights in m or m^2); with one set per group, the squares
            hold every group's spots.
        pitch
            Cell pitch, in m.
        """
        n = radius.shape[-1]
        edge = np.minimum(np.arange(n), np.arange(n)[::-1])
        ring = np.minimum.outer(edge, edge)  # rings of cells between each cell and the window's edge
        held = ((radius != 0) | (weights != 0)).reshape((-1,) + radius.shape[-3:]).any(axis=0)
        empty = np.where(held, ring, n).min(axis=(1, 2))  # outer rings without a spot, per load step
        return cls(radius, weights, pitch, n - 2 * np.minimum(empty, (n - 1) // 2), 0.0)
