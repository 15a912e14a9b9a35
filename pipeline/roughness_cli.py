"""``g2tom roughness HEIGHTMAP --pixel-size S``: sigma, eta and beta from a measured surface.

Height maps are read from numpy ``.npy``, netCDF (``.nc``: the variable ``height``, ``z``
or the only 2-D variable) or whitespace-separated text (any other suffix). Heights and the
pixel size are in m.
"""

from __future__ import annotations

import argparse
import math
import warnings
from pathlib import Path

import numpy as np
import xarray as xr

from pipeline.config import ConfigError
from pipeline.physics.roughness import RoughnessParameters, roughness_parameters

__all__ = ["read_heightmap", "roughness_cli", "PLAUSIBLE_SIGMA"]

#: Height standard deviations (m) outside this range are almost surely in the wrong unit.
PLAUSIBLE_SIGMA = (1e-10, 1e-3)


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


def read_heightmap(path: str | Path) -> np.ndarray:
    """Load a height map (m) from .npy, netCDF or whitespace-separated text.

    Raises
    ------
    ConfigError
        If the file is missing or cannot be parsed.
    """
    path = Path(path)
    if path.is_dir():
        raise ConfigError(f"HEIGHTMAP {str(path)!r} is a directory: give a .npy, netCDF or text file")
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


def _report(result: RoughnessParameters) -> str:
    return "\n".join(
        [
            f"sigma = {result.sigma:.6g} m   (std of surface heights)",
            f"m2    = {result.m2:.6g}",
            f"m4    = {result.m4:.6g} m^-2",
            f"eta   = {result.eta:.6g} m^-2   (sqrt(3)/(18 pi) m4/m2)",
            f"beta  = {result.beta:.6g} m   (0.737/sqrt(m4))",
            "use: --set roughness.sigma={:.6g} --set roughness.eta={:.6g} --set roughness.beta={:.6g}".format(
                result.sigma, result.eta, result.beta
            ),
        ]
    )


def roughness_cli(args: argparse.Namespace) -> None:
    """Print sigma, m2, m4, eta and beta of ``args.heightmap`` at ``args.pixel_size``.

    Raises
    ------
    ConfigError
        On a bad pixel size, a missing or unreadable file, or an unusable map.
    """
    if not (math.isfinite(args.pixel_size) and args.pixel_size > 0):
        raise ConfigError(f"--pixel-size = {args.pixel_size!r} is out of range: must be > 0 (m)")
    heights = read_heightmap(args.heightmap)
    try:
        result = roughness_parameters(heights, args.pixel_size)
    except ValueError as exc:
        raise ConfigError(f"HEIGHTMAP {str(args.heightmap)!r}: {exc}") from None
    low, high = PLAUSIBLE_SIGMA
    if not low <= result.sigma <= high:
        warnings.warn(
            f"HEIGHTMAP {str(args.heightmap)!r}: sigma = {result.sigma:.3g} m is implausible for a "
            f"surface (expected {low:g}..{high:g} m): are the heights in m?", stacklevel=2)
    print(_report(result))
