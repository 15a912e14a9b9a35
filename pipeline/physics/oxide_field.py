"""Band-limited Gaussian random fields for the oxide islands (Sect. 2.6): their values and thresholds,
pure numpy/scipy.

The fields' spectrum, random coefficients and streams are :mod:`g2tom.physics.oxide_band`: a field
is ``psi(x, y) = Re sum_k c_k exp(i (k_x x + k_y y))`` over the band's wave vectors, periodic over
``L`` (the window, or a longer spectral period). Here: its values at the cell centres
(:func:`cell_values` for the window's period, :func:`centre_values` for any), on any grid
(:func:`grid_values`) and at any point (:func:`field_at_points`, the slow reference), and the
thresholds that turn a field into an oxide mask (:func:`theoretical_threshold`,
:func:`empirical_threshold`).

Exact values at the cell centres. The centres are ``x_p = (p - m) h`` with ``h = L / n``,
``m = (n - 1) / 2`` (``n`` odd), so ``exp(2 pi i i x_p / L) = exp(2 pi i (i mod n)(p - m) / n)``:
a mode takes at the centres exactly the values of the lattice mode ``(i mod n, j mod n)``.
Folding every coefficient onto that n x n spectrum and doing one n x n inverse FFT gives the
continuous field's point values, also where ``ks`` lies above the grid's Nyquist frequency
(lambda near 1); :func:`field_at_points` is the slow reference.
"""

from __future__ import annotations

import numpy as np
from scipy.special import erfcinv

from g2tom.physics.oxide_band import Band, coefficients, field_stream

__all__ = [
    "cell_values",
    "centre_values",
    "grid_values",
    "realize",
    "field_at_points",
    "theoretical_threshold",
    "empirical_threshold",
    "covered_count",
]


def cell_values(modes: Band, coeffs: np.ndarray, n_cells: int) -> np.ndarray:
    """Exact values of fields at the n x n cell centres, by folding the modes onto the grid.

    Parameters
    ----------
    modes
        The band, built for the same ``n_cells``.
    coeffs
        Complex coefficients, shape (..., modes.size).
    n_cells
        Cells along one side (odd).

    Returns
    -------
    numpy.ndarray
        float64, shape (..., n_cells, n_cells), indexed ``[..., y, x]`` like
        ``grid.cell_centres(n_cells, cell_size)``.
    """
    n = n_cells
    folded = (modes.j % n) * n + (modes.i % n)
    order = np.argsort(folded, kind="stable")
    sorted_bins = folded[order]
    starts = np.flatnonzero(np.r_[True, sorted_bins[1:] != sorted_bins[:-1]])
    lead = coeffs.shape[:-1]
    spectrum = np.zeros(lead + (n * n,), dtype=complex)
    spectrum[..., sorted_bins[starts]] = np.add.reduceat(coeffs[..., order], starts, axis=-1)
    values = np.fft.ifft2(spectrum.reshape(lead + (n, n)), norm="forward").real
    # FFT index q is the centre offset p - m (mod n): shift so index p is the p-th centre.
    return np.fft.fftshift(values, axes=(-2, -1))


def centre_values(modes: Band, coeffs: np.ndarray, n_cells: int, cell_size: float) -> np.ndarray:
    """Exact values of fields of any period at the n x n cell centres, by separable partial DFTs.

    ``psi[q, p] = Re sum_j sum_i E_y[q, j] C[j, i] E_x[p, i]`` with ``E[p, i] = exp(2 pi i i
    x_p / L)`` and ``C`` the coefficient table (``j >= 0``, ``-top <= i <= top``): one complex GEMM
    over all fields for the x sum, two real GEMMs for the real part of the y sum.

    Parameters
    ----------
    modes
        The band (any period).
    coeffs
        Complex coefficients, shape (..., modes.size).
    n_cells
        Cells along one side (odd).
    cell_size
        Cell pitch, in m.

    Returns
    -------
    numpy.ndarray
        float64, shape (..., n_cells, n_cells), indexed ``[..., y, x]``.
    """
    phase = 2.0 * np.pi * (np.arange(n_cells) - (n_cells - 1) / 2.0) * cell_size / modes.period
    return _separable(modes, coeffs, phase, phase)


def grid_values(modes: Band, coeffs: np.ndarray, x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Exact values of fields on any rectilinear grid of points (e.g. a finer image of the window).

    The continuous field of :func:`field_at_points`, evaluated like :func:`centre_values` by
    separable partial DFTs, so a fine grid costs two GEMMs instead of a sum per point.

    Parameters
    ----------
    modes
        The band (any period).
    coeffs
        Complex coefficients, shape (..., modes.size).
    x, y
        1-D point coordinates along x and y, in m, relative to the window centre.

    Returns
    -------
    numpy.ndarray
        float64, shape (..., y.size, x.size), indexed ``[..., y, x]``.
    """
    step = 2.0 * np.pi / modes.period
    return _separable(modes, coeffs, step * np.asarray(x, float), step * np.asarray(y, float))


def _separable(modes: Band, coeffs: np.ndarray, phase_x: np.ndarray, phase_y: np.ndarray) -> np.ndarray:
    """Fields at the points ``(x, y)`` whose phases ``2 pi x / L`` and ``2 pi y / L`` are given."""
    lead = coeffs.shape[:-1]
    batch = int(np.prod(lead, dtype=int))
    nx, ny = phase_x.size, phase_y.size
    top = int(max(np.abs(modes.i).max(), modes.j.max()))
    table = np.zeros((batch, top + 1, 2 * top + 1), dtype=complex)  # [field, j, i + top]
    table[:, modes.j, modes.i + top] = coeffs.reshape(batch, -1)
    ex = np.exp(1j * np.outer(phase_x, np.arange(-top, top + 1)))  # (x, i)
    ey = np.exp(1j * np.outer(phase_y, np.arange(0, top + 1)))  # (y, j)
    partial = (table.reshape(-1, 2 * top + 1) @ ex.T).reshape(batch, top + 1, nx)  # (field, j, x)
    partial = partial.transpose(1, 0, 2).reshape(top + 1, batch * nx)
    values = ey.real @ partial.real - ey.imag @ partial.imag  # (y, field * x)
    return values.reshape(ny, batch, nx).transpose(1, 0, 2).reshape(lead + (ny, nx))


def realize(
    modes: Band,
    seed: int,
    lam: float,
    realizations: np.ndarray,
    amplitudes: str,
    n_cells: int,
    cell_size: float,
) -> np.ndarray:
    """Fields of the given realizations at the cell centres, float32 (realization, y, x).

    Window-period bands (``modes.period == n_cells * cell_size``) are evaluated by folding
    (:func:`cell_values`), longer periods by :func:`centre_values`; either way realization r
    always gets the same field, from its own stream :func:`~g2tom.physics.oxide_band.field_stream`.
    """
    coeffs = np.stack([coefficients(modes, field_stream(seed, lam, r), amplitudes) for r in realizations])
    if modes.period == n_cells * cell_size:
        return cell_values(modes, coeffs, n_cells).astype(np.float32)
    return centre_values(modes, coeffs, n_cells, cell_size).astype(np.float32)


def field_at_points(modes: Band, coeffs: np.ndarray, x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Value of one field at arbitrary points by direct summation of its modes.

    Parameters
    ----------
    modes
        The band.
    coeffs
        Complex coefficients of one field, shape (modes.size,).
    x, y
        Point coordinates in m (broadcast together), relative to the window centre.

    Returns
    -------
    numpy.ndarray
        float64 with the broadcast shape of ``x`` and ``y``.
    """
    x, y = np.broadcast_arrays(np.asarray(x, float), np.asarray(y, float))
    top = int(max(np.abs(modes.i).max(), modes.j.max()))
    table = np.zeros((top + 1, 2 * top + 1), dtype=complex)  # [j, i + top]
    table[modes.j, modes.i + top] = coeffs
    step = 2.0 * np.pi / modes.period
    ex = np.exp(1j * step * np.outer(x.ravel(), np.arange(-top, top + 1)))
    ey = np.exp(1j * step * np.outer(y.ravel(), np.arange(0, top + 1)))
    return np.einsum("pj,pj->p", ey, ex @ table.T).real.reshape(x.shape)


def theoretical_threshold(xi: np.ndarray) -> np.ndarray:
    """Gaussian threshold ``psi0 = sqrt(2) erfcinv(2 xi)``: P(psi >= psi0) = xi for N(0, 1).

    Parameters
    ----------
    xi
        Oxide fractions in (0, 1).

    Returns
    -------
    numpy.ndarray
        Thresholds, dimensionless, same shape as ``xi``.
    """
    xi = np.asarray(xi, dtype=float)
    if np.any((xi <= 0) | (xi >= 1)):
        raise ValueError(f"xi = {xi} is out of range: every value must be in (0, 1)")
    return np.sqrt(2.0) * erfcinv(2.0 * xi)


def covered_count(xi: np.ndarray, n_points: int) -> np.ndarray:
    """Number of covered cells the empirical rule aims at: ``round(xi * n_points)`` (half to even)."""
    return np.rint(np.asarray(xi, dtype=float) * n_points).astype(int)


def empirical_threshold(values: np.ndarray, xi: np.ndarray) -> np.ndarray:
    """Each field's own threshold so that exactly ``round(xi N)`` of its N values are covered.

    The threshold is the ``K``-th largest value itself (``K = round(xi N)``), so ``values >=
    threshold`` covers exactly K cells unless the K-th and (K+1)-th largest values are equal
    (ties; then the tied cells are all covered). K = 0 gives +inf (nothing covered).

    Parameters
    ----------
    values
        Field values, shape (..., N); compared in their own dtype.
    xi
        Oxide fractions in (0, 1), shape (n_xi,).

    Returns
    -------
    numpy.ndarray
        Thresholds, shape (n_xi, ...), dtype of ``values``.
    """
    n = values.shape[-1]
    count = covered_count(xi, n)
    ordered = np.sort(values, axis=-1)  # ascending: K-th largest is at N - K
    padded = np.concatenate([ordered, np.full(values.shape[:-1] + (1,), np.inf, values.dtype)], axis=-1)
    return np.moveaxis(padded[..., n - count], -1, 0)
