"""Exact fast evaluations of Greenwood's interaction sum on a regular square cell grid.

For weights ``u`` on an ``L x L`` block of cells of pitch ``h`` the interaction sum is the
quadratic form

    Q(u) = sum_{i != j} u_i u_j / d_ij = u . (K * u),   K(dx, dy) = 1 / (h sqrt(dx^2 + dy^2)),

with ``K(0, 0) = 0`` (cell offsets ``dx, dy`` in cells). Four exact algorithms are offered,
three here and the fourth in :mod:`g2tom.physics.interaction_folded`, all batched over a leading axis of independent weight maps:

* :func:`interaction_gemm`: the dense ``1/d`` matrix of the block times the weight columns.
* :func:`interaction_fft`: Parseval on a zero-padded real 2-D FFT. Only the forward transform
  is needed: ``Q = (1/P^2) sum_f Khat(f) |uhat(f)|^2`` with the kernel's real, even spectrum
  ``Khat`` on a ``P x P`` grid, ``P >= 2L - 1`` so the circular wrap never aliases.
* :func:`interaction_dft_gemm`: a real Fourier transform along ``x`` only (zero-padded to
  ``P = 2L - 1``) makes the ``x``-Toeplitz structure diagonal; per frequency the remaining
  ``y`` coupling is a real symmetric ``L x L`` Toeplitz matrix ``T_f``, so
  ``Q = (1/P) sum_f c_f U_f^H T_f U_f`` is one small dense GEMM per frequency over all maps at
  once (``c_f`` counts the mirrored half of the spectrum): ``O(L^3)`` flops per map instead
  of ``2 L^4`` (dense). The transform itself is one more GEMM with the ``2F x L`` DFT matrix,
  which at these small sizes beats an FFT (a pocketfft variant measured 15-30 % slower).
* :func:`~g2tom.physics.interaction_folded.interaction_folded`: :func:`interaction_dft_gemm` on the four mirror-parity quarters
  of the block (the kernel commutes with both reflections), which halves both GEMMs.

``make bench`` measures them all against the double sum.
All results are in the units of ``u**2 / h`` (``h`` in m). Every function is pure numpy/scipy
(the FFT path's transforms are ducc0's) and thread-safe; FFTs run single-threaded, one map per
call (parallelism comes from the caller, e.g. dask).
"""


from __future__ import annotations

from functools import lru_cache

import ducc0
import numpy as np
import scipy.fft

from g2tom.physics.interaction_kernel import check_blocks, dense_kernel, spectrum_2d, toeplitz_stack
from g2tom.physics.scratch import scratch, zero_padded

__all__ = [
    "padded_length",
    "interaction_gemm",
    "interaction_fft",
    "fft_weights",
    "interaction_fft_filled",
    "interaction_dft_gemm",
]

def padded_length(n_cells: int) -> int:
    """FFT length that holds the linear (non-circular) correlation of ``n_cells`` samples.

    Parameters
    ----------
    n_cells
        Cells along one side of the block.

    Returns
    -------
    int
        The smallest FFT-friendly length ``>= 2 n_cells - 1``.
    """
    return int(scipy.fft.next_fast_len(2 * n_cells - 1, real=True))


def interaction_gemm(u: np.ndarray, pitch: float) -> np.ndarray:
    """Interaction sum by a GEMM with the dense ``1/d`` matrix of the block.

    Parameters
    ----------
    u
        Weights, shape (batch, n, n): cell ``(y, x)`` of each map; zero where no spot conducts.
    pitch
        Cell pitch ``h``, in m.

    Returns
    -------
    numpy.ndarray
        ``sum_{i != j} u_i u_j / d_ij`` per map, shape (batch,), in units of ``u**2 / m``.
    """
    n = check_blocks(u)
    flat = u.reshape(u.shape[0], n * n)
    return np.einsum("bi,bi->b", flat, flat @ dense_kernel(n)) / pitch


def interaction_fft(u: np.ndarray, pitch: float) -> np.ndarray:
    """Interaction sum by Parseval on a zero-padded real 2-D FFT (forward transforms only).

    Parameters
    ----------
    u
        Weights, shape (batch, n, n).
    pitch
        Cell pitch ``h``, in m.

    Returns
    -------
    numpy.ndarray
        ``sum_{i != j} u_i u_j / d_ij`` per map, shape (batch,), in units of ``u**2 / m``.
    """
    n = check_blocks(u)
    weights = fft_weights(u.shape[0], n)
    weights[...] = u
    return interaction_fft_filled(weights, pitch)


def fft_weights(batch: int, n_cells: int) -> np.ndarray:
    """This thread's input of :func:`interaction_fft_filled`: a writable (batch, n, n) view.

    It is the head of a zero-padded ``(batch, n, P)`` work array; the padding is zeroed only
    when the shape changes, so a caller that fills many blocks of one size in a row (and writes
    nothing but this view) pays for it once.
    """
    return zero_padded("fft_rows", (batch, n_cells, padded_length(n_cells)), np.float64)[..., :n_cells]


def interaction_fft_filled(weights: np.ndarray, pitch: float) -> np.ndarray:
    """:func:`interaction_fft` (same units) of the maps just written into ``weights``, the
    (batch, n, n) view returned by :func:`fft_weights`, without copying them."""
    batch, n = weights.shape[0], weights.shape[1]
    length = padded_length(n)
    padded = zero_padded("fft_rows", (batch, n, length), np.float64)
    if weights.base is None or weights.base is not padded.base:
        raise ValueError("interaction_fft_filled needs the view returned by fft_weights")
    # ducc0 (the successor of the pocketfft inside numpy and scipy, with wider SIMD) transforms
    # in reused buffers (fresh large arrays cost page faults, see :func:`~g2tom.physics.scratch.scratch`). The x
    # transform runs only over the n rows that hold weights, into the head of the spectrum
    # buffer; the y transform runs in place (out of place measured 1.6 times slower).
    uhat = scratch("fft_spectrum", (batch, length, length // 2 + 1), np.complex128)
    spectrum = _interleaved_spectrum(n, length)
    out = np.empty(batch)
    # One map per call: a batched transform vectorizes across maps, so a map's last bits
    # would depend on its neighbours and its place in the batch.
    for b in range(batch):
        ducc0.fft.r2c(padded[b], axes=(1,), out=uhat[b, :n], nthreads=1)
        uhat[b, n:] = 0.0
        ducc0.fft.c2c(uhat[b], axes=(0,), out=uhat[b], nthreads=1)
        # |uhat|^2 weighted by Khat as one dot product over the interleaved (re, im) floats.
        power = uhat[b].view(np.float64).ravel()
        np.square(power, out=power)
        out[b] = power @ spectrum
    return out / pitch


@lru_cache(maxsize=64)
def _interleaved_spectrum(n_cells: int, length: int) -> np.ndarray:
    """:func:`~g2tom.physics.interaction_kernel.spectrum_2d` with each weight repeated for the real and imaginary part, flattened.

    Only this copy is cached, one per crop size.
    """
    out = np.repeat(spectrum_2d(n_cells, length), 2, axis=1).ravel()
    out.setflags(write=False)
    return out


@lru_cache(maxsize=64)
def _dft_rows(n_cells: int, length: int) -> np.ndarray:
    """Real DFT matrix ``[cos; -sin](2 pi f x / length)``, shape ``(2F, n_cells)``, ``F = length//2+1``."""
    f = np.arange(length // 2 + 1)
    phase = 2.0 * np.pi * np.outer(f, np.arange(n_cells)) / length
    rows = np.concatenate([np.cos(phase), -np.sin(phase)])
    rows.setflags(write=False)
    return rows


def interaction_dft_gemm(u: np.ndarray, pitch: float) -> np.ndarray:
    """Interaction sum by a DFT along ``x`` applied as a GEMM, then a Toeplitz GEMM along ``y``.

    Parameters
    ----------
    u
        Weights, shape (batch, n, n).
    pitch
        Cell pitch ``h``, in m.

    Returns
    -------
    numpy.ndarray
        ``sum_{i != j} u_i u_j / d_ij`` per map, shape (batch,), in units of ``u**2 / m``.
    """
    n = check_blocks(u)
    batch = u.shape[0]
    length = 2 * n - 1
    columns = np.ascontiguousarray(u.transpose(2, 1, 0)).reshape(n, n * batch)  # (x, y batch)
    parts = (_dft_rows(n, length) @ columns).reshape(2, length // 2 + 1, n, batch)
    coupled = np.matmul(toeplitz_stack(n, length), parts)
    return np.einsum("cfyb,cfyb->b", parts, coupled) / pitch
