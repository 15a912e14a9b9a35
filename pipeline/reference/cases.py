"""One case of the validation: a surface realization at one load on one grid, solved and stored.

A case solves the full-field contact of the realization's rough sphere at g2tom's force, then the
conductance (Barber's analogy) of the contact set, clean and minus every oxide case's oxide set.
Part 1's cases are on the main grid (and the first realization's clean on the convergence grid);
part 2's ``ensemble`` cases on the ensemble grid. Each finished case is one small JSON file under
``<out>/cases/``, written atomically and keyed by everything that shaped it, so a killed run
continues where it stopped and a changed set recomputes.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from g2tom.reference import elastic, scene, window
from g2tom.reference.contact import ContactReachesEdge, ContactState, contact_at_force, flattened_heights
from g2tom.reference.oxide import oxide_on_grid
from g2tom.reference.punch import punch_conductance
from g2tom.scene import FieldSource
from g2tom.store import atomic_path

__all__ = ["Case", "plan_cases", "ensemble_cases", "pair_cases", "case_key", "load_case", "run_case",
           "barber_stiffness"]

#: The set's fields that shape no case (part 1's realizations and loads are the case's own; part
#: 2's sizes choose which cases run, not what one gives; the device and solver change a result only
#: within the solvers' tolerances, and each record names its own).
UNSHAPING = ("realizations", "models", "discretizations", "convergence_grid", "deltas", "ensemble_grid",
             "max_ensemble", "max_pairs", "model_realizations", "clean_error", "oxide_error", "spot_rule", "device",
             "solver")
#: Relative force step of the two nearby loads whose dF/d(delta) checks Barber's theorem.
BARBER_STEP = 0.01


@dataclass(frozen=True)
class Case:
    """Realization ``realization`` at load step ``load`` on an ``n x n`` grid; ``oxide``: with the oxide
    cases (else clean with Barber's check: the convergence grid); ``ensemble``: part 2's."""

    realization: int
    load: int
    n: int
    oxide: bool
    ensemble: bool = False

    @property
    def name(self) -> str:
        """File stem of the case."""
        return ("e_" if self.ensemble else "") + f"r{self.realization}_load{self.load}_n{self.n}"


def plan_cases(vset: scene.ValidationSet) -> list[Case]:
    """Every case of the set: all realizations and loads on the main grid (clean and oxidized), then
    the first realization's loads on the convergence grid (clean, with the Barber check)."""
    cases = [Case(r, k, vset.n_grid, True) for r in vset.realizations for k in range(len(vset.deltas))]
    if vset.convergence_grid:
        cases += [Case(vset.realizations[0], k, vset.convergence_grid, False) for k in range(len(vset.deltas))]
    return cases


def ensemble_cases(vset: scene.ValidationSet, load: int, realizations: range) -> list[Case]:
    """Part 2's cases of ``realizations`` at load step ``load`` on the ensemble grid (clean and oxidized)."""
    return [Case(r, load, vset.ensemble_grid, True, ensemble=True) for r in realizations]


def pair_cases(vset: scene.ValidationSet, load: int, realizations: range) -> list[Case]:
    """Part 2's added pairs: ``realizations`` at load step ``load`` on the main grid (clean and
    oxidized), the very cases part 1 would solve had the set those realizations."""
    return [Case(r, load, vset.n_grid, True) for r in realizations]


def case_key(vset: scene.ValidationSet, case: Case, force: float, source: FieldSource) -> str:
    """Hash of everything that shapes a case's result (the scene, the oxide fields, the force)."""
    # an elastic set (hardness None) keys its cases as before the hardness existed
    shaping = {k: v for k, v in dataclasses.asdict(vset).items()
               if k not in UNSHAPING and not (k == "hardness" and v is None)}
    shaping["window"] = [window.probe_grid(vset, case.ensemble), window.MARGIN, window.PAD_SPACINGS, window.GROWTH]
    fields = [source.n_cells, source.cell_size, source.seed, source.amplitudes, source.rule,
              [m.period for m in source.modes]]
    text = json.dumps({"set": shaping, "case": dataclasses.asdict(case), "force": float(force).hex(),
                       "fields": fields}, sort_keys=True)
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def load_case(path: Path, key: str) -> dict[str, Any] | None:
    """The stored result at ``path`` if it exists, is readable and has this ``key``; else None."""
    try:
        record = json.loads(path.read_text())
    except (OSError, ValueError):
        return None
    return record if record.get("key") == key else None


def run_case(vset: scene.ValidationSet, case: Case, force: float, source: FieldSource, key: str,
             path: Path) -> dict[str, Any]:
    """Solve one case at ``force`` (N), store it atomically at ``path`` and return its record.

    ``source`` is g2tom's oxide field source of the scene (the fields by seed and realization).

    The case is solved on its own window (:mod:`g2tom.reference.window`: ``side``, m, fitted
    to the probe's contact ``reach``, m). The record holds the force and approach of the
    full-field solution, its contact area (m^2),
    the clean resistance and, for ``case.oxide``, the resistance (xi, lambda) with oxide, in ohm
    (+inf where nothing conducts), the wall times (s) of the contact solve and of the whole case,
    and the case's CPU time (s: its time on a core of its own, what the plan's constants model).
    """
    start, cpu = time.perf_counter(), time.process_time()
    try:
        side, reach = window.fitted_side(vset, case.realization, force, case.ensemble)
        operator, heights, state, side = window.solve_in_window(vset, case.realization, case.n, force, side)
    except (elastic.SolverFailure, ContactReachesEdge) as exc:  # recorded (NaN results, the reason), not fatal
        return _store(path, {"key": key, **dataclasses.asdict(case), "device": vset.device, "solver": vset.solver,
                             "error": str(exc), "force": np.nan,
                             "delta": np.nan, "contact_area": np.nan, "gap_spread": np.nan,
                             "barber_ratio": np.nan, "resistance_clean": np.nan,
                             "resistance": np.full((len(vset.xi), len(vset.lambdas)), np.nan).tolist(),
                             "side": np.nan, "reach": np.nan,
                             "seconds_contact": np.nan, "seconds_total": time.perf_counter() - start,
                             "seconds_cpu": time.process_time() - cpu})
    pixel = side / case.n
    contact_seconds = time.perf_counter() - start
    clean = punch_conductance(operator, state.contact, vset.rho)
    barber = np.nan
    if not case.oxide:  # the convergence grid also checks Barber's theorem: kappa = K / (E* rho*)
        try:
            stiffness = barber_stiffness(operator, heights, state, force, vset.hardness)
            barber = clean.conductance / (stiffness / (vset.e_star * vset.rho))
        except (elastic.SolverFailure, ContactReachesEdge):
            barber = np.nan
    oxidized = np.full((len(vset.xi), len(vset.lambdas)), np.nan)
    if case.oxide:
        for a in range(len(vset.lambdas)):
            masks = oxide_on_grid(source, a, case.realization, case.n, pixel)
            for z in range(len(vset.xi)):
                kappa = punch_conductance(operator, state.contact & ~masks[z], vset.rho).conductance
                oxidized[z, a] = 1.0 / kappa if kappa > 0 else np.inf
    record = {
        "key": key, **dataclasses.asdict(case), "device": vset.device, "solver": vset.solver,
        "force": state.force, "delta": state.delta, "contact_area": float(state.contact.sum()) * pixel**2,
        "side": side, "reach": reach,
        "gap_spread": state.gap_spread, "barber_ratio": barber,
        "resistance_clean": 1.0 / clean.conductance if clean.conductance > 0 else np.inf,
        "resistance": oxidized.tolist(),
        "seconds_contact": contact_seconds,
        "seconds_total": time.perf_counter() - start,
        "seconds_cpu": time.process_time() - cpu,
    }
    return _store(path, record)


def barber_stiffness(operator: elastic.FreeSurface, heights: np.ndarray, state: ContactState, force: float,
                     hardness: float | None) -> float:
    """The stiffness K = dF/d(-delta) (N/m) that Barber's theorem ties to the conductance of ``state``,
    the contact of ``heights`` (m) at ``force`` (N): from two elastic solves at ``force (1 -+
    BARBER_STEP)``, of the heights themselves (elastic), or after a loading capped at ``hardness``
    (Pa) of the flattened heights (:func:`~g2tom.reference.contact.flattened_heights`): the
    unloading stiffness, not the loading slope, which is lower where the pressure sits at H.

    Raises
    ------
    g2tom.reference.elastic.SolverFailure, ContactReachesEdge
        If either solve fails or reaches the grid's edge.
    """
    surface = heights if hardness is None else flattened_heights(operator, heights, state, hardness)
    low, high = (contact_at_force(operator, surface, force * (1.0 + s * BARBER_STEP)) for s in (-1, 1))
    return -(high.force - low.force) / (high.delta - low.delta)


def _store(path: Path, record: dict[str, Any]) -> dict[str, Any]:
    """Write ``record`` to ``path`` atomically (JSON; NaN and Infinity as Python writes them)."""
    with atomic_path(path) as tmp:
        tmp.write_text(json.dumps(record, indent=1) + "\n")
    return record
