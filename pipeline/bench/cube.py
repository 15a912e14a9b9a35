"""Benchmark of stage 3: the full resistance cube, its throughput and the error of each path.

Builds the contact spots and the oxide ensemble in memory with their stages, times the whole
cube with the scenario's settings (median of :data:`REPEATS` runs, with the peak resident
memory), then compares every interaction algorithm with the direct double sum on the same
subset of entries: seconds per simulation, the speed-up over the double sum and the largest
relative error of ``R``, with and without cropping.
"""

from __future__ import annotations

import math
import resource
import statistics
import time
from typing import Any

import numpy as np
import xarray as xr

from g2tom.compute import ComputeOptions
from g2tom.config import ResolvedScenario, Scenario
from g2tom.physics import constriction
from g2tom.physics.crops import choose_crops
from g2tom.physics.spot_geometry import SpotGeometry
from g2tom.stages import contact as contact_stage
from g2tom.stages import cube
from g2tom.stages import oxide as oxide_stage

__all__ = ["run"]

#: Oxide masks (xi, lambda, realization) in the subset compared with the double sum.
N_SUBSET_MASKS = 10
#: Masks per timed batch of each fast path (the best of :data:`REPEATS` runs is kept).
N_TIMED_MASKS = 256
#: Timed runs of the full cube (the median is reported) and of each path's batch.
REPEATS = 3


def _inputs(scenario: ResolvedScenario) -> tuple[xr.Dataset, xr.Dataset]:
    """Contact spots and oxide ensemble of ``scenario``, built in memory by their stages."""
    return contact_stage.build(scenario), oxide_stage.build(scenario)


def _subset_masks(oxide: xr.Dataset, count: int, seed: int = 0) -> np.ndarray:
    """``count`` random oxide masks (xi, lambda, realization), bool (count, y, x)."""
    psi = oxide["psi"].transpose("lambda", "realization", "y", "x").values
    thr = oxide["threshold"].transpose("xi", "lambda", "realization").values
    rng = np.random.default_rng(seed)
    z = rng.integers(thr.shape[0], size=count)
    lam = rng.integers(thr.shape[1], size=count)
    r = rng.integers(thr.shape[2], size=count)
    return psi[lam, r] < thr[z, lam, r][:, None, None]


def _timed(func: Any, *args: Any) -> tuple[Any, float]:
    """``func(*args)`` and its wall time in s."""
    start = time.perf_counter()
    result = func(*args)
    return result, time.perf_counter() - start


def _max_rel_error(value: np.ndarray, reference: np.ndarray) -> float:
    """Largest ``|value / reference - 1|`` over finite entries; inf if the open circuits differ."""
    finite = np.isfinite(reference)
    if not np.array_equal(finite, np.isfinite(value)):
        return math.inf
    if not finite.any():
        return 0.0
    return float(np.max(np.abs(value[finite] / reference[finite] - 1.0)))


def _paths(
    scenario: Scenario, radius: np.ndarray, weights: np.ndarray, pitch: float
) -> dict[str, tuple[str, SpotGeometry]]:
    """Named fast paths: (method, the spots with their crops and tolerance)."""
    whole = SpotGeometry.whole_window(radius, weights, pitch)
    tol = scenario.cube.crop_tolerance
    cropped = SpotGeometry(radius, weights, pitch, choose_crops(radius, weights, pitch, tol), tol)
    spectral = ("folded", "dft_gemm", "fft")
    paths = {f"{m}_uncropped": (m, whole) for m in spectral + ("gemm",)}
    paths.update({f"{m}_cropped": (m, cropped) for m in spectral})
    return paths


def _compare(scenario: Scenario, contact: xr.Dataset, oxide: xr.Dataset) -> dict[str, Any]:
    """Each path against the direct double sum on the same subset of entries."""
    radius, weights, pitch = cube.spot_maps(scenario, contact)
    rho = scenario.material.rho
    masks = _subset_masks(oxide, N_SUBSET_MASKS)
    ref, t_direct = _timed(
        constriction.resistance, masks, SpotGeometry.whole_window(radius, weights, pitch), rho, "direct"
    )
    n_sims = masks.shape[0] * radius.shape[0]
    direct_per_sim = t_direct / n_sims
    timed_masks = _subset_masks(oxide, N_TIMED_MASKS, seed=1)
    out: dict[str, Any] = {
        "subset_simulations": n_sims,
        "direct_seconds_per_simulation": direct_per_sim,
        "paths": {},
    }
    for name, (method, spots) in _paths(scenario, radius, weights, pitch).items():
        res = constriction.resistance(masks, spots, rho, method)
        seconds = min(
            _timed(constriction.resistance, timed_masks, spots, rho, method)[1]
            for _ in range(REPEATS)
        )
        per_sim = seconds / (timed_masks.shape[0] * radius.shape[0])
        out["paths"][name] = {
            "max_relative_error_vs_direct": _max_rel_error(res.resistance, ref.resistance),
            "seconds_per_simulation_one_thread_best": per_sim,
            "speedup_vs_direct": direct_per_sim / per_sim,
            "cropped": bool(spots.tolerance > 0),
        }
    return out


def _peak_rss_mib() -> float:
    """Peak resident memory of this process so far, in MiB (Linux reports KiB)."""
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def run(scenario: Scenario) -> dict[str, Any]:
    """Time the full cube and compare every path with the double sum; JSON-ready figures."""
    (contact, oxide), t_inputs = _timed(_inputs, scenario)
    rss_inputs = _peak_rss_mib()
    options = ComputeOptions(progress=False)
    seconds = []
    for _ in range(REPEATS):
        ds, t_cube = _timed(cube.build, scenario, contact, oxide, options)
        seconds.append(t_cube)
    rss_cube = _peak_rss_mib()
    t_cube = statistics.median(seconds)
    n_sims = int(ds["resistance"].size)
    comparison = _compare(scenario, contact, oxide)
    cropped = "cropped" if scenario.cube.crop_tolerance > 0 else "uncropped"
    return {
        "inputs_seconds": t_inputs,
        "cube_shape": dict(ds["resistance"].sizes),
        "simulations": n_sims,
        "cube_seconds_median": t_cube,
        "cube_seconds_runs": seconds,
        "simulations_per_second": n_sims / t_cube,
        "speedup_vs_direct_full_cube": (
            comparison["direct_seconds_per_simulation"] * n_sims / t_cube
        ),
        "default_path": f"{ds.attrs['method']}_{cropped}",
        "chunk": scenario.compute.cube_chunk,
        "crop_tolerance": ds.attrs["crop_tolerance"],
        "crop_error_bound": ds.attrs["crop_error_bound"],
        "crop_error_measured": ds.attrs["crop_error_measured"],
        "n_uncropped": ds.attrs["n_uncropped"],
        "n_open_total": ds.attrs["n_open_total"],
        "crop_cells": [int(c) for c in ds["crop_cells"].values],
        "peak_rss_mib_inputs": rss_inputs,
        "peak_rss_mib_cube": rss_cube,
        **comparison,
    }
