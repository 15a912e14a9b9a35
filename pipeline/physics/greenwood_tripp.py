"""Axisymmetric Greenwood–Tripp contact of a rough surface (Eqs. 16-19).

The separation of the mean planes is h(r) = delta + z(r) + u(r): the approach delta (initial
separation of the tip, negative = interpenetration), the indenter profile z and the elastic
displacement u of both bodies. The asperity pressure is p(h) = (4/3) eta E* sqrt(beta) F_{3/2}(h)
and the displacement u = M p, with the influence matrix M of the radial discretisation
(:mod:`g2tom.physics.radial_grid`: the pressure piecewise linear on the radial nodes, Eq. 19).

The contact stiffness K = -dF/d delta follows from the converged solution by linearising the
discretised system itself (:func:`stiffness`), so it is exact for the discretisation, with no
finite difference in delta.

Two solvers find u = M p(h(u)): Newton (Jacobian I - M diag(dp/dh), kept as a chord while it
converges fast, backtracking line search, to a relative residual of 1e-10 or as set, started
from an extrapolation of the previous approaches' solutions) and the paper's relaxed fixed point
(u' = zeta u_{k+1} + (1 - zeta) u_k until ||u_{k+1} - u_k|| / ||u_k|| <= epsilon).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike
from scipy.linalg import lu_factor, lu_solve

from g2tom.physics.asperity import asperity_integral_slope, log_asperity_integral
from g2tom.physics.radial_grid import force_weights

__all__ = [
    "Layer",
    "Solution",
    "solve",
    "solve_newton",
    "solve_fixed_point",
    "stiffness",
]

#: Previous solutions extrapolated (cubic in delta) to start Newton at the next approach.
_PREDICTOR_ORDER = 4


@dataclass(frozen=True)
class Layer:
    """The asperity layer and elastic bodies: sigma (m), eta (m^-2), beta (m), E* (Pa)."""

    sigma: float
    eta: float
    beta: float
    e_star: float

    @property
    def pressure_scale(self) -> float:
        """(4/3) eta E* sqrt(beta) sigma^(3/2), Pa: p = pressure_scale * f_{3/2}(h / sigma)."""
        return 4.0 / 3.0 * self.eta * self.e_star * np.sqrt(self.beta) * self.sigma**1.5


@dataclass(frozen=True)
class Solution:
    """Converged displacement of one approach, u in m; iterations and final relative residual."""

    displacement: np.ndarray
    iterations: int
    residual: float
    converged: bool


def _pressure(x: np.ndarray) -> np.ndarray:
    return np.exp(log_asperity_integral(x, 1.5))


def _relative_residual(v: np.ndarray, image: np.ndarray) -> float:
    scale = np.max(np.abs(image))
    return float(np.max(np.abs(v - image)) / scale) if scale > 0 else 0.0


def solve_newton(a: np.ndarray, x0: np.ndarray, v: np.ndarray, tolerance: float,
                 max_iterations: int) -> tuple[np.ndarray, int, float]:
    """Newton's method on G(v) = v - A f_{3/2}(x0 + v) = 0 (all in units of sigma).

    The Jacobian I + A diag(1.5 f_{1/2}) is factorized at the first step and kept while each
    step reduces the residual at least tenfold (a chord step then costs one back-substitution),
    refactorized otherwise; a backtracking line search on max|G| makes every step a descent.

    Parameters
    ----------
    a
        Dimensionless influence matrix M * pressure_scale / sigma, (n, n).
    x0
        Rigid separation (delta + z) / sigma at the nodes.
    v
        Initial displacement / sigma.
    tolerance
        Relative residual max|G| / max|A f| to reach.
    max_iterations
        Steps allowed.

    Returns
    -------
    tuple
        (v, steps taken, final relative residual).
    """
    eye = np.eye(len(v))
    image = a @ _pressure(x0 + v)
    res = _relative_residual(v, image)
    it, factors, refresh = 0, None, True
    while res > tolerance and it < max_iterations:
        if refresh:
            slope = asperity_integral_slope(x0 + v, 1.5)
            factors = lu_factor(eye + a * slope[None, :])
        step = lu_solve(factors, image - v)
        norm0 = np.max(np.abs(image - v))
        lam = 1.0
        while True:
            trial = v + lam * step
            trial_image = a @ _pressure(x0 + trial)
            norm = np.max(np.abs(trial_image - trial))
            if norm < (1.0 - 1e-4 * lam) * norm0 or lam < 1e-6:
                break
            lam *= 0.5
        refresh = norm > 0.1 * norm0
        v, image = trial, trial_image
        res = _relative_residual(v, image)
        it += 1
    return v, it, res


def solve_fixed_point(a: np.ndarray, x0: np.ndarray, relaxation: float, tolerance: float,
                      max_iterations: int) -> tuple[np.ndarray, int, float, bool]:
    """The paper's relaxed fixed point, started from u = 0.

    Iterates v_{k+1} = zeta A f_{3/2}(x0 + v_k) + (1 - zeta) v_k until
    ||v_{k+1} - v_k||_inf <= zeta epsilon ||v_k||_inf (Sect. 2.5.1).

    Returns
    -------
    tuple
        (v, iterations, final relative residual max|v - A f| / max|A f|, converged).
    """
    v = np.zeros_like(x0)
    it = 0
    while it < max_iterations:
        new = relaxation * (a @ _pressure(x0 + v)) + (1.0 - relaxation) * v
        change = np.max(np.abs(new - v))
        size = np.max(np.abs(v))
        v = new
        it += 1
        if change <= relaxation * tolerance * size:  # from u = 0 only when p(x0) = 0 everywhere
            return v, it, _relative_residual(v, a @ _pressure(x0 + v)), True
    return v, it, _relative_residual(v, a @ _pressure(x0 + v)), False


def _predict(history: list[tuple[float, np.ndarray]], delta: float, n: int) -> np.ndarray:
    """Newton's starting displacement: Lagrange extrapolation in delta of the last solutions."""
    if not history:
        return np.zeros(n)
    if len({d for d, _ in history} | {delta}) <= len(history):
        return history[-1][1]
    guess = np.zeros(n)
    for i, (d_i, v_i) in enumerate(history):
        weight = 1.0
        for j, (d_j, _) in enumerate(history):
            if j != i:
                weight *= (delta - d_j) / (d_i - d_j)
        guess += weight * v_i
    return guess


def solve(matrix: np.ndarray, rigid_gap: np.ndarray, deltas: ArrayLike, layer: Layer, *,
          solver: str = "newton", tolerance: float = 1e-10, max_iterations: int = 200,
          relaxation: float = 0.3, fixed_point_tolerance: float = 1e-3) -> list[Solution]:
    """Solve the Greenwood–Tripp problem for every approach.

    Parameters
    ----------
    matrix
        Influence matrix from :func:`g2tom.physics.radial_grid.influence_matrix`, m/Pa.
    rigid_gap
        Indenter profile z(r) at the nodes, m.
    deltas
        Approaches delta, m, lightest first (Newton starts from a cubic extrapolation of the
        previous solutions; the fixed point starts from u = 0 as in the paper).
    layer
        Asperity layer and modulus.
    solver
        ``"newton"`` or ``"fixed_point"``.
    tolerance, max_iterations
        Newton: relative residual to reach; iteration limit of either solver.
    relaxation, fixed_point_tolerance
        Fixed point: zeta and epsilon.

    Returns
    -------
    list of Solution
        One per approach, displacement in m.
    """
    if solver not in ("newton", "fixed_point"):
        raise ValueError(f"solver = {solver!r} is not allowed: must be one of 'newton', 'fixed_point'")
    a = matrix * (layer.pressure_scale / layer.sigma)
    history: list[tuple[float, np.ndarray]] = []
    out = []
    for delta in np.asarray(deltas, dtype=float):
        x0 = (delta + np.asarray(rigid_gap)) / layer.sigma
        if solver == "newton":
            v, it, res = solve_newton(a, x0, _predict(history, delta, len(x0)), tolerance, max_iterations)
            history = [*history, (delta, v)][-_PREDICTOR_ORDER:]
            ok = res <= tolerance
        else:
            v, it, res, ok = solve_fixed_point(a, x0, relaxation, fixed_point_tolerance, max_iterations)
        out.append(Solution(v * layer.sigma, it, res, ok))
    return out


def stiffness(matrix: np.ndarray, rigid_gap: np.ndarray, deltas: ArrayLike, layer: Layer,
              solutions: list[Solution], r: ArrayLike) -> np.ndarray:
    """Contact stiffness K = -dF/d delta of the discretised system at each converged approach.

    With x = (delta + z + u) / sigma and the discrete equation u / sigma = A f_{3/2}(x), A the
    dimensionless influence matrix of :func:`solve`, differentiating in delta gives

        (I + A diag(s)) y = 1 / sigma,   y = dx/d delta (1/m),   s = -f'_{3/2}(x) = 1.5 f_{1/2}(x),

    (the Newton Jacobian of :func:`solve_newton`), and F = P c . f_{3/2}(x), P the layer's
    :attr:`Layer.pressure_scale` and c the :func:`~g2tom.physics.radial_grid.force_weights`, so K = P c . (s y) > 0: the
    force falls as the tip's separation delta grows. Exact for the discretised system at its
    solution; the error from the solve's residual is of the order of that residual.

    Parameters
    ----------
    matrix
        Influence matrix from :func:`g2tom.physics.radial_grid.influence_matrix`, m/Pa.
    rigid_gap
        Indenter profile z(r) at the nodes, m.
    deltas
        Approaches delta, m, one per solution.
    layer
        Asperity layer and modulus.
    solutions
        Converged solutions from :func:`solve`, one per approach.
    r
        The radial nodes of ``matrix``, m.

    Returns
    -------
    numpy.ndarray
        K per approach, N/m.
    """
    deltas = np.asarray(deltas, dtype=float)
    if len(solutions) != len(deltas):
        raise ValueError(f"{len(solutions)} solutions for {len(deltas)} approaches: one each is needed")
    a = matrix * (layer.pressure_scale / layer.sigma)
    eye = np.eye(len(a))
    weights = force_weights(r)
    out = np.empty(len(deltas))
    for k, (delta, sol) in enumerate(zip(deltas, solutions)):
        slope = asperity_integral_slope((delta + np.asarray(rigid_gap) + sol.displacement) / layer.sigma, 1.5)
        y = np.linalg.solve(eye + a * slope[None, :], np.full(len(a), 1.0 / layer.sigma))
        out[k] = layer.pressure_scale * (weights @ (slope * y))
    return out
