"""``g2tom validate [--quick]``: the full-field reference against g2tom on one validation set.

Prints the plan first (scene, grid, cases, estimated time), runs g2tom's stages in memory for every
spot discretization and ``cube.model``, then every reference case (resumable: finished cases are
read back from ``<out>/cases/``), with one progress line per case, and writes ``validate.nc``,
the figure ``validate.png`` and the report section ``validate.md`` under ``<out>``.
"""

from __future__ import annotations

import dataclasses
import sys
import time
from pathlib import Path
from typing import Callable, TextIO

import numpy as np
import xarray as xr

from pipeline.config import ConfigError, load_scenario
from pipeline.progress import format_duration
from pipeline.reference import cases as cases_mod
from pipeline.reference import discrete_spots, scene, section, summary, surface_spots, window
from pipeline.scene import FieldSource
from pipeline.store import atomic_path

#: Largest relative difference of g2tom's forces at one delta between discretizations and models
#: (their auto domains differ); the reference is solved at the first one's.
FORCE_AGREEMENT = 1e-4

__all__ = ["available_discretizations", "default_discretization", "plan_lines", "run_validation", "chosen_set",
           "output_folder", "SURFACES"]


def available_discretizations(surface: str = "gw") -> tuple[str, ...]:
    """The spot discretizations of ``contact.spots``, and on the GW surface its own asperities in
    g2tom's cells (:data:`surface_spots.SURFACE_ASPERITIES`) and as discrete coupled caps
    (:data:`discrete_spots.DISCRETE`)."""
    own = (surface_spots.SURFACE_ASPERITIES, discrete_spots.DISCRETE) if surface == "gw" else ()
    return ("mean_area", "expected", "asperities") + own


def default_discretization() -> str:
    """The discretization of the default scenario ``paper``."""
    return load_scenario("paper").contact.spots


def plan_lines(vset: scene.ValidationSet, everything: list[cases_mod.Case]) -> list[str]:
    """The plan printed before any work (the estimate assumes no case is stored yet)."""
    seconds = cases_mod.estimate_seconds(vset, everything)
    oxide = ", ".join(f"xi {x:g}/lambda {lam:g}" for x in vset.xi for lam in vset.lambdas)
    return [
        f"validate: {vset.surface} surface" + (f" (self-affine, H {vset.hurst:g}, rms {vset.rms:g} m, wavelengths "
                                              f"{vset.short_wavelength:.3g} .. {vset.short_wavelength * vset.bandwidth_ratio:.3g} m; "
                                              "g2tom's parameters are its summits')" if vset.surface == "random_process" else "")
        + f": sigma {vset.sigma:g} m, eta {vset.eta:g} m^-2, beta {vset.beta:g} m, "
        f"R* {vset.radius:g} m, E* {vset.e_star:.4g} Pa, rho* {vset.rho:g} ohm m (mu = {vset.mu:.3f})",
        f"validate: grid {vset.n_grid}^2 on each case's window, fitted to its contact by a {window.probe_grid(vset)}^2 "
        f"probe (at most the set's {vset.side * 1e3:.3g} mm: pixels of at most {vset.pixel * 1e6:.3g} um, "
        f"{vset.pixels_per_cell:g} per asperity spacing); convergence grid "
        + (f"{vset.convergence_grid}^2" if vset.convergence_grid else "none"),
        f"validate: loads delta/sigma {list(vset.deltas)}; realizations {list(vset.realizations)}; "
        f"clean + {oxide}",
        f"validate: g2tom {' x '.join([str(list(vset.discretizations)), str(list(vset.models))])}",
        f"validate: {len(everything)} cases; estimated {format_duration(seconds)} (without stored cases)",
    ]


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
                   draw: Callable[[xr.Dataset, Path], Path] | None = None) -> list[Path]:
    """Run the set into ``out`` (plan, g2tom, every case, outputs); return the written files
    (``progress``: one line per finished case; ``draw(ds, path)`` draws ``validate.png``, e.g.
    :func:`analysis.figures_validate.figure`, which the CLI passes: the library draws nothing)."""
    start = time.perf_counter()
    out = Path(out)
    case_dir = out / "cases"
    everything = cases_mod.plan_cases(vset)
    for line in plan_lines(vset, everything):
        print(line, file=stream, flush=True)
    source = FieldSource.of(scene.g2tom_scenario(vset, vset.models[0], vset.discretizations[0]))
    g2tom = _g2tom_side(vset)
    keys = {c: cases_mod.case_key(vset, c, g2tom["force"][c.load], source) for c in everything}
    done = {c: cases_mod.load_case(case_dir / f"{c.name}.json", keys[c]) for c in everything}
    todo = [c for c in everything if done[c] is None]
    print(f"validate: g2tom done; {len(everything) - len(todo)} of {len(everything)} cases already stored, "
          f"{len(todo)} to run (~{format_duration(cases_mod.estimate_seconds(vset, todo, g2tom=False))})",
          file=stream, flush=True)
    for number, case in enumerate(todo, start=1):
        record = cases_mod.run_case(vset, case, g2tom["force"][case.load], source, keys[case],
                                    case_dir / f"{case.name}.json")
        done[case] = record
        elapsed = time.perf_counter() - start
        left = cases_mod.estimate_seconds(vset, todo[number:], g2tom=False)
        result = (f"FAILED ({record['error']})" if "error" in record else
                  f"F = {record['force']:.4g} N, R = {record['resistance_clean']:.4g} ohm")
        if progress:
            print(f"validate: case {number}/{len(todo)} {case.name}: {result} in {record['seconds_total']:.1f} s; "
                  f"elapsed {format_duration(elapsed)}, ~{format_duration(max(left, 0.0))} left",
                  file=stream, flush=True)
    ds = summary.dataset(vset, everything, done, g2tom, default_discretization())
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


def chosen_set(quick: bool, surface: str = "gw", realizations: int | None = None,
               loads: int | None = None) -> scene.ValidationSet:
    """The default or the quick set on the chosen surface, with every discretization this g2tom offers;
    ``realizations`` (surfaces 0 .. N-1) and ``loads`` (steps evenly spaced in delta/sigma over the
    set's range, lightest first) override the set's.

    Raises
    ------
    ConfigError
        On an unknown surface, fewer than one realization or two loads.
    """
    if surface not in SURFACES:
        raise ConfigError(f"--surface {surface!r} is not allowed: must be one of {', '.join(SURFACES)}")
    if realizations is not None and realizations < 1:
        raise ConfigError(f"--realizations = {realizations} is out of range: must be >= 1")
    if loads is not None and loads < 2:
        raise ConfigError(f"--loads = {loads} is out of range: must be >= 2 (the lightest and the heaviest)")
    base = scene.QUICK if quick else scene.DEFAULT
    if surface == "random_process":
        base = scene.random_process_set(base, rms=scene.RANDOM.rms)
    changes: dict = {"discretizations": available_discretizations(surface)}
    if realizations is not None:
        changes["realizations"] = tuple(range(realizations))
    if loads is not None:
        changes["deltas"] = tuple(float(d) for d in np.linspace(max(base.deltas), min(base.deltas), loads))
    return dataclasses.replace(base, **changes)


def output_folder(data_dir: Path, surface: str) -> Path:
    """Where a validation writes: ``<data>/validate`` (GW surface) or ``<data>/validate_random_process``."""
    return Path(data_dir) / ("validate" if surface == "gw" else f"validate_{surface}")
