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
from g2tom.errors import SolveError
from g2tom.physics.cap_law import CapLaw, CappedCap, HertzCap
from g2tom.variables import entry

__all__ = ["CHUNK", "DOMAIN_MARGIN", "CAPPED_DOMAIN_MARGIN", "cap_contact", "domain", "capped_disc",
           "surface_spots", "solve_pool", "grow_pool", "pool_half_widths", "variables"]

#: Surfaces per dask task.
CHUNK = 16
#: The disc serves approaches down to the Greenwood–Tripp solution's lowest minus this many sigma
#: (the coupled caps' approach at the same force lies within a fraction of sigma of it).
DOMAIN_MARGIN = 1.0
#: Caps capped at a hardness sink deeper than the elastic layer by an amount the layer does not know
#: (yielding caps carry less at the same interference, and flattened caps share their discs: 1 sigma
#: at psi 4.5, 6 sigma at psi 50): their disc serves this many sigma below the lowest approach of
#: surface 0 solved first on the elastic layer's disc (:func:`capped_disc`).
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
    """The asperity disc's radius (m) and the lowest approach (m) it serves: :data:`DOMAIN_MARGIN` sigma
    below ``lowest_delta`` (m)."""
    return _disc(scenario, lowest_delta - DOMAIN_MARGIN * scenario.roughness.sigma)


def _disc(scenario: Scenario, served: float) -> tuple[float, float]:
    """The asperity disc's radius (m) that serves approaches down to ``served`` (m), and ``served``."""
    rough = scenario.roughness
    return dc.domain_radius(cap_contact(scenario)[0], served, rough.sigma, rough.eta, DOMAIN_OUTSIDE), served


def capped_disc(scenario: Scenario, settings: dict[str, Any]) -> tuple[dict[str, Any], dict[str, np.ndarray]]:
    """The disc of capped caps, from surface 0's own solve: the settings with the disc that serves
    :data:`CAPPED_DOMAIN_MARGIN` sigma below the lowest approach of surface 0 solved on the elastic
    layer's disc, and surface 0's solution on that disc (:func:`surface_spots`).

    Raises
    ------
    g2tom.errors.SolveError
        As :func:`surface_spots`.
    """
    pilot = _surface_solution(settings, 0)[1]
    radius, served = _disc(scenario, float(pilot.delta.min()) - CAPPED_DOMAIN_MARGIN * scenario.roughness.sigma)
    settings = {**settings, "radius": radius, "served": served}
    return settings, surface_spots(settings, 0)


def surface_spots(settings: dict[str, Any], k: int) -> dict[str, np.ndarray]:
    """Surface ``k``'s touching asperities and its solution at every force (see the module).

    Raises
    ------
    g2tom.errors.SolveError
        If the solve does not converge, or its approach falls below the one the disc serves
        (asperities may be missing).
    """
    asp, sol = _surface_solution(settings, k)
    if sol.delta.min() < settings["served"]:
        raise SolveError(f"contact: pool surface {k} sinks to the approach {sol.delta.min():.4g} m, below the "
                         f"{settings['served']:.4g} m its asperity disc serves (asperities may be missing)")
    touching = np.flatnonzero((sol.interference > 0).any(axis=0))
    return {"x": asp.x[touching], "y": asp.y[touching], "radius": sol.radii[:, touching],
            "delta": sol.delta, "stiffness": sol.stiffness, "unloading_stiffness": sol.unloading_stiffness,
            "iterations": sol.iterations,
            "residual": sol.residual, "candidates": sol.candidates}


def _surface_solution(settings: dict[str, Any], k: int) -> tuple[dc.Asperities, dc.DiscreteContact]:
    """Surface ``k``'s asperities on the settings' disc and its solution at every force.

    Raises
    ------
    g2tom.errors.SolveError
        If the solve does not converge.
    """
    asp = dc.draw_asperities(settings["seed"], k, settings["radius"], settings["eta"], settings["sigma"])
    try:
        return asp, dc.solve_forces(asp, settings["profile"], settings["forces"][: settings.get("steps")],
                                    settings["e_star"], settings["beta"], settings["floor"], cap=settings["cap"])
    except dc.NotConverged as exc:
        raise SolveError(f"contact: the discrete solve of pool surface {k} did not converge ({exc})") from None


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
    first: list[dict[str, np.ndarray]] = []
    if scenario.material.hardness is not None:
        settings, pilot = capped_disc(scenario, settings)
        first, radius = [pilot], settings["radius"]
    pool = first + _solve(dask.delayed(settings), len(first), n, options, f"contact: {n} discrete surfaces")
    target = scenario.contact.pool_half_width
    if target > 0:
        pool = grow_pool(pool, target, lambda first, stop, steps: _solve(
            dask.delayed({**settings, "steps": steps}), first, stop, options,
            f"contact: pool surfaces {first}-{stop - 1} at the {steps} lightest steps"))
    _warn_no_yield(settings["cap"], pool)
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
