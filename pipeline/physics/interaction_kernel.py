"""The interaction kernel ``1/d`` of a square cell grid, in the forms the exact algorithms use.

``K(dx, dy) = 1 / sqrt(dx^2 + dy^2)`` for cell offsets ``dx, dy`` (cells^-1), ``K(0, 0) = 0``: as
the dense ``N x N`` matrix of a block (:func:`dense_kernel`), as its half-plane spectrum on a
zero-padded circular grid (:func:`spectrum_2d`, the FFT path) and as per-``x``-frequency
``y``-coupling Toeplitz matrices (:func:`toeplitz_stack`, the DFT-GEMM paths). The algorithms are
:mod:`g2tom.physics.interaction_fft` and :mod:`g2tom.physics.interaction_folded`.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np
import scipy.fft

__all__ = ["dense_kernel", "spectrum_2d", "toeplitz_stack", "check_blocks"]

def _offset_kernel(n_cells: int) -> np.ndarray:
    """``1 / sqrt(dx^2 + dy^2)`` for offsets ``0 <= dx, dy < n_cells`` (cells^-1), 0 at the origin."""
    d = np.arange(n_cells, dtype=np.float64)
    r = np.hypot(d[:, None], d[None, :])
    with np.errstate(divide="ignore"):
        k = 1.0 / r
    k[0, 0] = 0.0
    return k


def _circular_axis(n_cells: int, length: int) -> np.ndarray:
    """Index of each circular position ``0..length-1`` as an offset magnitude, or -1 if unused."""
    pos = np.arange(length)
    offset = np.minimum(pos, length - pos)
    return np.where(offset < n_cells, offset, -1)


@lru_cache(maxsize=64)
def dense_kernel(n_cells: int) -> np.ndarray:
    """The ``N x N`` matrix ``1/d_ij`` (cells^-1, zero diagonal) of an ``n x n`` block, ``N = n^2``."""
    k = _offset_kernel(n_cells)
    iy, ix = np.divmod(np.arange(n_cells * n_cells), n_cells)
    out = k[np.abs(iy[:, None] - iy[None, :]), np.abs(ix[:, None] - ix[None, :])]
    out.setflags(write=False)
    return out


def spectrum_2d(n_cells: int, length: int) -> np.ndarray:
    """Half-plane spectrum weights ``Khat(f)`` of the kernel on a ``length^2`` circular grid.

    Returns a real array of shape ``(length, length // 2 + 1)`` that already carries the
    multiplicity of the mirrored half-plane and the ``1 / length^2`` Parseval factor.
    """
    axis = _circular_axis(n_cells, length)
    k = _offset_kernel(n_cells)
    grid = np.where(
        (axis[:, None] >= 0) & (axis[None, :] >= 0), k[axis[:, None], axis[None, :]], 0.0
    )
    spectrum = scipy.fft.rfft2(grid, workers=1).real
    spectrum *= _half_spectrum_multiplicity(length)[None, :] / float(length) ** 2
    spectrum.setflags(write=False)
    return spectrum


def _half_spectrum_multiplicity(length: int) -> np.ndarray:
    """How many frequencies of a full real spectrum each ``rfft`` bin stands for (1 or 2)."""
    c = np.full(length // 2 + 1, 2.0)
    c[0] = 1.0
    if length % 2 == 0:
        c[-1] = 1.0
    return c


@lru_cache(maxsize=64)
def toeplitz_stack(n_cells: int, length: int) -> np.ndarray:
    """Per ``x``-frequency ``y``-coupling matrices ``T_f`` of shape ``(F, n, n)``, ``F = length//2+1``.

    ``T_f[y, y'] = Ktilde(|y - y'|, f)`` is the kernel's real FFT along ``x`` (zero-padded to
    ``length``) for the row offset ``|y - y'|``; it carries the multiplicity ``c_f`` and the
    ``1 / length`` Parseval factor.
    """
    axis = _circular_axis(n_cells, length)
    k = _offset_kernel(n_cells)
    rows = np.where(axis[None, :] >= 0, k[:, np.maximum(axis, 0)], 0.0)  # (dy, x)
    ktilde = scipy.fft.rfft(rows, axis=1, workers=1).real  # (dy, F)
    ktilde *= _half_spectrum_multiplicity(length)[None, :] / float(length)
    y = np.arange(n_cells)
    stack = np.ascontiguousarray(ktilde[np.abs(y[:, None] - y[None, :])].transpose(2, 0, 1))
    stack.setflags(write=False)
    return stack


def check_blocks(u: np.ndarray) -> int:
    """Side ``n`` of a (batch, n, n) stack of weight maps; ValueError for any other shape."""
    if u.ndim != 3 or u.shape[1] != u.shape[2]:
        raise ValueError(f"weights must have shape (batch, n, n), got {u.shape}")
    return u.shape[1]
