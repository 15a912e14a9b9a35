"""The report's first screen ("Summary"): the study's answer in ohm, how right it is, how long it took,
and the command that answers other forces.

The fitted law R = alpha F'^-gamma R0 (F' = F / F0) is evaluated at three forces of the study for
the clean surface and for one or two oxide cells of the grid; the figures come from ``fits.nc`` and
``surrogate.nc`` as written by the stages (nothing is refitted here).
"""

from __future__ import annotations

import json
import shlex
from pathlib import Path

import numpy as np
import xarray as xr

from g2tom import __version__
from g2tom.analysis.report_blocks import Block
from g2tom.config import STAGE_INPUTS, Scenario
from g2tom.models import contact_model
from g2tom.scene import scene_plasticity
from g2tom.stages.table3 import PARAMETERS

__all__ = ["TIMED_STEPS", "summary_blocks", "recorded_timings", "predict_command", "law_forces", "shown_cells"]

#: Sections whose parameters decide the surface (the force and resistance scales, the groups mu and
#: Pi): the ``--set`` arguments of the predict command repeat those that differ from the bundled scenario.
SURFACE_SECTIONS = ("roughness", "material", "indenter")


def _span(values: np.ndarray, digits: int = 4) -> str:
    """``min-max`` of finite values as text (one value when they are equal)."""
    lo, hi = float(np.nanmin(values)), float(np.nanmax(values))
    return f"{lo:.{digits}g}" if lo == hi else f"{lo:.{digits}g}-{hi:.{digits}g}"


#: The steps whose wall times the report shows: the stages, then the figures.
TIMED_STEPS: tuple[str, ...] = (*STAGE_INPUTS, "figures")


def recorded_timings(scenario: Scenario, data_dir: Path) -> list[tuple[str, float, str]]:
    """``(step, wall time in s, finished)`` of every step in ``timings.json`` run with this configuration:
    the stages in order, then the figures, their families' times summed.

    ``timings.json`` keeps the last time of every step with the configuration hash it ran with
    (each figure family apart, ``figures: <family>``, as ``g2tom figures --only`` draws some);
    steps run with another configuration (an earlier or a different run) are left out.
    """
    path = Path(data_dir) / "timings.json"
    try:
        recorded = json.loads(path.read_text()) if path.is_file() else {}
    except (OSError, ValueError):
        recorded = {}
    if not isinstance(recorded, dict):
        recorded = {}
    entries = {step: entry for step, entry in recorded.items() if isinstance(entry, dict)}
    rows = [(stage, float(entries[stage]["seconds"]), entries[stage].get("finished", ""))
            for stage in STAGE_INPUTS if entries.get(stage, {}).get("config_hash") == scenario.config_hash(stage)]
    families = [entry for step, entry in entries.items()
                if step.startswith("figures: ") and entry.get("config_hash") == scenario.config_hash()]
    if families:
        rows.append(("figures", sum(float(e["seconds"]) for e in families),
                     max(str(e.get("finished", "")) for e in families)))
    return rows


def law_forces(fits: xr.Dataset) -> np.ndarray:
    """Three forces of the study, N: the lightest and heaviest fitted load steps and the step between
    them nearest their geometric mean (fewer when fewer steps were fitted)."""
    force = fits["force"].values
    fitted = force[fits["fitted"].values.astype(bool)] if "fitted" in fits else force
    fitted = np.sort(fitted[np.isfinite(fitted)]) if fitted.size else np.sort(force)
    if fitted.size <= 3:
        return fitted
    middle = fitted[1:-1][np.argmin(np.abs(np.log(fitted[1:-1]) - 0.5 * np.log(fitted[0] * fitted[-1])))]
    return np.array([fitted[0], middle, fitted[-1]])


def shown_cells(fits: xr.Dataset) -> list[tuple[int, int]]:
    """``(xi index, lambda index)`` of the oxide cells the summary shows: the grid's middle cell and
    the largest oxide fraction at the middle length (one cell when they coincide)."""
    i, j = fits.sizes["xi"] // 2, fits.sizes["lambda"] // 2
    cells = [(i, j), (fits.sizes["xi"] - 1, j)]
    return list(dict.fromkeys(cells))


def _law(alpha: float, gamma: float, force_n: np.ndarray, scale: float) -> np.ndarray:
    return alpha * force_n ** -gamma * scale


def _law_cell(alpha: float, gamma: float, a_ci: np.ndarray, g_ci: np.ndarray, force_n: float, scale: float) -> str:
    """``R [lower, upper]`` in ohm: the law and its range over the corners of the alpha and gamma intervals."""
    value = float(_law(alpha, gamma, np.asarray(force_n), scale))
    corners = [float(_law(a, g, np.asarray(force_n), scale)) for a in a_ci for g in g_ci]
    if not np.all(np.isfinite(corners)):
        return f"{value:.4g}"
    return f"{value:.4g} [{min(corners):.4g}, {max(corners):.4g}]"


def predict_command(scenario: Scenario, data_dir: Path, forces: np.ndarray, xi: float, lam: float) -> str:
    """The ``g2tom predict`` command line that answers ``forces`` at (xi, lambda) from this run's surrogate.

    ``--config`` names the bundled scenario; the surface's parameters that differ from it are repeated
    as ``--set`` arguments (the rest of the study does not enter a prediction).
    """
    from g2tom.before_work import load_scenario

    args = ["g2tom", "predict", "--config", scenario.name]
    try:
        base = load_scenario(scenario.name).flat()
    except Exception:  # a scenario read from a TOML file: the user names the file
        args[-1], base = f"{scenario.name}.toml", {}
    for key, value in scenario.flat().items():
        if key.split(".", 1)[0] in SURFACE_SECTIONS and base and value != base.get(key):
            args += ["--set", f"{key}={json.dumps(value)}"]
    args += ["--data-dir", str(data_dir), "--force", ",".join(f"{f:.4g}" for f in forces),
             "--xi", f"{xi:g}", "--lambda", f"{lam:g}"]
    return shlex.join(args)


def _answer_blocks(scenario: Scenario, fits: xr.Dataset, data_dir: Path) -> list[Block]:
    """The law in ohm at three forces (a table), with its scales and intervals."""
    force = fits["force"].values
    force_scale = float(np.nanmedian(force / fits["force_normalized"].values))
    scale = float(fits["resistance_scale"]) if "resistance_scale" in fits else scenario.resistance_scale
    forces = law_forces(fits)
    force_n = forces / force_scale
    cells = shown_cells(fits)
    header = ["F", "clean"] + [f"xi {float(fits['xi'][i]):g}, lambda {float(fits['lambda'][j]):g}"
                                   for i, j in cells]
    rows = []
    for f, fn in zip(forces, force_n):
        row = [f"{f:.4g}", _law_cell(float(fits["alpha_clean"]), float(fits["gamma_clean"]),
                                     fits["alpha_clean_ci"].values, fits["gamma_clean_ci"].values, fn, scale)]
        for i, j in cells:
            cell = fits.isel(xi=i, **{"lambda": j})
            row.append(_law_cell(float(cell["alpha"]), float(cell["gamma"]), cell["alpha_ci"].values,
                                 cell["gamma_ci"].values, fn, scale))
        rows.append(row)
    confidence = 100 * scenario.fits.confidence
    return [
        Block("p", f"**The answer:** R = alpha F'^-gamma R0, with F' = F / F0 (F0 = {force_scale:.4g} N) and "
                   f"R0 = {scale:.4g} ohm, in ohm at three forces of the study (F in N); in brackets the law over the "
                   f"corners of the {confidence:g} % intervals of alpha and gamma:"),
        Block("pre", _aligned([header, *rows])),
    ]


def _aligned(rows: list[list[str]]) -> str:
    """Rows as fixed-width text columns (the first screen's table, kept out of the Markdown tables
    that begin after the figures)."""
    widths = [max(len(row[k]) for row in rows) for k in range(len(rows[0]))]
    return "\n".join("   ".join(cell.ljust(w) for cell, w in zip(row, widths)).rstrip() for row in rows)


def _right_items(scenario: Scenario, fits: xr.Dataset, sur: xr.Dataset | None) -> list[str]:
    """How right: the clean fit's and the shown cells' intervals, the surrogate's worst error."""
    confidence = 100 * scenario.fits.confidence
    ci = {k: fits[f"{k}_clean_ci"].values for k in ("alpha", "gamma")}
    items = [f"**How right:** clean fit alpha = {float(fits['alpha_clean']):.4g} [{ci['alpha'][0]:.4g}, "
             f"{ci['alpha'][1]:.4g}], gamma = {float(fits['gamma_clean']):.4g} [{ci['gamma'][0]:.4g}, "
             f"{ci['gamma'][1]:.4g}] ({confidence:g} % intervals), RMS log residual "
             f"{float(fits['fit_residual_rms_clean']):.3g}; oxide cells: alpha's relative half-width "
             f"{_span(fits['alpha_half_width'].values, 3)}, gamma's half-width {_span(fits['gamma_half_width'].values, 3)}."]
    return items + ([] if sur is None else [_surrogate_item(sur)])


def _surrogate_item(sur: xr.Dataset) -> str:
    """The surrogate's worst relative error of alpha and gamma over the grid, and why it is trivial if it is."""
    worst = ", ".join(f"{p} {100 * float(np.nanmax(np.abs(sur[f'{p}_relative_error'].values))):.2f} %"
                      for p in PARAMETERS)
    trivial = f" Trivial: {sur.attrs['trivial']}." if "trivial" in sur.attrs else ""
    return f"**Surrogate (Eq. 26):** worst relative error on the grid: {worst}.{trivial}"


def summary_blocks(scenario: Scenario, fits: xr.Dataset | None, sur: xr.Dataset | None,
                   validation: list[Block], data_dir: str | Path | None = None) -> list[Block]:
    """Section "Summary": the answer in ohm, how right, how long, the predict command, what was computed.

    Parameters
    ----------
    scenario : Scenario
        The run's configuration (name, description, models).
    fits, sur : xarray.Dataset or None
        The fits and surrogate stages' outputs, None where not available.
    validation : list of Block
        The validation section's blocks; its bold paragraphs are the comparison's flag lines.
    data_dir : str or Path, optional
        The run's folder: its ``timings.json`` gives "how long", and the predict command names it.

    Returns
    -------
    list of Block
        The heading, the answer's paragraph and its fixed-width table (when the fits are available) and a list of
        statements, read from the stages' outputs (nothing recomputed).
    """
    data_dir = Path("data") if data_dir is None else Path(data_dir)
    spots = (f"a pool of {scenario.contact.surfaces} surfaces' own asperities, oxide spot rule "
             f"{scenario.oxide.spot_rule}" if contact_model(scenario).pooled else f"{scenario.contact.spots} spots")
    computed = (f"**Computed:** scenario '{scenario.name}': {scenario.description} (g2tom {__version__}, "
                f"configuration hash {scenario.config_hash()}); contact model {scenario.contact.model} with "
                f"{spots}, resistance model {scenario.cube.model}; "
                f"{scene_plasticity(scenario).line(scenario.roughness.sigma)}.")
    blocks: list[Block] = [Block("h2", "Summary")]
    items: list[str] = []
    if fits is None:
        items.append("**Not available:** the fits stage's output (run `g2tom fits`).")
        if sur is not None:
            items.append(_surrogate_item(sur))
    else:
        blocks += _answer_blocks(scenario, fits, data_dir)
        items += _right_items(scenario, fits, sur)
    label, flags = "", []
    for b in validation:
        if b.kind == "h3":
            label = b.text
        elif b.kind == "p" and b.text.startswith("**"):
            flags.append(f"Against the full elastic contact ({label}): {b.text}")
    items += flags or ["Against the full elastic contact: not run (`make validate`)."]
    timings = recorded_timings(scenario, data_dir)
    if timings:
        steps = ", ".join(f"{step} {seconds:.3g} s" for step, seconds, _ in timings)
        items.append(f"**How long:** {sum(t[1] for t in timings):.4g} s of wall time ({steps}; see Timings).")
    else:
        items.append("**How long:** no recorded time of this configuration's stages (run through the g2tom command).")
    if fits is not None:
        i, j = shown_cells(fits)[0]
        command = predict_command(scenario, data_dir, law_forces(fits), float(fits["xi"][i]), float(fits["lambda"][j]))
        items.append(f"**Other forces, fractions, lengths:** `{command}` (this run's surrogate; "
                     f"`g2tom predict --help` for a CSV of queries).")
    items.append(computed)
    if fits is not None:
        xi, lam = fits["xi"].values, fits["lambda"].values
        grid = f"{xi.size} xi ({_span(xi)}) x {lam.size} lambda ({_span(lam)})"
        if "force" in fits.coords and "force_normalized" in fits.coords:
            grid += (f"; {fits.sizes['delta']} load steps, F = {_span(fits['force'].values)} N, "
                     f"F' = {_span(fits['force_normalized'].values)}")
        if "n_realizations" in fits:
            grid += f"; realizations used per cell {_span(fits['n_realizations'].values)}"
        items.append(f"**Grid:** {grid}.")
        if "flagged" in fits:
            items.append(f"**Flagged cells** (stopped at the cap short of the confidence target): "
                         f"{int(fits['flagged'].sum())} of {fits['flagged'].size}.")
    return blocks + [Block("list", rows=tuple((0, item) for item in items))]
