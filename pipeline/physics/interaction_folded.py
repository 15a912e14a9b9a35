"""The folded DFT-GEMM interaction sum and the interaction operator applied, by mirror parity.

The ``1/d`` kernel on a centred block commutes with the reflections ``x -> -x`` and ``y -> -y``,
so the four mirror-parity components of a weight map do not interact: each is transformed along
``x`` and coupled along ``y`` on a quarter of the cells (:func:`interaction_folded`, the DFT-GEMM
of :mod:`g2tom.physics.interaction_fft` with both GEMMs halved). The same quarters give the
operator itself, ``(K * u)_i = sum_{j != i} u_j / d_ij`` (:func:`interaction_apply_columns`), which
the point model's conjugate gradients apply; :func:`interaction_apply_dense` is its dense
reference. Units as in :mod:`g2tom.physics.interaction_fft`.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

from g2tom.physics.interaction_kernel import check_blocks, dense_kernel, toeplitz_stack
from g2tom.physics.scratch import scratch

__all__ = [
    "interaction_folded",
    "interaction_apply",
    "interaction_apply_columns",
    "interaction_apply_dense",
    "interaction_apply_dense_columns",
]

def _fold_matrices(n_cells: int) -> tuple[np.ndarray, np.ndarray]:
    """Even and odd parts of a length-``n`` vector about its centre, from its folded halves.

    Returns ``G_e`` of shape ``(n, n_e)`` and ``G_o`` of shape ``(n, n_o)`` with
    ``(c + Jc)/2 = G_e e`` and ``(c - Jc)/2 = G_o o``, where ``J`` reverses the vector and the
    folded halves are ``e_j = c(m + j) + c(m' - j)``, ``o_j = c(m + j) - c(m' - j)`` (``m'``
    mirrors ``m``; for odd ``n`` the centre enters ``e_0`` once and ``o`` starts at ``j = 1``).
    """
    half = n_cells // 2
    odd = n_cells % 2
    upper = np.arange(half, n_cells)  # m + j
    lower = n_cells - 1 - upper  # its mirror
    g_e = np.zeros((n_cells, upper.size))
    g_e[upper, np.arange(upper.size)] = 0.5
    g_e[lower, np.arange(upper.size)] += 0.5
    g_o = np.zeros((n_cells, half))
    cols = np.arange(half)
    g_o[upper[odd:], cols] = 0.5
    g_o[lower[odd:], cols] = -0.5
    return g_e, g_o


def _fold(c: np.ndarray, axis: int, slot: str) -> tuple[np.ndarray, np.ndarray]:
    """Folded even and odd halves (see :func:`_fold_matrices`) of ``c`` along ``axis``."""
    n = c.shape[axis]
    half, odd = n // 2, n % 2

    def part(a: np.ndarray, sl: slice) -> np.ndarray:
        return a[(slice(None),) * axis + (sl,)]

    lower = part(c, slice(half - 1, None, -1) if half else slice(0, 0))
    upper = part(c, slice(half, None))
    even = scratch(f"{slot}_even", upper.shape, c.dtype)
    odd_half = scratch(f"{slot}_odd", lower.shape, c.dtype)
    np.copyto(even, upper)
    np.add(part(even, slice(odd, None)), lower, out=part(even, slice(odd, None)))
    np.subtract(part(c, slice(half + odd, None)), lower, out=odd_half)
    return even, odd_half


@lru_cache(maxsize=64)
def _folded_operators(n_cells: int) -> tuple[np.ndarray, ...]:
    """DFT rows for the even/odd ``x`` halves and the ``y`` coupling of the even/odd ``y`` halves.

    Returns ``(cos_e, sin_o, a_e, a_o)``: ``cos_e`` (F, n_e) and ``sin_o`` (F, n_o) transform the
    folded ``x`` halves about the centre (the centred DFT's real and imaginary parts), and
    ``a_e = G_e^T T_f G_e`` (F, n_e, n_e), ``a_o = G_o^T T_f G_o`` (F, n_o, n_o) are the
    Toeplitz couplings restricted to the even and odd ``y`` halves.
    """
    length = 2 * n_cells - 1
    g_e, g_o = _fold_matrices(n_cells)
    f = np.arange(length // 2 + 1)
    phase = 2.0 * np.pi * np.outer(f, np.arange(n_cells) - (n_cells - 1) / 2.0) / length
    stack = toeplitz_stack.__wrapped__(n_cells, length)  # not cached: 2 n^3 floats
    out = (
        np.cos(phase) @ g_e,
        -np.sin(phase) @ g_o,
        np.ascontiguousarray(g_e.T @ stack @ g_e),
        np.ascontiguousarray(g_o.T @ stack @ g_o),
    )
    for a in out:
        a.setflags(write=False)
    return out


@lru_cache(maxsize=64)
def _folded_operators_as(n_cells: int, dtype: str) -> tuple[np.ndarray, ...]:
    """:func:`_folded_operators` rounded to ``dtype`` (a numpy type code), read-only."""
    out = tuple(np.ascontiguousarray(a, dtype=dtype) for a in _folded_operators(n_cells))
    for a in out:
        a.setflags(write=False)
    return out


def _coupled_energy(rows: np.ndarray, coupling: np.ndarray, halves: np.ndarray) -> np.ndarray:
    """``sum_f t_f^T a_f t_f`` per map for ``t = rows @ halves`` (x transform, then y coupling)."""
    n_x, n_y, batch = halves.shape
    if n_x == 0 or n_y == 0:
        return np.zeros(batch)
    spectra = scratch("spectra", (rows.shape[0], n_y, batch))
    np.matmul(rows, halves.reshape(n_x, n_y * batch), out=spectra.reshape(-1, n_y * batch))
    coupled = np.matmul(coupling, spectra, out=scratch("coupled", spectra.shape))
    return np.einsum("fyb,fyb->b", spectra, coupled)


def interaction_folded(u: np.ndarray, pitch: float) -> np.ndarray:
    """Interaction sum by :func:`~g2tom.physics.interaction_fft.interaction_dft_gemm` with both mirror symmetries folded out.

    The ``1/d`` kernel on a centred block commutes with the reflections ``x -> -x`` and
    ``y -> -y``, so the four parity components of ``u`` do not interact: each is transformed
    and coupled on a quarter of the cells, halving both GEMMs.

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
    cos_e, sin_o, a_e, a_o = _folded_operators(n)
    columns = np.ascontiguousarray(u.transpose(2, 1, 0))  # (x, y, batch)
    x_even, x_odd = _fold(columns, axis=0, slot="x")
    total = np.zeros(u.shape[0])
    for rows, x_half in ((cos_e, x_even), (sin_o, x_odd)):
        y_even, y_odd = _fold(x_half, axis=1, slot="y")
        total += _coupled_energy(rows, a_e, y_even) + _coupled_energy(rows, a_o, y_odd)
    return total / pitch


def _unfold(even: np.ndarray, odd_half: np.ndarray, axis: int, out: np.ndarray) -> np.ndarray:
    """Adjoint of :func:`_fold` along ``axis``: the full-length vector from its folded halves.

    ``_fold`` maps ``c`` to ``e_j = c(m + j) + c(m' - j)`` and ``o_j = c(m + j) - c(m' - j)``
    (for odd ``n`` the centre enters ``e_0`` once and ``o`` starts at ``j = 1``), so its
    transpose writes ``e_j + o_j`` to ``m + j`` and ``e_j - o_j`` to ``m' - j``.
    """
    n = out.shape[axis]
    half, odd = n // 2, n % 2

    def part(a: np.ndarray, sl: slice) -> np.ndarray:
        return a[(slice(None),) * axis + (sl,)]

    upper = part(out, slice(half, None))
    np.copyto(upper, even)
    np.add(part(upper, slice(odd, None)), odd_half, out=part(upper, slice(odd, None)))
    if half:
        lower = part(out, slice(half - 1, None, -1))
        np.subtract(part(even, slice(odd, None)), odd_half, out=lower)
    return out


def _coupled_apply(rows: np.ndarray, coupling: np.ndarray, halves: np.ndarray, slot: str) -> np.ndarray:
    """``rows^T a_f rows`` applied to folded halves of shape (n_x, n_y, batch) (x transform, y coupling, back)."""
    n_x, n_y, batch = halves.shape
    out = scratch(slot, halves.shape, halves.dtype)
    if n_x == 0 or n_y == 0:
        out.fill(0.0)
        return out
    spectra = scratch("spectra", (rows.shape[0], n_y, batch), halves.dtype)
    np.matmul(rows, halves.reshape(n_x, n_y * batch), out=spectra.reshape(-1, n_y * batch))
    coupled = np.matmul(coupling, spectra, out=scratch("coupled", spectra.shape, halves.dtype))
    np.matmul(rows.T, coupled.reshape(rows.shape[0], n_y * batch), out=out.reshape(n_x, n_y * batch))
    return out


def interaction_apply_columns(columns: np.ndarray, pitch: float) -> np.ndarray:
    """The interaction operator applied, ``(K * u)_i = sum_{j != i} u_j / d_ij``, by the folded DFT-GEMM.

    The same operator whose quadratic form :func:`interaction_folded` contracts: each mirror-parity
    quarter of ``u`` is transformed along ``x``, coupled along ``y`` by the cached ``a_e``/``a_o``
    and transformed back by the transpose, then the quarters are unfolded. The work is about
    1.6 times that of the contraction (one more GEMM of the size of the forward transform).
    Maps are laid out (x, y, map), the layout the GEMMs consume, so iterative solvers that keep
    their vectors in it never transpose.

    Parameters
    ----------
    columns
        Weights, shape (n, n, batch) as (x, y, map), float64 or float32 (the whole computation
        then runs in float32, about twice as fast, with relative errors of order 1e-7).
    pitch
        Cell pitch ``h``, in m.

    Returns
    -------
    numpy.ndarray
        ``K * u``, a new C-contiguous array of shape (n, n, batch) as (x, y, map), in units of
        ``u / m``, of the dtype of ``columns``.
    """
    if columns.ndim != 3 or columns.shape[0] != columns.shape[1]:
        raise ValueError(f"weights must have shape (n, n, batch), got {columns.shape}")
    if columns.dtype not in (np.float32, np.float64):
        raise ValueError(f"weights must be float32 or float64, got {columns.dtype}")
    cos_e, sin_o, a_e, a_o = _folded_operators_as(columns.shape[0], columns.dtype.char)
    x_even, x_odd = _fold(columns, axis=0, slot="x")
    halves = []
    for rows, x_half, part in ((cos_e, x_even, "e"), (sin_o, x_odd, "o")):
        y_even, y_odd = _fold(x_half, axis=1, slot="y")
        back_e = _coupled_apply(rows, a_e, y_even, "back_e")
        back_o = _coupled_apply(rows, a_o, y_odd, "back_o")
        halves.append(_unfold(back_e, back_o, axis=1, out=scratch(f"unfold_{part}", x_half.shape, columns.dtype)))
    out = _unfold(halves[0], halves[1], axis=0, out=np.empty(columns.shape, columns.dtype))
    out /= pitch
    return out


def interaction_apply(u: np.ndarray, pitch: float) -> np.ndarray:
    """:func:`interaction_apply_columns` for maps laid out (map, y, x).

    Parameters
    ----------
    u
        Weights, shape (batch, n, n) as (map, y, x).
    pitch
        Cell pitch ``h``, in m.

    Returns
    -------
    numpy.ndarray
        ``K * u`` of shape (batch, n, n) (a new array), in units of ``u / m``.
    """
    check_blocks(u)
    return interaction_apply_columns(np.ascontiguousarray(u.transpose(2, 1, 0)), pitch).transpose(2, 1, 0)


def interaction_apply_dense(u: np.ndarray, pitch: float) -> np.ndarray:
    """``K * u`` by the dense ``1/d`` matrix of the block (the reference for :func:`interaction_apply`).

    Parameters
    ----------
    u
        Weights, shape (batch, n, n).
    pitch
        Cell pitch ``h``, in m.

    Returns
    -------
    numpy.ndarray
        ``K * u``, shape (batch, n, n), in units of ``u / m``.
    """
    n = check_blocks(u)
    flat = u.reshape(u.shape[0], n * n)
    return (flat @ dense_kernel(n)).reshape(u.shape) / pitch


def interaction_apply_dense_columns(columns: np.ndarray, pitch: float) -> np.ndarray:
    """:func:`interaction_apply_dense` for maps laid out (x, y, map) (the ``1/d`` matrix is symmetric
    under exchanging x and y, so the same matrix serves both layouts)."""
    n = columns.shape[0]
    return (dense_kernel(n) @ columns.reshape(n * n, -1)).reshape(columns.shape) / pitch
