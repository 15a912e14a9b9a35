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

from pipeline.physics.discrete_contact import symmetric_solve

__all__ = ["MODELS", "resistances"]

#: The resistance models on discrete spots.
MODELS = ("point", "greenwood")


def resistances(kernel: np.ndarray, radius: np.ndarray, rho: float, model: str = "point") -> np.ndarray:
    """Resistance of each set of spot radii on one set of positions.

    Parameters
    ----------
    kernel
        ``1 / (pi max(d_ij, l))`` of the positions, zero diagonal, 1/m, shape (n, n)
        (:func:`pipeline.physics.discrete_contact.interaction_kernel`).
    radius
        Spot radii, m, shape (..., n); 0 where a spot does not conduct.
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
    flat = radius.reshape(-1, radius.shape[-1])
    total = flat.sum(axis=1)
    out = np.full(flat.shape[0], np.inf)
    if model == "greenwood":
        quadratic = np.einsum("bi,bi->b", flat @ kernel, flat)
        live = total > 0
        out[live] = rho * (total[live] / 2.0 + quadratic[live]) / total[live] ** 2
        return out.reshape(radius.shape[:-1])
    for b in np.flatnonzero(total > 0):
        spots = np.flatnonzero(flat[b] > 0)
        system = kernel[np.ix_(spots, spots)]
        system[np.diag_indices_from(system)] = 1.0 / (2.0 * flat[b, spots])
        out[b] = rho / symmetric_solve(system, np.ones(spots.size)).sum()
    return out.reshape(radius.shape[:-1])
