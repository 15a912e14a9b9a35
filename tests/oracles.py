"""Independent references the tests check the production code against (slow or simple on purpose).

* :func:`fine_grid`: oxide fields synthesised on a fine pixel image by one inverse FFT.
* :func:`spot_points`, :func:`clean_share`: the disc rule's points and clean shares, spot by
  spot in plain NumPy (the compiled :func:`g2tom.physics.spot_share.disc_points` and
  :func:`~g2tom.physics.spot_share.disc_shares` equal them).
* :func:`roughness_parameters`: Greenwood–Williamson parameters of a height map from
  finite-difference moments, independent of the spectral estimator of
  :mod:`g2tom.physics.surface_spectrum`:

  The spectral moments of an isotropic surface are those of any straight profile through it
  (Nayak): ``m0 = <z^2>``, ``m2 = <(dz/dx)^2>``, ``m4 = <(d^2z/dx^2)^2>``. For an isotropic map
  they are estimated from all directions at once, as averages over the map:

      m2 = <|grad z|^2> / 2,       m4 = 3/8 <(laplacian z)^2>,

  (the direction averages of cos^2 and cos^4 being 1/2 and 3/8). Derivatives are taken by
  second-order central finite differences on the interior pixels, not by FFT: a measured map
  is not periodic, and the jump at its edges would leak into an FFT spectrum and inflate m4.
  For a spectral component of wavelength L the finite differences underestimate m2 and m4
  by a relative (k h)^2 / 4 and (k h)^2 / 8 on average over directions (k = 2 pi / L, h: pixel
  size; up to (k h)^2 / 3 and / 6 along a grid axis): about 4 % and 2 % at 16 pixels per
  wavelength, under 1 % and 0.5 % above 32. The best-fit plane is removed before anything is
  computed.

  Then ``sigma = sqrt(m0)``, ``eta = sqrt(3)/(18 pi) m4/m2`` and ``beta = 0.737/sqrt(m4)``.
  Note that sigma here is the standard deviation of the surface heights; the asperity-height
  sigma of the Greenwood–Williamson model is smaller at low Nayak parameter (Sect. 3.2).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from g2tom.physics.oxide_band import Band
from g2tom.physics.spot_share import DiscRule
from g2tom.physics.roughness import detrend, validated_heights


def fine_grid(modes: Band, coeffs: np.ndarray, n_pixels: int) -> np.ndarray:
    """Synthesis of fields on a fine n_pixels x n_pixels image of the window (the slow way).

    Pixel ``(a, b)`` lies at ``(x, y) = (b, a) * period / n_pixels`` relative to the window
    centre (the centre is pixel (0, 0); coordinates wrap with the period).

    Parameters
    ----------
    modes
        The band; every mode must lie below the image's Nyquist index ``n_pixels / 2``.
    coeffs
        Complex coefficients, shape (..., modes.size).
    n_pixels
        Image side in pixels.

    Returns
    -------
    numpy.ndarray
        float64, shape (..., n_pixels, n_pixels), indexed ``[..., y, x]``.
    """
    top = max(np.abs(modes.i).max(), modes.j.max())
    if 2 * top >= n_pixels:
        raise ValueError(
            f"n_pixels = {n_pixels} is too small: modes up to index {top} need more than {2 * top}"
        )
    lead = coeffs.shape[:-1]
    spectrum = np.zeros(lead + (n_pixels, n_pixels), dtype=complex)
    spectrum[..., modes.j % n_pixels, modes.i % n_pixels] = coeffs
    return np.fft.ifft2(spectrum, norm="forward").real


@dataclass(frozen=True)
class RoughnessParameters:
    """Roughness statistics of a height map.

    Attributes
    ----------
    sigma
        Standard deviation of heights, m.
    m2
        Second spectral moment (mean squared profile slope), dimensionless.
    m4
        Fourth spectral moment (mean squared profile curvature), m^-2.
    eta
        Asperity density sqrt(3)/(18 pi) m4/m2, m^-2.
    beta
        Mean asperity tip radius 0.737/sqrt(m4), m.
    """

    sigma: float
    m2: float
    m4: float
    eta: float
    beta: float


def spectral_moments(heights: ArrayLike, pixel_size: float) -> tuple[float, float, float]:
    """m0, m2 and m4 of a detrended, isotropic height map.

    Parameters
    ----------
    heights
        Height map, shape (ny, nx) with ny, nx >= 3, in m.
    pixel_size
        Pixel pitch (the same along x and y), m, > 0.

    Returns
    -------
    tuple of float
        m0 (m^2), m2 (dimensionless), m4 (m^-2).
    """
    z = detrend(heights)
    h = float(pixel_size)
    core = z[1:-1, 1:-1]
    dzdx = (z[1:-1, 2:] - z[1:-1, :-2]) / (2.0 * h)
    dzdy = (z[2:, 1:-1] - z[:-2, 1:-1]) / (2.0 * h)
    laplacian = (z[1:-1, 2:] + z[1:-1, :-2] + z[2:, 1:-1] + z[:-2, 1:-1] - 4.0 * core) / h**2
    m0 = float(np.mean(z**2))
    m2 = 0.5 * float(np.mean(dzdx**2 + dzdy**2))
    m4 = 3.0 / 8.0 * float(np.mean(laplacian**2))
    return m0, m2, m4


def roughness_parameters(heights: ArrayLike, pixel_size: float) -> RoughnessParameters:
    """sigma, m2, m4, eta and beta of a height map (Sect. 3.2).

    Parameters
    ----------
    heights
        Height map, 2-D, at least 3 x 3 pixels, finite, in m.
    pixel_size
        Pixel pitch, m, > 0.

    Raises
    ------
    ValueError
        If the map is complex-valued, not numeric, not 2-D, too small, not finite or flat
        (after detrending), or the pixel size is not positive.
    """
    z = validated_heights(heights)
    if not (np.isfinite(pixel_size) and pixel_size > 0):
        raise ValueError(f"pixel size = {pixel_size} is out of range: must be > 0 (m)")
    m0, m2, m4 = spectral_moments(z, pixel_size)
    scale = max(float(np.max(np.abs(z))), np.finfo(float).tiny)
    if m0 <= (1e-12 * scale) ** 2 or m2 <= 0.0 or m4 <= 0.0:
        raise ValueError("height map is flat (a plane after detrending): sigma, m2 and m4 vanish")
    return RoughnessParameters(
        sigma=float(np.sqrt(m0)),
        m2=m2,
        m4=m4,
        eta=float(np.sqrt(3.0) / (18.0 * np.pi) * m4 / m2),
        beta=float(0.737 / np.sqrt(m4)),
    )


def spot_points(x: np.ndarray, y: np.ndarray, a: np.ndarray, rule: DiscRule) -> tuple[np.ndarray, np.ndarray]:
    """The rule's points on every spot: ``(x_i + a_i u, y_i + a_i v)``.

    Parameters
    ----------
    x, y
        Spot centres, m, shape (n_spots,).
    a
        Spot radii, m, shape (n_spots,).
    rule
        The quadrature pattern.

    Returns
    -------
    tuple of numpy.ndarray
        Point coordinates x and y, m, each shape (n_spots, rule.size).
    """
    u, v = rule.offsets()
    a = np.asarray(a, float)[:, None]
    return np.asarray(x, float)[:, None] + a * u, np.asarray(y, float)[:, None] + a * v


def clean_share(values: np.ndarray, threshold: np.ndarray | float, weights: np.ndarray) -> np.ndarray:
    """Weighted share of every spot's quadrature points where the field is clean (``psi < psi0``).

    Parameters
    ----------
    values
        Field values at the spots' points, dimensionless, shape (..., n_spots, n_quad).
    threshold
        Oxide threshold psi0, dimensionless, broadcastable to ``values`` (e.g. shape (..., 1, 1)).
    weights
        Quadrature weights summing to 1, shape (n_quad,).

    Returns
    -------
    numpy.ndarray
        Clean share f in [0, 1], float64, shape (..., n_spots): exactly 1 where every point is
        clean (the spot keeps its own radius, whatever the rounding of the weights' sum), exactly
        0 where none is.
    """
    clean = np.asarray(values) < threshold
    return np.where(clean.all(axis=-1), 1.0, clean.astype(float) @ np.asarray(weights, float))
