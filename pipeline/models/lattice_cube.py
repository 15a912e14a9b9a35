"""The Greenwood–Tripp model's cube (:class:`g2tom.models.GreenwoodTripp`): the resistance terms of a
chunk of oxide fields at every load step, on the spots of the cell lattice.

A dask task regenerates a chunk of fields of one lambda from their seeds
(:class:`g2tom.scene.FieldSource`), thresholds them at each oxide fraction and runs
the scenario's resistance model (:func:`model`) on the conducting masks: Greenwood's closed
form, Greenwood's form with films, or the point model. With ``asperities`` spots each
realization brings its own drawn spots (:func:`asperity_spots`). Discrete spots have their own
chunk (:mod:`g2tom.models.discrete_cube`).
"""

from __future__ import annotations

import functools
from dataclasses import replace
from typing import Any

import numpy as np

from g2tom.physics import constriction, point_model, spot_models
from g2tom.physics.spot_geometry import SpotGeometry
from g2tom.scene import FieldSource
from g2tom.models.cube_settings import CubeSettings

__all__ = ["TERMS", "SOLVER_TERMS", "model", "terms", "asperity_spots", "spots_of", "chunk_terms", "clean_terms",
           "exact_terms", "field_chunk"]

TERMS = ("resistance", "resistance_self", "resistance_interaction", "n_conducting", "crop_bound")
#: Extra terms of the point model's iterative solve.
SOLVER_TERMS = ("iterations", "residual", "error_estimate")


def model(settings: CubeSettings) -> Any:
    """The resistance function of ``settings.model`` with the calling convention of
    :func:`constriction.resistance`: the point solve, Greenwood with films, or Greenwood."""
    film = settings.film_resistance
    if settings.model == "point":
        return functools.partial(
            point_model.resistance, film_resistance=film,
            solver_tolerance=settings.solver_tolerance, max_iterations=settings.max_iterations,
            criterion=settings.solver_criterion, lattice_constant=settings.lattice_constant,
        )
    if np.isfinite(film):
        return functools.partial(point_model.greenwood_resistance, film_resistance=film)
    return constriction.resistance


def terms(settings: CubeSettings) -> tuple[str, ...]:
    """The per-entry terms the resistance model of ``settings`` returns on the lattice's spots (the point
    model's also its solver's)."""
    return TERMS + SOLVER_TERMS if settings.model == "point" else TERMS


def _resistance(masks: np.ndarray, radius: np.ndarray, weights: np.ndarray, settings: CubeSettings,
                groups: np.ndarray | None = None) -> constriction.ChunkResult:
    """Resistance terms of a batch of conducting masks (batch, y, x) at every load step (map
    ``b`` with the spots ``radius[groups[b]]`` when ``groups`` is given)."""
    extra = {} if groups is None else {"groups": groups}
    spots = SpotGeometry(radius, weights, settings.pitch, settings.crops, settings.tolerance)
    return model(settings)(masks, spots, settings.rho, settings.method, **extra)


def asperity_spots(settings: CubeSettings, realizations: np.ndarray) -> np.ndarray:
    """The ``asperities`` discretization's spot radii of ``realizations``, (realization, delta, y, x), m.

    Realization ``k`` draws its asperity heights from its own stream
    (:func:`g2tom.physics.spot_models.heights`), held over every load step and shared by
    every (xi, lambda): the surface is one, the oxide fields vary.
    """
    seed, sigma, beta = settings.asperities
    separation = settings.separation
    n = separation.shape[-1]
    return np.stack([
        spot_models.asperity_radius(spot_models.heights(seed, int(k), n, sigma)[None], separation, beta)
        for k in realizations
    ])


def chunk_terms(
    psi: np.ndarray,
    threshold: np.ndarray,
    radius: np.ndarray,
    weights: np.ndarray,
    settings: CubeSettings,
) -> dict[str, Any]:
    """Greenwood terms of a chunk of fields.

    Parameters
    ----------
    psi
        Fields, float32, shape (lambda, realization, y, x).
    threshold
        Thresholds, float32, shape (xi, lambda, realization).
    radius, weights
        Spot radii (m) and interaction weights, shape (delta, y, x) when every realization
        shares its spots, or (realization, delta, y, x) when each brings its own (``asperities``
        spots, :func:`asperity_spots`).
    settings
        ``pitch``, ``rho``, ``crops``, ``tolerance``, ``method`` and the model's settings.

    Returns
    -------
    dict
        The arrays of :data:`TERMS`, shape (xi, lambda, delta, realization), and
        ``n_uncropped``.
    """
    n_xi, n_lam, n_real = threshold.shape
    n = psi.shape[-1]
    masks = psi[None] < threshold[..., None, None]
    groups = None
    if radius.ndim == 4:  # per-realization spots: map (xi, lambda, r) takes group r
        groups = np.tile(np.arange(n_real), n_xi * n_lam)
    res = _resistance(masks.reshape(-1, n, n), radius, weights, settings, groups)
    out: dict[str, Any] = {
        name: getattr(res, name).reshape(n_xi, n_lam, n_real, -1).transpose(0, 1, 3, 2)
        for name in terms(settings)
    }
    out["n_uncropped"] = res.n_uncropped
    return out


def clean_terms(radius: np.ndarray, weights: np.ndarray, settings: CubeSettings) -> constriction.ChunkResult:
    """The oxide-free surface, every spot conducting, on the whole window (exact), at every load step.

    ``radius`` and ``weights`` as in :func:`chunk_terms`: (delta, y, x) gives one map,
    (realization, delta, y, x) one map per realization. The point model's iterative solve runs on
    the smallest centred squares that hold every spot (:meth:`g2tom.physics.spot_geometry.SpotGeometry.spanning`, the whole
    window's system: on the spots bench's 400 drawn asperity maps 1.8 times faster, the mean
    conductance within 1e-14); Greenwood's closed form, one pass, on the whole window.
    """
    n = radius.shape[-1]
    maps = radius.shape[0] if radius.ndim == 4 else 1
    extra = {"groups": np.arange(maps)} if radius.ndim == 4 else {}
    window = SpotGeometry.spanning if settings.model == "point" else SpotGeometry.whole_window
    spots = window(radius, weights, settings.pitch)
    return model(settings)(np.ones((maps, n, n), dtype=bool), spots, settings.rho, settings.method, **extra)


def exact_terms(source: FieldSource, realizations: np.ndarray, radius: np.ndarray, weights: np.ndarray,
                settings: CubeSettings) -> dict[str, Any]:
    """:func:`chunk_terms` of the fields of ``realizations`` at every lambda and xi of ``source``,
    in one batch of masks, on the whole window (no crop: exact). ``radius`` and ``weights`` as
    there (shared, or one map per realization of ``realizations``)."""
    fields = [source.fields(a, realizations) for a in range(len(source.lambdas))]
    psi = np.stack([f[0] for f in fields])  # (lambda, realization, y, x)
    threshold = np.stack([f[1] for f in fields], axis=1)  # (xi, lambda, realization)
    whole = replace(settings, crops=np.full(radius.shape[-3], radius.shape[-1]), tolerance=0.0)
    return chunk_terms(psi, threshold, radius, weights, whole)


def spots_of(settings: CubeSettings, realizations: np.ndarray, radius: np.ndarray,
             weights: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The spot radii and weights the fields of ``realizations`` meet: drawn per realization for
    ``asperities`` spots (:func:`asperity_spots`), else the shared ``radius`` and ``weights``."""
    if settings.spots == "asperities":
        drawn = asperity_spots(settings, realizations)
        return drawn, drawn
    return radius, weights


def field_chunk(
    source: FieldSource, index: int, realizations: np.ndarray, xi_index: np.ndarray,
    radius: np.ndarray, weights: np.ndarray, settings: CubeSettings, limit: int | None = None,
) -> dict[str, Any]:
    """Regenerate the fields of ``realizations`` at lambda number ``index`` and run :func:`chunk_terms`.

    Only the fractions ``xi_index`` are evaluated; returns the terms shaped (xi, delta, realization),
    at every step (``limit`` is the discrete model's: unused here).
    """
    psi, threshold = source.fields(index, realizations)
    radius, weights = spots_of(settings, realizations, radius, weights)
    out = chunk_terms(psi[None], threshold[xi_index][:, None], radius, weights, settings)
    return {k: (v[:, 0] if k in terms(settings) else v) for k, v in out.items()}
