"""The oxide field's spectrum on a lattice (Sect. 2.6): the band of one correlation length and its draws.

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

Spectral period. With the window as the period the band ``k1..3 k1`` holds only n / (2 lambda)
... 3n / (2 lambda) lattice steps: a few dozen modes at lambda >= 13, and which rings fall inside
jumps between neighbouring lambda. :func:`spectral_period` instead picks a period of ``P >= n``
cells with ``k1 = P / (2 lambda)`` at least ``resolution`` lattice steps, so the annulus holds
about ``4 pi resolution^2`` half-plane modes at every lambda and samples the continuous spectrum
Phi(k) on a lattice ``resolution`` times finer than k1. Such a field is evaluated exactly at the
n x n cell centres by separable partial DFTs (:func:`g2tom.physics.oxide_field.centre_values`): ``psi = Re(E_y C E_x^T)``
with ``C`` the half-plane coefficient table, two GEMMs whose size depends on ``resolution`` only,
so the cost per field is about constant in lambda.

Unit variance. ``sum |c_k|^2 / 2 = 1`` is the variance of the field over its whole period, i.e.
of the continuous spectrum (for "ideal" amplitudes, the ensemble variance at every point). With a
period larger than the window, one realization's sample variance over the window fluctuates
around 1 and its window mean around 0: those are the large-scale fluctuations a finite window of
an infinite surface sees, and they are not normalized away.
"

The values of the fields (at the cell centres, on any grid, at any point) and their thresholds are
:mod:`g2tom.physics.oxide_field`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["LAMBDA_KEY_SCALE", "Band", "band", "spectral_period", "field_stream", "coefficients"]

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
