"""``g2tom surface`` timed on its reference case, and one position on g2tom's solver against tamaas'.

The case: a 1 mm sphere of hard gold (E* of the pair, elastic) on a synthetic self-affine map (H 0.8,
rms 0.3 um, 1024^2 pixels of 0.5 um), a 256^2 window, 10 forces from 0.02 to 3 N, 16 positions and
8 oxide fields each (xi 0.3, l_O 5 um): its wall time on every core (one run: it takes about a
minute). Then the first position's work (every force, the clean and oxidized conductances) on
g2tom's operator and on tamaas' (the ``reference`` extra) with the same inputs: medians of
:data:`REPEATS`, the ratio tamaas over ours, and the largest relative difference of R.
"""

from __future__ import annotations

import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

from g2tom.config import Scenario
from g2tom.reference import elastic, missing_extra, surfaces
from g2tom.surface import surface_resistance
from g2tom.surface.oxide import oxide_masks
from g2tom.surface.run import prepare
from g2tom.surface.solve import solve_position
from g2tom.surface.study import SurfaceStudy, study_of
from g2tom.before_work import load_scenario

__all__ = ["CASE", "PAIR", "REPEATS", "write_map", "first_position", "run"]

#: The reference case: map pixels a side, pixel (m), window (pixels), forces (N), positions, fields.
CASE = {"map": 1024, "pixel": 0.5e-6, "window": 256, "forces": [float(f) for f in np.geomspace(0.02, 3.0, 10)],
        "positions": 16, "fields": 8, "xi": [0.3], "correlation_length": [5e-6], "rms": 0.3e-6}
#: The pair and the sphere.
PAIR = {"material.bodies": ["hard_gold"], "material.hardness": "none", "indenter.radius": 1e-3}
#: Timed repeats of one position on each solver.
REPEATS = 3


def write_map(folder: Path, refine: int = 1) -> Path:
    """The case's map, its pixel divided by ``refine`` on the same side (finer content of the same
    spectrum, the same rms), saved as ``.npy`` in ``folder``."""
    n, pixel = CASE["map"] * refine, CASE["pixel"] / refine
    rng = np.random.default_rng(20261129)
    heights = surfaces.random_process(n, pixel, 0.8, 8 * np.pi / (n * pixel), np.pi / (2 * pixel), CASE["rms"], rng)
    path = folder / f"self_affine_{refine}.npy"
    np.save(path, heights)
    return path


def first_position(path: Path, refine: int = 1) -> tuple[SurfaceStudy, np.ndarray, np.ndarray]:
    """The case's study, its first position's window of heights (m, (n, n)) and oxide masks, on the
    map of :func:`write_map` with ``refine`` (the window ``refine`` times the case's)."""
    scenario = load_scenario("paper", PAIR, rough_scene=False)
    study = study_of(scenario, CASE["forces"], xi=CASE["xi"], correlation_lengths=CASE["correlation_length"],
                     fields=CASE["fields"], positions=1, window=CASE["window"] * refine)
    pixel = CASE["pixel"] / refine
    prepared = prepare(study, [path], pixel)
    (row, col), n = prepared.positions.corners[0], prepared.n
    return study, prepared.surface.heights[row:row + n, col:col + n], oxide_masks(study, n, pixel, 0)


def _one_position(path: Path, solver: str) -> tuple[float, np.ndarray]:
    """Median seconds of the first position's work on ``solver``, and its resistances (clean, then oxidized)."""
    study, window, masks = first_position(path)
    n = window.shape[0]
    seconds, result = [], None
    for _ in range(REPEATS):
        operator = elastic.free_surface(n, CASE["pixel"], study.e_star, "cpu", solver)
        start = time.perf_counter()
        result = solve_position(study, operator, window, masks)
        seconds.append(time.perf_counter() - start)
    return float(np.median(seconds)), np.concatenate([result.resistance_clean, result.resistance.ravel()])


def run(scenario: Scenario) -> dict[str, Any]:
    """The case's wall time and the per-position comparison (``scenario`` names the study only)."""
    with tempfile.TemporaryDirectory() as folder:
        path = write_map(Path(folder))
        start = time.perf_counter()
        ds = surface_resistance(path, CASE["forces"], xi=CASE["xi"], correlation_length=CASE["correlation_length"],
                                overrides=PAIR, pixel_size=CASE["pixel"], fields=CASE["fields"],
                                positions=CASE["positions"], window=CASE["window"])
        out: dict[str, Any] = {"case": CASE, "seconds": time.perf_counter() - start,
                               "solved": int(ds["solved"].sum()), "solves": int(ds["solved"].size)}
        ours, r_ours = _one_position(path, "g2tom")
        out["position_seconds_g2tom"] = ours
        why = missing_extra()
        if why is not None:
            out["tamaas"] = f"skipped: {why}"
            return out
        theirs, r_theirs = _one_position(path, "tamaas")
        out.update(position_seconds_tamaas=theirs, ratio_tamaas_over_g2tom=theirs / ours,
                   largest_relative_difference=float(np.nanmax(np.abs(r_ours / r_theirs - 1))))
    return out
