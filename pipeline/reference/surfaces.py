"""Rigid surfaces on a grid: the sphere, GW surfaces and Gaussian random-process surfaces.

Pixel centres lie at ``(i - (n - 1) / 2) * pixel`` along x and y (``grid.cell_centres``), so the
sphere's axis is the grid's centre. Heights are in m, positive towards the elastic half-space.

* GW surface (Greenwood and Williamson): asperities at the points of a Poisson process of
  density eta, heights N(0, sigma^2), tips of curvature radius beta (paraboloids, as in Hertz's
  and GW's analysis): exactly g2tom's input parameters. Between asperities the surface lies at a
  ``floor`` far below any contact.
* Random-process surface: an isotropic self-affine spectrum ``C(q) ~ q^-2(1+H)`` on
  ``q_low <= |q| <= q_high``, synthesised with fixed amplitudes ``sqrt(C)`` and uniform random
  phases (periodic over the grid): Gaussian in the limit of many modes, and its spectral moments
  are those of the spectrum exactly (:func:`spectral_moments_closed_form`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from g2tom.physics.grid import cell_centres

__all__ = ["coordinates", "sphere", "Asperities", "gw_asperities", "gw_heights", "random_process",
           "spectral_moments_closed_form"]


def coordinates(n: int, pixel: float) -> tuple[np.ndarray, np.ndarray]:
    """Pixel-centre coordinates ``x, y`` (m), each (n, n), indexed ``[y, x]``."""
    c = cell_centres(n, pixel)
    return np.meshgrid(c, c, indexing="xy")


def sphere(n: int, pixel: float, radius: float) -> np.ndarray:
    """Heights of a sphere of ``radius`` (m) with its tip at height 0 on the axis (parabolic, Hertz)."""
    x, y = coordinates(n, pixel)
    return -(x**2 + y**2) / (2.0 * radius)


@dataclass(frozen=True)
class Asperities:
    """The asperities of a GW surface: tip positions ``x``, ``y`` and heights ``z`` (m), radius ``beta`` (m)."""

    x: np.ndarray
    y: np.ndarray
    z: np.ndarray
    beta: float


def gw_asperities(side: float, eta: float, sigma: float, beta: float, rng: np.random.Generator) -> Asperities:
    """Asperities of a GW surface on the square ``[-side/2, side/2]^2``.

    Parameters
    ----------
    side
        Side of the square, m.
    eta, sigma, beta
        Asperity density (m^-2), standard deviation of the tip heights (m), tip radius (m).
    rng
        The surface's own random stream: count (Poisson, mean eta side^2), then positions, then heights.
    """
    count = int(rng.poisson(eta * side**2))
    xy = rng.uniform(-side / 2.0, side / 2.0, size=(2, count))
    z = rng.normal(0.0, sigma, size=count)
    return Asperities(x=xy[0], y=xy[1], z=z, beta=float(beta))


def gw_heights(asperities: Asperities, n: int, pixel: float, floor: float) -> np.ndarray:
    """Heights (m, (n, n)) of the asperities: the highest tip ``z - d^2 / (2 beta)`` above each pixel, at least ``floor``.

    Only asperities above the floor whose reach (where the tip meets the floor) comes within a
    pixel of the grid are visited: a small window of a large surface skips the rest at once.
    """
    c = cell_centres(n, pixel)
    heights = np.full((n, n), float(floor))
    beta = asperities.beta
    above = asperities.z > floor
    reaches = np.sqrt(2.0 * beta * np.where(above, asperities.z - floor, 0.0))
    edge = float(np.abs(c).max()) + pixel
    near = above & (np.abs(asperities.x) - reaches <= edge) & (np.abs(asperities.y) - reaches <= edge)
    for x0, y0, z0 in zip(asperities.x[near], asperities.y[near], asperities.z[near]):
        reach = np.sqrt(2.0 * beta * (z0 - floor))  # beyond it the tip lies below the floor
        ix = np.flatnonzero(np.abs(c - x0) <= reach)
        iy = np.flatnonzero(np.abs(c - y0) <= reach)
        if ix.size == 0 or iy.size == 0:
            continue
        patch = z0 - ((c[ix][None, :] - x0) ** 2 + (c[iy][:, None] - y0) ** 2) / (2.0 * beta)
        block = heights[iy[0]:iy[-1] + 1, ix[0]:ix[-1] + 1]
        np.maximum(block, patch, out=block)
    return heights


def _band_modes(period: float, q_low: float, q_high: float) -> tuple[np.ndarray, np.ndarray]:
    """Integer wave vectors (kx, ky) of the periodic lattice (q = 2 pi k / period) in the band, one
    per +-pair (ky > 0, or ky = 0 and kx > 0), in a fixed order: (n_modes,) each."""
    top = int(np.ceil(q_high * period / (2.0 * np.pi)))
    kx, ky = np.meshgrid(np.arange(-top, top + 1), np.arange(0, top + 1), indexing="xy")
    kx, ky = kx.ravel(), ky.ravel()
    q = 2.0 * np.pi / period * np.hypot(kx, ky)
    keep = (q >= q_low) & (q <= q_high) & ((ky > 0) | (kx > 0))
    return kx[keep], ky[keep]


def random_process(n: int, pixel: float, hurst: float, q_low: float, q_high: float, rms: float,
                   rng: np.random.Generator, period: float | None = None) -> np.ndarray:
    """A self-affine surface (m, (n, n)) at the pixel centres, periodic over ``period``.

    The surface is one continuous function: a sum over the band's lattice modes
    ``q = 2 pi k / period`` with amplitudes ``q^-(1+H)`` and uniform random phases drawn in a
    fixed order of the modes, scaled to the variance ``rms^2`` of the continuous spectrum. So grids
    of any pixel over the same period sample the same surface (the validation's grid-convergence
    check relies on it), evaluated exactly by two separable partial DFTs.

    Parameters
    ----------
    n, pixel
        Grid side (pixels) and pitch (m).
    hurst
        Hurst exponent H in (0, 1): ``C(q) ~ q^-2(1+H)``.
    q_low, q_high
        Band of wave numbers, rad/m, ``2 pi / period <= q_low < q_high <= pi / pixel``.
    rms
        Standard deviation of the heights (of the continuous spectrum), m.
    rng
        The surface's random stream (one uniform phase per mode).
    period
        Period of the surface, m (default: the grid's side ``n pixel``).
    """
    period = n * pixel if period is None else period
    if not 0 < hurst < 1:
        raise ValueError(f"hurst = {hurst} is out of range: must be in (0, 1)")
    if not (2.0 * np.pi / period <= q_low < q_high <= np.pi / pixel):
        raise ValueError(f"q_low = {q_low:g}, q_high = {q_high:g} rad/m: need 2 pi / period <= q_low "
                         f"< q_high <= pi / pixel for period = {period:g} m, pixel = {pixel:g} m")
    kx, ky = _band_modes(period, q_low, q_high)
    q = 2.0 * np.pi / period * np.hypot(kx, ky)
    amplitude = q ** (-(1.0 + hurst))
    amplitude *= rms / np.sqrt(0.5 * np.sum(amplitude**2))
    coeff = amplitude * np.exp(2j * np.pi * rng.random(kx.size))
    top = int(max(np.abs(kx).max(), ky.max()))
    table = np.zeros((top + 1, 2 * top + 1), complex)  # [ky, kx + top]
    table[ky, kx + top] = coeff
    c = cell_centres(n, pixel)
    e_x = np.exp(2j * np.pi / period * np.outer(c, np.arange(-top, top + 1)))  # (n, 2 top + 1)
    e_y = np.exp(2j * np.pi / period * np.outer(c, np.arange(0, top + 1)))  # (n, top + 1)
    return np.real(e_y @ table @ e_x.T)


def spectral_moments_closed_form(hurst: float, q_low: float, q_high: float, rms: float) -> tuple[float, float, float]:
    """Profile moments m0 (m^2), m2 (1), m4 (m^-2) of the continuous isotropic band ``C(q) ~ q^-2(1+H)``.

    ``m_2k = c_k int C(q) q^(2k+1) dq / int C(q) q dq * rms^2`` with the direction averages
    ``c_1 = <cos^2> = 1/2`` and ``c_2 = <cos^4> = 3/8``.
    """
    def integral(power: float) -> float:  # int_{q_low}^{q_high} q^power dq
        return (q_high ** (power + 1) - q_low ** (power + 1)) / (power + 1)

    base = integral(-1.0 - 2.0 * hurst)
    m0 = rms**2
    return m0, 0.5 * m0 * integral(1.0 - 2.0 * hurst) / base, 0.375 * m0 * integral(3.0 - 2.0 * hurst) / base
