"""The point model's system ``M``: its diagonal (spot, film, lattice term), which spots carry
current, its dense form, and the matrix-free interaction operators ``K * f`` by ``compute.interaction_sum``
(see :mod:`g2tom.physics.point_model` for the model)."""

from __future__ import annotations

from typing import Callable

import numpy as np

from g2tom.physics.interaction_folded import interaction_apply_columns, interaction_apply_dense_columns

__all__ = ["OPERATORS", "CONDUCTANCE_FLOOR", "film_diagonal", "system_matrix", "checked_settings", "spot_states"]

#: Interaction operators ``K * f`` by ``compute.interaction_sum``: the folded DFT-GEMM or the dense matrix.
OPERATORS: dict[str, Callable[[np.ndarray, float], np.ndarray]] = {
    "auto": interaction_apply_columns,
    "folded": interaction_apply_columns,
    "gemm": interaction_apply_dense_columns,
    "direct": interaction_apply_dense_columns,
}


#: Spots whose own conductance ``t = 1 / M_ii`` (``2a`` when clean) is below this many cell
#: pitches carry no current. A spot's current is at most its ``t`` (the currents are
#: non-negative), so removing even a million such spots changes the conductance (m) by less than
#: 1e-94 pitches; and every remaining ``M_ii`` is at most 1e100 / pitch, so ``M_ii``, its square
#: and ``1 / sqrt(M_ii)`` stay normal doubles (a radius of 1e-323 m makes ``1 / (2a)`` inf, and
#: the solve NaN). Spots far smaller than an atom (1e-30 m on the paper's pitch) are still solved.
CONDUCTANCE_FLOOR = 1e-100


def film_diagonal(radius: np.ndarray, filmed: np.ndarray, rho: float, film_resistance: float) -> np.ndarray:
    """Diagonal ``M_ii = 1/(2a) + r_f/(rho* pi a^2)`` (film term only where ``filmed``), in 1/m.

    Parameters
    ----------
    radius
        Spot radii, in m; must be > 0.
    filmed
        Spots under the film, bool, broadcastable to ``radius``.
    rho
        Effective resistivity rho*, in ohm m.
    film_resistance
        Specific resistance of the film r_f, in ohm m^2 (finite, >= 0).
    """
    return 1.0 / (2.0 * radius) + np.where(filmed, film_resistance / (rho * np.pi * radius**2), 0.0)


def system_matrix(x: np.ndarray, y: np.ndarray, diagonal: np.ndarray) -> np.ndarray:
    """The dense matrix ``M`` of spots at ``(x, y)`` (m) with the given diagonal (1/m)."""
    d = np.hypot(x[:, None] - x[None, :], y[:, None] - y[None, :])
    np.fill_diagonal(d, 1.0)
    m = 1.0 / (np.pi * d)
    np.fill_diagonal(m, diagonal)
    return m


def checked_settings(rho: float, pitch: float, film_resistance: float, lattice_constant: float) -> dict:
    """The physical settings of a solve, validated."""
    if not film_resistance >= 0:
        raise ValueError(f"film_resistance = {film_resistance!r} must be >= 0 (ohm m^2) or inf")
    if not (np.isfinite(lattice_constant) and lattice_constant >= 0):
        raise ValueError(f"lattice_constant = {lattice_constant!r} is out of range: must be finite and >= 0")
    return {"rho": rho, "pitch": pitch, "film_resistance": film_resistance, "lattice_constant": lattice_constant}


def spot_states(
    mask: np.ndarray, radius: np.ndarray, settings: dict
) -> tuple[np.ndarray, np.ndarray]:
    """Spots carrying current and the diagonal ``M_ii`` (1 where none), broadcast shapes.

    An insulating film (``film_resistance = inf``) removes the oxidized spots; a finite one
    keeps them, with the film in series. The lattice term ``C / (pi dx)`` is added on every
    spot. Spots whose ``1 / M_ii`` is below :data:`CONDUCTANCE_FLOOR` pitches carry none.
    """
    rho, film_resistance, pitch = settings["rho"], settings["film_resistance"], settings["pitch"]
    own = settings["lattice_constant"] / (np.pi * pitch)
    spot = radius > 0
    safe = np.where(spot, radius, 1.0)
    with np.errstate(over="ignore", divide="ignore", invalid="ignore"):
        if np.isinf(film_resistance):
            spot = spot & mask
            diag = 1.0 / (2.0 * safe) + own
        else:
            diag = film_diagonal(safe, ~mask, rho, film_resistance) + own
    active = spot & (diag <= 1.0 / (CONDUCTANCE_FLOOR * pitch))
    return active, np.where(active, diag, 1.0)
