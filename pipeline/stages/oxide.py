"""Stage 2: oxide ensembles, thresholded Gaussian random fields over lambda and realization.

One unit-variance field per (lambda, realization) is evaluated exactly at the cell centres
(:mod:`g2tom.physics.oxide_field`) and serves every oxide fraction xi. A cell is OXIDE where
``psi >= threshold`` and CONDUCTING where ``psi < threshold``, comparing the stored float32
values, so later stages rebuild bit-identical masks from ``psi`` and ``threshold``.

Threshold rules (``oxide.threshold``):

* ``theoretical``: ``psi0 = sqrt(2) erfcinv(2 xi)``, the same for every field.
* ``empirical``: each field's own quantile: the ``K``-th largest of its N float32 cell values,
  ``K = round(xi N)`` (half to even), so exactly K cells are covered (unless float32 values tie
  at the threshold, when every tied cell is covered).

Every field has its own random stream (``oxide_band.field_stream``), so ``psi`` does not depend
on the dask chunking, the scheduler, the worker count or the order of evaluation.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

import dask.array as da
import numpy as np
import xarray as xr

from g2tom import store
from g2tom.before_work.domains import resolved
from g2tom.compute import ComputeOptions, compute, single_threaded
from g2tom.config import CHUNK_BYTES, ResolvedScenario, Scenario
from g2tom.physics.grid import cell_centres
from g2tom.scene import FieldSource, bands, threshold_block
from g2tom.stages.schema import variable

__all__ = ["build", "run", "RecordedFields", "recorded_realizations"]


def recorded_realizations(scenario: Scenario) -> int:
    """Fields per lambda kept in oxide.nc: the fixed count, or the adaptive ensemble's first batch."""
    ox = scenario.oxide
    return ox.n_realizations if ox.ensemble == "fixed" else ox.min_realizations


#: Largest record of fields (bytes) the cube serves from oxide.nc instead of regenerating them
#: (a local cluster ships it to each worker once).
RECORD_BYTES = 256 * 2**20


@dataclass(frozen=True)
class RecordedFields:
    """oxide.nc's record in front of the :class:`FieldSource` that made it: the recorded
    realizations are served as stored (bit-identical to regenerating them), later ones are
    regenerated. Same interface as :class:`FieldSource` for the cube's tasks."""

    source: FieldSource
    psi: np.ndarray  # float32 (lambda, realization, y, x)
    threshold: np.ndarray  # float32 (xi, lambda, realization)

    @classmethod
    def of(cls, scenario: ResolvedScenario, record: xr.Dataset, limit: int = RECORD_BYTES) -> "FieldSource | RecordedFields":
        """The record of ``scenario``'s fields in front of its source, or the bare source when
        the record exceeds ``limit`` bytes (tasks then regenerate every field, bounding memory)."""
        source = FieldSource.of(scenario)
        psi = record["psi"].transpose("lambda", "realization", "y", "x").values
        if psi.nbytes > limit:
            return source
        return cls(source, psi, record["threshold"].transpose("xi", "lambda", "realization").values)

    @property
    def lambdas(self) -> tuple[float, ...]:
        return self.source.lambdas

    @property
    def xi(self) -> np.ndarray:
        return self.source.xi

    def fields(self, index: int, realizations: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """As :meth:`FieldSource.fields`: from the record when it holds every realization asked."""
        if realizations.size and int(realizations.max()) < self.psi.shape[1]:
            return self.psi[index, realizations], self.threshold[:, index, realizations]
        return self.source.fields(index, realizations)

    def thresholds(self, index: int, realizations: np.ndarray) -> np.ndarray:
        """As :meth:`FieldSource.thresholds`: from the record when it holds every realization asked."""
        if realizations.size and int(realizations.max()) < self.psi.shape[1]:
            return self.threshold[:, index, realizations]
        return self.source.thresholds(index, realizations)


#: Working memory of the field synthesis, bytes per cell and realization (measured: 336 MiB
#: beyond the result for 50 fields of 229^2 cells), and the most a chunk's synthesis may use.
FIELD_WORK_PER_CELL = 128
FIELD_WORK_BYTES = 64 * 2**20


def _psi_block(realizations: np.ndarray, *, source: FieldSource) -> np.ndarray:
    """Fields of a chunk of realizations at every lambda: float32 (lambda, realization, y, x)."""
    out = np.empty((len(source.lambdas), realizations.size, source.n_cells, source.n_cells), np.float32)
    # a few realizations at a time: each field is independent of its batch, bit for bit
    step = max(1, FIELD_WORK_BYTES // (FIELD_WORK_PER_CELL * source.n_cells**2))
    for a in range(len(source.lambdas)):
        for start in range(0, realizations.size, step):
            out[a, start : start + step] = source.psi(a, realizations[start : start + step])
    return out


def _fraction_block(psi: np.ndarray, threshold: np.ndarray) -> np.ndarray:
    """Covered fraction (xi, lambda, realization) of the cell centres: mean of psi >= threshold."""
    flat = psi.reshape(psi.shape[:2] + (-1,))
    counts = np.stack([(flat >= t[..., None]).sum(axis=-1) for t in threshold])  # one xi at a time
    return counts / flat.shape[-1]


def _lazy(scenario: ResolvedScenario) -> tuple[da.Array, da.Array, da.Array]:
    """Dask arrays psi, threshold and oxide_fraction, chunked over realization."""
    ox = scenario.oxide
    n = scenario.n_cells
    xi = np.asarray(ox.xi, dtype=float)
    # at most compute.oxide_chunk realizations per chunk, fewer where a chunk's fields would pass CHUNK_BYTES
    chunk = min(scenario.compute.oxide_chunk, max(1, CHUNK_BYTES // (4 * len(ox.lambda_) * n * n)))
    realization = da.arange(recorded_realizations(scenario), chunks=chunk)
    psi = da.map_blocks(
        _psi_block,
        realization,
        source=FieldSource.of(scenario),
        new_axis=[0, 2, 3],
        chunks=((len(ox.lambda_),), realization.chunks[0], (n,), (n,)),
        dtype=np.float32,
        meta=np.empty((0, 0, 0, 0), np.float32),
    )
    # Index letters: z = xi, l = lambda, r = realization; y, x are reduced (one chunk each).
    threshold = da.blockwise(
        threshold_block, "zlr", psi, "lryx",
        xi=xi, rule=ox.threshold, new_axes={"z": xi.size}, concatenate=True,
        dtype=np.float32, meta=np.empty((0, 0, 0), np.float32),
    )
    fraction = da.blockwise(
        _fraction_block, "zlr", psi, "lryx", threshold, "zlr",
        concatenate=True, dtype=np.float64, meta=np.empty((0, 0, 0), np.float64),
    )
    return psi, threshold, fraction


def _dataset(scenario: ResolvedScenario, psi: np.ndarray, threshold: np.ndarray, fraction: np.ndarray) -> xr.Dataset:
    """Wrap the computed arrays with coordinates and attributes."""
    ox = scenario.oxide
    centres = cell_centres(scenario.n_cells, scenario.cell_size)
    modes = bands(scenario)
    lambdas = np.asarray(ox.lambda_, float)
    coords = {
        "lambda": variable("oxide", "lambda", lambdas),
        "realization": variable("oxide", "realization", np.arange(recorded_realizations(scenario))),
        "xi": variable("oxide", "xi", np.asarray(ox.xi, float)),
        "y": variable("oxide", "y", centres),
        "x": variable("oxide", "x", centres),
        "correlation_length": variable("oxide", "correlation_length", lambdas * scenario.cell_size),
    }
    data_vars = {
        "psi": variable("oxide", "psi", psi,
                        comment="oxide where psi >= threshold, conducting where psi < threshold (float32)"),
        "threshold": variable("oxide", "threshold", threshold, rule=ox.threshold),
        "oxide_fraction": variable("oxide", "oxide_fraction", fraction),
        "n_modes": variable("oxide", "n_modes", np.array([m.size for m in modes])),
        "period_cells": variable("oxide", "period_cells", np.array([int(round(m.period / scenario.cell_size)) for m in modes])),
    }
    dataset_attrs = {
        "oxide_rule": "a cell is oxide where psi >= threshold (float32 comparison)",
        "field_normalization": (
            "sum |c_k|^2 / 2 = 1: unit variance of the continuous spectrum over the field's whole "
            "period (not each realization's sample variance over the window)"
        ),
        "field_period": ox.period,
        "ensemble": ox.ensemble,
        "recorded_realizations": (
            "every realization of the fixed ensemble" if ox.ensemble == "fixed"
            else "the adaptive ensemble's first batch; the cube regenerates every field from its seed"
        ),
        "random_streams": "SeedSequence(oxide.seed, spawn_key=(round(lambda * 1e6), realization))",
    }
    return xr.Dataset(data_vars, coords=coords, attrs=dataset_attrs)


@single_threaded
def build(scenario: Scenario, options: ComputeOptions = ComputeOptions(progress=False)) -> xr.Dataset:
    """Compute the oxide ensemble of ``scenario`` with dask over realization chunks.

    Parameters
    ----------
    scenario
        The scenario (section ``oxide``, the cell grid; resolved first where it is not:
        :func:`g2tom.before_work.domains.resolved`).
    options
        Where dask runs (see :func:`g2tom.compute.compute`).

    Returns
    -------
    xarray.Dataset
        In memory: ``psi`` (lambda, realization, y, x) float32, ``threshold`` and
        ``oxide_fraction`` (xi, lambda, realization), ``n_modes`` (lambda).
    """
    scenario = resolved(scenario)
    psi, threshold, fraction = _lazy(scenario)
    return _dataset(scenario, *_computed(psi, threshold, fraction, options))


#: Realization chunks computed per call, per worker. Each chunk comes back on its own and is
#: copied into one preallocated array, so the peak holds the ensemble once plus a chunk per
#: worker (one call over all chunks also held them all once more while they were joined:
#: 2.9 GB for 500 fields of 229^2 cells per lambda).
CHUNKS_PER_WORKER = 1


def _computed(
    psi: da.Array, threshold: da.Array, fraction: da.Array, options: ComputeOptions
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The three arrays computed a group of realization chunks at a time, into preallocated arrays."""
    out = tuple(np.empty(a.shape, a.dtype) for a in (psi, threshold, fraction))
    bounds = np.cumsum((0,) + psi.chunks[1])
    n_chunks = len(psi.chunks[1])
    step = CHUNKS_PER_WORKER * max(1, options.workers or os.cpu_count() or 1)
    groups = range(0, n_chunks, step)
    for number, first in enumerate(groups, start=1):
        chunks = range(first, min(first + step, n_chunks))
        label = "oxide fields" + (f" (part {number} of {len(groups)})" if len(groups) > 1 else "")
        parts = compute(*[block for i in chunks for block in
                          (psi.blocks[:, i], threshold.blocks[:, :, i], fraction.blocks[:, :, i])],
                        options=options, label=label)
        for i, (p, t, f) in zip(chunks, zip(parts[0::3], parts[1::3], parts[2::3])):
            r = slice(int(bounds[i]), int(bounds[i + 1]))
            out[0][:, r], out[1][:, :, r], out[2][:, :, r] = p, t, f
    return out


@single_threaded
def run(scenario: Scenario, data_dir: str | Path, options: ComputeOptions) -> Path:
    """Build the ensemble and write ``<data_dir>/oxide.nc`` atomically; return its path."""
    return store.write_dataset(build(scenario, options), data_dir, "oxide", scenario)
