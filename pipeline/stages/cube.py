"""Stage 3: Greenwood's resistance over xi x lambda x delta x realization (the cube).

Reads the discrete spots of ``contact.nc`` and the oxide fields of ``oxide.nc``. A spot
conducts where its cell's ``psi < threshold`` (the stored float32 values); its resistance at
every load step follows Greenwood's Eqs. 11-15 (:mod:`pipeline.physics.constriction`), with
interaction weights ``cube.weights`` (spot radii, Eq. 13, or cell contact areas as in the
published code). With ``cube.model = "point"`` the exact point-interaction solve
(:mod:`pipeline.physics.point_model`) replaces the closed form, and ``oxide.film = "resistive"``
lets oxidized spots conduct through their film. The work is split over realization chunks of ``cube.chunk`` fields, each a
dask task; every entry's result is bit-identical whatever the chunk size or scheduler.
"""

from __future__ import annotations

import functools
from pathlib import Path
from typing import Any

import dask
import numpy as np
import xarray as xr

from pipeline import store
from pipeline.compute import ComputeOptions, compute
from pipeline.config import Scenario
from pipeline.physics import constriction, point_model

__all__ = ["build", "run", "spot_maps"]

_TERMS = ("resistance", "resistance_self", "resistance_interaction", "n_conducting", "crop_bound")
_SOLVER_TERMS = ("iterations", "residual")
_LONG_NAMES = {
    "greenwood": "Greenwood constriction resistance R = R_self + R_int",
    "point": "point-interaction constriction resistance R = rho* / sum f (exact solve of M f = 1)",
}


def _model(settings: dict[str, Any]) -> Any:
    """The resistance function of ``settings["model"]`` with the calling convention of
    :func:`constriction.resistance`: the point solve, Greenwood with films, or Greenwood."""
    film = settings["film_resistance"]
    if settings["model"] == "point":
        return functools.partial(
            point_model.resistance, film_resistance=film,
            solver_tolerance=settings["solver_tolerance"], max_iterations=settings["max_iterations"],
        )
    if np.isfinite(film):
        return functools.partial(point_model.greenwood_resistance, film_resistance=film)
    return constriction.resistance


def spot_maps(scenario: Scenario, contact: xr.Dataset) -> tuple[np.ndarray, np.ndarray, float]:
    """Spot radii and interaction weights per load step, and the cell pitch.

    Parameters
    ----------
    scenario
        Supplies ``cube.weights`` (``radius`` or ``area``).
    contact
        ``spot_radius`` and ``spot_area`` (delta, y, x) on evenly spaced cell centres ``x``.

    Returns
    -------
    tuple
        ``radius`` (m) and ``weights`` (m for ``cube.weights = radius``, m^2 for ``area``),
        both float64 of shape (delta, y, x), and the pitch of the cell centres ``x`` (m).
    """
    radius = np.asarray(contact["spot_radius"].transpose("delta", "y", "x").values, np.float64)
    if scenario.cube.weights == "radius":
        weights = radius
    else:
        weights = np.asarray(contact["spot_area"].transpose("delta", "y", "x").values, np.float64)
    x = np.asarray(contact["x"].values, np.float64)
    steps = np.diff(x)
    if x.size < 2 or not np.allclose(steps, steps[0], rtol=1e-9, atol=0):
        raise ValueError("contact.nc: the cell centres x must be evenly spaced")
    return radius, weights, float(steps[0])


def _check_grids(contact: xr.Dataset, oxide: xr.Dataset) -> None:
    """Raise ValueError unless both files share one square grid of cell centres."""
    for axis in ("x", "y"):
        if contact[axis].size != oxide[axis].size or not np.allclose(
            contact[axis].values, oxide[axis].values, rtol=1e-9, atol=0
        ):
            raise ValueError(f"contact.nc and oxide.nc disagree on the cell centres '{axis}'")
    if not np.allclose(contact["x"].values, contact["y"].values, rtol=1e-9, atol=0):
        raise ValueError("contact.nc: the cell grid must be square (x and y identical)")


def _chunk(
    psi: np.ndarray,
    threshold: np.ndarray,
    radius: np.ndarray,
    weights: np.ndarray,
    settings: dict[str, Any],
) -> dict[str, Any]:
    """Greenwood terms of a chunk of fields.

    Parameters
    ----------
    psi
        Fields, float32, shape (lambda, realization, y, x).
    threshold
        Thresholds, float32, shape (xi, lambda, realization).
    radius, weights
        Spot radii (m) and interaction weights, shape (delta, y, x).
    settings
        ``pitch``, ``rho``, ``crops``, ``tolerance``, ``method``.

    Returns
    -------
    dict
        The arrays of :data:`_TERMS`, shape (xi, lambda, delta, realization), and
        ``n_uncropped``.
    """
    n_xi, n_lam, n_real = threshold.shape
    n = psi.shape[-1]
    masks = psi[None] < threshold[..., None, None]
    res = _model(settings)(
        masks.reshape(-1, n, n), radius, weights, settings["pitch"], settings["rho"],
        settings["crops"], settings["tolerance"], settings["method"],
    )
    out: dict[str, Any] = {
        name: getattr(res, name).reshape(n_xi, n_lam, n_real, -1).transpose(0, 1, 3, 2)
        for name in _TERMS + _SOLVER_TERMS if hasattr(res, name)
    }
    out["n_uncropped"] = res.n_uncropped
    return out


def _compute(
    oxide: xr.Dataset, radius: np.ndarray, weights: np.ndarray, settings: dict[str, Any],
    chunk: int, options: ComputeOptions,
) -> dict[str, Any]:
    """Run :func:`_chunk` over realization chunks with dask and join the pieces."""
    psi = oxide["psi"].transpose("lambda", "realization", "y", "x").values
    threshold = oxide["threshold"].transpose("xi", "lambda", "realization").values
    shared = dask.delayed(radius), dask.delayed(weights), dask.delayed(settings)
    tasks = [
        dask.delayed(_chunk, pure=True)(
            psi[:, start : start + chunk], threshold[:, :, start : start + chunk], *shared
        )
        for start in range(0, psi.shape[1], chunk)
    ]
    pieces = compute(*tasks, options=options)
    out: dict[str, Any] = {
        name: np.concatenate([p[name] for p in pieces], axis=-1)
        for name in _TERMS + _SOLVER_TERMS if name in pieces[0]
    }
    out["n_uncropped"] = int(sum(p["n_uncropped"] for p in pieces))
    return out


def _clean(radius: np.ndarray, weights: np.ndarray, settings: dict[str, Any]) -> constriction.ChunkResult:
    """Every spot conducting, on the whole window (exact)."""
    n = radius.shape[-1]
    return _model(settings)(
        np.ones((1, n, n), dtype=bool), radius, weights, settings["pitch"], settings["rho"],
        np.full(radius.shape[0], n), 0.0, settings["method"],
    )


def _measured_crop_error(
    oxide: xr.Dataset, radius: np.ndarray, weights: np.ndarray, settings: dict[str, Any],
    cropped: np.ndarray,
) -> float:
    """Largest relative change of ``R`` from cropping, over the first realization's entries."""
    n = radius.shape[-1]
    whole = dict(settings, crops=np.full(radius.shape[0], n), tolerance=0.0)
    psi = oxide["psi"].transpose("lambda", "realization", "y", "x").values[:, :1]
    threshold = oxide["threshold"].transpose("xi", "lambda", "realization").values[:, :, :1]
    exact = _chunk(psi, threshold, radius, weights, whole)["resistance"]
    finite = np.isfinite(exact)
    if not finite.any():
        return 0.0
    return float(np.max(np.abs(cropped[..., :1][finite] / exact[finite] - 1.0)))


def _attrs(units: str, long_name: str, **extra: Any) -> dict[str, Any]:
    """CF-style attributes ``units`` and ``long_name`` plus any ``extra`` ones."""
    return {"units": units, "long_name": long_name, **extra}


def _dataset(
    scenario: Scenario, contact: xr.Dataset, oxide: xr.Dataset, out: dict[str, Any],
    clean: constriction.ChunkResult, settings: dict[str, Any], measured: float,
) -> xr.Dataset:
    """Wrap the computed arrays with coordinates and CF attributes."""
    dims = ("xi", "lambda", "delta", "realization")
    w_unit = "m" if scenario.cube.weights == "radius" else "m2"
    coords = {
        "xi": ("xi", oxide["xi"].values, _attrs("1", "nominal oxide fraction")),
        "lambda": ("lambda", oxide["lambda"].values,
                   _attrs("1", "normalized oxide correlation length l_O sqrt(eta)")),
        "delta": ("delta", contact["delta"].values, _attrs("m", "approach delta of the sphere tip")),
        "realization": ("realization", oxide["realization"].values,
                        _attrs("1", "realization index of the random field")),
        "force": ("delta", contact["force"].values, _attrs("N", "normal force")),
        "force_normalized": ("delta", contact["force_normalized"].values,
                             _attrs("1", "normalized force F' = 2F / (E* sqrt(R* sigma^3))")),
    }
    is_open = np.isinf(out["resistance"])
    data_vars = {
        "resistance": (dims, out["resistance"], _attrs(
            "ohm", _LONG_NAMES[scenario.cube.model],
            comment="+inf: open circuit (no conducting spot)")),
        "resistance_self": (dims, out["resistance_self"],
                            _attrs("ohm", "self term rho* / (2 sum phi a)")),
        "resistance_interaction": (dims, out["resistance_interaction"], _attrs(
            "ohm", f"interaction term rho* sum phi phi w w / d / (pi (sum phi w)^2), w in {w_unit}")),
        "n_conducting": (dims, out["n_conducting"].astype(np.int32),
                         _attrs("1", "number of conducting spots")),
        "n_open": (("xi", "lambda", "delta"), is_open.sum(axis=-1).astype(np.int32),
                   _attrs("1", "number of open-circuit realizations (R = +inf)")),
        "resistance_clean": ("delta", clean.resistance[0],
                             _attrs("ohm", "resistance of the oxide-free surface")),
        "resistance_clean_self": ("delta", clean.resistance_self[0],
                                  _attrs("ohm", "self term of the oxide-free surface")),
        "resistance_clean_interaction": ("delta", clean.resistance_interaction[0],
                                         _attrs("ohm", "interaction term of the oxide-free surface")),
        "crop_cells": ("delta", np.asarray(settings["crops"], np.int32), _attrs(
            "1", "side of the centred square of cells kept at each approach")),
    }
    if "iterations" in out:
        data_vars["iterations"] = (dims, out["iterations"].astype(np.int32), _attrs(
            "1", "conjugate-gradient iterations of the point-model solve"))
        data_vars["residual"] = (dims, out["residual"], _attrs(
            "1", "final relative residual of the point-model solve (Jacobi norm)"))
    attrs = {
        "interaction_weights": scenario.cube.weights,
        "method": settings["method_used"],
        "crop_tolerance": settings["tolerance"],
        "crop_error_bound": float(out["crop_bound"].max(initial=0.0)),
        "crop_error_measured": measured,
        "crop_error_measured_on": "all entries of the first realization, against the whole window",
        "n_uncropped": out["n_uncropped"],
        "n_open_total": int(is_open.sum()),
        "conducting_rule": "a spot conducts where spot_radius > 0 and psi < threshold (float32)",
        "model": scenario.cube.model,
        "film": scenario.oxide.film,
    }
    if scenario.oxide.film == "resistive":
        attrs["film_resistance"] = scenario.oxide.film_resistance
        attrs["conducting_rule"] = "every spot conducts; where psi >= threshold through the film"
    if "iterations" in out:
        attrs["solver_tolerance"] = scenario.cube.solver_tolerance
        attrs["n_not_converged"] = int((out["residual"] > scenario.cube.solver_tolerance).sum())
    return xr.Dataset(data_vars, coords=coords, attrs=attrs)


def build(
    scenario: Scenario,
    contact: xr.Dataset,
    oxide: xr.Dataset,
    options: ComputeOptions = ComputeOptions(progress=False),
) -> xr.Dataset:
    """Compute the resistance cube of ``scenario`` from in-memory contact and oxide datasets.

    Parameters
    ----------
    scenario
        The validated scenario (sections ``material`` for rho*, ``cube``).
    contact
        ``spot_radius`` and ``spot_area`` (delta, y, x), ``force``, ``force_normalized``.
    oxide
        ``psi`` (lambda, realization, y, x) and ``threshold`` (xi, lambda, realization).
    options
        Where dask runs (see :func:`pipeline.compute.compute`).

    Returns
    -------
    xarray.Dataset
        ``resistance``, its two terms and ``n_conducting`` (xi, lambda, delta, realization),
        ``n_open`` (xi, lambda, delta), the clean-surface terms and ``crop_cells`` (delta).
    """
    _check_grids(contact, oxide)
    radius, weights, pitch = spot_maps(scenario, contact)
    cube = scenario.cube
    film = scenario.oxide.film_resistance if scenario.oxide.film == "resistive" else np.inf
    whole_window = cube.model == "greenwood" and np.isfinite(film)
    settings = {
        "pitch": pitch,
        "rho": scenario.material.rho,
        "model": cube.model,
        "film_resistance": film,
        "solver_tolerance": cube.solver_tolerance,
        "max_iterations": cube.max_iterations,
        "crops": constriction.choose_crops(radius, weights, pitch, 0.0 if whole_window else cube.crop_tolerance),
        "tolerance": cube.crop_tolerance,
        "method": cube.method,
        "method_used": constriction.AUTO_METHOD if cube.method == "auto" else cube.method,
    }
    out = _compute(oxide, radius, weights, settings, cube.chunk, options)
    clean = _clean(radius, weights, settings)
    measured = _measured_crop_error(oxide, radius, weights, settings, out["resistance"])
    return _dataset(scenario, contact, oxide, out, clean, settings, measured)


def run(scenario: Scenario, data_dir: str | Path, options: ComputeOptions) -> Path:
    """Read contact.nc and oxide.nc, build the cube and write ``<data_dir>/cube.nc`` atomically."""
    contact = store.read_stage(data_dir, "contact", scenario)
    oxide = store.read_stage(data_dir, "oxide", scenario)
    return store.write_dataset(build(scenario, contact, oxide, options), data_dir, "cube", scenario)
