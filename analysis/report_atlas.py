"""Report section "The atlas over (mu, Pi)": the surrogate chosen by leave-one-scene-out
cross-validation with its error table, the band by region, and the held-out verdict, computed by
:func:`g2tom.atlas.fit.verdict` from ``<data>/atlas/heldout.csv`` (the code that wrote
``surrogate.json``'s verdict); then the measured-surface chain (:mod:`g2tom.analysis.report_chain`)."""

from __future__ import annotations

import csv
import json
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr

from g2tom.analysis.report_blocks import Block, table
from g2tom.analysis.report_chain import chain_blocks
from g2tom.fitting.atlas_band import region_labels
from g2tom.fitting.atlas_grid import FRAME_COORDINATES

__all__ = ["atlas_blocks", "read_heldout"]

_FLOATS = ("mu", "Pi", "xi", "lambda", "force_normalized", "resistance_normalized", "error", "power_law_error",
           "half_width", "noise_sigma", "allowed")


def read_heldout(path: Path) -> list[dict[str, Any]]:
    """The rows of ``heldout.csv`` with their types (as :func:`g2tom.atlas.fit.heldout_rows` made them)."""
    with open(path, newline="") as handle:
        rows = list(csv.DictReader(handle))
    for r in rows:
        for key in _FLOATS:
            if key in r:
                r[key] = float(r[key])
        r["within"] = r["within"] == "True"
    return rows


def _fmt(value: Any, spec: str = ".3g") -> str:
    return "-" if value is None or (isinstance(value, float) and not np.isfinite(value)) else format(value, spec)


def _cv_table(doc: dict[str, Any]) -> Block:
    rows = []
    for r in doc.get("cross_validation", []):
        if "cv_cells_within" in r and r.get("cv_rms") is None:
            continue  # a candidate with more terms than a fold's points
        name = f"{r['model']} (chosen)" if r.get("chosen") else r["model"]
        across = f"{r['kernel']} RBF, smoothing {r['smoothing']:g}" if "kernel" in r else str(r["degree"])
        if "frame" in r:
            across = f"{across} in {FRAME_COORDINATES[r['frame']]}"
        within = f"{r['cv_cells_within']} of {r['cells']}" if "cv_cells_within" in r else "-"
        rows.append([name, across, _fmt(r.get("order"), "d") if r.get("order") is not None else "-",
                     str(r["terms"]), _fmt(r.get("cv_rms")), _fmt(r.get("cv_max")), within])
    return table(["model", "across the groups", "order P (ln F')", "terms per node", "LOSO RMS ln R'",
                  "LOSO max", "LOSO cells within"], rows)


def _ceiling_words(held: dict[str, Any], ceiling: dict[str, Any] | None) -> str:
    """What a perfect surrogate would pass through the held-out scenes' own noise, if known, and the
    noise ceiling of ``surrogate.json`` (None: fitted by an older g2tom)."""
    low, high = held.get("perfect_share_independent"), held.get("perfect_share_correlated")
    if low is None or not np.isfinite(low):
        return ""
    words = (f" A perfect surrogate, erring only by the held-out scenes' own noise, would pass {100 * low:.0f} % of the "
             f"cells if that noise were independent from step to step and {100 * high:.0f} % if fully correlated "
             f"along the load.")
    if ceiling:
        words += (f" Its ceiling at this precision: were the truth exactly a model of the chosen kind, that kind refitted "
                  f"on the design scenes through their sampling noise would pass "
                  f"{100 * ceiling['independent_steps']:.0f} % of the cells (noise independent from step to step) to "
                  f"{100 * ceiling['correlated_steps']:.0f} % (fully correlated along the load; mean of "
                  f"{ceiling['draws']} draws each).")
    return words


def _band_table(doc: dict[str, Any]) -> Block:
    band = doc["band"]
    out = []
    for index, label in enumerate(region_labels()):
        flat = lambda key: np.asarray(band[key], float).ravel()[index]  # noqa: E731
        held = int(flat("heldout_counts"))
        out.append([label, _fmt(float(flat("regional"))), _fmt(float(flat("cross_validated"))), str(int(flat("counts"))),
                    _fmt(float(flat("heldout"))) if held else "-", str(held)])
    return table(["region", "band (one sigma of ln R')", "LOSO RMS", "LOSO points", "held-out RMS", "held-out points"],
                 out)


def atlas_blocks(data_dir: Path) -> list[Block]:
    """Section "The atlas": surrogate, cross-validation, band by region, held-out verdict per scene."""
    folder = Path(data_dir) / "atlas"
    blocks = [Block("h2", "The atlas over (mu, Pi): held-out scenes")]
    if not (folder / "surrogate.json").is_file() or not (folder / "heldout.csv").is_file():
        return blocks + [Block("p", "Not available: run `make atlas` (its plan first: `make atlas-plan`).")] + \
            chain_blocks(data_dir)
    from g2tom.atlas.fit import curve_words, verdict  # here: scipy.stats, half a second, for an atlas only

    doc = json.loads((folder / "surrogate.json").read_text())
    if int(doc.get("format_version", 1)) < 2:
        return blocks + [Block("p", "The atlas surrogate is of format 1 (one polynomial in five logs, an earlier version's): "
                                    "rerun `make atlas` for this section.")] + chain_blocks(data_dir)
    rows = read_heldout(folder / "heldout.csv")
    held = verdict(rows)
    worst = held["worst"]
    curve, domain = doc["log_resistance"], doc["domain"]
    blocks.append(Block("p", (
        f"Domain: mu {domain['mu'][0]:.3g}-{domain['mu'][1]:.3g}, Pi {domain['Pi'][0]:.3g}-{domain['Pi'][1]:.3g}, "
        f"F' {domain['force_normalized'][0]:.3g}-{domain['force_normalized'][1]:.3g} in every scene (its load "
        f"steps chosen in F'), xi 0 (clean)-{domain['xi'][1]:g}, lambda {domain['lambda'][0]:g}-"
        f"{domain['lambda'][1]:g}. Curve model (the predictor's default): {curve_words(curve)}; chosen by "
        f"leave-one-scene-out cross-validation (table below) for the most cells within at every step.")))
    blocks.append(Block("p", (
        f"Held out ({held['rule']}): {held['cells_within']} of {held['cells']} (scene, xi, lambda) cells "
        f"({100 * held['share_within']:.1f} %) within at every step ({held['steps_within']} of {held['steps']} "
        f"points); RMS {held['rms_ln_error']:.3g} in ln R'; worst step {worst['scene']} (mu {worst['mu']:.3g}, Pi "
        f"{worst['Pi']:.3g}, xi {worst['xi']:g}, lambda {worst['lambda']:g}, F' {worst['force_normalized']:.3g}): "
        f"{worst['error']:.3g} against {worst['allowed']:.3g} allowed. Targets "
        f"{'met' if held['met'] else 'NOT met'}. Eq. 25's power law, for the record: "
        f"{held['power_law_cells_within']} of {held['cells']} cells (RMS {held['power_law_rms_ln_error']:.3g})."
        + _ceiling_words(held, doc["heldout"].get("noise_ceiling")))))
    blocks.append(Block("p", "Leave-one-scene-out cross-validation on the design scenes (each predicted by the model "
                             "fitted without it; scenes at the box's edge are extrapolated to):"))
    blocks.append(_cv_table(doc))
    blocks.append(Block("p", "The band `g2tom predict` reports is the error of the query's region: the LOSO error "
                             "there, raised to the held-out scenes' where they err more (and, between oxide nodes, "
                             "the grid's interpolation error in quadrature):"))
    blocks.append(_band_table(doc))
    atlas_file = folder / "atlas.nc"
    if atlas_file.is_file():
        with xr.open_dataset(atlas_file) as atlas:
            if "invariance_pair" in atlas.attrs:
                blocks.append(Block("p", (
                    f"Invariance of the groups: scenes {atlas.attrs['invariance_pair']} give R' equal within "
                    f"{float(atlas.attrs['invariance_max_ln_error']):.2g} in ln R' at every cell and fitted step.")))
    per_scene: dict[str, list[dict[str, Any]]] = {}
    for r in rows:
        per_scene.setdefault(r["scene"], []).append(r)
    table_rows = []
    for scene, items in per_scene.items():
        errors = np.array([i["error"] for i in items])
        table_rows.append([scene, f"{items[0]['mu']:.4g}", f"{items[0]['Pi']:.4g}", f"{np.sqrt(np.mean(errors**2)):.3g}",
                           f"{errors.max():.3g}", f"{sum(i['within'] for i in items)} of {len(items)}"])
    blocks.append(table(["held-out scene", "mu", "Pi", "RMS error in ln R'", "max", "points within"], table_rows))
    return blocks + chain_blocks(data_dir)
