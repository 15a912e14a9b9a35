"""The point-interaction model: exact currents of a multi-spot contact, with or without oxide film.

Spots ``i`` of radius ``a_i`` at cell centres ``x_i``, all at one potential ``V = rho*`` above
the far field, carry currents ``f_i`` (in m, i.e. amperes per ``V / rho*``) with

    sum_j M_ij f_j = 1,   M_ii = 1 / (2 a_i) + r_i / (rho* pi a_i^2) + C / (pi dx),   M_ij = 1 / (pi d_ij),

where ``r_i`` is the specific resistance of a film on spot ``i`` (0 for a clean spot; an
insulating film removes the spot) and ``C`` the optional lattice constant (default 0): with
``C`` = :data:`~g2tom.physics.lattice.SQUARE_LATTICE_CONSTANT` the term restores the
interaction of each spot with its own cell's neighbourhood that the lattice sum over the other
spots misses when the spots stand for a continuous distribution (:mod:`g2tom.physics.lattice`).
Spots whose own conductance ``1 / M_ii`` is below
:data:`~g2tom.physics.point_system.CONDUCTANCE_FLOOR` pitches are treated
as absent, so that no radius, however small (expected radii reach 1e-323 m, where ``1 / (2a)``
overflows), and no film, however resistive, turns the solve into NaN.

The conductance is ``kappa = sum_i f_i / rho*`` and ``R = 1 / kappa``. ``M`` is symmetric; it
is positive definite for non-overlapping spots (:func:`resistance_dense` verifies it by a
Cholesky factorization). With trial currents ``t_i = 1 / M_ii`` (each spot's own conductance,
``2 a_i`` when clean) the Rayleigh quotient ``(sum t)^2 / t^T M t`` is Greenwood's closed form
(Eqs. 11-13 with radius weights, generalized to films), so Greenwood's conductance never exceeds
the exact one (:func:`greenwood_resistance` takes no lattice term: see there).

:func:`resistance` solves ``M f = 1`` matrix-free for a batch of oxide masks at every load step,
with the calling convention of :func:`g2tom.physics.constriction.resistance`:
``M f = f / (2a) + film term + (K * f) / pi``, ``K * f`` from
:func:`g2tom.physics.interaction_folded.interaction_apply`, by a Jacobi-preconditioned
conjugate gradient batched over the maps, started from the previous load step's solution. The
conductance is the variational estimate ``J(f) = 2 sum f - f^T M f``, exact to second order in
the residual, and by default the solve stops when CG's own energy-norm record says ``J`` is
within the tolerance (see ``g2tom.physics.point_solve._solve_step``); about half the iterations a residual
criterion of the same tolerance needs.

Cropping: forcing the currents outside a crop to zero can only lower the conductance, and
(for non-negative currents, which holds on every scene we measured) the conductance is
subadditive, so ``kappa - kappa_crop <= sum_{outside} t_o / rho*`` and the relative error of
``R`` is at most ``sum_outside t / sum f_crop``; entries whose bound exceeds the crop tolerance
are solved again on the whole window.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from g2tom.physics.constriction import ChunkResult, _blocks
from g2tom.physics.interaction import block_size
from g2tom.physics.point_solve import RECORDS, solve_block
from g2tom.physics.point_system import OPERATORS, checked_settings, spot_states, system_matrix
from g2tom.physics.spot_geometry import SpotGeometry

__all__ = ["CRITERIA", "PointResult", "resistance_dense", "resistance", "greenwood_resistance"]

#: What ``solver_tolerance`` measures (see ``g2tom.physics.point_solve._solve_step``).
CRITERIA = ("error", "residual")

#: Maps per block of the solve (at most; fewer where :func:`~g2tom.physics.interaction.block_size` bounds the memory). Its
#: vectors then stay in the core's cache: on the paper's scene with two dask threads, blocks of
#: 32 made the point cube 1.4 times faster than blocks of 128 (16: 1.2 times).
POINT_BLOCK = 32


@dataclass
class PointResult(ChunkResult):
    """:class:`~g2tom.physics.constriction.ChunkResult` of the point model plus the solver's record, shape (batch, n_delta).

    ``resistance_self`` is ``rho* / sum t`` (the spots in parallel without interaction) and
    ``resistance_interaction`` is ``R - resistance_self``.

    Attributes
    ----------
    iterations
        Conjugate-gradient iterations of the final solve (int32; 0 for an open circuit).
    residual
        Final relative residual ``||1 - M f|| / ||1||`` over the spots carrying current.
    error_estimate
        Estimated relative error of the conductance: the energy-norm error removed by the last
        conjugate-gradient step over the conductance (0 where the start was exact).
    n_breakdown
        Solves stopped because ``p^T M p <= 0`` (``M`` not positive definite).
    """

    iterations: np.ndarray
    residual: np.ndarray
    error_estimate: np.ndarray
    n_breakdown: int


def resistance_dense(
    masks: np.ndarray, radius: np.ndarray, pitch: float, rho: float, film_resistance: float = np.inf,
    *, lattice_constant: float = 0.0,
) -> tuple[np.ndarray, np.ndarray]:
    """Exact and Greenwood resistances by a dense Cholesky solve per (mask, load step): the reference.

    Parameters
    ----------
    masks
        Oxide-free cells, bool (batch, n, n).
    radius
        Spot radii per load step (n_delta, n, n), in m.
    pitch
        Cell pitch, in m.
    rho
        Effective resistivity rho*, in ohm m.
    film_resistance
        Film's specific resistance on oxidized spots, in ohm m^2; ``inf`` is insulating.
    lattice_constant
        C of the lattice term ``C / (pi pitch)`` on the diagonal, dimensionless (>= 0; 0: none).

    Returns
    -------
    tuple of numpy.ndarray
        ``(R_point, R_greenwood)``, each (batch, n_delta), in ohm; +inf for an open circuit.

    Raises
    ------
    numpy.linalg.LinAlgError
        If some ``M`` is not positive definite.
    """
    settings = checked_settings(rho, pitch, film_resistance, lattice_constant)
    n = masks.shape[-1]
    iy, ix = np.divmod(np.arange(n * n), n)
    r_point = np.full((masks.shape[0], radius.shape[0]), np.inf)
    r_green = np.full_like(r_point, np.inf)
    for b, mask in enumerate(masks):
        for k, a in enumerate(radius):
            active, diag = spot_states(mask, a, settings)
            sel = np.flatnonzero(active.ravel())
            if sel.size == 0:
                continue
            d = diag.ravel()[sel]
            m = system_matrix(ix[sel] * pitch, iy[sel] * pitch, d)
            chol = np.linalg.cholesky(m)
            f = np.linalg.solve(chol.T, np.linalg.solve(chol, np.ones(sel.size)))
            t = 1.0 / d
            r_point[b, k] = rho / f.sum()
            r_green[b, k] = rho * (t @ m @ t) / t.sum() ** 2
    return r_point, r_green



def resistance(
    masks: np.ndarray,
    spots: SpotGeometry,
    rho: float,
    method: str = "auto",
    *,
    film_resistance: float = np.inf,
    solver_tolerance: float = 1e-10,
    max_iterations: int = 100,
    criterion: str = "error",
    lattice_constant: float = 0.0,
    groups: np.ndarray | None = None,
) -> PointResult:
    """Point-interaction resistance of every (mask, load step) pair, by batched Jacobi-PCG.

    Parameters
    ----------
    masks
        Cells whose spot centre is free of oxide, bool (batch, n, n) as (y, x).
    spots
        Spot radii per load step, in order of the load (each step is warm-started from the
        previous one); its weights must equal the radii (the point model has no weighting
        convention); entries whose crop bound exceeds its tolerance are solved again on the
        whole window.
    rho
        Effective resistivity rho*, in ohm m.
    method
        Interaction operator: ``auto``/``folded`` (DFT-GEMM) or ``gemm``/``direct`` (dense).
    film_resistance
        Specific resistance of the film on oxidized spots, in ohm m^2; ``inf`` is insulating.
    solver_tolerance
        Where CG stops (> 0), in the measure ``criterion`` names.
    max_iterations
        Iteration cap per solve (>= 1); entries that reach it keep their residual on record.
    criterion
        ``error``: the estimated relative error of the conductance (the energy norm of the
        error, which the variational estimate ``J = sum f + f . r`` makes quadratic in the
        residual); ``residual``: the relative residual in the Jacobi norm.
    lattice_constant
        C of the lattice self term ``C / (pi pitch)`` added to every spot's ``M_ii``,
        dimensionless, finite and >= 0; 0 (default) leaves the model as published,
        :data:`~g2tom.physics.lattice.SQUARE_LATTICE_CONSTANT` makes the spots of a smooth
        field (one per cell) reproduce the continuum.
    groups
        Which set of spots each map has, int (batch,), ``spots.radius`` then (n_groups, n_delta, n, n)
        (the ``asperities`` discretization); None: one set for all maps (see
        :func:`g2tom.physics.constriction.resistance`).

    Returns
    -------
    PointResult
        Arrays of shape (batch, n_delta).
    """
    if method not in OPERATORS:
        raise ValueError(f"method = {method!r} is not allowed for the point model: must be one of {', '.join(OPERATORS)}")
    if spots.weights is not spots.radius and not np.array_equal(spots.weights, spots.radius):
        raise ValueError("the point model takes the spot radii as weights")
    if not solver_tolerance > 0 or max_iterations < 1:
        raise ValueError(f"solver_tolerance = {solver_tolerance!r} must be > 0 and max_iterations = {max_iterations!r} >= 1")
    if criterion not in CRITERIA:
        raise ValueError(f"criterion = {criterion!r} is not allowed: must be one of {', '.join(CRITERIA)}")
    settings = {**checked_settings(rho, spots.pitch, film_resistance, lattice_constant), "method": method,
                "solver_tolerance": solver_tolerance, "max_iterations": max_iterations, "criterion": criterion}
    return _run(masks, spots.radius, spots.crops, spots.tolerance, settings, groups)


def _run(masks: np.ndarray, radius: np.ndarray, crops: np.ndarray, tolerance: float, settings: dict,
         groups: np.ndarray | None = None) -> PointResult:
    """:func:`resistance` after validation (``max_iterations = 0`` stops at Greenwood's start)."""
    rho = settings["rho"]
    batch = masks.shape[0]
    size = min(POINT_BLOCK, block_size(masks.shape[-1]))
    padded = None if groups is None else np.concatenate([groups, np.zeros(-batch % size, int)])
    parts = [solve_block(block, radius, crops, tolerance, settings,
                          None if padded is None else padded[start : start + size])
             for start, block in zip(range(0, batch, size), _blocks(masks, size))]
    out = {
        name: np.concatenate([p[name] for p in parts])[:batch] if parts else np.zeros((0, radius.shape[-3]))
        for name in RECORDS + ("bound", "uncropped")
    }

    def inverse(conductance: np.ndarray) -> np.ndarray:
        positive = conductance > 0
        return np.where(positive, rho / np.where(positive, conductance, 1.0), np.inf)

    r, r_self = inverse(out["total"]), inverse(out["t_total"])
    r_int = np.subtract(r, r_self, out=np.full_like(r, np.inf), where=np.isfinite(r))
    return PointResult(
        r, r_self, r_int, out["count"].astype(np.int32), out["bound"], int(out["uncropped"].sum()),
        out["iterations"].astype(np.int32), out["residual"], out["error"],
        int(out["breakdown"].sum()),
    )


def greenwood_resistance(
    masks: np.ndarray,
    spots: SpotGeometry,
    rho: float,
    method: str = "auto",
    *,
    film_resistance: float = np.inf,
    groups: np.ndarray | None = None,
) -> ChunkResult:
    """Greenwood's closed form generalized to films: the Rayleigh quotient at ``t_i = 1 / M_ii``.

    ``R = rho* / sum t + rho* sum_{i != j} t_i t_j / d_ij / (pi (sum t)^2)``: Greenwood's Eqs. 11-13
    with every spot's own conductance ``t_i`` (``2 a_i`` when clean, ``a_i`` and film in series
    when oxidized) as its weight; equal to :func:`g2tom.physics.constriction.resistance` with
    radius weights for an insulating film. Evaluated on the whole window (the crops of ``spots``
    must not crop; its tolerance is unused).

    Parameters
    ----------
    masks, rho, method, film_resistance, groups
        As for :func:`resistance`. There is no lattice term: the form stays Greenwood's (and
        equal to the insulating-film path of :mod:`~g2tom.physics.constriction`). With the
        term it would be the Rayleigh quotient of the corrected ``M``, a lower bound of that
        model's conductance, which on the paper's scene with expected spots falls 0.01-5.1 %
        below Barber's K/(E* rho*) against -3.3 ... +1.8 % without it.
    spots
        As for :func:`resistance`, on the whole window (crops ``n`` for every load step,
        :meth:`~g2tom.physics.spot_geometry.SpotGeometry.whole_window`).

    Returns
    -------
    ChunkResult
        ``R``, ``R_self = rho* / sum t`` and ``R_int``, shape (batch, n_delta); no crop bound.
    """
    n = masks.shape[-1]
    if method not in OPERATORS:
        raise ValueError(f"method = {method!r} is not allowed: must be one of {', '.join(OPERATORS)}")
    if not np.all(np.asarray(spots.crops) == n):
        raise ValueError("greenwood_resistance evaluates the whole window: crops must all be n")
    if spots.weights is not spots.radius and not np.array_equal(spots.weights, spots.radius):
        raise ValueError("Greenwood's form with films takes the spot radii as weights")
    settings = {**checked_settings(rho, spots.pitch, film_resistance, 0.0), "method": method,
                "solver_tolerance": 1.0, "max_iterations": 0, "criterion": "residual"}
    res = _run(masks, spots.radius, spots.crops, spots.tolerance, settings, groups)
    return ChunkResult(res.resistance, res.resistance_self, res.resistance_interaction, res.n_conducting,
                       res.crop_bound, 0)
