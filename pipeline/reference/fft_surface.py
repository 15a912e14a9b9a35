"""g2tom's own free-surface operator: Love's influence coefficients applied by a zero-padded FFT, on any array namespace.

The operator is tamaas' non-periodic Boussinesq operator (uniform pressure on square pixels,
displacement at the pixel centres, no pressure outside the grid; equal to it to rounding, see
tests), written against an array namespace ``xp`` (NumPy on the CPU, CuPy on a GPU) so that the
GPU path of the reference runs it where its arrays live. The coefficients scale with the pixel
(``integral of 1/r`` over a pixel is linear in its side): the spectrum of a unit pixel and unit
modulus is computed once per grid size and device and scaled by ``pixel / E*``.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from types import ModuleType
from typing import Any

import numpy as np

from g2tom.physics.boussinesq import influence_coefficients

__all__ = ["FftSurface", "fft_surface"]


@functools.lru_cache(maxsize=4)
def _unit_spectrum(n: int, xp: ModuleType) -> Any:
    """``rfft2`` of the influence coefficients (:func:`influence_coefficients`) of unit pixel and
    unit modulus on the ``2n x 2n`` circular grid, as an array of ``xp``."""
    return xp.fft.rfft2(xp.asarray(influence_coefficients(n, 1.0, 1.0)))


@dataclass
class FftSurface:
    """The non-periodic Boussinesq operator of an ``n x n`` grid, applied by FFT on ``xp``.

    Attributes
    ----------
    n, pixel, e_star
        Pixels along one side, pixel side (m) and contact modulus E* (Pa), as tamaas' operator's.
    xp
        The array namespace (``numpy`` or ``cupy``).
    spectrum
        ``rfft2`` of the influence coefficients, m/Pa, an ``xp`` array (2n, n + 1).
    last_pressure
        The last contact pressure solved on this operator (Pa, ``xp``), the next solve's start (as
        tamaas' model keeps its traction), or None.
    """

    n: int
    pixel: float
    e_star: float
    xp: ModuleType
    spectrum: Any
    last_pressure: Any = None

    def apply(self, pressure: Any) -> Any:
        """Normal displacement (m, positive into the half-space) under ``pressure`` (Pa, (n, n)), on ``xp``."""
        size = (2 * self.n, 2 * self.n)
        padded = self.xp.fft.rfft2(pressure, s=size)
        return self.xp.fft.irfft2(padded * self.spectrum, s=size)[: self.n, : self.n]

    def to_host(self, array: Any) -> np.ndarray:
        """``array`` of ``xp`` as a NumPy array."""
        return array.get() if hasattr(array, "get") else np.asarray(array)

    def __call__(self, pressure: np.ndarray) -> np.ndarray:
        """Normal displacement (m) under ``pressure`` (Pa), NumPy in and out (as tamaas' operator)."""
        return self.to_host(self.apply(self.xp.asarray(pressure, dtype=float)))


def fft_surface(n: int, pixel: float, e_star: float, xp: ModuleType) -> FftSurface:
    """The operator of an ``n x n`` grid of pitch ``pixel`` (m) with modulus ``e_star`` (Pa) on ``xp``."""
    if n < 1 or not pixel > 0 or not e_star > 0:
        raise ValueError(f"n = {n}, pixel = {pixel}, e_star = {e_star}: need n >= 1, pixel > 0, e_star > 0")
    return FftSurface(n=n, pixel=float(pixel), e_star=float(e_star), xp=xp,
                      spectrum=_unit_spectrum(n, xp) * (pixel / e_star))
