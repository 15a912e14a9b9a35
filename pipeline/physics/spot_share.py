"""Clean share of contact spots cut by oxide edges: the ``disc`` spot rule of the discrete model.

A contact spot is a disc of centre ``(x_i, y_i)`` and radius ``a_i`` (m). The oxide covers the
surface where the Gaussian field reaches its threshold, ``psi >= psi0``; the rest is clean.
The ``disc`` rule gives every spot its clean share

    f_i = (area of the disc where psi < psi0) / (pi a_i^2),

estimated by thresholding the field at a fixed quadrature pattern scaled onto the disc, and
lets the spot conduct with the effective radius ``a_i sqrt(f_i)`` (the radius of a disc of the
clean area; f = 0: the spot does not conduct). The ``centre`` rule (on/off at the spot's
centre, f in {0, 1}) is the pattern with no ring. The ``segment`` rule counts f as ``disc`` does
but takes the clean part for the circular segment of that share (an oxide edge much longer than
the spot crosses it as a chord): effective radius ``a h(f)`` with ``h`` the segment's conductance
relative to the whole disc's, tabulated (:data:`SEGMENT_SHARE`, ``SEGMENT_GAIN``). The disc
has the least capacity of all plane sets of its area (Polya and Szego), so ``h(f) >= sqrt(f)``:
``disc`` understates a cut spot's conductance, by 4 % at f = 0.5 and 13 % at f = 0.15.

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

Many discs at once, each with its own pattern (the cube's spots at every load step):
:func:`disc_points` lays out their points and :func:`disc_shares` counts their clean shares, in
compiled loops (numba, ``nogil``), equal to the plain NumPy definitions ``spot_points`` and
``clean_share`` of tests/oracles.py applied disc by disc.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numba
import numpy as np

__all__ = ["DiscRule", "DEFAULT_RINGS", "RULES", "SEGMENT_SHARE", "SEGMENT_GAIN", "disc_points", "disc_shares",
           "effective_radius"]

#: The spot rules on discrete spots: on/off at the centre, the equal-area disc, the circular segment.
RULES = ("centre", "disc", "segment")
#: Clean shares f of circular segments of a disc (cut by chords at x = d a, d = cos theta for 29
#: evenly spaced theta) and their conductance over sqrt(f) times the disc's, ``h(f) / sqrt(f)``:
#: Barber's flat punch on the segment, 80 pixels of radius on a 256^2 grid (made by
#: ``python -m g2tom.reference.segment``; tests/test_spot_share.py recomputes a coarser table
#: with the reference's solver and holds these to it). Between them linear in f; 1 at f = 1.
SEGMENT_SHARE = (0.0024, 0.0067, 0.0153, 0.0300, 0.0473, 0.0774, 0.1057, 0.1488, 0.1954, 0.2451, 0.3044, 0.3657,
                 0.4363, 0.5000, 0.5637, 0.6343, 0.6956, 0.7549, 0.8046, 0.8512, 0.8943, 0.9226, 0.9527, 0.9700,
                 0.9847, 0.9933, 0.9976, 1.0)
SEGMENT_GAIN = (1.4164, 1.3702, 1.3178, 1.2588, 1.2166, 1.1743, 1.1539, 1.1256, 1.1058, 1.0903, 1.0747, 1.0621,
                1.0504, 1.0414, 1.0338, 1.0260, 1.0203, 1.0153, 1.0115, 1.0081, 1.0053, 1.0037, 1.0020, 1.0011,
                1.0005, 1.0001, 1.0000, 1.0)

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


@functools.cache
def _patterns() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Offsets (u, v) of the patterns of 0 .. :data:`DEFAULT_RINGS` rings, concatenated, and where
    each starts (n_rings + 2,): pattern n is ``[start[n], start[n + 1])``."""
    rules = [DiscRule(n) for n in range(DEFAULT_RINGS + 1)]
    u, v = (np.concatenate(part) for part in zip(*(rule.offsets() for rule in rules)))
    return u, v, np.concatenate([[0], np.cumsum([rule.size for rule in rules])])


def disc_points(x: np.ndarray, y: np.ndarray, radius: np.ndarray, rings: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The pattern points of every disc of ``radius > 0``: each disc's pattern scaled by its radius.

    Parameters
    ----------
    x, y
        Spot centres, m, shape (n,).
    radius
        Disc radii, m, shape (steps, n); discs of radius 0 have no points.
    rings
        Each disc's pattern, ``DiscRule(rings)``, integers 0 .. :data:`DEFAULT_RINGS`, shape (steps, n).

    Returns
    -------
    tuple of numpy.ndarray
        x and y of the points, m, flat: disc by disc in (step, spot) order, each disc's pattern
        in :meth:`DiscRule.offsets` order.
    """
    u, v, start = _patterns()
    return _disc_points(np.asarray(x, float), np.asarray(y, float), np.ascontiguousarray(radius, float),
                        _checked_rings(rings, np.shape(radius)), u, v, start)


def disc_shares(values: np.ndarray, thresholds: np.ndarray, radius: np.ndarray, rings: np.ndarray) -> np.ndarray:
    """Clean share of every disc at every threshold: the share of its pattern's points where the field is clean.

    Parameters
    ----------
    values
        Field values at :func:`disc_points`' points, dimensionless, flat, compared in their own
        dtype (float32 in the cube).
    thresholds
        Oxide thresholds psi0, shape (sets,), of ``values``' dtype.
    radius, rings
        As for :func:`disc_points`.

    Returns
    -------
    numpy.ndarray
        Clean shares f in [0, 1], shape (sets, steps, n): the share of the disc's points where
        ``value < threshold`` (exactly 1 where every point is clean), 0 where the radius is 0.
    """
    _, _, start = _patterns()
    values = np.ascontiguousarray(values)
    thresholds = np.asarray(thresholds, dtype=values.dtype)
    return _disc_shares(values, thresholds, np.ascontiguousarray(radius, float), _checked_rings(rings, np.shape(radius)),
                        start)


def _checked_rings(rings: np.ndarray, shape: tuple[int, ...]) -> np.ndarray:
    rings = np.ascontiguousarray(rings, dtype=np.int64)
    if rings.shape != shape or rings.size and not 0 <= rings.min() <= rings.max() <= DEFAULT_RINGS:
        raise ValueError(f"rings must be integers 0 .. {DEFAULT_RINGS} of the radii's shape {shape}")
    return rings


@numba.njit(cache=True, nogil=True)
def _disc_points(x: np.ndarray, y: np.ndarray, radius: np.ndarray, rings: np.ndarray, u: np.ndarray,
                 v: np.ndarray, start: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    steps, n = radius.shape
    total = 0
    for d in range(steps):
        for i in range(n):
            if radius[d, i] > 0.0:
                total += start[rings[d, i] + 1] - start[rings[d, i]]
    px, py = np.empty(total), np.empty(total)
    p = 0
    for d in range(steps):
        for i in range(n):
            a = radius[d, i]
            if a > 0.0:
                for k in range(start[rings[d, i]], start[rings[d, i] + 1]):
                    px[p] = x[i] + a * u[k]
                    py[p] = y[i] + a * v[k]
                    p += 1
    return px, py


@numba.njit(cache=True, nogil=True)
def _disc_shares(values: np.ndarray, thresholds: np.ndarray, radius: np.ndarray, rings: np.ndarray,
                 start: np.ndarray) -> np.ndarray:
    steps, n = radius.shape
    out = np.zeros((thresholds.size, steps, n))
    p = 0
    for d in range(steps):
        for i in range(n):
            if radius[d, i] > 0.0:
                size = start[rings[d, i] + 1] - start[rings[d, i]]
                for s in range(thresholds.size):
                    clean = 0
                    for k in range(p, p + size):
                        clean += values[k] < thresholds[s]
                    out[s, d, i] = 1.0 if clean == size else clean / size
                p += size
    return out


def effective_radius(a: np.ndarray, f: np.ndarray, rule: str = "disc") -> np.ndarray:
    """The radius with which a spot of clean share ``f`` conducts, in the unit of ``a`` (m).

    Parameters
    ----------
    a
        Spot radii, m.
    f
        Clean shares in [0, 1] (broadcast with ``a``); 0 gives radius 0 (not conducting).
    rule
        ``disc``: the disc of the clean area, ``a sqrt(f)``; ``segment``: the disc of the clean
        circular segment's conductance, ``a sqrt(f) h(f) / sqrt(f)`` (the table's gain, linear in
        f between its shares, its first below them); ``centre`` (f in {0, 1}): ``a f``.

    Returns
    -------
    numpy.ndarray
        Effective radii, m.
    """
    if rule not in RULES:
        raise ValueError(f"rule = {rule!r} is not allowed: must be one of {', '.join(RULES)}")
    f = np.asarray(f, float)
    radius = np.asarray(a, float) * np.sqrt(f)
    if rule == "segment":
        radius = radius * np.interp(f, SEGMENT_SHARE, SEGMENT_GAIN)
    return radius
