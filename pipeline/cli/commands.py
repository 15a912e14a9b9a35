"""``g2tom``'s command handlers: each subcommand's work on its loaded scenario, resolved where it computes."""

from __future__ import annotations

import argparse
import dataclasses
import fcntl
import importlib
import json
import os
import sys
import time
from pathlib import Path
from typing import TYPE_CHECKING

from g2tom.config import STAGE_INPUTS, ConfigError, ResolvedScenario, Scenario, parameter_table
from g2tom.errors import StaleInputError

if TYPE_CHECKING:
    from g2tom.compute import ComputeOptions
    from g2tom.reference.validate import Part2Precision

__all__ = ["STAGES", "compute_options", "stage", "run", "figures", "report", "bench", "stamp", "params", "plan",
           "predict", "atlas", "roughness", "surface", "validate"]

#: Stage name -> module implementing ``run(scenario, data_dir, options) -> Path``, in order.
STAGES: dict[str, str] = {
    "contact": "g2tom.stages.contact",
    "oxide": "g2tom.stages.oxide",
    "cube": "g2tom.stages.cube",
    "fits": "g2tom.stages.fits",
    "surrogate": "g2tom.stages.surrogate",
}


def compute_options(args: argparse.Namespace) -> ComputeOptions:
    """Where dask runs, from ``--scheduler``, ``--workers`` and ``--no-progress``; a refused
    ``--workers`` is a ConfigError."""
    from g2tom.compute import ComputeOptions  # dask only for commands that compute

    if args.workers is not None and args.workers < 1:
        raise ConfigError(f"--workers = {args.workers} is out of range: must be >= 1")
    return ComputeOptions(
        scheduler=args.scheduler, workers=args.workers, progress=not args.no_progress
    )


def _preflight(args: argparse.Namespace, scenario: ResolvedScenario, scene: bool = True) -> None:
    """Directory, scheduler and cross-stage checks before any work (g2tom.before_work.preflight)."""
    from g2tom.before_work.preflight import preflight

    preflight(scenario, args.data_dir, getattr(args, "scheduler", None), scene=scene)
    for note in getattr(args, "plan_notes", ()):  # the plan, once every check has passed
        print(note, file=sys.stderr)
    args.plan_notes = ()  # said once, though `run` checks again before the figures and the report


def _run_stage(name: str, scenario: ResolvedScenario, args: argparse.Namespace) -> None:
    """Run stage ``name`` where ``args`` says, and record its wall time (the contact stage first says
    whether the caps yield: :class:`g2tom.scene.Plasticity`)."""
    options = compute_options(args)
    if name == "contact":
        from g2tom.scene import scene_plasticity

        print(f"contact: {scene_plasticity(scenario).line(scenario.roughness.sigma)}", file=sys.stderr)
    module = importlib.import_module(STAGES[name])
    start = time.perf_counter()
    path = module.run(scenario, args.data_dir, options)
    elapsed = time.perf_counter() - start
    _record_timing(args.data_dir, name, elapsed, scenario.config_hash(name))
    print(f"{name}: wrote {path} in {elapsed:.2f} s", file=sys.stderr)


def _record_timing(data_dir: Path, step: str, seconds: float, config_hash: str) -> None:
    """Merge a step's wall time into ``<data_dir>/timings.json`` (read by the report).

    Each entry records the configuration hash it was run with, so the report shows only the
    times of the outputs it describes. The data folder is locked meanwhile (``flock``), so that
    commands finishing together keep each other's entries.
    """
    from g2tom.store import atomic_path

    path = Path(data_dir) / "timings.json"
    folder = os.open(path.parent, os.O_RDONLY)
    try:
        fcntl.flock(folder, fcntl.LOCK_EX)  # commands side by side (make's jobs) each add their step
        try:
            timings = json.loads(path.read_text()) if path.is_file() else {}
        except (OSError, ValueError):
            timings = {}  # a damaged timings file is only a cache of wall times
        timings[step] = {"seconds": round(seconds, 3), "config_hash": config_hash,
                         "finished": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime())}
        with atomic_path(path) as tmp:
            tmp.write_text(json.dumps(timings, indent=1, sort_keys=True) + "\n")
    finally:
        os.close(folder)  # and with it the lock


def stage(args: argparse.Namespace, scenario: ResolvedScenario) -> None:
    """``g2tom <stage>``: the checks before work, then that one stage."""
    _preflight(args, scenario)
    _run_stage(args.command, scenario, args)


def run(args: argparse.Namespace, scenario: ResolvedScenario) -> None:
    """``g2tom run``: every stage not up to date, the physics benchmarks, the figures and the report
    (``--check``: the checks before work only)."""
    _preflight(args, scenario)
    if args.check:
        print("run: every check before work passed (configuration, surrogate grid, plan, scene)", file=sys.stderr)
        return
    from g2tom.config import STAGE_UPSTREAM
    from g2tom.store import stage_path, stage_problem

    rebuilt: set[str] = set()
    for name in STAGES:  # as make: a stage file built from this configuration, on kept inputs, is kept
        if stage_problem(args.data_dir, name, scenario) is None and not rebuilt & set(STAGE_UPSTREAM[name]):
            print(f"{name}: up to date, kept {stage_path(args.data_dir, name)}", file=sys.stderr)
            continue
        _run_stage(name, scenario, args)
        rebuilt.add(name)
    if not args.no_bench:  # what make run adds to the report (the Makefile's PHYSICS_BENCH)
        from g2tom.bench import physics_benchmarks

        for line in physics_benchmarks(scenario, args.data_dir):
            print(line, file=sys.stderr)
    figures(args, scenario)
    report(args, scenario)


def figures(args: argparse.Namespace, scenario: ResolvedScenario) -> None:
    """``g2tom figures``: the figures of current stage files (refused before any is drawn otherwise); each
    family's wall time recorded apart (``--only`` draws some families, e.g. side by side)."""
    from g2tom.analysis.figures import FAMILIES, family_names, write_figures
    from g2tom.store import stage_problem

    _preflight(args, scenario, scene=False)
    names = family_names(getattr(args, "only", None))  # `g2tom run` draws them all
    drawn_from = [s for s in STAGES if any(s in FAMILIES[name].stages for name in names)]
    # checked before drawing, so that no figure is replaced by half a set
    _refuse_if("figures", [p for p in (stage_problem(args.data_dir, s, scenario) for s in drawn_from) if p])

    def drawn(family: str, files: list[Path], seconds: float) -> None:
        for path in files:
            print(f"figure: {path}", file=sys.stderr)
        if files:
            _record_timing(args.data_dir, f"figures: {family}", seconds, scenario.config_hash())

    write_figures(scenario, args.data_dir, names, on_family=drawn)


def _refuse_if(what: str, problems: list[str]) -> None:
    """One line for the first problem (and how many more) before anything is written."""
    if problems:
        more = f" (and {len(problems) - 1} more)" if len(problems) > 1 else ""
        raise StaleInputError(f"{what} not written: {problems[0]}{more}")


def _report_problems(data_dir: Path, scenario: Scenario) -> list[str]:
    """Why a report of ``data_dir`` would describe missing, stale or outdated results: the fits and the
    surrogate not current, no figure of the study, or a figure older than a stage file it draws."""
    from g2tom.analysis.figures import FAMILIES
    from g2tom.store import stage_path, stage_problem

    problems = [p for p in (stage_problem(data_dir, s, scenario) for s in ("fits", "surrogate")) if p]
    folder = data_dir / "figures"
    if not any(folder.glob("fig*.png")):  # the study's figures, not the benchmarks'
        return problems + [f"{folder} holds no figures: run `g2tom figures` (or `make figures`)"]
    for family in FAMILIES.values():
        sources = [stage_path(data_dir, s) for s in family.stages if stage_path(data_dir, s).is_file()]
        drawn = [folder / name for name in family.files if (folder / name).is_file()]
        if sources and drawn:
            newest = max(sources, key=lambda p: p.stat().st_mtime_ns)
            oldest = min(drawn, key=lambda p: p.stat().st_mtime_ns)
            if oldest.stat().st_mtime_ns < newest.stat().st_mtime_ns:
                problems.append(f"{oldest} is older than {newest}: run `g2tom figures` (or `make figures`)")
    return problems


def report(args: argparse.Namespace, scenario: ResolvedScenario) -> None:
    """``g2tom report``: report.md and report.html of current results and figures."""
    from g2tom.analysis.report import write_report

    _preflight(args, scenario, scene=False)
    _refuse_if("report", _report_problems(args.data_dir, scenario))
    for path in write_report(scenario, args.data_dir):
        print(f"report: {path}", file=sys.stderr)


def bench(args: argparse.Namespace, scenario: ResolvedScenario) -> None:
    """``g2tom bench``: the benchmarks (all, or ``--only`` those), saved under ``<data-dir>/bench``."""
    from g2tom.bench import run_benchmarks

    _preflight(args, scenario, scene=False)
    run_benchmarks(scenario, args.data_dir, only=args.only, verbose=args.verbose)


def stamp(args: argparse.Namespace, scenario: ResolvedScenario) -> None:
    """Write ``<data>/.stamps/<stage>.json`` only when its content changes (for make).

    A stamp is also touched when its stage file exists but is unreadable (a truncated or
    damaged file) or was built from another configuration (e.g. by ``g2tom fits --set
    ...``), so that make rebuilds it instead of failing on it forever.
    """
    from g2tom.store import stage_path, stage_problem

    _preflight(args, scenario, scene=False)
    stamps = args.data_dir / ".stamps"
    stamps.mkdir(parents=True, exist_ok=True)
    for name in STAGE_INPUTS:
        text = json.dumps(
            {"config_hash": scenario.config_hash(name), "parameters": scenario.stage_parameters(name)},
            indent=1,
            sort_keys=True,
        )
        path = stamps / f"{name}.json"
        if not path.is_file() or path.read_text() != text:
            path.write_text(text)
        elif stage_path(args.data_dir, name).is_file():
            problem = stage_problem(args.data_dir, name, scenario)
            if problem:
                print(f"g2tom: {problem}; make will rebuild it", file=sys.stderr)
                os.utime(path)


def params(args: argparse.Namespace, scenario: Scenario) -> None:
    """``g2tom params``: every parameter with its value, unit, range and meaning (``--resolved``: as a run
    uses them, ``auto`` domains resolved, and the cell grid they give)."""
    if args.resolved:
        from g2tom.before_work.domains import resolve

        scenario = resolve(scenario)
    flat = scenario.flat()
    for key, _default, unit, allowed, doc in parameter_table():
        print(f"{key:32s} {flat[key]!s:>24}  [{unit}]  {allowed}: {doc}")
    if args.resolved:
        print(f"{'cells':32s} {f'{scenario.n_cells} x {scenario.n_cells}':>24}  [1]  of pitch 1/sqrt(eta) = "
              f"{scenario.cell_size:.4g} m over the window")


def plan(args: argparse.Namespace, scenario: ResolvedScenario) -> None:
    """``g2tom plan``: each stage's estimate (``--atlas``: the atlas's scenes; ``--validate``: the
    validation's cases)."""
    from g2tom.before_work.plan import format_plan

    if args.validate:
        from g2tom.reference.validate import format_validate_plan

        print("\n".join(format_validate_plan(args.config, args.workers)))
        return

    if args.atlas:
        from g2tom.atlas.design import AtlasDesign, format_atlas_plan, plan_atlas

        # one single-threaded scene per worker
        parallel = max(1, args.workers or os.cpu_count() or 1)
        print("\n".join(format_atlas_plan(plan_atlas(scenario, AtlasDesign.of(scenario)), parallel)))
        return
    print("\n".join(format_plan(scenario, getattr(args, "workers", None))))


def predict(args: argparse.Namespace, scenario: Scenario) -> None:
    """``g2tom predict``: the surrogate's resistances (the run's own surrogate.nc, unreadable, refused
    first as a file to rebuild; a ``--surrogate`` file the user names is refused as a bad input)."""
    from g2tom.cli.predict import predict_cli
    from g2tom.store import stage_path, unreadable

    own = stage_path(args.data_dir, "surrogate")
    problem = args.surrogate is None and own.is_file() and unreadable(own, "surrogate")
    if problem:
        raise StaleInputError(problem)

    predict_cli(args, scenario)


def atlas(args: argparse.Namespace, scenario: ResolvedScenario) -> None:
    """``g2tom atlas``: every scene of the atlas's design, then its surrogate and held-out errors."""
    from g2tom.atlas.run import run_atlas
    from g2tom.atlas.design import AtlasDesign

    _preflight(args, scenario, scene=False)
    if args.workers is None and args.scheduler is None:
        args.workers = os.cpu_count() or 1  # a local cluster, one single-threaded scene per core
    path = run_atlas(scenario, AtlasDesign.of(scenario), args.data_dir, compute_options(args))
    print(f"atlas: wrote {path}", file=sys.stderr)
    from g2tom.atlas.fit import CURVE, curve_words, write_atlas_surrogate

    target, doc = write_atlas_surrogate(path)
    held, worst = doc["heldout"], doc["heldout"]["worst"]
    print(f"atlas: wrote {target}: curve model {curve_words(doc[CURVE])} (by leave-one-scene-out cross-validation); "
          f"held out: {held['cells_within']} of "
          f"{held['cells']} cells within max(5 %, interval) at every step; worst {worst['scene']} (xi {worst['xi']:g}, "
          f"lambda {worst['lambda']:g}, F' {worst['force_normalized']:.3g}): {worst['error']:.3g} in ln R' vs "
          f"{worst['allowed']:.3g} allowed; targets {'met' if held['met'] else 'not met'}; the noise ceiling at this "
          f"precision {100 * held['noise_ceiling']['independent_steps']:.0f}-"
          f"{100 * held['noise_ceiling']['correlated_steps']:.0f} % of the cells", file=sys.stderr)


def _device(args: argparse.Namespace) -> str:
    """``--device`` resolved (``cpu`` or ``gpu``; a refused one is a ConfigError naming why); on the
    GPU, ``--workers`` defaults to one (its solves take the whole device, one after another)."""
    from g2tom.reference.devices import resolve

    try:
        device = resolve(args.device)
    except ValueError as exc:
        raise ConfigError(str(exc)) from None
    if args.workers is None and args.scheduler is None and device == "gpu":
        args.workers = 1
    return device


def surface(args: argparse.Namespace, scenario: Scenario) -> None:
    """``g2tom surface``: the full-field resistance of a measured height map (the scenario's materials,
    indenter and oxide spectrum)."""
    from g2tom.before_work.preflight import check_scheduler
    from g2tom.cli.surface import surface_cli

    device = _device(args)
    if args.scheduler:
        check_scheduler(args.scheduler)
    surface_cli(args, scenario, compute_options(args), device)


def roughness(args: argparse.Namespace, scenario: Scenario) -> None:
    """``g2tom roughness``: sigma, eta and beta of a measured height map (no scenario used)."""
    from g2tom.cli.roughness import roughness_cli

    roughness_cli(args)


def _steps(text: str | None) -> tuple[int, ...] | None:
    """``--steps`` as load-step numbers (ConfigError naming a value that is not a whole number)."""
    if text is None:
        return None
    from g2tom.cli.parsing import number_list

    values = number_list("--steps", text)
    if not all(v.is_integer() for v in values):
        raise ConfigError(f"--steps = {text!r} is not allowed: must be whole load-step numbers, 1 = the lightest")
    return tuple(int(v) for v in values)


def _precision(args: argparse.Namespace) -> "Part2Precision":
    """Part 2's precision from ``--standard-error`` (CLEAN[,OXIDIZED]) and the realization caps."""
    from g2tom.cli.parsing import number_list
    from g2tom.reference.validate import Part2Precision

    error = None
    if args.standard_error is not None:
        values = number_list("--standard-error", args.standard_error)
        if values.size > 2:
            raise ConfigError(f"--standard-error = {args.standard_error!r} is not allowed: must be CLEAN or "
                              "CLEAN,OXIDIZED")
        error = (float(values[0]), float(values[-1]))
    return Part2Precision(standard_error=error, max_ensemble=args.max_realizations, max_pairs=args.max_pairs,
                          model_realizations=args.model_realizations)


def validate(args: argparse.Namespace, scenario: Scenario) -> None:
    """The full-field reference against g2tom (g2tom.reference); the extra is checked first."""
    from g2tom.reference import missing_extra

    if args.overrides:
        raise ConfigError("g2tom validate runs its own validation scene (the default set or --quick): --set is "
                          "not used by it; leave it out (--config names the scenario whose model part 2 validates)")
    from g2tom.before_work.preflight import check_data_dir, check_scheduler
    from g2tom.reference.validate import chosen_set, output_folder, plan_lines, run_validation

    from g2tom.reference.devices import solver_for

    vset = chosen_set(args.quick, args.surface, realizations=args.realizations, loads=args.loads,
                      steps=_steps(args.steps), precision=_precision(args))
    device = _device(args)
    try:
        vset = dataclasses.replace(vset, device=device, solver=solver_for(args.solver, device))
    except ValueError as exc:
        raise ConfigError(str(exc)) from None
    if args.plan:
        print("\n".join(plan_lines(vset, args.config, max(1, args.workers or os.cpu_count() or 1))))
        return
    check_data_dir(args.data_dir)
    if args.scheduler:
        check_scheduler(args.scheduler)
    problem = missing_extra() if vset.solver == "tamaas" else None
    if problem:
        raise ConfigError(problem)
    if args.workers is None and args.scheduler is None:
        # on the CPU a local cluster, one single-threaded case per core (as the atlas)
        args.workers = os.cpu_count() or 1
    from g2tom.analysis.figures_validate import figure

    run_validation(vset, output_folder(args.data_dir, args.surface), progress=not args.no_progress, draw=figure,
                   config=args.config, options=compute_options(args))
