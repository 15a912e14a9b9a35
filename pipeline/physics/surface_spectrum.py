"""Spectral moments of a measured surface below a stated cutoff, and its summits' GW parameters.

:func:`psd_moments` estimates the profile moments m0, m2, m4 of an isotropic height map from its
power spectrum up to a short-wavelength cutoff (the finite-difference estimate of
:mod:`g2tom.physics.roughness` has no explicit cutoff); :func:`summit_parameters` turns them
into the Greenwood–Williamson summit statistics via Nayak's bandwidth parameter.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from g2tom.physics.roughness import detrend

__all__ = ["SpectralMoments", "psd_moments", "SummitParameters", "summit_parameters", "BETA_RULES", "MIN_SIDE"]

#: Smallest side (pixels) of a map whose m4 can be estimated (a few wavelengths of >= 2 pixels).
MIN_SIDE = 8
#: Summit-curvature rules for beta: the paper's constant, and Nayak's mean summit curvature
#: (8/3) sqrt(m4/pi) for a large bandwidth parameter (beta = 0.375 sqrt(pi/m4) = 0.665/sqrt(m4)).
BETA_RULES = {"paper": "0.737/sqrt(m4)", "nayak": "0.375 sqrt(pi/m4)"}


@dataclass(frozen=True)
class SpectralMoments:
    """Profile spectral moments of an isotropic surface below a short-wavelength cutoff.

    Attributes
    ----------
    rms_height
        Standard deviation of the detrended heights (every wavelength), m.
    m0, m2, m4
        Moments of the profile spectrum up to the cutoff: m^2, dimensionless, m^-2.
    cutoff_wavelength
        Shortest wavelength counted, m.
    detrending
        ``"plane"`` (least-squares plane removed) or ``"mean"`` (periodic maps).
    window
        ``"hann"`` (non-periodic maps) or ``"none"`` (periodic maps).
    """

    rms_height: float
    m0: float
    m2: float
    m4: float
    cutoff_wavelength: float
    detrending: str
    window: str


def _hann(n: int) -> np.ndarray:
    return 0.5 - 0.5 * np.cos(2.0 * np.pi * np.arange(n) / n)


def psd_moments(heights: ArrayLike, pixel_size: tuple[float, float], cutoff_wavelength: float,
                periodic: bool = False) -> SpectralMoments:
    """m0, m2, m4 of an isotropic height map from its power spectrum below a cutoff.

    With P(q) the share of the height variance in the Fourier mode q of the map, the moments of
    any straight profile through an isotropic surface are (direction averages of cos^2 and
    cos^4 being 1/2 and 3/8; Nayak 1971)

        m0 = sum P,   m2 = 1/2 sum |q|^2 P,   m4 = 3/8 sum |q|^4 P,

    summed over 0 < |q| <= 2 pi / cutoff_wavelength. A periodic map is taken as it is (mean
    removed); a measured, non-periodic one has its least-squares plane removed and is multiplied
    by a 2-D Hann window scaled to unit mean square, so its edges do not leak into the spectrum.

    Parameters
    ----------
    heights
        Height map, shape (ny, nx), m.
    pixel_size
        Pixel pitch (dy, dx), m.
    cutoff_wavelength
        Shortest wavelength counted, m (at least two pixels of the coarser axis: the Nyquist limit).
    periodic
        Whether the map is one period of a periodic surface.

    Raises
    ------
    ValueError
        If the map is smaller than :data:`MIN_SIDE` pixels a side, or the cutoff is below two
        pixels or longer than a quarter of the shorter side (too few modes for m4).
    """
    z = np.asarray(heights, dtype=float)
    ny, nx = z.shape
    dy, dx = (float(v) for v in pixel_size)
    if min(ny, nx) < MIN_SIDE:
        raise ValueError(f"height map has shape {z.shape}: m4 needs at least {MIN_SIDE} x {MIN_SIDE} pixels")
    nyquist, longest = 2.0 * max(dx, dy), min(nx * dx, ny * dy) / 4.0
    if not nyquist * (1 - 1e-12) <= cutoff_wavelength <= longest:
        raise ValueError(f"cutoff wavelength = {cutoff_wavelength:.4g} m is out of range: must be >= "
                         f"{nyquist:.4g} m (2 pixels) and <= {longest:.4g} m (a quarter of the shorter side)")
    if periodic:
        z = z - z.mean()
        detrending, window = "mean", "none"
        weighted = z
    else:
        z = detrend(z)
        detrending, window = "plane", "hann"
        w = np.outer(_hann(ny), _hann(nx))
        weighted = z * w / np.sqrt(np.mean(w**2))
    if np.sqrt(np.mean(z**2)) <= 1e-12 * max(float(np.max(np.abs(np.asarray(heights, float)))), np.finfo(float).tiny):
        raise ValueError(f"height map is flat once its {detrending} is removed: m0, m2 and m4 vanish")
    power = np.abs(np.fft.fft2(weighted)) ** 2 / (nx * ny) ** 2
    qy = 2.0 * np.pi * np.fft.fftfreq(ny, dy)
    qx = 2.0 * np.pi * np.fft.fftfreq(nx, dx)
    q2 = qy[:, None] ** 2 + qx[None, :] ** 2
    band = (q2 > 0) & (q2 <= (2.0 * np.pi / cutoff_wavelength) ** 2 * (1 + 1e-12))
    p = power[band]
    return SpectralMoments(
        rms_height=float(np.sqrt(np.mean(z**2))),
        m0=float(p.sum()), m2=0.5 * float((p * q2[band]).sum()), m4=0.375 * float((p * q2[band] ** 2).sum()),
        cutoff_wavelength=float(cutoff_wavelength), detrending=detrending, window=window,
    )


@dataclass(frozen=True)
class SummitParameters:
    """Greenwood–Williamson parameters of the summits of an isotropic Gaussian surface.

    Attributes
    ----------
    bandwidth
        Nayak's alpha = m0 m4 / m2^2 (>= 1.5 for an isotropic Gaussian surface), dimensionless.
    sigma
        Standard deviation of summit heights, m.
    summit_mean_height
        Mean summit height above the surface's mean plane, m.
    eta
        Summit density, m^-2.
    beta
        Mean summit radius of curvature, m, by ``beta_rule``.
    beta_rule
        Key of :data:`BETA_RULES`.
    """

    bandwidth: float
    sigma: float
    summit_mean_height: float
    eta: float
    beta: float
    beta_rule: str


def summit_parameters(m0: float, m2: float, m4: float, beta_rule: str = "paper") -> SummitParameters:
    """GW summit statistics from profile moments (Nayak 1973; McCool, Wear 107 (1986) 37).

    With the bandwidth parameter alpha = m0 m4 / m2^2 (McCool's approximations of Nayak's
    results for an isotropic Gaussian surface):

    * summit height std       sigma_s = sqrt(1 - 0.8968 / alpha) sqrt(m0),
    * mean summit height      z_s = 4 sqrt(m0 / (pi alpha)) above the mean plane,
    * summit density          eta = m4 / (6 pi sqrt(3) m2) = sqrt(3)/(18 pi) m4/m2,
    * mean summit radius      beta = 0.737/sqrt(m4) (``paper``, the paper's Sect. 3.2) or
      0.375 sqrt(pi/m4) (``nayak``: the inverse of Nayak's mean summit curvature
      (8/3) sqrt(m4/pi) for large alpha), the first 10.9 % larger.

    Raises
    ------
    ValueError
        If a moment is not positive, alpha < 1.5 (no Gaussian isotropic surface has it) or the
        rule is unknown.
    """
    if not (m0 > 0 and m2 > 0 and m4 > 0):
        raise ValueError(f"spectral moments m0 = {m0:.4g}, m2 = {m2:.4g}, m4 = {m4:.4g} must be > 0")
    if beta_rule not in BETA_RULES:
        raise ValueError(f"beta rule = {beta_rule!r} is not allowed: must be one of {', '.join(BETA_RULES)}")
    alpha = m0 * m4 / m2**2
    if alpha < 1.5:
        raise ValueError(f"bandwidth parameter alpha = m0 m4/m2^2 = {alpha:.4g} is out of range: an isotropic "
                         "Gaussian surface has alpha >= 1.5 (is the map isotropic and the cutoff sensible?)")
    beta = 0.737 / np.sqrt(m4) if beta_rule == "paper" else 0.375 * np.sqrt(np.pi / m4)
    return SummitParameters(
        bandwidth=float(alpha),
        sigma=float(np.sqrt((1.0 - 0.8968 / alpha) * m0)),
        summit_mean_height=float(4.0 * np.sqrt(m0 / (np.pi * alpha))),
        eta=float(m4 / (6.0 * np.pi * np.sqrt(3.0) * m2)),
        beta=float(beta),
        beta_rule=beta_rule,
    )
