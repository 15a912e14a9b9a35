"""The measured surface's report: ``surface.md`` beside ``surface.nc`` (``g2tom surface``), and its
section in the study's report when ``<data-dir>/surface/`` holds one.

What was computed (the map, its digest, the window and positions, the pair), the answer per force
(typical resistance and its band over contacts, clean and per oxide case), the statistical answer's
ratio where there is one, the figure, and the command that reproduces it.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import xarray as xr

from g2tom.analysis.report_blocks import Block, markdown_blocks

__all__ = ["FOLDER", "surface_report", "surface_blocks"]

#: The surface's folder under the data directory.
FOLDER = "surface"


def _row(cells: list[str]) -> str:
    return "| " + " | ".join(cells) + " |"


def surface_report(ds: xr.Dataset, command: str) -> str:
    """The Markdown report of a surface dataset ``ds``, reproduced by ``command``."""
    low, high = (float(q) for q in ds.attrs["band_quantiles"])
    hardness = ds.attrs.get("study_hardness", "none")
    pair = (f"E* = {float(ds.attrs['study_e_star']):.4g} Pa, rho* = {float(ds.attrs['study_rho']):.4g} ohm m, "
            + ("elastic" if hardness == "none" else f"pressure capped at H = {float(hardness):.4g} Pa"))
    files = ", ".join(f"`{f}` (SHA-256 {d[:12]}...)" for f, d in zip(np.atleast_1d(ds.attrs["map_files"]),
                                                                      np.atleast_1d(ds.attrs["map_sha256"])))
    lines = [
        "## The resistance of a measured surface",
        "",
        f"Map {files}: {ds.attrs['map_shape'][0]} x {ds.attrs['map_shape'][1]} pixels of "
        f"{float(ds.attrs['map_pixel_size']):.4g} m, {float(ds.attrs['map_measured_share']):.1%} measured, rms height "
        f"{float(ds.attrs['map_rms_height']):.4g} m. Window {ds.attrs['window_pixels']} pixels "
        f"({float(ds.attrs['window_side']):.4g} m); {ds.sizes['position']} position(s), "
        f"{int(ds['independent'].sum())} independent (the map holds {ds.attrs['independent_positions']}). "
        f"{pair}; indenter {ds.attrs['study_shape']} (R* = {float(ds.attrs['study_radius']):.4g} m).",
        "",
        f"Typical = geometric mean over the contacts; band = their {low:g} % and {high:g} % quantiles.",
        "",
    ]
    if "extended" in ds.attrs:
        lines[2:2] = [f"Windows synthesized: {ds.attrs['extended']}.", ""]
    header = ["force (N)", "R clean (ohm)", "band (ohm)"]
    cases = []
    if "resistance_typical" in ds:
        for xi in ds["xi"].values:
            for length in ds["correlation_length"].values:
                cases.append({"xi": xi, "correlation_length": length})
                header.append(f"R at xi {xi:g}, l_O {length:.3g} m (ohm)")
                if "statistical_ratio" in ds:
                    header.append("full field / statistical")
    lines += [_row(header), _row(["---"] * len(header))]
    for f, force in enumerate(ds["force"].values):
        cells = [f"{force:.4g}", f"{float(ds['resistance_clean_typical'][f]):.4g}",
                 f"{float(ds['resistance_clean_lower'][f]):.4g} .. {float(ds['resistance_clean_upper'][f]):.4g}"]
        for sel in cases:
            cells.append(f"{float(ds['resistance_typical'].sel(sel)[f]):.4g}")
            if "statistical_ratio" in ds:
                cells.append(f"{float(ds['statistical_ratio'].sel(sel)[f]):.3g}")
        lines.append(_row(cells))
    lines += ["", f"Statistical answer (the map's summits through g2tom's predictor): "
              f"{ds.attrs.get('statistical_answer', 'none')}.", "", "![R against F](surface.png)", "",
              f"Reproduce with `{command}`.", ""]
    return "\n".join(lines)


def surface_blocks(data_dir: str | Path) -> list[Block]:
    """Section "Your surface": ``g2tom surface``'s report and figure, when ``<data_dir>/surface/`` holds
    them (nothing otherwise: the surface is not part of the study)."""
    folder = Path(data_dir) / FOLDER
    if not (folder / "surface.md").is_file():
        return []
    text = "\n".join(line for line in (folder / "surface.md").read_text().splitlines() if not line.startswith("!["))
    blocks = [Block("h2", "Your surface: the full field on a measured map (g2tom surface)")]
    blocks += markdown_blocks(text, "The resistance of a measured surface")
    if (folder / "surface.png").is_file():
        blocks.append(Block("img", "R against F on the measured surface, with its band over contacts; one contact's "
                                   "map", src=f"{FOLDER}/surface.png"))
    return blocks
