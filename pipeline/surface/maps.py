"""The map a contact is pressed on: one measured topography, or the composite of two, in m.

Two rough bodies in elastic contact (small slopes) are one rigid rough body of the composite
topography ``h1 + h2`` on a flat of the pair's E*: the two maps are added pixel by pixel as given
(same shape and pixel; flip one first if they were measured facing each other). Undefined pixels
are handled by ``g2tom.heightmap.measured_area``: holes inside the measured area are filled,
the outside (an irregular field of view) stays undefined and no window may cover it. The plane
removed (``plane``) is the least-squares plane of the measured pixels.
"""

from __future__ import annotations

import hashlib
import math
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from g2tom.config import ConfigError
from g2tom.heightmap import CUTOFF_PIXELS, PLAUSIBLE_SIGMA, Measured, area_moments, measured_area, read_measured
from g2tom.physics.roughness import detrend, validated_heights
from g2tom.physics.surface_spectrum import SummitParameters, summit_parameters

__all__ = ["RESAMPLE_ORDER", "PIXEL_RANGE", "SurfaceMap", "load_map", "summits"]

#: Spline order of the resampling of oblong pixels onto square ones (1: linear).
RESAMPLE_ORDER = 1
#: The pixel sides a map may have, m (from atomic spacing to a metre).
PIXEL_RANGE = (1e-12, 1.0)


@dataclass(frozen=True)
class SurfaceMap:
    """A measured (or composite) topography ready for windows.

    Attributes
    ----------
    heights
        Heights, m, (rows, columns) = (y, x); NaN outside the measured area.
    inside
        Where the map is measured (or a hole was filled), bool, same shape.
    pixel
        Pixel side, m (square pixels).
    files, digests
        The files read and the SHA-256 of each.
    filled
        Undefined pixels filled inside the measured area.
    detrend
        What was removed: ``plane`` or ``none``.
    resampled
        How oblong pixels were made square ('' where they were square).
    """

    heights: np.ndarray
    inside: np.ndarray
    pixel: float
    files: tuple[str, ...]
    digests: tuple[str, ...]
    filled: int
    detrend: str
    resampled: str = ""

    @property
    def measured_share(self) -> float:
        """Share of the map's pixels that are measured (or filled holes)."""
        return float(self.inside.mean())

    @property
    def rms_height(self) -> float:
        """Standard deviation of the heights over the measured area, m."""
        return float(np.std(self.heights[self.inside]))


def _digest(path: Path) -> str:
    sha = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            sha.update(block)
    return sha.hexdigest()


def _checked(path: Path, measured: Measured) -> np.ndarray:
    """The map's heights as floats, refused (one line naming the file) unless real, numeric, 2-D, at
    least 3 x 3 and finite wherever defined (NaN marks an undefined pixel)."""
    raw = np.asarray(measured.heights)
    try:
        validated_heights(np.where(np.isnan(raw), 0.0, raw) if raw.dtype.kind == "f" else raw)
    except ValueError as exc:
        raise ConfigError(f"MAP {str(path)!r}: {exc}") from None
    return raw.astype(float)


def _square(path: Path, measured: Measured, pixel_size: float | None) -> tuple[np.ndarray, float, str]:
    """The map's heights (m) on square pixels and their side, m: ``pixel_size`` where given, else the
    file's; a map of oblong pixels is resampled along its finer axis onto the coarser pitch
    (linear interpolation between pixel centres, :data:`RESAMPLE_ORDER`)."""
    heights = _checked(path, measured)
    if pixel_size is not None:
        low, high = PIXEL_RANGE
        if not (math.isfinite(pixel_size) and low <= pixel_size <= high):
            raise ConfigError(f"--pixel-size = {pixel_size!r} is out of range: must be in [{low:g}, {high:g}] (m)")
        return heights, float(pixel_size), ""
    if measured.pixel_size is None:
        raise ConfigError(f"MAP {str(path)!r} carries no pixel size: give --pixel-size (m)")
    dy, dx = measured.pixel_size
    if math.isclose(dy, dx, rel_tol=1e-6):
        return heights, float(dx), ""
    if np.isnan(heights).any():
        raise ConfigError(f"MAP {str(path)!r} has pixels of {dy:.4g} x {dx:.4g} m and undefined pixels: the full "
                          "field needs square pixels; resample the map, or give --pixel-size to take them as square")
    from scipy.ndimage import zoom

    pixel = max(dy, dx)
    factors = (dy / pixel, dx / pixel)
    square = zoom(heights, factors, order=RESAMPLE_ORDER, mode="nearest", grid_mode=True)
    return square, float(pixel), f"resampled linearly from pixels of {dy:.4g} x {dx:.4g} m"


def load_map(paths: list[Path], pixel_size: float | None, how: str = "plane") -> SurfaceMap:
    """Read one map, or two and add them, with their measured area and (``how="plane"``) plane removed.

    Parameters
    ----------
    paths
        One or two height maps (any format ``g2tom.heightmap.read_measured`` reads).
    pixel_size
        Pixel side, m (required for .npy, netCDF and text maps; overrides an instrument file's).
    how
        ``plane`` or ``none`` (:data:`g2tom.surface.study.DETRENDS`).

    Raises
    ------
    ConfigError
        If a map is unreadable, has no pixel size, oblong pixels and undefined ones, no measured
        pixel, or the two maps differ in shape or pixel.
    """
    maps, pixels, notes = [], [], []
    for path in paths:
        heights, pixel, note = _square(Path(path), read_measured(path), pixel_size)
        maps.append(heights)
        pixels.append(pixel)
        notes.append(note)
    if len(maps) == 2 and (maps[0].shape != maps[1].shape or not np.isclose(pixels[0], pixels[1], rtol=1e-6)):
        raise ConfigError(f"MAP2 {str(paths[1])!r} is {maps[1].shape[0]} x {maps[1].shape[1]} pixels of "
                          f"{pixels[1]:.4g} m: must match MAP ({maps[0].shape[0]} x {maps[0].shape[1]} pixels of "
                          f"{pixels[0]:.4g} m) to be added pixel by pixel")
    composite = maps[0] if len(maps) == 1 else maps[0] + maps[1]
    area = measured_area(composite)
    heights = detrend(area.heights) if how == "plane" else area.heights - np.nanmean(area.heights)
    rms = float(np.std(heights[area.inside]))
    low, high = PLAUSIBLE_SIGMA
    if not low <= rms <= high:
        warnings.warn(f"MAP {str(paths[0])!r}: rms height = {rms:.3g} m is implausible for a surface (expected "
                      f"{low:g}..{high:g} m): are the heights in m?", stacklevel=2)
    return SurfaceMap(heights=heights, inside=area.inside, pixel=pixels[0], files=tuple(str(p) for p in paths),
                      digests=tuple(_digest(Path(p)) for p in paths), filled=area.filled, detrend=how,
                      resampled="; ".join(n for n in notes if n))


def summits(surface: SurfaceMap) -> SummitParameters | None:
    """The Greenwood–Williamson summit parameters of the map's measured area (``g2tom roughness``'s:
    spectral moments to ``g2tom.heightmap.CUTOFF_PIXELS`` pixels, beta by the paper's rule), or
    None where the area is too narrow for them."""
    pixel = (surface.pixel, surface.pixel)
    try:
        moments = area_moments(surface.heights, surface.inside, pixel, CUTOFF_PIXELS * surface.pixel)
        return summit_parameters(moments.m0, moments.m2, moments.m4)
    except ValueError:
        return None
