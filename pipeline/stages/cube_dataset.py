"""The cube's computed arrays wrapped as a labelled dataset: coordinates, CF attributes, provenance."""

from __future__ import annotations

from typing import Any

import numpy as np
import xarray as xr

from g2tom.config import Scenario
from g2tom.models.cube_settings import CubeSettings
from g2tom.stages.cube_rounds import RULE_MARGIN
from g2tom.stages.schema import RESISTANCE_LONG_NAMES, variable

__all__ = ["dataset"]

def dataset(
    scenario: Scenario, contact: xr.Dataset, oxide: xr.Dataset, out: dict[str, Any],
    clean: dict[str, Any], settings: CubeSettings, measured: float,
    counts: np.ndarray, widths: tuple[np.ndarray, np.ndarray],
) -> xr.Dataset:
    """Wrap the computed arrays with coordinates and CF attributes."""
    ox = scenario.oxide

    slots = {"resistance": RESISTANCE_LONG_NAMES[scenario.cube.model], "model": scenario.cube.model,
             "weights_unit": "m" if scenario.cube.weights == "radius" else "m2"}

    def cube(name: str, data: Any, **extra: Any) -> tuple:
        return variable("cube", name, data, slots, **extra)

    coords = {
        "xi": cube("xi", oxide["xi"].values),
        "lambda": cube("lambda", oxide["lambda"].values),
        "delta": cube("delta", contact["delta"].values),
        "realization": cube("realization", np.arange(out["resistance"].shape[-1])),
        "force": cube("force", contact["force"].values),
        "force_normalized": cube("force_normalized", contact["force_normalized"].values),
    }
    is_open = np.isposinf(out["resistance"])
    clean_comment = settings.contact_model.clean_comment(scenario, clean["n_drawn"])
    rule = settings.contact_model.conducting_rule(scenario)
    counted = ("step_realizations(xi, lambda, delta)" if "step_realizations" in out
               else "n_realizations(xi, lambda)")
    padding = f"NaN beyond {counted}"
    data_vars = {
        "resistance": cube("resistance", out["resistance"], comment=f"+inf: open circuit (no conducting spot); {padding}"),
        "resistance_self": cube("resistance_self", out["resistance_self"], comment=padding),
        "resistance_interaction": cube("resistance_interaction", out["resistance_interaction"], comment=padding),
        "n_conducting": cube("n_conducting", out["n_conducting"].astype(np.int32), comment=f"-1 beyond {counted}"),
        "n_open": cube("n_open", is_open.sum(axis=-1).astype(np.int32)),
        "n_realizations": cube("n_realizations", counts.astype(np.int32), ensemble=ox.ensemble),
        "rule_alpha_half_width": cube(
            "rule_alpha_half_width", widths[0],
            method="sinh(z std(t_r) / sqrt(n)), t_r = least-squares log-alpha weights . log R_r"),
        "rule_gamma_half_width": cube(
            "rule_gamma_half_width", widths[1], method="z std(t_r) / sqrt(n), t_r = least-squares slope weights . log R_r"),
        "resistance_clean": cube("resistance_clean", clean["resistance"], comment=clean_comment),
        "resistance_clean_self": cube("resistance_clean_self", clean["self"], comment=clean_comment),
        "resistance_clean_interaction": cube("resistance_clean_interaction", clean["interaction"]),
        "conductance_clean": cube("conductance_clean", 1.0 / clean["resistance"]),
        **{f"conductance_clean_{name}": cube(
            f"conductance_clean_{name}", values,
            comment="beside contact.nc's barber_conductance (Barber's theorem); NaN where the model does not apply")
           for name, values in clean["models"].items()},
        "clean_open_probability": cube("clean_open_probability", clean["open"]),
        "crop_cells": cube("crop_cells", np.asarray(settings.crops, np.int32)),
    }
    if "clean_share" in out:
        for name in ("rule_alpha_half_width", "rule_gamma_half_width"):
            data_vars[name][2]["control_variate"] = ("t_r's residual after its least-squares regression on "
                                                     "u_r = the same weights . clean_share_r")
        data_vars["clean_share"] = cube("clean_share", out["clean_share"], comment=padding)
        data_vars["clean_share_expected"] = cube(
            "clean_share_expected", out["clean_share_expected"],
            method="Gil-Pelaez inversion of the random-phase field's characteristic function prod_k J0(w_k u) "
                   "at the float32 threshold (g2tom.physics.oxide_marginal)")
    if "step_realizations" in out:
        data_vars["step_realizations"] = cube("step_realizations", out["step_realizations"].astype(np.int32),
                                              comment="at least n_realizations, the lightest steps more")
    if "iterations" in out:
        data_vars["iterations"] = cube("iterations", out["iterations"].astype(np.int32),
                                       comment="-1 beyond n_realizations(xi, lambda)")
        data_vars["residual"] = cube("residual", out["residual"], comment=padding)
        data_vars["error_estimate"] = cube("error_estimate", out["error_estimate"], comment=padding)
    attrs = {
        "interaction_weights": scenario.cube.weights,
        "method": settings.method_used,
        "crop_tolerance": settings.tolerance,
        "crop_error_bound": float(np.nanmax(out["crop_bound"], initial=0.0)),
        "crop_error_measured": measured,
        "crop_error_measured_on": "all entries of the first realization, against the whole window",
        "n_uncropped": out["n_uncropped"],
        "n_open_total": int(is_open.sum()),
        "conducting_rule": rule.pop("conducting_rule"),
        "fields": "regenerated in every task from SeedSequence(oxide.seed, spawn_key=(round(lambda * 1e6), realization))",
        "ensemble": ox.ensemble,
        "model": scenario.cube.model,
        "film": ox.film,
    }
    attrs.update(rule)
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
        if "clean_share" in out:
            attrs["stopping_rule"] += (
                "; the half-width of the fits' control-variate estimate, linearized (the influence of each "
                "realization on every step's adjusted ratio, open circuits counted)")
    if "step_realizations" in out:
        attrs["step_half_width"] = ox.step_half_width
        attrs["stopping_rule"] += (
            f"; then per fitted step, the smallest n >= n_realizations at which the fast-rule half-width of the "
            f"geometric mean is <= {RULE_MARGIN:g} x step_half_width, else max_realizations, each step keeping at "
            "least the count of the steps above it")
    ds = xr.Dataset(data_vars, coords=coords, attrs=attrs)
    if ox.ensemble == "adaptive":  # the padding compresses to almost nothing
        for name in ("resistance", "resistance_self", "resistance_interaction", "n_conducting"):
            ds[name].encoding.update(zlib=True, complevel=1)
    return ds
