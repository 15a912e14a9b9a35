"""Benchmarks behind ``make bench``: run time against error, as ratios to a plain reference.

Each module ``g2tom.bench.<name>`` exposes ``run(scenario) -> dict`` returning JSON-ready
figures (medians of repeated timings, errors, ratios to a reference run in the same process).
:func:`run_benchmarks` saves ``<data_dir>/bench/<name>.json`` (and prints them with ``verbose``). Modules whose
``run`` also takes ``data_dir`` save labelled data there too: ``frontier`` (the accuracy–time
frontier, ``bench/frontier.nc`` and its figures; its sweeps, prefix curve and figures in
``frontier_sweeps``, ``frontier_prefix`` and ``frontier_plot``) and ``stability``
(``bench/stability.nc``); ``schema`` declares those files' variables. ``biases`` reads the contact
stage's file there instead (the steps' contact it holds, not solved again).
"""

from __future__ import annotations

import importlib
import inspect
import json
import os
import platform
from pathlib import Path
from typing import Any, Iterable, Mapping

from g2tom import __version__
from g2tom.config import ConfigError, Scenario
from g2tom.store import atomic_path

__all__ = ["BENCHMARKS", "PHYSICS_BENCH", "bench_problem", "physics_benchmarks", "run_benchmarks", "summary_lines"]

BENCHMARKS: tuple[str, ...] = (
    "contact", "oxide", "cube", "point", "scaling", "predict", "convergence", "stability", "frontier", "spots",
    "biases", "discrete", "gpu", "solver", "surface", "surface_gpu",
)
#: The physics benchmarks the report shows beside the study: ``g2tom run`` and ``make run`` (its
#: PHYSICS_BENCH) run them before the figures and the report.
PHYSICS_BENCH: tuple[str, ...] = ("spots", "biases")


def _machine() -> dict[str, Any]:
    return {"cores": os.cpu_count(), "python": platform.python_version(), "g2tom": __version__}


def _short(value: Any) -> str:
    if isinstance(value, float):
        return f"{value:.4g}"
    if isinstance(value, list) and len(value) > 4 and all(isinstance(v, (int, float)) for v in value):
        return f"[{len(value)} values, {min(value):.4g} .. {max(value):.4g}]"
    return str(value)


def summary_lines(result: Mapping[str, Any], prefix: str = "") -> list[str]:
    """``key: value`` lines of a nested result, long numeric lists shown as count and range."""
    lines: list[str] = []
    for key, value in result.items():
        if key == "machine":
            continue
        if isinstance(value, Mapping):
            lines += summary_lines(value, f"{prefix}{key}.")
        elif isinstance(value, list) and value and all(isinstance(v, Mapping) for v in value):
            for i, item in enumerate(value):
                lines += summary_lines(item, f"{prefix}{key}[{i}].")
        else:
            lines.append(f"  {prefix}{key}: {_short(value)}")
    return lines


def run_benchmarks(scenario: Scenario, data_dir: str | Path, only: Iterable[str] | None = None,
                   verbose: bool = False) -> dict[str, Path]:
    """Run the benchmarks (all, or ``only`` those named) and save each as JSON: one line per
    benchmark naming its file, or with ``verbose`` every figure (:func:`summary_lines`); a benchmark
    that could not run (its result's ``skipped``: why) says so instead.

    Returns
    -------
    dict
        Benchmark name -> the ``<data_dir>/bench/<name>.json`` written.

    Raises
    ------
    ConfigError
        If ``only`` names an unknown benchmark (the CLI then exits with status 2).
    """
    names = tuple(only) if only else BENCHMARKS
    unknown = [n for n in names if n not in BENCHMARKS]
    if unknown:
        raise ConfigError(f"--only {unknown[0]!r} is not a benchmark: must be one of {', '.join(BENCHMARKS)}")
    out_dir = Path(data_dir) / "bench"
    written: dict[str, Path] = {}
    for name in names:
        module = importlib.import_module(f"g2tom.bench.{name}")
        extra = {"data_dir": data_dir} if "data_dir" in inspect.signature(module.run).parameters else {}
        result = {"benchmark": name, "scenario": scenario.name, "config_hash": scenario.config_hash(),
                  "machine": _machine(), **module.run(scenario, **extra)}
        text = json.dumps(result, indent=2, sort_keys=False, default=float)
        target = out_dir / f"{name}.json"
        with atomic_path(target) as tmp:
            tmp.write_text(text + "\n")
        lines = summary_lines(result)
        if "skipped" in result:  # e.g. the GPU benchmark without a GPU: its file holds only why
            print(f"bench {name}: skipped ({result['skipped']}); {target} says so")
        elif verbose:
            print(f"== bench {name} ==")
            print("\n".join(lines))
        else:
            print(f"bench {name}: {len(lines)} figures in {target} (`g2tom bench --only {name} --verbose` prints them)")
        written[name] = target
    return written


def bench_problem(data_dir: str | Path, name: str, scenario: Scenario) -> str | None:
    """Why ``<data_dir>/bench/<name>.json`` cannot be kept for ``scenario`` (one line), or None if it can.

    A benchmark's JSON is kept when it is readable and records the scenario's whole configuration
    hash (:meth:`~g2tom.config.Scenario.config_hash`).
    """
    path = Path(data_dir) / "bench" / f"{name}.json"
    if not path.is_file():
        return f"{path} is missing"
    try:
        found = json.loads(path.read_text()).get("config_hash")
    except (OSError, ValueError, AttributeError):
        return f"{path} is unreadable"
    if found != scenario.config_hash():
        return f"{path} was written for another configuration (config_hash {found}, needs {scenario.config_hash()})"
    return None


def physics_benchmarks(scenario: Scenario, data_dir: str | Path) -> list[str]:
    """Run those of :data:`PHYSICS_BENCH` that are not current (:func:`bench_problem`), keep the others.

    Returns
    -------
    list of str
        One line per benchmark: ``bench spots: up to date, kept <path>`` or ``bench spots: wrote <path>``.
    """
    stale = [name for name in PHYSICS_BENCH if bench_problem(data_dir, name, scenario)]
    written = run_benchmarks(scenario, data_dir, only=stale) if stale else {}
    return [f"bench {name}: wrote {written[name]}" if name in written
            else f"bench {name}: up to date, kept {Path(data_dir) / 'bench' / f'{name}.json'}"
            for name in PHYSICS_BENCH]
