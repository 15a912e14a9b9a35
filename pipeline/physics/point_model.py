"""The point-interaction model: exact currents of a multi-spot contact, with or without oxide film.

Spots ``i`` of radius ``a_i`` at cell centres ``x_i``, all at one potential ``V = rho*`` above
the far field, carry currents ``f_i`` (in m, i.e. amperes per ``V / rho*``) with

    sum_j M_ij f_j = 1,   M_ii = 1 / (2 a_i) + r_i / (rho* pi a_i^2) + C / (pi dx),   M_ij = 1 / (pi d_ij),

where ``r_i`` is the specific resistance of a film on spot ``i`` (0 for a clean spot; an
insulating film removes the spot) and ``C`` the optional lattice constant (default 0): with
``C`` = :data:`~pipeline.physics.lattice.SQUARE_LATTICE_CONSTANT` the term restores the
interaction of each spot with its own cell's neighbourhood that the lattice sum over the other
spots misses when the spots stand for a continuous distribution (:mod:`pipeline.physics.lattice`).
Spots whose own conductance ``1 / M_ii`` is below :data:`CONDUCTANCE_FLOOR` pitches are treated
as absent, so that no radius, however small (expected radii reach 1e-323 m, where ``1 / (2a)``
overflows), and no film, however resistive, turns the solve into NaN.

The conductance is ``kappa = sum_i f_i / rho*`` and ``R = 1 / kappa``. ``M`` is symmetric; it
is positive definite for non-overlapping spots (:func:`resistance_dense` verifies it by a
Cholesky factorization). With trial currents ``t_i = 1 / M_ii`` (each spot's own conductance,
``2 a_i`` when clean) the Rayleigh quotient ``(sum t)^2 / t^T M t`` is Greenwood's closed form
(Eqs. 11-13 with radius weights, generalized to films), so Greenwood's conductance never exceeds
the exact one (:func:`greenwood_resistance` takes no lattice term: see there).

:func:`resistance` solves ``M f = 1`` matrix-free for a batch of oxide masks at every load step,
with the calling convention of :func:`pipeline.physics.constriction.resistance`:
``M f = f / (2a) + film term + (K * f) / pi``, ``K * f`` from
:func:`pipeline.physics.interaction_fft.interaction_apply`, by a Jacobi-preconditioned
conjugate gradient batched over the maps, started from the previous load step's solution. The
conductance is the variational estimate ``J(f) = 2 sum f - f^T M f``, exact to second order in
the residual, and by default the solve stops when CG's own energy-norm record says ``J`` is
within the tolerance (see :func:`_solve_step`); about half the iterations a residual
criterion of the same tolerance needs.

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
    "CRITERIA",
    "OPERATORS",
    "CONDUCTANCE_FLOOR",
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


#: Spots whose own conductance ``t = 1 / M_ii`` (``2a`` when clean) is below this many cell
#: pitches carry no current. A spot's current is at most its ``t`` (the currents are
#: non-negative), so removing even a million such spots changes the conductance (m) by less than
#: 1e-94 pitches; and every remaining ``M_ii`` is at most 1e100 / pitch, so ``M_ii``, its square
#: and ``1 / sqrt(M_ii)`` stay normal doubles (a radius of 1e-323 m makes ``1 / (2a)`` inf, and
#: the solve NaN). Spots far smaller than an atom (1e-30 m on the paper's pitch) are still solved.
CONDUCTANCE_FLOOR = 1e-100

#: What ``solver_tolerance`` measures (see :func:`_solve_step`).
CRITERIA = ("error", "residual")

#: Maps per block of the solve (at most; fewer where :func:`block_size` bounds the memory). Its
#: vectors then stay in the core's cache: on the paper's scene with two dask threads, blocks of
#: 32 made the point cube 1.4 times faster than blocks of 128 (16: 1.2 times).
POINT_BLOCK = 32

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


def _checked_settings(rho: float, pitch: float, film_resistance: float, lattice_constant: float) -> dict:
    """The physical settings of a solve, validated."""
    if not film_resistance >= 0:
        raise ValueError(f"film_resistance = {film_resistance!r} must be >= 0 (ohm m^2) or inf")
    if not (np.isfinite(lattice_constant) and lattice_constant >= 0):
        raise ValueError(f"lattice_constant = {lattice_constant!r} is out of range: must be finite and >= 0")
    return {"rho": rho, "pitch": pitch, "film_resistance": film_resistance, "lattice_constant": lattice_constant}


def _spot_states(
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
    settings = _checked_settings(rho, pitch, film_resistance, lattice_constant)
    n = masks.shape[-1]
    iy, ix = np.divmod(np.arange(n * n), n)
    r_point = np.full((masks.shape[0], radius.shape[0]), np.inf)
    r_green = np.full_like(r_point, np.inf)
    for b, mask in enumerate(masks):
        for k, a in enumerate(radius):
            active, diag = _spot_states(mask, a, settings)
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
    total: np.ndarray  # variational conductance estimate J = sum f + f . r, m
    outside: np.ndarray  # sum of t over the spots outside the crop, m
    t_total: np.ndarray  # sum of t over the whole window, m
    count: np.ndarray  # spots carrying current
    iterations: np.ndarray
    residual: np.ndarray
    error: np.ndarray  # estimated relative error of total (energy norm of the last step)
    breakdown: np.ndarray


def _dot(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Per-map inner products of (x, y, map) arrays."""
    return np.einsum("xyb,xyb->b", u, v)


def _scaled_start(v: np.ndarray, mv: np.ndarray, has: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Start ``x = c v`` and its ``M x``, with ``c = sum v / v^T M v`` minimizing the energy norm of the error.

    For ``v = t`` the variational estimate at this start is Greenwood's Rayleigh quotient
    ``(sum t)^2 / t^T M t``.
    """
    c = np.divide(v.sum(axis=(0, 1)), _dot(v, mv), out=np.zeros(v.shape[-1]), where=has)
    return c * v, c * mv


#: The inner iterations run in float32 (the folded operator is 2-3 times faster) while the
#: diagonal stays below this (1/m), so that ``1 / sqrt(M_ii)`` stays a normal float32; beyond
#: it (spots far smaller than an atom, or very resistive films) they run in float64.
SINGLE_PRECISION_DIAGONAL = 1e60
#: An inner round stops once its recurrence residual has fallen by this factor: the float32
#: recurrence no longer tracks the true residual much beyond it, so a new round restarts
#: from the float64 residual.
ROUND_REDUCTION = 1e-5


@dataclass
class _System:
    """``M`` of one load step on a crop, maps on the last axis of the (x, y, map) layout."""

    b: np.ndarray  # 1 on the spots carrying current, else 0
    diag: np.ndarray  # M_ii (1 where no current), 1/m
    pitch: float
    apply: Callable[[np.ndarray, float], np.ndarray]

    def __post_init__(self) -> None:
        spots = self.diag[self.b > 0]
        self.single = np.float32 if spots.max(initial=0.0) < SINGLE_PRECISION_DIAGONAL else np.float64
        self.root_t = self.b / np.sqrt(self.diag)  # D^-1/2 on the spots, 0 elsewhere
        self._scaled = tuple(np.asarray(a, self.single) for a in (self.root_t, self.root_t / np.pi))
        self._coupling, self._own = self.b / np.pi, self.diag * self.b

    def apply_m(self, v: np.ndarray) -> np.ndarray:
        """``M v`` on the spots carrying current (0 elsewhere), in float64."""
        out = self.apply(v, self.pitch)
        out *= self._coupling
        out += self._own * v
        return out

    def apply_scaled(self, y: np.ndarray) -> np.ndarray:
        """``D^-1/2 M D^-1/2 y = y + D^-1/2 (K * D^-1/2 y) / pi`` for ``y`` zero off the spots, in ``single``."""
        root_t, root_t_pi = self._scaled
        out = self.apply(root_t * y, self.pitch)
        out *= root_t_pi
        out += y
        return out


def _cg_round(
    system: _System, r: np.ndarray, scale: np.ndarray, safe_b: np.ndarray, active: np.ndarray,
    budget: np.ndarray, settings: dict,
) -> tuple[np.ndarray, ...]:
    """One round of Jacobi-preconditioned CG on ``M d = r`` from ``d = 0``, in ``system.single``.

    It runs as plain CG on the symmetrically scaled system ``(D^-1/2 M D^-1/2) y = D^-1/2 r``,
    ``d = D^-1/2 y`` (the same iterates as Jacobi-PCG), so every vector stays of order one
    whatever the spot sizes. Maps stop (are frozen) when they meet ``settings["criterion"]``
    (``error``: the energy error the step removed, relative to ``scale``, the conductance;
    ``residual``: the relative residual), when the round's residual has fallen by
    :data:`ROUND_REDUCTION`, at a breakdown, or when their iteration ``budget`` is spent.

    Returns
    -------
    tuple
        ``(d, iterations, error, met, breakdown)`` per map (``d`` in float64).
    """
    single = system.single
    tolerance, by_error = settings["solver_tolerance"], settings["criterion"] == "error"
    r = system.root_t * r
    # each map's residual scaled to unit norm, so float32 neither underflows nor overflows
    norm = np.sqrt(_dot(r, r))
    norm = np.where(norm > 0, norm, 1.0)
    r = (r / norm).astype(single)
    p = r.copy()
    y = np.zeros_like(r)
    rr = _dot(r, r).astype(np.float64)
    floor = ROUND_REDUCTION**2 * rr
    batch = r.shape[-1]
    iterations = np.zeros(batch, np.int32)
    error = np.full(batch, np.inf)
    met = np.zeros(batch, bool)
    breakdown = np.zeros(batch, bool)
    running = active & (rr > 0) & (budget > 0)
    while running.any():
        q = system.apply_scaled(p)
        pq = _dot(p, q).astype(np.float64)
        broken = running & ~(pq > 0)
        breakdown |= broken
        running &= ~broken
        alpha = np.divide(rr, pq, out=np.zeros_like(rr), where=running)
        y += alpha.astype(single) * p
        r -= alpha.astype(single) * q
        rr_new = _dot(r, r).astype(np.float64)
        beta = np.divide(rr_new, rr, out=np.zeros_like(rr), where=running)
        p *= beta.astype(single)
        p += r
        # the step's energy reduction estimates the error before it; none is left at a zero residual
        step = np.divide(alpha * rr * norm**2, scale, out=np.zeros_like(rr), where=running & (rr_new > 0))
        error = np.where(running, step, error)
        iterations += running
        rr = np.where(running, rr_new, rr)
        now = (error <= tolerance) if by_error else (np.sqrt(np.maximum(rr, 0.0)) * norm / safe_b <= tolerance)
        met |= running & (now | ~(rr_new > 0))
        running &= ~met & (rr_new > floor) & (iterations < budget)
    return system.root_t * norm * y, iterations, error, met, breakdown


def _solve_step(
    columns: np.ndarray,
    radius_xy: np.ndarray,
    size: int,
    previous: np.ndarray | None,
    settings: dict,
) -> _Solve:
    """Solve ``M f = 1`` for every mask at one load step on the centred ``size``-cell crop.

    ``columns`` holds the oxide-free cells laid out (x, y, map), the layout the interaction
    operator works in, so no vector of the iteration is ever transposed. The start is
    ``t * previous`` (``previous``: the shielding factors ``f / t`` of the neighbouring load
    step on the whole window, same layout), or Greenwood's trial vector ``t`` where there is
    none, scaled to minimize the energy norm of the error (one operator application; adding
    ``t`` to the span as well saved fewer iterations than the application it costs). With
    ``settings["max_iterations"] = 0`` the result is therefore Greenwood's closed form.

    Then rounds of mixed-precision iterative refinement: Jacobi-preconditioned CG on the
    correction ``M d = r`` in float32 (:func:`_cg_round`), ``f += d``, and the residual
    ``r = 1 - M f`` and the conductance recomputed in float64, until each map meets
    ``settings["criterion"]``:

    * ``error``: the conductance is estimated variationally, ``J(f) = 2 sum f - f^T M f =
      sum f + f . r``, whose error ``J* - J = ||f* - f||_M^2`` is quadratic in the residual;
      CG's step ``k`` lowers that energy error by exactly ``alpha_k r_k . z_k``
      (Hestenes-Stiefel), the estimate of the error left before the step. The solve stops after
      the step whose estimate, relative to ``J``, is below ``settings["solver_tolerance"]``; the
      step's own reduction makes the returned error smaller still.
    * ``residual``: the relative residual in the Jacobi norm, recomputed in float64, falls
      below the tolerance.

    Maps that meet it are frozen, so every map's result is independent of its neighbours in the
    batch. ``radius_xy`` holds the spot radii in the same layout: (x, y, 1) for spots shared by
    every map, or (x, y, map).
    """
    n = columns.shape[0]
    c = crop_slice(n, size)
    active_full, diag_full = _spot_states(columns, radius_xy, settings)
    t_full = np.where(active_full, 1.0 / diag_full, 0.0)
    diag = np.ascontiguousarray(diag_full[c, c])
    system = _System(active_full[c, c].astype(np.float64), diag, settings["pitch"], OPERATORS[settings["method"]])
    t = np.ascontiguousarray(t_full[c, c])
    st = t.sum(axis=(0, 1))
    has = st > 0
    v = t if previous is None else t * previous[c, c]
    v = np.where(v.sum(axis=(0, 1)) > 0, v, t)  # no current before on these spots: Greenwood's vector
    x, mx = _scaled_start(v, system.apply_m(v), has)
    r = system.b - mx
    # Residuals in the Jacobi norm ||r||_{D^-1} = sqrt(r . r / M_ii), i.e. weighted by each spot's own
    # conductance t: ||r|| / ||1|| = sqrt(r . z / sum t), with z = D^-1 r the preconditioned residual.
    safe_b = np.where(has, np.sqrt(st), 1.0)
    rz = _dot(r, r / diag)
    residual = np.sqrt(np.maximum(rz, 0.0)) / safe_b
    total = x.sum(axis=(0, 1)) + _dot(x, r)
    exact = ~(rz > 0)  # no current, or the start is the solution
    # before any step, the Jacobi estimate r^T D^-1 r of the energy error r^T M^-1 r
    error = np.divide(rz, total, out=np.where(exact, 0.0, np.inf), where=~exact & (total > 0))
    done = exact if settings["criterion"] == "error" else exact | (residual <= settings["solver_tolerance"])
    batch = columns.shape[-1]
    iterations = np.zeros(batch, np.int32)
    breakdown = np.zeros(batch, bool)
    while not done.all() and (iterations < settings["max_iterations"]).any():
        scale = np.where(total > 0, total, 1.0)
        d, steps, round_error, met, broken = _cg_round(
            system, r, scale, safe_b, ~done, settings["max_iterations"] - iterations, settings)
        if not steps.any():
            break
        x += d
        r = system.b - system.apply_m(x)
        total = np.where(done, total, x.sum(axis=(0, 1)) + _dot(x, r))
        rz = _dot(r, r / diag)
        residual = np.where(done, residual, np.sqrt(np.maximum(rz, 0.0)) / safe_b)
        error = np.where(steps > 0, round_error, error)
        iterations += steps
        breakdown |= broken
        if settings["criterion"] == "residual":
            met = residual <= settings["solver_tolerance"]
        done |= met | broken
    shielding = np.zeros(columns.shape)
    shielding[c, c] = x * diag * system.b
    t_total = t_full.sum(axis=(0, 1))
    count = active_full.sum(axis=(0, 1))
    return _Solve(shielding, total, t_total - st, t_total, count,
                  iterations, residual, error, breakdown)


_RECORDS = ("total", "t_total", "count", "iterations", "residual", "error", "breakdown")


def _solve_block(
    block: np.ndarray, radius: np.ndarray, crops: np.ndarray, tolerance: float, settings: dict,
    groups: np.ndarray | None = None,
) -> dict[str, np.ndarray]:
    """Every load step of one block of :func:`~pipeline.physics.constriction.block_size` masks, each warm-started from the previous one.

    Entries whose cropping bound exceeds ``tolerance`` are solved again on the whole window,
    gathered into padded blocks of exactly :data:`REDO_BLOCK` maps (a fixed shape, so results
    never depend on the batch; small, because such entries are rare and scattered). With
    ``groups`` (one per map), map ``b`` has the spots ``radius[groups[b]]``.
    """
    n = block.shape[-1]
    n_delta = radius.shape[-3]
    columns = np.ascontiguousarray(block.transpose(2, 1, 0))  # (x, y, map)
    out = {name: np.zeros((block.shape[0], n_delta)) for name in _RECORDS + ("bound", "uncropped")}
    previous = None
    for k in range(n_delta):
        a = radius[k].T[:, :, None] if groups is None else radius[groups, k].transpose(2, 1, 0)
        step = _solve_step(columns, a, int(crops[k]), previous, settings)
        # no current inside the crop but some outside: the crop bound is infinite
        bound = np.divide(step.outside, step.total, out=np.where(step.outside > 0, np.inf, 0.0),
                          where=step.total > 0)
        rows = np.flatnonzero(bound > tolerance)
        for start in range(0, rows.size, REDO_BLOCK):
            chosen = rows[start : start + REDO_BLOCK]
            again = np.zeros(columns.shape[:2] + (REDO_BLOCK,), dtype=bool)
            again[..., : chosen.size] = columns[..., chosen]
            warm = np.zeros(again.shape)
            warm[..., : chosen.size] = step.shielding[..., chosen]
            own = a
            if groups is not None:
                own = np.zeros(again.shape)
                own[..., : chosen.size] = a[..., chosen]
            whole = _solve_step(again, own, n, warm, settings)
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
    criterion: str = "error",
    lattice_constant: float = 0.0,
    groups: np.ndarray | None = None,
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
        :data:`~pipeline.physics.lattice.SQUARE_LATTICE_CONSTANT` makes the spots of a smooth
        field (one per cell) reproduce the continuum.
    groups
        Which set of spots each map has, int (batch,), ``radius`` then (n_groups, n_delta, n, n)
        (the ``asperities`` discretization); None: one set for all maps (see
        :func:`pipeline.physics.constriction.resistance`).

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
    if criterion not in CRITERIA:
        raise ValueError(f"criterion = {criterion!r} is not allowed: must be one of {', '.join(CRITERIA)}")
    settings = {**_checked_settings(rho, pitch, film_resistance, lattice_constant), "method": method,
                "solver_tolerance": solver_tolerance, "max_iterations": max_iterations, "criterion": criterion}
    return _run(masks, radius, crops, tolerance, settings, groups)


def _run(masks: np.ndarray, radius: np.ndarray, crops: np.ndarray, tolerance: float, settings: dict,
         groups: np.ndarray | None = None) -> PointResult:
    """:func:`resistance` after validation (``max_iterations = 0`` stops at Greenwood's start)."""
    rho = settings["rho"]
    batch = masks.shape[0]
    size = min(POINT_BLOCK, block_size(masks.shape[-1]))
    padded = None if groups is None else np.concatenate([groups, np.zeros(-batch % size, int)])
    parts = [_solve_block(block, radius, crops, tolerance, settings,
                          None if padded is None else padded[start : start + size])
             for start, block in zip(range(0, batch, size), _blocks(masks, size))]
    out = {
        name: np.concatenate([p[name] for p in parts])[:batch] if parts else np.zeros((0, radius.shape[-3]))
        for name in _RECORDS + ("bound", "uncropped")
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
    radius: np.ndarray,
    weights: np.ndarray,
    pitch: float,
    rho: float,
    crops: np.ndarray,
    tolerance: float,
    method: str = "auto",
    *,
    film_resistance: float = np.inf,
    groups: np.ndarray | None = None,
) -> ChunkResult:
    """Greenwood's closed form generalized to films: the Rayleigh quotient at ``t_i = 1 / M_ii``.

    ``R = rho* / sum t + rho* sum_{i != j} t_i t_j / d_ij / (pi (sum t)^2)``: Greenwood's Eqs. 11-13
    with every spot's own conductance ``t_i`` (``2 a_i`` when clean, ``a_i`` and film in series
    when oxidized) as its weight; equal to :func:`pipeline.physics.constriction.resistance` with
    radius weights for an insulating film. Evaluated on the whole window (``crops`` and
    ``tolerance`` are accepted for the calling convention and must not crop).

    Parameters
    ----------
    masks, radius, weights, pitch, rho, method, film_resistance, groups
        As for :func:`resistance`. There is no lattice term: the form stays Greenwood's (and
        equal to the insulating-film path of :mod:`~pipeline.physics.constriction`). With the
        term it would be the Rayleigh quotient of the corrected ``M``, a lower bound of that
        model's conductance, which on the paper's scene with expected spots falls 0.01-5.1 %
        below Barber's K/(E* rho*) against -3.3 ... +1.8 % without it.
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
    settings = {**_checked_settings(rho, pitch, film_resistance, 0.0), "method": method,
                "solver_tolerance": 1.0, "max_iterations": 0, "criterion": "residual"}
    res = _run(masks, radius, crops, tolerance, settings, groups)
    return ChunkResult(res.resistance, res.resistance_self, res.resistance_interaction, res.n_conducting,
                       res.crop_bound, 0)
