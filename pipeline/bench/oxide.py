"""Benchmark of the oxide fields: cost per field and per lambda, against direct summation.

The stage evaluates every field exactly at the cell centres: by folding onto one n x n FFT when
the period is the window, by separable partial DFTs (two GEMMs) for a spectral period. The
reference is the direct sum of every mode at every centre (:func:`oxide_field.field_at_points`),
timed on a few fields per lambda; its agreement with the stored float32 values is the error
column.
"""

from __future__ import annotations

import statistics
import time
from typing import Any

import numpy as np

from g2tom.compute import ComputeOptions
from g2tom.config import ResolvedScenario
from g2tom.physics import oxide_band, oxide_field
from g2tom.physics.grid import cell_centres
from g2tom.scene import FieldSource, bands
from g2tom.stages import oxide

__all__ = ["run"]

#: Repetitions of the whole stage build (the median is reported).
REPEATS = 3
#: Fields per lambda timed for the per-lambda cost.
PER_LAMBDA_FIELDS = 100
#: Fields per lambda in the direct-summation subset.
SUBSET_REALIZATIONS = 2


def _per_lambda(scenario: ResolvedScenario) -> list[dict[str, Any]]:
    """Seconds per field (stream, coefficients, evaluation, thresholds) at every lambda."""
    source = FieldSource.of(scenario)
    rows = []
    for a, (lam, modes) in enumerate(zip(source.lambdas, source.modes)):
        start = time.perf_counter()
        source.fields(a, np.arange(PER_LAMBDA_FIELDS))
        seconds = (time.perf_counter() - start) / PER_LAMBDA_FIELDS
        rows.append({"lambda": lam, "period_cells": int(round(modes.period / scenario.cell_size)),
                     "n_modes": modes.size, "seconds_per_field": seconds})
    return rows


def _direct_subset(scenario: ResolvedScenario, psi: np.ndarray) -> tuple[float, float]:
    """Time the direct summation of a subset; return (seconds per field, max error)."""
    ox = scenario.oxide
    x = cell_centres(scenario.n_cells, scenario.cell_size)
    fields, error = 0, 0.0
    start = time.perf_counter()
    for a, (lam, modes) in enumerate(zip(ox.lambda_, bands(scenario))):
        for r in range(min(SUBSET_REALIZATIONS, psi.shape[1])):
            coeffs = oxide_band.coefficients(modes, oxide_band.field_stream(ox.seed, lam, r), ox.amplitudes)
            direct = oxide_field.field_at_points(modes, coeffs, x[None, :], x[:, None])
            error = max(error, float(np.max(np.abs(direct - psi[a, r]))))
            fields += 1
    return (time.perf_counter() - start) / fields, error


def run(scenario: ResolvedScenario) -> dict[str, Any]:
    """Median wall time of the stage build, per-field and per-lambda cost, the direct comparison.

    Returns
    -------
    dict
        ``stage_seconds`` (median over :data:`REPEATS` builds of oxide.nc, threaded scheduler),
        ``per_field_seconds``, ``per_lambda`` (period, modes and seconds per field at every
        lambda, single thread), ``direct_per_field_seconds`` (direct summation of a subset),
        ``speedup_per_field`` and ``direct_subset_max_abs_error`` (stored float32 psi against
        the direct sum).
    """
    ox = scenario.oxide
    options = ComputeOptions(progress=False)
    times = []
    for _ in range(REPEATS):
        start = time.perf_counter()
        ds = oxide.build(scenario, options)
        times.append(time.perf_counter() - start)
    stage = statistics.median(times)
    n_fields = len(ox.lambda_) * ds.sizes["realization"]
    direct_per_field, error = _direct_subset(scenario, ds["psi"].values)
    per_lambda = _per_lambda(scenario)
    per_field = stage / n_fields
    return {
        "n_lambda": len(ox.lambda_),
        "n_realizations": ds.sizes["realization"],
        "n_cells": scenario.n_cells,
        "period": ox.period,
        "stage_seconds": stage,
        "stage_seconds_all": times,
        "per_field_seconds": per_field,
        "per_lambda": per_lambda,
        "direct_subset_fields": len(ox.lambda_) * min(SUBSET_REALIZATIONS, ds.sizes["realization"]),
        "direct_per_field_seconds": direct_per_field,
        "speedup_per_field": direct_per_field / per_field,
        "direct_subset_max_abs_error": error,
    }
