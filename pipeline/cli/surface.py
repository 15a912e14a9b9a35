"""``g2tom surface MAP [MAP2]``: the full-field resistance of a measured surface, its files and a summary."""

from __future__ import annotations

import argparse
import os
import shlex
import sys
from pathlib import Path

import numpy as np
import xarray as xr

from g2tom.cli.parsing import number_list
from g2tom.compute import ComputeOptions
from g2tom.config import ConfigError, Scenario

__all__ = ["surface_cli", "summary_lines"]


def _spot(text: str | None):
    """``--at``: None, the map's centre, or x,y in m."""
    from g2tom.surface.study import Spot

    if text is None:
        return None
    if text.strip().lower() in ("centre", "center"):
        return Spot(centre=True)
    values = number_list("--at", text)
    if values.size != 2:
        raise ConfigError(f"--at = {text!r} is not allowed: must be X,Y (m from the centre of the map's first "
                          "pixel) or 'centre'")
    return Spot(x=float(values[0]), y=float(values[1]))


def summary_lines(ds: xr.Dataset) -> list[str]:
    """The answer in a few lines: typical R and its band per force, clean and per oxide case."""
    low, high = ds.attrs["band_quantiles"]
    lines = [f"{'force (N)':>10}  {'R clean (ohm)':>13}  {f'band {low:g}-{high:g} % (ohm)':>27}"
             + ("  R with oxide (ohm), per case" if "resistance_typical" in ds else "")]
    for f, force in enumerate(ds["force"].values):
        row = (f"{force:>10.4g}  {float(ds.resistance_clean_typical[f]):>13.5g}  "
               f"{float(ds.resistance_clean_lower[f]):>12.5g} .. {float(ds.resistance_clean_upper[f]):<12.5g}")
        if "resistance_typical" in ds:
            row += "  " + "  ".join(f"{v:.5g}" for v in ds["resistance_typical"].values[..., f].ravel())
        lines.append(row)
    if "statistical_ratio" in ds:
        ratios = ds["statistical_ratio"].values
        lines.append(f"full field / statistical answer (the map's summits, {ds.attrs['statistical_answer'].split(' (')[0]}): "
                     f"{np.nanmin(ratios):.3g} .. {np.nanmax(ratios):.3g} over the oxide cases and forces")
    else:
        lines.append(f"statistical answer: {ds.attrs['statistical_answer']}")
    if "extended" in ds.attrs:
        lines.append(f"windows synthesized: {ds.attrs['extended']}")
    unsolved = int((ds["solved"] == 0).sum())
    if unsolved:
        lines.append(f"{unsolved} of {ds['solved'].size} position-force solves reached the window's edge or failed "
                     "(NaN): give a larger --window")
    return lines


def surface_cli(args: argparse.Namespace, scenario: Scenario, options: ComputeOptions, device: str = "cpu") -> None:
    """Check everything, print the plan, solve every position where ``options`` says on ``device``
    (``cpu`` or ``gpu``, resolved), write surface.nc, surface.csv, surface.png.

    Raises
    ------
    ConfigError
        On any input out of range, before work.
    """
    from g2tom.analysis.figures_surface import figure
    from g2tom.analysis.report_surface import surface_report
    from g2tom.surface.run import compute, plan_lines, prepare, write_outputs
    from g2tom.surface.statistical import attach_statistical
    from g2tom.surface.study import study_of

    if args.force is None:
        raise ConfigError("--force is required: the normal forces, N, e.g. --force 0.02,0.1,0.5,3")
    study = study_of(
        scenario, number_list("--force", args.force),
        xi=number_list("--xi", args.xi) if args.xi else (),
        correlation_lengths=number_list("--correlation-length", args.correlation_length)
        if args.correlation_length else (),
        fields=args.fields, positions=args.positions, at=_spot(args.at), window=args.window, detrend=args.detrend,
        extend=args.extend)
    prepared = prepare(study, [args.heightmap] + ([args.second] if args.second else []), args.pixel_size)
    workers = options.workers or os.cpu_count() or 1
    if args.plan:
        print("\n".join(plan_lines(prepared, workers, device)))
        return
    folder = Path(args.output) if args.output else Path(args.data_dir) / "surface"
    from g2tom.store import atomic_path, check_writable

    check_writable(folder, "nothing is written")
    for line in plan_lines(prepared, workers, device):
        print(line, file=sys.stderr)
    ds = attach_statistical(compute(prepared, options, device), scenario, prepared.summits, args.data_dir)
    written = write_outputs(ds, folder)
    written.append(figure(ds, folder / "surface.png"))
    report = folder / "surface.md"
    with atomic_path(report) as tmp:
        tmp.write_text(surface_report(ds, shlex.join(args.command_line)))
    written.append(report)
    print("\n".join(summary_lines(ds)))
    print(f"surface: wrote {', '.join(str(p) for p in written)}", file=sys.stderr)
