"""Axisymmetric Greenwood–Tripp contact of a rough surface (Eqs. 16-19).

The separation of the mean planes is h(r) = delta + z(r) + u(r): the approach delta (initial
separation of the tip, negative = interpenetration), the indenter profile z and the elastic
displacement u of both bodies. The asperity pressure is p(h) = (4/3) eta E* sqrt(beta) F_{3/2}(h)
and the displacement

    u(r) = 4 / (pi E*) integral_0^inf rho / (rho + r) p(rho) K(m) d rho,  m = 4 rho r / (rho + r)^2,

with K the complete elliptic integral of the first kind of *parameter* m (Eq. 19 writes the
modulus k where k^2 is meant). The pressure is piecewise linear on the radial nodes, so
u = M p with an influence matrix M. K has a logarithmic singularity at rho = r; writing

    K(m) = g(m) + ln(rho + r) - ln|rho - r|,     g(m) = K(m) + ln(1 - m) / 2,

g is bounded and smooth enough for Gauss-Legendre, and the ln|rho - r| term is integrated
with a product rule that is exact for polynomial integrands times the logarithm.

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
from scipy.special import eval_sh_legendre, ellipkm1

from pipeline.physics.asperity import asperity_integral_slope, log_asperity_integral

__all__ = [
    "radial_nodes",
    "graded_nodes",
    "influence_matrix",
    "force_weights",
    "Layer",
    "Solution",
    "solve",
    "solve_newton",
    "solve_fixed_point",
    "stiffness",
]

#: Gauss-Legendre points per element.
_N_GAUSS = 8
#: Previous solutions extrapolated (cubic in delta) to start Newton at the next approach.
_PREDICTOR_ORDER = 4
#: Target rows assembled at once (bounds the memory of the influence matrix build).
_BLOCK = 256


def radial_nodes(n: int, r_max: float) -> np.ndarray:
    """Uniform radial nodes 0, ..., r_max.

    Parameters
    ----------
    n
        Number of nodes (>= 2).
    r_max
        Outer radius, m (> 0); the pressure is taken as zero beyond it.

    Returns
    -------
    numpy.ndarray
        Shape (n,), m.
    """
    if n < 2:
        raise ValueError(f"n_radial = {n!r} is out of range: must be >= 2")
    if not (np.isfinite(r_max) and r_max > 0):
        raise ValueError(f"r_max = {r_max!r} is out of range: must be > 0 (m)")
    return np.linspace(0.0, r_max, n)


def graded_nodes(n: int, r_max: float, r_fine: float, coarsening: float = 4.0) -> np.ndarray:
    """Radial nodes, uniform on [0, r_fine] and ``coarsening`` times coarser on [r_fine, r_max].

    Parameters
    ----------
    n
        Number of nodes (>= 2).
    r_max
        Outer radius, m.
    r_fine
        Radius out to which the fine spacing is kept, m; beyond it the asperities are out of
        reach (the pressure there is negligible) and only the displacement field is needed.
    coarsening
        Ratio of the coarse to the fine spacing (>= 1).

    Returns
    -------
    numpy.ndarray
        Shape (n,), m, strictly increasing from 0 to r_max; uniform if r_fine >= r_max.
    """
    nodes = radial_nodes(n, r_max)
    if not (np.isfinite(r_fine) and r_fine > 0):
        raise ValueError(f"r_fine = {r_fine!r} is out of range: must be > 0 (m)")
    if coarsening < 1:
        raise ValueError(f"coarsening = {coarsening!r} is out of range: must be >= 1")
    if r_fine >= r_max:
        return nodes
    fine_step = (r_fine + (r_max - r_fine) / coarsening) / (n - 1)
    n_fine = min(max(int(round(r_fine / fine_step)), 1), n - 2)
    fine = np.linspace(0.0, r_fine, n_fine + 1)
    coarse = np.linspace(r_fine, r_max, n - n_fine)
    return np.concatenate([fine, coarse[1:]])


def _log_product_weights(t: np.ndarray) -> np.ndarray:
    """Weights v with sum_q v_q f(t_q) = integral_0^1 f(t) ln t dt for polynomials of degree < len(t)."""
    k = np.arange(len(t))
    moments = np.where(k == 0, -1.0, (-1.0) ** (k + 1) / np.maximum(k * (k + 1), 1))
    basis = eval_sh_legendre(k[None, :], t[:, None])  # (point, degree)
    return np.linalg.solve(basis.T, moments)


def _block(r_target: np.ndarray, r: np.ndarray, t: np.ndarray, w: np.ndarray, v: np.ndarray,
           first: int) -> np.ndarray:
    """Rows ``first:first+len(r_target)`` of the influence matrix, without the 4/(pi E*) factor."""
    left, length = r[:-1], np.diff(r)
    rho = left[:, None] + length[:, None] * t[None, :]  # (element, point)
    rt = r_target[:, None, None]
    ratio = rho / (rho + rt)
    diff = np.abs(rho - rt)
    m1 = (diff / (rho + rt)) ** 2  # 1 - m, formed without cancellation
    g = ellipkm1(m1) + 0.5 * np.log(m1)
    off_axis = rt > 0
    smooth = g + np.where(off_axis, np.log(rho + rt), 0.0)
    log_w = w * np.log(np.where(off_axis, diff, 1.0))  # w_q ln|rho - r| (Gauss, regular elements)
    rows = np.arange(len(r_target))
    node = first + rows
    n_elem = len(length)
    right = node < n_elem  # the element starting at the target node
    log_w[rows[right], node[right], :] = w * np.log(length[node[right]])[:, None] + v
    left_ok = (node >= 1) & (node <= n_elem)  # the element ending at the target node
    log_w[rows[left_ok], node[left_ok] - 1, :] = w * np.log(length[node[left_ok] - 1])[:, None] + v[::-1]
    log_w = np.where(off_axis, log_w, 0.0)
    kern = length[None, :, None] * ratio * (w * smooth - log_w)  # (target, element, point)
    out = np.zeros((len(r_target), len(r)))
    out[:, :-1] += kern @ (1.0 - t)
    out[:, 1:] += kern @ t
    return out


def influence_matrix(r: ArrayLike, e_star: float) -> np.ndarray:
    """Displacements at the nodes per unit nodal pressure of a piecewise-linear pressure.

    Parameters
    ----------
    r
        Increasing radial nodes, m, starting at 0; the pressure vanishes beyond the last.
    e_star
        Effective modulus E* (1/E* = sum (1 - nu_i^2) / E_i), Pa.

    Returns
    -------
    numpy.ndarray
        M of shape (n, n), m/Pa: u(r_i) = sum_j M_ij p(r_j).
    """
    r = np.asarray(r, dtype=float)
    if r.ndim != 1 or len(r) < 2 or r[0] != 0 or np.any(np.diff(r) <= 0):
        raise ValueError("r must be a 1-D, strictly increasing array of >= 2 nodes starting at 0 (m)")
    if not (np.isfinite(e_star) and e_star > 0):
        raise ValueError(f"e_star = {e_star!r} is out of range: must be > 0 (Pa)")
    x, w = np.polynomial.legendre.leggauss(_N_GAUSS)
    t, w = 0.5 * (x + 1.0), 0.5 * w
    v = _log_product_weights(t)
    rows = [_block(r[i:i + _BLOCK], r, t, w, v, i) for i in range(0, len(r), _BLOCK)]
    return 4.0 / (np.pi * e_star) * np.vstack(rows)


def force_weights(r: ArrayLike) -> np.ndarray:
    """Weights c with F = c . p = 2 pi integral p r dr exactly for piecewise-linear p, in m^2."""
    r = np.asarray(r, dtype=float)
    a, b = r[:-1], r[1:]
    length = b - a
    c = np.zeros_like(r)
    c[:-1] += length * (2 * a + b) / 6.0
    c[1:] += length * (a + 2 * b) / 6.0
    return 2.0 * np.pi * c


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
        Influence matrix from :func:`influence_matrix`, m/Pa.
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
    :attr:`Layer.pressure_scale` and c the :func:`force_weights`, so K = P c . (s y) > 0: the
    force falls as the tip's separation delta grows. Exact for the discretised system at its
    solution; the error from the solve's residual is of the order of that residual.

    Parameters
    ----------
    matrix
        Influence matrix from :func:`influence_matrix`, m/Pa.
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
