"""Polonsky and Keer's constrained conjugate gradients for a frictionless contact at a given force, on any array namespace.

The rigid surface of ``heights`` h (m) is pressed on the half-space whose free-surface operator G
gives the displacement ``u = G p`` (positive into it) of a pressure ``p``. The contact pressure
minimises ``p.Gp / 2 - p.h`` over ``p >= 0`` with the mean pressure fixed; its gradient
``g = G p - h`` equals ``-delta`` (one rigid approach) where ``p > 0`` and is larger elsewhere
(the gap ``g + delta >= 0``). Polonsky and Keer (Wear 231, 1999) minimise it by conjugate
gradients on the current contact set S = {p > 0}: the gradient is centred on S (its mean there
is the approach), the step is exact for the quadratic, negative pressures are cut to zero, and
points outside S where the surfaces overlap (``p = 0``, centred gap < 0) re-enter with the
gradient step, which also restarts the conjugate directions; the mean pressure is then restored
by scaling.

The error is the pressure-weighted mean gap over the heights' standard deviation,
``sum p (g - min g) / (sum p * std h)``: zero exactly when the gap is closed on S and open
elsewhere. Every operation is on the namespace of the operator (NumPy or CuPy); only the error
crosses to the host, once per iteration.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from g2tom.reference.fft_surface import FftSurface

__all__ = ["PolonskyKeerResult", "solve_at_mean_pressure"]


@dataclass(frozen=True)
class PolonskyKeerResult:
    """The solver's answer.

    Attributes
    ----------
    pressure
        Contact pressure, Pa, (n, n), an array of the operator's namespace.
    error
        The error of the module docstring at ``pressure`` (dimensionless).
    iterations
        Iterations done.
    """

    pressure: Any
    error: float
    iterations: int


def solve_at_mean_pressure(operator: FftSurface, heights: Any, mean_pressure: float, tolerance: float,
                           max_iterations: int = 10000, start: Any = None) -> PolonskyKeerResult:
    """The contact pressure of ``heights`` (m, (n, n)) at ``mean_pressure`` (Pa, over the grid).

    Starts from ``start`` (a pressure on the grid, e.g. the solution at a nearby load; scaled to
    the mean pressure) or a uniform pressure. Stops at the first iterate whose error is at most
    ``tolerance``, or after ``max_iterations`` (the last iterate and its error: the caller judges
    it). A non-finite error (e.g. the pressure vanished) stops it at once.
    """
    xp = operator.xp
    h = xp.asarray(heights, dtype=float)
    scale = float(xp.std(h)) or 1.0
    if start is None:
        p = xp.full(h.shape, float(mean_pressure))
    else:
        p = xp.asarray(start, dtype=float) * (mean_pressure / xp.mean(xp.asarray(start, dtype=float)))
    direction = xp.zeros_like(h)
    norm_before = xp.asarray(1.0)
    conjugate = xp.asarray(0.0)
    iteration = 0
    while True:
        g = operator.apply(p) - h
        error = float(xp.sum(p * (g - xp.min(g))) / (xp.sum(p) * scale))
        if not error > tolerance or iteration == max_iterations:  # converged, not finite, or out of iterations
            return PolonskyKeerResult(pressure=p, error=error, iterations=iteration)
        on = p > 0
        count = xp.count_nonzero(on)
        g = g - xp.sum(xp.where(on, g, 0.0)) / count
        g_on = xp.where(on, g, 0.0)
        norm = xp.sum(g_on * g_on)
        direction = xp.where(on, g + conjugate * (norm / norm_before) * direction, 0.0)
        norm_before = norm
        r = operator.apply(direction)
        r = xp.where(on, r - xp.sum(xp.where(on, r, 0.0)) / count, 0.0)
        tau = xp.sum(g_on * direction) / xp.sum(r * direction)
        p = xp.maximum(p - tau * direction, 0.0)
        overlap = (p == 0.0) & (g < 0.0)
        p = xp.where(overlap, p - tau * g, p)
        conjugate = 1.0 - xp.any(overlap).astype(float)
        p = p * (mean_pressure / xp.mean(p))
        iteration += 1
