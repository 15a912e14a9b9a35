"""``g2tom surface`` on a GPU against the CPU: one position per window size, same inputs, same run.

The case of :mod:`g2tom.bench.surface` (a 1 mm hard-gold sphere, elastic, on a self-affine map of
H 0.8 and rms 0.3 um, 10 forces from 0.02 to 3 N, 8 oxide fields of xi 0.3 and l_O 5 um) on the same
map side at the pixels 0.5, 0.25 and 0.125 um (:data:`REFINE`): the same contacts on windows of 256^2,
512^2 and 1024^2 pixels. For each, the first position's whole work (every force; the clean and the 8
oxidized conductances) on the GPU, the median of :data:`REPEATS` after one untimed warm-up (cuFFT
plans, kernel compilation); at 256^2 also on the CPU (NumPy, one run; a position takes minutes there
on the larger windows), their ratio and the largest relative difference of R. Then the whole study on
1024^2 windows (:data:`STUDY_POSITIONS` positions) on the GPU, one run. Without a GPU it says so and
measures nothing.
"""

from __future__ import annotations

import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

from g2tom.bench.surface import CASE, PAIR, first_position, write_map
from g2tom.config import Scenario
from g2tom.reference import devices
from g2tom.reference.fft_surface import fft_surface
from g2tom.surface import surface_resistance
from g2tom.surface.solve import PositionResult, solve_position
from g2tom.surface.study import SurfaceStudy

__all__ = ["REFINE", "REPEATS", "STUDY_POSITIONS", "run"]

#: Pixel refinements of the case's map (window 256^2 times each).
REFINE = (1, 2, 4)
#: Timed repeats of a position on the GPU.
REPEATS = 2
#: Positions of the whole study on the largest windows.
STUDY_POSITIONS = 4


def _timed(study: SurfaceStudy, window: np.ndarray, masks: np.ndarray, pixel: float,
           device: str) -> tuple[float, PositionResult]:
    """Seconds of one position's work on ``device`` (a fresh operator), and its result."""
    operator = fft_surface(window.shape[0], pixel, study.e_star, devices.namespace(device))
    start = time.perf_counter()
    result = solve_position(study, operator, window, masks)
    return time.perf_counter() - start, result


def _resistances(result: PositionResult) -> np.ndarray:
    return np.concatenate([result.resistance_clean, result.resistance.ravel()])


def _row(path: Path, refine: int) -> dict[str, Any]:
    """One window size: the GPU's median position; on the smallest, the CPU's and their differences."""
    study, window, masks = first_position(path, refine)
    pixel = CASE["pixel"] / refine
    _timed(study, window, masks, pixel, "gpu")  # warm-up
    runs = [_timed(study, window, masks, pixel, "gpu") for _ in range(REPEATS)]
    gpu_seconds = float(np.median([seconds for seconds, _ in runs]))
    on_gpu = runs[0][1]
    row: dict[str, Any] = {"window": int(window.shape[0]), "pixel_m": pixel, "gpu_position_seconds": gpu_seconds,
                           "gpu_solved": int(np.isfinite(on_gpu.resistance_clean).sum())}
    if refine == REFINE[0]:
        cpu_seconds, on_cpu = _timed(study, window, masks, pixel, "cpu")
        ours, theirs = _resistances(on_gpu), _resistances(on_cpu)
        both = np.isfinite(ours) & np.isfinite(theirs)
        row.update(cpu_position_seconds=cpu_seconds, ratio_cpu_over_gpu=cpu_seconds / gpu_seconds,
                   largest_relative_difference=float(np.max(np.abs(ours[both] / theirs[both] - 1))))
    return row


def run(scenario: Scenario) -> dict[str, Any]:
    """Rows by window size and the whole study on the largest, or why nothing was measured
    (``scenario`` names the study only)."""
    why = devices.gpu_missing()
    if why is not None:
        return {"skipped": f"no GPU: {why}"}
    with tempfile.TemporaryDirectory() as folder:
        rows = []
        for refine in REFINE:
            path = write_map(Path(folder), refine)
            rows.append(_row(path, refine))
        largest = REFINE[-1]
        start = time.perf_counter()
        ds = surface_resistance(path, CASE["forces"], xi=CASE["xi"], correlation_length=CASE["correlation_length"],
                                overrides=PAIR, pixel_size=CASE["pixel"] / largest, fields=CASE["fields"],
                                positions=STUDY_POSITIONS, window=CASE["window"] * largest, device="gpu")
        study = {"window": CASE["window"] * largest, "positions": STUDY_POSITIONS, "forces": len(CASE["forces"]),
                 "fields": CASE["fields"], "seconds": time.perf_counter() - start,
                 "solved": int(ds["solved"].sum()), "solves": int(ds["solved"].size)}
    return {"case": CASE, "rows": rows, "study": study}
