"""surface.nc: every position's answers, their summary over positions and fields, and provenance.

The summary has one meaning per word: *typical* is the geometric mean over the contacts
(positions, and oxide fields), the *band* (``lower``, ``upper``) the :data:`BAND` quantiles over
the same contacts (where a new contact of this surface is likely to fall), and the *standard
error* that of ln of the geometric mean over the independent positions (how well the typical
value is known).
"""

from __future__ import annotations

import warnings

import numpy as np
import xarray as xr

from g2tom import __version__
from g2tom.physics.indenter import smooth_contact_radius
from g2tom.surface.maps import SurfaceMap
from g2tom.surface.solve import PositionResult
from g2tom.surface.study import SurfaceStudy
from g2tom.surface.windows import Positions
from g2tom.variables import entry

__all__ = ["BAND", "surface_dataset", "surface_variable"]

#: The band's quantiles over the contacts, %.
BAND = (10.0, 90.0)


def surface_variable(name: str, data: np.ndarray) -> xr.Variable:
    """surface.nc's variable ``name`` holding ``data``: dims, units and long name from the registry."""
    declared = entry(f"surface.{name}")
    return xr.Variable(declared.dims, np.asarray(data), declared.attrs(lower=BAND[0], upper=BAND[1]))


def _geometric(values: np.ndarray, axes: tuple[int, ...]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Geometric mean and the band's quantiles of the finite values over ``axes`` (NaN where none)."""
    logs = np.log(np.where(np.isfinite(values), values, np.nan))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # all-NaN slices: NaN, said by 'solved'
        mean = np.nanmean(logs, axis=axes)
        low, high = np.nanpercentile(logs, BAND, axis=axes)
    return np.exp(mean), np.exp(low), np.exp(high)


def _standard_error(values: np.ndarray, independent: np.ndarray) -> np.ndarray:
    """Standard error of ln of the geometric mean of ``values`` (position, force) over the independent positions."""
    logs = np.log(np.where(np.isfinite(values[independent]), values[independent], np.nan))
    count = np.sum(np.isfinite(logs), axis=0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        sd = np.nanstd(logs, axis=0, ddof=1) if logs.shape[0] > 1 else np.full(logs.shape[1], np.nan)
    return np.where(count > 1, sd / np.sqrt(np.maximum(count, 1)), np.nan)


def surface_dataset(study: SurfaceStudy, surface: SurfaceMap, n: int, positions: Positions,
                    results: list[PositionResult], first_window: np.ndarray, first_masks: np.ndarray) -> xr.Dataset:
    """The Dataset of a finished study (``results`` in ``positions``' order; the first position's
    window, m, and oxide masks draw its maps)."""
    pixel = surface.pixel
    centres = (positions.corners + (n - 1) / 2.0) * pixel  # (row, column) -> (y, x), m
    clean = np.stack([r.resistance_clean for r in results])
    oxidized = np.stack([r.resistance for r in results], axis=2)  # (xi, length, position, field, force)
    state = results[0].contact.astype(np.uint8)
    if first_masks.size:
        state = np.where(results[0].contact & first_masks[0, 0, 0], 2, state).astype(np.uint8)
    coords = {
        "force": surface_variable("force", np.asarray(study.forces)),
        "xi": surface_variable("xi", np.asarray(study.xi, float)),
        "correlation_length": surface_variable("correlation_length", np.asarray(study.correlation_lengths, float)),
        "position": surface_variable("position", np.arange(len(results))),
        "field": surface_variable("field", np.arange(study.fields if study.oxidized else 0)),
        "y": surface_variable("y", (np.arange(n) - (n - 1) / 2.0) * pixel),
        "x": surface_variable("x", (np.arange(n) - (n - 1) / 2.0) * pixel),
    }
    typical, lower, upper = _geometric(clean, (0,))
    data = {
        "position_x": surface_variable("position_x", centres[:, 1]),
        "position_y": surface_variable("position_y", centres[:, 0]),
        "independent": surface_variable("independent", positions.independent.astype(np.int8)),
        "contact_radius_smooth": surface_variable("contact_radius_smooth", smooth_contact_radius(
            np.asarray(study.forces), study.e_star, study.shape, radius=study.radius, cone_angle=study.cone_angle,
            punch_radius=study.punch_radius)),
        "solved": surface_variable("solved", np.stack([[not why for why in r.failed] for r in results]).astype(np.int8)),
        "delta": surface_variable("delta", np.stack([r.delta for r in results])),
        "contact_area": surface_variable("contact_area", np.stack([r.area for r in results])),
        "resistance_clean": surface_variable("resistance_clean", clean),
        "resistance_clean_typical": surface_variable("resistance_clean_typical", typical),
        "resistance_clean_lower": surface_variable("resistance_clean_lower", lower),
        "resistance_clean_upper": surface_variable("resistance_clean_upper", upper),
        "resistance_clean_standard_error": surface_variable("resistance_clean_standard_error",
                                                _standard_error(clean, positions.independent)),
        "height": surface_variable("height", first_window),
        "contact_state": surface_variable("contact_state", state),
    }
    if study.hardness is not None:
        data["plastic_share"] = surface_variable("plastic_share", np.stack([r.plastic_share for r in results]))
    if study.oxidized:
        typical, lower, upper = _geometric(oxidized, (2, 3))
        open_share = np.mean(np.isinf(oxidized), axis=(2, 3))
        data.update({
            "resistance": surface_variable("resistance", oxidized),
            "oxide_fraction": surface_variable("oxide_fraction", np.stack([r.oxide_fraction for r in results], axis=2)),
            "resistance_typical": surface_variable("resistance_typical", typical),
            "resistance_lower": surface_variable("resistance_lower", lower),
            "resistance_upper": surface_variable("resistance_upper", upper),
            "open_fraction": surface_variable("open_fraction", open_share),
        })
    attrs = {
        "title": "g2tom surface: the full-field resistance of a measured topography",
        "g2tom_version": __version__,
        "map_files": list(surface.files), "map_sha256": list(surface.digests),
        "map_pixel_size": surface.pixel, "map_shape": list(surface.inside.shape),
        "map_measured_share": surface.measured_share, "map_filled_pixels": surface.filled,
        "map_rms_height": surface.rms_height, "map_resampled": surface.resampled or "no",
        "window_pixels": n, "window_side": n * pixel, "independent_positions": positions.capacity,
        "band_quantiles": list(BAND),
        **{f"study_{k}": v for k, v in study.parameters().items()},
    }
    return xr.Dataset(data, coords=coords, attrs=attrs)
