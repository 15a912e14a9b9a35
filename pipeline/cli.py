"""The ``g2tom`` command: run stages, benchmarks, figures, the report and the predictor."""

from __future__ import annotations

import os

# One BLAS/OpenMP thread per dask worker thread: set before numpy is imported anywhere.
for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import argparse  # noqa: E402
import importlib  # noqa: E402
import json  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
import warnings  # noqa: E402
from pathlib import Path  # noqa: E402
from typing import TYPE_CHECKING, Callable, Sequence  # noqa: E402

from pipeline.config import STAGE_INPUTS, ConfigError, Scenario, load_scenario, parameter_table  # noqa: E402
from pipeline.errors import StaleInputError  # noqa: E402
from pipeline.plan import prepare  # noqa: E402

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


def _scenario_args(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--config",
        default="paper",
        help="bundled scenario name (paper, published) or a TOML file (default: paper)",
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


def _run_stage(name: str, scenario: Scenario, args: argparse.Namespace) -> None:
    options = _options(args)
    module = importlib.import_module(STAGES[name])
    start = time.perf_counter()
    path = module.run(scenario, args.data_dir, options)
    elapsed = time.perf_counter() - start
    _record_timing(args.data_dir, name, elapsed)
    print(f"{name}: wrote {path} in {elapsed:.2f} s", file=sys.stderr)


def _record_timing(data_dir: Path, stage: str, seconds: float) -> None:
    """Merge a stage's wall time into ``<data_dir>/timings.json`` (read by the report)."""
    from pipeline.store import atomic_path

    path = Path(data_dir) / "timings.json"
    timings = json.loads(path.read_text()) if path.is_file() else {}
    timings[stage] = round(seconds, 3)
    with atomic_path(path) as tmp:
        tmp.write_text(json.dumps(timings, indent=1, sort_keys=True) + "\n")


def _cmd_stage(args: argparse.Namespace, scenario: Scenario) -> None:
    _run_stage(args.command, scenario, args)


def _cmd_run(args: argparse.Namespace, scenario: Scenario) -> None:
    for name in STAGES:
        _run_stage(name, scenario, args)
    _cmd_figures(args, scenario)
    _cmd_report(args, scenario)


def _cmd_figures(args: argparse.Namespace, scenario: Scenario) -> None:
    from analysis.figures import write_figures

    for path in write_figures(scenario, args.data_dir):
        print(f"figure: {path}", file=sys.stderr)


def _cmd_report(args: argparse.Namespace, scenario: Scenario) -> None:
    from analysis.report import write_report

    for path in write_report(scenario, args.data_dir):
        print(f"report: {path}", file=sys.stderr)


def _cmd_bench(args: argparse.Namespace, scenario: Scenario) -> None:
    from pipeline.bench import run_benchmarks

    run_benchmarks(scenario, args.data_dir, only=args.only)


def _cmd_stamp(args: argparse.Namespace, scenario: Scenario) -> None:
    """Write ``<data>/.stamps/<stage>.json`` only when its content changes (for make)."""
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


def _cmd_params(args: argparse.Namespace, scenario: Scenario) -> None:
    flat = scenario.flat()
    for key, _default, unit, allowed, doc in parameter_table():
        print(f"{key:32s} {flat[key]!s:>24}  [{unit}]  {allowed}: {doc}")


def _cmd_plan(args: argparse.Namespace, scenario: Scenario) -> None:
    from pipeline.plan import format_plan

    print("\n".join(format_plan(scenario, getattr(args, "workers", None))))


def _cmd_predict(args: argparse.Namespace, scenario: Scenario) -> None:
    from pipeline.predict import predict_cli

    predict_cli(args, scenario)


def _cmd_roughness(args: argparse.Namespace, scenario: Scenario) -> None:
    from pipeline.roughness_cli import roughness_cli

    roughness_cli(args)


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="g2tom",
        description="Electrical contact resistance of rough, partially oxidized sphere-on-flat contacts.",
    )
    sub = parser.add_subparsers(dest="command", required=True)
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
    add("run", _cmd_run, "run every stage, the figures and the report", compute=True)
    add("figures", _cmd_figures, "write the figures under <data-dir>/figures")
    add("report", _cmd_report, "write <data-dir>/report.md and report.html")
    bench = add("bench", _cmd_bench, "benchmarks: run time against error, printed and saved")
    bench.add_argument("--only", action="append", default=None, help="run only this benchmark")
    add("stamp", _cmd_stamp, "update per-stage configuration stamps (used by make)")
    add("plan", _cmd_plan, "estimate each stage's peak memory and run time; refuse what cannot fit",
        compute=True)
    add("params", _cmd_params, "list every parameter with its value, unit and range")
    predict = add("predict", _cmd_predict, "predict R_el with the surrogate (Eq. 27)")
    predict.add_argument("--force", type=float, required=True, help="normal force F, N")
    predict.add_argument("--xi", type=float, required=True, help="oxide fraction, (0, 1)")
    predict.add_argument("--lambda", dest="lam", type=float, required=True, help="l_O sqrt(eta)")
    predict.add_argument("--surrogate", type=Path, default=None, help="surrogate.nc (default: <data-dir>/surrogate.nc)")
    rough = add("roughness", _cmd_roughness, "sigma, eta and beta from a measured height map")
    rough.add_argument("heightmap", type=Path, help=".npy, netCDF or whitespace-separated text")
    rough.add_argument("--pixel-size", type=float, required=True, help="pixel size, m")
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``g2tom`` console script; returns the exit status."""
    parser = _parser()
    args = parser.parse_args(argv)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("default")
            scenario = load_scenario(args.config, args.overrides)
            scenario = prepare(args.command, scenario, getattr(args, "workers", None))
        args.handler(args, scenario)
    except ConfigError as exc:
        print(f"g2tom: error: {exc}", file=sys.stderr)
        return 2
    except StaleInputError as exc:
        print(f"g2tom: error: {exc}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
