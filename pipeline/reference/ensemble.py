"""Part 2, *the default's ensemble* (unpaired): the validated scenario against the full field, ensemble against ensemble.

At each load (g2tom's force, where the full field is solved too: equal force, no interpolation)
and each case (clean, every xi x lambda), the validated scenario's ensemble geometric mean of R
(:func:`model_ensemble`: its own contact model, spot rule and resistance model, read from the
scenario, over ``model_realizations`` realizations) is divided by the full field's ensemble
geometric mean (:mod:`g2tom.reference.statistics`: two-phase, a proxy on N realizations
corrected by the paired full field on the main grid on the first P). The proxy is the full field on the
ensemble grid (part 2's ``ensemble`` cases), or on the GW surface, where part 1 shows the discrete
solve of every surface's own caps (``discrete``, ``point``) within :data:`STAND_IN_TOLERANCE` of the
full field at that load and case, that solve (:func:`stand_in`, milliseconds a surface). Where N
would not exceed P, the pairs' full field is the ensemble (no proxy). N, and the pairs P
(part 1's realizations, then part 2's added main-grid cases), are sized per load and case
(:func:`plan_round`) for the ratio's standard error to reach the set's ``clean_error`` /
``oxide_error`` at least cost: first from the prior scatter (:func:`prior_allocation`), then, for
at most :data:`MAX_ROUNDS` rounds in all, from the scatter of what was solved
(:func:`statistics.allocation`); at most ``max_ensemble`` and ``max_pairs``.
Everything is deterministic given the stored cases, so a resumed run makes the same choices.

The two ensembles share the oxide seed (realization k of the model and of the full field draw
from the same stream) but not their surfaces, and the ratio's standard error adds both
ensembles' in squares as if they were independent. Measured on the GW default set (segment
rule, 2026-11-27): the correlation of ``ln R`` between the model's realization k and the full
field's proxy k, per oxidized case and load, lies within -0.24 .. +0.19 wherever 45 or more pairs
conduct (|rho| <= 0.1 in 15 of 23): the sum in squares neither hides nor adds a material term.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Callable

import numpy as np

from g2tom.config import ResolvedScenario, Scenario
from g2tom.before_work import load_scenario
from g2tom.reference import discrete_spots, scene, statistics
from g2tom.reference.cases import Case, ensemble_cases, pair_cases
from g2tom.reference.statistics import LogMean
from g2tom.reference.variables import variable
from g2tom.stages import contact as contact_stage
from g2tom.stages import cube as cube_stage
from g2tom.stages import oxide as oxide_stage
from g2tom.models import contact_model
from g2tom.models.discrete_cube import DiscretePool, clean_pool

__all__ = ["STAND_IN_TOLERANCE", "STAND_IN", "MAX_ROUNDS", "ModelEnsemble", "validated_scenario", "model_ensemble",
           "model_means", "describe", "admitted", "stand_in", "Part2", "CaseCosts", "plan_round", "prior_allocation", "run_part2",
           "variables"]

#: Part 1's largest |discrete / full field - 1| over every realization at a load and case that lets
#: the discrete solve of each surface's own caps stand in for the full field there (2 %).
STAND_IN_TOLERANCE = 0.02
#: Part 1's discretization and resistance model whose solve stands in.
STAND_IN = (discrete_spots.DISCRETE, "point")
#: Rounds of sizing and solving at most (the first from the prior scatter, then each from the
#: scatter solved so far until it says the goal is met; on the default GW set a third round still
#: added cases and left one standard error at 0.051 > 0.05 for want of a fourth).
MAX_ROUNDS = 5


@dataclass(frozen=True)
class ModelEnsemble:
    """The validated scenario's side of part 2.

    Attributes
    ----------
    force
        Forces of the load steps, N (delta).
    clean
        Clean resistance per realization, ohm (realization, delta); one row where the model's clean
        answer is one exact value (``deterministic``).
    deterministic
        The clean answer is one value, not a sample (Greenwood-Tripp's spots).
    resistance
        Oxidized resistance per realization, ohm (xi, lambda, delta, realization; +inf: open).
    description
        The scenario's model and the ensemble's sizes, in words.
    """

    force: np.ndarray
    clean: np.ndarray
    deterministic: bool
    resistance: np.ndarray
    description: str


def validated_scenario(vset: scene.ValidationSet, config: str) -> ResolvedScenario:
    """``config`` on the validation scene with a fixed ensemble of ``vset.model_realizations`` oxide
    fields (and, for a pooled contact model, a pool of at least as many surfaces): its
    contact model, spots, spot rule and resistance model are its own."""
    base = load_scenario(config)
    overrides = scene.scene_overrides(vset, vset.model_realizations)
    if contact_model(base).pooled:
        overrides["contact.surfaces"] = max(base.contact.surfaces, vset.model_realizations)
    return scene.scenario_of(vset, config, overrides)


def describe(scenario: Scenario) -> str:
    """The validated scenario's model in words (its name and the settings that make the model)."""
    words = contact_model(scenario).words(scenario)
    words += [f"oxide.spot_rule {scenario.oxide.spot_rule}", f"cube.model {scenario.cube.model}",
              f"{scenario.oxide.n_realizations} oxide realizations"]
    return f"{scenario.name} ({', '.join(words)})"


def model_ensemble(vset: scene.ValidationSet, config: str) -> ModelEnsemble:
    """The validated scenario's resistances per realization on the validation scene (its stages in memory)."""
    scenario = validated_scenario(vset, config)
    contact = contact_stage.build(scenario)
    oxide = oxide_stage.build(scenario)
    cube = cube_stage.build(scenario, contact, oxide)
    if contact_model(scenario).pooled:  # each surface of the pool its own clean resistance
        clean, deterministic = clean_pool(DiscretePool.of(contact), scenario.material.rho,
                                          scenario.cube.model)["resistance"], False
    else:  # Greenwood-Tripp's spots: one clean answer
        clean, deterministic = cube["resistance_clean"].transpose("delta").values[None], True
    return ModelEnsemble(force=contact["force"].values, clean=np.asarray(clean, float), deterministic=deterministic,
                         resistance=cube["resistance"].transpose("xi", "lambda", "delta", "realization").values,
                         description=describe(scenario))


def model_means(model: ModelEnsemble) -> tuple[list[LogMean], list[list[list[LogMean]]]]:
    """The model's ensemble means: clean per load, oxidized [xi][lambda][load]."""
    clean = [statistics.log_mean(model.clean[:, k], model.deterministic) for k in range(model.clean.shape[1])]
    ox = [[[statistics.log_mean(model.resistance[z, a, k]) for k in range(model.resistance.shape[2])]
           for a in range(model.resistance.shape[1])] for z in range(model.resistance.shape[0])]
    return clean, ox


def admitted(vset: scene.ValidationSet, ratio_clean: np.ndarray, ratio: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Where the discrete solve of each surface's own caps may stand in: clean (load) and oxidized
    (xi, lambda, load), from part 1's ratios (discretization, model, [xi, lambda,] realization, load):
    every realization's :data:`STAND_IN` ratio finite and within :data:`STAND_IN_TOLERANCE`, with at
    least two realizations (their pairs correct the stand-in)."""
    shape_ox = (len(vset.xi), len(vset.lambdas), len(vset.deltas))
    spots, model = STAND_IN
    if (vset.surface != "gw" or spots not in vset.discretizations or model not in vset.models
            or len(vset.realizations) < 2):
        return np.zeros(len(vset.deltas), bool), np.zeros(shape_ox, bool)
    d, m = vset.discretizations.index(spots), vset.models.index(model)

    def close(r: np.ndarray) -> np.ndarray:
        with np.errstate(invalid="ignore"):
            return np.all(np.isfinite(r) & (np.abs(r - 1.0) <= STAND_IN_TOLERANCE), axis=-2)

    return close(ratio_clean[d, m]), close(ratio[d, m])


def stand_in(vset: scene.ValidationSet, realizations: range) -> tuple[np.ndarray, np.ndarray]:
    """The discrete solve of each surface's own caps (point model, the set's spot rule on g2tom's fields) for
    ``realizations``: clean (realization, load) and oxidized (xi, lambda, realization, load), ohm."""
    out = discrete_spots.g2tom_resistances(dataclasses.replace(vset, realizations=tuple(realizations)), STAND_IN[1])
    return (out["resistance_clean"].transpose("realization", "delta").values,
            out["resistance"].transpose("xi", "lambda", "realization", "delta").values)


@dataclass
class Part2:
    """Part 2's full field as solved so far (NaN: not solved), (realization, load) and (xi, lambda,
    realization, load), ohm: the proxies on the ensemble grid (``grid_count`` per load; their summed
    wall and CPU ``seconds``) and by the stand-in (``stand_in_count``, every load), and the pairs,
    the full field on the main grid (part 1's realizations, then part 2's added ones: ``pair_count``
    per load)."""

    grid_clean: np.ndarray
    grid: np.ndarray
    grid_count: np.ndarray
    stand_clean: np.ndarray
    stand: np.ndarray
    seconds: np.ndarray
    seconds_cpu: np.ndarray
    pair_clean: np.ndarray
    pair: np.ndarray
    pair_count: np.ndarray
    stand_in_count: int = 0

    @classmethod
    def empty(cls, vset: scene.ValidationSet, exact_clean: np.ndarray, exact: np.ndarray) -> "Part2":
        """No proxy yet; the pairs are part 1's full field, ``exact_clean`` (P, load) and ``exact``
        (xi, lambda, P, load)."""
        n, loads, ox = vset.max_ensemble, len(vset.deltas), (len(vset.xi), len(vset.lambdas))
        P, pairs = exact_clean.shape[0], max(vset.max_pairs, exact_clean.shape[0])
        pair_clean, pair = np.full((pairs, loads), np.nan), np.full(ox + (pairs, loads), np.nan)
        pair_clean[:P], pair[:, :, :P] = exact_clean, exact
        return cls(np.full((n, loads), np.nan), np.full(ox + (n, loads), np.nan), np.zeros(loads, int),
                   np.full((n, loads), np.nan), np.full(ox + (n, loads), np.nan), np.zeros(loads), np.zeros(loads),
                   pair_clean, pair, np.full(loads, P, int))

    def exact(self, load: int, cell: tuple[int, int] | None) -> np.ndarray:
        """The full field on the main grid at one (load, cell) (cell None: clean), realizations 0 .. P-1."""
        values = self.pair_clean if cell is None else self.pair[cell]
        return values[:self.pair_count[load], load]

    def proxy(self, load: int, cell: tuple[int, int] | None, stand: bool) -> np.ndarray:
        """The proxy of one (load, cell): the stand-in's, the ensemble grid's, or the pairs' full
        field itself where the load has no ensemble case."""
        if stand:
            values = self.stand_clean if cell is None else self.stand[cell]
            return values[:self.stand_in_count, load]
        if self.grid_count[load] == 0:
            return self.exact(load, cell)
        values = self.grid_clean if cell is None else self.grid[cell]
        return values[:self.grid_count[load], load]


def _cells(vset: scene.ValidationSet) -> list[tuple[int, int] | None]:
    return [None] + [(z, a) for z in range(len(vset.xi)) for a in range(len(vset.lambdas))]


def _full_field_error(vset: scene.ValidationSet, cell: tuple[int, int] | None, model_error: float) -> float:
    """The full field's share of the ratio's standard error target: sqrt(target^2 - model's^2),
    at least half the target."""
    goal = vset.clean_error if cell is None else vset.oxide_error
    share = goal**2 - (model_error if np.isfinite(model_error) else 0.0) ** 2
    return math.sqrt(max(share, (goal / 2.0) ** 2))


@dataclass(frozen=True)
class CaseCosts:
    """What one realization costs at each load, s: a pair (the full field on the main grid), a proxy
    on the ensemble grid, and the stand-in's (:func:`g2tom.reference.cost.case_costs`)."""

    pair: np.ndarray
    grid: np.ndarray
    stand_in: float


def prior_allocation(vset: scene.ValidationSet, force_normalized: np.ndarray, costs: CaseCosts,
                     model_errors: Callable[[tuple[int, int] | None, int], float] | None = None
                     ) -> tuple[np.ndarray, np.ndarray]:
    """Round 1's full-field realizations N and pairs P per cell and load (cell axis: clean, then xi x
    lambda), from the prior scatter (:func:`statistics.prior_log_sd`, :func:`statistics.prior_pairs_sd`)
    at least cost (:func:`statistics.cheapest`, a pair's cost over an ensemble-grid proxy's), within
    [P, max_ensemble] and [part 1's realizations, max_pairs]. ``model_errors(cell, load)`` gives the
    model's standard error (default: half the target, as the plan assumes)."""
    N = np.zeros((len(_cells(vset)), len(force_normalized)), int)
    P = np.zeros_like(N)
    for c, cell in enumerate(_cells(vset)):
        goal = vset.clean_error if cell is None else vset.oxide_error
        for k, f in enumerate(force_normalized):
            error = _full_field_error(vset, cell, model_errors(cell, k) if model_errors else goal / 2.0)
            oxidized = cell is not None
            N[c, k], P[c, k] = statistics.cheapest(
                statistics.prior_log_sd(float(f), oxidized) ** 2, statistics.prior_pairs_sd(float(f), oxidized) ** 2,
                error, vset.max_ensemble, vset.pairs_cap, costs.pair[k] / costs.grid[k],
                len(vset.realizations))
    return N, P


def plan_round(vset: scene.ValidationSet, state: Part2, first: bool, force_normalized: np.ndarray,
               model: tuple[list[LogMean], list], stand_clean: np.ndarray, stand: np.ndarray,
               costs: CaseCosts) -> tuple[list[Case], int]:
    """The next round's work: full-field cases to solve (proxies on the ensemble grid, pairs on the
    main grid), and the stand-in count to reach.

    ``model``: :func:`model_means`; ``stand_clean`` (load) and ``stand`` (xi, lambda, load):
    :func:`admitted`. Round 1 sizes the proxies from the prior scatter; later rounds size proxies
    and pairs together from the measured (co)variances at least cost
    (:func:`g2tom.reference.statistics.allocation`, the pair's cost over the proxy's from ``costs``).
    """
    model_clean, model_ox = model
    if first:
        first_counts, first_pairs = prior_allocation(vset, force_normalized, costs, lambda cell, k: (
            model_clean[k] if cell is None else model_ox[cell[0]][cell[1]][k]).error)
    todo: list[Case] = []
    stand_goal = state.stand_in_count
    for k in range(len(force_normalized)):
        grid_need, pair_goal, any_grid, any_stand = 0, int(state.pair_count[k]), False, False
        for c, cell in enumerate(_cells(vset)):
            use_stand = bool(stand_clean[k] if cell is None else stand[cell][k])
            if first:
                need, pairs = int(first_counts[c, k]), (pair_goal if use_stand else int(first_pairs[c, k]))
            else:
                m = model_clean[k] if cell is None else model_ox[cell[0]][cell[1]][k]
                proxy_cost = costs.stand_in if use_stand else costs.grid[k]
                need, pairs = statistics.allocation(state.proxy(k, cell, use_stand), state.exact(k, cell),
                                                    _full_field_error(vset, cell, m.error), vset.max_ensemble,
                                                    vset.pairs_cap,
                                                    costs.pair[k] / proxy_cost)
            pair_goal = max(pair_goal, pairs)
            if use_stand:
                any_stand, stand_goal = True, max(stand_goal, need)
            else:
                any_grid, grid_need = True, max(grid_need, need)
        grid_goal = 0
        if any_grid and (state.grid_count[k] > 0 or grid_need > pair_goal):
            grid_goal = max(grid_need, pair_goal)  # every pair has its proxy
        if any_stand:  # every pair has its stand-in
            stand_goal = max(stand_goal, pair_goal)
        if grid_goal > state.grid_count[k]:
            todo += ensemble_cases(vset, k, range(state.grid_count[k], grid_goal))
        todo += pair_cases(vset, k, range(state.pair_count[k], pair_goal))
    return todo, stand_goal


def run_part2(vset: scene.ValidationSet, force_normalized: np.ndarray, exact_clean: np.ndarray, exact: np.ndarray,
              model: ModelEnsemble, stand_clean: np.ndarray, stand: np.ndarray, costs: CaseCosts,
              solve: Callable[[list[Case]], dict[Case, dict]], log: Callable[[str], None] = lambda _: None) -> Part2:
    """Size and solve part 2's full-field ensembles (``solve`` runs cases, returns their records);
    ``exact_clean`` (P, load) and ``exact`` (xi, lambda, P, load): part 1's full field."""
    state = Part2.empty(vset, exact_clean, exact)
    means = model_means(model)
    for r in range(MAX_ROUNDS):
        todo, stand_goal = plan_round(vset, state, r == 0, force_normalized, means, stand_clean, stand, costs)
        if not todo and stand_goal <= state.stand_in_count:
            break
        if stand_goal > state.stand_in_count:
            new = range(state.stand_in_count, stand_goal)
            clean, ox = stand_in(vset, new)
            state.stand_clean[new.start:new.stop] = clean
            state.stand[:, :, new.start:new.stop] = ox
            state.stand_in_count = stand_goal
            log(f"part 2 round {r + 1}: stand-in (each surface's own caps, discrete) on realizations 0 .. "
                f"{stand_goal - 1}")
        if todo:
            for kind, grid in (("ensemble", vset.ensemble_grid), ("pair", vset.n_grid)):
                these = [c for c in todo if c.ensemble == (kind == "ensemble")]
                if these:
                    log(f"part 2 round {r + 1}: {len(these)} full-field {kind} cases on {grid}^2 at load(s) "
                        + ", ".join(f"{k} (to {max(c.realization for c in these if c.load == k) + 1})"
                                    for k in sorted({c.load for c in these})))
            for case, record in solve(todo).items():
                rows = (state.grid_clean, state.grid) if case.ensemble else (state.pair_clean, state.pair)
                rows[0][case.realization, case.load] = record["resistance_clean"]
                rows[1][:, :, case.realization, case.load] = np.asarray(record["resistance"], float)
                state.seconds[case.load] += record["seconds_total"]
                state.seconds_cpu[case.load] += record.get("seconds_cpu", np.nan)
            for case in todo:
                counts = state.grid_count if case.ensemble else state.pair_count
                counts[case.load] = max(counts[case.load], case.realization + 1)
    return state


def variables(vset: scene.ValidationSet, state: Part2, model: ModelEnsemble, stand_clean: np.ndarray,
              stand: np.ndarray, force_normalized: np.ndarray) -> dict[str, tuple]:
    """validate.nc's part 2 variables (:data:`g2tom.reference.variables.VARIABLES`, ``ensemble_*``)."""
    model_clean, model_ox = model_means(model)
    loads = len(force_normalized)
    X, A = len(vset.xi), len(vset.lambdas)

    def estimate(cell: tuple[int, int] | None, k: int) -> tuple[LogMean, LogMean]:
        use_stand = bool(stand_clean[k] if cell is None else stand[cell][k])
        ff = statistics.two_phase_log_mean(state.proxy(k, cell, use_stand), state.exact(k, cell))
        return ff, (model_clean[k] if cell is None else model_ox[cell[0]][cell[1]][k])

    clean = [estimate(None, k) for k in range(loads)]
    ox = [[[estimate((z, a), k) for k in range(loads)] for a in range(A)] for z in range(X)]

    def field(pick: Callable[[LogMean, LogMean], float]) -> tuple[np.ndarray, np.ndarray]:
        c = np.array([pick(*clean[k]) for k in range(loads)], float)
        o = np.array([[[pick(*ox[z][a][k]) for k in range(loads)] for a in range(A)] for z in range(X)], float)
        return c, o

    ratio = field(lambda f, m: math.exp(m.mean - f.mean))
    error = field(lambda f, m: statistics.ratio_error(m, f))
    ref_mean = field(lambda f, m: math.exp(f.mean))
    ref_error = field(lambda f, m: f.error)
    ref_pairs = field(lambda f, m: f.pairs_error)
    ref_count = field(lambda f, m: f.count)
    ref_open = field(lambda f, m: f.open_fraction)
    mod_mean = field(lambda f, m: math.exp(m.mean))
    mod_error = field(lambda f, m: m.error)
    mod_open = field(lambda f, m: m.open_fraction)
    target_clean = np.array([statistics.target(float(f), False) for f in force_normalized])
    target_ox = np.broadcast_to([statistics.target(float(f), True) for f in force_normalized], (X, A, loads))
    n = max(int(state.grid_count.max()), state.stand_in_count, int(state.pair_count.max()), 1)

    def rows(values: np.ndarray) -> np.ndarray:  # the realization axis (second last) cut or padded to n
        out = np.full(values.shape[:-2] + (n, loads), np.nan)
        m = min(n, values.shape[-2])
        out[..., :m, :] = values[..., :m, :]
        return out

    proxy_clean = np.where(stand_clean[None], rows(state.stand_clean), rows(state.grid_clean))
    proxy = np.where(stand[:, :, None], rows(state.stand), rows(state.grid))
    check = np.full(loads, np.nan)  # the ensemble grid against the main grid on the pairs' realizations
    for k in np.flatnonzero(state.grid_count > 0):
        P = min(state.grid_count[k], state.pair_count[k])
        check[k] = math.exp(statistics.log_mean(state.grid_clean[:P, k] / state.pair_clean[:P, k]).mean)
    return {
        "ensemble_count_clean": variable("ensemble_count_clean", ref_count[0].astype(int)),
        "ensemble_count": variable("ensemble_count", ref_count[1].astype(int)),
        "ensemble_grid_cases": variable("ensemble_grid_cases", state.grid_count.copy()),
        "ensemble_pairs": variable("ensemble_pairs", state.pair_count.copy()),
        "resistance_pairs_clean": variable("resistance_pairs_clean", rows(state.pair_clean),
                                           comment="+inf: open circuit; NaN: not solved"),
        "resistance_pairs": variable("resistance_pairs", rows(state.pair), comment="+inf: open circuit; NaN: not solved"),
        "ensemble_stand_in_clean": variable("ensemble_stand_in_clean", stand_clean.astype(np.int8)),
        "ensemble_stand_in": variable("ensemble_stand_in", stand.astype(np.int8)),
        "resistance_ensemble_clean": variable("resistance_ensemble_clean", proxy_clean,
                                              comment="+inf: open circuit; NaN: not solved"),
        "resistance_ensemble": variable("resistance_ensemble", proxy, comment="+inf: open circuit; NaN: not solved"),
        "ensemble_reference_clean": variable("ensemble_reference_clean", ref_mean[0]),
        "ensemble_reference_clean_standard_error": variable("ensemble_reference_clean_standard_error", ref_error[0]),
        "ensemble_reference": variable("ensemble_reference", ref_mean[1]),
        "ensemble_reference_standard_error": variable("ensemble_reference_standard_error", ref_error[1]),
        "ensemble_reference_clean_pairs_standard_error": variable("ensemble_reference_clean_pairs_standard_error",
                                                                  ref_pairs[0]),
        "ensemble_reference_pairs_standard_error": variable("ensemble_reference_pairs_standard_error", ref_pairs[1]),
        "ensemble_reference_open_fraction": variable("ensemble_reference_open_fraction", ref_open[1]),
        "ensemble_model_clean": variable("ensemble_model_clean", mod_mean[0]),
        "ensemble_model_clean_standard_error": variable("ensemble_model_clean_standard_error", mod_error[0]),
        "ensemble_model": variable("ensemble_model", mod_mean[1]),
        "ensemble_model_standard_error": variable("ensemble_model_standard_error", mod_error[1]),
        "ensemble_model_open_fraction": variable("ensemble_model_open_fraction", mod_open[1]),
        "ensemble_model_count": variable("ensemble_model_count", int(model.resistance.shape[-1])),
        "ensemble_model_count_clean": variable("ensemble_model_count_clean", int(model.clean.shape[0])),
        "ensemble_ratio_clean": variable("ensemble_ratio_clean", ratio[0]),
        "ensemble_ratio_clean_standard_error": variable("ensemble_ratio_clean_standard_error", error[0]),
        "ensemble_ratio": variable("ensemble_ratio", ratio[1]),
        "ensemble_ratio_standard_error": variable("ensemble_ratio_standard_error", error[1]),
        "ensemble_target_clean": variable("ensemble_target_clean", target_clean),
        "ensemble_target": variable("ensemble_target", np.array(target_ox)),
        "ensemble_grid_check_clean": variable("ensemble_grid_check_clean", check),
        "ensemble_seconds": variable("ensemble_seconds", state.seconds.copy()),
        "ensemble_seconds_cpu": variable("ensemble_seconds_cpu", state.seconds_cpu.copy()),
    }
