"""The point-interaction model: exact currents of a multi-spot contact, with or without oxide film.

Spots ``i`` of radius ``a_i`` at cell centres ``x_i``, all at one potential ``V = rho*`` above
the far field, carry currents ``f_i`` (in m, i.e. amperes per ``V / rho*``) with

    sum_j M_ij f_j = 1,   M_ii = 1 / (2 a_i) + r_i / (rho* pi a_i^2),   M_ij = 1 / (pi d_ij),

where ``r_i`` is the specific resistance of a film on spot ``i`` (0 for a clean spot; an
insulating film removes the spot). The conductance is ``kappa = sum_i f_i / rho*`` and
``R = 1 / kappa``. ``M`` is symmetric; it is positive definite for non-overlapping spots
(:func:`resistance_dense` verifies it by a Cholesky factorization). With trial currents
``t_i = 1 / M_ii`` (each spot's own conductance, ``2 a_i`` when clean) the Rayleigh quotient
``(sum t)^2 / t^T M t`` is Greenwood's closed form (Eqs. 11-13 with radius weights, generalized
to films), so Greenwood's conductance never exceeds the exact one.

:func:`resistance` solves ``M f = 1`` matrix-free for a batch of oxide masks at every load step,
with the calling convention of :func:`pipeline.physics.constriction.resistance`:
``M f = f / (2a) + film term + (K * f) / pi``, ``K * f`` from
:func:`pipeline.physics.interaction_fft.interaction_apply`, by a Jacobi-preconditioned
conjugate gradient batched over the maps, started from the Galerkin combination of Greenwood's
trial vector and the previous load step's solution.

Cropping: forcing the currents outside a crop to zero can only lower the conductance, and
(for non-negative currents, which holds on every scene we measured) the conductance is
subadditive, so ``kappa - kappa_crop <= sum_{outside} t_o / rho*`` and the relative error of
``R`` is at most ``sum_outside t / sum f_crop``; entries whose bound exceeds the crop tolerance
are solved again on the whole window.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from pipeline.physics.constriction import ChunkResult, _blocks, block_size, crop_slice
from pipeline.physics.interaction_fft import interaction_apply_columns, interaction_apply_dense_columns

__all__ = [
    "OPERATORS",
    "PointResult",
    "film_diagonal",
    "system_matrix",
    "resistance_dense",
    "resistance",
    "greenwood_resistance",
]

#: Interaction operators ``K * f`` by ``cube.method``: the folded DFT-GEMM or the dense matrix.
OPERATORS: dict[str, Callable[[np.ndarray, float], np.ndarray]] = {
    "auto": interaction_apply_columns,
    "folded": interaction_apply_columns,
    "gemm": interaction_apply_dense_columns,
    "direct": interaction_apply_dense_columns,
}


#: Maps per block of entries solved again on the whole window (see :func:`_solve_block`).
REDO_BLOCK = 8


@dataclass
class PointResult(ChunkResult):
    """:class:`ChunkResult` of the point model plus the solver's record, shape (batch, n_delta).

    ``resistance_self`` is ``rho* / sum t`` (the spots in parallel without interaction) and
    ``resistance_interaction`` is ``R - resistance_self``.

    Attributes
    ----------
    iterations
        Conjugate-gradient iterations of the final solve (int32; 0 for an open circuit).
    residual
        Final relative residual ``||1 - M f|| / ||1||`` over the spots carrying current.
    resistance_greenwood
        Greenwood's closed form (the Rayleigh quotient at the trial currents), in ohm.
    n_breakdown
        Solves stopped because ``p^T M p <= 0`` (``M`` not positive definite).
    """

    iterations: np.ndarray
    residual: np.ndarray
    resistance_greenwood: np.ndarray
    n_breakdown: int


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


def _spot_states(
    mask: np.ndarray, radius: np.ndarray, rho: float, film_resistance: float
) -> tuple[np.ndarray, np.ndarray]:
    """Spots carrying current and the diagonal ``M_ii`` (1 where none), broadcast shapes.

    An insulating film (``film_resistance = inf``) removes the oxidized spots; a finite one
    keeps them, with the film in series.
    """
    spot = radius > 0
    if np.isinf(film_resistance):
        active = spot & mask
        diag = np.where(active, 1.0 / (2.0 * np.where(spot, radius, 1.0)), 1.0)
    else:
        active = np.broadcast_to(spot, np.broadcast_shapes(spot.shape, mask.shape))
        safe = np.where(spot, radius, 1.0)
        diag = np.where(active, film_diagonal(safe, ~mask, rho, film_resistance), 1.0)
    return active, diag


def resistance_dense(
    masks: np.ndarray, radius: np.ndarray, pitch: float, rho: float, film_resistance: float = np.inf
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

    Returns
    -------
    tuple of numpy.ndarray
        ``(R_point, R_greenwood)``, each (batch, n_delta), in ohm; +inf for an open circuit.

    Raises
    ------
    numpy.linalg.LinAlgError
        If some ``M`` is not positive definite.
    """
    n = masks.shape[-1]
    iy, ix = np.divmod(np.arange(n * n), n)
    r_point = np.full((masks.shape[0], radius.shape[0]), np.inf)
    r_green = np.full_like(r_point, np.inf)
    for b, mask in enumerate(masks):
        for k, a in enumerate(radius):
            active, diag = _spot_states(mask, a, rho, film_resistance)
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


@dataclass
class _Solve:
    """One batched solve at one load step; maps on the last axis of the (x, y, map) layout."""

    shielding: np.ndarray  # f / t on the whole window (n, n, batch), 0 where no current
    total: np.ndarray  # sum f, m
    greenwood: np.ndarray  # Rayleigh quotient (sum t)^2 / t^T M t, m
    outside: np.ndarray  # sum of t over the spots outside the crop, m
    t_total: np.ndarray  # sum of t over the whole window, m
    count: np.ndarray  # spots carrying current
    iterations: np.ndarray
    residual: np.ndarray
    breakdown: np.ndarray


def _dot(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Per-map inner products of (x, y, map) arrays."""
    return np.einsum("xyb,xyb->b", u, v)


def _solve_step(
    columns: np.ndarray,
    radius: np.ndarray,
    size: int,
    previous: np.ndarray | None,
    settings: dict,
) -> _Solve:
    """Solve ``M f = 1`` for every mask at one load step on the centred ``size``-cell crop.

    ``columns`` holds the oxide-free cells laid out (x, y, map), the layout the interaction
    operator works in, so no vector of the iteration is ever transposed. Greenwood's trial
    vector ``t`` and ``t * previous`` (``previous``: the shielding factors ``f / t`` of the
    neighbouring load step on the whole window, same layout, or None) span the start: the
    Galerkin combination minimizing the energy norm of the error over that span. Then
    Jacobi-preconditioned CG runs until each map's relative residual is below
    ``settings["solver_tolerance"]``; maps that converge are frozen, so every map's result is
    independent of its neighbours in the batch.
    """
    n = columns.shape[0]
    rho, film, pitch = settings["rho"], settings["film_resistance"], settings["pitch"]
    apply = OPERATORS[settings["method"]]
    c = crop_slice(n, size)
    active_full, diag_full = _spot_states(columns, radius.T[:, :, None], rho, film)
    t_full = np.where(active_full, 1.0 / diag_full, 0.0)
    active, diag = active_full[c, c], np.ascontiguousarray(diag_full[c, c])
    b = active.astype(np.float64)

    def operator(v: np.ndarray) -> np.ndarray:
        out = apply(v, pitch)
        out *= 1.0 / np.pi
        out += diag * v
        out *= b
        return out

    t = np.ascontiguousarray(t_full[c, c])
    mt = operator(t)
    tmt, st = _dot(t, mt), t.sum(axis=(0, 1))
    has = st > 0
    greenwood = np.divide(st**2, tmt, out=np.zeros_like(st), where=has)
    # Galerkin start on span{t, t * previous}; span{t} alone where the 2x2 system is singular.
    coef = np.divide(st, tmt, out=np.zeros_like(st), where=has)
    x = coef * t
    r = b - coef * mt
    if previous is not None:
        p0 = t * previous[c, c]
        mp0 = operator(p0)
        g11, g12, g22 = tmt, _dot(t, mp0), _dot(p0, mp0)
        r1, r2 = st, p0.sum(axis=(0, 1))
        det = g11 * g22 - g12**2
        ok = has & (det > 1e-12 * g11 * g22)
        ct = np.divide(g22 * r1 - g12 * r2, det, out=coef.copy(), where=ok)
        cp = np.divide(g11 * r2 - g12 * r1, det, out=np.zeros_like(st), where=ok)
        x = ct * t + cp * p0
        r = b - ct * mt - cp * mp0
    # Residuals in the Jacobi norm ||r||_{D^-1} = sqrt(r . r / M_ii), i.e. weighted by each spot's own
    # conductance t: ||r|| / ||1|| = sqrt(r . z / sum t), with z = D^-1 r the preconditioned residual.
    safe_b = np.where(has, np.sqrt(st), 1.0)
    z = r / diag
    p = z.copy()
    rz = _dot(r, z)
    batch = columns.shape[-1]
    iterations = np.zeros(batch, np.int32)
    breakdown = np.zeros(batch, bool)
    residual = np.sqrt(np.maximum(rz, 0.0)) / safe_b
    done = ~has | (residual <= settings["solver_tolerance"])
    for _ in range(settings["max_iterations"]):
        if done.all():
            break
        q = operator(p)
        pq = _dot(p, q)
        broken = ~done & ~(pq > 0)
        breakdown |= broken
        done |= broken
        alpha = np.divide(rz, pq, out=np.zeros_like(rz), where=~done)
        x += alpha * p
        q *= alpha
        r -= q
        np.divide(r, diag, out=z)
        rz_new = _dot(r, z)
        beta = np.divide(rz_new, rz, out=np.zeros_like(rz), where=~done)
        p *= beta
        p += z
        rz = np.where(done, rz, rz_new)
        iterations += ~done
        residual = np.where(done, residual, np.sqrt(np.maximum(rz_new, 0.0)) / safe_b)
        done |= residual <= settings["solver_tolerance"]
    shielding = np.zeros(columns.shape)
    shielding[c, c] = x * diag * b
    t_total = t_full.sum(axis=(0, 1))
    count = active_full.sum(axis=(0, 1))
    return _Solve(shielding, x.sum(axis=(0, 1)), greenwood, t_total - st, t_total, count,
                  iterations, residual, breakdown)


_RECORDS = ("total", "greenwood", "t_total", "count", "iterations", "residual", "breakdown")


def _solve_block(
    block: np.ndarray, radius: np.ndarray, crops: np.ndarray, tolerance: float, settings: dict
) -> dict[str, np.ndarray]:
    """Every load step of one block of :func:`~pipeline.physics.constriction.block_size` masks, each warm-started from the previous one.

    Entries whose cropping bound exceeds ``tolerance`` are solved again on the whole window,
    gathered into padded blocks of exactly :data:`REDO_BLOCK` maps (a fixed shape, so results
    never depend on the batch; small, because such entries are rare and scattered).
    """
    n = block.shape[-1]
    columns = np.ascontiguousarray(block.transpose(2, 1, 0))  # (x, y, map)
    out = {name: np.zeros((block.shape[0], radius.shape[0])) for name in _RECORDS + ("bound", "uncropped")}
    previous = None
    for k, a in enumerate(radius):
        step = _solve_step(columns, a, int(crops[k]), previous, settings)
        bound = np.divide(step.outside, step.total, out=np.zeros_like(step.total), where=step.total > 0)
        rows = np.flatnonzero(bound > tolerance)
        for start in range(0, rows.size, REDO_BLOCK):
            chosen = rows[start : start + REDO_BLOCK]
            again = np.zeros(columns.shape[:2] + (REDO_BLOCK,), dtype=bool)
            again[..., : chosen.size] = columns[..., chosen]
            warm = np.zeros(again.shape)
            warm[..., : chosen.size] = step.shielding[..., chosen]
            whole = _solve_step(again, a, n, warm, settings)
            step.shielding[..., chosen] = whole.shielding[..., : chosen.size]
            for name in _RECORDS:
                getattr(step, name)[chosen] = getattr(whole, name)[: chosen.size]
            bound[chosen] = 0.0
            out["uncropped"][chosen, k] = 1.0
        for name in _RECORDS:
            out[name][:, k] = getattr(step, name)
        out["bound"][:, k] = bound
        previous = step.shielding if settings["max_iterations"] else None
    return out


def resistance(
    masks: np.ndarray,
    radius: np.ndarray,
    weights: np.ndarray,
    pitch: float,
    rho: float,
    crops: np.ndarray,
    tolerance: float,
    method: str = "auto",
    *,
    film_resistance: float = np.inf,
    solver_tolerance: float = 1e-10,
    max_iterations: int = 100,
) -> PointResult:
    """Point-interaction resistance of every (mask, load step) pair, by batched Jacobi-PCG.

    Parameters
    ----------
    masks
        Cells whose spot centre is free of oxide, bool (batch, n, n) as (y, x).
    radius
        Spot radii per load step (n_delta, n, n), in m, in order of the load (each step is
        warm-started from the previous one); 0 means no spot.
    weights
        Must equal ``radius``: the point model has no weighting convention (the argument keeps
        the calling convention of :func:`pipeline.physics.constriction.resistance`).
    pitch
        Cell pitch, in m.
    rho
        Effective resistivity rho*, in ohm m.
    crops
        Crop size per load step (:func:`pipeline.physics.constriction.choose_crops`).
    tolerance
        Entries whose crop bound exceeds this are solved again on the whole window.
    method
        Interaction operator: ``auto``/``folded`` (DFT-GEMM) or ``gemm``/``direct`` (dense).
    film_resistance
        Specific resistance of the film on oxidized spots, in ohm m^2; ``inf`` is insulating.
    solver_tolerance
        Relative residual at which CG stops (> 0).
    max_iterations
        Iteration cap per solve (>= 1); entries that reach it keep their residual on record.

    Returns
    -------
    PointResult
        Arrays of shape (batch, n_delta).
    """
    if method not in OPERATORS:
        raise ValueError(f"method = {method!r} is not allowed for the point model: must be one of {', '.join(OPERATORS)}")
    if weights is not radius and not np.array_equal(weights, radius):
        raise ValueError("the point model takes the spot radii as weights")
    if not solver_tolerance > 0 or max_iterations < 1:
        raise ValueError(f"solver_tolerance = {solver_tolerance!r} must be > 0 and max_iterations = {max_iterations!r} >= 1")
    if not film_resistance >= 0:
        raise ValueError(f"film_resistance = {film_resistance!r} must be >= 0 (ohm m^2) or inf")
    settings = {"rho": rho, "pitch": pitch, "method": method, "film_resistance": film_resistance,
                "solver_tolerance": solver_tolerance, "max_iterations": max_iterations}
    return _run(masks, radius, crops, tolerance, settings)


def _run(masks: np.ndarray, radius: np.ndarray, crops: np.ndarray, tolerance: float, settings: dict) -> PointResult:
    """:func:`resistance` after validation (``max_iterations = 0`` stops at Greenwood's start)."""
    rho = settings["rho"]
    batch = masks.shape[0]
    parts = [_solve_block(block, radius, crops, tolerance, settings) for block in _blocks(masks, block_size(masks.shape[-1]))]
    out = {
        name: np.concatenate([p[name] for p in parts])[:batch] if parts else np.zeros((0, radius.shape[0]))
        for name in _RECORDS + ("bound", "uncropped")
    }

    def inverse(conductance: np.ndarray) -> np.ndarray:
        positive = conductance > 0
        return np.where(positive, rho / np.where(positive, conductance, 1.0), np.inf)

    r, r_self = inverse(out["total"]), inverse(out["t_total"])
    r_int = np.subtract(r, r_self, out=np.full_like(r, np.inf), where=np.isfinite(r))
    return PointResult(
        r, r_self, r_int, out["count"].astype(np.int32), out["bound"], int(out["uncropped"].sum()),
        out["iterations"].astype(np.int32), out["residual"], inverse(out["greenwood"]),
        int(out["breakdown"].sum()),
    )


def greenwood_resistance(
    masks: np.ndarray,
    radius: np.ndarray,
    weights: np.ndarray,
    pitch: float,
    rho: float,
    crops: np.ndarray,
    tolerance: float,
    method: str = "auto",
    *,
    film_resistance: float = np.inf,
) -> ChunkResult:
    """Greenwood's closed form generalized to films: the Rayleigh quotient at ``t_i = 1 / M_ii``.

    ``R = rho* / sum t + rho* sum_{i != j} t_i t_j / d_ij / (pi (sum t)^2)``: Greenwood's Eqs. 11-13
    with every spot's own conductance ``t_i`` (``2 a_i`` when clean, ``a_i`` and film in series
    when oxidized) as its weight; equal to :func:`pipeline.physics.constriction.resistance` with
    radius weights for an insulating film. Evaluated on the whole window (``crops`` and
    ``tolerance`` are accepted for the calling convention and must not crop).

    Parameters
    ----------
    masks, radius, weights, pitch, rho, method, film_resistance
        As for :func:`resistance`.
    crops
        Must be the whole window (``n`` for every load step).
    tolerance
        Unused by the whole-window evaluation; kept for the calling convention.

    Returns
    -------
    ChunkResult
        ``R``, ``R_self = rho* / sum t`` and ``R_int``, shape (batch, n_delta); no crop bound.
    """
    n = masks.shape[-1]
    if method not in OPERATORS:
        raise ValueError(f"method = {method!r} is not allowed: must be one of {', '.join(OPERATORS)}")
    if not np.all(np.asarray(crops) == n):
        raise ValueError("greenwood_resistance evaluates the whole window: crops must all be n")
    if weights is not radius and not np.array_equal(weights, radius):
        raise ValueError("Greenwood's form with films takes the spot radii as weights")
    if not film_resistance >= 0:
        raise ValueError(f"film_resistance = {film_resistance!r} must be >= 0 (ohm m^2) or inf")
    settings = {"rho": rho, "pitch": pitch, "method": method, "film_resistance": film_resistance,
                "solver_tolerance": 1.0, "max_iterations": 0}
    res = _run(masks, radius, crops, tolerance, settings)
    r_self = res.resistance_self
    r_int = np.subtract(res.resistance_greenwood, r_self, out=np.full_like(r_self, np.inf),
                        where=np.isfinite(res.resistance_greenwood))
    return ChunkResult(res.resistance_greenwood, r_self, r_int, res.n_conducting, res.crop_bound, 0)
