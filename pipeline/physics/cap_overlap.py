"""Overlapping contact discs shared by their power cells: the part of each disc that is its own.

Capped caps flatten: a cap pressed far past first yield is truncated, its contact a disc of radius
``a ~ sqrt(2 beta w)``, and on a dense surface neighbouring discs overlap. The surface there is the
higher of the two caps, so the overlap is one contact, not two. For caps of one tip radius
``beta`` truncated at one level, the higher cap at a point ``p`` is the one of least power
``|p - x_i|^2 - a_i^2``: the contact is the union of the discs, split without gaps or double
counting by the power diagram (Laguerre cells) of the circles ``(x_i, a_i)``. Two overlapping
circles' cells meet on their radical line, the line through both intersection points; circles
that do not overlap leave each other's discs whole.

:func:`g2tom.physics.cap_overlap.owned_areas` gives each disc's area inside its own cell, exactly
(the disc clipped by the radical lines of the discs it overlaps, a convex polygon, and the disc's
area inside that polygon as a sum of circle-triangle intersections). Their sum is the area of the
union of the discs.
"""

from __future__ import annotations

import numba
import numpy as np

__all__ = ["owned_areas", "owned_area_derivatives"]


def owned_areas(x: np.ndarray, y: np.ndarray, radius: np.ndarray) -> np.ndarray:
    """Each disc's area inside its power cell, m^2: ``pi a_i^2`` for a disc that overlaps none.

    Parameters
    ----------
    x, y
        Disc centres, m, shape (n,).
    radius
        Disc radii, m, shape (n,); a disc of radius 0 owns nothing and clips nothing.

    Returns
    -------
    numpy.ndarray
        Owned areas, m^2, shape (n,); they sum to the area of the union of the discs.
    """
    return owned_area_derivatives(x, y, radius)[0]


def owned_area_derivatives(x: np.ndarray, y: np.ndarray, radius: np.ndarray) -> tuple[np.ndarray, ...]:
    """Owned areas (:func:`g2tom.physics.cap_overlap.owned_areas`) and their derivatives in the radii.

    A disc's owned area grows with its own radius by its free arc (the part of its circle inside
    its cell) and by the chords it shares with its neighbours, whose radical lines move away from
    it: the line between discs ``i`` and ``j`` lies at ``(d^2 + a_i^2 - a_j^2) / (2 d)`` from
    ``x_i``, so ``dA_i / da_i = a_i theta_i + sum_j l_ij a_i / d_ij`` and ``dA_i / da_j = -l_ij
    a_j / d_ij``, with ``theta_i`` the free arc's angle and ``l_ij`` the length of the shared chord.

    Parameters
    ----------
    x, y, radius
        As :func:`g2tom.physics.cap_overlap.owned_areas`.

    Returns
    -------
    tuple of numpy.ndarray
        The owned areas (m^2, (n,)), ``dA_i / da_i`` (m, (n,)), and the other derivatives
        ``dA_i / da_j`` as ``(rows i, columns j, values)`` (m; one entry per ordered pair of
        overlapping discs that share a chord).
    """
    x, y, radius = (np.ascontiguousarray(v, dtype=np.float64) for v in (x, y, radius))
    if not (x.shape == y.shape == radius.shape and x.ndim == 1):
        raise ValueError(f"x {x.shape}, y {y.shape} and radius {radius.shape} must be one shape (n,)")
    return _owned(x, y, radius)


@numba.njit(cache=True, nogil=True)
def _owned(x: np.ndarray, y: np.ndarray, a: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray,
                                                                    np.ndarray]:
    """``owned_area_derivatives``, compiled: candidate neighbours by a sweep along x."""
    n = x.size
    order = np.argsort(x)
    top = a.max() if n else 0.0
    area = np.pi * a * a
    own = 2.0 * np.pi * a
    rows, cols, values = [0], [0], [0.0]  # typed by their first items, dropped below
    for oi in range(n):
        i = order[oi]
        if a[i] <= 0.0:
            area[i], own[i] = 0.0, 0.0
            continue
        lines = [(0.0, 0.0, 0.0)]  # (nx, ny, c): the disc's side is n . q <= c, q = (p - x_i) / a_i
        partners = [0]
        for direction in (-1, 1):
            oj = oi + direction
            while 0 <= oj < n:
                j = order[oj]
                dx = x[j] - x[i]
                if abs(dx) > a[i] + top:
                    break
                oj += direction
                dy = y[j] - y[i]
                d2 = dx * dx + dy * dy
                if a[j] <= 0.0 or d2 >= (a[i] + a[j]) ** 2:
                    continue
                lines.append((dx / a[i], dy / a[i], (d2 + a[i] * a[i] - a[j] * a[j]) / (2.0 * a[i] * a[i])))
                partners.append(j)
        if len(lines) == 1:
            continue
        polygon, labels = _clipped_square(lines)
        unit_area, arc, chords = _unit_disc_in_polygon(polygon, labels, len(lines))
        area[i] = a[i] * a[i] * unit_area
        own[i] = a[i] * arc
        for k in range(1, len(lines)):
            if chords[k] > 0.0:
                j = partners[k]
                d = np.hypot(x[j] - x[i], y[j] - y[i])
                chord = a[i] * chords[k]
                own[i] += chord * a[i] / d
                rows.append(i)
                cols.append(j)
                values.append(-chord * a[j] / d)
    return (area, own, np.array(rows[1:], dtype=np.int64), np.array(cols[1:], dtype=np.int64),
            np.array(values[1:]))


@numba.njit(cache=True, nogil=True)
def _clipped_square(lines: list) -> tuple[np.ndarray, np.ndarray]:
    """The square ``[-1.5, 1.5]^2`` (it holds the unit disc) clipped by the half-planes
    ``nx qx + ny qy <= c`` (Sutherland-Hodgman; ``lines[0]`` is a placeholder), vertices
    counter-clockwise, shape (k, 2), and the line each edge (vertex v to v + 1) lies on: its index
    in ``lines``, 0 for the square's own edges."""
    polygon = np.array([[-1.5, -1.5], [1.5, -1.5], [1.5, 1.5], [-1.5, 1.5]])
    labels = np.zeros(4, np.int64)
    for index in range(1, len(lines)):
        nx, ny, c = lines[index]
        k = polygon.shape[0]
        if k == 0:
            break
        out = np.empty((k + 1, 2))
        out_labels = np.empty(k + 1, np.int64)
        m = 0
        for v in range(k):
            px, py = polygon[v, 0], polygon[v, 1]
            qx, qy = polygon[(v + 1) % k, 0], polygon[(v + 1) % k, 1]
            fp = nx * px + ny * py - c
            fq = nx * qx + ny * qy - c
            if fp <= 0.0:
                out[m, 0], out[m, 1] = px, py
                out_labels[m] = labels[v]
                m += 1
                if fq > 0.0:  # leaving: the clipping line runs on from here
                    t = fp / (fp - fq)
                    out[m, 0], out[m, 1] = px + t * (qx - px), py + t * (qy - py)
                    out_labels[m] = index
                    m += 1
            elif fq < 0.0:  # entering: the edge's own line runs on from here
                t = fp / (fp - fq)
                out[m, 0], out[m, 1] = px + t * (qx - px), py + t * (qy - py)
                out_labels[m] = labels[v]
                m += 1
        polygon, labels = out[:m].copy(), out_labels[:m].copy()
    return polygon, labels


@numba.njit(cache=True, nogil=True)
def _unit_disc_in_polygon(polygon: np.ndarray, labels: np.ndarray, count: int) -> tuple[float, float, np.ndarray]:
    """The unit disc (centre 0) inside a convex polygon (vertices counter-clockwise): its area, the
    angle of its boundary's arcs, and the length of its boundary on each line (``count`` lines,
    by ``labels``), as sums over edges of the triangle (0, p, q)."""
    k = polygon.shape[0]
    area, arc = 0.0, 0.0
    chords = np.zeros(count)
    for v in range(k):
        w = (v + 1) % k
        part, angle, chord = _disc_in_triangle(polygon[v, 0], polygon[v, 1], polygon[w, 0], polygon[w, 1])
        area += part
        arc += angle
        chords[labels[v]] += chord
    return area, arc, chords


@numba.njit(cache=True, nogil=True)
def _disc_in_triangle(px: float, py: float, qx: float, qy: float) -> tuple[float, float, float]:
    """The unit disc (centre 0) inside the triangle (0, p, q): signed area, signed angle of the
    disc's arcs in it, and the length of the segment pq inside the disc."""
    dx, dy = qx - px, qy - py
    a = dx * dx + dy * dy
    if a == 0.0:
        return 0.0, 0.0, 0.0
    b = px * dx + py * dy
    c = px * px + py * py - 1.0
    disc = b * b - a * c
    if disc <= 0.0:  # the segment's line misses the disc: a sector
        angle = _angle(px, py, qx, qy)
        return 0.5 * angle, angle, 0.0
    root = np.sqrt(disc)
    t0, t1 = (-b - root) / a, (-b + root) / a  # where the line meets the circle, t in p + t (q - p)
    if t1 <= 0.0 or t0 >= 1.0:  # the chord lies beyond the segment
        angle = _angle(px, py, qx, qy)
        return 0.5 * angle, angle, 0.0
    s0, s1 = max(t0, 0.0), min(t1, 1.0)
    ux, uy = px + s0 * dx, py + s0 * dy  # the part of the segment inside the disc
    vx, vy = px + s1 * dx, py + s1 * dy
    before, after = _angle(px, py, ux, uy), _angle(vx, vy, qx, qy)
    return (0.5 * (before + after) + 0.5 * (ux * vy - uy * vx), before + after, (s1 - s0) * np.sqrt(a))


@numba.njit(cache=True, nogil=True)
def _angle(px: float, py: float, qx: float, qy: float) -> float:
    """Signed angle from the direction of p to that of q, radians."""
    return np.arctan2(px * qy - py * qx, px * qx + py * qy)
