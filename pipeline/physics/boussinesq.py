"""Boussinesq's free-surface operator of an elastic half-space on square pixels (Love's influence coefficients).

A uniform pressure ``p`` on a rectangle of the surface of a half-space with contact modulus
``E*`` displaces the surface normally by ``u = p / (pi E*) * integral of 1/r over the rectangle``
(Boussinesq; Love 1929 integrated it over the rectangle in closed form). With

    I(X, Y) = X ln(Y + sqrt(X^2 + Y^2)) + Y ln(X + sqrt(X^2 + Y^2)),

the integral of ``1 / sqrt(X^2 + Y^2)`` over ``[x1, x2] x [y1, y2]`` is
``I(x2, y2) - I(x1, y2) - I(x2, y1) + I(x1, y1)`` (each term's limit 0 where its factor is 0).

On an ``n x n`` grid of pixels of side ``h`` the displacement at the pixel centres is the linear
convolution of the pixel pressures with these coefficients at the offsets ``-(n-1) .. n-1``
pixels. :func:`influence_coefficients` lays them out for a circular convolution of size ``2n``
(zero-padded pressure, no pressure outside the grid: the non-periodic, unbounded half-space), the
form an FFT applies.
"""

from __future__ import annotations

import numpy as np

__all__ = ["rectangle_integral", "influence_coefficients"]


def _corner(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """``I(X, Y)`` of the module docstring (m), with ``0 ln 0 = 0``."""
    r = np.hypot(x, y)
    with np.errstate(divide="ignore", invalid="ignore"):
        first = np.where(x == 0.0, 0.0, x * np.log(np.where(y + r > 0.0, y + r, 1.0)))
        second = np.where(y == 0.0, 0.0, y * np.log(np.where(x + r > 0.0, x + r, 1.0)))
    return first + second


def rectangle_integral(x: np.ndarray, y: np.ndarray, half_x: float, half_y: float) -> np.ndarray:
    """Integral of ``1 / r`` (m) over the rectangle of half sides ``half_x``, ``half_y`` (m) centred
    at the offset ``(x, y)`` (m) from the point where ``r`` is measured."""
    x = np.asarray(x, dtype=float)
    y = np.asarray(y, dtype=float)
    return (_corner(x + half_x, y + half_y) - _corner(x - half_x, y + half_y)
            - _corner(x + half_x, y - half_y) + _corner(x - half_x, y - half_y))


def influence_coefficients(n: int, pixel: float, e_star: float) -> np.ndarray:
    """Displacement (m per Pa) at a pixel centre under unit pressure on a pixel at each offset, laid
    out for a circular convolution of size ``2n`` x ``2n``.

    Entry ``[i, j]`` holds the offset ``(i, j)`` pixels for ``i, j < n`` and ``(i - 2n, j - 2n)``
    for ``i, j > n``; the row and column ``n`` (offset ``-n``, never reached by a zero-padded
    ``n x n`` pressure) hold that offset's value too.

    Parameters
    ----------
    n
        Pixels along a side of the grid (>= 1).
    pixel
        Pixel side, m (> 0).
    e_star
        Contact modulus E*, Pa (> 0).
    """
    if n < 1 or not pixel > 0 or not e_star > 0:
        raise ValueError(f"n = {n}, pixel = {pixel}, e_star = {e_star}: need n >= 1, pixel > 0, e_star > 0")
    offsets = np.fft.fftfreq(2 * n, d=1.0 / (2 * n)) * pixel  # 0, 1, .., n-1, -n, .., -1 pixels, in m
    x, y = np.meshgrid(offsets, offsets, indexing="xy")
    return rectangle_integral(x, y, pixel / 2.0, pixel / 2.0) / (np.pi * e_star)
