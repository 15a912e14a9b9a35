"""The ``segment`` spot rule's table: the conductance of a disc's circular segment, by the full field.

An oxide edge whose correlation length is much larger than a contact spot crosses the spot as
a nearly straight chord, so the clean part of a spot of radius ``a`` and clean share ``f`` is a
circular segment. Its constriction conductance is that of a rigid flat punch on the segment
(Barber's analogy, :func:`g2tom.reference.punch.punch_conductance`), here relative to the
whole disc's, ``h(f) = C(segment) / C(disc)``, on an ``n x n`` grid with the disc ``radius``
pixels across, the segments cut by chords at ``x = d a``, ``d = cos(theta)`` for evenly spaced
theta (thin segments included), and ``f`` the segment's share of the disc's pixels.

Of all plane sets of one area the disc has the least capacity (Polya and Szego), so the
``disc`` rule's equal-area disc ``a sqrt(f)`` understates a segment's conductance; the table
gives the gain ``h(f) / sqrt(f)``: 1.04 at f = 0.5, 1.13 at 0.15, 1.42 at 0.002, 1 at f -> 1.
``python -m g2tom.reference.segment`` prints it (the constants of
:mod:`g2tom.physics.spot_share` come from the defaults: 80 pixels on 256^2, tolerance 1e-9;
on 60 pixels the gain at f = 0.5 differs by 0.04 %).
"""

from __future__ import annotations

import numpy as np

from g2tom.reference.elastic import free_surface
from g2tom.reference.punch import punch_conductance

__all__ = ["segment_gains"]


def segment_gains(radius: float = 80.0, n: int = 256, chords: int = 29,
                  tolerance: float = 1e-9) -> tuple[np.ndarray, np.ndarray]:
    """Clean shares ``f`` of circular segments and their gains ``h(f) / sqrt(f)``, increasing f.

    Parameters
    ----------
    radius
        Disc radius, pixels (< n / 2).
    n
        Grid side, pixels.
    chords
        Segments, cut at ``d = cos(theta)``, theta evenly spaced strictly inside (0, pi).
    tolerance
        The punch solves' relative residual.

    Returns
    -------
    tuple of numpy.ndarray
        Shares ``f`` in (0, 1) and gains ``C(segment) / (sqrt(f) C(disc))``, each (chords,),
        dimensionless; segments of no pixel are left out.
    """
    if not 0.0 < radius < n / 2.0:
        raise ValueError(f"radius = {radius!r} is out of range: must be in (0, n / 2 = {n / 2:g}) pixels")
    operator = free_surface(n, 1.0, 1.0)
    y, x = np.mgrid[:n, :n] - (n - 1) / 2.0
    disc = x * x + y * y <= radius * radius
    whole = punch_conductance(operator, disc, 1.0, tolerance).conductance
    shares, gains = [], []
    for d in np.cos(np.linspace(0.0, np.pi, chords + 2)[1:-1]):  # thin segments first
        segment = disc & (x >= d * radius)
        if not segment.any():
            continue
        f = segment.sum() / disc.sum()
        shares.append(f)
        gains.append(punch_conductance(operator, segment, 1.0, tolerance).conductance / whole / np.sqrt(f))
    return np.array(shares), np.array(gains)


if __name__ == "__main__":
    f, g = segment_gains()
    print("SEGMENT_SHARE = (" + ", ".join(f"{v:.4f}" for v in f) + ")")
    print("SEGMENT_GAIN = (" + ", ".join(f"{v:.4f}" for v in g) + ")")
