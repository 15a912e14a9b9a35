"""Clean share of contact spots cut by oxide edges: the ``disc`` spot rule (design note 11).

A contact spot is a disc of centre ``(x_i, y_i)`` and radius ``a_i`` (m). The oxide covers the
surface where the Gaussian field reaches its threshold, ``psi >= psi0``; the rest is clean.
The ``disc`` rule gives every spot its clean share

    f_i = (area of the disc where psi < psi0) / (pi a_i^2),

estimated by thresholding the field at a fixed quadrature pattern scaled onto the disc, and
lets the spot conduct with the effective radius ``a_i sqrt(f_i)`` (the radius of a disc of the
clean area; f = 0: the spot does not conduct). The ``centre`` rule (on/off at the spot's
centre, f in {0, 1}) is the pattern with no ring.

Quadrature pattern (:class:`DiscRule`), an equal-area partition of the unit disc into
``N = 1 + 3 n (n + 1)`` cells for ``n`` rings: a central disc of radius ``1 / sqrt(N)`` holding
the centre point, and ring k = 1 .. n, the annulus ``(1 + 3 (k - 1) k) / N <= r^2 <= (1 + 3 k
(k + 1)) / N``, cut into ``6 k`` equal sectors (a count proportional to the ring's
circumference, as in a hexagonal packing). Each cell carries one point of weight ``1 / N``, at
the cell's mean ``r^2`` (the middle of the annulus in ``r^2``) and its middle angle; ring k is
turned by ``k (sqrt(5) - 1) / 2`` of its sector width, so no two rings' points line up.
Every ring's points sum to zero, so the pattern's mean offset vanishes and its second moment
``sum w u^2`` is exactly that of the unit disc (1/4) but for the central cell's share
``1 / (4 N^2)``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["DiscRule", "DEFAULT_RINGS", "spot_points", "clean_share", "effective_radius"]

#: Rings of the default pattern (217 points). On discs of radius half the correlation length
#: cut by oxide edges, the clean share's absolute error against a 200 x 200 image of the disc is
#: 0.005 on average and below 0.02 on every disc tried (6 rings: 0.007 and 0.03; 3 rings: 0.017
#: and 0.07), without bias (mean signed error within +-0.0012 at lambda 1, 5, 23); see
#: tests/test_spot_share.py.
DEFAULT_RINGS = 8

#: Rotation of ring k, in sectors of that ring: k times the fractional golden ratio.
_GOLDEN = (np.sqrt(5.0) - 1.0) / 2.0


@dataclass(frozen=True)
class DiscRule:
    """An equal-area quadrature pattern on the unit disc (see the module docstring).

    Attributes
    ----------
    n_rings
        Rings around the centre point, >= 0 (0: the centre rule, one point).
    """

    n_rings: int = DEFAULT_RINGS

    def __post_init__(self) -> None:
        if not (isinstance(self.n_rings, (int, np.integer)) and self.n_rings >= 0):
            raise ValueError(f"n_rings = {self.n_rings!r} is out of range: must be an integer >= 0")

    @property
    def size(self) -> int:
        """Number of points ``1 + 3 n (n + 1)``."""
        return 1 + 3 * self.n_rings * (self.n_rings + 1)

    def offsets(self) -> tuple[np.ndarray, np.ndarray]:
        """Point offsets (u, v) on the unit disc, dimensionless, each shape (size,), centre first."""
        u, v = [np.zeros(1)], [np.zeros(1)]
        for k in range(1, self.n_rings + 1):
            count = 6 * k
            radius = np.sqrt((1 + 3 * k * k) / self.size)  # mean r^2 of (1+3(k-1)k)/N .. (1+3k(k+1))/N
            angle = 2.0 * np.pi * (np.arange(count) + 0.5 + k * _GOLDEN) / count
            u.append(radius * np.cos(angle))
            v.append(radius * np.sin(angle))
        return np.concatenate(u), np.concatenate(v)

    def weights(self) -> np.ndarray:
        """Equal weights ``1 / size`` (the cells' shares of the disc's area), shape (size,)."""
        return np.full(self.size, 1.0 / self.size)


def spot_points(x: np.ndarray, y: np.ndarray, a: np.ndarray, rule: DiscRule) -> tuple[np.ndarray, np.ndarray]:
    """The rule's points on every spot: ``(x_i + a_i u, y_i + a_i v)``.

    Parameters
    ----------
    x, y
        Spot centres, m, shape (n_spots,).
    a
        Spot radii, m, shape (n_spots,).
    rule
        The quadrature pattern.

    Returns
    -------
    tuple of numpy.ndarray
        Point coordinates x and y, m, each shape (n_spots, rule.size).
    """
    u, v = rule.offsets()
    a = np.asarray(a, float)[:, None]
    return np.asarray(x, float)[:, None] + a * u, np.asarray(y, float)[:, None] + a * v


def clean_share(values: np.ndarray, threshold: np.ndarray | float, weights: np.ndarray) -> np.ndarray:
    """Weighted share of every spot's quadrature points where the field is clean (``psi < psi0``).

    Parameters
    ----------
    values
        Field values at the spots' points, dimensionless, shape (..., n_spots, n_quad).
    threshold
        Oxide threshold psi0, dimensionless, broadcastable to ``values`` (e.g. shape (..., 1, 1)).
    weights
        Quadrature weights summing to 1, shape (n_quad,).

    Returns
    -------
    numpy.ndarray
        Clean share f in [0, 1], float64, shape (..., n_spots): exactly 1 where every point is
        clean (the spot keeps its own radius, whatever the rounding of the weights' sum), exactly
        0 where none is.
    """
    clean = np.asarray(values) < threshold
    return np.where(clean.all(axis=-1), 1.0, clean.astype(float) @ np.asarray(weights, float))


def effective_radius(a: np.ndarray, f: np.ndarray) -> np.ndarray:
    """Radius of a disc of the spot's clean area, ``a sqrt(f)``, in the unit of ``a`` (m).

    Parameters
    ----------
    a
        Spot radii, m.
    f
        Clean shares in [0, 1] (broadcast with ``a``); 0 gives radius 0 (not conducting).

    Returns
    -------
    numpy.ndarray
        Effective radii, m.
    """
    return np.asarray(a, float) * np.sqrt(f)
