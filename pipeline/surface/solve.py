"""One contact position: the full-field contact at every force, its clean conductance and its
conductance with every oxide field.

The rigid body is the window of the map minus the indenter's profile about the window's centre
(heights positive towards the flat, as in :mod:`g2tom.reference.surfaces`). Forces are solved
lightest first, each starting from the previous pressure. The conductance of a set of pixels is
Barber's: the flat punch on the set (:func:`g2tom.reference.punch.punch_conductance`, to
:data:`PUNCH_TOLERANCE`), elastic or capped alike (it depends on the set's shape only).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from g2tom.physics.indenter import profile
from g2tom.reference.contact import ContactReachesEdge, contact_at_force
from g2tom.reference.elastic import SolverFailure
from g2tom.reference.fft_surface import FftSurface
from g2tom.reference.punch import punch_conductance
from g2tom.reference.surfaces import coordinates
from g2tom.surface.study import SurfaceStudy

__all__ = ["PUNCH_TOLERANCE", "PositionResult", "rigid_heights", "solve_position"]

#: The punch's relative residual. The conductance (the sum of the punch's pressure) is the
#: system's energy, whose error falls with the square of the residual: on a 256^2 window of a
#: rough sphere, 1e-5 gives the conductance of 1e-7 within 1e-7 relative in two thirds of the
#: iterations.
PUNCH_TOLERANCE = 1e-5


@dataclass(frozen=True)
class PositionResult:
    """A position's answers (NaN at a force whose contact reached the window's edge or failed).

    Attributes
    ----------
    delta
        Approach of the indenter's tip from the window's mean plane in g2tom's convention
        (negative: interpenetration), m (force,).
    area
        Contact area, m^2 (force,).
    plastic_share
        Share of the contact area at the hardness (force,; 0 when elastic).
    resistance_clean
        Clean resistance, ohm (force,).
    resistance
        Resistance with oxide, ohm (xi, correlation length, field, force); +inf: no conducting pixel.
    oxide_fraction
        Oxidized share of the window's pixels (xi, correlation length, field).
    failed
        Why a force has no answer, '' where it has one (force,).
    contact
        The contact set at the middle force, bool (n, n): the figure's map.
    """

    delta: np.ndarray
    area: np.ndarray
    plastic_share: np.ndarray
    resistance_clean: np.ndarray
    resistance: np.ndarray
    oxide_fraction: np.ndarray
    failed: tuple[str, ...]
    contact: np.ndarray


def rigid_heights(study: SurfaceStudy, window: np.ndarray, pixel: float) -> np.ndarray:
    """The rigid body's heights (m, (n, n)): the map's window minus the indenter's profile about its centre."""
    x, y = coordinates(window.shape[0], pixel)
    return window - profile(np.hypot(x, y), **study.indenter)


def _resistance(operator: FftSurface, conducting: np.ndarray, rho: float) -> float:
    kappa = punch_conductance(operator, conducting, rho, PUNCH_TOLERANCE).conductance
    return 1.0 / kappa if kappa > 0 else np.inf


def solve_position(study: SurfaceStudy, operator: FftSurface, window: np.ndarray, masks: np.ndarray) -> PositionResult:
    """Solve one position's window (m, (n, n)) at every force, clean and with the oxide ``masks``
    (bool, (xi, correlation length, field, n, n): :func:`g2tom.surface.oxide.oxide_masks`)."""
    heights = rigid_heights(study, window, operator.pixel)
    count = len(study.forces)
    delta, area, plastic, clean = (np.full(count, np.nan) for _ in range(4))
    resistance = np.full(masks.shape[:3] + (count,), np.nan)
    failed = [""] * count
    contact_map = np.zeros(window.shape, bool)
    operator.last_pressure = None  # each position starts cold: its answer depends on it alone
    for f, force in enumerate(study.forces):
        try:
            state = contact_at_force(operator, heights, force, study.tolerance, hardness=study.hardness)
        except (ContactReachesEdge, SolverFailure, ValueError) as exc:  # ValueError: more than H times the window
            failed[f] = str(exc)
            operator.last_pressure = None
            continue
        delta[f] = state.delta
        area[f] = state.contact.sum() * operator.pixel**2
        at_cap = 0 if study.hardness is None else np.count_nonzero(state.pressure >= study.hardness)
        plastic[f] = at_cap / max(1, np.count_nonzero(state.contact))
        clean[f] = _resistance(operator, state.contact, study.rho)
        for index in np.ndindex(*masks.shape[:3]):
            resistance[index + (f,)] = _resistance(operator, state.contact & ~masks[index], study.rho)
        if f == count // 2:
            contact_map = state.contact
    return PositionResult(delta, area, plastic, clean, resistance, masks.mean(axis=(-2, -1)), tuple(failed), contact_map)
