"""The atlas's grid surrogate: ln R'(xi, lambda, mu, Pi, F') with the structure of the atlas's data.

The atlas holds, per scene (mu, Pi), the curve ln R'(ln F') of every node (xi_k, lambda_l) of one
oxide grid, and the clean curve. The model follows that layout:

* nodes: z_k = -ln(1 - xi_k) with the clean surface as the node z = 0, times w_l = ln lambda_l
  (the clean node's curve repeated over lambda, so the oxide factor Phi = R'/R'_c is exactly 1 at
  xi = 0);
* at each node, a tensor product of a polynomial in the groups' coordinates (:data:`FRAMES`: the
  logs (ln mu, ln Pi) or the sheared (ln(mu / Pi), ln Pi)) mapped to [-1, 1] (total degree
  i + j <= D, or a tensor product i <= a, j <= b) and a Chebyshev series of order P in the mapped
  ln F':

      ln R'_node(mu, Pi, F') = sum_{(i, j)} sum_{q <= P} c_ijq m^i p^j T_q(L),

  fitted by weighted least squares over every (scene, step) of the design scenes (weights
  1 / sigma^2, one standard deviation of ln R' per point; points that are not finite, e.g. all
  realizations open, are left out);
* between nodes, ln R' is interpolated linearly in (z, w), as the single-scene curve model is.

(frame, D, P) are chosen by leave-one-scene-out cross-validation (:func:`cross_validate`): each design
scene predicted by the model fitted without it. Pure numpy; no I/O.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable

import numpy as np
from numpy.polynomial import chebyshev

from g2tom.fitting.atlas_surrogate import exponents

__all__ = ["FRAMES", "FRAME_COORDINATES", "GridTensorModel", "group_coordinates", "node_coordinates", "group_powers",
           "fit_grid_tensor", "cross_validate", "interpolation_weights", "load_basis", "weighted_fit", "node_series_value",
           "leave_one_scene_out"]


#: Coordinates of the groups the curve models are built in: ``log``, (ln mu, ln Pi); ``sheared``,
#: (ln(mu / Pi), ln Pi). mu / Pi = (8/3) sqrt(2 beta / R*) (:mod:`g2tom.physics.groups`): the
#: asperities' curvature against the sphere's, which alone sets most of ln R' at light loads
#: (the atlas's clean ln R' at F' 0.06 spans 2.0 along it, at most 0.2 across it), so a response
#: that bends along the diagonal of (ln mu, ln Pi) is straight along one coordinate here.
FRAME_COORDINATES = {"log": "(ln mu, ln Pi)", "sheared": "(ln(mu / Pi), ln Pi)"}
FRAMES = tuple(FRAME_COORDINATES)


def group_coordinates(mu: np.ndarray, pi: np.ndarray, frame: str = "log") -> np.ndarray:
    """(n, 2) coordinates of the groups in ``frame`` (:data:`FRAMES`).

    Raises
    ------
    ValueError
        If the frame is unknown.
    """
    logs = np.column_stack([np.log(np.asarray(mu, float)).ravel(), np.log(np.asarray(pi, float)).ravel()])
    if frame == "log":
        return logs
    if frame == "sheared":
        return np.column_stack([logs[:, 0] - logs[:, 1], logs[:, 1]])
    raise ValueError(f"frame {frame!r} is not one of {FRAMES}")


def node_coordinates(xi: np.ndarray, lam: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """z = -ln(1 - xi) and w = ln(lambda)."""
    return -np.log1p(-np.asarray(xi, float)), np.log(np.asarray(lam, float))


def _mapped(x: np.ndarray, low: np.ndarray | float, high: np.ndarray | float) -> np.ndarray:
    return 2.0 * (np.asarray(x, float) - low) / (np.asarray(high) - low) - 1.0


def _group_basis(mu: np.ndarray, pi: np.ndarray, low: np.ndarray, high: np.ndarray, powers: np.ndarray,
                 frame: str) -> np.ndarray:
    """(n, terms) monomials m^i p^j of the groups' coordinates in ``frame``, mapped."""
    u = _mapped(group_coordinates(mu, pi, frame), low, high)
    return np.prod(u[:, None, :] ** powers[None, :, :], axis=-1)


def load_basis(force_n: np.ndarray, low: float, high: float, order: int) -> np.ndarray:
    """(n, order + 1) Chebyshev polynomials T_q of ln F' mapped from [low, high] to [-1, 1]."""
    return chebyshev.chebvander(_mapped(np.log(force_n), low, high), order)


def interpolation_weights(x: np.ndarray, nodes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Left node index and fraction t of ``x`` between it and the next (linear; beyond the ends t
    leaves [0, 1], i.e. linear extrapolation from the end interval)."""
    k = np.clip(np.searchsorted(nodes, x, side="right") - 1, 0, nodes.size - 2)
    return k, (x - nodes[k]) / (nodes[k + 1] - nodes[k])


@dataclass(frozen=True)
class GridTensorModel:
    """The fitted grid surrogate of ln R'.

    Attributes
    ----------
    z_nodes, w_nodes
        (nz,) -ln(1 - xi) of the nodes (0 first: the clean surface) and (nw,) ln lambda.
    group_low, group_high
        (2,) ends of the groups' two coordinates (in ``frame``) mapped to -1 and 1.
    load_low, load_high
        Ends of ln F' mapped to -1 and 1.
    group_powers
        (terms, 2) exponents (i, j) of m^i p^j.
    coef
        (nz, nw, terms, P + 1) coefficients c_ijq per node.
    frame
        The groups' coordinates (:data:`FRAMES`).
    """

    z_nodes: np.ndarray
    w_nodes: np.ndarray
    group_low: np.ndarray
    group_high: np.ndarray
    load_low: float
    load_high: float
    group_powers: np.ndarray
    coef: np.ndarray
    frame: str = "log"

    @property
    def degree(self) -> int | list[int]:
        """The groups' polynomial: [a, b] of a tensor product (every i <= a, j <= b), else its total degree."""
        a, b = (int(v) for v in self.group_powers.max(axis=0))
        if min(a, b) > 0 and self.group_powers.shape[0] == (a + 1) * (b + 1):
            return [a, b]
        return int(self.group_powers.sum(axis=1).max())

    @property
    def order(self) -> int:
        """Order P of the Chebyshev series in ln F'."""
        return int(self.coef.shape[-1] - 1)

    def log_resistance(self, xi: np.ndarray, lam: np.ndarray, mu: np.ndarray, pi: np.ndarray,
                       force_n: np.ndarray) -> np.ndarray:
        """ln R' at the points (arrays of equal size; xi = 0: the clean surface).

        The groups' polynomial is contracted once per distinct (mu, Pi), so many queries on a
        few surfaces cost little more than their load basis and four gathers.
        """
        xi, lam, mu, pi, force_n = (np.asarray(a, float).ravel() for a in (xi, lam, mu, pi, force_n))
        pairs, inverse = np.unique(np.column_stack([mu, pi]), axis=0, return_inverse=True)
        inverse = inverse.ravel()
        phi = _group_basis(pairs[:, 0], pairs[:, 1], self.group_low, self.group_high, self.group_powers, self.frame)
        per_surface = np.einsum("ut,zwtq->uzwq", phi, self.coef)  # (surfaces, nz, nw, P + 1)
        return node_series_value(per_surface, inverse, xi, lam, force_n, self.z_nodes, self.w_nodes,
                                 (self.load_low, self.load_high))


def node_series_value(per_surface: np.ndarray, inverse: np.ndarray, xi: np.ndarray, lam: np.ndarray,
                      force_n: np.ndarray, z_nodes: np.ndarray, w_nodes: np.ndarray,
                      load: tuple[float, float]) -> np.ndarray:
    """ln R' at points from the Chebyshev series in ln F' of each surface's nodes.

    Parameters
    ----------
    per_surface
        (surfaces, nz, nw, P + 1) coefficients of the series at every node of every distinct surface.
    inverse
        (n,) the surface of each point.
    xi, lam, force_n
        (n,) the points (xi = 0: the clean surface), interpolated linearly between nodes in
        (z, ln lambda).
    z_nodes, w_nodes
        The nodes' z = -ln(1 - xi) and ln lambda, increasing.
    load
        (low, high) of ln F' mapped to -1 and 1.
    """
    z, w = node_coordinates(xi, lam)
    iz, tz = interpolation_weights(z, z_nodes)
    iw, tw = interpolation_weights(w, w_nodes)
    series = np.zeros((xi.size, per_surface.shape[-1]))
    for dz, fz in ((0, 1.0 - tz), (1, tz)):
        for dw, fw in ((0, 1.0 - tw), (1, tw)):
            series += (fz * fw)[:, None] * per_surface[inverse, iz + dz, iw + dw]
    basis = load_basis(force_n, load[0], load[1], per_surface.shape[-1] - 1)
    return np.einsum("nq,nq->n", series, basis)


def weighted_fit(design: np.ndarray, values: np.ndarray, sigma: np.ndarray) -> np.ndarray:
    """Weighted least-squares coefficients (weights 1 / sigma^2) of ``design`` (n, terms) to ``values``
    (n,); points not finite left out.

    Raises
    ------
    ValueError
        If no more points are finite than there are terms.
    """
    keep = np.isfinite(values) & np.isfinite(sigma) & (sigma > 0)
    if keep.sum() <= design.shape[1]:
        raise ValueError(f"{int(keep.sum())} finite points cannot fit {design.shape[1]} terms")
    weight = 1.0 / sigma[keep]
    coef, *_ = np.linalg.lstsq(design[keep] * weight[:, None], values[keep] * weight, rcond=None)
    return coef


def group_powers(degree: int | tuple[int, int]) -> np.ndarray:
    """Exponents (i, j) of m^i p^j: total degree i + j <= ``degree`` (an int), or the tensor product
    i <= a, j <= b (a pair (a, b))."""
    if isinstance(degree, tuple):
        return np.array([(i, j) for i in range(degree[0] + 1) for j in range(degree[1] + 1)], dtype=int)
    return exponents(degree, 2)


def fit_grid_tensor(z_nodes: np.ndarray, w_nodes: np.ndarray, mu: np.ndarray, pi: np.ndarray, force_n: np.ndarray,
                    log_r: np.ndarray, sigma: np.ndarray, degree: int | tuple[int, int], order: int,
                    bounds: tuple[np.ndarray, np.ndarray, float, float] | None = None,
                    frame: str = "log") -> GridTensorModel:
    """Fit the grid surrogate.

    Parameters
    ----------
    z_nodes, w_nodes
        (nz,), (nw,) node coordinates (:func:`node_coordinates`), increasing.
    mu, pi, force_n
        (n,) groups and F' of every point (a design scene's load step).
    log_r, sigma
        (n, nz, nw) ln R' at every point and node, and one standard deviation of it (> 0);
        NaN or inf values are left out of that node's fit.
    degree, order
        The groups' polynomial (:func:`group_powers`: a total degree D, or a pair of degrees in
        the frame's two coordinates for a tensor product) and the Chebyshev order P in ln F'.
    bounds
        (group_low, group_high, load_low, load_high) of the mapping (default: the points' own).
    frame
        The groups' coordinates (:data:`FRAMES`).

    Raises
    ------
    ValueError
        If a node has no more finite points than terms, or the frame is unknown.
    """
    x = group_coordinates(mu, pi, frame)
    if bounds is None:
        bounds = (x.min(axis=0), x.max(axis=0), float(np.log(force_n).min()), float(np.log(force_n).max()))
    group_low, group_high, load_low, load_high = bounds
    group_high = np.where(group_high > group_low, group_high, group_low + 1.0)  # a group held fixed
    powers = group_powers(degree)
    design = (_group_basis(mu, pi, group_low, group_high, powers, frame)[:, :, None]
              * load_basis(force_n, load_low, load_high, order)[:, None, :]).reshape(len(mu), -1)
    coef = np.empty((z_nodes.size, w_nodes.size, powers.shape[0], order + 1))
    for k in range(z_nodes.size):
        for l in range(w_nodes.size):
            coef[k, l] = weighted_fit(design, log_r[:, k, l], sigma[:, k, l]).reshape(powers.shape[0], order + 1)
    return GridTensorModel(np.asarray(z_nodes, float), np.asarray(w_nodes, float), np.asarray(group_low, float),
                           np.asarray(group_high, float), float(load_low), float(load_high), powers, coef, frame)


def cross_validate(z_nodes: np.ndarray, w_nodes: np.ndarray, mu: np.ndarray, pi: np.ndarray, force_n: np.ndarray,
                   log_r: np.ndarray, sigma: np.ndarray, scenes: np.ndarray, degree: int | tuple[int, int],
                   order: int, frame: str = "log") -> np.ndarray:
    """Leave-one-scene-out residuals ln R'_predicted - ln R' (n, nz, nw) of the grid surrogate (frame, D, P).

    Each scene's points are predicted by the model fitted on the other scenes (the mapping fixed
    to all points' bounds, so a scene at the box's edge is extrapolated to, as a query there
    would be from a design without it). A fold that cannot be fitted leaves its residuals inf.
    """
    x = group_coordinates(mu, pi, frame)
    bounds = (x.min(axis=0), x.max(axis=0), float(np.log(force_n).min()), float(np.log(force_n).max()))
    return leave_one_scene_out(
        lambda keep: fit_grid_tensor(z_nodes, w_nodes, mu[keep], pi[keep], force_n[keep], log_r[keep], sigma[keep],
                                     degree, order, bounds, frame),
        z_nodes, w_nodes, mu, pi, force_n, log_r, scenes)


def leave_one_scene_out(fit: Callable[[np.ndarray], Any], z_nodes: np.ndarray, w_nodes: np.ndarray, mu: np.ndarray,
                        pi: np.ndarray, force_n: np.ndarray, log_r: np.ndarray, scenes: np.ndarray) -> np.ndarray:
    """Residuals ln R'_predicted - ln R' (n, nz, nw) of each scene's points, predicted at every node by
    ``fit(keep)`` (a model with ``log_resistance``, fitted on the points ``keep``: every other scene's).
    A fold whose fit raises ValueError (too few points, a singular system) leaves its residuals inf."""
    residual = np.full(log_r.shape, np.inf)
    nz, nw = z_nodes.size, w_nodes.size
    xi_nodes = -np.expm1(-z_nodes)
    for s in np.unique(scenes):
        out = scenes == s
        try:
            model = fit(~out)
        except ValueError:
            continue
        n = int(out.sum())
        xi = np.broadcast_to(xi_nodes[None, :, None], (n, nz, nw)).ravel()
        lam = np.broadcast_to(np.exp(w_nodes)[None, None, :], (n, nz, nw)).ravel()
        rep = [np.broadcast_to(a[out][:, None, None], (n, nz, nw)).ravel() for a in (mu, pi, force_n)]
        residual[out] = model.log_resistance(xi, lam, *rep).reshape(n, nz, nw) - log_r[out]
    return residual
