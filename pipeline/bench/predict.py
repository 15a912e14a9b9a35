"""Benchmark of the predictor: 10^5 vectorized queries against one query at a time.

Builds surrogate tables on the scenario's (lambda, xi) grid with a log-space rank-2 model and
smooth band tables (the timing does not depend on their values), times
:func:`g2tom.predict.predict` on 10^5 random queries inside the fitted ranges (median of
repeated runs), and, as the reference in the same process, the same predictor called once per
query on a few hundred of them; reports both, their ratio per query, and the largest relative
difference between the two on the common queries (they must agree). Beside it, the shipped atlas
surrogate (:func:`g2tom.predict.atlas.predict_atlas`) answering 10^5 queries spread over
:data:`_ATLAS_SURFACES` surfaces (the scenario's with other asperity densities, inside the atlas),
median of repeated runs.
"""

from __future__ import annotations

import dataclasses
import time
import warnings
from typing import Any

import numpy as np

from g2tom.bench.timing import median_time
from g2tom.config import Scenario
from g2tom.predict.atlas import load_atlas_surrogate, predict_atlas, shipped_path
from g2tom.predict.predictor import predict
from g2tom.stages.surrogate_file import CURVE_TABLE, GRID_TABLES, STEP_TABLES, SurrogateTables
from g2tom.scene import scene_groups

__all__ = ["run"]

_REPEATS = 5
_QUERIES = 100_000
_LOOP_QUERIES = 300
#: Surfaces the atlas timing spreads its queries over, and their asperity densities (m^-2): on the
#: paper's scene mu 4.1-7.9 and Pi 20-38, inside the shipped atlas.
_ATLAS_SURFACES = 10
_ATLAS_ETA = (1.0e8, 1.9e8)




def _tables(scenario: Scenario) -> SurrogateTables:
    lam, xi = np.asarray(scenario.oxide.lambda_, dtype=float), np.asarray(scenario.oxide.xi, dtype=float)
    force_n = np.geomspace(0.5, 20.0, 16)
    grid = np.add.outer(np.log(lam), -np.log1p(-xi))
    tables = {name: 0.01 * (1 + k) * (1 + 0.1 * grid) for k, name in enumerate(GRID_TABLES)}
    band = 0.8 - 0.02 * grid[..., None] * np.ones(force_n.size)
    tables.update(dict(zip(STEP_TABLES, (band, band, np.zeros_like(band), 0.01 * band))))
    # a curved clean-like law, ln R' = -0.5 - 0.5 ln F' + 0.03 (ln F')^2, shifted up with xi
    tables[CURVE_TABLE] = np.stack([-0.5 + 0.3 * grid, -0.5 - 0.02 * grid, 0.03 + 0.0 * grid, 0.0 * grid], axis=-1)
    coef = {
        "alpha": (np.array([[-1.2, 0.01, 0.01], [0.0, 0.1, -0.05]]), np.array([[1.2, -0.3], [0.05, 0.2]]), "log"),
        "gamma": (np.array([[-1.2]]), np.array([[1.2, -0.26]]), "log"),
    }
    ranges = {"xi": (xi.min(), xi.max()), "lambda": (lam.min(), lam.max()), "force_normalized": (force_n[0], force_n[-1])}
    scene = scene_groups(scenario)  # tables of the scenario's own surface
    return SurrogateTables(coef, lam, xi, force_n, ranges, tables, {"method": "bench", "mu": scene.mu, "Pi": scene.Pi})


def _atlas_seconds(scenario: Scenario) -> float | None:
    """Median seconds of 10^5 atlas-surrogate queries over :data:`_ATLAS_SURFACES` surfaces (each a
    tenth of them), None without a shipped atlas surrogate."""
    path = shipped_path()
    if path is None:
        return None
    surrogate = load_atlas_surrogate(path)
    rng = np.random.default_rng(np.random.SeedSequence(20240531))
    lo, hi = surrogate.domain["force_normalized"]
    share = _QUERIES // _ATLAS_SURFACES
    batches = []
    for eta in np.linspace(*_ATLAS_ETA, _ATLAS_SURFACES):
        surface = dataclasses.replace(scenario, roughness=dataclasses.replace(scenario.roughness, eta=float(eta)))
        force = np.exp(rng.uniform(np.log(lo), np.log(hi), share)) * surface.force_scale
        batches.append((surface, force, rng.uniform(*surrogate.domain["xi"], share),
                        rng.uniform(*surrogate.domain["lambda"], share)))
    seconds, _ = median_time(lambda: [predict_atlas(surrogate, *batch) for batch in batches], _REPEATS)
    return seconds


def run(scenario: Scenario) -> dict[str, Any]:
    """Time 10^5 vectorized predictions against one-at-a-time calls, and 10^5 atlas-surrogate
    predictions over ten surfaces; JSON-ready figures."""
    tables = _tables(scenario)
    rng = np.random.default_rng(np.random.SeedSequence(20240531))
    lo, hi = (r * scenario.force_scale for r in tables.ranges["force_normalized"])
    force = rng.uniform(lo, hi, _QUERIES)
    xi = rng.uniform(*tables.ranges["xi"], _QUERIES)
    lam = rng.uniform(*tables.ranges["lambda"], _QUERIES)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        vector_s, result = median_time(lambda: predict(tables, scenario, force, xi, lam), _REPEATS)
        start = time.perf_counter()
        single = [float(predict(tables, scenario, force[i], xi[i], lam[i])["resistance_mean_upper"]) for i in range(_LOOP_QUERIES)]
        loop_per_query = (time.perf_counter() - start) / _LOOP_QUERIES
    vector_per_query = vector_s / _QUERIES
    atlas_s = _atlas_seconds(scenario)
    return {
        "atlas_queries": _QUERIES,
        "atlas_surfaces": _ATLAS_SURFACES,
        "atlas_seconds": None if atlas_s is None else round(atlas_s, 4),
        "queries": _QUERIES,
        "vectorized_seconds": round(vector_s, 4),
        "vectorized_per_query_seconds": vector_per_query,
        "loop_per_query_seconds": loop_per_query,
        "speedup_per_query": round(loop_per_query / vector_per_query, 1),
        "max_rel_difference_upper": float(np.max(np.abs(np.array(single) / result["resistance_mean_upper"].values[:_LOOP_QUERIES] - 1))),
        "under_one_second": vector_s < 1.0,
    }
