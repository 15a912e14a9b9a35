"""Benchmark of the cost's growth with the cell count: the scaling table of ``make bench``.

For windows of about L = 57, 113, 227 and 453 cells a side (eta = 2e8 x 1, 4, 16, 64 with
``auto`` windows), it measures

* each interaction algorithm per map (folded DFT-GEMM ~ L^3, padded FFT ~ L^2 log L), one
  thread, and which one ``auto`` takes (:func:`g2tom.physics.interaction.auto_method`);
* the time per simulation (one oxide mask at one load step) of the cube's kernel
  (:func:`g2tom.physics.constriction.resistance` with the scenario's crops), on real
  oxide masks, and its growth from L = 113 against L^2 log L;
* the plan's memory and time estimates of the paper's full study on each scene;
* the paper's scene against today's 57-cell window (the ``published`` window, 0.4 R*): the
  cube's time ratio in this one run.

All times are medians of :data:`REPEATS` runs in this process; the machine is shared.
"""

from __future__ import annotations

import math
import statistics
import time
from typing import Any

import numpy as np

from g2tom.before_work import plan
from g2tom.compute import ComputeOptions
from g2tom.config import ResolvedScenario, Scenario
from g2tom.before_work import load_scenario
from g2tom.before_work.domains import resolve
from g2tom.physics import constriction, interaction
from g2tom.physics.crops import choose_crops
from g2tom.physics.spot_geometry import SpotGeometry
from g2tom.physics import interaction_fft as fft
from g2tom.stages import contact as contact_stage
from g2tom.stages import cube
from g2tom.stages import oxide as oxide_stage

__all__ = ["run", "ETAS"]

#: Asperity densities of the table (m^-2): windows of about 57, 113, 227 and 453 cells.
ETAS: tuple[float, ...] = (2e8, 8e8, 3.2e9, 1.28e10)
REPEATS = 3
#: Oxide masks timed per size (two lambdas x realizations at xi = 0.5).
N_MASKS = 16
#: Study used for the default-scene ratio (realizations of the paper's 9 x 12 grid).
RATIO_REALIZATIONS = 25


def _timed(func: Any, *args: Any) -> float:
    start = time.perf_counter()
    func(*args)
    return time.perf_counter() - start


def _scene(eta: float) -> ResolvedScenario:
    return resolve(load_scenario("paper_gt", {"roughness.eta": eta, "oxide.xi": [0.5], "oxide.lambda": [5.0, 13.0],
                                           "oxide.n_realizations": N_MASKS // 2, "compute.oxide_chunk": N_MASKS}))


def _kernel_inputs(s: ResolvedScenario) -> tuple:
    """The cube kernel's arguments (masks, spots, rho) on the scene's real masks (tiled to whole
    blocks) and crops."""
    quiet = ComputeOptions(progress=False)
    contact, oxide = contact_stage.build(s), oxide_stage.build(s, quiet)
    radius, weights, pitch = cube.spot_maps(s, contact)
    psi = oxide["psi"].transpose("lambda", "realization", "y", "x").values
    thr = oxide["threshold"].transpose("xi", "lambda", "realization").values
    masks = (psi[None] < thr[..., None, None]).reshape(-1, s.n_cells, s.n_cells)
    block = interaction.block_size(s.n_cells)
    count = block * math.ceil(masks.shape[0] / block)  # no padded (wasted) maps in the timing
    masks = masks[np.arange(count) % masks.shape[0]]
    crops = choose_crops(radius, weights, pitch, s.cube.crop_tolerance)
    return masks, SpotGeometry(radius, weights, pitch, crops, s.cube.crop_tolerance), s.material.rho


def _interleaved(jobs: dict[str, tuple]) -> dict[str, float]:
    """Median wall time of each ``(func, *args)`` job, the jobs run in turn :data:`REPEATS` times
    (so a change of the shared machine's load affects all of them alike)."""
    for func, *args in jobs.values():
        func(*args)  # warm-up: operators and scratch built outside the timing
    times: dict[str, list[float]] = {name: [] for name in jobs}
    for _ in range(REPEATS):
        for name, (func, *args) in jobs.items():
            times[name].append(_timed(func, *args))
    return {name: statistics.median(t) for name, t in times.items()}


def _default_ratio() -> dict[str, Any]:
    """Cube time of the paper's scene (auto window) against today's 0.4 R* window, interleaved."""
    quiet = ComputeOptions(progress=False)
    sets = {"oxide.ensemble": "fixed", "oxide.n_realizations": RATIO_REALIZATIONS}
    scenes = {"auto": resolve(load_scenario("paper_gt", sets)),
              "window_0.4": resolve(load_scenario("paper_gt", {**sets, "contact.window": 0.4, "contact.r_max": 0.3}))}
    jobs = {name: (cube.build, s, contact_stage.build(s), oxide_stage.build(s, quiet), quiet)
            for name, s in scenes.items()}
    seconds = _interleaved(jobs)
    out: dict[str, Any] = {}
    for name, s in scenes.items():
        out[f"cube_seconds_{name}"] = seconds[name]
        out[f"n_cells_{name}"] = s.n_cells
    out["ratio_auto_to_window_0.4"] = seconds["auto"] / seconds["window_0.4"]
    return out


def run(scenario: Scenario) -> dict[str, Any]:
    """The scaling table (the scenario's own settings are not used: the table is fixed)."""
    scenes = [_scene(eta) for eta in ETAS]
    rng = np.random.default_rng(0)
    jobs: dict[str, tuple] = {}
    inputs = {}
    for s in scenes:
        n = s.n_cells
        u = rng.random((interaction.block_size(n), n, n))
        for name in ("folded", "fft"):
            jobs[f"{n}_{name}"] = (interaction.interaction_sum, u, 1.0, name)
        inputs[n] = _kernel_inputs(s)
        jobs[f"{n}_simulation"] = (constriction.resistance, *inputs[n])
    seconds = _interleaved(jobs)
    rows = []
    for s, eta in zip(scenes, ETAS):
        n = s.n_cells
        masks, spots, _ = inputs[n]
        block = interaction.block_size(n)
        estimates = {e.stage: e for e in plan.estimate(resolve(load_scenario("paper_gt", {"roughness.eta": eta})))}
        rows.append({
            "eta": eta,
            "L": n,
            "auto_method": interaction.auto_method(n),
            "block_size": block,
            "per_map_seconds": {name: seconds[f"{n}_{name}"] / block for name in ("folded", "fft")},
            "seconds_per_simulation": seconds[f"{n}_simulation"] / (masks.shape[0] * spots.radius.shape[0]),
            "crop_cells_max": int(spots.crops.max()),
            "crop_cells_min": int(spots.crops.min()),
            "paper_study_estimate": {
                "cube_seconds": estimates["cube"].seconds,
                "cube_peak_mib": estimates["cube"].peak_bytes / 2**20,
                "oxide_peak_mib": estimates["oxide"].peak_bytes / 2**20,
            },
        })
    ref = next(r for r in rows if r["L"] >= 100)
    for r in rows:
        r["growth_vs_L113"] = r["seconds_per_simulation"] / ref["seconds_per_simulation"]
        r["L2logL_growth_vs_L113"] = (r["L"] ** 2 * math.log(r["L"])) / (ref["L"] ** 2 * math.log(ref["L"]))
        r["L3_growth_vs_L113"] = (r["L"] / ref["L"]) ** 3
    return {
        "machine_note": "2 shared cores; one thread; sizes and paths timed in turn, medians",
        "fft_from_cells": interaction.FFT_FROM,
        "work_bytes_per_thread": interaction.WORK_BYTES,
        "padded_length_largest": fft.padded_length(rows[-1]["L"]),
        "table": rows,
        "default_scene": _default_ratio(),
    }
