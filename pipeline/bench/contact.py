"""Benchmark of stage 1: the Greenwood–Tripp solve over every approach, time against force error.

Times (median of repeated runs) the whole stage build and the solve alone for the Newton
solver and the paper's relaxed fixed point (zeta, epsilon), on the scenario's grid and on the
published study's 20-node grid, and measures each one's largest relative force error against
a grid-converged reference computed in the same run (4x the nodes, Newton to 1e-12). A
uniform grid of the same size shows what the graded grid gains.
"""

from __future__ import annotations

import dataclasses
import time
from typing import Any

import numpy as np

from g2tom.before_work.domains import solve_scenario
from g2tom.bench.timing import median_time
from g2tom.config import Scenario
from g2tom.contact_solution import fields
from g2tom.stages import contact

__all__ = ["run"]

_REPEATS = 5
_REFINEMENT = 4




def _case(scenario: Scenario, solver: str, reference: np.ndarray) -> dict[str, Any]:
    """Time one solver on the scenario's grid; its force error against ``reference`` (N)."""
    seconds, (r, sols) = median_time(lambda: solve_scenario(scenario, solver=solver), _REPEATS)
    force = fields(scenario, r, sols)["force"]
    return {
        "solver": solver,
        "n_radial": len(r),
        "radial_grid": scenario.contact.radial_grid,
        "solve_seconds": round(seconds, 4),
        "force_max_rel_error": float(np.max(np.abs(force / reference - 1))),
        "iterations": [s.iterations for s in sols],
        "iterations_total": int(sum(s.iterations for s in sols)),
        "max_residual": float(max(s.residual for s in sols)),
        "all_converged": all(s.converged for s in sols),
    }


def _with_contact(scenario: Scenario, **changes: Any) -> Scenario:
    """``scenario`` with ``changes`` to its contact section: a plain scenario (``r_max`` may be among them)."""
    return Scenario.of(scenario, contact=dataclasses.replace(scenario.contact, **changes))


def run(scenario: Scenario) -> dict[str, Any]:
    """Time the stage and its solvers and measure force errors; JSON-ready figures."""
    n_ref = _REFINEMENT * scenario.contact.n_radial
    start = time.perf_counter()
    r_ref, sols_ref = solve_scenario(scenario, solver="newton", n_radial=n_ref, tolerance=1e-12)
    reference = fields(scenario, r_ref, sols_ref)["force"]
    ref_seconds = time.perf_counter() - start
    stage_seconds, _ = median_time(lambda: contact.build(scenario), _REPEATS)
    cases = [_case(scenario, solver, reference) for solver in ("newton", "fixed_point")]
    uniform = _with_contact(scenario, radial_grid="uniform")
    cases.append(_case(uniform, "newton", reference))
    published = _with_contact(scenario, n_radial=20, radial_grid="uniform", r_max=0.3)
    cases += [_case(published, solver, reference) for solver in ("newton", "fixed_point")]
    newton, fixed = cases[0], cases[1]
    return {
        "n_delta": scenario.loading.n_delta,
        "stage_build_seconds": round(stage_seconds, 4),
        "reference": {"n_radial": n_ref, "tolerance": 1e-12, "seconds": round(ref_seconds, 3),
                      "force_N": reference.tolist()},
        "cases": cases,
        "fixed_point_over_newton_time": round(fixed["solve_seconds"] / newton["solve_seconds"], 3),
        "targets": {"stage_seconds": 1.0, "force_error": 1e-5},
    }
