"""Measured surfaces: height maps read from files, their spectral moments and Greenwood–Williamson
parameters (what ``g2tom roughness FILE`` prints and ``g2tom predict --heightmap`` uses).

Height maps are read from numpy ``.npy``, netCDF (``.nc``: the variable ``height``, ``z``
or the only 2-D variable) or whitespace-separated text, heights in m with ``--pixel-size``
in m; any other file (instrument formats: X3P, Gwyddion, Dektak, Keyence, Zygo, Sensofar,
MountainsMap, SurfaceTopography's netCDF, ...) through SurfaceTopography (the optional extra
``g2tom[topography]``), which reads the pixel size and the height unit from the file; every
result is in SI units whatever the file's unit.

The moments m0, m2, m4 come from the power spectrum below a stated short-wavelength cutoff
(:func:`g2tom.physics.surface_spectrum.psd_moments`), the summit parameters from them
(:func:`g2tom.physics.surface_spectrum.summit_parameters`).

A region of undefined pixels that touches the map's border and holds more than
:data:`OUTSIDE_FILL_SHARE` of it (an instrument's frame, a round or irregular field of view) lies
outside the measured area (:func:`measured_area`); every other undefined (NaN) pixel, up to
:data:`MAX_MISSING_SHARE` of the measured area, is filled by the fill of least curvature
(:func:`g2tom.physics.height_fill.fill_gaps`). A map whose measured area is the whole map takes
the spectral path above, unchanged. Any other is masked, not cropped: its rms height is that of
every pixel of the measured area (a least-squares plane fitted over it removed), and m0, m2, m4
come from the masked spectrum of the area, windowed by a taper that follows its edge and
corrected for the window's own spectrum (:func:`g2tom.physics.masked_moments.masked_psd_moments`),
so they keep the cutoff; every measured pixel is used (the window is > 0 on all of them). A
rectangle cropped from a round or irregular area would drop most of it; an area too narrow for
the cutoff is refused instead.
The report says how many pixels were measured and used, how many were filled, and how the rms
height, m2 and m4 change if the filled pixels are masked instead
(:func:`g2tom.physics.height_fill.masked_moments`, finite differences on both maps).
On a synthetic surface with 5 % of its pixels missing (tests/test_height_fill.py's, three seeds),
masked and filled agree within 0.5 % (rms height, m2) and 1.1 % (m4) by that estimator, and the
filled map's spectral moments are within 0.2 % of the complete map's. The same surface measured
through a disc or an L-shaped area (69 %, 75 % of the map) gives rms height, m2 and m4 within
0.5 %, 0.9 % and 1.7 % of the complete map's.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr

from g2tom.config import ConfigError
from g2tom.errors import install_hint
from g2tom.physics.height_fill import fill_gaps, masked_moments
from g2tom.physics.masked_moments import masked_psd_moments
from g2tom.physics.roughness import validated_heights
from g2tom.physics.surface_spectrum import BETA_RULES, SpectralMoments, psd_moments, summit_parameters

__all__ = ["read_heightmap", "read_measured", "Measured", "measure", "MeasuredArea", "measured_area", "area_moments",
           "PLAUSIBLE_SIGMA", "CUTOFF_PIXELS", "INSTALL", "MAX_MISSING_SHARE", "MAP_EXTENT", "OUTSIDE_FILL_SHARE"]

#: Height standard deviations (m) outside this range are almost surely in the wrong unit.
PLAUSIBLE_SIGMA = (1e-10, 1e-3)
#: Physical side lengths (m) a measured map may span: from a nanometre to a metre.
MAP_EXTENT = (1e-9, 1.0)
#: Default short-wavelength cutoff, in pixels of the coarser axis.
CUTOFF_PIXELS = 4.0
#: Largest share of the measured area's pixels that are undefined and filled: beyond it the fill,
#: not the measurement, would set the moments (a filled hole holds no roughness shorter than its own size; see height_fill).
MAX_MISSING_SHARE = 0.25
#: Largest share of a map's pixels that one region of undefined pixels touching its border may hold
#: and still be filled (an edge dropout); a larger one lies outside the measured area, masked instead.
OUTSIDE_FILL_SHARE = 0.01
#: How to install the instrument-format reader.
INSTALL = install_hint("topography", "SurfaceTopography")
#: Height units of instrument files, in m.
_UNITS = {"m": 1.0, "mm": 1e-3, "um": 1e-6, "µm": 1e-6, "μm": 1e-6, "nm": 1e-9, "pm": 1e-12, "Å": 1e-10, "A": 1e-10}
_OWN_SUFFIXES = (".npy", ".nc", ".nc4", ".cdf")


@dataclass(frozen=True)
class Measured:
    """A height map in m, its pixel pitch (dy, dx) in m (None: not in the file), and its origin."""

    heights: np.ndarray
    pixel_size: tuple[float, float] | None
    periodic: bool
    unit: str
    reader: str


def _netcdf_heights(path: Path) -> np.ndarray:
    with xr.open_dataset(path, engine="netcdf4") as ds:
        for name in ("height", "z"):
            if name in ds:
                return ds[name].values
        two_d = [name for name, var in ds.data_vars.items() if var.ndim == 2]
        if len(two_d) != 1:
            raise ConfigError(
                f"HEIGHTMAP {str(path)!r}: expected a variable 'height' or 'z' or exactly one 2-D variable, "
                f"found {list(ds.data_vars)}"
            )
        return ds[two_d[0]].values


def _is_surface_topography_netcdf(path: Path) -> bool:
    """SurfaceTopography's netCDF layout: a 2-D ``heights`` with its ``unit`` (not in m, maybe)."""
    try:
        with xr.open_dataset(path, engine="netcdf4") as ds:
            return "heights" in ds and ds["heights"].ndim == 2 and "unit" in ds["heights"].attrs
    except (OSError, ValueError):
        return False


def read_heightmap(path: str | Path) -> np.ndarray:
    """Load a height map (m) from .npy, netCDF or whitespace-separated text.

    Raises
    ------
    ConfigError
        If the file is missing or cannot be parsed.
    """
    path = Path(path)
    if path.is_dir():
        raise ConfigError(f"HEIGHTMAP {str(path)!r} is a directory: give a .npy, netCDF, text or instrument file")
    if not path.is_file():
        raise ConfigError(f"HEIGHTMAP {str(path)!r} does not exist")
    if path.stat().st_size == 0:
        raise ConfigError(f"HEIGHTMAP {str(path)!r} is empty (0 bytes)")
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error")  # loadtxt's "empty input file" and the like
            if path.suffix == ".npy":
                return np.load(path, allow_pickle=False)
            if path.suffix in (".nc", ".nc4", ".cdf"):
                return _netcdf_heights(path)
            return np.loadtxt(path, ndmin=2)
    except ConfigError:
        raise
    except (OSError, ValueError, EOFError, UnicodeDecodeError, UserWarning) as exc:
        reason = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise ConfigError(f"HEIGHTMAP {str(path)!r} is unreadable ({reason})") from None


def _surface_topography(path: Path, why: str) -> Measured:
    """Read an instrument file with SurfaceTopography; heights and pixel size converted to m."""
    try:
        import SurfaceTopography as st
        from SurfaceTopography.Exceptions import ReadFileError
    except ImportError:
        raise ConfigError(f"HEIGHTMAP {str(path)!r} is {why}; reading instrument formats needs "
                          f"SurfaceTopography: {INSTALL}") from None
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            topography = st.read_topography(str(path))
            heights = np.ma.filled(np.ma.asarray(topography.heights(), dtype=float), np.nan)  # undefined: NaN
    except (ReadFileError, OSError, ValueError, KeyError, IndexError, TypeError) as exc:
        reason = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        raise ConfigError(f"HEIGHTMAP {str(path)!r} is unreadable: {why}, and SurfaceTopography knows no "
                          f"format for it ({reason})") from None
    if topography.dim != 2:
        raise ConfigError(f"HEIGHTMAP {str(path)!r} is a {topography.dim}-D line scan: must be a 2-D map")
    unit = str(topography.unit) if topography.unit is not None else ""
    if unit not in _UNITS:
        raise ConfigError(f"HEIGHTMAP {str(path)!r}: height unit {unit or 'none'!r} is not one of "
                          f"{', '.join(_UNITS)}")
    scale = _UNITS[unit]
    sizes = topography.physical_sizes
    pixel = None
    if sizes is not None and all(s is not None and s > 0 for s in sizes):
        nx, ny = topography.nb_grid_pts  # SurfaceTopography's heights are (x, y)
        pixel = (sizes[1] * scale / ny, sizes[0] * scale / nx)
    return Measured(heights.T * scale, pixel, bool(topography.is_periodic), unit,
                    f"SurfaceTopography {st.__version__}")


def read_measured(path: str | Path) -> Measured:
    """A height map in m from .npy, the project's netCDF, plain text, or an instrument file.

    Raises
    ------
    ConfigError
        If the file is missing, unreadable by every reader, or SurfaceTopography is needed but
        not installed (naming the install command).
    """
    path = Path(path)
    if path.suffix in (".nc", ".nc4", ".cdf") and path.is_file() and _is_surface_topography_netcdf(path):
        return _surface_topography(path, "SurfaceTopography's netCDF")
    try:
        heights = read_heightmap(path)
    except ConfigError as exc:
        if path.suffix in _OWN_SUFFIXES or not path.is_file() or path.stat().st_size == 0:
            raise
        return _surface_topography(path, f"not a plain text height map ({str(exc).rsplit('(', 1)[-1].rstrip(')')})")
    return Measured(heights, None, False, "m", "g2tom")


def _check_extent(shape: tuple[int, ...], pixel: tuple[float, float], source: str) -> None:
    """Refuse a pixel size that makes the map span less than a nanometre or more than a metre.

    Parameters
    ----------
    shape
        The map's pixels (rows, columns).
    pixel
        Pixel pitch (dy, dx), m.
    source
        Where the pixel size came from (``--pixel-size`` or the file), for the message.

    Raises
    ------
    ConfigError
        Naming the pixel size, the span it gives and the allowed range of square pixels.
    """
    spans = [n * d for n, d in zip(shape, pixel)]
    low, high = MAP_EXTENT
    if low <= min(spans) and max(spans) <= high:
        return
    value = pixel[0] if pixel[0] == pixel[1] else pixel
    raise ConfigError(f"{source} = {value!r} is out of range: the {shape[0]} x {shape[1]} map would span "
                      f"{spans[0]:.3g} x {spans[1]:.3g} m; must be in [{low / min(shape):.3g}, {high / max(shape):.3g}] m "
                      f"(a map spans {low:g} m to {high:g} m)")


def area_moments(heights: np.ndarray, inside: np.ndarray | None, pixel: tuple[float, float], cutoff: float,
                 periodic: bool = False) -> SpectralMoments:
    """The spectral moments of a map's measured area: the whole map's spectrum where every pixel is
    measured (``inside`` None or all True), else the masked, window-corrected spectrum.

    Parameters
    ----------
    heights
        Height map, m (finite on the measured area).
    inside
        The measured area, bool, or None: all of it.
    pixel
        Pixel pitch (dy, dx), m.
    cutoff
        Shortest wavelength counted, m.
    periodic
        The whole map is one period (ignored for a masked area).
    """
    if inside is None or bool(np.all(inside)):
        return psd_moments(heights, pixel, cutoff, periodic)
    return masked_psd_moments(heights, inside, pixel, cutoff)


def measure(path: str | Path, pixel_size: float | None = None, cutoff: float | None = None,
            periodic: bool | None = None, beta_rule: str = "paper") -> dict[str, Any]:
    """Everything ``g2tom roughness --json`` prints: moments, summit parameters, what was done (SI).

    The measured area (:func:`measured_area`) is ``measured_pixels`` defined pixels of the map
    as read; ``used_pixels`` of them (``used_share``) enter the statistics, all of them. Its
    undefined pixels are filled (``filled_pixels``, ``filled_share`` of the measured area); with
    any, ``masked_rms_height`` (m) and ``masked_rms_change``, ``masked_m2_change``,
    ``masked_m4_change`` (relative, masked over filled map, by finite differences) say how much
    masking them instead would change; all four are None for a complete map. ``estimator`` names
    how the moments were taken: the spectrum of the whole map, or the masked, window-corrected
    spectrum of a measured area that is not the whole map.

    Parameters
    ----------
    path
        The height map.
    pixel_size
        Pixel pitch, m (required for .npy, netCDF and text maps; overrides an instrument file's).
    cutoff
        Shortest wavelength counted, m (default :data:`CUTOFF_PIXELS` pixels of the coarser axis).
    periodic
        Treat the map as periodic (default: what the file says; never for .npy, netCDF and text;
        never when the measured area is not the whole map).
    beta_rule
        ``paper`` (0.737/sqrt(m4)) or ``nayak`` (0.375 sqrt(pi/m4)).

    Raises
    ------
    ConfigError
        Naming the file or option at fault.
    """
    if pixel_size is not None and not (math.isfinite(pixel_size) and pixel_size > 0):
        raise ConfigError(f"--pixel-size = {pixel_size!r} is out of range: must be > 0 (m)")
    measured = read_measured(path)
    pixel = (pixel_size, pixel_size) if pixel_size is not None else measured.pixel_size
    if pixel is None:
        raise ConfigError(f"HEIGHTMAP {str(path)!r} carries no pixel size: give --pixel-size (m)")
    periodic = measured.periodic if periodic is None else periodic
    raw = np.asarray(measured.heights)
    area = None
    if raw.dtype.kind == "f" and raw.ndim == 2 and np.isnan(raw).any():
        try:
            area = measured_area(raw)
        except ConfigError as exc:
            raise ConfigError(f"HEIGHTMAP {str(path)!r}: {exc}") from None
    try:
        whole = area is None or bool(area.inside.all())
        periodic = periodic and whole  # a map cut to its measured area is no longer periodic
        z = validated_heights(raw if area is None else area.heights) if whole else area.heights
        if not whole and min(z.shape) < 3:
            raise ValueError(f"height map has shape {z.shape}: must be at least 3 x 3 pixels")
        _check_extent(z.shape, pixel, "--pixel-size" if pixel_size is not None else
                      f"the pixel size of HEIGHTMAP {str(path)!r}")
        cutoff = CUTOFF_PIXELS * max(pixel) if cutoff is None else cutoff
        if not (math.isfinite(cutoff) and cutoff > 0):
            raise ConfigError(f"--cutoff = {cutoff!r} is out of range: must be > 0 (m)")
        if not whole and not np.all(np.isfinite(z[area.inside])):
            raise ValueError(f"height map holds {int(np.sum(~np.isfinite(z[area.inside])))} infinite values")
        moments = area_moments(z, None if whole else area.inside, pixel, cutoff, periodic)
        summits = summit_parameters(moments.m0, moments.m2, moments.m4, beta_rule)
        gaps = _gaps(z, raw if area is not None and area.filled else None, pixel, periodic,
                     None if area is None else area.inside)
    except ValueError as exc:
        raise ConfigError(f"HEIGHTMAP {str(path)!r}: {exc}") from None
    size = int(np.size(raw))
    inside = size if area is None else int(area.inside.sum())
    filled = 0 if area is None else area.filled
    measured_pixels = inside - filled
    used = measured_pixels  # the masked spectrum's window is > 0 on every pixel of the measured area
    return {
        "file": str(path), "reader": measured.reader, "file_height_unit": measured.unit,
        "shape": list(z.shape), "pixel_size": list(pixel),
        "detrending": moments.detrending, "window": moments.window, "cutoff_wavelength": moments.cutoff_wavelength,
        "estimator": "spectrum of the whole map" if whole else "masked spectrum of the measured area",
        "rms_height": moments.rms_height, "m0": moments.m0, "m2": moments.m2, "m4": moments.m4,
        "bandwidth_alpha": summits.bandwidth, "sigma": summits.sigma,
        "summit_mean_height": summits.summit_mean_height, "eta": summits.eta, "beta": summits.beta,
        "beta_rule": f"{summits.beta_rule}: {BETA_RULES[summits.beta_rule]}",
        "map_pixels": size, "measured_pixels": measured_pixels, "used_pixels": used,
        "used_share": used / measured_pixels,
        **gaps,
    }


@dataclass(frozen=True)
class MeasuredArea:
    """The measured area of a height map, its holes filled.

    Attributes
    ----------
    heights
        Heights, m, the shape of the map read: undefined pixels inside the measured area filled by
        the fill of least curvature (:func:`g2tom.physics.height_fill.fill_gaps`), pixels outside
        the measured area NaN.
    inside
        bool, same shape: True where measured or filled.
    filled
        How many undefined pixels were filled.
    """

    heights: np.ndarray
    inside: np.ndarray
    filled: int


def measured_area(heights: np.ndarray) -> MeasuredArea:
    """The measured area of a height map (NaN: undefined), and the map with its holes filled.

    A region of undefined pixels (4-neighbours) that touches the map's border and holds more than
    :data:`OUTSIDE_FILL_SHARE` of the map lies outside the measured area (an instrument's frame, a
    round or irregular field of view); every other undefined pixel (a hole, or a small dropout on
    the border) is inside it and is filled, if they are at most :data:`MAX_MISSING_SHARE` of the
    measured area.

    Parameters
    ----------
    heights
        Height map, 2-D, m; NaN marks an undefined pixel.

    Returns
    -------
    MeasuredArea
        The filled heights (NaN outside), the measured area and the number of filled pixels.

    Raises
    ------
    ConfigError
        If the map is not a 2-D array of real numbers, holds no defined pixel, or more than
        :data:`MAX_MISSING_SHARE` of its measured area is undefined.
    """
    from scipy import ndimage

    try:
        z = np.array(heights, dtype=float)
    except (TypeError, ValueError):
        raise ConfigError(f"height map holds {np.asarray(heights).dtype} values: heights must be real numbers (m)"
                          ) from None
    if z.ndim != 2:
        raise ConfigError(f"height map has shape {z.shape}: must be a 2-D array")
    undefined = np.isnan(z)
    if undefined.all():
        raise ConfigError(f"height map holds no defined pixel: all {z.size} pixels are undefined (NaN)")
    if not undefined.any():
        return MeasuredArea(z, np.ones(z.shape, dtype=bool), 0)
    labels, _ = ndimage.label(undefined)
    edge = np.unique(np.concatenate([labels[0], labels[-1], labels[:, 0], labels[:, -1]]))
    edge = edge[edge > 0]
    sizes = ndimage.sum_labels(np.ones(z.shape), labels, edge) if edge.size else np.zeros(0)
    large = edge[sizes > OUTSIDE_FILL_SHARE * z.size]
    inside = ~np.isin(labels, large) if large.size else np.ones(z.shape, dtype=bool)
    holes = int((undefined & inside).sum())
    share = holes / int(inside.sum())
    if share > MAX_MISSING_SHARE:
        raise ConfigError(f"{share:.1%} of the pixels of the measured area are undefined (NaN), more than the "
                          f"{MAX_MISSING_SHARE:.0%} that are filled")
    if holes == 0:
        return MeasuredArea(z, inside, 0)
    filled, count = fill_gaps(z, inside=None if inside.all() else inside)
    return MeasuredArea(filled, inside, count)


def _gaps(z: np.ndarray, holed: np.ndarray | None, pixel: tuple[float, float], periodic: bool,
          inside: np.ndarray | None) -> dict[str, Any]:
    """Filled pixels and their share of the measured area; with any, the masked map's rms height (m)
    and the relative change of rms height, m2 and m4 from the filled to the masked map (same finite
    differences over the measured area)."""
    if holed is None:
        return {"filled_pixels": 0, "filled_share": 0.0, "masked_rms_height": None,
                "masked_rms_change": None, "masked_m2_change": None, "masked_m4_change": None}
    area = holed.size if inside is None else int(inside.sum())
    count = int(np.isnan(holed).sum()) - (holed.size - area)
    full = masked_moments(z, pixel, periodic)
    masked = masked_moments(holed, pixel, periodic)
    return {"filled_pixels": count, "filled_share": count / area, "masked_rms_height": masked[0],
            "masked_rms_change": masked[0] / full[0] - 1, "masked_m2_change": masked[1] / full[1] - 1,
            "masked_m4_change": masked[2] / full[2] - 1}
