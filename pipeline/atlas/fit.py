"""The atlas surrogate: R'(xi, lambda, mu, Pi, F') and alpha, gamma over (xi, lambda, mu, Pi) from
``atlas.nc``, checked on held-out scenes.

Fitted on the design scenes only (:mod:`pipeline.fitting.atlas_surrogate`, degrees by
leave-one-scene-out cross-validation): the curve model, ln R' as one polynomial of total degree
D in the mapped log coordinates of (xi, lambda, mu, Pi, F') fitted to every design cell's
reduction at every fitted step (the predictor's default: Barber's curve bends, so a power law
misses the light loads by ~10 %), and ln alpha and gamma of Eq. 27 over (xi, lambda, mu, Pi),
each weighted by the cell's interval. The held-out scenes judge the curve model: at every
fitted F' step of every held-out (scene, xi, lambda) cell, |ln R'_surrogate - ln R'_scene|,
R'_scene the scene's fitted reduction, against max(:data:`FLOOR`, the cell's relative
half-width of alpha); the power law's verdict is reported beside it. Writes ``<atlas>/surrogate.json``
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

from pipeline.fitting.atlas_surrogate import AtlasModel, fit_atlas_model, select_degree
from pipeline.store import atomic_path, git_commit

__all__ = ["fit_atlas", "write_atlas_surrogate", "FLOOR", "FORMAT", "CURVE"]

FORMAT = "g2tom-atlas-surrogate"
#: The name of the curve model of ln R'(xi, lambda, mu, Pi, F') in the document.
CURVE = "log_resistance"
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


def _curve_points(atlas: xr.Dataset, scenes: np.ndarray) -> dict[str, np.ndarray]:
    """Flat (scene, xi, lambda, fitted step) points of the given scenes: F', R' and its sigma."""
    cells = _points(atlas, scenes)
    keys = ("scene", "xi", "lambda", "mu", "Pi", "force_normalized", "resistance", "sigma", "half_width")
    out: dict[str, list] = {k: [] for k in keys}
    xi_index = {float(v): i for i, v in enumerate(atlas["xi"].values)}
    lam_index = {float(v): i for i, v in enumerate(atlas["lambda"].values)}
    for k in range(cells["xi"].size):
        s = int(cells["scene"][k])
        steps = np.flatnonzero(atlas["fitted"].values[s].astype(bool))
        r = atlas["resistance_normalized"].values[s, xi_index[float(cells["xi"][k])], lam_index[float(cells["lambda"][k])], steps]
        for name in ("scene", "xi", "lambda", "mu", "Pi"):
            out[name].append(np.full(steps.size, cells[name][k]))
        out["force_normalized"].append(atlas["force_normalized"].values[s, steps])
        out["resistance"].append(r)
        out["sigma"].append(np.full(steps.size, cells["alpha_sigma"][k]))
        out["half_width"].append(np.full(steps.size, cells["alpha_half_width"][k]))
    return {k: np.concatenate(v) for k, v in out.items()}


def _model_doc(model: AtlasModel, degree: int, scores: dict[int, float]) -> dict[str, Any]:
    return {"transform": model.transform, "degree": degree, "low": model.low.tolist(), "high": model.high.tolist(),
            "powers": model.powers.tolist(), "coef": model.coef.tolist(),
            "cv_rms": {str(d): (s if np.isfinite(s) else None) for d, s in scores.items()}}


def fit_atlas(atlas: xr.Dataset, degrees: range = range(1, 5),
              curve_degrees: range = range(2, 7)) -> tuple[dict[str, Any], list[dict[str, Any]]]:
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
    curve = _curve_points(atlas, np.flatnonzero(~held))
    args = (curve["xi"], curve["lambda"], curve["mu"], curve["Pi"], curve["resistance"], curve["sigma"])
    degree, scores = select_degree(*args, curve["scene"], curve_degrees, "log", force_n=curve["force_normalized"])
    models[CURVE] = fit_atlas_model(*args, degree, "log", force_n=curve["force_normalized"])
    doc[CURVE] = _model_doc(models[CURVE], degree, scores)
    rows = _heldout_rows(atlas, np.flatnonzero(held), models)
    passing = [r["within"] for r in rows]
    worst = max(rows, key=lambda r: r["error"] / r["allowed"])
    power_cells = _cells_within([dict(r, within=r["power_law_error"] <= r["allowed"]) for r in rows])
    doc.update({
        "format": FORMAT,
        "model": f"{CURVE} (the predictor's default): ln R' as a polynomial of total degree D in "
                 "u = 2 (x - low)/(high - low) - 1 of x = (-ln(1 - xi), ln lambda, ln mu, ln Pi, ln F'); ln alpha "
                 "and gamma (Eq. 27): the same over the first four; term k is prod_i u_i^powers[k][i]",
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
                    "power_law_cells_within": power_cells,
                    "power_law_rms_ln_error": float(np.sqrt(np.mean([r["power_law_error"] ** 2 for r in rows]))),
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
    """One row per held-out (scene, xi, lambda) cell and fitted step: the curve model's error
    (``error``) and the power law's (``power_law_error``) in ln R'."""
    pts = _curve_points(atlas, scenes)
    args = (pts["xi"], pts["lambda"], pts["mu"], pts["Pi"])
    curve = models[CURVE].transformed(*args, pts["force_normalized"])
    power = np.log(models["alpha"](*args)) - models["gamma"](*args) * np.log(pts["force_normalized"])
    target = np.log(pts["resistance"])
    rows = []
    for k in range(target.size):
        allowed = max(FLOOR, float(pts["half_width"][k]))
        error = abs(float(curve[k] - target[k]))
        rows.append({"scene": str(atlas["scene"].values[int(pts["scene"][k])]), "mu": float(pts["mu"][k]),
                     "Pi": float(pts["Pi"][k]), "xi": float(pts["xi"][k]), "lambda": float(pts["lambda"][k]),
                     "force_normalized": float(pts["force_normalized"][k]),
                     "resistance_normalized": float(pts["resistance"][k]), "error": error,
                     "power_law_error": abs(float(power[k] - target[k])), "allowed": allowed,
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
