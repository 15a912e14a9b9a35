"""Greenwood's interaction sum by name: the exact algorithms, the one ``auto`` runs, and block sizes.

The interaction sum ``Q(u) = sum_{i != j} u_i u_j / d_ij`` of a batch of weight maps on a
regular square cell grid (:func:`interaction_sum`) by one of the exact algorithms of
:mod:`g2tom.physics.interaction_fft` and :mod:`g2tom.physics.interaction_folded`, or by the
direct double sum (:func:`interaction_direct`, the reference). ``auto`` takes the folded DFT-GEMM
below :data:`FFT_FROM` cells per side and the FFT from there (:func:`auto_method`);
:func:`block_size` says how many maps a block holds within the work-memory budget.
"""

from __future__ import annotations

from typing import Callable

import numpy as np

from g2tom.physics.interaction_fft import interaction_dft_gemm, interaction_fft, interaction_gemm, padded_length
from g2tom.physics.interaction_folded import interaction_folded

__all__ = [
    "METHODS",
    "AUTO_METHOD",
    "BLOCK",
    "WORK_BYTES",
    "FFT_FROM",
    "FFT_WORK_BYTES",
    "interaction_direct",
    "pair_sum_points",
    "interaction_sum",
    "auto_method",
    "block_size",
    "work_bytes_per_map",
]

#: Most maps per block. A block's size depends only on the window side (:func:`block_size`)
#: and every block has exactly that many columns (the last one is padded), so each map's
#: result is bit-identical whatever the batch it arrives in.
BLOCK = 128
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
