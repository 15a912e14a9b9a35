"""The window a contact needs, the refusals before work, and the contact positions on the map.

**The window.** The contact at force F reaches about the smooth indenter's contact radius a(F)
(:func:`g2tom.physics.indenter.smooth_contact_radius`; where the caps yield, at least Holm's
sqrt(F / (pi H))) plus the distance over which the indenter's profile rises
:data:`ROUGHNESS_RMS` rms heights of the map above its height at a: beyond it no summit of the
map reaches the indenter. The window's half side is :data:`MARGIN` times that reach at the
heaviest force. Should a contact still reach the window's edge (a summit far above the rms),
that force's results are NaN and the answer says so.

**The pixel.** The lightest force's contact radius must span :data:`MIN_RADIUS_PIXELS` pixels.

**Positions.** A window may only cover measured pixels. The map is tiled by windows that do not
overlap, at the tiling offset (in steps of a quarter window) that fits the most windows inside
the measured area: that many positions are *independent* (they share no pixel). The positions are
those tiles, completed by windows at random valid corners that overlap none of them, in an order
drawn from the seed (``SeedSequence(seed, spawn_key=(POSITIONS_KEY,))``); more positions than that
add windows at random valid corners, which overlap others and are marked not independent.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable

import numpy as np

from g2tom.config import ConfigError
from g2tom.physics.indenter import profile, smooth_contact_radius
from g2tom.surface.maps import SurfaceMap
from g2tom.surface.study import DEFAULT_POSITIONS, SurfaceStudy, stream

__all__ = ["MARGIN", "ROUGHNESS_RMS", "MIN_RADIUS_PIXELS", "MAX_FORCE", "POSITIONS_KEY", "CANDIDATES", "LATTICE_LIMIT", "Positions", "contact_reach",
           "smooth_radius", "window_pixels", "check_resolution", "check_window", "valid_corners", "choose_positions", "spot_corner"]

#: The window's half side over the heaviest force's contact reach.
MARGIN = 1.15
#: How far (in rms heights of the map) the indenter's profile must rise above its height at the
#: smooth contact radius before no summit can reach it.
ROUGHNESS_RMS = 3.0
#: Pixels the lightest force's smooth contact radius must span.
MIN_RADIUS_PIXELS = 8.0
#: The heaviest force (N) a refusal suggests: beyond it, it says to measure a finer map instead.
MAX_FORCE = 1e12
#: The spawn key of the positions' random order (the oxide fields use others).
POSITIONS_KEY = 0
#: Most valid corners (in the seed's order) looked at to complete the independent windows and to
#: add overlapping ones.
CANDIDATES = 4096
#: Most valid corners drawn from: a larger map's are thinned to every 2nd, 4th, ... pixel.
LATTICE_LIMIT = 65536


def _bisect(below: Callable[[float], bool], low: float, high: float, steps: int = 60,
            geometric: bool = False) -> tuple[float, float]:
    """The bracket ``[low, high]`` narrowed ``steps`` times around where ``below`` turns False (True at
    ``low``, False at ``high``), at the arithmetic or ``geometric`` midpoint."""
    for _ in range(steps):
        mid = math.sqrt(low * high) if geometric else 0.5 * (low + high)
        low, high = (mid, high) if below(mid) else (low, mid)
    return low, high


def smooth_radius(study: SurfaceStudy, force: float) -> float:
    """The study's smooth indenter's contact radius at ``force`` (N), m
    (:func:`g2tom.physics.indenter.smooth_contact_radius`)."""
    return float(smooth_contact_radius(force, study.e_star, study.shape, radius=study.radius,
                                       cone_angle=study.cone_angle, punch_radius=study.punch_radius))


def contact_reach(study: SurfaceStudy, force: float, rms: float) -> float:
    """How far from the axis the contact at ``force`` (N) may reach on a map of ``rms`` heights (m), m."""
    a = smooth_radius(study, force)
    if study.hardness is not None:
        a = max(a, math.sqrt(force / (math.pi * study.hardness)))
    rise = float(profile(a, **study.indenter)) + ROUGHNESS_RMS * rms
    low, high = a, max(2.0 * a, a + 1e-9)
    while float(profile(high, **study.indenter)) < rise:
        low, high = high, 2.0 * high
    low, high = _bisect(lambda r: float(profile(r, **study.indenter)) < rise, low, high)  # the profile rises
    return high


def window_pixels(study: SurfaceStudy, surface: SurfaceMap, force: float | None = None) -> int:
    """The window's side in pixels for the heaviest force (or ``force``, N): ``study.window`` where
    given, else 2 MARGIN reach / pixel rounded up to an even number."""
    if study.window is not None and force is None:
        return study.window
    force = study.forces[-1] if force is None else force
    reach = contact_reach(study, force, surface.rms_height)
    n = math.ceil(2.0 * MARGIN * reach / surface.pixel)
    return n + n % 2


def check_resolution(study: SurfaceStudy, surface: SurfaceMap) -> None:
    """Refuse a pixel that does not resolve the lightest force's contact.

    Raises
    ------
    ConfigError
        Naming the lightest force, its contact radius in pixels and the force that would do.
    """
    a = smooth_radius(study, study.forces[0])
    pixels = a / surface.pixel
    if pixels >= MIN_RADIUS_PIXELS:
        return
    needed = MIN_RADIUS_PIXELS * surface.pixel
    lightest = _force_for_radius(study, needed)
    fix = (f"raise the lightest --force to >= {lightest:.3g} N or measure a finer map" if lightest is not None
           else "measure a finer map")
    raise ConfigError(f"--force = {study.forces[0]:g} is out of range: its contact radius {a:.3g} m spans "
                      f"{pixels:.2f} pixels of {surface.pixel:.3g} m, fewer than the {MIN_RADIUS_PIXELS:g} the "
                      f"full field needs; {fix}")


def _force_for_radius(study: SurfaceStudy, radius: float) -> float | None:
    """The force (N) whose smooth contact radius is ``radius`` (m), or None if none is (a flat punch) or
    it exceeds :data:`MAX_FORCE`."""
    if study.shape == "flat_punch":
        return None
    low, high = 1e-12, 1.0
    while smooth_radius(study, high) < radius:
        if high > MAX_FORCE:
            return None
        high *= 10.0
    low, high = _bisect(lambda force: smooth_radius(study, force) < radius, low, high, steps=200, geometric=True)
    return high


def valid_corners(inside: np.ndarray, n: int) -> np.ndarray:
    """Where an ``n x n`` window may start: bool (rows - n + 1, columns - n + 1), True where every
    pixel it covers is measured (an empty array when the map is smaller than the window)."""
    rows, cols = inside.shape
    if rows < n or cols < n:
        return np.zeros((0, 0), bool)
    outside = np.pad(np.cumsum(np.cumsum(~inside, axis=0), axis=1), ((1, 0), (1, 0)))
    count = outside[n:, n:] - outside[:-n, n:] - outside[n:, :-n] + outside[:-n, :-n]
    return count == 0


@dataclass(frozen=True)
class Positions:
    """The windows' first pixels (row, column) in the order used, whether each is independent, and
    how many independent windows the map holds."""

    corners: np.ndarray
    independent: np.ndarray
    capacity: int


def _tiles(valid: np.ndarray, n: int) -> np.ndarray:
    """The non-overlapping windows of the offset (quarter-window steps) that fits the most, (k, 2)."""
    step = max(1, n // 4)
    best = np.zeros((0, 2), int)
    for oy in range(0, min(n, valid.shape[0]), step):
        for ox in range(0, min(n, valid.shape[1]), step):
            rows, cols = np.arange(oy, valid.shape[0], n), np.arange(ox, valid.shape[1], n)
            r, c = np.meshgrid(rows, cols, indexing="ij")
            keep = valid[r, c]
            if keep.sum() > len(best):
                best = np.column_stack([r[keep], c[keep]])
    return best


def choose_positions(valid: np.ndarray, n: int, count: int | None, seed: int) -> Positions:
    """``count`` windows of ``n`` pixels among the ``valid`` corners (:func:`valid_corners`), in the
    seed's order: the independent windows first, then overlapping ones (``count`` None: every
    independent window, at most :data:`g2tom.surface.study.DEFAULT_POSITIONS`).

    The independent windows are the best tiling's, completed by any valid corner (of at most
    :data:`CANDIDATES`, in the seed's order) whose window overlaps none of them.

    Raises
    ------
    ConfigError
        If the measured area holds fewer than ``count`` windows among those candidates.
    """
    rng = stream(seed, POSITIONS_KEY)
    tiles = [tuple(t) for t in _tiles(valid, n).tolist()]
    step = 1  # a large map's valid corners are thinned to a lattice of at most LATTICE_LIMIT
    while np.count_nonzero(valid[::step, ::step]) > LATTICE_LIMIT:
        step *= 2
    corners = np.argwhere(valid[::step, ::step]) * step
    order = rng.permutation(len(corners))[:CANDIDATES]
    rest = []
    for corner in corners[order].tolist():
        if all(max(abs(corner[0] - t[0]), abs(corner[1] - t[1])) >= n for t in tiles):
            tiles.append(tuple(corner))
        else:
            rest.append(tuple(corner))
    independent = np.array(tiles, int).reshape(-1, 2)[rng.permutation(len(tiles))]
    extra = np.array([c for c in rest if c not in set(tiles)], int).reshape(-1, 2)
    available = len(independent) + len(extra)
    if count is None:
        count = min(DEFAULT_POSITIONS, len(independent))
    if available < count:
        raise ConfigError(f"--positions = {count} is out of range: the measured area holds {available} windows of "
                          f"{n} pixels ({len(independent)} of them independent); must be <= {available}")
    chosen = np.concatenate([independent, extra])[:count]
    return Positions(chosen, np.arange(count) < len(independent), len(independent))


def _largest_window(inside: np.ndarray) -> int:
    """The side (pixels) of the largest square window that covers measured pixels only."""
    low, high = 0, min(inside.shape)
    while low < high:
        mid = (low + high + 1) // 2
        low, high = (mid, high) if valid_corners(inside, mid).any() else (low, mid - 1)
    return low


def check_window(study: SurfaceStudy, surface: SurfaceMap, n: int) -> np.ndarray:
    """The valid corners of the window of ``n`` pixels; refuse a map whose measured area holds none.

    Raises
    ------
    ConfigError
        Naming the heaviest force, the window it needs and the heaviest force the map holds.
    """
    valid = valid_corners(surface.inside, n)
    if valid.any():
        return valid
    largest = _largest_window(surface.inside)
    side = f"{n if n < 10**7 else format(n, '.3g')} pixels ({n * surface.pixel:.3g} m)"
    if study.window is not None:
        raise ConfigError(f"--window = {n} is out of range: the map's measured area holds no window of {side}; "
                          f"must be <= {largest}")
    low, high = 0.0, study.forces[-1]
    low, high = _bisect(lambda force: window_pixels(study, surface, force) <= largest, low, high)
    if low > 0:
        fix = f"the heaviest force it holds is {low:.3g} N: lower --force or measure a larger area"
    else:
        fix = (f"the margin for the map's roughness ({ROUGHNESS_RMS:g} rms heights) alone needs more: measure a larger "
               f"area, or give --window <= {largest} and check that no force reports the window's edge")
    raise ConfigError(f"--force = {study.forces[-1]:g} is out of range: its contact needs a window of {side} and "
                      f"the map's measured area holds at most {largest} pixels ({largest * surface.pixel:.3g} m); "
                      f"{fix}")


def spot_corner(surface: SurfaceMap, n: int, x: float, y: float, centre: bool) -> np.ndarray:
    """The first pixel (row, column) of the window centred at ``x``, ``y`` (m from the first pixel's
    centre; ``centre``: the map's centre).

    Raises
    ------
    ConfigError
        If that window leaves the map or covers unmeasured pixels.
    """
    rows, cols = surface.inside.shape
    if centre:
        corner = np.array([(rows - n) // 2, (cols - n) // 2])
    else:
        corner = np.array([round(y / surface.pixel - (n - 1) / 2), round(x / surface.pixel - (n - 1) / 2)])
    r, c = corner
    if r < 0 or c < 0 or r + n > rows or c + n > cols or not surface.inside[r:r + n, c:c + n].all():
        where = "centre" if centre else f"{x:g},{y:g}"
        raise ConfigError(f"--at = {where} is out of range: the window of {n} pixels around it leaves the map's "
                          f"measured area; centres must lie in x in [{(n - 1) / 2 * surface.pixel:.4g}, "
                          f"{(cols - 1 - (n - 1) / 2) * surface.pixel:.4g}] m, y in [{(n - 1) / 2 * surface.pixel:.4g}, "
                          f"{(rows - 1 - (n - 1) / 2) * surface.pixel:.4g}] m, over measured pixels")
    return corner
