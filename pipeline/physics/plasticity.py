"""When asperities yield: Greenwood and Williamson's plasticity index and a cap's first yield.

A cap of tip radius ``beta`` pressed into a half-space of modulus ``E*`` is Hertzian until its peak
pressure ``p0 = 2 E* a / (pi beta)`` reaches the hardness ``H`` of the softer body (the pressure of
the perfectly plastic surface model); that happens at the contact radius ``a_c = pi beta H / (2 E*)``,
the interference ``omega_c = a_c^2 / beta = beta (pi H / (2 E*))^2`` and the force
``F_c = (4/3) E* sqrt(beta) omega_c^(3/2) = pi^3 beta^2 H^3 / (6 E*^2)``.

Greenwood and Williamson (Proc. R. Soc. A 295, 1966) compare the asperities' height spread with
that interference: ``psi = (E* / H) sqrt(sigma / beta)``. Below about 0.6 few asperities yield
at any practical load; above about 1 most touching asperities are plastic.
"""

from __future__ import annotations

import math

__all__ = ["ELASTIC_LIMIT", "plasticity_index", "yield_radius", "yield_interference", "yield_force"]

#: The plasticity index below which Greenwood and Williamson's asperities stay mostly elastic.
ELASTIC_LIMIT = 0.6


def plasticity_index(e_star: float, hardness: float, sigma: float, beta: float) -> float:
    """``psi = (E* / H) sqrt(sigma / beta)`` (dimensionless) of ``E*`` and ``H`` in Pa, the asperity
    height spread ``sigma`` and tip radius ``beta`` in m."""
    return e_star / hardness * math.sqrt(sigma / beta)


def yield_radius(beta: float, e_star: float, hardness: float) -> float:
    """The contact radius ``a_c = pi beta H / (2 E*)`` at which a cap's peak pressure reaches ``H``, m."""
    return math.pi * beta * hardness / (2.0 * e_star)


def yield_interference(beta: float, e_star: float, hardness: float) -> float:
    """The interference ``omega_c = beta (pi H / (2 E*))^2`` of a cap's first yield, m."""
    return yield_radius(beta, e_star, hardness) ** 2 / beta


def yield_force(beta: float, e_star: float, hardness: float) -> float:
    """The force ``F_c = pi^3 beta^2 H^3 / (6 E*^2)`` of a cap's first yield, N."""
    return math.pi**3 * beta**2 * hardness**3 / (6.0 * e_star**2)
