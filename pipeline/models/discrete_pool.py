"""The discrete model's contact (:class:`g2tom.models.Discrete`): a pool of rough surfaces, each solved at the
load steps' forces.

The load steps are forces: those the Greenwood–Tripp solution gives at the scenario's approaches,
so both models share the steps and F'. Surface ``k`` of the pool (``contact.surfaces`` of them)
draws its own asperities (:func:`g2tom.physics.discrete_contact.draw_asperities`, stream
``k``) on a disc that holds every asperity able to touch at the heaviest load
(:func:`domain`); :func:`g2tom.physics.discrete_contact.solve_forces` gives its coupled caps
at every force. The contact file keeps, per surface, the asperities that touch at some step
(positions; radius per step, 0 off contact; padded to the largest count with ``spot_count``
saying how many are real), its approach, stiffness K and Barber's conductance K / (E* rho*) per
step, and the solver's report. The work is split over dask tasks of :data:`CHUNK` surfaces;
each surface's result is independent of the chunking and the scheduler.

With ``contact.pool_half_width`` > 0 the pool grows at the light steps (:func:`grow_pool`): the
first ``contact.surfaces`` are solved at every step, further surfaces (the next streams) only up
to the last step whose pool mean of Barber's conductance is still wider than the target, in
rounds, until every step meets it or the pool holds :data:`g2tom.config.MAX_POOL_SURFACES`.
Each surface is solved at a prefix of the steps (``surface_steps``: the solver warm-starts step by step, so a prefix
gives the same numbers as a full solve), and surface ``s`` is solved at step ``i`` exactly when
``s`` is below the pool's size there: at each step the pool is its first surfaces.
"""

from __future__ import annotations

import functools
import warnings
from typing import Any, Callable

import dask
import numpy as np

from g2tom.compute import ComputeOptions, compute
from g2tom import config
from g2tom.config import POOL_CONFIDENCE, Scenario
from g2tom.fitting.ensemble import mean_half_width, z_value
from g2tom.physics import discrete_contact as dc
from g2tom.physics.cap_law import CapLaw, CappedCap, HertzCap
from g2tom.variables import entry

__all__ = ["CHUNK", "DOMAIN_MARGIN", "cap_contact", "domain", "surface_spots", "solve_pool", "grow_pool",
           "pool_half_widths", "variables"]

#: Surfaces per dask task.
CHUNK = 16
#: The disc serves approaches down to the Greenwood–Tripp solution's lowest minus this many sigma
#: (the coupled caps' approach at the same force lies within a fraction of sigma of it).
DOMAIN_MARGIN = 1.0
#: The same margin for caps capped at a hardness, whose approach at a force lies deeper than the elastic
#: layer's (yielding caps carry less at the same interference): 1.02 sigma below it at 10 N on
#: ``gold_connector`` (psi 4.5).
CAPPED_DOMAIN_MARGIN = 4.0
#: Expected number of asperities left outside the disc that could touch at that approach.
DOMAIN_OUTSIDE = 1e-6


def cap_contact(scenario: Scenario) -> tuple[Callable[[np.ndarray], np.ndarray], float]:
    """The least gap (m) above each cap's tip as a function of its distance from the axis, and the
    caps' Hertz radius (m): the cap's exact first contact with the indenter
    (:func:`g2tom.physics.discrete_contact.cap_gap`, :func:`~g2tom.physics.discrete_contact.cap_radius`)."""
    ind, beta = scenario.indenter, scenario.roughness.beta
    gap = functools.partial(dc.cap_gap, shape=ind.shape, beta=beta, radius=ind.radius, cone_angle=ind.cone_angle,
                            punch_radius=ind.punch_radius, edge_radius=ind.edge_radius)
    return gap, dc.cap_radius(ind.shape, beta, radius=ind.radius)


def cap_law(scenario: Scenario) -> CapLaw:
    """The caps' law of force and radius against interference: Hertz's of the caps' Hertz radius
    (:func:`cap_contact`), capped at ``material.hardness`` where it is given (the perfectly plastic
    surface: :class:`g2tom.physics.cap_law.CappedCap`)."""
    beta, hardness = cap_contact(scenario)[1], scenario.material.hardness
    e_star = scenario.material.E_star
    return HertzCap(e_star, beta) if hardness is None else CappedCap(e_star, beta, hardness)


def domain(scenario: Scenario, lowest_delta: float) -> tuple[float, float]:
    """The asperity disc's radius (m) and the lowest approach (m) it serves."""
    rough = scenario.roughness
    margin = DOMAIN_MARGIN if scenario.material.hardness is None else CAPPED_DOMAIN_MARGIN
    served = lowest_delta - margin * rough.sigma
    return dc.domain_radius(cap_contact(scenario)[0], served, rough.sigma, rough.eta, DOMAIN_OUTSIDE), served


def surface_spots(settings: dict[str, Any], k: int) -> dict[str, np.ndarray]:
    """Surface ``k``'s touching asperities and its solution at every force (see the module).

    Raises
    ------
    ValueError
        If the solved approach falls below the one the disc serves (asperities may be missing).
    """
    asp = dc.draw_asperities(settings["seed"], k, settings["radius"], settings["eta"], settings["sigma"])
    sol = dc.solve_forces(asp, settings["profile"], settings["forces"][: settings.get("steps")], settings["e_star"],
                          settings["beta"], settings["floor"], cap=settings["cap"])
    if sol.delta.min() < settings["served"]:
        raise ValueError(f"surface {k}: the approach {sol.delta.min():.4g} m falls below the "
                         f"{settings['served']:.4g} m its asperity disc serves")
    touching = np.flatnonzero((sol.interference > 0).any(axis=0))
    return {"x": asp.x[touching], "y": asp.y[touching], "radius": sol.radii[:, touching],
            "delta": sol.delta, "stiffness": sol.stiffness, "unloading_stiffness": sol.unloading_stiffness,
            "iterations": sol.iterations,
            "residual": sol.residual, "candidates": sol.candidates}


def _chunk(settings: dict[str, Any], surfaces: np.ndarray) -> list[dict[str, np.ndarray]]:
    return [surface_spots(settings, int(k)) for k in surfaces]


def _solve(shared: Any, first: int, stop: int, options: ComputeOptions, label: str) -> list[dict[str, np.ndarray]]:
    """Surfaces ``first`` to ``stop - 1`` in dask tasks of :data:`CHUNK`."""
    tasks = [dask.delayed(_chunk, pure=True)(shared, np.arange(s, min(s + CHUNK, stop)))
             for s in range(first, stop, CHUNK)]
    return [r for chunk in compute(*tasks, options=options, label=label) for r in chunk]


def solve_pool(scenario: Scenario, forces: np.ndarray, lowest_delta: float,
               options: ComputeOptions) -> tuple[list[dict[str, np.ndarray]], float]:
    """Every surface of the pool at ``forces`` (N), grown where ``contact.pool_half_width`` asks
    (:func:`grow_pool`); returns the per-surface results and the disc radius (m)."""
    rough = scenario.roughness
    radius, served = domain(scenario, lowest_delta)
    cap_profile, cap_radius = cap_contact(scenario)
    settings = {"seed": scenario.oxide.seed, "radius": radius, "served": served, "eta": rough.eta,
                "sigma": rough.sigma, "beta": cap_radius, "e_star": scenario.material.E_star,
                "profile": cap_profile, "forces": np.asarray(forces, float),
                "floor": dc.coupling_floor(rough.beta, rough.sigma), "cap": cap_law(scenario)}
    n = scenario.contact.surfaces
    pool = _solve(dask.delayed(settings), 0, n, options, f"contact: {n} discrete surfaces")
    target = scenario.contact.pool_half_width
    if target > 0:
        pool = grow_pool(pool, target, lambda first, stop, steps: _solve(
            dask.delayed({**settings, "steps": steps}), first, stop, options,
            f"contact: pool surfaces {first}-{stop - 1} at the {steps} lightest steps"))
    _warn_no_yield(settings["cap"], pool)
    _warn_overlap(settings["cap"], pool, settings["forces"])
    return pool, radius


def _warn_no_yield(cap: CapLaw, pool: list[dict[str, np.ndarray]]) -> None:
    """One warning where the caps are capped at a hardness that none of them reaches at any load
    (every contact radius below first yield's): the answer is the elastic one."""
    if not isinstance(cap, CappedCap):
        return
    largest = max(float(r["radius"].max(initial=0.0)) for r in pool)
    if largest < cap.a_c:
        warnings.warn(f"material.hardness = {cap.hardness:g} Pa: no cap of the pool reaches first yield at any load "
                      f"(largest contact radius {largest:.3g} m, first yield at {cap.a_c:.3g} m): the answer is the "
                      "elastic one", stacklevel=4)


#: Share of touching caps whose contact disc overlaps a neighbour's above which capped caps are
#: warned about by the contact stage.
OVERLAP_SHARE = 0.1


def overlap_shares(pool: list[dict[str, np.ndarray]]) -> np.ndarray:
    """Share of the pool's touching caps whose contact disc overlaps another's (``a_i + a_j > d_ij``) at
    every step (NaN where none touches)."""
    steps = pool[0]["delta"].size
    overlapping, touching = np.zeros(steps), np.zeros(steps)
    for r in pool:
        d = np.hypot(r["x"][:, None] - r["x"][None, :], r["y"][:, None] - r["y"][None, :])
        np.fill_diagonal(d, np.inf)
        for k, a in enumerate(r["radius"]):
            on = a > 0
            touching[k] += on.sum()
            overlapping[k] += ((a[:, None] + a[None, :] > d) & on[:, None] & on[None, :]).any(axis=1).sum()
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(touching > 0, overlapping / np.maximum(touching, 1), np.nan)


def _warn_overlap(cap: CapLaw, pool: list[dict[str, np.ndarray]], forces: np.ndarray) -> None:
    """One warning where capped caps flatten into their neighbours: from the lightest step at which more
    than :data:`OVERLAP_SHARE` of the touching caps overlap another's disc, the discrete model counts
    merged contacts as separate spots (and its point solve takes the slow path of indefinite
    matrices)."""
    if not isinstance(cap, CappedCap):
        return
    shares = overlap_shares(pool)
    crowded = np.flatnonzero(shares > OVERLAP_SHARE)
    if crowded.size:
        k = int(crowded[0])
        warnings.warn(f"capped caps overlap: from {forces[k]:.4g} N (step {k + 1}) {100 * shares[k]:.0f} % of the "
                      f"touching caps' discs overlap a neighbour's ({100 * np.nanmax(shares):.0f} % at most), where "
                      "the discrete model counts merged contacts as separate spots: its R is too high there "
                      "(g2tom validate measures by how much) and its cube is slow", stacklevel=4)


def pool_half_widths(pool: list[dict[str, np.ndarray]]) -> np.ndarray:
    """Relative half-width (:data:`g2tom.config.POOL_CONFIDENCE`) of the pool's mean Barber conductance
    (its unloading stiffness) at every step, over the surfaces solved there (NaN where no surface touches)."""
    width = pool[0]["delta"].size
    stiffness = np.full((len(pool), width), np.nan)
    for k, r in enumerate(pool):
        stiffness[k, : r["unloading_stiffness"].size] = r["unloading_stiffness"]
    return mean_half_width(stiffness, z_value(POOL_CONFIDENCE))


def grow_pool(pool: list[dict[str, np.ndarray]], target: float,
              solve: Callable[[int, int, int], list[dict[str, np.ndarray]]]) -> list[dict[str, np.ndarray]]:
    """The pool grown until its mean clean conductance meets ``target`` at every step.

    Parameters
    ----------
    pool
        The surfaces solved so far (each at every step, or at a prefix of them).
    target
        Relative half-width (:data:`g2tom.config.POOL_CONFIDENCE`) wanted at every step.
    solve
        ``solve(first, stop, steps)``: surfaces ``first`` to ``stop - 1`` at the ``steps`` lightest
        forces, in :func:`surface_spots`'s form.

    Returns
    -------
    list of dict
        The pool: each round adds the surfaces the widest short step is estimated to need
        (``n (w / target)^2``, at least :data:`CHUNK`, to at most
        :data:`g2tom.config.MAX_POOL_SURFACES`), solved up to the last short step. Steps beyond
        it are not short and their surfaces do not change, so the solved prefixes shrink from round
        to round and the pool at every step is its first surfaces.
    """
    while len(pool) < config.MAX_POOL_SURFACES:
        widths = pool_half_widths(pool)
        short = np.flatnonzero(widths > target)
        if short.size == 0:
            break
        steps = int(short[-1]) + 1
        counts = np.array([sum(r["delta"].size > i for r in pool) for i in short])
        wanted = int(np.max(np.ceil(counts * (widths[short] / target) ** 2)))
        stop = min(config.MAX_POOL_SURFACES, max(wanted, len(pool) + CHUNK))
        pool = pool + solve(len(pool), stop, steps)
    return pool


def _var(name: str, data: np.ndarray) -> tuple:
    """A variable of contact.nc's pool: dims, units and long name from the schema."""
    var = entry(f"stages.contact.{name}")
    return (var.dims, np.asarray(data), var.attrs())


def variables(scenario: Scenario, pool: list[dict[str, np.ndarray]], radius: float) -> tuple[dict, dict, dict]:
    """The pool's variables, coordinates and attributes for contact.nc (spots padded: NaN
    positions, zero radii beyond ``spot_count``)."""
    n_s, n_d = len(pool), pool[0]["delta"].size
    width = max(1, max(r["x"].size for r in pool))
    x, y = np.full((n_s, width), np.nan), np.full((n_s, width), np.nan)
    spot_radius = np.zeros((n_s, n_d, width))
    solved = np.array([r["delta"].size for r in pool], np.int32)
    for k, r in enumerate(pool):
        m = r["x"].size
        x[k, :m], y[k, :m], spot_radius[k, : solved[k], :m] = r["x"], r["y"], r["radius"]
    stacked = {}  # steps a surface was not solved at: NaN (counts -1)
    for name in ("delta", "stiffness", "unloading_stiffness", "iterations", "residual", "candidates"):
        stacked[name] = np.full((n_s, n_d), -1 if name in ("iterations", "candidates") else np.nan)
        for k, r in enumerate(pool):
            stacked[name][k, : solved[k]] = r[name]
    e_star, rho = scenario.material.E_star, scenario.material.rho
    data_vars = {
        "spot_count": _var("spot_count", np.array([r["x"].size for r in pool], np.int32)),
        "asperity_x": _var("asperity_x", x),
        "asperity_y": _var("asperity_y", y),
        "asperity_radius": _var("asperity_radius", spot_radius),
        "discrete_approach": _var("discrete_approach", stacked["delta"]),
        "discrete_stiffness": _var("discrete_stiffness", stacked["stiffness"]),
        "discrete_barber_conductance": _var("discrete_barber_conductance",
                                            stacked["unloading_stiffness"] / (e_star * rho)),
        "discrete_iterations": _var("discrete_iterations", stacked["iterations"].astype(np.int32)),
        "discrete_residual": _var("discrete_residual", stacked["residual"]),
        "discrete_candidates": _var("discrete_candidates", stacked["candidates"].astype(np.int32)),
    }
    if np.any(solved < n_d):  # a grown pool (contact.pool_half_width)
        data_vars["surface_steps"] = _var("surface_steps", solved)
    coords = {"surface": _var("surface", np.arange(n_s)), "spot": _var("spot", np.arange(width))}
    attrs = {"asperity_disc_radius": radius,
             "coupling_floor": dc.coupling_floor(scenario.roughness.beta, scenario.roughness.sigma),
             "discrete_tolerance": dc.TOLERANCE}
    return data_vars, coords, attrs
