"""Conductance of a conducting set by Barber's analogy (a rigid flat punch on the set).

The potential problem of two half-spaces joined through a set C of the interface (resistivity
rho* = rho_1 + rho_2) is the elastic problem of a rigid flat punch pressed on C: with the
half-space's free-surface operator ``G`` (pressure -> displacement), solve ``G p = 1`` on C with
``p = 0`` outside; the punch's stiffness is ``K = sum p dA`` (N/m per m) and the conductance is
``kappa = K / (E* rho*)``. A disc of radius a gives ``K = 2 a E*``, ``kappa = 2 a / rho*``.
The system is symmetric positive definite on C, solved by conjugate gradients: SciPy's on tamaas'
operator (the CPU reference), :func:`conjugate_gradients` on the arrays of an
:class:`~g2tom.reference.fft_surface.FftSurface` (the GPU path), where C is a mask of the
whole grid rather than a list of pixels (no gathers on the device).
"""

from __future__ import annotations

from dataclasses import dataclass
from types import ModuleType
from typing import Any, Callable

import numpy as np
from scipy.sparse.linalg import LinearOperator, cg

from g2tom.reference.elastic import FreeSurface
from g2tom.reference.fft_surface import FftSurface

__all__ = ["PunchResult", "punch_conductance", "conjugate_gradients"]


@dataclass(frozen=True)
class PunchResult:
    """Conductance of one conducting set.

    Attributes
    ----------
    conductance
        kappa = K / (E* rho*), S (0 for an empty set: an open circuit).
    stiffness
        Flat-punch stiffness K, N/m.
    iterations
        Conjugate-gradient iterations.
    """

    conductance: float
    stiffness: float
    iterations: int


def conjugate_gradients(apply: Callable[[Any], Any], b: Any, tolerance: float, max_iterations: int,
                        xp: ModuleType) -> tuple[Any, int]:
    """``x`` with ``apply(x) = b`` for a symmetric positive definite ``apply``, and the iterations.

    Conjugate gradients from ``x = 0`` until ``|b - apply(x)| <= tolerance |b|`` (SciPy's relative
    criterion), on arrays of ``xp`` of any shape (dot products over all their entries).

    Raises
    ------
    RuntimeError
        If ``max_iterations`` do not reach the tolerance.
    """
    x = xp.zeros_like(b)
    residual = b.copy()
    direction = residual.copy()
    rr = xp.sum(residual * residual)
    target = tolerance**2 * float(rr)
    for iteration in range(1, max_iterations + 1):
        image = apply(direction)
        step = rr / xp.sum(direction * image)
        x = x + step * direction
        residual = residual - step * image
        rr_next = xp.sum(residual * residual)
        if float(rr_next) <= target:
            return x, iteration
        direction = residual + (rr_next / rr) * direction
        rr = rr_next
    raise RuntimeError(f"punch conjugate gradients did not converge ({max_iterations} iterations)")


def punch_conductance(operator: FreeSurface | FftSurface, conducting: np.ndarray, rho: float,
                      tolerance: float = 1e-7) -> PunchResult:
    """Conductance (S) of the conducting pixels ``conducting`` (bool, (n, n)) for resistivity ``rho`` (ohm m).

    ``tolerance`` is the conjugate gradients' relative residual.
    """
    where = np.flatnonzero(np.asarray(conducting, bool).ravel())
    if where.size == 0:
        return PunchResult(conductance=0.0, stiffness=0.0, iterations=0)
    if isinstance(operator, FftSurface):
        xp = operator.xp
        mask = xp.asarray(conducting, dtype=bool)
        ones = mask.astype(float)
        pressure, iterations = conjugate_gradients(lambda p: xp.where(mask, operator.apply(p), 0.0), ones,
                                                   tolerance, 20 * where.size, xp)
        stiffness = float(xp.sum(pressure)) * operator.pixel**2
        return PunchResult(conductance=stiffness / (operator.e_star * rho), stiffness=stiffness,
                           iterations=iterations)
    n = operator.n
    field = np.zeros(n * n)

    def apply(p: np.ndarray) -> np.ndarray:
        field[:] = 0.0
        field[where] = p.ravel()
        return operator(field.reshape(n, n)).ravel()[where]

    count = [0]

    def counted(_: np.ndarray) -> None:
        count[0] += 1

    system = LinearOperator((where.size, where.size), matvec=apply, dtype=float)
    pressure, info = cg(system, np.ones(where.size), rtol=tolerance, atol=0.0, maxiter=20 * where.size,
                        callback=counted)
    if info != 0:
        raise RuntimeError(f"punch conjugate gradients did not converge ({info} iterations)")
    stiffness = float(pressure.sum() * operator.pixel**2)
    return PunchResult(conductance=stiffness / (operator.e_star * rho), stiffness=stiffness,
                       iterations=count[0])
