"""What every task of the cube reads besides the fields and the spot maps: :class:`CubeSettings`.

Its own module, below both kinds of chunk (:mod:`g2tom.models.lattice_cube` on the cell lattice,
:mod:`g2tom.models.discrete_cube` on discrete spots), which both read it.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

__all__ = ["CubeSettings"]


@dataclass(frozen=True, eq=False)
class CubeSettings:
    """What every task of the cube reads besides the fields and the spot maps (picklable).

    Attributes
    ----------
    pitch
        Cell pitch, m.
    rho
        Effective resistivity rho*, ohm m.
    model
        ``cube.model``: ``greenwood`` or ``point``.
    film_resistance
        Specific resistance of a resistive oxide film, ohm m2 (inf: insulating).
    solver_tolerance, max_iterations, solver_criterion
        The point model's iterative solve (``cube.*``).
    crops
        Side of the centred square of cells kept at each approach, (delta,).
    tolerance
        ``cube.crop_tolerance``: the crop's relative error bound (0: whole window).
    method
        ``compute.interaction_sum`` as configured; ``method_used`` with ``auto`` resolved.
    spots
        ``contact.spots`` (the Greenwood–Tripp model's spots on the cell lattice).
    lattice_constant
        ``cube.lattice_constant`` of the point model's self term.
    asperities
        ``asperities`` spots only: (oxide.seed, sigma in m, beta in m) of the drawn heights.
    separation
        ``asperities`` spots only: separation at the cell centres (delta, y, x), m.
    spot_rule
        ``oxide.spot_rule`` (discrete spots: ``centre`` or ``disc``).
    control_variate
        ``fits.control_variate``: discrete spots also return each realization's ``clean_share``.
    contact_model
        The run's contact model, a :class:`g2tom.models.base.ContactModel` (:func:`g2tom.models.contact_model`):
        its cube chunks and clean terms.
    """

    pitch: float
    rho: float
    model: str
    film_resistance: float
    solver_tolerance: float
    max_iterations: int
    solver_criterion: str
    crops: np.ndarray
    tolerance: float
    method: str
    method_used: str
    spots: str
    lattice_constant: float
    asperities: tuple[int, float, float] | None = None
    separation: np.ndarray | None = None
    spot_rule: str = "centre"
    control_variate: bool = False
    contact_model: Any = None
