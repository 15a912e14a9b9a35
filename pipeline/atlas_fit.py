"""The atlas surrogate: alpha and gamma over (xi, lambda, mu, Pi) from ``atlas.nc``, checked on held-out scenes.

Fitted on the design scenes only (:mod:`pipeline.physics.atlas_surrogate`: ln alpha and gamma
as polynomials of total degree D in the mapped log coordinates, weighted by each cell's
interval, D by leave-one-scene-out cross-validation). The held-out scenes judge it: at every
fitted F' step of every held-out (scene, xi, lambda) cell, |ln R'_surrogate - ln R'_scene| with
R'_surrogate = alpha F'^-gamma and R'_scene the scene's fitted reduction, against
max(:data:`FLOOR`, the cell's relative half-width of alpha). Writes ``<atlas>/surrogate.json``
(coefficients, domain, cross-validation, the held-out verdict and its worst cell) and
``<atlas>/heldout.csv`` (one line per held-out cell and step).
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr
from scipy.stats import norm

from pipeline.physics.atlas_surrogate import AtlasModel, fit_atlas_model, select_degree
from pipeline.store import atomic_path, git_commit

__all__ = ["fit_atlas", "write_atlas_surrogate", "FLOOR", "FORMAT"]

FORMAT = "g2tom-atlas-surrogate"
#: Least relative error of ln R' a held-out cell is allowed (the issue's 5 %).
FLOOR = 0.05
#: Least one-sigma uncertainty of ln alpha and of gamma in the fit's weights.
SIGMA_FLOOR = {"alpha": 0.01, "gamma": 0.005}
TRANSFORM = {"alpha": "log", "gamma": "identity"}


def _points(atlas: xr.Dataset, scenes: np.ndarray) -> dict[str, np.ndarray]:
    """Flat (scene, xi, lambda) points of the given scenes, with alpha, gamma and their sigmas."""
    sub = atlas.isel(scene=scenes)
    shape = sub["alpha"].transpose("scene", "xi", "lambda").shape
    s, x, l = np.meshgrid(np.arange(shape[0]), sub["xi"].values, sub["lambda"].values, indexing="ij")
    z_c = norm.ppf(0.5 + float(atlas.attrs.get("fits.confidence", 0.95)) / 2.0)
    out = {"scene": scenes[s.ravel()], "xi": x.ravel(), "lambda": l.ravel(),
           "mu": sub["mu"].values[s.ravel()], "Pi": sub["Pi"].values[s.ravel()]}
    for name in ("alpha", "gamma"):
        value = sub[name].transpose("scene", "xi", "lambda").values.ravel()
        ci = sub[f"{name}_ci"].transpose("scene", "xi", "lambda", "bound").values.reshape(-1, 2)
        width = (np.log(ci[:, 1]) - np.log(ci[:, 0])) if name == "alpha" else (ci[:, 1] - ci[:, 0])
        out[name] = value
        out[f"{name}_sigma"] = np.fmax(width / (2.0 * z_c), SIGMA_FLOOR[name])
        out[f"{name}_half_width"] = (ci[:, 1] - ci[:, 0]) / (2.0 * value) if name == "alpha" else width / 2.0
    return out


def _model_doc(model: AtlasModel, degree: int, scores: dict[int, float]) -> dict[str, Any]:
    return {"transform": model.transform, "degree": degree, "low": model.low.tolist(), "high": model.high.tolist(),
            "powers": model.powers.tolist(), "coef": model.coef.tolist(),
            "cv_rms": {str(d): (s if np.isfinite(s) else None) for d, s in scores.items()}}


def fit_atlas(atlas: xr.Dataset, degrees: range = range(1, 5)) -> tuple[dict[str, Any], list[dict[str, Any]]]:
    """The surrogate document and the held-out rows of an atlas dataset.

    Raises
    ------
    ValueError
        If the atlas has no design or no held-out scene, or no degree can be cross-validated.
    """
    held = atlas["heldout"].values.astype(bool)
    if held.all() or not held.any():
        raise ValueError(f"the atlas needs design and held-out scenes (has {int((~held).sum())} and {int(held.sum())})")
    design = _points(atlas, np.flatnonzero(~held))
    models, doc = {}, {}
    for name in ("alpha", "gamma"):
        args = (design["xi"], design["lambda"], design["mu"], design["Pi"], design[name], design[f"{name}_sigma"])
        degree, scores = select_degree(*args, design["scene"], degrees, TRANSFORM[name])
        models[name] = fit_atlas_model(*args, degree, TRANSFORM[name])
        doc[name] = _model_doc(models[name], degree, scores)
    rows = _heldout_rows(atlas, np.flatnonzero(held), models)
    passing = [r["within"] for r in rows]
    worst = max(rows, key=lambda r: r["error"] / r["allowed"])
    doc.update({
        "format": FORMAT,
        "model": "ln alpha and gamma: polynomials of total degree D in u = 2 (x - low)/(high - low) - 1 of "
                 "x = (-ln(1 - xi), ln lambda, ln mu, ln Pi); term k is prod_i u_i^powers[k][i]",
        "domain": {"mu": [float(atlas["mu"].min()), float(atlas["mu"].max())],
                   "Pi": [float(atlas["Pi"].min()), float(atlas["Pi"].max())],
                   "xi": [float(atlas["xi"].min()), float(atlas["xi"].max())],
                   "lambda": [float(atlas["lambda"].min()), float(atlas["lambda"].max())],
                   "force_normalized": _force_range(atlas)},
        "heldout": {"rule": f"|ln R'_surrogate - ln R'_scene| <= max({FLOOR:g}, the cell's relative half-width of "
                            "alpha) at every fitted F' step",
                    "cells": len({(r['scene'], r['xi'], r['lambda']) for r in rows}),
                    "steps": len(rows), "steps_within": int(sum(passing)),
                    "cells_within": _cells_within(rows), "worst": worst,
                    "rms_ln_error": float(np.sqrt(np.mean([r["error"] ** 2 for r in rows]))),
                    "max_ln_error": float(max(r["error"] for r in rows))},
        "provenance": {"g2tom_commit": git_commit(), "config_hash": atlas.attrs.get("config_hash", ""),
                       "atlas_config_hashes": atlas.attrs.get("scene_config_hashes", "")},
    })
    return doc, rows


def _force_range(atlas: xr.Dataset) -> list[float]:
    """F' fitted in every scene: from the largest of the scenes' lowest fitted F' to the smallest highest."""
    force = np.where(atlas["fitted"].values.astype(bool), atlas["force_normalized"].values, np.nan)
    return [float(np.nanmax(np.nanmin(force, axis=1))), float(np.nanmin(np.nanmax(force, axis=1)))]


def _cells_within(rows: list[dict[str, Any]]) -> int:
    cells: dict[tuple, bool] = {}
    for r in rows:
        key = (r["scene"], r["xi"], r["lambda"])
        cells[key] = cells.get(key, True) and r["within"]
    return int(sum(cells.values()))


def _heldout_rows(atlas: xr.Dataset, scenes: np.ndarray, models: dict[str, AtlasModel]) -> list[dict[str, Any]]:
    """One row per held-out (scene, xi, lambda) cell and fitted step."""
    pts = _points(atlas, scenes)
    alpha = models["alpha"](pts["xi"], pts["lambda"], pts["mu"], pts["Pi"])
    gamma = models["gamma"](pts["xi"], pts["lambda"], pts["mu"], pts["Pi"])
    rows = []
    for k in range(pts["xi"].size):
        s = int(pts["scene"][k])
        fitted = atlas["fitted"].values[s].astype(bool)
        xi_i = int(np.flatnonzero(atlas["xi"].values == pts["xi"][k])[0])
        lam_i = int(np.flatnonzero(atlas["lambda"].values == pts["lambda"][k])[0])
        allowed = max(FLOOR, float(pts["alpha_half_width"][k]))
        for step in np.flatnonzero(fitted):
            f = float(atlas["force_normalized"].values[s, step])
            scene_r = float(atlas["resistance_normalized"].values[s, xi_i, lam_i, step])
            error = abs(np.log(alpha[k]) - gamma[k] * np.log(f) - np.log(scene_r))
            rows.append({"scene": str(atlas["scene"].values[s]), "mu": float(pts["mu"][k]), "Pi": float(pts["Pi"][k]),
                         "xi": float(pts["xi"][k]), "lambda": float(pts["lambda"][k]), "force_normalized": f,
                         "resistance_normalized": scene_r, "error": float(error), "allowed": allowed,
                         "within": bool(error <= allowed)})
    return rows


def write_atlas_surrogate(atlas_path: str | Path) -> tuple[Path, dict[str, Any]]:
    """Fit ``atlas.nc``; write ``surrogate.json`` and ``heldout.csv`` beside it, atomically."""
    atlas_path = Path(atlas_path)
    with xr.open_dataset(atlas_path, engine="netcdf4") as ds:
        doc, rows = fit_atlas(ds.load())
    target = atlas_path.parent / "surrogate.json"
    with atomic_path(target) as tmp:
        tmp.write_text(json.dumps(doc, indent=1) + "\n")
    keys = list(rows[0])
    with atomic_path(atlas_path.parent / "heldout.csv") as tmp:
        tmp.write_text("\n".join([",".join(keys)] + [",".join(str(r[k]) for k in keys) for r in rows]) + "\n")
    return target, doc
