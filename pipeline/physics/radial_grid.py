"""The radial discretisation of the Greenwood–Tripp contact: nodes, influence matrix, force weights.

The pressure is piecewise linear on the radial nodes (:func:`radial_nodes`, :func:`graded_nodes`),
so the elastic displacement of both bodies (Eq. 19)

    u(r) = 4 / (pi E*) integral_0^inf rho / (rho + r) p(rho) K(m) d rho,  m = 4 rho r / (rho + r)^2,

is u = M p with an influence matrix M (:func:`influence_matrix`). K, the complete elliptic integral
of the first kind of *parameter* m (Eq. 19 writes the modulus k where k^2 is meant), has a
logarithmic singularity at rho = r; writing

    K(m) = g(m) + ln(rho + r) - ln|rho - r|,     g(m) = K(m) + ln(1 - m) / 2,

g is bounded and smooth enough for Gauss-Legendre, and the ln|rho - r| term is integrated
with a product rule that is exact for polynomial integrands times the logarithm. The force is
``2 pi integral p r dr``, a weighted sum of the nodal pressures (:func:`force_weights`).
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np
from numpy.typing import ArrayLike
from scipy.special import eval_sh_legendre, ellipkm1

__all__ = ["radial_nodes", "graded_nodes", "influence_matrix", "forget_kept_matrices", "force_weights"]

#: Gauss-Legendre points per element.
_N_GAUSS = 8
#: Target rows assembled at once (bounds the memory of the influence matrix build).
_BLOCK = 256
#: Largest grid whose matrix is kept for the next solve on the same nodes (8 MiB), and how many
#: such matrices are kept (64 MiB at most): a study and its tests solve the same grids again.
_KEPT_NODES = 1024
_KEPT_MATRICES = 8


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
    total = rho + rt
    ratio = rho / total
    diff = np.abs(rho - rt)
    m1 = (diff / total) ** 2  # 1 - m, formed without cancellation
    # The (target, element, point) arrays are updated in place: one allocation less each.
    smooth = ellipkm1(m1)
    smooth += 0.5 * np.log(m1)  # g
    off_axis = rt > 0
    smooth += np.where(off_axis, np.log(total, out=total), 0.0)
    log_w = np.log(np.where(off_axis, diff, 1.0))
    log_w *= w  # w_q ln|rho - r| (Gauss, regular elements)
    rows = np.arange(len(r_target))
    node = first + rows
    n_elem = len(length)
    right = node < n_elem  # the element starting at the target node
    log_w[rows[right], node[right], :] = w * np.log(length[node[right]])[:, None] + v
    left_ok = (node >= 1) & (node <= n_elem)  # the element ending at the target node
    log_w[rows[left_ok], node[left_ok] - 1, :] = w * np.log(length[node[left_ok] - 1])[:, None] + v[::-1]
    log_w[~off_axis[:, 0, 0]] = 0.0
    smooth *= w
    smooth -= log_w
    kern = ratio
    kern *= length[None, :, None]
    kern *= smooth  # length ratio (w smooth - log_w), (target, element, point)
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
    unscaled = _kept_matrix(r.tobytes()) if len(r) <= _KEPT_NODES else _unscaled_matrix(r)
    return 4.0 / (np.pi * e_star) * unscaled


def _unscaled_matrix(r: np.ndarray) -> np.ndarray:
    """The influence matrix of the nodes ``r`` (m) without the 4/(pi E*) factor, m."""
    x, w = np.polynomial.legendre.leggauss(_N_GAUSS)
    t, w = 0.5 * (x + 1.0), 0.5 * w
    v = _log_product_weights(t)
    return np.vstack([_block(r[i:i + _BLOCK], r, t, w, v, i) for i in range(0, len(r), _BLOCK)])


@lru_cache(maxsize=_KEPT_MATRICES)
def _kept_matrix(nodes: bytes) -> np.ndarray:
    """:func:`_unscaled_matrix` of the nodes given as their float64 bytes, m, computed once per
    node set (the last :data:`_KEPT_MATRICES` kept; safe from several threads) and read only."""
    matrix = _unscaled_matrix(np.frombuffer(nodes, dtype=float))
    matrix.flags.writeable = False
    return matrix


def forget_kept_matrices() -> None:
    """Drop the influence matrices :func:`influence_matrix` keeps, so that the next solve on any nodes
    builds its own (what the benchmarks time: a stage's one solve pays for it)."""
    _kept_matrix.cache_clear()


def force_weights(r: ArrayLike) -> np.ndarray:
    """Weights c with F = c . p = 2 pi integral p r dr exactly for piecewise-linear p, in m^2."""
    r = np.asarray(r, dtype=float)
    a, b = r[:-1], r[1:]
    length = b - a
    c = np.zeros_like(r)
    c[:-1] += length * (2 * a + b) / 6.0
    c[1:] += length * (a + 2 * b) / 6.0
    return 2.0 * np.pi * c
