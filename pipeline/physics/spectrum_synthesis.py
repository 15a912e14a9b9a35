"""Surfaces drawn from a measured map's own isotropic power spectrum (``g2tom surface --extend spectrum``).

**The spectrum.** The map's measured area, its plane removed, is multiplied by the window of the
area (:func:`g2tom.physics.masked_moments.measured_window`: 0 outside, tapering along the edge)
and Fourier-transformed on the map's grid; ``|c_k|^2 = |FFT(w h)|^2 / (N sum w^2)`` (N pixels)
estimates the power of the lattice mode k, and ``C(q) = A |c_k|^2`` (A the map's area, m^4) is
independent of the period. C is averaged over the modes in logarithmic rings of |q| from the map's
longest wavelength ``q_min = 2 pi / L`` (L its longer side) to the Nyquist ``pi / pixel``.

**Synthesis.** A surface of period P is ``sum_k c_k exp(i k x)`` over the lattice ``2 pi / P``
with ``|c_k| = sqrt(C(|k|) / P^2)`` and uniform random phases: C interpolated log-log between the
rings; above the Nyquist nothing; **below q_min (wavelengths longer than the map) the spectrum is
rolled off to a plateau at C(q_min)** — the measured wavelengths are kept, the longer ones carry
the power of the longest measured one per mode, a self-affine surface's roll-off.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from g2tom.physics.masked_moments import measured_window
from g2tom.physics.roughness import detrend

__all__ = ["RINGS_PER_DECADE", "IsotropicSpectrum", "isotropic_spectrum", "synthesize"]

#: Logarithmic rings per decade of |q| in the radial average.
RINGS_PER_DECADE = 20


@dataclass(frozen=True)
class IsotropicSpectrum:
    """A radially averaged power spectrum.

    Attributes
    ----------
    q
        Ring centres (geometric), rad/m, ascending; only rings holding modes.
    power
        C(q) at the rings, m^4.
    q_min, q_max
        The measured band: the longest wavelength's 2 pi / L and the Nyquist pi / pixel, rad/m.
    """

    q: np.ndarray
    power: np.ndarray
    q_min: float
    q_max: float

    def __call__(self, q: np.ndarray) -> np.ndarray:
        """C at wave numbers ``q`` (rad/m): log-log interpolation, the plateau C(q_min) below the
        measured band, 0 above the Nyquist."""
        q = np.asarray(q, float)
        inside = np.clip(q, self.q[0], self.q[-1])
        out = np.exp(np.interp(np.log(np.maximum(inside, 1e-300)), np.log(self.q), np.log(self.power)))
        return np.where(q > self.q_max, 0.0, out)


def isotropic_spectrum(heights: np.ndarray, inside: np.ndarray, pixel: float) -> IsotropicSpectrum:
    """The radially averaged C(q) (m^4) of a map's measured area (heights in m, square ``pixel`` in m).

    Raises
    ------
    ValueError
        If the map holds no ring of modes (fewer than 4 pixels a side).
    """
    ny, nx = heights.shape
    residual = np.where(inside, detrend(np.where(inside, heights, np.nan)), 0.0)
    window, _ = measured_window(inside, (pixel, pixel))
    coefficients = np.fft.fft2(window * residual)
    power = np.abs(coefficients) ** 2 / (heights.size * np.sum(window**2)) * (ny * pixel) * (nx * pixel)
    qy = 2 * np.pi * np.fft.fftfreq(ny, d=pixel)
    qx = 2 * np.pi * np.fft.fftfreq(nx, d=pixel)
    q = np.hypot(*np.meshgrid(qx, qy))
    q_min, q_max = 2 * np.pi / (max(nx, ny) * pixel), np.pi / pixel
    edges = np.geomspace(q_min, q_max, max(2, int(np.ceil(RINGS_PER_DECADE * np.log10(q_max / q_min)))) + 1)
    ring = np.digitize(q.ravel(), edges) - 1
    keep = (ring >= 0) & (ring < len(edges) - 1)
    counts = np.bincount(ring[keep], minlength=len(edges) - 1)
    sums = np.bincount(ring[keep], weights=power.ravel()[keep], minlength=len(edges) - 1)
    held = (counts > 0) & (sums > 0)
    if held.sum() < 2:
        raise ValueError(f"a map of {ny} x {nx} pixels holds too few Fourier modes for its spectrum")
    centres = np.sqrt(edges[:-1] * edges[1:])
    return IsotropicSpectrum(centres[held], sums[held] / counts[held], q_min, q_max)


def synthesize(spectrum: IsotropicSpectrum, n: int, pixel: float, rng: np.random.Generator,
               period: int | None = None) -> np.ndarray:
    """An ``n x n`` surface (m) of ``pixel`` (m) drawn from ``spectrum``, periodic over ``period``
    pixels (default 2 n: the window sees no copy of itself), phases from ``rng``."""
    period = 2 * n if period is None else int(period)
    q = 2 * np.pi * np.fft.fftfreq(period, d=pixel)
    qq = np.hypot(*np.meshgrid(q, q))
    amplitude = np.sqrt(spectrum(qq) / (period * pixel) ** 2)
    amplitude[0, 0] = 0.0
    phases = np.exp(2j * np.pi * rng.random(qq.shape))
    # the real part of a complex field with independent phases holds half the power: sqrt(2) restores it
    field = np.fft.ifft2(amplitude * phases) * period**2
    return np.sqrt(2.0) * field.real[:n, :n]
