"""The atlas's scene-series surrogate: each design scene's own curves, interpolated across (mu, Pi).

The grid surrogate (:mod:`g2tom.fitting.atlas_grid`) fits one polynomial in (ln mu, ln Pi) through
all design scenes at once; where the response bends more than that polynomial can, it misses the
scenes between. This model keeps what each scene measured and interpolates only between scenes:

* per design scene and oxide node (z = -ln(1 - xi), ln lambda; the clean surface as the node
  z = 0), a Chebyshev series of order P in the mapped ln F', fitted by weighted least squares to
  the scene's steps (weights 1 / sigma^2; points that are not finite left out);
* across scenes, each coefficient of each node interpolated over the groups' coordinates
  (:data:`~g2tom.fitting.atlas_grid.FRAMES`: (ln mu, ln Pi) or (ln(mu / Pi), ln Pi)) by a radial basis
  function (polyharmonic ``cubic`` r^3 or ``thin_plate_spline`` r^2 ln r with a linear polynomial
  tail, ``quintic`` -r^5 with the quadratic tail it needs: :data:`TAIL_DEGREE`; so a response linear
  in the groups' coordinates is reproduced exactly by every kernel) with a ``smoothing`` that lets
  it pass off a scene's own noise (0: through every scene's series);
* between oxide nodes, linear in (z, ln lambda), as the grid surrogate is.

Frame, kernel, smoothing and P are chosen by leave-one-scene-out cross-validation beside the grid
surrogate's candidates (:func:`cross_validate`). Pure numpy/scipy; no I/O.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
from scipy.interpolate import RBFInterpolator

from g2tom.fitting.atlas_grid import (group_coordinates, group_powers, leave_one_scene_out, load_basis,
                                         node_series_value, weighted_fit)

__all__ = ["KERNELS", "TAIL_DEGREE", "SceneSeriesModel", "fit_scene_series", "cross_validate"]

#: Radial basis functions offered (polyharmonic: no length scale to choose). The quintic is the
#: smoothest of the three; with enough smoothing it suits scenes whose light steps are noisy (on the
#: 6 x 6 atlas leave-one-scene-out chose it, smoothing 10: 662 of 960 cells, the cubic's best 657).
KERNELS = ("cubic", "thin_plate_spline", "quintic")
#: Degree of each kernel's polynomial tail: the least that makes its system solvable (scipy's
#: minimum: 1 for r^3 and r^2 ln r, 2 for -r^5).
TAIL_DEGREE = {"cubic": 1, "thin_plate_spline": 1, "quintic": 2}


@dataclass(frozen=True)
class SceneSeriesModel:
    """The fitted scene-series surrogate of ln R'.

    Attributes
    ----------
    z_nodes, w_nodes
        (nz,) -ln(1 - xi) of the nodes (0 first: the clean surface) and (nw,) ln lambda.
    centers
        (scenes, 2) the design scenes' coordinates in ``frame``.
    coef
        (scenes, nz, nw, P + 1) each scene's Chebyshev coefficients of ln R' in the mapped ln F'.
    load_low, load_high
        Ends of ln F' mapped to -1 and 1.
    kernel
        The radial basis function (:data:`KERNELS`).
    smoothing
        Its smoothing parameter (0: interpolation through every scene), in (ln R')^2 per unit of
        the kernel.
    frame
        The groups' coordinates (:data:`~g2tom.fitting.atlas_grid.FRAMES`).
    """

    z_nodes: np.ndarray
    w_nodes: np.ndarray
    centers: np.ndarray
    coef: np.ndarray
    load_low: float
    load_high: float
    kernel: str
    smoothing: float
    frame: str = "log"

    @property
    def order(self) -> int:
        """Order P of the Chebyshev series in ln F'."""
        return int(self.coef.shape[-1] - 1)

    @property
    def degree(self) -> str:
        """The interpolation across scenes, in words (the report's "degree" column)."""
        return f"{self.kernel} RBF, smoothing {self.smoothing:g}"

    @cached_property
    def _interpolator(self) -> RBFInterpolator:
        return RBFInterpolator(self.centers, self.coef.reshape(self.coef.shape[0], -1), kernel=self.kernel,
                               smoothing=self.smoothing, degree=TAIL_DEGREE[self.kernel])

    def log_resistance(self, xi: np.ndarray, lam: np.ndarray, mu: np.ndarray, pi: np.ndarray,
                       force_n: np.ndarray) -> np.ndarray:
        """ln R' at the points (arrays of equal size; xi = 0: the clean surface).

        The interpolation across scenes runs once per distinct (mu, Pi), so many queries on a few
        surfaces cost little more than their load basis.
        """
        xi, lam, mu, pi, force_n = (np.asarray(a, float).ravel() for a in (xi, lam, mu, pi, force_n))
        pairs, inverse = np.unique(np.column_stack([mu, pi]), axis=0, return_inverse=True)
        at = group_coordinates(pairs[:, 0], pairs[:, 1], self.frame)
        per_surface = self._interpolator(at).reshape((pairs.shape[0],) + self.coef.shape[1:])
        return node_series_value(per_surface, inverse.ravel(), xi, lam, force_n, self.z_nodes, self.w_nodes,
                                 (self.load_low, self.load_high))


def fit_scene_series(z_nodes: np.ndarray, w_nodes: np.ndarray, mu: np.ndarray, pi: np.ndarray, force_n: np.ndarray,
                     log_r: np.ndarray, sigma: np.ndarray, scenes: np.ndarray, order: int, kernel: str,
                     smoothing: float, load: tuple[float, float] | None = None, frame: str = "log") -> SceneSeriesModel:
    """Fit the scene-series surrogate.

    Parameters
    ----------
    z_nodes, w_nodes
        (nz,), (nw,) node coordinates, increasing.
    mu, pi, force_n, scenes
        (n,) groups, F' and scene of every point (a design scene's load step).
    log_r, sigma
        (n, nz, nw) ln R' at every point and node, and one standard deviation of it (> 0).
    order, kernel, smoothing
        P of the series in ln F'; the radial basis function and its smoothing.
    load
        (low, high) of ln F' mapped to [-1, 1] (default: the points' own).
    frame
        The groups' coordinates the interpolation works in (:data:`~g2tom.fitting.atlas_grid.FRAMES`).

    Raises
    ------
    ValueError
        If a scene's node has no more finite points than P + 1, fewer than three scenes are
        given, they lie on one line in (ln mu, ln Pi) (the linear tail is then undetermined),
        the scenes cannot fix the kernel's tail (the quintic's quadratic: six scenes not on one
        conic), or the kernel or frame is unknown.
    """
    if load is None:
        load = (float(np.log(force_n).min()), float(np.log(force_n).max()))
    centers, fits = _own_series(z_nodes, w_nodes, mu, pi, force_n, log_r, sigma, scenes, order, load, frame)
    return _interpolated(z_nodes, w_nodes, centers, fits, load, kernel, smoothing, frame)


def _own_series(z_nodes: np.ndarray, w_nodes: np.ndarray, mu: np.ndarray, pi: np.ndarray, force_n: np.ndarray,
                log_r: np.ndarray, sigma: np.ndarray, scenes: np.ndarray, order: int, load: tuple[float, float],
                frame: str) -> tuple[np.ndarray, list[np.ndarray | ValueError]]:
    """Every scene's (in :func:`numpy.unique` order) center in ``frame`` (scenes, 2) and its own series'
    coefficients (nz, nw, P + 1), or the ValueError its fit raised (too few finite points)."""
    labels = np.unique(scenes)
    centers = np.empty((labels.size, 2))
    fits: list[np.ndarray | ValueError] = []
    for k, s in enumerate(labels):
        own = scenes == s
        centers[k] = group_coordinates(mu[own][:1], pi[own][:1], frame)[0]
        basis = load_basis(force_n[own], load[0], load[1], order)
        coef = np.empty((z_nodes.size, w_nodes.size, order + 1))
        try:
            for i in range(z_nodes.size):
                for j in range(w_nodes.size):
                    coef[i, j] = weighted_fit(basis, log_r[own, i, j], sigma[own, i, j])
        except ValueError as error:
            fits.append(error)
            continue
        fits.append(coef)
    return centers, fits


def _interpolated(z_nodes: np.ndarray, w_nodes: np.ndarray, centers: np.ndarray, fits: list[np.ndarray | ValueError],
                  load: tuple[float, float], kernel: str, smoothing: float, frame: str) -> SceneSeriesModel:
    """The model interpolating the scenes' own series (:func:`_own_series`) across their ``centers``;
    raises what :func:`fit_scene_series` documents."""
    for fit in fits:
        if isinstance(fit, ValueError):
            raise fit
    scenes = centers.shape[0]
    if scenes < 3 or np.linalg.matrix_rank(centers - centers.mean(axis=0)) < 2:
        raise ValueError(f"{scenes} scenes on one line in (ln mu, ln Pi) cannot fix a linear tail")
    if kernel not in KERNELS:
        raise ValueError(f"kernel {kernel!r} is not one of {KERNELS}")
    shifted = centers - centers.mean(axis=0)
    tail = np.prod(shifted[:, None, :] ** group_powers(TAIL_DEGREE[kernel])[None, :, :], axis=-1)
    if np.linalg.matrix_rank(tail) < tail.shape[1]:
        raise ValueError(f"{scenes} scenes cannot fix the {kernel} kernel's tail of degree {TAIL_DEGREE[kernel]}"
                         f" ({tail.shape[1]} terms)")
    return SceneSeriesModel(np.asarray(z_nodes, float), np.asarray(w_nodes, float), centers, np.stack(fits),
                            float(load[0]), float(load[1]), kernel, float(smoothing), frame)


def cross_validate(z_nodes: np.ndarray, w_nodes: np.ndarray, mu: np.ndarray, pi: np.ndarray, force_n: np.ndarray,
                   log_r: np.ndarray, sigma: np.ndarray, scenes: np.ndarray, order: int, kernel: str,
                   smoothing: float, frame: str = "log") -> np.ndarray:
    """Leave-one-scene-out residuals ln R'_predicted - ln R' (n, nz, nw) of the scene-series surrogate.

    Each scene's points are predicted by the model fitted on the other scenes (the load mapping
    fixed to all points' ends); as a scene's own series does not depend on the others, each is fitted
    once and every fold only interpolates. A fold that cannot be fitted leaves its residuals inf.
    """
    load = (float(np.log(force_n).min()), float(np.log(force_n).max()))
    labels = np.unique(scenes)
    centers, fits = _own_series(z_nodes, w_nodes, mu, pi, force_n, log_r, sigma, scenes, order, load, frame)

    def fold(keep: np.ndarray) -> SceneSeriesModel:
        kept = np.isin(labels, scenes[keep])
        return _interpolated(z_nodes, w_nodes, centers[kept], [f for f, k in zip(fits, kept) if k], load, kernel,
                             smoothing, frame)

    return leave_one_scene_out(fold, z_nodes, w_nodes, mu, pi, force_n, log_r, scenes)
