"""``g2tom validate [--quick]``: the full-field reference against g2tom on one validation set, in two parts.

Part 1, *exactness per surface* (paired): g2tom's discretizations and models on the very surfaces
the full field solves, per realization. Part 2, *the default's ensemble* (unpaired,
:mod:`g2tom.reference.ensemble`): the validated scenario's ensemble geometric mean of R against
the full field's over as many realizations as each load needs.

Prints the plan first (scene, cases, grids, estimated time), runs g2tom's sides in memory, then
part 1's cases and part 2's rounds on dask (:class:`CaseRunner`: a ``dask.distributed`` cluster
for ``workers`` > 1 or a ``scheduler``, as the atlas; otherwise one after the other in this
process), each case resumable (finished cases are read back from ``<out>/cases/``), with one
progress line per case, and writes ``validate.nc``, the figure ``validate.png`` and the report
section ``validate.md`` under ``<out>``.
"""

from __future__ import annotations

import dataclasses
import os
import sys
import time
from contextlib import ExitStack
from pathlib import Path
from typing import Any, Callable, TextIO

import numpy as np
import xarray as xr

from g2tom.compute import ComputeOptions
from g2tom.models import contact_model
from g2tom.config import ConfigError, Scenario
from g2tom.before_work import load_scenario
from g2tom.progress import format_duration
from g2tom.reference import cases as cases_mod
from g2tom.reference import cost, discrete_spots, ensemble, scene, section, summary, surface_spots, window
from g2tom.scene import FieldSource
from g2tom.stages import contact as contact_stage
from g2tom.store import atomic_path

#: Largest relative difference of g2tom's forces at one delta between discretizations and models
#: (their auto domains differ); the reference is solved at the first one's.
FORCE_AGREEMENT = 1e-4
#: One process, no cluster: the library's default.
SERIAL = ComputeOptions(workers=1, progress=False)

__all__ = ["available_discretizations", "default_of", "plan_lines", "format_validate_plan", "run_validation",
           "chosen_set", "Part2Precision", "output_folder", "SURFACES", "CaseRunner", "SERIAL", "COUNTS", "LEAST_ERROR"]


def available_discretizations(surface: str = "gw") -> tuple[str, ...]:
    """The spot discretizations of ``contact.spots``, and on the GW surface its own asperities in
    g2tom's cells (:data:`surface_spots.SURFACE_ASPERITIES`) and as discrete coupled caps
    (:data:`discrete_spots.DISCRETE`)."""
    own = (surface_spots.SURFACE_ASPERITIES, discrete_spots.DISCRETE) if surface == "gw" else ()
    return ("mean_area", "expected", "asperities") + own


def default_of(config: str, model: ensemble.ModelEnsemble) -> dict[str, str]:
    """The validated scenario ``config`` as validate.nc names it: ``name``, ``model`` (part 2's
    words for it on the scene), ``discretization`` (part 1's name for its spots: ``discrete`` for the
    discrete model) and ``resistance_model`` (its cube.model)."""
    s = load_scenario(config)
    return {"name": s.name, "model": model.description, "resistance_model": s.cube.model,
            "discretization": contact_model(s).discretization(s)}


def _force_normalized(vset: scene.ValidationSet) -> np.ndarray:
    """g2tom's F' at the set's approaches (Greenwood-Tripp's forces, which every model shares)."""
    contact = contact_stage.build(scene.g2tom_scenario(vset, vset.models[0], "expected"))
    return contact["force_normalized"].values


def _model_seconds(validated: Scenario, workers: int) -> float:
    """The project's plan of the validated scenario's contact, oxide and cube stages on the scene, s."""
    from g2tom.before_work.plan import estimate

    stages = estimate(validated, workers)
    return sum(e.seconds for e in stages if e.stage in ("contact", "oxide", "cube"))


def _validated(vset: scene.ValidationSet, config: str) -> Scenario:
    """The scenario part 2 validates (:func:`g2tom.reference.ensemble.validated_scenario`); a refusal
    names it, since its settings meet the validation scene's (not the user's) surface here."""
    try:
        return ensemble.validated_scenario(vset, config)
    except ConfigError as exc:
        raise ConfigError(f"--config {config!r} (the scenario part 2 validates) cannot run on the validation "
                          f"scene: {exc}; choose another --config, or a TOML file of it with that setting "
                          "changed") from None


def plan_lines(vset: scene.ValidationSet, config: str = "paper", workers: int = 1) -> list[str]:
    """The plan printed before any work: scene, both parts' cases and grids, the estimate (no case stored);
    the full field capped at the validated scenario's hardness where it has one (:func:`g2tom.reference.scene.with_hardness_of`)."""
    vset = scene.with_hardness_of(vset, config)
    f = _force_normalized(vset)
    validated = _validated(vset, config)
    est = cost.estimate(vset, f, workers, _model_seconds(validated, workers))
    oxide = ", ".join(f"xi {x:g}/lambda {lam:g}" for x in vset.xi for lam in vset.lambdas)
    stand = (f"on the GW surface the discrete solve of each surface's own caps stands in where part 1 shows it "
             f"within {100 * ensemble.STAND_IN_TOLERANCE:g} % at every realization" if vset.surface == "gw"
             else "no stand-in on this surface")
    return [
        f"validate: {vset.surface} surface" + (f" (self-affine, H {vset.hurst:g}, rms {vset.rms:g} m, wavelengths "
                                              f"{vset.short_wavelength:.3g} .. {vset.short_wavelength * vset.bandwidth_ratio:.3g} m; "
                                              "g2tom's parameters are its summits')" if vset.surface == "random_process" else "")
        + f": sigma {vset.sigma:g} m, eta {vset.eta:g} m^-2, beta {vset.beta:g} m, "
        f"R* {vset.radius:g} m, E* {vset.e_star:.4g} Pa, rho* {vset.rho:g} ohm m (mu = {vset.mu:.3f})"
        + ("" if vset.hardness is None else
           f"; the full field's {scene.capped_contact(vset.hardness)}: the validated scenario's material.hardness"),
        f"validate: {len(vset.deltas)} loads delta/sigma {[round(d, 3) for d in vset.deltas]}, F' "
        + ", ".join(f"{x:.3g}" for x in f) + f"; clean + {oxide}",
        f"validate: part 1 (exactness per surface, paired): realizations {list(vset.realizations)}, grid "
        f"{vset.n_grid}^2 on each case's window, fitted to its contact by a {window.probe_grid(vset)}^2 probe (at most "
        f"the set's {vset.side * 1e3:.3g} mm); convergence grid "
        + (f"{vset.convergence_grid}^2" if vset.convergence_grid else "none")
        + f"; g2tom {list(vset.discretizations)} x {list(vset.models)}: {est.part1} + {est.convergence} cases",
        f"validate: part 2 (the default's ensemble, unpaired): {ensemble.describe(validated)} "
        f"against the full field on {vset.ensemble_grid}^2 (probe {window.probe_grid(vset, True)}^2), "
        f"standard error of ln R <= {vset.clean_error:g} clean, {vset.oxide_error:g} oxidized; full-field "
        f"realizations per load from the prior scatter {est.ensemble_counts.tolist()} (at most {vset.max_ensemble}), "
        f"corrected by main-grid pairs {est.ensemble_pairs.tolist()} (part 1's {len(vset.realizations)}, then more where "
        f"proxy and full field disagree, at most {vset.max_pairs}; proxies and pairs sized together at least cost, "
        f"resized from the measured scatter, "
        f"{ensemble.MAX_ROUNDS} rounds at most): {est.ensemble} cases; {stand}",
        f"validate: estimated {format_duration(est.wall)} on {workers} worker(s) (cases: part 1 "
        f"{format_duration(est.seconds_part1)}, part 2 {format_duration(est.seconds_part2)} of one process; "
        f"g2tom {format_duration(est.seconds_g2tom)}); at most {format_duration(est.wall_cap)} should every load need "
        f"{vset.max_ensemble} realizations and {vset.max_pairs} pairs (solver {vset.solver} on the {vset.device}; constants: seconds per "
        f"solve in pipeline/reference/cost.py)",
    ]


class CaseRunner:
    """Runs cases where ``options`` says (one cluster for the whole validation, made at the first
    case to run), each stored as it finishes; stored cases are read back.

    Use as a context manager (the cluster is closed at its end).
    """

    def __init__(self, vset: scene.ValidationSet, forces: np.ndarray, source: FieldSource, case_dir: Path,
                 options: ComputeOptions, stream: TextIO, progress: bool, start: float) -> None:
        self.vset, self.forces, self.source, self.case_dir = vset, forces, source, case_dir
        self.options, self.stream, self.progress, self.start = options, stream, progress, start
        self._stack = ExitStack()
        self._client: Any = None
        self._made = False
        self._f = np.asarray(forces) / vset.force_scale

    def __enter__(self) -> "CaseRunner":
        return self

    def __exit__(self, *exc: object) -> None:
        self._stack.close()

    def _workers(self) -> int:
        return 1 if self._client is None else max(len(self._client.scheduler_info().get("workers", {})), 1)

    def _left(self, cases: list[cases_mod.Case]) -> float:
        return sum(cost.case_seconds(self.vset, c, float(self._f[c.load])) for c in cases) / self._workers()

    def solve(self, cases: list[cases_mod.Case], label: str) -> dict[cases_mod.Case, dict]:
        """The records of ``cases``: stored ones read back, the others solved (and stored)."""
        keys = {c: cases_mod.case_key(self.vset, c, self.forces[c.load], self.source) for c in cases}
        done = {c: cases_mod.load_case(self.case_dir / f"{c.name}.json", keys[c]) for c in cases}
        todo = [c for c in cases if done[c] is None]
        if todo and not self._made:
            from g2tom.compute import _client

            self._client, self._made = _client(self._stack, self.options), True
        print(f"validate: {label}: {len(cases) - len(todo)} of {len(cases)} cases already stored, {len(todo)} to run "
              f"(~{format_duration(self._left(todo))})", file=self.stream, flush=True)
        args = {c: (self.vset, c, self.forces[c.load], self.source, keys[c], self.case_dir / f"{c.name}.json")
                for c in todo}
        if self._client is None or not todo:
            finished = ((c, cases_mod.run_case(*args[c])) for c in todo)
        else:
            from distributed import as_completed

            futures = {self._client.submit(cases_mod.run_case, *args[c], key=f"validate-{c.name}-{keys[c]}",
                                           pure=False): c for c in todo}
            finished = ((futures[fut], fut.result()) for fut in as_completed(futures))
        for number, (case, record) in enumerate(finished, start=1):
            done[case] = record
            if self.progress:
                result = (f"FAILED ({record['error']})" if "error" in record else
                          f"F = {record['force']:.4g} N, R = {record['resistance_clean']:.4g} ohm")
                left = self._left([c for c in todo if c not in done or done[c] is None])
                print(f"validate: case {number}/{len(todo)} {case.name}: {result} in {record['seconds_total']:.1f} s; "
                      f"elapsed {format_duration(time.perf_counter() - self.start)}, ~{format_duration(left)} left",
                      file=self.stream, flush=True)
        return done


def _g2tom_side(vset: scene.ValidationSet) -> dict:
    """g2tom's forces and resistances of the set, stacked (discretization, model, ...): clean
    (realization, load), one value over the realizations unless the discretization takes each
    surface's own asperities, and oxidized (xi, lambda, realization, load).

    A combination g2tom refuses is NaN, and named in ``skipped`` with g2tom's reason.
    """
    shape_clean = (len(vset.realizations), len(vset.deltas))
    shape = (len(vset.xi), len(vset.lambdas), len(vset.realizations), len(vset.deltas))
    clean = np.full((len(vset.discretizations), len(vset.models)) + shape_clean, np.nan)
    oxidized = np.full((len(vset.discretizations), len(vset.models)) + shape, np.nan)
    forces, skipped = [], []
    for d, spots in enumerate(vset.discretizations):
        for m, model in enumerate(vset.models):
            try:
                if spots == surface_spots.SURFACE_ASPERITIES:
                    cube = surface_spots.g2tom_resistances(vset, model)
                elif spots == discrete_spots.DISCRETE:
                    cube = discrete_spots.g2tom_resistances(vset, model)
                else:
                    cube = scene.g2tom_resistances(vset, model, spots)
            except ConfigError as exc:
                skipped.append(f"{spots}/{model}: {exc}")
                continue
            clean[d, m] = cube["resistance_clean"].transpose(..., "delta").values
            oxidized[d, m] = cube["resistance"].transpose("xi", "lambda", "realization", "delta").values
            forces.append(cube["force"].values)
            extent = float(cube["contact_extent"].max())
            if extent > vset.side / 2.0:
                raise ValueError(f"the contact reaches r = {extent * 1e3:.3g} mm (GT), beyond the reference grid's "
                                 f"half side {vset.side / 2 * 1e3:.3g} mm: enlarge n_grid or the pixel")
    for f in forces[1:]:  # each discretization's auto domain (r_max) moves F by ~1e-6 at the same delta
        if not np.allclose(f, forces[0], rtol=FORCE_AGREEMENT, atol=0):
            raise RuntimeError(f"g2tom's forces differ between discretizations or models by more than "
                               f"{FORCE_AGREEMENT:g}: {forces[0]} and {f}")
    return {"force": forces[0], "clean": clean, "resistance": oxidized, "skipped": skipped}


def run_validation(vset: scene.ValidationSet, out: Path, stream: TextIO = sys.stderr, progress: bool = True,
                   draw: Callable[[xr.Dataset, Path], Path] | None = None, config: str = "paper",
                   options: ComputeOptions = SERIAL) -> list[Path]:
    """Run the set into ``out`` (plan, g2tom, part 1's cases, part 2's rounds, outputs); return the
    written files.

    Parameters
    ----------
    vset
        The validation set (:func:`chosen_set`).
    out
        The output folder (``cases/`` under it keeps every finished case).
    stream, progress
        Where the plan and the lines go; ``progress``: one line per finished case.
    draw
        ``draw(ds, path)`` draws ``validate.png``, e.g. :func:`g2tom.analysis.figures_validate.figure`,
        which the CLI passes: the library draws nothing.
    config
        The validated scenario (bundled name or TOML file): part 2's model is its own.
    options
        Where the cases run (:class:`CaseRunner`).
    """
    start = time.perf_counter()
    out = Path(out)
    vset = scene.with_hardness_of(discrete_spots.with_rule_of(vset, config), config)
    everything = cases_mod.plan_cases(vset)
    workers = 1 if options.scheduler is None and (options.workers or 1) <= 1 else (options.workers or 1)
    for line in plan_lines(vset, config, workers):
        print(line, file=stream, flush=True)
    source = FieldSource.of(scene.g2tom_scenario(vset, vset.models[0], vset.discretizations[0]))
    g2tom = _g2tom_side(vset)
    model = ensemble.model_ensemble(vset, config)
    if not np.allclose(model.force, g2tom["force"], rtol=FORCE_AGREEMENT, atol=0):
        raise ConfigError(f"the validated scenario {config!r} loads at other forces ({model.force} N) than the "
                          f"validation's ({g2tom['force']} N): its load steps must be loading.delta_* of Greenwood-Tripp")
    f = g2tom["force"] / vset.force_scale
    print(f"validate: g2tom done (part 1's discretizations; part 2: {model.description})", file=stream, flush=True)
    with CaseRunner(vset, g2tom["force"], source, out / "cases", options, stream, progress, start) as runner:
        done = runner.solve(everything, "part 1")
        ref = summary.reference_arrays(vset, everything, done)
        ratio_clean, ratio = summary.part1_ratios(g2tom, ref)
        stand_clean, stand = ensemble.admitted(vset, ratio_clean, ratio)
        state = ensemble.run_part2(vset, f, ref["resistance_clean"], ref["resistance"], model, stand_clean, stand,
                                   cost.case_costs(vset, f),
                                   lambda todo: runner.solve(todo, "part 2"),
                                   lambda text: print(f"validate: {text}", file=stream, flush=True))
    part2 = ensemble.variables(vset, state, model, stand_clean, stand, f)
    ds = summary.dataset(vset, everything, done, g2tom, default_of(config, model), part2)
    paths = [out / "validate.nc", out / "validate.md"]
    with atomic_path(paths[0]) as tmp:
        ds.to_netcdf(tmp, format="NETCDF4", engine="netcdf4")
    with atomic_path(paths[1]) as tmp:
        tmp.write_text(section.markdown(ds))
    if draw is not None:
        paths.append(draw(ds, out / "validate.png"))
    print(f"validate: wrote {', '.join(map(str, paths))} in {format_duration(time.perf_counter() - start)}",
          file=stream, flush=True)
    return paths


#: ``--surface`` values: the GW surface of g2tom's own parameters, or a Gaussian self-affine one.
SURFACES = ("gw", "random_process")


#: The smallest ``--standard-error`` (of ln R): the realizations it asks for grow as its inverse square,
#: and below it they overflow every cap.
LEAST_ERROR = 1e-4
#: Each count option's range, and why its least (the most keeps the plan and the run's arrays small:
#: one full-field case takes seconds to minutes).
COUNTS: dict[str, tuple[int, int, str]] = {
    "--realizations": (2, 1000, "part 2 corrects its ensembles by part 1's paired realizations"),
    "--loads": (2, 100, "the lightest and the heaviest"),
    "--max-realizations": (2, 10_000, "a load's ensemble needs two"),
    "--max-pairs": (2, 10_000, "a load's pairs need two"),
    "--model-realizations": (16, 100_000, "the validated scenario's ensemble"),
}


def _count(option: str, value: int) -> int:
    """``value`` of a count option if inside its range (:data:`COUNTS`), else ConfigError naming the
    option, the value and the range."""
    least, most, why = COUNTS[option]
    if not least <= value <= most:
        raise ConfigError(f"{option} = {value} is out of range: must be {least} .. {most} (at least {least}: {why})")
    return value


@dataclasses.dataclass(frozen=True)
class Part2Precision:
    """Part 2's precision, where the set's defaults are not enough (``--standard-error``,
    ``--max-realizations``, ``--max-pairs``, ``--model-realizations``): None keeps the set's.

    Attributes
    ----------
    standard_error
        Goal of the standard error of ln ratio, (clean, oxidized), each in [:data:`LEAST_ERROR`, 0.5].
    max_ensemble, max_pairs
        Most full-field realizations (proxies) and most main-grid pairs a load (ranges: :data:`COUNTS`).
    model_realizations
        The validated scenario's surfaces and oxide realizations (range: :data:`COUNTS`).
    """

    standard_error: tuple[float, float] | None = None
    max_ensemble: int | None = None
    max_pairs: int | None = None
    model_realizations: int | None = None

    def changes(self) -> dict[str, Any]:
        """The set's fields this precision replaces, each checked (ConfigError naming option, value, range)."""
        out: dict[str, Any] = {}
        if self.standard_error is not None:
            for value in self.standard_error:
                if not (isinstance(value, float) and LEAST_ERROR <= value <= 0.5):
                    raise ConfigError(f"--standard-error = {value!r} is out of range: must be in [{LEAST_ERROR:g}, "
                                      "0.5] (the standard error of ln R, clean[,oxidized])")
            out["clean_error"], out["oxide_error"] = self.standard_error
        for option, field, value in (("--max-realizations", "max_ensemble", self.max_ensemble),
                                     ("--max-pairs", "max_pairs", self.max_pairs),
                                     ("--model-realizations", "model_realizations", self.model_realizations)):
            if value is not None:
                out[field] = _count(option, value)
        return out


def chosen_set(quick: bool, surface: str = "gw", realizations: int | None = None,
               loads: int | None = None, steps: tuple[int, ...] | None = None,
               precision: Part2Precision = Part2Precision()) -> scene.ValidationSet:
    """The default or the quick set on the chosen surface, with every discretization this g2tom offers;
    ``realizations`` (surfaces 0 .. N-1) and ``loads`` (steps evenly spaced in delta/sigma over the
    set's range, lightest first) override the set's; ``steps`` keeps only those of its load steps
    (1 = the lightest; like ``realizations`` and ``loads``, another set in the same output folder
    replaces the stored one); ``precision`` tightens or loosens part 2.

    Raises
    ------
    ConfigError
        On an unknown surface, fewer than two realizations (part 2 corrects its ensembles by part
        1's pairs, whose scatter needs two) or two loads, a step outside the set's, or a precision
        out of range.
    """
    if surface not in SURFACES:
        raise ConfigError(f"--surface {surface!r} is not allowed: must be one of {', '.join(SURFACES)}")
    for option, value in (("--realizations", realizations), ("--loads", loads)):
        if value is not None:
            _count(option, value)
    base = scene.QUICK if quick else scene.DEFAULT
    if surface == "random_process":
        base = scene.random_process_set(base, rms=scene.RANDOM.rms)
        if not quick:
            base = dataclasses.replace(base, deltas=scene.RANDOM.deltas)
    changes: dict = {"discretizations": available_discretizations(surface), **precision.changes()}
    if realizations is not None:
        changes["realizations"] = tuple(range(realizations))
    deltas = base.deltas
    if loads is not None:
        deltas = tuple(float(d) for d in np.linspace(max(base.deltas), min(base.deltas), loads))
    if steps is not None:
        bad = [k for k in steps if not 1 <= k <= len(deltas)]
        if bad or not steps or len(set(steps)) != len(steps):
            raise ConfigError(f"--steps = {','.join(map(str, steps))} is out of range: must be distinct load "
                              f"steps 1 .. {len(deltas)} (1 = the lightest)")
        deltas = tuple(deltas[k - 1] for k in sorted(steps))
    changes["deltas"] = deltas
    return dataclasses.replace(base, **changes)


def format_validate_plan(config: str = "paper", workers: int | None = None) -> list[str]:
    """Lines of ``g2tom plan --validate``: ``g2tom validate``'s default set on both surfaces, part 2
    validating ``config`` (cases, grids, the estimate: :mod:`g2tom.reference.cost`)."""
    parallel = max(1, workers or os.cpu_count() or 1)
    return [line for surface in SURFACES for line in plan_lines(chosen_set(False, surface), config, parallel)]


def output_folder(data_dir: Path, surface: str) -> Path:
    """Where a validation writes: ``<data>/validate`` (GW surface) or ``<data>/validate_random_process``."""
    return Path(data_dir) / ("validate" if surface == "gw" else f"validate_{surface}")
