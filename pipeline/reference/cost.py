"""The validation's cost before work: how many cases of which grid, and how long they take.

A case costs its probe (a contact solve on the probe grid, :func:`pipeline.reference.window.probe_grid`),
its contact solve(s) and its punch conductances (clean and one per oxide case; the convergence
case solves the contact three times for Barber's check and one punch). One contact solve and one
punch on an n x n grid at F' cost :data:`CONTACT_SECONDS` and :data:`PUNCH_SECONDS`, interpolated in
(ln F', ln s) between the lightest and heaviest default load, scaled by (n / n_table)^3 from the
nearest measured grid (CG and Polonsky-Keer iterations grow about as n, each costs ~n^2 log n).
Cases run on ``workers`` processes: the wall time is their summed time over the workers (at
least the longest case). g2tom's side runs in the driver before the cases: part 1's
discretizations (:data:`G2TOM_SECONDS` each), part 2's validated scenario (the project's own plan,
:func:`pipeline.before_work.plan.estimate`, for its contact, oxide and cube stages) and, on the GW
surface, the stand-in (:data:`STAND_IN_SECONDS` per realization and load).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from pipeline.reference import cases as cases_mod
from pipeline.reference import ensemble, scene, window

__all__ = ["CONTACT_SECONDS", "PUNCH_SECONDS", "G2TOM_SECONDS", "STAND_IN_SECONDS", "LIGHT_HEAVY", "Estimate",
           "case_seconds", "estimate"]

#: The F' of the table's light and heavy columns (the default set's lightest and heaviest loads).
LIGHT_HEAVY = (0.0752, 18.8)
#: One full-field contact solve on a case's fitted window (GW default set, realization 0, one
#: process), s, at (lightest, heaviest) load, by grid: measured 2026-11-27 on the shared 2-core
#: machine while two other processes ran (load average ~5): upper ends.
CONTACT_SECONDS = {128: (0.20, 0.63), 256: (0.82, 4.3), 512: (16.7, 24.8), 1024: (39.9, 80.0)}
#: One punch conductance (CG) on the same grids and loads, s, measured with the contact solves.
PUNCH_SECONDS = {128: (0.02, 0.15), 256: (0.36, 1.2), 512: (4.0, 11.0), 1024: (10.6, 29.0)}
#: g2tom's part 1, per (discretization, model), s (its contact, oxide and cube stages in memory).
G2TOM_SECONDS = 4.0
#: The stand-in (the discrete solve of one surface's own caps and its resistances), s per realization and load.
STAND_IN_SECONDS = 3e-3


def _table(table: dict[int, tuple[float, float]], n: int, force_normalized: float) -> float:
    ref = min(table, key=lambda m: abs(math.log(m / n)))
    light, heavy = table[ref]
    t = (math.log(max(force_normalized, 1e-9)) - math.log(LIGHT_HEAVY[0])) / math.log(LIGHT_HEAVY[1] / LIGHT_HEAVY[0])
    t = min(max(t, 0.0), 1.0)
    return math.exp((1 - t) * math.log(light) + t * math.log(heavy)) * (n / ref) ** 3


def case_seconds(vset: scene.ValidationSet, case: cases_mod.Case, force_normalized: float) -> float:
    """The estimated time of one case, s (see the module docstring)."""
    probe = _table(CONTACT_SECONDS, window.probe_grid(vset, case.ensemble), force_normalized)
    contact = _table(CONTACT_SECONDS, case.n, force_normalized)
    punch = _table(PUNCH_SECONDS, case.n, force_normalized)
    if not case.oxide:
        return probe + 3 * contact + punch
    return probe + contact + (1 + len(vset.xi) * len(vset.lambdas)) * punch


@dataclass(frozen=True)
class Estimate:
    """The plan of one validation, before work.

    Attributes
    ----------
    part1, convergence
        Part 1's cases on the main grid and on the convergence grid.
    ensemble_counts
        Part 2's first-round full-field realizations per load from the prior scatter (those beyond
        part 1's solve ensemble cases; on the GW surface the stand-in can only lower them).
    ensemble
        Part 2's first-round ensemble cases.
    seconds_part1, seconds_part2, seconds_g2tom
        Summed case times of each part (s, one process) and g2tom's side (s).
    wall
        Estimated wall time on ``workers`` processes, s.
    """

    part1: int
    convergence: int
    ensemble_counts: np.ndarray
    ensemble: int
    seconds_part1: float
    seconds_part2: float
    seconds_g2tom: float
    wall: float


def estimate(vset: scene.ValidationSet, force_normalized: np.ndarray, workers: int,
             model_seconds: float) -> Estimate:
    """The plan's estimate (no case stored yet) at the loads' F' on ``workers`` processes;
    ``model_seconds``: the validated scenario's stages on the validation scene (s)."""
    part1 = cases_mod.plan_cases(vset)
    counts = ensemble.prior_counts(vset, force_normalized).max(axis=0)
    P = len(vset.realizations)
    extra = [c for k, n in enumerate(counts) if n > P for c in cases_mod.ensemble_cases(vset, k, range(n))]
    seconds = [case_seconds(vset, c, float(force_normalized[c.load])) for c in part1 + extra]
    s1, s2 = sum(seconds[:len(part1)]), sum(seconds[len(part1):])
    stand = STAND_IN_SECONDS * len(force_normalized) * int(counts.max()) if vset.surface == "gw" else 0.0
    g2tom = G2TOM_SECONDS * len(vset.discretizations) * len(vset.models) + model_seconds + stand
    wall = g2tom + max((s1 + s2) / max(workers, 1), max(seconds, default=0.0))
    return Estimate(part1=sum(c.oxide for c in part1), convergence=sum(not c.oxide for c in part1),
                    ensemble_counts=counts, ensemble=len(extra), seconds_part1=s1, seconds_part2=s2,
                    seconds_g2tom=g2tom, wall=wall)
