"""Band-limited Gaussian random fields for the oxide islands (Sect. 2.6), pure numpy/scipy.

The field is periodic over the square spot window of side ``L = n_cells * cell_size``, so its
wave vectors lie on the lattice ``k = 2 pi (i, j) / L`` (``i`` along x, ``j`` along y). It is

    psi(x, y) = Re sum_k c_k exp(i (k_x x + k_y y)),

summed over one wave vector of every Hermitian pair (the half plane ``j > 0`` or ``j = 0,
i > 0``) inside the band ``k1 <= |k| <= ks`` with ``k1 = pi / l_O``, ``l_O = lambda *
cell_size`` and ``ks = ks_ratio * k1``. The complex coefficients are ``c_k = a_k exp(i phi_k)``
with uniform random phases ``phi_k`` and amplitudes ``a_k`` proportional to ``sqrt(Phi(|k|))``,
``Phi(k) = k^-2(1+H)`` ("ideal"), optionally multiplied by a unit Rayleigh variate
("rayleigh"). The field has no mean mode, and its variance over one period is
``sum |c_k|^2 / 2``; every realization is rescaled so that this variance is exactly 1, i.e. the
field is rescaled by its own standard deviation over the whole window (the standard deviation a
fine image of the field would have), not by the sample standard deviation of the few cell values.

Exact values at the cell centres. The centres are ``x_p = (p - m) h`` with ``h = L / n``,
``m = (n - 1) / 2`` (``n`` odd), so ``exp(2 pi i i x_p / L) = exp(2 pi i (i mod n)(p - m) / n)``:
a mode takes at the centres exactly the values of the lattice mode ``(i mod n, j mod n)``.
Folding every coefficient onto that n x n spectrum and doing one n x n inverse FFT gives the
continuous field's point values, also where ``ks`` lies above the grid's Nyquist frequency
(lambda near 1); :func:`field_at_points` is the slow reference.

Spectral period. With the window as the period the band ``k1..3 k1`` holds only n / (2 lambda)
... 3n / (2 lambda) lattice steps: a few dozen modes at lambda >= 13, and which rings fall inside
jumps between neighbouring lambda. :func:`spectral_period` instead picks a period of ``P >= n``
cells with ``k1 = P / (2 lambda)`` at least ``resolution`` lattice steps, so the annulus holds
about ``4 pi resolution^2`` half-plane modes at every lambda and samples the continuous spectrum
Phi(k) on a lattice ``resolution`` times finer than k1. Such a field is evaluated exactly at the
n x n cell centres by separable partial DFTs (:func:`centre_values`): ``psi = Re(E_y C E_x^T)``
with ``C`` the half-plane coefficient table, two GEMMs whose size depends on ``resolution`` only,
so the cost per field is about constant in lambda.

Unit variance. ``sum |c_k|^2 / 2 = 1`` is the variance of the field over its whole period, i.e.
of the continuous spectrum (for "ideal" amplitudes, the ensemble variance at every point). With a
period larger than the window, one realization's sample variance over the window fluctuates
around 1 and its window mean around 0: those are the large-scale fluctuations a finite window of
an infinite surface sees, and they are not normalized away.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.special import erfcinv

__all__ = [
    "Band",
    "band",
    "spectral_period",
    "field_stream",
    "coefficients",
    "cell_values",
    "centre_values",
    "grid_values",
    "realize",
    "field_at_points",
    "theoretical_threshold",
    "empirical_threshold",
    "covered_count",
]

#: Resolution of lambda in the random-stream key: lambda values closer than this share a stream.
LAMBDA_KEY_SCALE = 1_000_000


@dataclass(frozen=True)
class Band:
    """The wave vectors of one correlation length on the window's lattice.

    Attributes
    ----------
    i, j
        Integer lattice indices of the wave vectors ``2 pi (i, j) / period`` (x and y), one per
        Hermitian pair, in a fixed order (ascending ``j``, then ``i``): the order of the draws.
    weight
        Amplitude ``sqrt(Phi(|k|))`` of every mode, scaled so that an "ideal" field has unit
        variance, dimensionless.
    period
        Side ``L`` of the periodic window, in m.
    """

    i: np.ndarray
    j: np.ndarray
    weight: np.ndarray
    period: float

    @property
    def size(self) -> int:
        """Number of independent modes (Hermitian pairs) in the band."""
        return int(self.i.size)


def spectral_period(n_cells: int, lam: float, resolution: float) -> int:
    """Period in cells of a field whose k1 spans at least ``resolution`` lattice steps.

    Parameters
    ----------
    n_cells
        Cells along one side of the window: the period is never shorter.
    lam
        Normalized correlation length, > 0.
    resolution
        Wanted ``k1`` in lattice steps ``2 pi / period`` (k1 = pi / l_O), > 0.

    Returns
    -------
    int
        ``max(n_cells, ceil(2 lam resolution))``.
    """
    if not (lam > 0 and resolution > 0):
        raise ValueError(f"lambda = {lam}, resolution = {resolution}: both must be > 0")
    return max(int(n_cells), int(np.ceil(2.0 * lam * resolution)))


def band(
    n_cells: int, cell_size: float, lam: float, ks_ratio: float, hurst: float,
    period_cells: int | None = None,
) -> Band:
    """Lattice wave vectors in ``k1 <= |k| <= ks`` with their spectral amplitudes.

    Parameters
    ----------
    n_cells
        Cells along one side of the window; the period is ``n_cells * cell_size`` unless
        ``period_cells`` is given.
    cell_size
        Cell pitch 1/sqrt(eta), in m.
    lam
        Normalized correlation length ``lambda = l_O sqrt(eta)``, dimensionless, > 0.
    ks_ratio
        Upper to lower cut-off ``ks / k1``, > 1.
    hurst
        Hurst exponent H in (0, 1) of the spectrum ``Phi(k) = k^-2(1+H)``.
    period_cells
        Period in cells (>= n_cells), e.g. from :func:`spectral_period`; default the window.

    Returns
    -------
    Band

    Raises
    ------
    ValueError
        If a parameter is out of range or the band holds no lattice mode.
    """
    _check_band_parameters(n_cells, cell_size, lam, ks_ratio, hurst)
    cells = n_cells if period_cells is None else int(period_cells)
    if cells < n_cells:
        raise ValueError(f"period_cells = {cells} is out of range: must be >= n_cells = {n_cells}")
    period = cells * cell_size
    # |k| in units of the lattice step 2 pi / L: k1 = pi / (lam h) -> P / (2 lam).
    k1 = cells / (2.0 * lam)
    ks = ks_ratio * k1
    top = int(np.floor(ks))
    j, i = np.meshgrid(np.arange(0, top + 1), np.arange(-top, top + 1), indexing="ij")
    i, j = i.ravel(), j.ravel()
    radius = np.hypot(i, j)
    keep = (radius >= k1) & (radius <= ks) & ((j > 0) | (i > 0))
    i, j, radius = i[keep], j[keep], radius[keep]
    if i.size == 0:
        raise ValueError(
            f"lambda = {lam:g}: the band k1..ks holds no Fourier mode of a period of "
            f"{cells} cells"
        )
    weight = radius ** (-(1.0 + hurst))
    weight *= np.sqrt(2.0 / np.sum(weight**2))
    return Band(i=i, j=j, weight=weight, period=period)


def _check_band_parameters(
    n_cells: int, cell_size: float, lam: float, ks_ratio: float, hurst: float
) -> None:
    """Raise ValueError for a parameter of :func:`band` out of range."""
    if n_cells < 1 or n_cells % 2 == 0:
        raise ValueError(f"n_cells = {n_cells} is out of range: must be odd and >= 1")
    if not cell_size > 0:
        raise ValueError(f"cell_size = {cell_size} is out of range: must be > 0 (m)")
    if not lam > 0:
        raise ValueError(f"lambda = {lam} is out of range: must be > 0")
    if not ks_ratio > 1:
        raise ValueError(f"ks_ratio = {ks_ratio} is out of range: must be > 1")
    if not 0 < hurst < 1:
        raise ValueError(f"hurst = {hurst} is out of range: must be in (0, 1)")


def field_stream(seed: int, lam: float, realization: int) -> np.random.Generator:
    """The random stream of one field, independent of chunking, workers and evaluation order.

    The stream is ``SeedSequence(seed, spawn_key=(round(lam * 1e6), realization))``: it is keyed
    on the value of lambda (not its position in the list), so adding or removing a correlation
    length leaves the other fields unchanged.

    Parameters
    ----------
    seed
        Root seed of the scenario, >= 0.
    lam
        Normalized correlation length, > 0.
    realization
        Realization index, >= 0.

    Returns
    -------
    numpy.random.Generator
        A PCG64 generator private to this (seed, lambda, realization).
    """
    key = (int(round(lam * LAMBDA_KEY_SCALE)), int(realization))
    return np.random.Generator(np.random.PCG64(np.random.SeedSequence(seed, spawn_key=key)))


def coefficients(modes: Band, rng: np.random.Generator, amplitudes: str = "ideal") -> np.ndarray:
    """Complex mode coefficients ``c_k`` of one unit-variance field.

    Draws the phases (uniform on [0, 2 pi)) first, then, for "rayleigh", one unit Rayleigh
    factor per mode; both in the band's mode order.

    Parameters
    ----------
    modes
        The band, from :func:`band`.
    rng
        The field's stream, from :func:`field_stream`.
    amplitudes
        "ideal" (fixed amplitudes ``sqrt(Phi)``) or "rayleigh" (``sqrt(Phi)`` times Rayleigh).

    Returns
    -------
    numpy.ndarray
        Complex, shape (modes.size,), with ``sum |c|^2 / 2 = 1`` (unit variance over the window).
    """
    phase = np.exp(2j * np.pi * rng.random(modes.size))
    if amplitudes == "ideal":
        return modes.weight * phase
    if amplitudes != "rayleigh":
        raise ValueError(f"amplitudes = {amplitudes!r} is not allowed: must be 'ideal' or 'rayleigh'")
    amplitude = modes.weight * rng.rayleigh(1.0, modes.size)
    return amplitude * np.sqrt(2.0 / np.sum(amplitude**2)) * phase


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
    always gets the same field, from its own stream :func:`field_stream`.
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
