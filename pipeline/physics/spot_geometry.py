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
