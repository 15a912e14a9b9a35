"""Benchmark of the point-interaction model against Greenwood's closed form on the same cube.

Both models run on the scenario's full (xi, lambda, delta) grid with a subset of
:data:`N_REALIZATIONS` realizations (the point model with both stopping criteria) (per-simulation work is the same for every realization, so
the full cube's time follows by scaling with the realization count, stated as an
extrapolation). Reported: the time ratio point / Greenwood in one process, conjugate-gradient
iterations per solve (median, max), the final residuals, the Rayleigh bound R_greenwood >= R_point
on every entry, the agreement of the uncropped fast solve with the dense Cholesky solve on random
masks, and the cropping error of the point model (measured against the whole window, with its
bound).
"""

from __future__ import annotations

import dataclasses
import statistics
import time
from typing import Any

import numpy as np

from g2tom.bench.cube import _max_rel_error, _subset_masks
from g2tom.compute import ComputeOptions
from g2tom.config import ResolvedScenario, Scenario
from g2tom.physics import constriction, point_model
from g2tom.physics.crops import choose_crops
from g2tom.physics.spot_geometry import SpotGeometry
from g2tom.stages import contact as contact_stage
from g2tom.stages import cube
from g2tom.stages import oxide as oxide_stage

__all__ = ["run"]

#: Realizations of the timed cube subset (all xi, lambda and delta of the scenario).
N_REALIZATIONS = 20
#: Timed runs of each model's cube (the median is reported).
REPEATS = 2
#: Random masks (and every :data:`DELTA_STRIDE`-th load step) solved densely as the reference.
N_DENSE_MASKS = 4
DELTA_STRIDE = 5
#: Random masks on which cropping is measured against the whole window.
N_CROP_MASKS = 128


def _timed_cube(scenario: ResolvedScenario, contact: Any, oxide: Any) -> tuple[Any, list[float]]:
    seconds, ds = [], None
    for _ in range(REPEATS):
        start = time.perf_counter()
        ds = cube.build(scenario, contact, oxide, ComputeOptions(progress=False))
        seconds.append(time.perf_counter() - start)
    return ds, seconds


def _dense_agreement(scenario: Scenario, contact: Any, oxide: Any) -> dict[str, Any]:
    radius, _, pitch = cube.spot_maps(scenario, contact)
    radius = radius[::DELTA_STRIDE]
    masks = _subset_masks(oxide, N_DENSE_MASKS, seed=2)
    whole = SpotGeometry.whole_window(radius, radius, pitch)
    rho = scenario.material.rho
    fast = point_model.resistance(masks, whole, rho, solver_tolerance=scenario.cube.solver_tolerance,
                                  criterion=scenario.cube.solver_criterion)
    closed = point_model.greenwood_resistance(masks, whole, rho)
    start = time.perf_counter()
    dense, greenwood = point_model.resistance_dense(masks, radius, pitch, rho)
    t_dense = time.perf_counter() - start
    return {
        "dense_solves": int(dense.size),
        "max_relative_error_fast_vs_dense": _max_rel_error(fast.resistance, dense),
        "max_relative_error_greenwood_rayleigh_vs_dense": _max_rel_error(closed.resistance, greenwood),
        "dense_seconds_per_solve": t_dense / dense.size,
    }


def _cropping(scenario: Scenario, contact: Any, oxide: Any) -> dict[str, Any]:
    radius, _, pitch = cube.spot_maps(scenario, contact)
    rho, tol = scenario.material.rho, scenario.cube.crop_tolerance
    masks = _subset_masks(oxide, N_CROP_MASKS, seed=3)
    crops = choose_crops(radius, radius, pitch, tol)
    whole = SpotGeometry.whole_window(radius, radius, pitch)
    start = time.perf_counter()
    solver = {"solver_tolerance": scenario.cube.solver_tolerance, "criterion": scenario.cube.solver_criterion}
    cropped = point_model.resistance(masks, SpotGeometry(radius, radius, pitch, crops, tol), rho, **solver)
    t_cropped = time.perf_counter() - start
    start = time.perf_counter()
    exact = point_model.resistance(masks, whole, rho, **solver)
    t_whole = time.perf_counter() - start
    greenwood = constriction.resistance(masks, whole, rho).resistance
    finite = np.isfinite(exact.resistance)
    return {
        "rayleigh_bound_violations_whole_window": int(
            np.sum(greenwood[finite] < exact.resistance[finite] * (1 - 1e-12))),
        "greenwood_over_point_min_whole_window": float(np.min(greenwood[finite] / exact.resistance[finite])),
        "crop_tolerance": tol,
        "crop_error_measured": _max_rel_error(cropped.resistance, exact.resistance),
        "crop_error_bound": float(cropped.crop_bound.max(initial=0.0)),
        "n_uncropped": cropped.n_uncropped,
        "entries": int(cropped.resistance.size),
        "time_ratio_cropped_over_whole": t_cropped / t_whole,
        "iterations_median_whole": float(np.median(exact.iterations)),
        "iterations_max_whole": int(exact.iterations.max()),
    }


def run(scenario: ResolvedScenario) -> dict[str, Any]:
    """Time both models on the cube subset and check the point solve; JSON-ready figures."""
    subset = dataclasses.replace(
        scenario, oxide=dataclasses.replace(scenario.oxide, n_realizations=N_REALIZATIONS, film="insulating", ensemble="fixed"),
    )
    greenwood_sc = dataclasses.replace(subset, cube=dataclasses.replace(subset.cube, model="greenwood"))
    point_sc = dataclasses.replace(subset, cube=dataclasses.replace(subset.cube, model="point"))
    other = "residual" if scenario.cube.solver_criterion == "error" else "error"
    other_sc = dataclasses.replace(point_sc, cube=dataclasses.replace(point_sc.cube, solver_criterion=other))
    contact, oxide = contact_stage.build(subset), oxide_stage.build(subset)
    green, t_green = _timed_cube(greenwood_sc, contact, oxide)
    point, t_point = _timed_cube(point_sc, contact, oxide)
    alternative, t_other = _timed_cube(other_sc, contact, oxide)
    ratio = statistics.median(t_point) / statistics.median(t_green)
    other_iterations = alternative["iterations"].values
    other_iterations = other_iterations[other_iterations >= 0]
    n_sims = int(point["resistance"].size)
    full_sims = n_sims // N_REALIZATIONS * scenario.oxide.n_realizations
    r_g, r_p = green["resistance"].values, point["resistance"].values
    finite = np.isfinite(r_p)
    iterations = point["iterations"].values
    iterations = iterations[iterations >= 0]
    return {
        "subset_realizations": N_REALIZATIONS,
        "subset_simulations": n_sims,
        "greenwood_seconds_runs": t_green,
        "point_seconds_runs": t_point,
        "time_ratio_point_over_greenwood": ratio,
        "target_time_ratio": 10.0,
        "full_cube_simulations": full_sims,
        "point_full_cube_seconds_extrapolated": statistics.median(t_point) * full_sims / n_sims,
        "greenwood_full_cube_seconds_extrapolated": statistics.median(t_green) * full_sims / n_sims,
        "solver_tolerance": scenario.cube.solver_tolerance,
        "solver_criterion": scenario.cube.solver_criterion,
        "iterations_median": float(np.median(iterations)),
        "iterations_max": int(iterations.max()),
        "error_estimate_max": float(np.nanmax(point["error_estimate"].values)),
        f"{other}_criterion": {
            "point_seconds_runs": t_other,
            "time_ratio_point_over_greenwood": statistics.median(t_other) / statistics.median(t_green),
            "iterations_median": float(np.median(other_iterations)),
            "iterations_max": int(other_iterations.max()),
            "max_relative_difference_from_default": _max_rel_error(alternative["resistance"].values, point["resistance"].values),
        },
        "iterations_median_by_delta": [float(v) for v in np.median(point["iterations"].values, axis=(0, 1, 3))],
        "residual_max": float(point["residual"].values.max()),
        "n_not_converged": point.attrs["n_not_converged"],
        "open_circuits_agree": bool(np.array_equal(np.isinf(r_g), np.isinf(r_p))),
        # both cubes are cropped (errors of opposite sign, each within the crop tolerance)
        "rayleigh_bound_violations_beyond_crop_tolerance": int(
            np.sum(r_g[finite] < r_p[finite] * (1 - 2 * scenario.cube.crop_tolerance))),
        "greenwood_over_point_min": float(np.min(r_g[finite] / r_p[finite])),
        "greenwood_over_point_max": float(np.max(r_g[finite] / r_p[finite])),
        "clean_greenwood_over_point": [float(v) for v in green["resistance_clean"].values / point["resistance_clean"].values],
        "dense": _dense_agreement(scenario, contact, oxide),
        "cropping": _cropping(scenario, contact, oxide),
        "crop_error_bound_cube": point.attrs["crop_error_bound"],
        "crop_error_measured_cube": point.attrs["crop_error_measured"],
        "n_uncropped_cube": point.attrs["n_uncropped"],
        "note": "timings on a shared 2-core machine; full-cube seconds scale the subset by the realization count",
        "finite_entries": int(finite.sum()),
    }
