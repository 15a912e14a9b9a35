"""The surrogate stage's tables for the predictor's band and its curve model, over (lambda, xi[, step]).

From fits.nc: the realization spread and open-circuit share at each fitted step
(:func:`band_tables`), and each cell's curve model with its errors (:func:`curve_tables`).
"""

from __future__ import annotations

import numpy as np
import xarray as xr
from scipy.special import ndtri

from g2tom.config import Scenario
from g2tom.fitting import surrogate as sg
from g2tom.fitting.curve_model import evaluate_curve, interpolation_error
from g2tom.stages.schema import array, attrs

__all__ = ["band_tables", "curve_tables"]


def band_tables(fits: xr.Dataset) -> dict[str, xr.DataArray]:
    """Band ratios and open probability on the fitted steps, dims (lambda, xi, step)."""
    steps = fits["fitted"].values.astype(bool)
    center = fits[f"{fits.attrs['reduction']}_normalized"]
    quant = fits["resistance_quantile_normalized"]
    with np.errstate(divide="ignore", invalid="ignore"):
        lower = quant.sel(quantile=0.16) / center
        upper = center / quant.sel(quantile=0.84)
    out = {}
    for name, value in {"band_ratio_lower": lower, "band_ratio_upper": upper, "open_probability": fits["open_probability"]}.items():
        value = value.isel(delta=steps).transpose("lambda", "xi", "delta")
        out[name] = xr.DataArray(value.values, dims=("lambda", "xi", "step"))
    for name in ("band_ratio_lower", "band_ratio_upper", "open_probability"):
        out[name].attrs = attrs("surrogate", name)
    return out


def curve_tables(scenario: Scenario, fits: xr.Dataset) -> dict[str, xr.DataArray]:
    """The curve model of every cell for the predictor (its default): coefficients (lambda, xi,
    power), the one-sigma error of ln R' from each fitted step's interval (lambda, xi, step) and
    the grid's leave-one-out interpolation error of ln R' (lambda, xi)."""
    steps = fits["fitted"].values.astype(bool)
    coef = fits["curve_coefficients"].transpose("lambda", "xi", "power").values
    ln_r = evaluate_curve(coef, fits["force_normalized"].values[steps])
    ci = fits[f"{fits.attrs['reduction']}_normalized_ci"].isel(delta=steps).transpose("lambda", "xi", "delta", "bound")
    z = ndtri(0.5 + scenario.fits.confidence / 2.0)
    with np.errstate(divide="ignore", invalid="ignore"):
        sigma = (np.log(ci.sel(bound="upper").values) - np.log(ci.sel(bound="lower").values)) / (2.0 * z)
    error = interpolation_error(ln_r, sg.to_w(fits["lambda"].values), sg.to_z(fits["xi"].values))
    return {
        "curve_coefficients": array("surrogate", "curve_coefficients", coef),
        "curve_fit_error": array("surrogate", "curve_fit_error", sigma),
        "curve_interpolation_error": array(
            "surrogate", "curve_interpolation_error", error,
            method="largest over the fitted steps; RMS of the two axes; edge cells take the nearest interior value"),
    }
