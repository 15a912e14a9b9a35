"""Oxide fields on a window's pixels, their correlation length in m (the unit a measured map has).

The field is g2tom's band-limited Gaussian field (:mod:`g2tom.physics.oxide_band`: the band
``k1 <= |k| <= ks_ratio k1`` with ``k1 = pi / l_O``, spectrum ``k^-2(1+H)``, a period of at least
the window with ``k1`` resolved by the scenario's ``oxide.spectral_resolution`` lattice steps),
evaluated exactly at the window's pixel centres; a pixel is oxidized where the field is at or above
the threshold of ``xi`` (the theoretical quantile, or the field's own over the window's pixels).
Each (position, field, correlation length) has its own stream,
``SeedSequence(seed, spawn_key=(OXIDE_KEY, position, field, l_O in pm))``: the same position
keeps its fields whatever other positions or cases are computed.
"""

from __future__ import annotations

import numpy as np

from g2tom.config import ConfigError
from g2tom.physics import oxide_band, oxide_field
from g2tom.physics.grid import cell_centres
from g2tom.surface.study import SurfaceStudy, stream

__all__ = ["OXIDE_KEY", "LONGEST", "check_lengths", "oxide_masks"]

#: The spawn key of the oxide fields (the positions use another).
OXIDE_KEY = 1
#: The longest correlation length, in sides of the map.
LONGEST = 1000.0


def check_lengths(study: SurfaceStudy, pixel: float, side: float) -> None:
    """Refuse a correlation length below one pixel (m: its islands would fall between the pixels) or
    above :data:`LONGEST` times the map's longer ``side`` (m: every window then lies inside one island
    or one gap).

    Raises
    ------
    ConfigError
        Naming the length, and the allowed range for this map.
    """
    if not study.correlation_lengths:
        return
    shortest, longest = min(study.correlation_lengths), max(study.correlation_lengths)
    bounds = f"[{pixel:.4g}, {LONGEST * side:.4g}] (m: one pixel of the map to {LONGEST:g} times its side"
    if shortest < pixel:
        raise ConfigError(f"--correlation-length = {shortest:g} is out of range: must be in {bounds}; a finer map "
                          "resolves shorter ones)")
    if longest > LONGEST * side:
        raise ConfigError(f"--correlation-length = {longest:g} is out of range: must be in {bounds})")


def oxide_masks(study: SurfaceStudy, n: int, pixel: float, position: int) -> np.ndarray:
    """Oxidized pixels of every case of a position's window: bool (xi, correlation length, field, n, n).

    Parameters
    ----------
    study
        Its ``xi``, ``correlation_lengths`` (m), ``fields`` and oxide spectrum.
    n, pixel
        The window's side (pixels) and pixel side (m).
    position
        The position's index (its streams).
    """
    cells = n + 1 - n % 2  # the band's lattice wants an odd count; the period only grows with it
    centres = cell_centres(n, pixel)
    out = np.zeros((len(study.xi), len(study.correlation_lengths), study.fields, n, n), bool)
    xi = np.asarray(study.xi, float)
    for b, length in enumerate(study.correlation_lengths):
        lam = length / pixel
        period = oxide_band.spectral_period(cells, lam, study.resolution)
        modes = oxide_band.band(cells, pixel, lam, study.ks_ratio, study.hurst, period)
        coeffs = np.stack([oxide_band.coefficients(modes, stream(study.seed, OXIDE_KEY, position, k, round(length * 1e12)),
                                                     study.amplitudes)
                           for k in range(study.fields)])
        psi = oxide_field.grid_values(modes, coeffs, centres, centres)  # (field, n, n)
        if study.threshold == "theoretical":
            threshold = oxide_field.theoretical_threshold(xi)[:, None]
        else:
            threshold = oxide_field.empirical_threshold(psi.reshape(study.fields, -1), xi)
        out[:, b] = psi[None] >= threshold[:, :, None, None]
    return out
