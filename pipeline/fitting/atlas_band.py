"""The atlas surrogate's band where the query is: its cross-validated error by region of the domain.

One global RMS says nothing about where a surrogate is worse (light loads, much oxide, the edges
of the (mu, Pi) box). The band here is one standard deviation of ln R' made of

* the **regional error**: the RMS of the leave-one-scene-out residuals of the design scenes
  (:func:`g2tom.fitting.atlas_grid.cross_validate`; the box's corner scenes left out, as a
  corner left out is extrapolated to in both groups) in the query's region, a cell of
  F' (:data:`FORCE_EDGES`) x xi (:data:`XI_EDGES`) x the groups' position (``inside`` the box, or
  at its ``edge``: closer than :data:`EDGE_STEPS` design grid steps to its boundary, where the
  left-out side scenes were extrapolated to in one group, so the edge's error is an upper bound);
* the **grid error** between oxide nodes: the leave-one-node-out error of linear interpolation
  along z = -ln(1 - xi) and along ln lambda (an interior node predicted from its neighbours,
  over every design scene and step, by F' and xi region), times t (1 - t) at the query's fraction t of its
  interval (a quadratic's interpolation error: zero on a node, a quarter of the leave-one-out
  error mid-interval);

combined in quadrature. Where the held-out scenes (never fitted) have at least :data:`MIN_POINTS`
points in a region and err more there than the cross-validation says, the regional error is
theirs (:func:`with_heldout`): the band is the larger of the two honest estimates. Pure numpy; no I/O.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from g2tom.fitting.atlas_grid import interpolation_weights, node_coordinates

__all__ = ["FORCE_EDGES", "XI_EDGES", "EDGE_STEPS", "MIN_POINTS", "RegionalBand", "fit_band", "with_heldout",
           "region_labels"]

#: F' between the regions of the band: light, middle, heavy loads.
FORCE_EDGES = (0.3, 3.0)
#: xi between the regions of the band (the clean surface counts as the least oxide).
XI_EDGES = (0.4, 0.6)
#: A surface closer than this many design grid steps to the (mu, Pi) box's boundary is at its edge.
EDGE_STEPS = 0.5
#: Fewest residuals a region needs; a region with fewer takes its F' region's RMS over all the rest.
MIN_POINTS = 20
_GROUPS = ("inside", "edge")


def region_labels() -> list[str]:
    """Names of the regions, in the order of :attr:`RegionalBand.regional` flattened (F', xi, groups)."""
    force = [f"F' < {FORCE_EDGES[0]:g}", f"{FORCE_EDGES[0]:g} <= F' < {FORCE_EDGES[1]:g}", f"F' >= {FORCE_EDGES[1]:g}"]
    xi = [f"xi < {XI_EDGES[0]:g}", f"{XI_EDGES[0]:g} <= xi < {XI_EDGES[1]:g}", f"xi >= {XI_EDGES[1]:g}"]
    return [f"{f}, {x}, {g}" for f in force for x in xi for g in _GROUPS]


@dataclass(frozen=True)
class RegionalBand:
    """The band's tables and the design box it locates a surface in.

    Attributes
    ----------
    regional
        (3, 3, 2) RMS leave-one-scene-out error of ln R' by (F', xi, groups) region.
    counts
        (3, 3, 2) residuals behind each entry.
    grid_z, grid_w
        (3, 3) leave-one-node-out interpolation error of ln R' along z and ln lambda, by F' and xi
        region (of the node left out).
    box_low, box_step
        (2,) ln mu, ln Pi of the box's low corner and of one design grid step.
    box_steps
        (2,) design grid steps across the box (n_mu - 1, n_pi - 1).
    z_nodes, w_nodes
        The oxide nodes (z, ln lambda) the grid error refers to.
    """

    regional: np.ndarray
    counts: np.ndarray
    grid_z: np.ndarray
    grid_w: np.ndarray
    box_low: np.ndarray
    box_step: np.ndarray
    box_steps: np.ndarray
    z_nodes: np.ndarray
    w_nodes: np.ndarray

    def to_dict(self) -> dict[str, Any]:
        """Plain lists for JSON."""
        return {k: np.asarray(v).tolist() for k, v in self.__dict__.items()}

    @classmethod
    def from_dict(cls, doc: dict[str, Any]) -> "RegionalBand":
        """The inverse of :meth:`to_dict` (other keys of ``doc`` are ignored)."""
        return cls(**{k: np.asarray(doc[k], float) for k in cls.__dataclass_fields__})

    def regions(self, xi: np.ndarray, mu: np.ndarray, pi: np.ndarray, force_n: np.ndarray) -> np.ndarray:
        """Flat index (F', xi, groups) of each point's region, as in :func:`region_labels`."""
        f = np.searchsorted(FORCE_EDGES, force_n, side="right")
        x = np.searchsorted(XI_EDGES, xi, side="right")
        return f * 6 + x * 2 + self.at_edge(mu, pi).astype(int)

    def at_edge(self, mu: np.ndarray, pi: np.ndarray) -> np.ndarray:
        """Whether each surface lies within :data:`EDGE_STEPS` grid steps of the box's boundary."""
        u = (np.column_stack([np.log(mu), np.log(pi)]) - self.box_low) / self.box_step
        return np.min(np.minimum(u, self.box_steps - u), axis=1) < EDGE_STEPS

    def __call__(self, xi: np.ndarray, lam: np.ndarray, mu: np.ndarray, pi: np.ndarray,
                 force_n: np.ndarray) -> np.ndarray:
        """One standard deviation of ln R' at each query (arrays of equal size)."""
        f = np.searchsorted(FORCE_EDGES, force_n, side="right")
        x = np.searchsorted(XI_EDGES, xi, side="right")
        regional = self.regional[f, x, self.at_edge(mu, pi).astype(int)]
        z, w = node_coordinates(xi, lam)
        _, tz = interpolation_weights(z, self.z_nodes)
        _, tw = interpolation_weights(w, self.w_nodes)
        grid_z = self.grid_z[f, x] * np.clip(tz * (1.0 - tz), 0.0, None)
        grid_w = self.grid_w[f, x] * np.clip(tw * (1.0 - tw), 0.0, None)
        return np.sqrt(regional**2 + grid_z**2 + grid_w**2)


def _loo_nodes(log_r: np.ndarray, nodes: np.ndarray, axis: int) -> np.ndarray:
    """(n, nz, nw) residuals of predicting each interior node along ``axis`` (1: z, 2: lambda) from
    its two neighbours by linear interpolation; NaN at the end nodes."""
    out = np.full(log_r.shape, np.nan)
    for k in range(1, nodes.size - 1):
        t = (nodes[k] - nodes[k - 1]) / (nodes[k + 1] - nodes[k - 1])
        take = lambda j: np.take(log_r, j, axis=axis)  # noqa: E731
        index = [slice(None)] * 3
        index[axis] = k
        out[tuple(index)] = (1 - t) * take(k - 1) + t * take(k + 1) - take(k)
    return out


def _rms(values: np.ndarray) -> float:
    values = values[np.isfinite(values)]
    return float(np.sqrt(np.mean(values**2))) if values.size else 0.0


def fit_band(residual: np.ndarray, log_r: np.ndarray, xi_nodes: np.ndarray, w_nodes: np.ndarray, mu: np.ndarray,
             pi: np.ndarray, force_n: np.ndarray, box: tuple[np.ndarray, np.ndarray, np.ndarray]) -> RegionalBand:
    """The band's tables from the design scenes.

    Parameters
    ----------
    residual
        (n, nz, nw) leave-one-scene-out residuals of ln R' at every design point and node.
    log_r
        (n, nz, nw) ln R' of the design scenes (for the grid's leave-one-node-out error).
    xi_nodes, w_nodes
        (nz,) xi of the nodes (0: clean) and (nw,) ln lambda.
    mu, pi, force_n
        (n,) groups and F' of every point.
    box
        (low, step, steps): ln mu, ln Pi of the design box's low corner, one grid step, and the
        grid steps across it.
    """
    low, step, steps = (np.asarray(b, float) for b in box)
    z_nodes = node_coordinates(xi_nodes, np.ones_like(xi_nodes))[0]
    band = RegionalBand(np.zeros((3, 3, 2)), np.zeros((3, 3, 2)), np.zeros((3, 3)), np.zeros((3, 3)), low, step, steps,
                        z_nodes, np.asarray(w_nodes, float))
    f_region = np.searchsorted(FORCE_EDGES, force_n, side="right")
    x_region = np.searchsorted(XI_EDGES, xi_nodes, side="right")
    edge = band.at_edge(mu, pi).astype(int)
    regional, counts = np.zeros((3, 3, 2)), np.zeros((3, 3, 2))
    for f in range(3):
        in_f = f_region == f
        for x in range(3):
            for g in range(2):
                values = residual[in_f & (edge == g)][:, x_region == x]
                values = values[np.isfinite(values)]
                counts[f, x, g], regional[f, x, g] = values.size, _rms(values)
        fallback = _rms(residual[in_f])
        regional[f][counts[f] < MIN_POINTS] = fallback
    loo_z = _loo_nodes(log_r, z_nodes, 1)
    loo_w = _loo_nodes(log_r, np.asarray(w_nodes, float), 2)
    loo_w[:, 0] = np.nan  # the clean node does not vary with lambda
    grid_z, grid_w = np.zeros((3, 3)), np.zeros((3, 3))
    for f in range(3):
        for x in range(3):
            grid_z[f, x] = _rms(loo_z[f_region == f][:, x_region == x])
            grid_w[f, x] = _rms(loo_w[f_region == f][:, x_region == x])
    return RegionalBand(regional, counts, grid_z, grid_w, low, step, steps, z_nodes, np.asarray(w_nodes, float))


def with_heldout(band: RegionalBand, xi: np.ndarray, mu: np.ndarray, pi: np.ndarray, force_n: np.ndarray,
                 error: np.ndarray) -> tuple[RegionalBand, np.ndarray, np.ndarray]:
    """``band`` with each region's error raised to the held-out scenes' RMS ``error`` (ln R') there,
    where they have at least :data:`MIN_POINTS` finite points; and the held-out RMS and counts (3, 3, 2)."""
    index = band.regions(xi, mu, pi, force_n)
    finite = np.isfinite(error)
    rms, counts = np.zeros(18), np.zeros(18)
    for k in range(18):
        values = error[(index == k) & finite]
        counts[k], rms[k] = values.size, _rms(values)
    regional = np.where(counts >= MIN_POINTS, np.maximum(band.regional.ravel(), rms), band.regional.ravel())
    raised = RegionalBand(regional.reshape(3, 3, 2), band.counts, band.grid_z, band.grid_w, band.box_low,
                          band.box_step, band.box_steps, band.z_nodes, band.w_nodes)
    return raised, rms.reshape(3, 3, 2), counts.reshape(3, 3, 2)
