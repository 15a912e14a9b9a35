"""The cube's computed arrays wrapped as a labelled dataset: coordinates, CF attributes, provenance."""

from __future__ import annotations

from typing import Any

import numpy as np
import xarray as xr

from pipeline.config import Scenario
from pipeline.stages.cube_chunks import CubeSettings
from pipeline.stages.cube_rounds import RULE_MARGIN

__all__ = ["dataset"]

_LONG_NAMES = {
    "greenwood": "Greenwood constriction resistance R = R_self + R_int",
    "point": "point-interaction constriction resistance R = rho* / sum f (exact solve of M f = 1)",
}


def _attrs(units: str, long_name: str, **extra: Any) -> dict[str, Any]:
    """CF-style attributes ``units`` and ``long_name`` plus any ``extra`` ones."""
    return {"units": units, "long_name": long_name, **extra}


def dataset(
    scenario: Scenario, contact: xr.Dataset, oxide: xr.Dataset, out: dict[str, Any],
    clean: dict[str, Any], settings: CubeSettings, measured: float,
    counts: np.ndarray, widths: tuple[np.ndarray, np.ndarray],
) -> xr.Dataset:
    """Wrap the computed arrays with coordinates and CF attributes."""
    dims = ("xi", "lambda", "delta", "realization")
    w_unit = "m" if scenario.cube.weights == "radius" else "m2"
    ox = scenario.oxide
    coords = {
        "xi": ("xi", oxide["xi"].values, _attrs("1", "nominal oxide fraction")),
        "lambda": ("lambda", oxide["lambda"].values,
                   _attrs("1", "normalized oxide correlation length l_O sqrt(eta)")),
        "delta": ("delta", contact["delta"].values, _attrs("m", "approach delta of the sphere tip")),
        "realization": ("realization", np.arange(out["resistance"].shape[-1]),
                        _attrs("1", "realization index of the random field")),
        "force": ("delta", contact["force"].values, _attrs("N", "normal force")),
        "force_normalized": ("delta", contact["force_normalized"].values,
                             _attrs("1", "normalized force F' = 2F / (E* sqrt(R* sigma^3))")),
    }
    is_open = np.isposinf(out["resistance"])
    discrete = scenario.contact.model == "discrete"
    clean_comment = ("the mean conductance (self-conductance) over the "
                     f"{clean['n_drawn']} discrete surfaces of contact.nc" if discrete else
                     "the mean conductance (self-conductance) over the first "
                     f"{clean['n_drawn']} realizations of the asperity heights"
                     if scenario.contact.spots == "asperities" else "exact, every spot conducting")
    padding = "NaN beyond n_realizations(xi, lambda)"
    grid = ("xi", "lambda")
    data_vars = {
        "resistance": (dims, out["resistance"], _attrs(
            "ohm", _LONG_NAMES[scenario.cube.model],
            comment=f"+inf: open circuit (no conducting spot); {padding}")),
        "resistance_self": (dims, out["resistance_self"],
                            _attrs("ohm", "self term rho* / (2 sum phi a)", comment=padding)),
        "resistance_interaction": (dims, out["resistance_interaction"], _attrs(
            "ohm", f"interaction term rho* sum phi phi w w / d / (pi (sum phi w)^2), w in {w_unit}",
            comment=padding)),
        "n_conducting": (dims, out["n_conducting"].astype(np.int32),
                         _attrs("1", "number of conducting spots", comment="-1 beyond n_realizations(xi, lambda)")),
        "n_open": (("xi", "lambda", "delta"), is_open.sum(axis=-1).astype(np.int32),
                   _attrs("1", "number of open-circuit realizations (R = +inf)")),
        "n_realizations": (grid, counts.astype(np.int32), _attrs(
            "1", "realizations used at this (xi, lambda): the leading entries of realization",
            ensemble=ox.ensemble)),
        "rule_alpha_half_width": (grid, widths[0], _attrs(
            "1", "fast-rule relative half-width of alpha at n_realizations",
            method="sinh(z std(t_r) / sqrt(n)), t_r = least-squares log-alpha weights . log R_r")),
        "rule_gamma_half_width": (grid, widths[1], _attrs(
            "1", "fast-rule absolute half-width of gamma at n_realizations",
            method="z std(t_r) / sqrt(n), t_r = least-squares slope weights . log R_r")),
        "resistance_clean": ("delta", clean["resistance"],
                             _attrs("ohm", "resistance of the oxide-free surface", comment=clean_comment)),
        "resistance_clean_self": ("delta", clean["self"],
                                  _attrs("ohm", "self term of the oxide-free surface", comment=clean_comment)),
        "resistance_clean_interaction": ("delta", clean["interaction"],
                                         _attrs("ohm", "interaction term of the oxide-free surface")),
        "conductance_clean": ("delta", 1.0 / clean["resistance"],
                              _attrs("S", f"conductance of the oxide-free surface ({scenario.cube.model} model)")),
        **{f"conductance_clean_{name}": ("delta", values, _attrs(
            "S", f"conductance of the oxide-free surface by the {name.replace('_', ' + ')} model",
            comment="beside contact.nc's barber_conductance (Barber's theorem); NaN where the model does not apply"))
           for name, values in clean["models"].items()},
        "clean_open_probability": ("delta", clean["open"], _attrs(
            "1", "probability that the oxide-free surface is an open circuit (no touching asperity)")),
        "crop_cells": ("delta", np.asarray(settings.crops, np.int32), _attrs(
            "1", "side of the centred square of cells kept at each approach")),
    }
    if "iterations" in out:
        data_vars["iterations"] = (dims, out["iterations"].astype(np.int32), _attrs(
            "1", "conjugate-gradient iterations of the point-model solve", comment="-1 beyond n_realizations(xi, lambda)"))
        data_vars["residual"] = (dims, out["residual"], _attrs(
            "1", "final relative residual of the point-model solve (Jacobi norm)", comment=padding))
        data_vars["error_estimate"] = (dims, out["error_estimate"], _attrs(
            "1", "estimated relative error of the point-model conductance (energy norm of the last step)",
            comment=padding))
    attrs = {
        "interaction_weights": scenario.cube.weights,
        "method": settings.method_used,
        "crop_tolerance": settings.tolerance,
        "crop_error_bound": float(np.nanmax(out["crop_bound"], initial=0.0)),
        "crop_error_measured": measured,
        "crop_error_measured_on": "all entries of the first realization, against the whole window",
        "n_uncropped": out["n_uncropped"],
        "n_open_total": int(is_open.sum()),
        "conducting_rule": "a spot conducts where spot_radius > 0 and psi < threshold (float32)",
        "fields": "regenerated in every task from SeedSequence(oxide.seed, spawn_key=(round(lambda * 1e6), realization))",
        "ensemble": ox.ensemble,
        "model": scenario.cube.model,
        "film": ox.film,
    }
    if discrete:
        attrs["conducting_rule"] = (
            "realization k meets discrete surface k mod contact.surfaces; a spot conducts with radius a where the "
            "field at its centre is below the threshold (spot_rule centre), or with a sqrt(f), f its clean share of "
            "the contact disc (spot_rule disc)")
        attrs["spot_rule"] = ox.spot_rule
    if ox.film == "resistive":
        attrs["film_resistance"] = ox.film_resistance
        attrs["conducting_rule"] = "every spot conducts; where psi >= threshold through the film"
    if "iterations" in out:
        attrs["solver_tolerance"] = scenario.cube.solver_tolerance
        attrs["solver_criterion"] = scenario.cube.solver_criterion
        measure = out["error_estimate"] if scenario.cube.solver_criterion == "error" else out["residual"]
        attrs["n_not_converged"] = int((measure > scenario.cube.solver_tolerance).sum())
    if ox.ensemble == "adaptive":
        attrs.update({
            "target_half_width": ox.target_half_width,
            "rule_target_half_width": RULE_MARGIN * ox.target_half_width,
            "min_realizations": ox.min_realizations,
            "max_realizations": ox.max_realizations,
            "stopping_rule": (
                f"per (xi, lambda), the smallest n >= min_realizations at which the fast-rule "
                f"alpha half-width is <= {RULE_MARGIN:g} x target_half_width, else max_realizations"
            ),
        })
    ds = xr.Dataset(data_vars, coords=coords, attrs=attrs)
    if ox.ensemble == "adaptive":  # the padding compresses to almost nothing
        for name in ("resistance", "resistance_self", "resistance_interaction", "n_conducting"):
            ds[name].encoding.update(zlib=True, complevel=1)
    return ds
