"""Resistance of discrete contact spots at arbitrary positions: the point-interaction solve and Greenwood's form.

Spots ``i`` of radius ``a_i`` at ``(x_i, y_i)`` all at one potential: the currents ``f`` solve
``M f = 1`` with ``M_ii = 1 / (2 a_i)`` and ``M_ij = 1 / (pi max(d_ij, l))`` (the coupling kernel
of :mod:`pipeline.physics.discrete_contact`, floor ``l`` included, so that Barber's theorem
``1 / R = K / (E* rho*)`` holds exactly for the clean contact), and ``R = rho* / sum f``.
Greenwood's closed form is the Rayleigh quotient of ``M`` at ``f`` proportional to ``a``:
``R_G = rho* (sum a / 2 + a^T K a) / (sum a)^2``, an upper bound on the point model's ``R``.
An oxide rule enters only through the radii (an effective radius ``a sqrt(f)``, or 0 for a spot
that does not conduct). No conducting spot: ``R = inf`` (an open circuit).
"""

from __future__ import annotations

import numpy as np
from scipy.linalg import solve_triangular

__all__ = ["MODELS", "NEGLIGIBLE", "resistances"]

#: The resistance models on discrete spots.
MODELS = ("point", "greenwood")
#: Radius (m) standing for "not conducting" inside a batched point solve: ``M_ii = 1e300 / m``.
NEGLIGIBLE = 1e-300


def resistances(kernel: np.ndarray, radius: np.ndarray, rho: float, model: str = "point") -> np.ndarray:
    """Resistance of each set of spot radii on one set of positions.

    Parameters
    ----------
    kernel
        ``1 / (pi max(d_ij, l))`` of the positions, zero diagonal, 1/m, shape (n, n)
        (:func:`pipeline.physics.discrete_contact.interaction_kernel`).
    radius
        Spot radii, m, shape (..., n); 0 where a spot does not conduct. The point model solves
        the sets along the first axis together (e.g. the oxide fractions of one load step), on
        the union of their conducting spots: a spot that conducts in none is left out, one that
        conducts in some but not this set gets ``M_ii = 1 / NEGLIGIBLE`` (its current is below
        1e-250 of any other's, so the answer equals the solve without it to rounding).
    rho
        Effective resistivity rho*, ohm m.
    model
        ``"point"`` (exact solve) or ``"greenwood"`` (closed form).

    Returns
    -------
    numpy.ndarray
        Resistances in ohm, shape ``radius.shape[:-1]``; ``inf`` where no spot conducts.
    """
    if model not in MODELS:
        raise ValueError(f"model = {model!r} is not allowed: must be one of {', '.join(MODELS)}")
    radius = np.asarray(radius, dtype=float)
    total = radius.sum(axis=-1)
    out = np.full(total.shape, np.inf)
    live = total > 0
    if model == "greenwood":
        quadratic = np.einsum("...i,...i->...", radius @ kernel, radius)
        out[live] = rho * (total[live] / 2.0 + quadratic[live]) / total[live] ** 2
        return out
    stacked = radius.reshape((radius.shape[0] if radius.ndim > 1 else 1, -1, radius.shape[-1]))
    flat_out, flat_live = out.reshape(stacked.shape[:2]), live.reshape(stacked.shape[:2])
    for column in range(stacked.shape[1]):
        rows = np.flatnonzero(flat_live[:, column])
        if rows.size == 0:
            continue
        sets = stacked[rows, column]
        spots = np.flatnonzero((sets > 0).any(axis=0))
        a = sets[:, spots]
        system = np.broadcast_to(kernel[np.ix_(spots, spots)], (rows.size, spots.size, spots.size)).copy()
        diagonal = np.where(a > 0, 1.0 / (2.0 * np.where(a > 0, a, 1.0)), 1.0 / NEGLIGIBLE)
        system[:, np.arange(spots.size), np.arange(spots.size)] = diagonal
        flat_out[rows, column] = rho / _total_currents(system, a > 0)
    return out


def _total_currents(system: np.ndarray, conducting: np.ndarray) -> np.ndarray:
    """``sum f`` over the conducting spots of ``M f = 1`` for a stack of symmetric ``M`` (batch, n, n).

    Positive definite systems (the rule): ``1^T M^-1 1 = |L^-1 1|^2`` by Cholesky and one forward
    substitution; the non-conducting spots' currents are below 1e-250 of the rest, so the sum
    over all equals the sum over the conducting ones to rounding. Large caps closer than the
    coupling floor can leave ``M`` indefinite: then LU.
    """
    try:
        lower = np.linalg.cholesky(system)
    except np.linalg.LinAlgError:
        currents = np.linalg.solve(system, np.ones(system.shape[:-1] + (1,)))[..., 0]
        return np.where(conducting, currents, 0.0).sum(axis=-1)
    ones = np.ones(system.shape[-1])
    return np.array([np.sum(solve_triangular(l, ones, lower=True, check_finite=False) ** 2) for l in lower])
