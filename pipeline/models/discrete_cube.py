"""The cube on discrete spots (``contact.model = "discrete"``): oxide fields where each surface's spots lie.

Oxide realization ``k`` meets surface ``k mod S`` of contact.nc's pool (``S = contact.surfaces``;
in a grown pool, ``contact.pool_half_width``, ``S`` is the pool's size at each step, so a light step
may meet another surface than the heavy ones: :meth:`DiscretePool.groups`) and its own field
(the same field as on grid spots, by seed and index, so paired comparisons stay possible). The
field is evaluated where the spots are, exactly
(:func:`g2tom.physics.oxide_points.values_at_points`), and each spot conducts by
``oxide.spot_rule``:

* ``centre``: all of it where the field at its centre is clean (``psi < threshold``, float32
  values compared, as on grid spots), else nothing;
* ``disc``: its clean share ``f`` of the contact disc, from the field at an equal-area pattern of
  points on the disc (:class:`g2tom.physics.spot_share.DiscRule`), with radius ``a sqrt(f)``;
* ``segment``: the same ``f``, with the radius ``a h(f)`` of the circular segment of that share's
  conductance (:func:`g2tom.physics.spot_share.effective_radius`).
  The pattern's rings follow the disc's size against the correlation length ``l_O``:
  ``min(DEFAULT_RINGS, ceil(RINGS_PER_CORRELATION a / l_O))``, at least one, so a disc of radius
  ``l_O / 2`` gets the full pattern (clean share within 0.02 of a fine image of the disc, see
  :mod:`g2tom.physics.spot_share`) and a small one a few points.

The resistance of each (xi, load step) is the exact point-interaction solve or Greenwood's form
on the conducting spots (:func:`g2tom.physics.discrete_resistance.resistances`), with the
coupling kernel of the contact solve, so the clean surface obeys Barber's theorem exactly.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
import xarray as xr

from g2tom import config
from g2tom.physics import oxide_band
from g2tom.physics.discrete_contact import interaction_kernel
from g2tom.physics.discrete_resistance import resistances
from g2tom.physics.oxide_points import values_at_points
from g2tom.physics.spot_share import DEFAULT_RINGS, disc_points, disc_shares, effective_radius

from g2tom.models.cube_settings import CubeSettings

__all__ = ["RINGS_PER_CORRELATION", "POINT_TOLERANCE", "DiscretePool", "rings", "clean_shares", "discrete_chunk", "clean_pool",
           "weighted_clean_share"]

#: Disc rule: pattern rings per disc radius in correlation lengths l_O (8 rings at a = l_O / 2).
RINGS_PER_CORRELATION = 16.0
#: Relative tolerance of the field at the discs' points (FINUFFT's ``eps``), 10-20 % faster than
#: 1e-12: on the paper's pool not one of 2 million shares differs (60 fields at each of lambda 1,
#: 5, 11, 23; 1e-6 changes two), and of paper_discrete's 3.1 million resistances 6 differ (a
#: pattern point within ~1e-7 of its threshold, counted on the other side).
POINT_TOLERANCE = 1e-7


@dataclass(frozen=True)
class DiscretePool:
    """contact.nc's pool of discrete surfaces: spot positions (m) and radii per step (m), padded.

    Attributes
    ----------
    x, y
        Spot positions, shape (surface, spot).
    radius
        Contact radii, shape (surface, delta, spot); 0 off contact and beyond ``count``.
    count
        Spots of each surface, shape (surface,).
    floor
        The coupling kernel's distance floor, m.
    steps
        Load steps each surface was solved at, the lightest first, shape (surface,); None: every
        step (the fixed pool).
    """

    x: np.ndarray
    y: np.ndarray
    radius: np.ndarray
    count: np.ndarray
    floor: float
    steps: np.ndarray | None = None
    #: Coupling kernels made so far, by surface (a surface meets many oxide realizations).
    _kernels: dict[int, np.ndarray] = field(default_factory=dict, compare=False, repr=False)

    @classmethod
    def of(cls, contact: xr.Dataset) -> "DiscretePool":
        """The pool stored in a discrete contact dataset."""
        steps = contact["surface_steps"].values if "surface_steps" in contact else None
        return cls(contact["asperity_x"].values, contact["asperity_y"].values,
                   contact["asperity_radius"].transpose("surface", "delta", "spot").values,
                   contact["spot_count"].values, float(contact.attrs["coupling_floor"]), steps)

    @property
    def size(self) -> int:
        """Surfaces in the pool (at its lightest step, in a grown pool)."""
        return int(self.count.size)

    def sizes(self) -> np.ndarray:
        """The pool's size at every step, shape (delta,): its first that many surfaces are solved there."""
        n_delta = self.radius.shape[1]
        if self.steps is None:
            return np.full(n_delta, self.size)
        return (self.steps[:, None] > np.arange(n_delta)).sum(axis=0)

    def groups(self, realization: int) -> list[tuple[int, np.ndarray | None]]:
        """The surfaces oxide realization ``realization`` meets, each with the steps it meets it at
        (``k mod`` the pool's size at each step); steps None: one surface at every step."""
        if self.steps is None:
            return [(int(realization) % self.size, None)]
        met = int(realization) % self.sizes()
        return [(int(s), np.flatnonzero(met == s)) for s in np.unique(met)]

    def solved(self, surface: int) -> np.ndarray | None:
        """The steps ``surface`` was solved at (None: every step)."""
        return None if self.steps is None else np.arange(int(self.steps[surface]))

    def kernel(self, surface: int) -> np.ndarray:
        """The coupling kernel (1/m, spot x spot) of ``surface``, made once per surface and kept while
        the kept ones fit :data:`g2tom.config.KERNEL_CACHE_BYTES`."""
        s = int(surface)
        kernel = self._kernels.get(s)
        if kernel is None:
            x, y, _ = self.spots(s)
            kernel = interaction_kernel(x, y, self.floor)
            kept = tuple(self._kernels.values())  # one step under the GIL: other threads add kernels meanwhile
            if sum(k.nbytes for k in kept) + kernel.nbytes <= config.KERNEL_CACHE_BYTES:
                self._kernels[s] = kernel
        return kernel

    def spots(self, surface: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Positions (m) and radii (delta, spot) of ``surface``."""
        s = int(surface)
        m = int(self.count[s])
        return self.x[s, :m], self.y[s, :m], self.radius[s, :, :m]


def rings(radius: np.ndarray, correlation_length: float) -> np.ndarray:
    """Rings of the disc pattern for discs of ``radius`` (m) in a field of correlation length ``l_O`` (m)."""
    wanted = np.ceil(RINGS_PER_CORRELATION * np.asarray(radius, float) / correlation_length)
    return np.clip(wanted, 1, DEFAULT_RINGS).astype(int)


def clean_shares(modes: oxide_band.Band, coeffs: np.ndarray, x: np.ndarray, y: np.ndarray, radius: np.ndarray,
                 threshold: np.ndarray, rule: str, correlation_length: float) -> np.ndarray:
    """Clean share of every spot at every step and oxide fraction, shape (xi, delta, spot).

    Parameters
    ----------
    modes, coeffs
        The field's band and its coefficients (modes.size,).
    x, y
        Spot positions, m, shape (spot,).
    radius
        Contact radii, m, shape (delta, spot); 0 off contact (share 0).
    threshold
        float32 thresholds, shape (xi,).
    rule
        ``centre`` (the pattern of no ring: the centre point) or ``disc``.
    correlation_length
        ``l_O``, m (sets the disc pattern's rings).
    """
    count = np.zeros(radius.shape, int) if rule == "centre" else rings(radius, correlation_length)
    px, py = disc_points(x, y, radius, count)
    values = values_at_points(modes, coeffs, px, py, POINT_TOLERANCE).astype(np.float32)
    return disc_shares(values, threshold.astype(np.float32), radius, count)


def _terms(kernel: np.ndarray, radius: np.ndarray, rho: float, model: str) -> dict[str, np.ndarray]:
    """Resistance terms of spot radii (..., spot) on one surface: R, its self term, the rest, the count."""
    total = radius.sum(axis=-1)
    resistance = resistances(kernel, radius, rho, model)
    with np.errstate(divide="ignore"):
        own = rho / (2.0 * total)
    open_ = ~np.isfinite(resistance)
    return {"resistance": resistance, "resistance_self": own,
            "resistance_interaction": np.where(open_, np.inf, resistance - np.where(open_, 0.0, own)),
            "n_conducting": (radius > 0).sum(axis=-1).astype(np.int32),
            "crop_bound": np.zeros(resistance.shape)}


def discrete_chunk(source: Any, index: int, realizations: np.ndarray, xi_index: np.ndarray,
                   pool: DiscretePool, settings: "CubeSettings", limit: int | None = None) -> dict[str, Any]:
    """The terms (xi, delta, realization) of the fields of ``realizations`` at lambda number ``index``.

    ``source`` is a :class:`g2tom.scene.FieldSource` (or the record in front of one):
    its thresholds and its fields' coefficients. ``limit``: only the steps below it are computed
    (NaN, counts -1, at the others; ``oxide.step_half_width``); None: every step.
    """
    base = getattr(source, "source", source)
    modes, lam = base.modes[index], base.lambdas[index]
    thresholds = source.thresholds(index, realizations)[xi_index]
    n_delta = pool.radius.shape[1]
    limit = n_delta if limit is None else int(limit)
    pieces = []
    for column, k in enumerate(realizations):
        coeffs = oxide_band.coefficients(modes, oxide_band.field_stream(base.seed, lam, int(k)), base.amplitudes)
        parts = []
        for surface, steps in pool.groups(int(k)):
            if limit < n_delta:
                steps = (np.arange(n_delta) if steps is None else steps)
                steps = steps[steps < limit]
                if steps.size == 0:
                    continue
            x, y, radius = pool.spots(surface)
            radius = radius if steps is None else radius[steps]
            share = clean_shares(modes, coeffs, x, y, radius, thresholds[:, column], settings.spot_rule,
                                 lam * base.cell_size)
            part = _terms(pool.kernel(surface), effective_radius(radius[None], share, settings.spot_rule),
                          settings.rho, settings.model)
            if settings.control_variate:
                part["clean_share"] = weighted_clean_share(share, radius)
            parts.append((steps, part))
        pieces.append(parts[0][1] if parts[0][0] is None else _by_step(parts, n_delta))
    out: dict[str, Any] = {name: np.stack([p[name] for p in pieces], axis=-1) for name in pieces[0]}
    out["n_uncropped"] = 0
    return out


def _by_step(parts: list[tuple[np.ndarray, dict[str, np.ndarray]]], n_delta: int) -> dict[str, np.ndarray]:
    """One realization's terms (..., delta) put together from the surfaces it meets at the steps given
    (NaN, counts -1, at steps none of them gives)."""
    out = {}
    for name, first in parts[0][1].items():
        fill = -1 if np.issubdtype(first.dtype, np.integer) else np.nan
        joined = np.full(first.shape[:-1] + (n_delta,), fill, first.dtype)
        for steps, part in parts:
            joined[..., steps] = part[name]
        out[name] = joined
    return out


def weighted_clean_share(share: np.ndarray, radius: np.ndarray) -> np.ndarray:
    """The control variate of a realization: its spots' clean shares averaged with their contact radii.

    Parameters
    ----------
    share
        Clean share of every spot, (xi, delta, spot).
    radius
        Contact radii, m, (delta, spot); 0 off contact.

    Returns
    -------
    numpy.ndarray
        (xi, delta) ``sum_i a_i f_i / sum_i a_i`` (NaN at a step without contact). Its expectation
        over the fields is the probability that a point is clean
        (:func:`g2tom.physics.oxide_marginal.clean_probability`), whatever the surface.
    """
    total = radius.sum(axis=-1)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(total > 0, (share * radius[None]).sum(axis=-1) / total, np.nan)


def clean_pool(pool: DiscretePool, rho: float, model: str) -> dict[str, np.ndarray]:
    """The oxide-free terms of every surface of the pool, each (surface, delta); in a grown pool,
    NaN (counts -1) at the steps a surface was not solved at."""
    n_delta = pool.radius.shape[1]
    pieces = []
    for s in range(pool.size):
        steps = pool.solved(s)
        radius = pool.spots(s)[2]
        piece = _terms(pool.kernel(s), radius if steps is None else radius[steps], rho, model)
        if steps is not None:
            piece = {name: np.concatenate([v, np.full(n_delta - steps.size, -1 if v.dtype.kind == "i" else np.nan,
                                                      v.dtype)]) for name, v in piece.items()}
        pieces.append(piece)
    return {name: np.stack([p[name] for p in pieces]) for name in pieces[0]}
