"""``g2tom``'s arguments: every subcommand, its options and its handler, declared for argparse."""

from __future__ import annotations

import argparse
import re
from pathlib import Path
from typing import Callable, NoReturn, Sequence

from g2tom import __version__
from g2tom.cli import commands
from g2tom.config import bundled_scenarios

__all__ = ["attach_negative_values", "build_parser", "default_config"]


def _scenario_args(p: argparse.ArgumentParser) -> None:
    """Every subcommand's options: the scenario (``--config``, ``--set``) and ``--data-dir``."""
    p.add_argument(
        "--config",
        default=None,
        help=f"bundled scenario name ({', '.join(bundled_scenarios())}) or a TOML file (default: paper; "
             "atlas for `g2tom atlas` and `g2tom plan --atlas`)",
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


def default_config(args: argparse.Namespace) -> str:
    """The scenario a command runs without ``--config``: the bundled ``atlas`` for ``g2tom atlas``
    and ``g2tom plan --atlas`` (the atlas's own base scene, as ``make atlas`` passes), else ``paper``."""
    if args.config is not None:
        return args.config
    return "atlas" if args.command == "atlas" or getattr(args, "atlas", False) else "paper"


def _compute_args(p: argparse.ArgumentParser) -> None:
    """A computing subcommand's options: where dask runs and whether progress is shown."""
    p.add_argument("--scheduler", default=None, help="address of a dask.distributed scheduler")
    p.add_argument("--workers", type=int, default=None, help="local dask workers (default: cores)")
    p.add_argument("--no-progress", action="store_true", help="hide the progress bar")


def _device_arg(p: argparse.ArgumentParser, what: str) -> None:
    """``--device``: where the full field's solves of ``what`` run (:mod:`g2tom.reference.devices`)."""
    p.add_argument("--device", default="cpu",
                   help=f"where {what} compute: cpu (default), gpu (CuPy, the optional extra 'gpu'; one at a time "
                        "unless --workers) or auto (gpu when CuPy sees one, else cpu)")


def _version() -> str:
    """``--version``'s line: the package version and, in a git checkout, its commit."""
    from g2tom.store import git_commit

    commit = git_commit()
    return f"g2tom {__version__}" + (f" (git {commit})" if commit else "")


class _Parser(argparse.ArgumentParser):
    """argparse with its refusals as one ``g2tom: error:`` line (exit status 2)."""

    def error(self, message: str) -> NoReturn:
        self.exit(2, f"g2tom: error: {self.prog}: {message} (see `{self.prog} --help`)\n")


_NEGATIVE = re.compile(r"^-(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?$|^-(inf|nan)$", re.IGNORECASE)


def attach_negative_values(argv: Sequence[str]) -> list[str]:
    """``--opt -1e-6`` as ``--opt=-1e-6``: argparse takes ``-1e-6`` for an option otherwise."""
    out: list[str] = []
    for item in argv:
        if out and out[-1].startswith("--") and "=" not in out[-1] and _NEGATIVE.match(item):
            out[-1] = f"{out[-1]}={item}"
        else:
            out.append(item)
    return out


def build_parser() -> argparse.ArgumentParser:
    """The ``g2tom`` parser: each subcommand's options, and its handler as ``handler``
    (:mod:`g2tom.cli.commands`)."""
    parser = _Parser(
        prog="g2tom",
        description="Electrical contact resistance of rough, partially oxidized sphere-on-flat contacts.",
    )
    parser.add_argument("--version", action="version", version=_version())
    sub = parser.add_subparsers(dest="command", required=True, parser_class=_Parser)

    def add(name: str, handler: Callable, help_text: str | None, compute: bool = False) -> argparse.ArgumentParser:
        """Subcommand ``name``; without ``help_text`` it is left out of ``g2tom --help`` (still runs)."""
        p = sub.add_parser(name, **({"help": help_text} if help_text else {}))
        _scenario_args(p)
        if compute:
            _compute_args(p)
        p.set_defaults(handler=handler)
        return p

    for stage in commands.STAGES:
        add(stage, commands.stage, f"run the {stage} stage", compute=True)
    run = add("run", commands.run, "run every stage not up to date, the physics benchmarks, the figures and the report", compute=True)
    run.add_argument("--check", action="store_true",
                     help="only the checks a run makes before work (make run calls it before the first stage)")
    run.add_argument("--no-bench", action="store_true",
                     help="leave out the physics benchmarks the report shows (spots, biases; about a minute)")
    figures = add("figures", commands.figures, "write the figures under <data-dir>/figures")
    figures.add_argument("--only", action="append", default=None, metavar="FAMILY",
                         help="draw only this family of figures (repeatable; an unknown name lists them)")
    add("report", commands.report, "write <data-dir>/report.md and report.html")
    bench = add("bench", commands.bench, "benchmarks: run time against error, printed and saved")
    bench.add_argument("--only", action="append", default=None, help="run only this benchmark")
    bench.add_argument("--verbose", action="store_true", help="print every figure, not only where it was saved")
    add("stamp", commands.stamp, None)  # make's own: per-stage configuration stamps
    plan = add("plan", commands.plan, "estimate each stage's peak memory and run time; refuse what cannot fit",
               compute=True)
    plan.add_argument("--atlas", action="store_true",
                      help="plan the atlas's default design over (mu, Pi) on this scenario (one scene per worker)")
    plan.add_argument("--validate", action="store_true",
                      help="plan `g2tom validate`'s default set on both surfaces, part 2 validating this scenario")
    add("atlas", commands.atlas, "run the chain on every scene of the atlas's design over (mu, Pi), one scene per "
        "task, resumable (<data-dir>/atlas/)", compute=True)
    params = add("params", commands.params, "list every parameter with its value, unit and range")
    params.add_argument("--resolved", action="store_true",
                        help="the values a run uses: 'auto' domains (contact.window, contact.r_max) resolved from "
                             "the solution, and the cell grid they give")
    predict = add("predict", commands.predict, "predict R_el at forces, oxide fractions and lambdas: the run's own "
                  "surrogate on its surface, else the atlas's; each cell's ln R'(ln F') curve (--model power_law: "
                  "Eq. 27, a run's own surrogate only)")
    predict.add_argument("--force", default=None, help="normal force F, N: a number or a comma-separated list")
    predict.add_argument("--xi", default=None, help="oxide fraction in (0, 1): a number or a comma-separated list")
    predict.add_argument("--lambda", dest="lam", default=None, help="l_O sqrt(eta) > 0: a number or a comma-separated list")
    predict.add_argument("--csv", type=Path, default=None, help="CSV file of queries with columns force, xi, lambda")
    predict.add_argument("--output", type=Path, default=None,
                         help="write the CSV (or --json) result here (default: stdout; on a terminal, a short table)")
    predict.add_argument("--json", action="store_true", help="the result as one JSON object (SI units)")
    predict.add_argument("--extrapolate", action="store_true", help="allow queries outside the fitted ranges (with a warning)")
    predict.add_argument("--model", choices=("curve", "power_law"), default="curve",
                         help="curve: each cell's ln R'(ln F') curve, interpolated (default); power_law: Eq. 27 "
                              "(a run's own surrogate only: the atlas answers with its curve model)")
    predict.add_argument("--roughness", type=Path, default=None,
                         help="a measured topography (see `g2tom roughness`): its summit sigma, eta and beta "
                              "replace roughness.*")
    predict.add_argument("--pixel-size", type=float, default=None,
                         help="with --roughness: pixel size, m (for .npy, netCDF and text maps)")
    predict.add_argument("--surrogate", type=Path, default=None,
                         help="surrogate.json or surrogate.nc (default: <data-dir>/surrogate.json, else surrogate.nc)")
    validate = add("validate", commands.validate,
                   "the full-field elastic contact (tamaas) against g2tom, part 1 per surface and part 2 the "
                   "--config scenario's ensemble: <data-dir>/validate/", compute=True)
    validate.add_argument("--quick", action="store_true",
                          help="256^2 grid, two realizations, two loads, clean and one oxidized case; part 2 on 128^2")
    validate.add_argument("--realizations", type=int, default=None,
                          help="part 1's surfaces (and oxide fields) 0 .. N-1 instead of the set's (>= 2)")
    validate.add_argument("--loads", type=int, default=None,
                          help="load steps evenly spaced in delta/sigma over the set's range (>= 2)")
    validate.add_argument("--steps", default=None,
                          help="only these of the set's load steps, comma-separated, 1 = the lightest (e.g. 4,5)")
    validate.add_argument("--standard-error", default=None,
                          help="part 2's goal for the standard error of ln R: CLEAN[,OXIDIZED] in (0, 0.5] "
                               "(default 0.03,0.05)")
    for flag, text in (("--max-realizations", "part 2's most full-field realizations a load (default 512, >= 2)"),
                       ("--max-pairs", "part 2's most main-grid pairs a load (default 24, >= 2)"),
                       ("--model-realizations", "part 2's surfaces and oxide realizations of the validated "
                                                "scenario (default 1024, >= 16)")):
        validate.add_argument(flag, type=int, default=None, help=text)
    validate.add_argument("--plan", action="store_true",
                          help="print this set's cases, grids and estimate (as the run prints first), then stop: "
                               "no work, nothing written")
    _device_arg(validate, "the reference's cases")
    validate.add_argument("--solver", default=None,
                          help="the reference's contact and punch solver: g2tom (our own, the default: equal to "
                               "tamaas within 1e-7 and on the CPU about twice as fast; the GPU's) or tamaas "
                               "(the CPU only; the optional extra 'reference')")
    validate.add_argument("--surface", choices=("gw", "random_process"), default="gw",
                          help="gw: asperities with g2tom's own parameters (<data-dir>/validate/); random_process: a "
                               "Gaussian self-affine surface, g2tom fed its summit statistics (<data-dir>/validate_random_process/)")
    rough = add("roughness", commands.roughness, "sigma, eta and beta from a measured height map")
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
    surface = add("surface", commands.surface,
                  "the full-field resistance of a measured height map (or two: their sum) at given forces, clean "
                  "and with oxide, over contact positions: <data-dir>/surface/", compute=True)
    surface.add_argument("heightmap", type=Path, help="the height map (any format `g2tom roughness` reads)")
    surface.add_argument("second", type=Path, nargs="?", default=None,
                         help="the other body's height map: the composite (sum) is pressed on a flat")
    surface.add_argument("--force", default=None, help="normal forces F, N: a number or a comma-separated list")
    surface.add_argument("--pixel-size", type=float, default=None,
                         help="pixel size, m (required for .npy, netCDF and text; overrides an instrument file's)")
    surface.add_argument("--xi", default=None, help="oxide fractions in (0, 1), comma-separated (with "
                         "--correlation-length; neither: clean only)")
    surface.add_argument("--correlation-length", default=None,
                         help="oxide correlation lengths l_O, m, comma-separated (at least one pixel)")
    surface.add_argument("--fields", type=int, default=8, help="oxide fields per position and case (default 8)")
    surface.add_argument("--positions", type=int, default=None,
                         help="contact positions spread over the map (default: every window that shares no pixel "
                              "with another, at most 16; more overlap)")
    surface.add_argument("--at", default=None,
                         help="one contact at X,Y (m from the centre of the map's first pixel) or 'centre'")
    surface.add_argument("--window", type=int, default=None,
                         help="window side, pixels (default: the smallest that holds the heaviest force's contact)")
    surface.add_argument("--detrend", choices=("plane", "none"), default="plane",
                         help="remove the measured pixels' least-squares plane (default) or nothing")
    surface.add_argument("--extend", choices=("none", "spectrum"), default="none",
                         help="a map smaller than the window: refused (none, default) or windows drawn from its own "
                              "isotropic power spectrum, longer wavelengths at the plateau of its longest (spectrum)")
    _device_arg(surface, "the positions")
    surface.add_argument("--plan", action="store_true",
                         help="print the map, window, positions, work and its estimated time and memory, then stop")
    surface.add_argument("--output", type=Path, default=None, help="folder of the outputs (default <data-dir>/surface)")
    sub.metavar = "{" + ",".join(name for name, p in sub.choices.items() if name != "stamp") + "}"
    return parser
