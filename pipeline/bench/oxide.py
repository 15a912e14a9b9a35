"""Benchmark of the oxide stage: folded cell-grid fields against a fine-image synthesis.

The stage evaluates every field exactly at the cell centres with one n x n FFT. The reference
is what an image-based code does: synthesise each field on a fine image (about 1024^2 pixels)
and read it at the centres. The fine image's side is the multiple of ``n_cells`` nearest to
1024 (1026 for 57 cells) so that its pixels contain the centres exactly and the error column
compares like with like.
"""

from __future__ import annotations

import statistics
import time
from typing import Any

import numpy as np

from pipeline.compute import ComputeOptions
from pipeline.config import Scenario
from pipeline.physics import oxide_field
from pipeline.stages import oxide

__all__ = ["run"]

#: Repetitions of the whole stage build (the median is reported).
REPEATS = 3
#: Target side of the fine reference image, in pixels.
FINE_PIXELS = 1024
#: Realizations per lambda in the fine-image subset.
SUBSET_REALIZATIONS = 2


def _fine_side(n_cells: int) -> int:
    """The multiple of ``n_cells`` nearest to :data:`FINE_PIXELS`."""
    return n_cells * max(1, round(FINE_PIXELS / n_cells))


def _fine_subset(scenario: Scenario, psi: np.ndarray) -> tuple[float, float, int]:
    """Time the fine-image synthesis of a subset; return (seconds per field, max error, side)."""
    ox = scenario.oxide
    n = scenario.n_cells
    side = _fine_side(n)
    stride = side // n
    # Pixel q * stride lies at centre offset q (mod n); fftshift puts centre p at index p.
    take = np.fft.fftshift(np.arange(n) * stride)
    fields, error = 0, 0.0
    start = time.perf_counter()
    for a, (lam, modes) in enumerate(zip(ox.lambda_, oxide.bands(scenario))):
        for r in range(min(SUBSET_REALIZATIONS, ox.n_realizations)):
            coeffs = oxide_field.coefficients(modes, oxide_field.field_stream(ox.seed, lam, r), ox.amplitudes)
            image = oxide_field.fine_grid(modes, coeffs, side)
            error = max(error, float(np.max(np.abs(image[np.ix_(take, take)] - psi[a, r]))))
            fields += 1
    return (time.perf_counter() - start) / fields, error, side


def run(scenario: Scenario) -> dict[str, Any]:
    """Median wall time of the stage build, per-field cost, and the fine-image comparison.

    Returns
    -------
    dict
        ``stage_seconds`` (median of the build over :data:`REPEATS` runs, threaded scheduler),
        ``per_field_seconds``, ``fine_per_field_seconds`` (fine-image synthesis of a subset),
        ``speedup_per_field`` (their ratio), ``fine_subset_max_abs_error`` (stored float32 psi
        against the fine image at the centres) and the sizes involved.
    """
    ox = scenario.oxide
    options = ComputeOptions(progress=False)
    times = []
    for _ in range(REPEATS):
        start = time.perf_counter()
        ds = oxide.build(scenario, options)
        times.append(time.perf_counter() - start)
    stage = statistics.median(times)
    n_fields = len(ox.lambda_) * ox.n_realizations
    fine_per_field, error, side = _fine_subset(scenario, ds["psi"].values)
    per_field = stage / n_fields
    return {
        "n_lambda": len(ox.lambda_),
        "n_realizations": ox.n_realizations,
        "n_cells": scenario.n_cells,
        "stage_seconds": stage,
        "stage_seconds_all": times,
        "per_field_seconds": per_field,
        "fine_pixels": side,
        "fine_subset_fields": len(ox.lambda_) * min(SUBSET_REALIZATIONS, ox.n_realizations),
        "fine_per_field_seconds": fine_per_field,
        "fine_stage_estimate_seconds": fine_per_field * n_fields,
        "speedup_per_field": fine_per_field / per_field,
        "fine_subset_max_abs_error": error,
    }
