"""Conductance of a conducting set by Barber's analogy (a rigid flat punch on the set).

The potential problem of two half-spaces joined through a set C of the interface (resistivity
rho* = rho_1 + rho_2) is the elastic problem of a rigid flat punch pressed on C: with the
half-space's free-surface operator ``G`` (pressure -> displacement), solve ``G p = 1`` on C with
``p = 0`` outside; the punch's stiffness is ``K = sum p dA`` (N/m per m) and the conductance is
``kappa = K / (E* rho*)``. A disc of radius a gives ``K = 2 a E*``, ``kappa = 2 a / rho*``.
The system is symmetric positive definite on C, solved by conjugate gradients.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.sparse.linalg import LinearOperator, cg

from pipeline.reference.elastic import FreeSurface

__all__ = ["PunchResult", "punch_conductance"]


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


def punch_conductance(operator: FreeSurface, conducting: np.ndarray, rho: float,
                      tolerance: float = 1e-7) -> PunchResult:
    """Conductance (S) of the conducting pixels ``conducting`` (bool, (n, n)) for resistivity ``rho`` (ohm m).

    ``tolerance`` is the conjugate gradients' relative residual.
    """
    where = np.flatnonzero(np.asarray(conducting, bool).ravel())
    if where.size == 0:
        return PunchResult(conductance=0.0, stiffness=0.0, iterations=0)
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
