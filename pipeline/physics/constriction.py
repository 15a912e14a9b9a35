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
:mod:`pipeline.physics.interaction_fft` (or the direct double sum, the reference), on a
centred square crop per load step that drops spots whose effect on ``R`` is provably below a
tolerance. Entries whose own bound exceeds the tolerance are recomputed on the whole window,
so every entry's relative error from cropping is bounded by the tolerance (see
:func:`crop_error_bound`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Iterator

import numpy as np

from pipeline.physics.interaction_fft import (
    padded_length,
    interaction_dft_gemm,
    interaction_fft,
    interaction_fft_filled,
    fft_weights,
    interaction_folded,
    interaction_gemm,
    scratch,
)

__all__ = [
    "METHODS",
    "greenwood_terms",
    "interaction_direct",
    "pair_sum_points",
    "interaction_sum",
    "crop_slice",
    "choose_crops",
    "crop_error_bound",
    "truncation_bounds",
    "ChunkResult",
    "resistance",
    "auto_method",
    "block_size",
    "work_bytes_per_map",
]

#: Most maps per block. A block's size depends only on the window side (:func:`block_size`)
#: and every block has exactly that many columns (the last one is padded), so each map's
#: result is bit-identical whatever the batch it arrives in.
BLOCK = 128
#: Work memory of one block of the spot sums (counts, radius and weight sums), per thread
#: (bytes): they read four (load step, cell) tables per block, so their blocks hold more maps
#: than the FFT path's (40 instead of 2 at 229 cells).
SUMS_WORK_BYTES = 16 * 2**20
#: Work memory of one block of maps, per thread (bytes): bounds the peak whatever the size.
WORK_BYTES = 128 * 2**20
#: Cells per side from which ``auto`` takes the FFT path. Measured on this 2-core machine, one
#: thread, medians per map (folded in blocks of 128 / fft in its blocks of :data:`FFT_WORK_BYTES`,
#: ducc0 transforms): 0.059 / 0.067 ms at 59, 0.092 / 0.102 ms at 71, 0.117 / 0.108 ms at 77,
#: 0.134 / 0.118 ms at 81, 0.31 / 0.17 ms at 113. The paper's windows (55, 57) stay on the
#: folded path.
FFT_FROM = 75
#: Work memory of one block of the FFT path, per thread (bytes): its arrays exceed the L2 cache
#: anyway, and two threads share the memory bandwidth. On the 229-cell scene (fixed 20
#: realizations, two threads, ducc0 transforms) blocks of 4 maps ran the cube in 27.9-29.3 s,
#: blocks of 1 or 2 in 19.3-21.6 s (three runs each). This budget gives blocks of 2 maps there.
FFT_WORK_BYTES = 6 * 2**20


def interaction_direct(u: np.ndarray, pitch: float) -> np.ndarray:
    """Interaction sum by the plain double sum over conducting spot pairs (the reference).

    Parameters
    ----------
    u
        Weights, shape (batch, n, n); zero where no spot conducts.
    pitch
        Cell pitch ``h``, in m.

    Returns
    -------
    numpy.ndarray
        ``sum_{i != j} u_i u_j / d_ij`` per map, shape (batch,), in units of ``u**2 / m``.
    """
    out = np.zeros(u.shape[0])
    for b, weights in enumerate(u):
        iy, ix = np.nonzero(weights)
        out[b] = pair_sum_points(ix * pitch, iy * pitch, weights[iy, ix])
    return out


def pair_sum_points(x: np.ndarray, y: np.ndarray, w: np.ndarray) -> float:
    """``sum_{i != j} w_i w_j / d_ij`` over an arbitrary list of distinct points.

    Parameters
    ----------
    x, y
        Point coordinates, shape (n,), in m.
    w
        Weights, shape (n,).

    Returns
    -------
    float
        The double sum, in units of ``w**2 / m``.
    """
    d = np.hypot(x[:, None] - x[None, :], y[:, None] - y[None, :])
    np.fill_diagonal(d, np.inf)
    return float(np.sum(w[:, None] * w[None, :] / d))


METHODS: dict[str, Callable[[np.ndarray, float], np.ndarray]] = {
    "direct": interaction_direct,
    "gemm": interaction_gemm,
    "fft": interaction_fft,
    "dft_gemm": interaction_dft_gemm,
    "folded": interaction_folded,
}
#: Safety factor on the oxide-free ratio sum(a)/sum(w) when sizing crops for non-radius weights.
CROP_MARGIN = 10.0
#: What ``method = "auto"`` runs (see :func:`auto_method`).
AUTO_METHOD = f"folded below {FFT_FROM} cells per side, fft from {FFT_FROM}"


def auto_method(n_cells: int) -> str:
    """The interaction algorithm ``auto`` runs on an ``n_cells``-wide block (:data:`FFT_FROM`)."""
    return "folded" if n_cells < FFT_FROM else "fft"


def work_bytes_per_map(n_cells: int) -> int:
    """Estimated work memory (bytes) of one map of an ``n_cells``-wide window in a block.

    The folded path holds about six float64 copies of the map (mask, weights, folded halves,
    spectra, couplings); the FFT path the complex half spectrum of the padded ``P x P`` grid
    (``P ~ 2 n``, 8 P^2 bytes), its x-padded input (8 n P) and the mask.
    """
    if auto_method(n_cells) == "folded":
        return 48 * n_cells * n_cells
    length = int(padded_length(n_cells))
    return 8 * length * length + 8 * n_cells * length + n_cells * n_cells


def block_size(n_cells: int) -> int:
    """Maps per block for an ``n_cells``-wide window: at most :data:`BLOCK`, within :data:`WORK_BYTES`
    (:data:`FFT_WORK_BYTES` on the FFT path)."""
    budget = WORK_BYTES if auto_method(n_cells) == "folded" else FFT_WORK_BYTES
    return int(min(BLOCK, max(1, budget // work_bytes_per_map(n_cells))))


def interaction_sum(u: np.ndarray, pitch: float, method: str = "auto") -> np.ndarray:
    """Interaction sum ``sum_{i != j} u_i u_j / d_ij`` of each map, by the named algorithm.

    Parameters
    ----------
    u
        Weights, shape (batch, n, n).
    pitch
        Cell pitch, in m.
    method
        ``auto``, ``direct``, ``gemm``, ``fft``, ``dft_gemm`` or ``folded``.

    Returns
    -------
    numpy.ndarray
        Shape (batch,), in units of ``u**2 / m``, never negative.
    """
    name = auto_method(u.shape[-1]) if method == "auto" else method
    if name not in METHODS:
        raise ValueError(f"method = {method!r} is not allowed: must be auto or one of {', '.join(METHODS)}")
    return np.maximum(METHODS[name](u, pitch), 0.0)


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


def crop_slice(n_cells: int, size: int) -> slice:
    """Centred slice of ``size`` cells out of ``n_cells`` (same parity, ``size <= n_cells``)."""
    if size > n_cells or (n_cells - size) % 2:
        raise ValueError(f"crop size {size} must be <= {n_cells} with the same parity")
    start = (n_cells - size) // 2
    return slice(start, start + size)


def choose_crops(radius: np.ndarray, weights: np.ndarray, pitch: float, tolerance: float) -> np.ndarray:
    """Smallest centred square crop per load step whose cropping bound stays within tolerance.

    Dropping conducting weight ``eps`` outside the crop changes the interaction sum by at most
    ``eps (2 s_w - eps) / h`` (every pair is at least one pitch apart), so the relative change
    of ``R >= R_self`` is at most ``4 eps s_a / (pi s_w h)``, and ``eps`` is at most the
    unmasked weight outside the crop. For radius weights ``s_a / s_w = 1`` for every oxide
    mask, so the crop is safe for all of them. For other weights the ratio depends on the
    mask; the crop is sized with :data:`CROP_MARGIN` times the oxide-free ratio, and entries
    that still exceed the tolerance are recomputed uncropped by :func:`resistance`.

    Parameters
    ----------
    radius, weights
        Spot radii (m) and interaction weights, shape (n_delta, n, n).
    pitch
        Cell pitch, in m.
    tolerance
        Allowed relative change of ``R``; 0 keeps the whole window.

    Returns
    -------
    numpy.ndarray
        Crop sizes in cells, shape (n_delta,), same parity as ``n``.
    """
    n = radius.shape[-1]
    sizes = np.full(radius.shape[0], n, dtype=int)
    if tolerance <= 0:
        return sizes
    margin = 1.0 if np.array_equal(radius, weights) else CROP_MARGIN
    for k, (a, w) in enumerate(zip(radius, weights)):
        if not w.sum() > 0:
            continue
        ratio = margin * a.sum() / w.sum()
        for size in range(1 + (n + 1) % 2, n, 2):
            c = crop_slice(n, size)
            outside = w.sum() - w[c, c].sum()
            if 4.0 * outside * ratio / (np.pi * pitch) <= tolerance:
                sizes[k] = size
                break
    return sizes


def truncation_bounds(radius: np.ndarray, weights: np.ndarray, pitch: float, margin: float) -> np.ndarray:
    """Bound on the relative change of ``R`` from keeping only a centred square of each odd size.

    The bound of :func:`choose_crops`, ``4 eps margin s_a / (pi s_w h)`` with ``eps`` the
    weight outside the square, for every odd square side at once: the weights are summed over
    the square rings of equal Chebyshev distance from the centre cell.

    Parameters
    ----------
    radius, weights
        Spot radii (m) and interaction weights of one map, shape (n, n), ``n`` odd.
    pitch
        Cell pitch, in m.
    margin
        Safety factor on ``s_a / s_w`` (1 for radius weights, :data:`CROP_MARGIN` otherwise).

    Returns
    -------
    numpy.ndarray
        Shape ((n + 1) // 2,): entry ``k`` bounds the square of side ``2 k + 1``; 0 for an
        empty map.
    """
    n = radius.shape[-1]
    if n % 2 == 0 or radius.shape != (n, n):
        raise ValueError(f"the map must be square with an odd side, got {radius.shape}")
    offset = np.abs(np.arange(n) - n // 2)
    ring = np.maximum(offset[:, None], offset[None, :])
    inside = np.cumsum(np.bincount(ring.ravel(), weights=weights.ravel(), minlength=n // 2 + 1))
    total = inside[-1]
    if not total > 0:
        return np.zeros(n // 2 + 1)
    outside = np.maximum(total - inside, 0.0)
    outside[-1] = 0.0
    return 4.0 * outside * margin * radius.sum() / (total * np.pi * pitch)


def crop_error_bound(
    radius_sum: np.ndarray,
    weight_sum: np.ndarray,
    outside_sum: np.ndarray,
    resistance_cropped: np.ndarray,
    pitch: float,
    rho: float,
) -> np.ndarray:
    """Upper bound on the relative error of ``R`` from dropping the spots outside a crop.

    The dropped conducting weight ``eps`` changes the interaction sum by at most
    ``eps (2 s_w - eps) / h`` and never increases ``R``, so the cropped value ``R'`` is a
    lower bound of ``R`` and ``(R - R') / R <= rho eps (2 s_w - eps) / (pi s_w^2 h R')``.

    Parameters
    ----------
    radius_sum
        ``s_a = sum phi a`` over all spots, in m (0 marks an open circuit).
    weight_sum
        ``s_w = sum phi w`` over all spots.
    outside_sum
        ``eps = sum phi w`` over the spots outside the crop.
    resistance_cropped
        ``R'`` computed with the cropped interaction sum, in ohm.
    pitch
        Cell pitch, in m.
    rho
        Effective resistivity, in ohm m.

    Returns
    -------
    numpy.ndarray
        The bound, 0 where nothing was dropped or the circuit is open.
    """
    eps = np.asarray(outside_sum, float)
    with np.errstate(divide="ignore", invalid="ignore"):
        delta_r = rho * eps * (2.0 * weight_sum - eps) / (np.pi * weight_sum**2 * pitch)
        bound = delta_r / resistance_cropped
    keep = (eps > 0) & (np.asarray(radius_sum) > 0) & np.isfinite(resistance_cropped)
    return np.where(keep, bound, 0.0)


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
    whose result does not depend on the block.
    """
    n = masks.shape[-1]
    lead = radius.shape[:-3]
    n_delta = radius.shape[-3]
    outside = np.ones((n_delta, n, n))
    for k, size in enumerate(crops):
        c = crop_slice(n, int(size))
        outside[k, c, c] = 0.0
    tables = np.stack([(radius > 0).astype(np.float64), radius, weights, weights * outside], axis=-4)
    tables = tables.reshape(lead + (4, n_delta, n * n))
    if groups is None:
        def fill(block: np.ndarray, rows: slice, out: np.ndarray) -> None:
            for i, table in enumerate(tables):
                out[i, rows] = block @ table.T
        # The shared tables are read once per block: up to BLOCK maps within SUMS_WORK_BYTES.
        return fill, max(1, min(BLOCK, SUMS_WORK_BYTES // (8 * n * n)))
    stacked = tables.reshape(tables.shape[0], 4 * n_delta, n * n)

    def fill_each(block: np.ndarray, rows: slice, out: np.ndarray) -> None:
        mine = groups[rows]
        for b in range(min(block.shape[0], mine.size)):
            out[:, rows.start + b] = (stacked[mine[b]] @ block[b]).reshape(4, n_delta)
    return fill_each, block_size(n)


def resistance(
    masks: np.ndarray,
    radius: np.ndarray,
    weights: np.ndarray,
    pitch: float,
    rho: float,
    crops: np.ndarray,
    tolerance: float,
    method: str = "auto",
    *,
    groups: np.ndarray | None = None,
) -> ChunkResult:
    """Greenwood's resistance of every (mask, load step) pair.

    Parameters
    ----------
    masks
        Cells whose spot centre is free of oxide, bool, shape (batch, n, n) as (y, x).
    radius
        Spot radii ``a_i`` per load step, shape (n_delta, n, n), in m; 0 means no spot. With
        ``groups``: one such set per group, shape (n_groups, n_delta, n, n).
    weights
        Interaction weights per load step, same shape: ``radius`` or the cell contact areas.
    pitch
        Cell pitch, in m.
    rho
        Effective resistivity rho*, in ohm m.
    crops
        Crop size per load step (see :func:`choose_crops`); ``n`` everywhere disables cropping.
    tolerance
        Entries whose crop bound exceeds this are recomputed on the whole window.
    method
        Interaction algorithm (see :func:`interaction_sum`).
    groups
        Which set of spots each map has, int (batch,), for spots that differ between maps (the
        ``asperities`` discretization draws them per realization); None: one set for all. A
        map's result is the same whatever other maps share its batch.

    Returns
    -------
    ChunkResult
        Arrays of shape (batch, n_delta).
    """
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
    redo = bound > tolerance
    if redo.any():
        _recompute_uncropped(masks, weights, pair, redo, pitch, method, groups)
        bound = np.where(redo, 0.0, bound)
    r, r_self, r_int = greenwood_terms(s_a, s_w, pair, n_cond, rho)
    return ChunkResult(r, r_self, r_int, n_cond, bound, int(redo.sum()))
