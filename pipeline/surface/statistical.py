"""The statistical answer beside the full field: the map's Greenwood–Williamson summits fed to g2tom's
predictor, and its ratio to the full field's typical resistance with oxide.

The map's summit sigma, eta and beta (:func:`g2tom.surface.maps.summits`) replace the scenario's
roughness; the oxide case's correlation length l_O becomes lambda = l_O sqrt(eta); the predictor
answers as ``g2tom predict`` would (the run's own surrogate where it was fitted on this surface,
else the atlas's). Where it cannot (a scene outside the atlas, caps capped at a hardness the atlas
was not fitted with, no oxide case, summits not measurable), the dataset says why in
``statistical_answer`` and carries no statistical variables. The ratio shows how well the
Greenwood–Williamson description fits this surface: the full field is the answer.
"""

from __future__ import annotations

import dataclasses
import math
import warnings
from pathlib import Path

import xarray as xr

from g2tom.config import ConfigError, Scenario
from g2tom.physics.surface_spectrum import SummitParameters
from g2tom.predict import predict_resistance
from g2tom.surface.dataset import surface_variable

__all__ = ["attach_statistical"]


def attach_statistical(ds: xr.Dataset, scenario: Scenario, summits: SummitParameters | None,
                       data_dir: str | Path = "data") -> xr.Dataset:
    """``ds`` (surface.nc's contents) with ``resistance_statistical`` and ``statistical_ratio`` (xi,
    correlation length, force) where the predictor answers, and ``statistical_answer`` (what
    answered, or why nothing did)."""
    ds = ds.copy()
    if summits is None:
        ds.attrs["statistical_answer"] = "none: the map's summit parameters could not be measured"
        return ds
    if "resistance_typical" not in ds:
        ds.attrs["statistical_answer"] = "none: the predictor answers with oxide only (no --xi given)"
        return ds
    roughness = dataclasses.replace(scenario.roughness, sigma=summits.sigma, eta=summits.eta, beta=summits.beta)
    scene = dataclasses.replace(scenario, roughness=roughness)
    force = xr.DataArray(ds["force"].values, dims="force")
    xi = xr.DataArray(ds["xi"].values, dims="xi")
    lam = xr.DataArray(ds["correlation_length"].values * math.sqrt(summits.eta), dims="correlation_length")
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # its own error estimate is recorded with the answer
            answer = predict_resistance(scene, force, xi, lam, data_dir=data_dir)
    except ConfigError as exc:
        ds.attrs["statistical_answer"] = f"none: {exc}"
        return ds
    statistical = answer["resistance"].transpose("xi", "correlation_length", "force").values
    ds["resistance_statistical"] = surface_variable("resistance_statistical", statistical)
    ds["statistical_ratio"] = surface_variable("statistical_ratio", ds["resistance_typical"].values / statistical)
    ds.attrs["statistical_answer"] = str(answer.attrs.get("answered_by", "g2tom's predictor"))
    return ds
