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

The perfectly plastic surface (:func:`solve_capped_at_mean_pressure`) bounds the pressure by the
hardness H: ``0 <= p <= H``. At its solution the gradient is ``-delta`` where ``0 < p < H``, at
least that where ``p = 0`` (the gap is open) and at most that where ``p = H`` (the surfaces
interpenetrate there: the cap holds the pressure, not the gap). The conjugate gradients run on the
free set F = {0 < p < H}, centred there; pixels at 0 and at H both lie outside it and take the
gradient step of the centred gradient instead (a pixel at 0 re-enters where it is negative, the
gap being closed; one at H where it is positive, the pressure wanting to fall), which restarts
the conjugate directions. Scaling cannot restore the mean pressure (it would push pixels above H),
so the trial pressure is projected onto {0 <= p <= H, mean p = target}: the Euclidean projection
is ``clip(trial + c, 0, H)`` with one uniform shift ``c`` (:func:`project_onto_box`), found by
a safeguarded Newton search on the mean, monotone and piecewise linear in ``c``. Pixels far out
of contact have trial pressures far below zero (their gradient step of the open gap), so the
shift leaves them at zero. The error is that of the elastic solve with the minimum taken where
``p < H`` and only the excess counted, ``sum p max(g - lambda, 0) / (sum p * std h)`` with
``lambda = min over p < H of g``: zero exactly when the gradient is one value on F, no less at the
zeros and no more at the cap (without capped pixels it is the elastic error).
"""

from __future__ import annotations

from dataclasses import dataclass
from types import ModuleType
from typing import Any

from g2tom.reference.fft_surface import FftSurface

__all__ = ["PolonskyKeerResult", "solve_at_mean_pressure", "solve_capped_at_mean_pressure", "project_onto_box",
           "MEAN_TOLERANCE"]

#: Relative error of the mean pressure at which :func:`project_onto_box` stops (rounding of the sum).
MEAN_TOLERANCE = 1e-14


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
        g, direction, norm_before, tau = _conjugate_step(operator, g, p > 0, direction, norm_before, conjugate)
        p = xp.maximum(p - tau * direction, 0.0)
        overlap = (p == 0.0) & (g < 0.0)
        p = xp.where(overlap, p - tau * g, p)
        conjugate = 1.0 - xp.any(overlap).astype(float)
        p = p * (mean_pressure / xp.mean(p))
        iteration += 1


def solve_capped_at_mean_pressure(operator: FftSurface, heights: Any, mean_pressure: float, hardness: float,
                                  tolerance: float, max_iterations: int = 10000,
                                  start: Any = None) -> PolonskyKeerResult:
    """The contact pressure of ``heights`` (m, (n, n)) at ``mean_pressure`` (Pa, over the grid),
    bounded above by ``hardness`` (Pa): the perfectly plastic surface (module docstring).

    Starts from ``start`` (a pressure on the grid, projected onto the bounds at the mean pressure)
    or a uniform pressure; stops as :func:`solve_at_mean_pressure` does, with the capped error.

    Raises
    ------
    ValueError
        If the mean pressure is not in ``(0, hardness)`` (the grid cannot carry it below H).
    """
    if not 0 < mean_pressure < hardness:
        raise ValueError(f"mean pressure {mean_pressure:.4g} Pa is out of range: must be in (0, hardness "
                         f"{hardness:.4g} Pa), or the grid cannot carry the force at pressures up to H")
    xp = operator.xp
    h = xp.asarray(heights, dtype=float)
    scale = float(xp.std(h)) or 1.0
    first = xp.full(h.shape, float(mean_pressure)) if start is None else xp.asarray(start, dtype=float)
    p = project_onto_box(first, mean_pressure, hardness, xp)
    direction = xp.zeros_like(h)
    norm_before = xp.asarray(1.0)
    conjugate = xp.asarray(0.0)
    iteration = 0
    while True:
        g = operator.apply(p) - h
        below = p < hardness
        floor = xp.min(xp.where(below, g, xp.inf))
        error = float(xp.sum(p * xp.maximum(g - floor, 0.0)) / (xp.sum(p) * scale))
        if not error > tolerance or iteration == max_iterations:  # converged, not finite, or out of iterations
            return PolonskyKeerResult(pressure=p, error=error, iterations=iteration)
        free = (p > 0) & below
        if int(xp.count_nonzero(free)) < 2:  # a centred gradient on under two pixels vanishes: steepest descent,
            trial = p - xp.sum(g * g) / xp.sum(g * operator.apply(g)) * g  # exact step, the projection re-centres
            projected = project_onto_box(trial, mean_pressure, hardness, xp)
            conjugate = xp.asarray(0.0)
        else:
            g, direction, norm_before, tau = _conjugate_step(operator, g, free, direction, norm_before, conjugate)
            trial = p - tau * xp.where(free, direction, g)
            projected = project_onto_box(trial, mean_pressure, hardness, xp)
            conjugate = 1.0 - xp.any(~free & (projected != p)).astype(float)
        p = projected
        iteration += 1


def project_onto_box(trial: Any, mean_pressure: float, hardness: float, xp: ModuleType) -> Any:
    """The pressure nearest ``trial`` (Pa, an ``xp`` array) with ``0 <= p <= hardness`` and mean
    ``mean_pressure`` (Pa, in ``(0, hardness)``): ``clip(trial + c, 0, hardness)``.

    The mean of the clipped field is continuous, non-decreasing and piecewise linear in the shift
    ``c``, from 0 at ``c = -max(trial)`` to ``hardness`` at ``c = hardness - min(trial)``: Newton's
    step (slope: the share of pixels strictly inside the bounds) inside that bracket, bisection
    where it would leave it or the slope is zero, until the mean is met to :data:`MEAN_TOLERANCE`
    or the bracket closes. A trial that is not finite is returned clipped (the caller's error is
    then not finite).
    """
    target = mean_pressure * trial.size
    low, high = -float(xp.max(trial)), hardness - float(xp.min(trial))
    shift = 0.0
    while True:
        p = xp.clip(trial + shift, 0.0, hardness)
        excess = float(xp.sum(p)) - target
        if not abs(excess) > MEAN_TOLERANCE * target:  # met, or not finite
            return p
        if excess > 0:
            high = shift
        else:
            low = shift
        inside = float(xp.count_nonzero((p > 0) & (p < hardness)))
        step = shift - excess / inside if inside > 0 else 0.5 * (low + high)
        if not low < step < high:
            step = 0.5 * (low + high)
        if step == shift:  # the bracket has closed to adjacent floats
            return p
        shift = step


def _conjugate_step(operator: FftSurface, g: Any, on: Any, direction: Any, norm_before: Any,
                    conjugate: Any) -> tuple[Any, Any, Any, Any]:
    """One conjugate-gradient step on the set ``on`` (bool, (n, n)) from the gradient ``g`` (m).

    Returns the gradient centred on the set, the new direction (zero off the set, conjugate to the
    last ``direction`` when ``conjugate`` is 1), its squared norm on the set (the next
    ``norm_before``) and the exact step ``tau`` (Pa/m) of the quadratic along it, all ``xp``.
    """
    xp = operator.xp
    count = xp.count_nonzero(on)
    g = g - xp.sum(xp.where(on, g, 0.0)) / count
    g_on = xp.where(on, g, 0.0)
    norm = xp.sum(g_on * g_on)
    direction = xp.where(on, g + conjugate * (norm / norm_before) * direction, 0.0)
    r = operator.apply(direction)
    r = xp.where(on, r - xp.sum(xp.where(on, r, 0.0)) / count, 0.0)
    return g, direction, norm, xp.sum(g_on * direction) / xp.sum(r * direction)
