"""Benchmark of the cost's growth with the cell count: the scaling table of ``make bench``.

For windows of about L = 57, 113, 227 and 453 cells a side (eta = 2e8 x 1, 4, 16, 64 with
``auto`` windows), it measures

* each interaction algorithm per map (folded DFT-GEMM ~ L^3, padded FFT ~ L^2 log L), one
  thread, and which one ``auto`` takes (:func:`pipeline.physics.constriction.auto_method`);
* the time per simulation (one oxide mask at one load step) of the cube's kernel
  (:func:`pipeline.physics.constriction.resistance` with the scenario's crops), on real
  oxide masks, and its growth from L = 113 against L^2 log L;
* the plan's memory and time estimates of the paper's full study on each scene;
* the paper's scene against today's 57-cell window (the ``published`` window, 0.4 R*): the
  cube's time ratio in this one run.

All times are medians of :data:`REPEATS` runs in this process; the machine is shared.
"""

from __future__ import annotations

import dataclasses
import math
import statistics
import time
from typing import Any

import numpy as np

from pipeline import plan
from pipeline.compute import ComputeOptions
from pipeline.config import Scenario, load_scenario
from pipeline.domains import resolve
from pipeline.physics import constriction
from pipeline.physics import interaction_fft as fft
from pipeline.stages import contact as contact_stage
from pipeline.stages import cube
from pipeline.stages import oxide as oxide_stage

__all__ = ["run", "ETAS"]

#: Asperity densities of the table (m^-2): windows of about 57, 113, 227 and 453 cells.
ETAS: tuple[float, ...] = (2e8, 8e8, 3.2e9, 1.28e10)
REPEATS = 3
#: Oxide masks timed per size (two lambdas x realizations at xi = 0.5).
N_MASKS = 16
#: Study used for the default-scene ratio (realizations of the paper's 9 x 12 grid).
RATIO_REALIZATIONS = 25


def _median_time(func: Any, *args: Any) -> float:
    times = []
    for _ in range(REPEATS):
        start = time.perf_counter()
        func(*args)
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def _scene(eta: float) -> Scenario:
    return resolve(load_scenario("paper", {"roughness.eta": eta, "oxide.xi": [0.5], "oxide.lambda": [5.0, 13.0],
                                           "oxide.n_realizations": N_MASKS // 2, "oxide.chunk": N_MASKS}))


def _per_map(n: int) -> dict[str, float]:
    """Seconds per map of each spectral path on an n-wide block (one block of maps)."""
    rng = np.random.default_rng(n)
    u = rng.random((constriction.block_size(n), n, n))
    out = {}
    for name in ("folded", "fft"):
        constriction.interaction_sum(u[:1], 1.0, name)  # operators built outside the timing
        out[name] = _median_time(constriction.interaction_sum, u, 1.0, name) / u.shape[0]
    return out


def _simulation(s: Scenario) -> dict[str, Any]:
    """Time per simulation of the cube kernel on the scene's real masks and crops."""
    quiet = ComputeOptions(progress=False)
    contact, oxide = contact_stage.build(s), oxide_stage.build(s, quiet)
    radius, weights, pitch = cube.spot_maps(s, contact)
    psi = oxide["psi"].transpose("lambda", "realization", "y", "x").values
    thr = oxide["threshold"].transpose("xi", "lambda", "realization").values
    masks = (psi[None] < thr[..., None, None]).reshape(-1, s.n_cells, s.n_cells)
    crops = constriction.choose_crops(radius, weights, pitch, s.cube.crop_tolerance)
    args = (masks, radius, weights, pitch, s.material.rho, crops, s.cube.crop_tolerance)
    constriction.resistance(*args)
    seconds = _median_time(constriction.resistance, *args)
    return {"seconds_per_simulation": seconds / (masks.shape[0] * radius.shape[0]),
            "crop_cells_max": int(crops.max()), "crop_cells_min": int(crops.min())}


def _default_ratio() -> dict[str, Any]:
    """Cube time of the paper's scene (auto window) against today's 0.4 R* window, one run."""
    quiet = ComputeOptions(progress=False)
    sets = {"oxide.n_realizations": RATIO_REALIZATIONS}
    scenes = {"auto": resolve(load_scenario("paper", sets)),
              "window_0.4": resolve(load_scenario("paper", {**sets, "contact.window": 0.4, "contact.r_max": 0.3}))}
    out: dict[str, Any] = {}
    for name, s in scenes.items():
        contact, oxide = contact_stage.build(s), oxide_stage.build(s, quiet)
        cube.build(s, contact, oxide, quiet)
        out[f"cube_seconds_{name}"] = _median_time(cube.build, s, contact, oxide, quiet)
        out[f"n_cells_{name}"] = s.n_cells
    out["ratio_auto_to_window_0.4"] = out["cube_seconds_auto"] / out["cube_seconds_window_0.4"]
    return out


def run(scenario: Scenario) -> dict[str, Any]:
    """The scaling table (the scenario's own settings are not used: the table is fixed)."""
    rows = []
    for eta in ETAS:
        s = _scene(eta)
        n = s.n_cells
        paper_study = resolve(load_scenario("paper", {"roughness.eta": eta}))
        estimates = {e.stage: e for e in plan.estimate(paper_study)}
        row = {
            "eta": eta,
            "L": n,
            "auto_method": constriction.auto_method(n),
            "block_size": constriction.block_size(n),
            "per_map_seconds": _per_map(n),
            **_simulation(s),
            "paper_study_estimate": {
                "cube_seconds": estimates["cube"].seconds,
                "cube_peak_mib": estimates["cube"].peak_bytes / 2**20,
                "oxide_peak_mib": estimates["oxide"].peak_bytes / 2**20,
            },
        }
        rows.append(row)
    ref = next(r for r in rows if r["L"] >= 100)
    for r in rows:
        model = (r["L"] ** 2 * math.log(r["L"])) / (ref["L"] ** 2 * math.log(ref["L"]))
        r["growth_vs_L113"] = r["seconds_per_simulation"] / ref["seconds_per_simulation"]
        r["L2logL_growth_vs_L113"] = model
        r["L3_growth_vs_L113"] = (r["L"] / ref["L"]) ** 3
    largest = rows[-1]
    return {
        "machine_note": "2 shared cores; per-map and per-simulation times are one thread",
        "fft_from_cells": constriction.FFT_FROM,
        "work_bytes_per_thread": constriction.WORK_BYTES,
        "padded_length_largest": fft.padded_length(largest["L"]),
        "table": rows,
        "default_scene": _default_ratio(),
    }
