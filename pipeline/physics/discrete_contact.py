"""Discrete asperities with elastic interaction: a rough sphere's own caps solved at a given force.

Greenwood–Tripp replaces the asperities by their mean, which is right when hundreds touch and
biased when a handful do. This model keeps one realization's asperities:

* Asperities: Poisson positions of density ``eta`` over a disc that holds every asperity able to
  touch (:func:`domain_radius`), heights ``z_i ~ N(0, sigma^2)``, spherical caps of radius
  ``beta``, drawn from their own stream per realization (:func:`draw_asperities`).
* Gap: ``g_i = z_i - profile(r_i)``, the asperity's height above the undeformed indenter surface
  measured from the tip's level; at approach ``delta`` (the tip's separation from the mean
  plane, negative: interpenetration) the interference is

      w_i = g_i - delta - sum_{j != i} C_ij P_j,      P_i = (4/3) E* sqrt(beta) max(w_i, 0)^(3/2),

  with ``C_ij = 1 / (pi E* max(r_ij, l))`` the half-space compliance of a point load (far-field
  Boussinesq, both bodies through E*). Pairs closer than the floor ``l`` (:func:`coupling_floor`)
  use ``l``: ``l = 4 sqrt(beta sigma) / (3 pi)`` is the distance at which a point load's
  displacement equals the displacement ``3P / (4 a E*)`` at the centre of a Hertzian contact of
  interference ``sigma`` (radius ``a = sqrt(beta sigma)``), so no pair is coupled more stiffly
  than a cap is to its own load.
* At a given total force ``F``: ``sum_i P_i = F`` fixes ``delta``. The solution minimises the
  energy ``sum_i (3/5) k^(-2/3) P_i^(5/3) + P^T C P / 2 - sum_i g_i P_i`` on ``{P >= 0, sum P = F}``
  (``k = (4/3) E* sqrt(beta)``), whose Hessian on the contacting caps is ``D^-1 + C``. It is solved
  by a semismooth Newton method on ``(s, delta)`` with ``s`` the interference of every candidate
  (:func:`solve_forces`), warm-started along ascending forces, with a backtracking line search on
  the residual.
* The energy is convex while the caps are small against the floor: ``D^-1 = 1 / (2 E* a_i)`` falls
  below the floor's ``1 / (pi E* l)`` once ``a_i > pi l / 2``, i.e. an interference above
  ``4 sigma / 9``, and caps that large closer than ``l`` make ``D^-1 + C`` indefinite (the atlas's
  large ``beta sigma eta``: caps wider than their spacing). There the load path can reach a fold,
  where no solution on its branch carries more force, and Newton stalls on an indefinite system.
  The solve then minimises the energy by proximal rounds (``_proximal``): each adds
  ``c |P - P_k|^2 / 2`` with ``c`` large enough to make the energy convex and is solved by the same
  Newton; their fixed point solves the original equations. The path jumps to the next branch,
  as a loaded structure snaps through; Newton's answer is used wherever it converges.
* Candidates: since every displacement is >= 0, an asperity can touch only where ``g_i > delta``;
  the solve starts from a candidate set ``g_i > threshold`` and grows it until the solved
  ``delta`` lies above the threshold, so the answer is the one on the whole set, exactly.
* Capped caps (:mod:`g2tom.physics.cap_law`) share overlapping discs: cap ``i`` carries its law's
  force times the share ``A_i / (pi a_i^2)`` of its disc that lies in its power cell
  (:mod:`g2tom.physics.cap_overlap`), so a merged contact is counted once, and ``D = dP/dw`` gains
  the neighbours' terms; Newton then solves ``(I + C D)`` as it is, on the exact derivative.
* Stiffness ``K = -dF/d delta = d^T (I + C D)^-1 1`` on the contacting set (``D = diag(dP/dw) =
  diag(2 E* a_i)``), i.e. ``K = E* 1^T M^-1 1`` with ``M_ii = 1/(2 a_i)``, ``M_ij = 1/(pi
  max(d_ij, l))``: Barber's theorem holds exactly against the point-interaction conductance on
  the same spots and kernel (:mod:`g2tom.physics.discrete_resistance`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable

import numba
import numpy as np

from g2tom.physics import indenter
from g2tom.physics.cap_law import CapLaw, HertzCap

__all__ = [
    "ASPERITIES_TAG",
    "Asperities",
    "NotConverged",
    "DiscreteContact",
    "coupling_floor",
    "sphere_cap_geometry",
    "cap_gap",
    "cap_radius",
    "interaction_kernel",
    "domain_radius",
    "draw_asperities",
    "solve_forces",
    "symmetric_solve",
]

#: Second entropy word of the asperity sets' streams: ``SeedSequence([seed, ASPERITIES_TAG],
#: spawn_key=(k,))`` for surface ``k``, never equal to an oxide field's stream (whose entropy is
#: the seed alone) nor to the grid asperities' heights (``spot_models.HEIGHTS_TAG``).
ASPERITIES_TAG = 0x61737072  # "aspr"
#: Default relative tolerance of the Newton solve: max |residual| <= tol x the largest
#: interference, and |sum P - F| <= tol x F.
TOLERANCE = 1e-10
#: Newton iterations at most per force (a warm-started solve takes 3-8).
MAX_ITERATIONS = 100
#: A solve whose line search can no longer lower the residual is accepted up to this relative
#: residual (1e-6 of a micrometre interference is 1e-12 m, of the force 1e-6); a larger stalled
#: residual is not converged (unless the energy is not convex there: see ``_proximal``).
STALL_TOLERANCE = 1e-6
#: Largest ratio of consecutive forces a surface is solved at: farther requested forces are
#: reached through intermediate ones, geometrically spaced (``_Walker.climb``). A jump's
#: candidates come from the previous stiffness's linear extrapolation, which far overshoots over
#: a large jump: on the paper's pool the 2 steps F' 0.075 and 18.8 cost 1.34 s a surface against
#: 74 ms for its 20 steps (now 46 ms). Above the largest ratio of the paper's steps (2.08, at its
#: lightest) and of the atlas's scenes (2.39), whose solves this leaves as they were, bit for bit.
#: A cold start at a heavy force is left as it was: a first step of many touching caps (the
#: validation's F' 3.32 alone, 44) costs several times its share of the cost model
#: (:mod:`g2tom.models.discrete_cost`), as the README says.
MAX_STEP_RATIO = 2.5
#: Proximal rounds at most where the energy is not convex (a fold of the atlas's large caps takes
#: 170-530).
MAX_PROXIMAL_ROUNDS = 5000


@dataclass(frozen=True)
class Asperities:
    """One surface's asperities: positions and heights, m (all shape (n,))."""

    x: np.ndarray
    y: np.ndarray
    z: np.ndarray

    @property
    def size(self) -> int:
        """Number of asperities."""
        return int(self.z.size)


@dataclass(frozen=True)
class DiscreteContact:
    """The solution of one surface at every force (``n_f`` forces, ``n`` asperities).

    Attributes
    ----------
    force
        The imposed total forces, N, shape (n_f,).
    delta
        Approach (separation of the indenter's tip from the mean plane), m, shape (n_f,).
    interference
        ``max(w_i, 0)`` of every asperity at every force, m, shape (n_f, n).
    load
        Asperity forces ``P_i``, N, shape (n_f, n); they sum to ``force``.
    stiffness
        Contact stiffness ``K = -dF/d delta``, N/m, shape (n_f,).
    iterations
        Newton iterations per force (all candidate rounds), shape (n_f,).
    residual
        Final relative residual (the larger of the interference and the force balance), (n_f,).
    candidates
        Candidates in the final solve of each force, shape (n_f,).
    radii
        Contact radii of the caps by their law (Hertz: ``sqrt(beta w)``), m, shape (n_f, n) (0 off contact);
        capped caps: the radius of the area they own, ``sqrt(A_i / pi)``.
    unloading_stiffness
        The elastic stiffness of the contact set, ``1^T (D_u^-1 + C)^-1 1`` with ``D_u = diag(2 E* a_i)``
        (N/m, shape (n_f,)): the slope of unloading, which Barber's theorem ties to the conductance. It
        is ``stiffness`` for elastic caps; below it once caps yield (their loading slope is lower).
    """

    force: np.ndarray
    delta: np.ndarray
    interference: np.ndarray
    load: np.ndarray
    stiffness: np.ndarray
    iterations: np.ndarray
    residual: np.ndarray
    candidates: np.ndarray
    radii: np.ndarray
    unloading_stiffness: np.ndarray


def sphere_cap_geometry(radius: float, beta: float) -> tuple[float, float]:
    """The exact first contact of a paraboloidal cap (tip radius ``beta``) under a paraboloidal sphere
    (radius ``radius``), m: (the profile radius to evaluate at the cap's tip, the cap's Hertz radius).

    The gap between the cap at distance r from the axis and the sphere,
    ``(t - r)^2 / (2 beta) + t^2 / (2 R)`` along the radial line, is least at ``t = r beta / (R + beta)``
    (off the tip, toward the axis), where it is ``r^2 / (2 (R + beta))``; about that point it is a
    paraboloid of curvature ``1 / beta + 1 / R`` in every direction. So the cap's rigid interference
    is its tip height minus ``r^2 / (2 (R + beta))`` and its contact Hertz's with the radius
    ``beta R / (beta + R)``. Evaluating the sphere at the tip, ``r^2 / (2 R)``, understates the
    interference by ``r^2 beta / (2 R (R + beta))`` (0.47 um at r = 0.63 mm for beta 60 um, R 5 mm).
    """
    return radius + beta, beta * radius / (beta + radius)


def cap_gap(r: np.ndarray, shape: str, beta: float, **dimensions: float) -> np.ndarray:
    """The least gap between a paraboloidal cap (tip radius ``beta``, m) whose tip lies at distance
    ``r`` (m) from the axis and the indenter (``shape`` and its ``dimensions`` as
    :func:`g2tom.physics.indenter.profile` takes them), above the cap's tip height:
    ``min_t (t - r)^2 / (2 beta) + z(|t|)`` along the line through both axes, m. A cap's rigid
    interference is its tip height minus this minus the approach.

    Closed forms, each the indenter's own profile with other dimensions: a sphere of radius
    ``R + beta`` (:func:`sphere_cap_geometry`); a flat punch whose edge radius is ``R_e + beta``; a
    cone of slope ``s = tan(angle)`` lowered by ``s^2 beta / 2`` where the cap touches its flank
    (``r >= s beta``), ``r^2 / (2 beta)`` on the apex.
    """
    r = np.asarray(r, dtype=float)
    if shape == "sphere":
        return indenter.profile(r, shape, radius=sphere_cap_geometry(dimensions["radius"], beta)[0])
    if shape == "flat_punch":
        return indenter.profile(r, shape, punch_radius=dimensions["punch_radius"],
                                edge_radius=dimensions["edge_radius"] + beta)
    z = indenter.profile(r, shape, **dimensions)  # the cone (an unknown shape is refused there)
    s = np.tan(dimensions["cone_angle"])
    return np.where(r >= s * beta, z - 0.5 * s * s * beta, r * r / (2.0 * beta))


def cap_radius(shape: str, beta: float, *, radius: float = 10e-3) -> float:
    """The caps' Hertz radius, m: ``beta R / (beta + R)`` under a sphere (both curvatures add); ``beta``
    under a cone or a flat punch, whose faces are flat (the punch's rounded edge curves only
    radially, a non-axisymmetric contact left at ``beta``: its radial curvature is ``1 / R_e``,
    ``R_e`` the edge radius, against the cap's ``1 / beta``)."""
    return sphere_cap_geometry(radius, beta)[1] if shape == "sphere" else beta


def coupling_floor(beta: float, sigma: float) -> float:
    """The coupling's distance floor ``l = 4 sqrt(beta sigma) / (3 pi)``, m (see the module)."""
    return 4.0 * np.sqrt(beta * sigma) / (3.0 * np.pi)


def interaction_kernel(x: np.ndarray, y: np.ndarray, floor: float) -> np.ndarray:
    """``1 / (pi max(d_ij, floor))`` between points at ``(x, y)`` (m), zero diagonal, in 1/m.

    Divided by E* it is the compliance of point loads; it is also the off-diagonal of the
    point-interaction resistance matrix.
    """
    d = np.hypot(x[:, None] - x[None, :], y[:, None] - y[None, :])
    kernel = 1.0 / (np.pi * np.maximum(d, floor))
    np.fill_diagonal(kernel, 0.0)
    return kernel


def domain_radius(profile: Callable[[np.ndarray], np.ndarray], delta: float, sigma: float, eta: float,
                  outside: float = 1e-6) -> float:
    """Radius of a disc outside which fewer than ``outside`` asperities are expected to be able to touch.

    An asperity at radius ``r`` can touch at approach ``delta`` only if its height exceeds
    ``profile(r) + delta`` (displacements only separate the surfaces), so the expected number
    outside ``R`` is ``eta int_R^inf 2 pi r Q((profile(r) + delta) / sigma) dr`` (``Q`` the normal
    upper tail). Returns the smallest ``R`` on a fine grid where it is below ``outside``.

    Parameters
    ----------
    profile
        Indenter profile z(r) >= 0, m, increasing in r without bound.
    delta
        The lowest approach the disc must serve, m.
    sigma, eta
        Asperity height std (m) and density (1/m^2).
    outside
        Expected number of asperities left out, > 0.
    """
    from scipy.special import ndtr

    if not (outside > 0 and sigma > 0 and eta > 0):
        raise ValueError(f"outside = {outside!r}, sigma = {sigma!r}, eta = {eta!r}: all must be > 0")
    top = 1e-6
    while profile(np.array([top]))[0] + delta < 40.0 * sigma:
        top *= 2.0
        if top > 1e3:
            raise ValueError("the indenter profile does not rise above the asperities: no finite domain")
    r = np.linspace(0.0, top, 20001)
    density = 2.0 * np.pi * r * eta * ndtr(-(profile(r) + delta) / sigma)
    tail = np.concatenate([np.cumsum(((density[1:] + density[:-1]) * np.diff(r) / 2.0)[::-1])[::-1], [0.0]])
    return float(r[np.argmax(tail < outside)])


def draw_asperities(seed: int, realization: int, radius: float, eta: float, sigma: float) -> Asperities:
    """Surface ``realization``'s asperities on a disc of ``radius`` (m), from its own stream.

    Poisson count of mean ``eta pi radius^2``, uniform positions on the disc, heights
    ``N(0, sigma^2)``. Surface ``k`` always gets the same asperities for the same disc.
    """
    stream = np.random.SeedSequence([int(seed), ASPERITIES_TAG], spawn_key=(int(realization),))
    rng = np.random.default_rng(stream)
    n = int(rng.poisson(eta * np.pi * radius**2))
    r = radius * np.sqrt(rng.random(n))
    theta = 2.0 * np.pi * rng.random(n)
    z = sigma * rng.standard_normal(n)
    return Asperities(r * np.cos(theta), r * np.sin(theta), z)


def symmetric_solve(matrix: np.ndarray, rhs: np.ndarray) -> np.ndarray:
    """Solve ``matrix x = rhs`` for a symmetric ``matrix`` (overwritten): Cholesky, or LU where
    the distance floor leaves it indefinite (large caps closer than the floor)."""
    from scipy.linalg import LinAlgError, cho_factor, cho_solve

    try:
        return cho_solve(cho_factor(matrix, check_finite=False), rhs, check_finite=False)
    except LinAlgError:
        return np.linalg.solve(matrix, rhs)


def _positive_definite(matrix: np.ndarray) -> bool:
    """Whether the symmetric ``matrix`` is positive definite (it has a Cholesky factor)."""
    from scipy.linalg import LinAlgError, cho_factor

    try:
        cho_factor(matrix, check_finite=False)
    except LinAlgError:
        return False
    return True


def _rigid_delta(g: np.ndarray, force: float, cap: CapLaw) -> float:
    """The approach at which the uncoupled caps carry ``force``: an upper bound on the coupled one."""
    from scipy.optimize import brentq

    top = float(g.max())
    low = top - cap.interference(force)  # one cap alone: too low

    def excess(d: float) -> float:
        return float(cap.load(g - d).sum() - force)

    if excess(low) <= 0.0:  # only the highest cap touches there: low is the root (to rounding)
        return low
    return float(brentq(excess, low, top, xtol=1e-15, rtol=1e-15))


@dataclass
class _State:
    s: np.ndarray  # interference of every candidate (negative: gap), m
    delta: float


class _GrowingKernel:
    """:func:`interaction_kernel` of the first ``m`` points, extended block by block as ``m`` grows."""

    def __init__(self, x: np.ndarray, y: np.ndarray, floor: float) -> None:
        self.x, self.y, self.floor = x, y, floor
        self.size = 0
        self.table = np.zeros((0, 0))

    def __call__(self, m: int) -> np.ndarray:
        """The (m, m) kernel (a view)."""
        if m > self.table.shape[0]:
            grown = np.zeros((min(self.x.size, max(m, 2 * self.table.shape[0])),) * 2)
            grown[: self.size, : self.size] = self.table[: self.size, : self.size]
            self.table = grown
        if m > self.size:
            old, x, y = self.size, self.x[:m], self.y[:m]
            d = np.hypot(x[old:, None] - x[None, :], y[old:, None] - y[None, :])
            rows = 1.0 / (np.pi * np.maximum(d, self.floor))
            rows[np.arange(m - old), np.arange(old, m)] = 0.0
            self.table[old:m, :m] = rows
            self.table[:old, old:m] = rows[:, :old].T
            self.size = m
        return self.table[:m, :m]


class _SharedCaps:
    """Capped caps whose contact discs share their overlaps (:mod:`g2tom.physics.cap_overlap`).

    Cap ``i`` of the first ``m`` candidates (positions ``x``, ``y``, m) carries its law's load times
    the share of its disc it owns, ``s_i = A_i / (pi a_i^2)``, and conducts through a spot of the
    owned area, radius ``sqrt(s_i) a_i``; a cap whose disc overlaps none is its law's. The load
    depends on the neighbours' interferences through the owned areas: :meth:`jacobian` gives the
    exact derivative, so Newton keeps its quadratic convergence.
    """

    def __init__(self, law: CapLaw, x: np.ndarray, y: np.ndarray) -> None:
        self.law, self.x, self.y = law, x, y
        self._last: tuple[np.ndarray, dict[str, Any]] | None = None

    def _at(self, w: np.ndarray) -> dict[str, Any]:
        """The law's radii (m) and loads (N), the discs' areas (m^2), the owned shares and
        :func:`g2tom.physics.cap_overlap.owned_area_derivatives` at ``w``; those of the last ``w`` are
        kept (Newton asks for the loads, the Jacobian and the spots at one point)."""
        from g2tom.physics.cap_overlap import owned_area_derivatives

        w = np.maximum(w, 0.0)  # the law gives nothing off contact
        if self._last is None or not np.array_equal(self._last[0], w):
            radius = self.law.radius(w)
            disc = np.pi * radius * radius
            m = w.shape[-1]
            owned, own_slope, rows, cols, values = owned_area_derivatives(self.x[:m], self.y[:m], radius)
            share = np.clip(np.where(disc > 0.0, owned / np.where(disc > 0.0, disc, 1.0), 1.0), 0.0, 1.0)
            self._last = w, {"radius": radius, "disc": disc, "share": share, "own_slope": own_slope,
                             "pairs": (rows, cols, values), "law_load": self.law.load(w)}
        return self._last[1]

    def share(self, w: np.ndarray) -> np.ndarray:
        """Each cap's owned share of its disc at the interferences ``w`` (m) of the first caps (1 off contact)."""
        return self._at(w)["share"]

    def load(self, w: np.ndarray) -> np.ndarray:
        """Loads, N, at the interferences ``w`` (m) of the first caps."""
        at = self._at(w)
        return at["share"] * at["law_load"]

    def radius(self, w: np.ndarray) -> np.ndarray:
        """Spot radii of the owned areas, m, at the interferences ``w`` (m) of the first caps."""
        at = self._at(w)
        return np.sqrt(at["share"]) * at["radius"]

    def interference(self, load: float) -> float:
        """One cap's interference at ``load`` (N): the law's (a lone cap owns its disc)."""
        return self.law.interference(load)

    def jacobian(self, w: np.ndarray, active: np.ndarray) -> tuple[np.ndarray, tuple[np.ndarray, ...]]:
        """``dP/dw`` on the ``active`` caps (N/m): its diagonal, and the rest as coordinates
        ``(rows, cols, values)`` into the active caps (``dP_row / dw_col``, pairs of overlapping caps)."""
        at = self._at(w)
        radius, disc, share = at["radius"], at["disc"], at["share"]
        rows, cols, values = at["pairs"]
        scale = np.where(disc > 0.0, at["law_load"] / np.where(disc > 0.0, disc, 1.0), 0.0)  # F / (pi a^2), Pa
        radius_slope = self.law.radius_slope(w)
        diagonal = share * self.law.slope(w) + scale * (at["own_slope"] - 2.0 * np.pi * radius * share) * radius_slope
        index = np.full(w.shape[-1], -1)
        index[active] = np.arange(active.size)
        keep = (index[rows] >= 0) & (index[cols] >= 0)
        rest = (index[rows[keep]], index[cols[keep]], scale[rows[keep]] * values[keep] * radius_slope[cols[keep]])
        return diagonal[active], rest


@numba.njit(cache=True, nogil=True)
def _coupled_jacobian(coupling: np.ndarray, diagonal: np.ndarray, rows: np.ndarray, cols: np.ndarray,
                      values: np.ndarray) -> np.ndarray:
    """``C D`` for ``D = diag(diagonal) + R``, ``R`` given as coordinates (``R[rows, cols] = values``),
    ``C`` symmetric (m/N): built as its transpose ``D^T C`` row by row, which reads and writes
    contiguous memory (each pair adds ``v C[row]`` to row ``col``), and returned transposed (a view)."""
    n = diagonal.size
    transposed = np.empty((n, n))
    for i in range(n):
        for j in range(n):
            transposed[i, j] = diagonal[i] * coupling[i, j]
    for k in range(rows.size):
        r, c, v = rows[k], cols[k], values[k]
        for j in range(n):
            transposed[c, j] += v * coupling[r, j]
    return transposed.T


def _hessian(kernel: np.ndarray, s: np.ndarray, active: np.ndarray, e_star: float, cap: CapLaw) -> tuple[
        np.ndarray, np.ndarray]:
    """The energy's Hessian ``D^-1 + C`` on the ``active`` caps (m/N) and their ``dP/ds`` (N/m)."""
    slope = cap.slope(s[active])
    system = kernel[np.ix_(active, active)] / e_star
    system[np.diag_indices_from(system)] += 1.0 / slope
    return system, slope


def _newton(g: np.ndarray, kernel: np.ndarray, force: float, e_star: float, cap: CapLaw, state: _State,
            tolerance: float, max_iterations: int) -> tuple[_State, float, int, float, bool]:
    """Solve ``s - g + delta + C P(s) = 0``, ``sum P(s) = F`` on a fixed candidate set (``C = kernel / E*``).

    The Newton system of the contacting rows ``(I + C D) ds + d delta = -r`` is solved through
    the symmetric ``D^-1 + C`` (:func:`symmetric_solve`), ``D = diag(dP/ds)``. Returns the
    state, the stiffness ``K = 1^T (D^-1 + C)^-1 1`` (N/m), the iterations, the final relative
    residual, and whether it stalled (no step of the line search lowered the residual).
    """
    s, delta = state.s.copy(), state.delta
    shared = isinstance(cap, _SharedCaps)

    def residuals(s: np.ndarray, delta: float) -> tuple[np.ndarray, float, np.ndarray]:
        load = cap.load(s)
        active = np.flatnonzero(s > 0 if shared else load > 0)  # shared: a cap that owns nothing is held too
        return s - g + delta + kernel[:, active] @ load[active] / e_star, load.sum() - force, active

    res, res_f, active = residuals(s, delta)
    for iteration in range(max_iterations + 1):
        if active.size == 0:  # no cap touches: put the highest one at its lone interference
            delta = delta + s.max() - cap.interference(force)
            s = g - delta
            res, res_f, active = residuals(s, delta)
            continue
        scale = float(s[active].max())
        error = max(float(np.abs(res).max()) / scale, abs(res_f) / force)
        if shared:  # D = dP/ds is not diagonal (and has zero rows, caps that own nothing): (I + C D) as it is
            diagonal, (rows, cols, values) = cap.jacobian(s, active)
            coupling = kernel[np.ix_(active, active)] / e_star
            system = _coupled_jacobian(coupling, diagonal, rows, cols, values)
            system[np.diag_indices_from(system)] += 1.0
            solved = np.linalg.solve(system, np.column_stack([np.ones(active.size), res[active]]))
            unit, along = solved[:, 0], solved[:, 1]
            column = diagonal + np.bincount(cols, values, active.size)  # 1^T D
            stiffness = float(column @ unit)
            if error <= tolerance or iteration == max_iterations:
                return _State(s, delta), stiffness, iteration, error, False
            step_delta = (res_f - column @ along) / stiffness
            step_active = -(along + step_delta * unit)
            load_step = diagonal * step_active + np.bincount(rows, values * step_active[cols], active.size)
        else:
            system, slope = _hessian(kernel, s, active, e_star, cap)
            solved = symmetric_solve(system, np.column_stack([np.ones(active.size), res[active]]))
            unit, along = solved[:, 0], solved[:, 1]
            stiffness = float(unit.sum())
            if error <= tolerance or iteration == max_iterations:
                return _State(s, delta), stiffness, iteration, error, False
            # (I + C D)^-1 = D^-1 (D^-1 + C)^-1 on the contacting rows
            step_delta = (res_f - along.sum()) / stiffness
            step_active = -(along + step_delta * unit) / slope
            load_step = slope * step_active
        step = -res - step_delta - kernel[:, active] @ load_step / e_star
        step[active] = step_active
        merit = (np.linalg.norm(res) / scale) ** 2 + (res_f / force) ** 2
        t = 1.0
        for _ in range(40):
            trial = residuals(s + t * step, delta + t * step_delta)
            if (np.linalg.norm(trial[0]) / scale) ** 2 + (trial[1] / force) ** 2 < merit:
                break
            t *= 0.5
        else:  # no step lowers the residual: stalled
            return _State(s, delta), stiffness, iteration, error, True
        s, delta = s + t * step, delta + t * step_delta
        res, res_f, active = trial
    raise AssertionError("unreachable")  # pragma: no cover


def _convex_at(kernel: np.ndarray, state: _State, e_star: float, cap: CapLaw) -> bool:
    """Whether the energy's Hessian ``D^-1 + C`` is positive definite at ``state``."""
    active = np.flatnonzero(state.s > 0)
    return _positive_definite(_hessian(kernel, state.s, active, e_star, cap)[0])


def _unloading_stiffness(kernel: np.ndarray, s: np.ndarray, e_star: float, cap: CapLaw) -> float:
    """``1^T (D_u^-1 + C)^-1 1`` on the contacting caps, ``D_u = diag(2 E* a_i)`` (N/m): the elastic
    stiffness of the contact set (:class:`DiscreteContact`)."""
    radius = cap.radius(s)
    active = np.flatnonzero(radius > 0)
    system = kernel[np.ix_(active, active)] / e_star
    system[np.diag_indices_from(system)] += 1.0 / (2.0 * e_star * radius[active])
    return float(symmetric_solve(system, np.ones(active.size)).sum())


def _proximal(g: np.ndarray, kernel: np.ndarray, force: float, e_star: float, cap: CapLaw, state: _State,
              tolerance: float, max_iterations: int) -> tuple[_State, float, int, float, bool]:
    """Minimise the energy where it is not convex by proximal rounds, from ``state``.

    Round ``k`` minimises the energy plus ``c |P - P_k|^2 / 2`` (``P_k`` the previous round's
    forces), with ``c E*`` 1.01 x the most negative eigenvalue of ``kernel`` so that every round's
    energy is convex: its equations are :func:`_newton`'s with ``c E*`` added to the kernel's
    diagonal and ``g`` raised by ``c P_k``. Each round lowers the energy; at their fixed point
    ``P_k`` solves the original equations, which is when the rounds stop (the original residual
    within ``tolerance``). Returns what :func:`_newton` returns, with the stiffness of the
    original equations, the iterations of all rounds, and ``stalled`` True where a round did not
    converge or the rounds ran out (:data:`MAX_PROXIMAL_ROUNDS`).
    """
    from scipy.linalg import eigvalsh

    lowest = float(eigvalsh(kernel, subset_by_index=[0, 0], check_finite=False)[0])
    shift = 1.01 * max(-lowest, 0.0)  # 1/m, like the kernel
    shifted = kernel.copy()
    shifted[np.diag_indices_from(shifted)] += shift
    iterations = 0
    for _ in range(MAX_PROXIMAL_ROUNDS):
        raised = g + shift / e_star * cap.load(state.s)
        state, _, its, error, stalled = _newton(raised, shifted, force, e_star, cap, state, tolerance,
                                                max_iterations)
        iterations += its
        if stalled or error > tolerance:
            break
        _, stiffness, _, error, _ = _newton(g, kernel, force, e_star, cap, state, tolerance, 0)
        if error <= tolerance:
            return state, stiffness, iterations, error, False
    return state, 0.0, iterations, error, True


class NotConverged(ArithmeticError):
    """Newton did not meet its tolerance within its iterations."""


class _Walker:
    """One surface's solution carried from force to force (warm starts, candidate rounds, continuation)."""

    def __init__(self, g: np.ndarray, kernel: _GrowingKernel, e_star: float, cap: CapLaw, tolerance: float,
                 max_iterations: int, all_candidates: bool = False) -> None:
        self.g, self.kernel, self.e_star, self.cap = g, kernel, e_star, cap
        self.all_candidates = all_candidates
        self.tolerance, self.max_iterations = tolerance, max_iterations
        self.force = 0.0  # 0: cold, no solution yet
        self.delta, self.threshold, self.stiffness, self.error = np.inf, np.inf, 0.0, np.inf
        self.s, self.loads = np.zeros(0), np.zeros(0)

    def _advance(self, force: float) -> int:
        """Solve at ``force`` from the current solution (or cold), growing the candidates until
        every asperity able to touch is one; the state changes only on success."""
        g, e_star = self.g, self.e_star
        if self.force == 0.0:
            delta = threshold = _rigid_delta(g, force, self.cap)
        else:  # the previous stiffness overstates the step: a lower delta, more candidates
            delta = self.delta
            threshold = min(self.threshold, delta - (force - self.force) / self.stiffness)
        iterations = 0
        while True:
            m = g.size if self.all_candidates else max(int(np.searchsorted(-g, -threshold, side="left")), 1)
            coupling = self.kernel(m)
            carried = np.zeros(m)
            carried[: self.loads.size] = self.loads[:m]
            start = _State(g[:m] - delta - coupling @ carried / e_star, delta)
            state, stiffness, its, error, stalled = _newton(g[:m], coupling, force, e_star, self.cap, start,
                                                            self.tolerance, self.max_iterations)
            iterations += its
            if stalled and error > STALL_TOLERANCE and (isinstance(self.cap, _SharedCaps)
                                                         or not _convex_at(coupling, state, e_star, self.cap)):
                state, stiffness, its, error, stalled = _proximal(g[:m], coupling, force, e_star, self.cap,
                                                                  state, self.tolerance, self.max_iterations)
                iterations += its
            if not (error <= self.tolerance or stalled and error <= STALL_TOLERANCE):
                raise NotConverged(f"force {force:g} N: relative residual {error:.3g}"
                                   + (" (stalled)" if stalled else ""))
            delta = state.delta
            if m == g.size or g[m] <= delta:  # every asperity that can touch was a candidate
                break
            threshold = delta - 0.5 * (threshold - delta)
        self.force, self.delta, self.threshold, self.stiffness, self.error = force, delta, threshold, stiffness, error
        self.s, self.loads = state.s, self.cap.load(state.s)
        return iterations

    def climb(self, force: float) -> int:
        """Solve at ``force`` as :meth:`reach` does, first through intermediate forces, geometrically
        spaced, where it lies more than :data:`MAX_STEP_RATIO` above the current one (a cold start
        goes straight to :meth:`reach`); returns the Newton iterations of all of them."""
        if self.force == 0.0 or force <= self.force * MAX_STEP_RATIO:
            return self.reach(force)
        steps = int(np.ceil(np.log(force / self.force) / np.log(MAX_STEP_RATIO)))
        return sum(self.reach(float(step)) for step in np.geomspace(self.force, force, steps + 1)[1:])

    def reach(self, force: float, depth: int = 0) -> int:
        """Solve at ``force``; where Newton fails from the current start, walk up from a lighter
        load in steps of at most sqrt(2) (from a quarter of the force when cold), and at least two
        of them, each refined the same way where it fails.

        Raises
        ------
        NotConverged
            Where even that fails (30 levels of refinement).
        """
        try:
            return self._advance(force)
        except NotConverged:
            if depth >= 30:
                raise
        iterations = 0
        if self.force == 0.0:
            iterations += self.reach(force / 4.0, depth + 1)
        # at least two steps, so that every level of refinement halves the step (in ln F) that failed
        steps = max(2, int(np.ceil(2.0 * np.log2(force / self.force))))
        for step in np.geomspace(self.force, force, steps + 1)[1:]:
            iterations += self.reach(float(step), depth + 1)
        return iterations


def solve_forces(
    asperities: Asperities,
    profile: Callable[[np.ndarray], np.ndarray],
    forces: np.ndarray,
    e_star: float,
    beta: float,
    floor: float,
    *,
    tolerance: float = TOLERANCE,
    max_iterations: int = MAX_ITERATIONS,
    all_candidates: bool = False,
    cap: CapLaw | None = None,
) -> DiscreteContact:
    """The coupled caps of one surface at each total force (see the module for the model).

    Parameters
    ----------
    asperities
        The surface's asperities (positions relative to the indenter's axis), m.
    profile
        Indenter profile z(r), m.
    forces
        Total forces, N, > 0 and strictly increasing (each solve warm-starts from the previous).
    e_star
        Effective modulus E*, Pa.
    beta
        Cap radius, m: the Hertz law's where ``cap`` is not given.
    floor
        Coupling distance floor, m (:func:`coupling_floor`).
    tolerance, max_iterations
        Newton's relative tolerance and iteration cap per candidate round.
    all_candidates
        Solve on every asperity of the surface (the slow reference of the candidate selection).
    cap
        The caps' force and radius against their interference (:mod:`g2tom.physics.cap_law`);
        Hertz's of radius ``beta`` by default. Where the law shares overlaps (capped caps), each cap
        carries its law's force times the share of its disc it owns and conducts through a spot of
        that area (:mod:`g2tom.physics.cap_overlap`).

    Raises
    ------
    ValueError
        On forces that are not positive and increasing, or a surface with no asperity.
    NotConverged
        Where Newton fails even along a refined load path.
    """
    forces = np.asarray(forces, dtype=float)
    if forces.ndim != 1 or not np.all(forces > 0) or np.any(np.diff(forces) <= 0):
        raise ValueError("forces must be > 0 and strictly increasing (N)")
    if asperities.size == 0:
        raise ValueError("the surface has no asperity")
    g = asperities.z - profile(np.hypot(asperities.x, asperities.y))
    order = np.argsort(-g, kind="stable")  # candidates are a prefix of the descending gaps
    cap = HertzCap(e_star, beta) if cap is None else cap
    caps = _SharedCaps(cap, asperities.x[order], asperities.y[order]) if cap.shares_overlap else cap
    walker = _Walker(g[order], _GrowingKernel(asperities.x[order], asperities.y[order], floor), e_star, caps,
                     tolerance, max_iterations, all_candidates)
    n, n_f = g.size, forces.size
    elastic = isinstance(cap, HertzCap)  # whose loading slope is its unloading slope: D = diag(2 E* a)
    names = ("delta", "stiffness", "unloading_stiffness", "iterations", "residual", "candidates")
    out = {name: np.zeros(n_f) for name in names}
    interference, load, radii = np.zeros((n_f, n)), np.zeros((n_f, n)), np.zeros((n_f, n))
    for index, force in enumerate(forces):
        iterations = walker.climb(force)
        m = walker.loads.size
        radii[index, order[:m]] = caps.radius(np.maximum(walker.s, 0.0))
        interference[index, order[:m]] = np.maximum(walker.s, 0.0)
        load[index, order[:m]] = walker.loads
        out["delta"][index], out["stiffness"][index] = walker.delta, walker.stiffness
        out["unloading_stiffness"][index] = (walker.stiffness if elastic else
                                             _unloading_stiffness(walker.kernel(m), walker.s, e_star, caps))
        out["iterations"][index], out["residual"][index], out["candidates"][index] = iterations, walker.error, m
    return DiscreteContact(
        force=forces, delta=out["delta"], interference=interference, load=load, stiffness=out["stiffness"],
        iterations=out["iterations"].astype(np.int32), residual=out["residual"],
        candidates=out["candidates"].astype(np.int32), radii=radii,
        unloading_stiffness=out["unloading_stiffness"],
    )
