"""One load step of the full-field contact of a rigid rough sphere on an elastic half-space.

The rigid body's surface is ``heights(x, y)`` (m, e.g. :func:`surfaces.sphere` plus a rough
surface): it touches where the elastic surface, displaced by ``u`` (positive into the
half-space), reaches it. In contact ``u = heights - delta`` with one rigid approach ``delta``,
in g2tom's convention: the separation of the sphere tip (height 0) from the reference plane
(height 0 of the rough surface) before deformation, negative when they interpenetrate.
Check: a smooth sphere has ``delta = -a^2 / R`` (Hertz).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from g2tom.reference.elastic import FreeSurface, solve_pressure

__all__ = ["ContactState", "ContactReachesEdge", "contact_at_force", "flattened_heights"]


class ContactReachesEdge(ValueError):
    """The contact reaches the grid's edge: the window is too small for this load."""


@dataclass(frozen=True)
class ContactState:
    """The solution of one load step.

    Attributes
    ----------
    force
        Total normal force, N.
    delta
        Rigid approach in g2tom's convention (see the module docstring), m.
    contact
        Contact set (p > 0), bool (n, n).
    pressure
        Contact pressure, Pa, (n, n).
    gap_spread
        Largest minus smallest ``heights - u`` over the contact set (below the hardness, where
        one caps the pressure), m: how exactly the solver closed the gap there (0 for an exact
        solution).
    """

    force: float
    delta: float
    contact: np.ndarray
    pressure: np.ndarray
    gap_spread: float


def contact_at_force(operator: FreeSurface, heights: np.ndarray, force: float,
                     tolerance: float = 1e-8, hardness: float | None = None) -> ContactState:
    """Solve the contact of the rigid ``heights`` (m, (n, n)) pressed by ``force`` (N, > 0).

    With ``hardness`` H (Pa) the surface is perfectly plastic (pressure capped at H,
    :func:`~g2tom.reference.elastic.solve_pressure`): the contact set is still ``p > 0`` and the
    force the sum of the pressures, but the approach and the gap's spread are taken where
    ``0 < p < H`` only (the surfaces interpenetrate at the cap).

    Raises
    ------
    ValueError
        If the force is not positive, or the grid cannot carry it below H.
    ContactReachesEdge
        If the contact reaches the grid's edge (the grid is too small for this load: the
        non-periodic operator assumes no pressure outside it).
    """
    if not force > 0:
        raise ValueError(f"force = {force} is out of range: must be > 0 (N)")
    pressure = solve_pressure(operator, heights, force, tolerance, hardness=hardness)
    contact = pressure > 0
    edge = contact[0].any() or contact[-1].any() or contact[:, 0].any() or contact[:, -1].any()
    if edge:
        raise ContactReachesEdge(f"force = {force:.4g} N: the contact reaches the edge of the grid; enlarge it")
    closed = contact if hardness is None else contact & (pressure < hardness)
    offset = (heights - operator(pressure))[closed]  # = delta wherever 0 < p (< H)
    return ContactState(
        force=float(pressure.sum() * operator.pixel**2),
        delta=float(np.mean(offset)),
        contact=contact,
        pressure=pressure,
        gap_spread=float(np.ptp(offset)),
    )


def flattened_heights(operator: FreeSurface, heights: np.ndarray, state: ContactState, hardness: float) -> np.ndarray:
    """The rigid ``heights`` (m, (n, n)) after the perfectly plastic loading of ``state`` (capped at
    ``hardness``, Pa): lowered to ``u + delta`` where the pressure is at H.

    There the surfaces interpenetrate by ``heights - delta - u``, a permanent set that unloading
    leaves. Pressed elastically at the state's force, the flattened heights carry the state's
    pressure again, every contact pixel closed; their elastic stiffness dF/d(-delta) is the
    unloading stiffness of the plastic contact, the one Barber's theorem ties to its conductance.
    """
    capped = state.pressure >= hardness
    return np.where(capped, np.minimum(heights, operator(state.pressure) + state.delta), heights)
