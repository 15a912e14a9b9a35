"""Benchmark of the discrete model: the coupled-cap solve per (surface, load) and the cube's cost per map.

On the scenario's scene with ``contact.model = "discrete"``, at the Greenwood–Tripp forces of its
approaches:

* the contact solve of each of :data:`SURFACES` surfaces over every load step (candidates grown
  as needed, warm starts), its median time per (surface, load), against the same solve on every
  asperity of the disc (no candidate selection: the slow exact reference) on the first
  :data:`REFERENCE_SURFACES`, with the largest differences in approach and in resistance;
* the cube's work per oxide map (one field at one lambda: every xi at every load step) on the
  pool, for both spot rules and both resistance models, median over :data:`MAPS` maps;
* the point model's large unions (the atlas's scenes at Pi 320 reach 2,000-6,000 touching caps,
  the default ~200): on one solved surface of a scene at :data:`LARGE_SCENE`, the steps of about
  :data:`LARGE_UNIONS` conducting spots with every oxide fraction of one field, conjugate
  gradients against the factorizations in the same process (median of :data:`LARGE_REPEATS`,
  their ratio) and the largest relative difference of ``1^T f``.
"""

from __future__ import annotations

import dataclasses
import statistics
import time
from typing import Any

import numpy as np

from g2tom.compute import ComputeOptions
from g2tom.models import Discrete
from g2tom.config import ResolvedScenario, Scenario
from g2tom.before_work.domains import resolve, solve_scenario
from g2tom.contact_solution import fields
from g2tom.physics import discrete_contact as dc
from g2tom.physics import oxide_band
from g2tom.physics.discrete_resistance import ITERATIVE, currents, resistances
from g2tom.physics.spot_share import RULES, effective_radius
from g2tom.scene import FieldSource
from g2tom.models import discrete_cube, discrete_pool
from g2tom.stages import contact, cube

__all__ = ["run"]

SURFACES = 24
REFERENCE_SURFACES = 3
MAPS = 12
#: The scene of the large unions (mu, Pi: the atlas's d22, up to ~2,000 touching caps), the union
#: sizes timed, and timed solves of each (the median is reported).
LARGE_SCENE = (7.071, 320.0)
LARGE_UNIONS = (400, 1000, 2000)
LARGE_REPEATS = 3


def _discrete(scenario: Scenario) -> ResolvedScenario:
    return resolve(dataclasses.replace(
        scenario, contact=dataclasses.replace(scenario.contact, model=Discrete.name, surfaces=SURFACES)))


def _solve(settings: dict[str, Any], k: int, all_candidates: bool = False) -> tuple[float, dc.DiscreteContact, Any]:
    asp = dc.draw_asperities(settings["seed"], k, settings["radius"], settings["eta"], settings["sigma"])
    start = time.perf_counter()
    sol = dc.solve_forces(asp, settings["profile"], settings["forces"], settings["e_star"], settings["beta"],
                          settings["floor"], all_candidates=all_candidates)
    return time.perf_counter() - start, sol, asp


def _contact(scenario: Scenario) -> tuple[dict[str, Any], np.ndarray]:
    r, sols = solve_scenario(scenario)
    forces = fields(scenario, r, sols)["force"]
    radius, served = discrete_pool.domain(scenario, min(scenario.deltas))
    rough = scenario.roughness
    cap_profile, cap_radius = discrete_pool.cap_contact(scenario)
    settings = {"seed": scenario.oxide.seed, "radius": radius, "eta": rough.eta, "sigma": rough.sigma,
                "beta": cap_radius, "e_star": scenario.material.E_star, "profile": cap_profile,
                "forces": forces, "floor": dc.coupling_floor(rough.beta, rough.sigma)}
    per_load, iterations, candidates, touching = [], [], [], []
    for k in range(SURFACES):
        seconds, sol, _ = _solve(settings, k)
        per_load.append(seconds / forces.size)
        iterations.append(float(sol.iterations.mean()))
        candidates.append(int(sol.candidates.max()))
        touching.append(int((sol.load[-1] > 0).sum()))
    reference = []
    for k in range(REFERENCE_SURFACES):
        fast_seconds, fast, asp = _solve(settings, k)
        slow_seconds, slow, _ = _solve(settings, k, all_candidates=True)
        kernel = dc.interaction_kernel(asp.x, asp.y, settings["floor"])
        rho = scenario.material.rho
        r_fast = resistances(kernel, fast.radii, rho)
        r_slow = resistances(kernel, slow.radii, rho)
        reference.append({"surface": k, "asperities": asp.size, "seconds": round(fast_seconds, 4),
                          "all_candidates_seconds": round(slow_seconds, 4),
                          "speedup": round(slow_seconds / fast_seconds, 2),
                          "max_approach_difference_m": float(np.max(np.abs(fast.delta - slow.delta))),
                          "max_resistance_rel_difference": float(np.max(np.abs(r_fast / r_slow - 1)))})
    figures = {
        "surfaces": SURFACES, "load_steps": int(forces.size),
        "force_normalized_range": [float(forces[0] / scenario.force_scale), float(forces[-1] / scenario.force_scale)],
        "asperity_disc_radius_m": settings["radius"],
        "median_seconds_per_surface_load": round(statistics.median(per_load), 5),
        "max_seconds_per_surface_load": round(max(per_load), 5),
        "mean_newton_iterations_per_load": round(statistics.mean(iterations), 2),
        "candidates_at_heaviest_load_median": int(statistics.median(candidates)),
        "touching_at_heaviest_load_median": int(statistics.median(touching)),
        "reference_all_candidates": reference,
        "target_median_seconds_per_surface_load": 0.020,
    }
    return figures, forces


def _maps(scenario: ResolvedScenario) -> list[dict[str, Any]]:
    pool_ds = contact.build(scenario, ComputeOptions(progress=False))
    pool, _, base = cube.work_settings(scenario, pool_ds)
    source = FieldSource.of(scenario)
    xi = np.arange(len(scenario.oxide.xi))
    out = []
    for rule in RULES:
        for model in ("point", "greenwood"):
            settings = dataclasses.replace(base, model=model, spot_rule=rule)
            for index, lam in enumerate(scenario.oxide.lambda_):
                if lam not in (min(scenario.oxide.lambda_), max(scenario.oxide.lambda_)):
                    continue
                times = []
                for k in range(MAPS):
                    start = time.perf_counter()
                    discrete_cube.discrete_chunk(source, index, np.array([k]), xi, pool, settings)
                    times.append(time.perf_counter() - start)
                out.append({"spot_rule": rule, "model": model, "lambda": lam, "xi_values": int(xi.size),
                            "median_seconds_per_map": round(statistics.median(times), 5)})
    return out


def _large_unions(scenario: ResolvedScenario) -> list[dict[str, Any]]:
    """Conjugate gradients against the factorizations on the steps of one solved surface of a scene
    at :data:`LARGE_SCENE` (mu, Pi), the scenario's sigma and R* (loads spanning F' 0.05-20, as an
    atlas scene): at the steps whose union of conducting spots is nearest each of
    :data:`LARGE_UNIONS`, every oxide fraction of the first field at the smallest and largest lambda."""
    from g2tom.atlas.design import Scene, scene_scenario

    mu, pi = LARGE_SCENE
    big = scene_scenario(scenario, Scene("bench", mu, pi, False))
    big = resolve(dataclasses.replace(big, contact=dataclasses.replace(big.contact, surfaces=1)))
    pool, _, _ = cube.work_settings(big, contact.build(big, ComputeOptions(progress=False)))
    x, y, radius = pool.spots(0)
    kernel = pool.kernel(0)
    source = FieldSource.of(big)
    out = []
    for index, lam in enumerate(source.lambdas):
        if lam not in (min(source.lambdas), max(source.lambdas)):
            continue
        modes = source.modes[index]
        coeffs = oxide_band.coefficients(modes, oxide_band.field_stream(source.seed, lam, 0), source.amplitudes)
        share = discrete_cube.clean_shares(modes, coeffs, x, y, radius, source.thresholds(index, np.array([0]))[:, 0],
                                           big.oxide.spot_rule, lam * source.cell_size)
        radii = effective_radius(radius[None], share, big.oxide.spot_rule)  # (xi, delta, spot)
        unions = (radii > 0).any(axis=0).sum(axis=-1)
        for n in LARGE_UNIONS:
            step = int(np.argmin(np.abs(unions - n)))
            sets = np.ascontiguousarray(radii[:, step:step + 1])
            seconds, totals, paths = {}, {}, {}
            for name, start_at in (("iterative", 1), ("factorized", int(unions[step]) + 1)):
                times = []
                for _ in range(LARGE_REPEATS):
                    start = time.perf_counter()
                    totals[name], paths[name] = currents(kernel, sets, iterative_from=start_at)
                    times.append(time.perf_counter() - start)
                seconds[name] = statistics.median(times)
            live = totals["factorized"] > 0
            out.append({"lambda": lam, "union": int(unions[step]), "sets": int(sets.shape[0]),
                        "iterative_path": bool(paths["iterative"][0] == ITERATIVE),
                        "median_seconds_iterative": round(seconds["iterative"], 5),
                        "median_seconds_factorized": round(seconds["factorized"], 5),
                        "ratio_factorized_to_iterative": round(seconds["factorized"] / seconds["iterative"], 3),
                        "max_relative_difference": float(np.max(np.abs(totals["iterative"][live]
                                                                       / totals["factorized"][live] - 1.0)))})
    return out


def run(scenario: Scenario) -> dict[str, Any]:
    """Time the discrete contact solve, the cube's work per map and the point model's large unions;
    JSON-ready figures."""
    discrete = _discrete(scenario)
    figures, _ = _contact(discrete)
    return {"contact": figures, "cube_per_map": _maps(discrete), "large_unions": _large_unions(discrete)}
