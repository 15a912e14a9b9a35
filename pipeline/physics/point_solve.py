"""The point model's batched solve of ``M f = 1`` at every load step (see :mod:`g2tom.physics.point_model`).

A Jacobi-preconditioned conjugate gradient, matrix-free (``M f = f / (2a) + film term + (K * f) / pi``),
batched over the maps of a block, in float32 inner rounds restarted from the float64 residual,
warm-started from the previous load step's solution, on the crop of each load step; entries whose
crop bound exceeds the tolerance are solved again on the whole window.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from g2tom.physics.crops import crop_slice
from g2tom.physics.point_system import OPERATORS, spot_states

__all__ = ["RECORDS", "REDO_BLOCK", "solve_block"]

#: Maps per block of entries solved again on the whole window (see ``_solve_block``).
REDO_BLOCK = 8


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
    active_full, diag_full = spot_states(columns, radius_xy, settings)
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


RECORDS = ("total", "t_total", "count", "iterations", "residual", "error", "breakdown")


def solve_block(
    block: np.ndarray, radius: np.ndarray, crops: np.ndarray, tolerance: float, settings: dict,
    groups: np.ndarray | None = None,
) -> dict[str, np.ndarray]:
    """Every load step of one block of :func:`~g2tom.physics.interaction.block_size` masks, each warm-started from the previous one.

    Entries whose cropping bound exceeds ``tolerance`` are solved again on the whole window,
    gathered into padded blocks of exactly :data:`REDO_BLOCK` maps (a fixed shape, so results
    never depend on the batch; small, because such entries are rare and scattered). With
    ``groups`` (one per map), map ``b`` has the spots ``radius[groups[b]]``.
    """
    n = block.shape[-1]
    n_delta = radius.shape[-3]
    columns = np.ascontiguousarray(block.transpose(2, 1, 0))  # (x, y, map)
    out = {name: np.zeros((block.shape[0], n_delta)) for name in RECORDS + ("bound", "uncropped")}
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
            for name in RECORDS:
                getattr(step, name)[chosen] = getattr(whole, name)[: chosen.size]
            bound[chosen] = 0.0
            out["uncropped"][chosen, k] = 1.0
        for name in RECORDS:
            out[name][:, k] = getattr(step, name)
        out["bound"][:, k] = bound
        previous = step.shielding if settings["max_iterations"] else None
    return out
