"""Exact fast evaluations of Greenwood's interaction sum on a regular square cell grid.

For weights ``u`` on an ``L x L`` block of cells of pitch ``h`` the interaction sum is the
quadratic form

    Q(u) = sum_{i != j} u_i u_j / d_ij = u . (K * u),   K(dx, dy) = 1 / (h sqrt(dx^2 + dy^2)),

with ``K(0, 0) = 0`` (cell offsets ``dx, dy`` in cells). Four exact algorithms are offered,
all batched over a leading axis of independent weight maps:

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
* :func:`interaction_folded`: :func:`interaction_dft_gemm` on the four mirror-parity quarters
  of the block (the kernel commutes with both reflections), which halves both GEMMs.

``make bench`` measures them all against the double sum.
All results are in the units of ``u**2 / h`` (``h`` in m). Every function is pure numpy/scipy
(the FFT path's transforms are ducc0's) and thread-safe; FFTs run single-threaded, one map per
call (parallelism comes from the caller, e.g. dask).
"""

from __future__ import annotations

import math
import threading
from functools import lru_cache

import ducc0
import numpy as np
import scipy.fft

__all__ = [
    "padded_length",
    "interaction_gemm",
    "interaction_fft",
    "fft_weights",
    "interaction_fft_filled",
    "interaction_dft_gemm",
    "interaction_folded",
    "interaction_apply",
    "interaction_apply_columns",
    "interaction_apply_dense",
    "interaction_apply_dense_columns",
    "scratch",
]

_SCRATCH = threading.local()


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
def _dense_kernel(n_cells: int) -> np.ndarray:
    """The ``N x N`` matrix ``1/d_ij`` (cells^-1, zero diagonal) of an ``n x n`` block, ``N = n^2``."""
    k = _offset_kernel(n_cells)
    iy, ix = np.divmod(np.arange(n_cells * n_cells), n_cells)
    out = k[np.abs(iy[:, None] - iy[None, :]), np.abs(ix[:, None] - ix[None, :])]
    out.setflags(write=False)
    return out


def _spectrum_2d(n_cells: int, length: int) -> np.ndarray:
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
def _toeplitz_stack(n_cells: int, length: int) -> np.ndarray:
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


def _check_blocks(u: np.ndarray) -> int:
    """Side ``n`` of a (batch, n, n) stack of weight maps; ValueError for any other shape."""
    if u.ndim != 3 or u.shape[1] != u.shape[2]:
        raise ValueError(f"weights must have shape (batch, n, n), got {u.shape}")
    return u.shape[1]


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
    n = _check_blocks(u)
    flat = u.reshape(u.shape[0], n * n)
    return np.einsum("bi,bi->b", flat, flat @ _dense_kernel(n)) / pitch


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
    n = _check_blocks(u)
    weights = fft_weights(u.shape[0], n)
    weights[...] = u
    return interaction_fft_filled(weights, pitch)


def fft_weights(batch: int, n_cells: int) -> np.ndarray:
    """This thread's input of :func:`interaction_fft_filled`: a writable (batch, n, n) view.

    It is the head of a zero-padded ``(batch, n, P)`` work array; the padding is zeroed only
    when the shape changes, so a caller that fills many blocks of one size in a row (and writes
    nothing but this view) pays for it once.
    """
    return _zero_padded("fft_rows", (batch, n_cells, padded_length(n_cells)), np.float64)[..., :n_cells]


def interaction_fft_filled(weights: np.ndarray, pitch: float) -> np.ndarray:
    """:func:`interaction_fft` (same units) of the maps just written into ``weights``, the
    (batch, n, n) view returned by :func:`fft_weights`, without copying them."""
    batch, n = weights.shape[0], weights.shape[1]
    length = padded_length(n)
    padded = _zero_padded("fft_rows", (batch, n, length), np.float64)
    if weights.base is None or weights.base is not padded.base:
        raise ValueError("interaction_fft_filled needs the view returned by fft_weights")
    # ducc0 (the successor of the pocketfft inside numpy and scipy, with wider SIMD) transforms
    # in reused buffers (fresh large arrays cost page faults, see :func:`scratch`). The x
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


def _zero_padded(slot: str, shape: tuple[int, ...], dtype: type) -> np.ndarray:
    """:func:`scratch` of ``shape`` under ``slot``, zeroed whenever its shape or storage changes.

    Its users write only into a head of it, so the rest stays zero between calls of one shape.
    """
    view = scratch(slot, shape, dtype)
    zeroed = getattr(_SCRATCH, "zeroed", None)
    if zeroed is None:
        zeroed = _SCRATCH.zeroed = {}
    key = (slot, np.dtype(dtype).char)
    if zeroed.get(key) != (shape, id(view.base)):
        view.fill(0)
        zeroed[key] = (shape, id(view.base))
    return view


@lru_cache(maxsize=64)
def _interleaved_spectrum(n_cells: int, length: int) -> np.ndarray:
    """:func:`_spectrum_2d` with each weight repeated for the real and imaginary part, flattened.

    Only this copy is cached, one per crop size.
    """
    out = np.repeat(_spectrum_2d(n_cells, length), 2, axis=1).ravel()
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
    n = _check_blocks(u)
    batch = u.shape[0]
    length = 2 * n - 1
    columns = np.ascontiguousarray(u.transpose(2, 1, 0)).reshape(n, n * batch)  # (x, y batch)
    parts = (_dft_rows(n, length) @ columns).reshape(2, length // 2 + 1, n, batch)
    coupled = np.matmul(_toeplitz_stack(n, length), parts)
    return np.einsum("cfyb,cfyb->b", parts, coupled) / pitch


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


def scratch(slot: str, shape: tuple[int, ...], dtype: type = np.float64) -> np.ndarray:
    """A work array of ``shape`` and ``dtype`` reused by this thread under ``slot`` (contents undefined).

    The hot loop reuses its large temporaries instead of allocating them afresh: with the
    allocator settings of ``dask.distributed`` workers (``MALLOC_TRIM_THRESHOLD_``) every large
    allocation is a fresh, zeroed memory mapping, which made the loop several times slower.
    """
    pool = getattr(_SCRATCH, "pool", None)
    if pool is None:
        pool = _SCRATCH.pool = {}
    size = math.prod(shape)
    key = (slot, np.dtype(dtype).char)
    flat = pool.get(key)
    if flat is None or flat.size < size:
        flat = pool[key] = np.empty(size, dtype)
    return flat[:size].reshape(shape)


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
    stack = _toeplitz_stack.__wrapped__(n_cells, length)  # not cached: 2 n^3 floats
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
    """Interaction sum by :func:`interaction_dft_gemm` with both mirror symmetries folded out.

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
    n = _check_blocks(u)
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
    _check_blocks(u)
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
    n = _check_blocks(u)
    flat = u.reshape(u.shape[0], n * n)
    return (flat @ _dense_kernel(n)).reshape(u.shape) / pitch


def interaction_apply_dense_columns(columns: np.ndarray, pitch: float) -> np.ndarray:
    """:func:`interaction_apply_dense` for maps laid out (x, y, map) (the ``1/d`` matrix is symmetric
    under exchanging x and y, so the same matrix serves both layouts)."""
    n = columns.shape[0]
    return (_dense_kernel(n) @ columns.reshape(n * n, -1)).reshape(columns.shape) / pitch
