"""The ``g2tom`` command: run stages, benchmarks, figures, the report and the predictor."""

from __future__ import annotations

import os

# One BLAS/OpenMP thread per dask worker thread: set before numpy is imported anywhere.
for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import argparse  # noqa: E402
import importlib  # noqa: E402
import json  # noqa: E402
import re  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
import warnings  # noqa: E402
from pathlib import Path  # noqa: E402
from typing import TYPE_CHECKING, Callable, NoReturn, Sequence  # noqa: E402

from pipeline import __version__  # noqa: E402
from pipeline.config import (  # noqa: E402
    STAGE_INPUTS, ConfigError, ResolvedScenario, Scenario, bundled_scenarios, load_scenario, parameter_table)
from pipeline.errors import StaleInputError  # noqa: E402
from pipeline.before_work.plan import prepare  # noqa: E402
from pipeline.before_work.surrogate_grid import check_surrogate_grid  # noqa: E402

if TYPE_CHECKING:
    from pipeline.compute import ComputeOptions

__all__ = ["main", "STAGES"]

#: Stage name -> module implementing ``run(scenario, data_dir, options) -> Path``, in order.
STAGES: dict[str, str] = {
    "contact": "pipeline.stages.contact",
    "oxide": "pipeline.stages.oxide",
    "cube": "pipeline.stages.cube",
    "fits": "pipeline.stages.fits",
    "surrogate": "pipeline.stages.surrogate",
}


#: Commands that run the surrogate stage: its limits on the oxide grid are checked before any stage.
_REACH_SURROGATE = ("run", "surrogate")



def _scenario_args(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--config",
        default="paper",
        help=f"bundled scenario name ({', '.join(bundled_scenarios())}) or a TOML file (default: paper)",
    )
    p.add_argument(
        "--set",
        dest="overrides",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="override one parameter, e.g. --set roughness.sigma=2e-5 (repeatable)",
    )
    p.add_argument("--data-dir", type=Path, default=Path("data"), help="where stage files live")


def _compute_args(p: argparse.ArgumentParser) -> None:
    p.add_argument("--scheduler", default=None, help="address of a dask.distributed scheduler")
    p.add_argument("--workers", type=int, default=None, help="local dask workers (default: cores)")
    p.add_argument("--no-progress", action="store_true", help="hide the progress bar")


def _options(args: argparse.Namespace) -> ComputeOptions:
    from pipeline.compute import ComputeOptions  # dask only for commands that compute

    if args.workers is not None and args.workers < 1:
        raise ConfigError(f"--workers = {args.workers} is out of range: must be >= 1")
    return ComputeOptions(
        scheduler=args.scheduler, workers=args.workers, progress=not args.no_progress
    )


def _preflight(args: argparse.Namespace, scenario: ResolvedScenario, scene: bool = True) -> None:
    """Directory, scheduler and cross-stage checks before any work (pipeline.before_work.preflight)."""
    from pipeline.before_work.preflight import preflight

    preflight(scenario, args.data_dir, getattr(args, "scheduler", None), scene=scene)
    for note in getattr(args, "plan_notes", ()):  # the plan, once every check has passed
        print(note, file=sys.stderr)


def _run_stage(name: str, scenario: ResolvedScenario, args: argparse.Namespace) -> None:
    options = _options(args)
    module = importlib.import_module(STAGES[name])
    start = time.perf_counter()
    path = module.run(scenario, args.data_dir, options)
    elapsed = time.perf_counter() - start
    _record_timing(args.data_dir, name, elapsed, scenario.config_hash(name))
    print(f"{name}: wrote {path} in {elapsed:.2f} s", file=sys.stderr)


def _record_timing(data_dir: Path, step: str, seconds: float, config_hash: str) -> None:
    """Merge a step's wall time into ``<data_dir>/timings.json`` (read by the report).

    Each entry records the configuration hash it was run with, so the report shows only the
    times of the outputs it describes.
    """
    from pipeline.store import atomic_path

    path = Path(data_dir) / "timings.json"
    try:
        timings = json.loads(path.read_text()) if path.is_file() else {}
    except (OSError, ValueError):
        timings = {}  # a damaged timings file is only a cache of wall times
    timings[step] = {"seconds": round(seconds, 3), "config_hash": config_hash,
                     "finished": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime())}
    with atomic_path(path) as tmp:
        tmp.write_text(json.dumps(timings, indent=1, sort_keys=True) + "\n")


def _cmd_stage(args: argparse.Namespace, scenario: ResolvedScenario) -> None:
    _preflight(args, scenario)
    _run_stage(args.command, scenario, args)


def _cmd_run(args: argparse.Namespace, scenario: ResolvedScenario) -> None:
    _preflight(args, scenario)
    if args.check:
        print("run: every check before work passed (configuration, surrogate grid, plan, scene)", file=sys.stderr)
        return
    from pipeline.config import STAGE_UPSTREAM
    from pipeline.store import stage_path, stage_problem

    rebuilt: set[str] = set()
    for name in STAGES:  # as make: a stage file built from this configuration, on kept inputs, is kept
        if stage_problem(args.data_dir, name, scenario) is None and not rebuilt & set(STAGE_UPSTREAM[name]):
            print(f"{name}: up to date, kept {stage_path(args.data_dir, name)}", file=sys.stderr)
            continue
        _run_stage(name, scenario, args)
        rebuilt.add(name)
    if not args.no_bench:  # what make run adds to the report (the Makefile's PHYSICS_BENCH)
        from pipeline.bench import physics_benchmarks

        for line in physics_benchmarks(scenario, args.data_dir):
            print(line, file=sys.stderr)
    _cmd_figures(args, scenario)
    _cmd_report(args, scenario)


def _cmd_figures(args: argparse.Namespace, scenario: ResolvedScenario) -> None:
    from analysis.figures import write_figures

    from pipeline.store import stage_problem

    _preflight(args, scenario, scene=False)
    # checked before drawing, so that no figure is replaced by half a set
    _refuse_if("figures", [p for p in (stage_problem(args.data_dir, s, scenario) for s in STAGES) if p])
    start = time.perf_counter()
    for path in write_figures(scenario, args.data_dir):
        print(f"figure: {path}", file=sys.stderr)
    _record_timing(args.data_dir, "figures", time.perf_counter() - start, scenario.config_hash())


def _refuse_if(what: str, problems: list[str]) -> None:
    """One line for the first problem (and how many more) before anything is written."""
    if problems:
        more = f" (and {len(problems) - 1} more)" if len(problems) > 1 else ""
        raise StaleInputError(f"{what} not written: {problems[0]}{more}")


def _report_problems(data_dir: Path, scenario: Scenario) -> list[str]:
    """Why a report of ``data_dir`` would describe missing, stale or outdated results."""
    from pipeline.store import stage_path, stage_problem

    problems = [p for p in (stage_problem(data_dir, s, scenario) for s in ("fits", "surrogate")) if p]
    stages = [stage_path(data_dir, s) for s in STAGES if stage_path(data_dir, s).is_file()]
    figures = sorted((data_dir / "figures").glob("fig*.png"))  # the study's figures, not the benchmarks'
    if not figures:
        problems.append(f"{data_dir / 'figures'} holds no figures: run `g2tom figures` (or `make figures`)")
    elif stages:
        newest = max(stages, key=lambda p: p.stat().st_mtime_ns)
        oldest = min(figures, key=lambda p: p.stat().st_mtime_ns)
        if oldest.stat().st_mtime_ns < newest.stat().st_mtime_ns:
            problems.append(f"{oldest} is older than {newest}: run `g2tom figures` (or `make figures`)")
    return problems


def _cmd_report(args: argparse.Namespace, scenario: ResolvedScenario) -> None:
    from analysis.report import write_report

    _preflight(args, scenario, scene=False)
    _refuse_if("report", _report_problems(args.data_dir, scenario))
    for path in write_report(scenario, args.data_dir):
        print(f"report: {path}", file=sys.stderr)


def _cmd_bench(args: argparse.Namespace, scenario: ResolvedScenario) -> None:
    from pipeline.bench import run_benchmarks

    _preflight(args, scenario, scene=False)
    run_benchmarks(scenario, args.data_dir, only=args.only, verbose=args.verbose)


def _cmd_stamp(args: argparse.Namespace, scenario: ResolvedScenario) -> None:
    """Write ``<data>/.stamps/<stage>.json`` only when its content changes (for make).

    A stamp is also touched when its stage file exists but is unreadable (a truncated or
    damaged file) or was built from another configuration (e.g. by ``g2tom fits --set
    ...``), so that make rebuilds it instead of failing on it forever.
    """
    from pipeline.store import stage_path, stage_problem

    _preflight(args, scenario, scene=False)
    stamps = args.data_dir / ".stamps"
    stamps.mkdir(parents=True, exist_ok=True)
    for stage in STAGE_INPUTS:
        text = json.dumps(
            {"config_hash": scenario.config_hash(stage), "parameters": scenario.stage_parameters(stage)},
            indent=1,
            sort_keys=True,
        )
        path = stamps / f"{stage}.json"
        if not path.is_file() or path.read_text() != text:
            path.write_text(text)
        elif stage_path(args.data_dir, stage).is_file():
            problem = stage_problem(args.data_dir, stage, scenario)
            if problem:
                print(f"g2tom: {problem}; make will rebuild it", file=sys.stderr)
                os.utime(path)


def _cmd_params(args: argparse.Namespace, scenario: Scenario) -> None:
    flat = scenario.flat()
    for key, _default, unit, allowed, doc in parameter_table():
        print(f"{key:32s} {flat[key]!s:>24}  [{unit}]  {allowed}: {doc}")


def _cmd_plan(args: argparse.Namespace, scenario: ResolvedScenario) -> None:
    from pipeline.before_work.plan import format_plan

    if args.validate:
        from pipeline.reference.validate import format_validate_plan

        print("\n".join(format_validate_plan(args.config, args.workers)))
        return

    if args.atlas:
        from pipeline.atlas.design import AtlasDesign, format_atlas_plan, plan_atlas

        # one single-threaded scene per worker
        parallel = max(1, args.workers or os.cpu_count() or 1)
        print("\n".join(format_atlas_plan(plan_atlas(scenario, AtlasDesign.of(scenario)), parallel)))
        return
    print("\n".join(format_plan(scenario, getattr(args, "workers", None))))


def _cmd_predict(args: argparse.Namespace, scenario: Scenario) -> None:
    from pipeline.cli.predict import predict_cli
    from pipeline.store import stage_path, unreadable

    surrogate = args.surrogate or stage_path(args.data_dir, "surrogate")
    problem = Path(surrogate).suffix != ".json" and Path(surrogate).is_file() and unreadable(surrogate, "surrogate")
    if problem:
        raise StaleInputError(problem)

    predict_cli(args, scenario)


def _cmd_atlas(args: argparse.Namespace, scenario: ResolvedScenario) -> None:
    from pipeline.atlas.run import run_atlas
    from pipeline.atlas.design import AtlasDesign

    _preflight(args, scenario, scene=False)
    if args.workers is None and args.scheduler is None:
        args.workers = os.cpu_count() or 1  # a local cluster, one single-threaded scene per core
    path = run_atlas(scenario, AtlasDesign.of(scenario), args.data_dir, _options(args))
    print(f"atlas: wrote {path}", file=sys.stderr)
    from pipeline.atlas.fit import write_atlas_surrogate

    target, doc = write_atlas_surrogate(path)
    held, worst = doc["heldout"], doc["heldout"]["worst"]
    curve = doc["log_resistance"]
    print(f"atlas: wrote {target}: curve model the grid surrogate (degree {curve['degree']} in the groups, order "
          f"{curve['order']} in ln F', by leave-one-scene-out cross-validation); held out: {held['cells_within']} of "
          f"{held['cells']} cells within max(5 %, interval) at every step; worst {worst['scene']} (xi {worst['xi']:g}, "
          f"lambda {worst['lambda']:g}, F' {worst['force_normalized']:.3g}): {worst['error']:.3g} in ln R' vs "
          f"{worst['allowed']:.3g} allowed; targets {'met' if held['met'] else 'not met'}", file=sys.stderr)


def _cmd_roughness(args: argparse.Namespace, scenario: Scenario) -> None:
    from pipeline.cli.roughness import roughness_cli

    roughness_cli(args)


def _cmd_validate(args: argparse.Namespace, scenario: Scenario) -> None:
    """The full-field reference against g2tom (pipeline.reference); the extra is checked first."""
    from pipeline.reference import missing_extra

    if args.overrides:
        raise ConfigError("g2tom validate runs its own validation scene (the default set or --quick): --set is "
                          "not used by it; leave it out (--config names the scenario whose model part 2 validates)")
    from pipeline.before_work.preflight import check_data_dir, check_scheduler
    from pipeline.reference.validate import chosen_set, output_folder, run_validation

    vset = chosen_set(args.quick, args.surface, realizations=args.realizations, loads=args.loads)
    check_data_dir(args.data_dir)
    if args.scheduler:
        check_scheduler(args.scheduler)
    problem = missing_extra()
    if problem:
        raise ConfigError(problem)
    if args.workers is None and args.scheduler is None:
        args.workers = os.cpu_count() or 1  # a local cluster, one single-threaded case per core (as the atlas)
    from analysis.figures_validate import figure

    run_validation(vset, output_folder(args.data_dir, args.surface), progress=not args.no_progress, draw=figure,
                   config=args.config, options=_options(args))


def _version() -> str:
    from pipeline.store import git_commit

    commit = git_commit()
    return f"g2tom {__version__}" + (f" (git {commit})" if commit else "")


def _rejoin(overrides: Sequence[str]) -> list[str]:
    """Glue back ``--set`` values that were split at spaces inside brackets or quotes.

    make's ``SET="oxide.xi=[0.3, 0.5]"`` becomes ``--set oxide.xi=[0.3,`` ``--set 0.5]``: a
    fragment is joined to the next until its brackets balance and its quotes close.
    """
    out: list[str] = []
    pending = ""
    for item in overrides:
        pending = f"{pending} {item}" if pending else item
        text = pending.partition("=")[2]
        balanced = (text.count("[") <= text.count("]") and text.count('"') % 2 == 0
                    and text.count("'") % 2 == 0)
        if balanced:
            out.append(pending)
            pending = ""
    if pending:
        out.append(pending)
    return out


def _load(args: argparse.Namespace) -> Scenario:
    """The scenario of ``--config`` and ``--set``; unreadable files become ConfigError."""
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("default")
            return load_scenario(args.config, _rejoin(args.overrides))
    except UnicodeDecodeError as exc:
        raise ConfigError(f"--config {args.config!r} is not UTF-8 text (byte {exc.start}: "
                          f"{exc.object[exc.start:exc.start + 1]!r}); save it as UTF-8") from None
    except OSError as exc:
        raise ConfigError(f"--config {args.config!r} is unreadable ({exc.strerror or exc})") from None


class _Parser(argparse.ArgumentParser):
    """argparse with its refusals as one ``g2tom: error:`` line (exit status 2)."""

    def error(self, message: str) -> NoReturn:
        self.exit(2, f"g2tom: error: {self.prog}: {message} (see `{self.prog} --help`)\n")


_NEGATIVE = re.compile(r"^-(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?$|^-(inf|nan)$", re.IGNORECASE)


def _attach_negative_values(argv: Sequence[str]) -> list[str]:
    """``--opt -1e-6`` as ``--opt=-1e-6``: argparse takes ``-1e-6`` for an option otherwise."""
    out: list[str] = []
    for item in argv:
        if out and out[-1].startswith("--") and "=" not in out[-1] and _NEGATIVE.match(item):
            out[-1] = f"{out[-1]}={item}"
        else:
            out.append(item)
    return out


def _parser() -> argparse.ArgumentParser:
    parser = _Parser(
        prog="g2tom",
        description="Electrical contact resistance of rough, partially oxidized sphere-on-flat contacts.",
    )
    parser.add_argument("--version", action="version", version=_version())
    sub = parser.add_subparsers(dest="command", required=True, parser_class=_Parser)
    handlers: dict[str, Callable[[argparse.Namespace, Scenario], None]] = {}

    def add(name: str, handler: Callable, help_text: str, compute: bool = False) -> argparse.ArgumentParser:
        p = sub.add_parser(name, help=help_text)
        _scenario_args(p)
        if compute:
            _compute_args(p)
        p.set_defaults(handler=handler)
        handlers[name] = handler
        return p

    for stage in STAGES:
        add(stage, _cmd_stage, f"run the {stage} stage", compute=True)
    run = add("run", _cmd_run, "run every stage not up to date, the physics benchmarks, the figures and the report", compute=True)
    run.add_argument("--check", action="store_true",
                     help="only the checks a run makes before work (make run calls it before the first stage)")
    run.add_argument("--no-bench", action="store_true",
                     help="leave out the physics benchmarks the report shows (spots, biases; about a minute)")
    add("figures", _cmd_figures, "write the figures under <data-dir>/figures")
    add("report", _cmd_report, "write <data-dir>/report.md and report.html")
    bench = add("bench", _cmd_bench, "benchmarks: run time against error, printed and saved")
    bench.add_argument("--only", action="append", default=None, help="run only this benchmark")
    bench.add_argument("--verbose", action="store_true", help="print every figure, not only where it was saved")
    add("stamp", _cmd_stamp, "update per-stage configuration stamps (used by make)")
    plan = add("plan", _cmd_plan, "estimate each stage's peak memory and run time; refuse what cannot fit",
               compute=True)
    plan.add_argument("--atlas", action="store_true",
                      help="plan the atlas's default design over (mu, Pi) on this scenario (one scene per worker)")
    plan.add_argument("--validate", action="store_true",
                      help="plan `g2tom validate`'s default set on both surfaces, part 2 validating this scenario")
    add("atlas", _cmd_atlas, "run the chain on every scene of the atlas's design over (mu, Pi), one scene per "
        "task, resumable (<data-dir>/atlas/)", compute=True)
    add("params", _cmd_params, "list every parameter with its value, unit and range")
    predict = add("predict", _cmd_predict, "predict R_el with the surrogate (Eq. 27)")
    predict.add_argument("--force", default=None, help="normal force F, N: a number or a comma-separated list")
    predict.add_argument("--xi", default=None, help="oxide fraction in (0, 1): a number or a comma-separated list")
    predict.add_argument("--lambda", dest="lam", default=None, help="l_O sqrt(eta) > 0: a number or a comma-separated list")
    predict.add_argument("--csv", type=Path, default=None, help="CSV file of queries with columns force, xi, lambda")
    predict.add_argument("--output", type=Path, default=None,
                         help="write the CSV (or --json) result here (default: stdout; on a terminal, a short table)")
    predict.add_argument("--json", action="store_true", help="the result as one JSON object (SI units)")
    predict.add_argument("--extrapolate", action="store_true", help="allow queries outside the fitted ranges (with a warning)")
    predict.add_argument("--model", choices=("curve", "power_law"), default="curve",
                         help="curve: each cell's ln R'(ln F') curve, interpolated (default); power_law: Eq. 27")
    predict.add_argument("--roughness", type=Path, default=None,
                         help="a measured topography (see `g2tom roughness`): its summit sigma, eta and beta "
                              "replace roughness.*")
    predict.add_argument("--pixel-size", type=float, default=None,
                         help="with --roughness: pixel size, m (for .npy, netCDF and text maps)")
    predict.add_argument("--surrogate", type=Path, default=None,
                         help="surrogate.json or surrogate.nc (default: <data-dir>/surrogate.json, else surrogate.nc)")
    validate = add("validate", _cmd_validate,
                   "the full-field elastic contact (tamaas) against g2tom, part 1 per surface and part 2 the "
                   "--config scenario's ensemble: <data-dir>/validate/", compute=True)
    validate.add_argument("--quick", action="store_true",
                          help="256^2 grid, two realizations, two loads, clean and one oxidized case; part 2 on 128^2")
    validate.add_argument("--realizations", type=int, default=None,
                          help="part 1's surfaces (and oxide fields) 0 .. N-1 instead of the set's (>= 2)")
    validate.add_argument("--loads", type=int, default=None,
                          help="load steps evenly spaced in delta/sigma over the set's range (>= 2)")
    validate.add_argument("--surface", choices=("gw", "random_process"), default="gw",
                          help="gw: asperities with g2tom's own parameters (<data-dir>/validate/); random_process: a "
                               "Gaussian self-affine surface, g2tom fed its summit statistics (<data-dir>/validate_random_process/)")
    rough = add("roughness", _cmd_roughness, "sigma, eta and beta from a measured height map")
    rough.add_argument("heightmap", type=Path, help=".npy, netCDF or text (heights in m), or an instrument file "
                       "(read by the optional package SurfaceTopography)")
    rough.add_argument("--pixel-size", type=float, default=None,
                       help="pixel size, m (required for .npy, netCDF and text; overrides an instrument file's)")
    rough.add_argument("--cutoff", type=float, default=None,
                       help="shortest wavelength in the moments, m (default: 4 pixels)")
    rough.add_argument("--periodic", action="store_true", help="the map is one period (no window, mean removed)")
    rough.add_argument("--beta-rule", choices=("paper", "nayak"), default="paper",
                       help="beta = 0.737/sqrt(m4) (paper, default) or 0.375 sqrt(pi/m4) (nayak)")
    rough.add_argument("--json", action="store_true", help="print one JSON object (SI units)")
    return parser


def _one_line_warning(message, category, filename, lineno, line=None) -> str:  # noqa: ANN001
    """Warnings as one ``g2tom: warning:`` line, without the source line that raised them."""
    return f"g2tom: warning: {message}\n"


#: Exit status after Ctrl-C (128 + SIGINT, as a shell reports a command killed by it).
INTERRUPTED = 130


def _kept(args: argparse.Namespace) -> str:
    """What an interrupted command kept, and how to go on from it (one line)."""
    if args.command == "validate":
        from pipeline.reference.validate import output_folder

        where = output_folder(args.data_dir, args.surface) / "cases"
        return (f"the cases finished so far are kept in {where}; run the same `g2tom validate` command again to "
                "continue from them")
    if args.command == "atlas":
        return (f"the scenes finished so far are kept in {Path(args.data_dir) / 'atlas'}; run the same `g2tom atlas` "
                "command again to continue from them")
    return "stopped before the end; run the command again"


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``g2tom`` console script; returns the exit status."""
    parser = _parser()
    args = parser.parse_args(_attach_negative_values(sys.argv[1:] if argv is None else argv))
    formatwarning = warnings.formatwarning
    warnings.formatwarning = _one_line_warning
    try:
        scenario = _load(args)
        if args.command in _REACH_SURROGATE:
            check_surrogate_grid(scenario)
        if getattr(args, "workers", None) is not None:
            _options(args)  # --workers is checked before the plan is announced
        with warnings.catch_warnings():
            warnings.simplefilter("default")
            scenario, args.plan_notes = prepare(args.command, scenario, getattr(args, "workers", None))
        args.handler(args, scenario)
    except ConfigError as exc:
        print(f"g2tom: error: {exc}", file=sys.stderr)
        return 2
    except StaleInputError as exc:
        print(f"g2tom: error: {exc}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print(f"g2tom: interrupted: {_kept(args)}", file=sys.stderr)
        return INTERRUPTED
    finally:
        warnings.formatwarning = formatwarning
    return 0


if __name__ == "__main__":
    sys.exit(main())
