"""The load steps the fits use: F >= ``fits.min_force`` (N) or, with ``fits.fit_range =
"force_normalized"``, F' >= ``fits.min_force_normalized``; shared by the fits stage and the cube's
adaptive ensemble (whose stopping rule looks at the fitted steps only)."""

from __future__ import annotations

import xarray as xr

from g2tom.config import ConfigError, Scenario

__all__ = ["fitted_steps", "range_label"]


def fitted_steps(scenario: Scenario, force: xr.DataArray, force_normalized: xr.DataArray) -> xr.DataArray:
    """Boolean mask (delta) of the fitted load steps: F >= fits.min_force (N) or, with
    ``fits.fit_range = "force_normalized"``, F' >= fits.min_force_normalized.

    Raises
    ------
    ConfigError
        If fewer than two steps qualify.
    """
    key, threshold, values, unit = scenario.fits.fitted_loads(force, force_normalized)
    mask = values >= threshold
    if int(mask.sum()) < 2:
        raise ConfigError(
            f"fits.{key} = {threshold:g} is out of range: only "
            f"{int(mask.sum())} load step(s) reach it (forces {values.min().item():.3g}.."
            f"{values.max().item():.3g}{unit}); a fit needs >= 2"
        )
    return mask


def range_label(scenario: Scenario) -> str:
    """The fitted steps' rule in words."""
    f = scenario.fits
    return f"F >= {f.min_force:g} N" if f.fit_range == "force" else f"F' >= {f.min_force_normalized:g}"
