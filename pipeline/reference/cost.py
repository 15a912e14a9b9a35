"""The validation's cost before work: how many cases of which grid, and how long they take.

A case costs its probe (a contact solve on the probe grid, :func:`g2tom.reference.window.probe_grid`),
its contact solve(s) and its punch conductances (clean and one per oxide case; the convergence
case solves the contact three times for Barber's check and one punch). One contact solve and one
punch on an n x n grid at F' cost :data:`CONTACT_SECONDS` and :data:`PUNCH_SECONDS` (CPU seconds
of one process: the wall time on a core of its own), interpolated in (ln F', ln s) between the
lightest and heaviest default load, scaled by (n / n_table)^3 from the nearest measured grid (CG
and Polonsky-Keer iterations grow about as n, each costs ~n^2 log n). Cases run on ``workers``
processes: the wall time is their summed time over the workers (at least the longest case).
Part 2's later rounds size the ensembles from the measured scatter: the estimate is the first
round's (from the prior scatter of the realizations and of the pairs,
:func:`g2tom.reference.ensemble.prior_allocation`), and ``wall_cap`` the bound with every load at
``max_ensemble`` proxies and ``max_pairs`` pairs (:func:`case_costs`: what a pair and a proxy cost). g2tom's side runs in the driver before the cases: part 1's
discretizations (:data:`G2TOM_SECONDS` each), part 2's validated scenario (the project's own plan,
:func:`g2tom.before_work.plan.estimate`, for its contact, oxide and cube stages) and, on the GW
surface, the stand-in (:data:`STAND_IN_SECONDS` per realization and load).

The tables are tamaas'. g2tom's own solver on the CPU (``--solver g2tom``) takes them divided by
:data:`G2TOM_CPU_SPEEDUP`; on a GPU (``--device gpu``) a solve costs about the same at every grid
up to 1024^2 (its iterations' kernel launches, not its FFTs, set the time there):
:data:`GPU_CONTACT_SECONDS` and :data:`GPU_PUNCH_SECONDS`, scaled by (n / 1024)^2 above, plus
:data:`GPU_CASE_SECONDS` of the CPU's work per case (heights, oxide masks).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from g2tom.reference import cases as cases_mod
from g2tom.reference import ensemble, scene, window

__all__ = ["CONTACT_SECONDS", "PUNCH_SECONDS", "G2TOM_SECONDS", "STAND_IN_SECONDS", "LIGHT_HEAVY", "Estimate", "case_costs",
           "G2TOM_CPU_SPEEDUP", "GPU_CONTACT_SECONDS", "GPU_PUNCH_SECONDS", "GPU_CASE_SECONDS", "case_seconds",
           "estimate"]

#: The F' of the tables' light and heavy columns (the default sets' lightest and heaviest loads).
LIGHT_HEAVY = (0.07, 18.8)
#: One full-field contact solve on a case's fitted window (its probe: on the set's window), CPU
#: seconds of one single-threaded process, at the (lightest, heaviest) load of the default set,
#: by surface and grid: realization 0's probe (:func:`window.fitted_side`), then
#: :func:`window.solve_in_window` and one :func:`g2tom.reference.punch.punch_conductance` per grid, timed by
#: ``time.process_time`` (2026-11-27, on the shared 2-core machine, whose wall time was twice the
#: CPU time then: other work shared the cores). A 1024^2 case of the old default's three loads
#: costs ~96 s by these tables; the quiet machine took 79 s a case on 2026-11-24 (README). The
#: random-process surface's 249^2 entry is its probe (two pixels per shortest wavelength over the
#: set's window).
CONTACT_SECONDS = {
    "gw": {128: (0.18, 0.20), 256: (0.86, 1.15), 512: (5.61, 7.79), 1024: (30.6, 45.1)},
    "random_process": {249: (2.87, 3.49), 256: (0.68, 0.92), 512: (5.26, 7.42), 1024: (29.9, 52.0)},
}
#: One punch conductance (CG to 1e-7) on the same windows, CPU seconds, measured with the contact solves.
PUNCH_SECONDS = {
    "gw": {128: (0.03, 0.05), 256: (0.16, 0.30), 512: (1.35, 2.53), 1024: (7.29, 14.6)},
    "random_process": {256: (0.11, 0.26), 512: (0.88, 2.03), 1024: (6.27, 12.0)},
}
#: g2tom's part 1, per (discretization, model), s (its contact, oxide and cube stages in memory at 8
#: loads: 15 s for the GW set's 10 on the loaded machine).
G2TOM_SECONDS = 2.0
#: The stand-in (the discrete solve of one surface's own caps and its resistances, the contact stage
#: included), s per realization and load: 5.0 s for 64 realizations at 8 loads on the loaded machine.
STAND_IN_SECONDS = 1e-2
#: The tables' (tamaas') time of a case over g2tom's own solver's CPU time on NumPy. Measured twice
#: on the 2-core machine, 2026-11-27: 1.88-2.10 over the default GW set's first 12 part-1 cases on
#: 1024^2 (tamaas and ours on the same cases, a loaded machine); then the tables over the CPU
#: medians of the eight-surface default sets' cases (a quiet machine): 2.41-2.61 (GW) and 2.49-2.76
#: (random process) per load on 1024^2, which carry most of the time; 1.7-1.9 (GW) and 2.8-2.9
#: (random process, its 249^2 probe) on the 256^2 ensemble grid. 2.5 puts the plan within ~10 % of
#: both default sets' measured totals.
G2TOM_CPU_SPEEDUP = 2.5
#: On a GPU: one contact step from rest up to 1024^2 and one punch, s (0.09-0.12 s and 0.019-0.025
#: s on an H200, `g2tom bench --only gpu`, 2026-11-27), and the CPU's work of a case besides
#: (medians of that run's validation: 0.29 s a 256^2 case, 0.47 s a 1024^2 one, 0.60 s a 512^2
#: convergence case with its three contact solves).
GPU_CONTACT_SECONDS = 0.1
GPU_PUNCH_SECONDS = 0.02
GPU_CASE_SECONDS = 0.05


def _table(table: dict[int, tuple[float, float]], n: int, force_normalized: float) -> float:
    ref = min(table, key=lambda m: abs(math.log(m / n)))
    light, heavy = table[ref]
    t = (math.log(max(force_normalized, 1e-9)) - math.log(LIGHT_HEAVY[0])) / math.log(LIGHT_HEAVY[1] / LIGHT_HEAVY[0])
    t = min(max(t, 0.0), 1.0)
    return math.exp((1 - t) * math.log(light) + t * math.log(heavy)) * (n / ref) ** 3


def _solves(vset: scene.ValidationSet, n: int, force_normalized: float) -> tuple[float, float]:
    """One contact solve's and one punch's time on an n x n grid, s, on the set's device and solver."""
    if vset.device == "gpu":
        scale = max(1.0, (n / 1024) ** 2)
        return GPU_CONTACT_SECONDS * scale, GPU_PUNCH_SECONDS * scale
    speed = G2TOM_CPU_SPEEDUP if vset.solver == "g2tom" else 1.0
    return (_table(CONTACT_SECONDS[vset.surface], n, force_normalized) / speed,
            _table(PUNCH_SECONDS[vset.surface], n, force_normalized) / speed)


def case_seconds(vset: scene.ValidationSet, case: cases_mod.Case, force_normalized: float) -> float:
    """The estimated time of one case, s (see the module docstring)."""
    probe, _ = _solves(vset, window.probe_grid(vset, case.ensemble), force_normalized)
    contact, punch = _solves(vset, case.n, force_normalized)
    base = GPU_CASE_SECONDS if vset.device == "gpu" else 0.0
    if not case.oxide:
        return base + probe + 3 * contact + punch
    return base + probe + contact + (1 + len(vset.xi) * len(vset.lambdas)) * punch


def case_costs(vset: scene.ValidationSet, force_normalized: np.ndarray) -> ensemble.CaseCosts:
    """One realization's cost at each load, s: a pair (a main-grid case), a proxy (an ensemble-grid
    case) and the stand-in (:data:`STAND_IN_SECONDS`): what part 2 weighs its pairs against its proxies by."""
    def per_load(n: int, proxy: bool) -> np.ndarray:
        return np.array([case_seconds(vset, cases_mod.Case(0, k, n, True, ensemble=proxy), float(f))
                         for k, f in enumerate(force_normalized)])

    return ensemble.CaseCosts(pair=per_load(vset.n_grid, False), grid=per_load(vset.ensemble_grid, True),
                              stand_in=STAND_IN_SECONDS)


@dataclass(frozen=True)
class Estimate:
    """The plan of one validation, before work.

    Attributes
    ----------
    part1, convergence
        Part 1's cases on the main grid and on the convergence grid.
    ensemble_counts, ensemble_pairs
        Part 2's first-round full-field realizations and pairs per load from the prior scatter
        (realizations beyond the pairs solve ensemble cases, pairs beyond part 1's main-grid cases;
        on the GW surface the stand-in can only lower them).
    ensemble
        Part 2's first-round ensemble cases.
    seconds_part1, seconds_part2, seconds_g2tom
        Summed case times of each part (s, one process) and g2tom's side (s).
    wall
        Estimated wall time on ``workers`` processes, s.
    wall_cap
        The same with every load's ensemble at ``max_ensemble`` and its pairs at ``max_pairs``
        (part 2's bound), s.
    """

    part1: int
    convergence: int
    ensemble_counts: np.ndarray
    ensemble_pairs: np.ndarray
    ensemble: int
    seconds_part1: float
    seconds_part2: float
    seconds_g2tom: float
    wall: float
    wall_cap: float


def estimate(vset: scene.ValidationSet, force_normalized: np.ndarray, workers: int,
             model_seconds: float) -> Estimate:
    """The plan's estimate (no case stored yet) at the loads' F' on ``workers`` processes;
    ``model_seconds``: the validated scenario's stages on the validation scene (s)."""
    part1 = cases_mod.plan_cases(vset)
    costs = case_costs(vset, force_normalized)
    N, P = ensemble.prior_allocation(vset, force_normalized, costs)
    counts, pairs = N.max(axis=0), P.max(axis=0)
    P0 = len(vset.realizations)

    def extra(proxies: np.ndarray, paired: np.ndarray) -> tuple[int, float, float]:
        """Part 2's cases (proxies on the ensemble grid where they exceed the pairs, the pairs added
        beyond part 1's), counted per load: how many, their summed seconds and the longest one's.
        Every case of a kind costs the same at a load (:func:`case_costs`), so no case is built."""
        n_proxy = np.where(proxies > paired, proxies, 0)
        n_pair = np.maximum(paired - P0, 0)
        longest = max([*costs.grid[n_proxy > 0], *costs.pair[n_pair > 0]], default=0.0)
        return int(n_proxy.sum() + n_pair.sum()), float(n_proxy @ costs.grid + n_pair @ costs.pair), float(longest)

    first = [case_seconds(vset, c, float(force_normalized[c.load])) for c in part1]
    s1 = sum(first)
    second = extra(counts, pairs)
    loads = len(force_normalized)
    most_pairs = max(P0, vset.pairs_cap)
    capped = extra(np.full(loads, vset.max_ensemble), np.full(loads, most_pairs))
    stand = STAND_IN_SECONDS * len(force_normalized) * int(counts.max()) if vset.surface == "gw" else 0.0
    g2tom = G2TOM_SECONDS * len(vset.discretizations) * len(vset.models) + model_seconds + stand

    def wall(part2: tuple[int, float, float]) -> float:
        _, total, longest = part2
        return g2tom + max((s1 + total) / max(workers, 1), max(first, default=0.0), longest)

    return Estimate(part1=sum(c.oxide for c in part1), convergence=sum(not c.oxide for c in part1),
                    ensemble_counts=counts, ensemble_pairs=pairs,
                    ensemble=second[0], seconds_part1=s1, seconds_part2=second[1],
                    seconds_g2tom=g2tom, wall=wall(second), wall_cap=wall(capped))
