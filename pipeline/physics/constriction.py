"""Greenwood's multi-spot constriction resistance (Eqs. 11-15) of partly oxidized spot sets.

For spots of radius ``a_i`` on a regular square cell grid of pitch ``h``, conducting states
``phi_i`` in {0, 1} and interaction weights ``w_i`` (``a_i`` for Greenwood's Eq. 13, or the
cell contact areas ``A_i = pi a_i^2`` as in the reference study's code):

    R_self = rho* / (2 sum_i phi_i a_i)
    R_int  = rho* sum_{i != j} phi_i phi_j w_i w_j / d_ij / (pi (sum_i phi_i w_i)^2)
    R      = R_self + R_int

No conducting spot is an open circuit (all three terms +inf); exactly one gives R_int = 0.

The interaction sum ``Q`` is the only costly part. :func:`resistance` evaluates it for a batch
of oxide masks and every load step with one of the exact algorithms of
:mod:`g2tom.physics.interaction` (or the direct double sum, the reference), on a
centred square crop per load step that drops spots whose effect on ``R`` is provably below a
tolerance. Entries whose own bound exceeds the tolerance are recomputed on the whole window,
so every entry's relative error from cropping is bounded by the tolerance (see
:func:`g2tom.physics.crops.crop_error_bound`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Iterator

import numpy as np

from g2tom.physics.crops import crop_error_bound, crop_slice
from g2tom.physics.interaction import BLOCK, auto_method, block_size, interaction_sum
from g2tom.physics.interaction_fft import fft_weights, interaction_fft_filled
from g2tom.physics.scratch import scratch
from g2tom.physics.spot_geometry import SpotGeometry

__all__ = [
    "greenwood_terms",
    "ChunkResult",
    "resistance",
]

#: Work memory of one block of the spot sums (counts, radius and weight sums), per thread
#: (bytes): they read four (load step, cell) tables per block, so their blocks hold more maps
#: than the FFT path's (40 instead of 2 at 229 cells).
SUMS_WORK_BYTES = 16 * 2**20


def greenwood_terms(
    radius_sum: np.ndarray,
    weight_sum: np.ndarray,
    pair_sum: np.ndarray,
    n_conducting: np.ndarray,
    rho: float,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Greenwood's resistance and its two terms from the spot sums.

    Parameters
    ----------
    radius_sum
        ``sum_i phi_i a_i``, in m.
    weight_sum
        ``sum_i phi_i w_i``, in the unit of the weights (m or m^2).
    pair_sum
        ``sum_{i != j} phi_i phi_j w_i w_j / d_ij``, in (unit of w)^2 / m.
    n_conducting
        Number of conducting spots.
    rho
        Effective resistivity rho*, in ohm m.

    Returns
    -------
    tuple of numpy.ndarray
        ``(R, R_self, R_int)`` in ohm, broadcast shape; +inf where no spot conducts, and
        ``R_int = 0`` where only one does.
    """
    radius_sum, weight_sum, pair_sum, n_conducting = np.broadcast_arrays(
        np.asarray(radius_sum, float), np.asarray(weight_sum, float),
        np.asarray(pair_sum, float), np.asarray(n_conducting),
    )
    open_circuit = n_conducting == 0
    interacting = (n_conducting > 1) & (pair_sum > 0)
    with np.errstate(divide="ignore", invalid="ignore"):
        r_self = np.where(open_circuit, np.inf, rho / (2.0 * radius_sum))
        r_int = np.where(interacting, rho * pair_sum / (np.pi * weight_sum**2), 0.0)
    r_int = np.where(open_circuit, np.inf, r_int)
    return r_self + r_int, r_self, r_int


@dataclass
class ChunkResult:
    """Greenwood terms of a batch of masks at every load step; arrays of shape (batch, n_delta).

    Attributes
    ----------
    resistance, resistance_self, resistance_interaction
        ``R``, ``R_self``, ``R_int`` in ohm (+inf for an open circuit).
    n_conducting
        Conducting spots (int32).
    crop_bound
        Bound on the relative error of ``R`` from cropping (0 where uncropped).
    n_uncropped
        Entries recomputed on the whole window because their crop bound exceeded the tolerance.
    """

    resistance: np.ndarray
    resistance_self: np.ndarray
    resistance_interaction: np.ndarray
    n_conducting: np.ndarray
    crop_bound: np.ndarray
    n_uncropped: int


def _blocks(masks: np.ndarray, size: int) -> Iterator[np.ndarray]:
    """Blocks of exactly ``size`` of the (batch, n, n) masks, the last padded with False."""
    for start in range(0, masks.shape[0], size):
        block = masks[start : start + size]
        if block.shape[0] < size:
            pad = np.zeros((size - block.shape[0],) + masks.shape[1:], dtype=bool)
            block = np.concatenate([block, pad])
        yield block


def _path(size: int, method: str) -> str:
    """The algorithm ``method`` runs on a ``size``-wide crop (``auto`` decides by size)."""
    return auto_method(size) if method == "auto" else method


def _map_weights(weights: np.ndarray, k: int, c: slice, groups: np.ndarray | None) -> np.ndarray:
    """Load step ``k``'s cropped weights of a block's maps: (1, size, size) shared by every map
    (``groups`` None), else (maps, size, size), map ``b`` taking group ``groups[b]``."""
    if groups is None:
        return weights[k, c, c][None]
    return weights[groups, k, c, c]


def _block_pair_sums(
    masks: np.ndarray, weights: np.ndarray, crops: np.ndarray, steps: list[int],
    pitch: float, method: str, out: np.ndarray, groups: np.ndarray | None,
) -> None:
    """Cropped interaction sums of one block at the load steps ``steps``, into ``out[:, k]``.

    The weight maps are laid out (x, y, map) in memory, the layout the ``*_gemm`` transforms
    consume, and passed on as (map, y, x) views of it.
    """
    n = masks.shape[-1]
    columns = np.ascontiguousarray(masks.transpose(2, 1, 0))
    for k in steps:
        size = int(crops[k])
        c = crop_slice(n, size)
        w = _map_weights(weights, k, c, groups).transpose(2, 1, 0)
        u = np.multiply(columns[c, c], w, out=scratch("weights", (size, size, masks.shape[0])))
        out[:, k] = interaction_sum(u.transpose(2, 1, 0), pitch, method)


def _fft_pair_sums(
    masks: np.ndarray, weights: np.ndarray, crops: np.ndarray, steps: list[int],
    pitch: float, size: int, out: np.ndarray, groups: np.ndarray | None,
) -> None:
    """Cropped interaction sums by the FFT path at the load steps ``steps``, into ``out[:, k]``.

    Load steps outside, blocks of ``size`` maps (the last padded with empty maps) inside: the
    weights are written straight into the FFT's zero-padded input, whose padding then stays
    valid across the blocks of one crop size (:func:`fft_weights`).
    """
    n, batch = masks.shape[-1], masks.shape[0]
    for k in steps:
        crop = int(crops[k])
        c = crop_slice(n, crop)
        u = fft_weights(size, crop)
        for start in range(0, batch, size):
            block = masks[start : start + size, c, c]
            chosen = None if groups is None else groups[start : start + size]
            np.multiply(block, _map_weights(weights, k, c, chosen), out=u[: block.shape[0]])
            u[block.shape[0] :] = 0.0
            out[start : start + size, k] = np.maximum(interaction_fft_filled(u, pitch), 0.0)


def _recompute_uncropped(
    masks: np.ndarray, weights: np.ndarray, pair_sum: np.ndarray, redo: np.ndarray,
    pitch: float, method: str, groups: np.ndarray | None,
) -> None:
    """Overwrite ``pair_sum[b, k]`` for the flagged entries with whole-window sums, in place."""
    size = block_size(masks.shape[-1])
    whole = slice(None)
    for k in np.flatnonzero(redo.any(axis=0)):
        rows = np.flatnonzero(redo[:, k])
        for start in range(0, rows.size, size):
            chosen = rows[start : start + size]
            block = np.zeros((size,) + masks.shape[1:])
            block[: chosen.size] = masks[chosen] * _map_weights(weights, k, whole, None if groups is None else groups[chosen])
            pair_sum[chosen, k] = interaction_sum(block, pitch, method)[: chosen.size]


def _spot_sums(
    masks: np.ndarray, radius: np.ndarray, weights: np.ndarray, crops: np.ndarray,
    groups: np.ndarray | None,
) -> tuple[Callable[[np.ndarray, np.ndarray, np.ndarray], None], int]:
    """The spot sums of a block of masks, and the most maps a block of them should hold.

    Returns a function ``fill(block, rows, out)`` writing the conducting count, ``sum a``,
    ``sum w`` and the weight outside the crop of each map of ``block`` (flattened (maps, n^2)
    float masks) into ``out[:, rows]`` (each (maps, n_delta)). Shared spots take one GEMM per
    table; per-map spots (``groups``) one GEMV per map over the stacked tables of its group,
    whose result does not depend on the block. A group's tables are built when a block needs
    them, once per block, in a reused work array: all groups' at once would be
    4 x (groups, n_delta, n, n), 0.6 GB for the 400 drawn clean surfaces of the paper's scene.
    """
    n = masks.shape[-1]
    n_delta = radius.shape[-3]
    outside = np.ones((n_delta, n, n))
    for k, size in enumerate(crops):
        c = crop_slice(n, int(size))
        outside[k, c, c] = 0.0
    if groups is None:
        tables = np.stack([(radius > 0).astype(np.float64), radius, weights, weights * outside])
        tables = tables.reshape(4, n_delta, n * n)

        def fill(block: np.ndarray, rows: slice, out: np.ndarray) -> None:
            for i, table in enumerate(tables):
                out[i, rows] = block @ table.T
        # The shared tables are read once per block: up to BLOCK maps within SUMS_WORK_BYTES.
        return fill, max(1, min(BLOCK, SUMS_WORK_BYTES // (8 * n * n)))
    outside = outside.reshape(n_delta, n * n)

    def group_tables(g: int) -> np.ndarray:
        """The stacked tables of group ``g``, (4 n_delta, n^2), in this thread's work array."""
        tables = scratch("group_tables", (4, n_delta, n * n))
        a, w = radius[g].reshape(n_delta, n * n), weights[g].reshape(n_delta, n * n)
        np.greater(a, 0.0, out=tables[0])
        tables[1], tables[2] = a, w
        np.multiply(w, outside, out=tables[3])
        return tables.reshape(4 * n_delta, n * n)

    def fill_each(block: np.ndarray, rows: slice, out: np.ndarray) -> None:
        mine = groups[rows][: block.shape[0]]
        for g in np.unique(mine):
            stacked = group_tables(g)
            for b in np.flatnonzero(mine == g):
                out[:, rows.start + b] = (stacked @ block[b]).reshape(4, n_delta)
    return fill_each, block_size(n)


def resistance(
    masks: np.ndarray,
    spots: SpotGeometry,
    rho: float,
    method: str = "auto",
    *,
    groups: np.ndarray | None = None,
) -> ChunkResult:
    """Greenwood's resistance of every (mask, load step) pair.

    Parameters
    ----------
    masks
        Cells whose spot centre is free of oxide, bool, shape (batch, n, n) as (y, x).
    spots
        Spot radii and interaction weights per load step (with ``groups``: one set per group),
        the cell pitch, the crop per load step and the crop tolerance: entries whose crop bound
        exceeds it are recomputed on the whole window.
    rho
        Effective resistivity rho*, in ohm m.
    method
        Interaction algorithm (see :func:`g2tom.physics.interaction.interaction_sum`).
    groups
        Which set of spots each map has, int (batch,), for spots that differ between maps (the
        ``asperities`` discretization draws them per realization); None: one set for all. A
        map's result is the same whatever other maps share its batch.

    Returns
    -------
    ChunkResult
        Arrays of shape (batch, n_delta).
    """
    radius, weights, pitch, crops = spots.radius, spots.weights, spots.pitch, spots.crops
    batch, n = masks.shape[0], masks.shape[-1]
    n_delta = radius.shape[-3]
    size = block_size(n)
    fill, per_block = _spot_sums(masks, radius, weights, crops, groups)
    sums_size = size * max(1, per_block // size)
    padded_batch = -(-batch // sums_size) * sums_size
    sums = np.empty((4, padded_batch, n_delta))
    pair = np.empty((padded_batch, n_delta))
    fft_steps = [k for k, crop in enumerate(crops) if _path(int(crop), method) == "fft"]
    other_steps = [k for k in range(n_delta) if k not in fft_steps]
    padded_groups = None if groups is None else np.concatenate([groups, np.zeros(padded_batch - batch, int)])
    for start, block in zip(range(0, padded_batch, sums_size), _blocks(masks, sums_size)):
        m = scratch("masks", (sums_size, n * n))
        np.copyto(m, block.reshape(sums_size, n * n))
        fill(m, slice(start, start + sums_size), sums)
        for sub in range(0, sums_size, size) if other_steps else ():
            part = slice(start + sub, start + sub + size)
            chosen = None if groups is None else padded_groups[part]
            _block_pair_sums(block[sub : sub + size], weights, crops, other_steps, pitch, method, pair[part], chosen)
    _fft_pair_sums(masks, weights, crops, fft_steps, pitch, size, pair, groups)
    count, s_a, s_w, eps = sums[:, :batch]
    pair = pair[:batch]
    n_cond = np.rint(count).astype(np.int32)
    r_crop = greenwood_terms(s_a, s_w, pair, n_cond, rho)[0]
    bound = crop_error_bound(s_a, s_w, eps, r_crop, pitch, rho)
    redo = bound > spots.tolerance
    if redo.any():
        _recompute_uncropped(masks, weights, pair, redo, pitch, method, groups)
        bound = np.where(redo, 0.0, bound)
    r, r_self, r_int = greenwood_terms(s_a, s_w, pair, n_cond, rho)
    return ChunkResult(r, r_self, r_int, n_cond, bound, int(redo.sum()))
