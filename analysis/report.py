"""``make report``: ``<data_dir>/report.md`` and ``report.html`` from one block structure.

The report is a list of blocks (heading, paragraph, table, image, preformatted text);
:func:`to_markdown` and :func:`to_html` render the same list, so the two files always agree
and no Markdown library is needed. Sections whose input file is missing or stale say so
instead of failing, so a partial run still gets a report.
"""

from __future__ import annotations

import html
import json
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr

from pipeline import __version__
from pipeline.config import Scenario, parameter_table
from pipeline.stages.surrogate import PARAMETERS, table3_rows
from pipeline.store import StaleInputError, atomic_path, read_stage

__all__ = ["Block", "build_blocks", "to_markdown", "to_html", "write_report"]


@dataclass(frozen=True)
class Block:
    """One report element.

    ``kind`` is ``h1``, ``h2``, ``p``, ``table`` (``rows[0]`` is the header), ``img``
    (``text`` = caption, ``src`` = relative path) or ``pre``.
    """

    kind: str
    text: str = ""
    rows: tuple[tuple[str, ...], ...] = ()
    src: str = ""


#: Captions of the known figures, keyed by file stem; other figures are captioned by their stem.
CAPTIONS = {
    "fig3_bounds": "Fig. 3: Barber's clean and oxide-extended conductance bounds (Eqs. 8-9) and their geometric mean",
    "fig4_contact": "Fig. 4: Greenwood-Tripp solution of the rough Hertzian contact",
    "fig5_spots": "Fig. 5: discrete contact spots",
    "fig6_oxide": "Fig. 6: random oxide fields and thresholded oxides",
    "fig8_resistance": "Fig. 8: resistance R against force F: 16-84 % band, the fitted reduction (markers) and its power-law fit",
    "fig9_conductance": "Fig. 9: normalized conductance kappa' = 1/R' against F'",
    "fig10_alpha_gamma": "Fig. 10: fitted alpha and gamma (95 % bootstrap intervals) with their SVD surrogate (Eq. 26) and its relative error",
    "fig10_realizations": "Fig. 10 (beside): realizations used per (xi, lambda) and alpha's reached 95 % half-width; x marks flagged cells",
    "fig11_barber": "Fig. 11: G2TOM against the p-average of the oxide-extended Barber bounds (Eq. 10)",
}


def _figure_order(path: Path) -> tuple[Any, ...]:
    """Sort key that puts fig3 before fig10 (numbers compared as numbers)."""
    return tuple(int(part) if part.isdigit() else part for part in re.split(r"(\d+)", path.stem))


def _fmt(value: Any) -> str:
    if isinstance(value, float):
        return f"{value:.6g}"
    return str(value)


def _table(header: list[str], rows: list[list[Any]]) -> Block:
    return Block("table", rows=(tuple(header),) + tuple(tuple(_fmt(v) for v in row) for row in rows))


def _load(data_dir: Path, stage: str, scenario: Scenario) -> tuple[xr.Dataset | None, list[Block]]:
    try:
        return read_stage(data_dir, stage, scenario), []
    except StaleInputError as exc:
        return None, [Block("p", f"Not available: {exc}")]


def _fit_blocks(fits: xr.Dataset, scenario: Scenario) -> list[Block]:
    f = scenario.fits
    ci = {k: fits[f"{k}_clean_ci"].values for k in ("alpha", "gamma")}
    steps = int(fits["fitted"].sum())
    return [
        Block("h2", "Clean-surface fit"),
        Block("p", f"R' = alpha F'^-gamma fitted by least squares in log-log on the {steps} load steps with "
                   f"F >= {f.min_force:g} N; intervals: {100 * f.confidence:g} % least-squares (Student t)."),
        _table(["parameter", "value", "lower", "upper"], [
            ["alpha_clean", float(fits["alpha_clean"]), float(ci["alpha"][0]), float(ci["alpha"][1])],
            ["gamma_clean", float(fits["gamma_clean"]), float(ci["gamma"][0]), float(ci["gamma"][1])],
            ["RMS log residual", float(fits["fit_residual_rms_clean"]), "", ""],
        ]),
        Block("p", f"Oxidized cells: reduction '{f.reduction}' over realizations (geometric and arithmetic "
                   f"means over conducting realizations only); {100 * f.confidence:g} % percentile intervals of "
                   f"alpha and gamma (fits.nc: alpha_ci, gamma_ci) from {f.n_bootstrap} bootstrap resamples over "
                   f"realizations (seed {f.seed}); largest open-circuit probability on the fitted steps "
                   f"{float(fits['open_probability'].isel(delta=fits['fitted'].values.astype(bool)).max()):.3g}."),
    ]


def _ensemble_blocks(fits: xr.Dataset, scenario: Scenario) -> list[Block]:
    """Realizations used, flagged cells, reached half-widths and power-law residuals per cell."""
    ox = scenario.oxide
    if "n_realizations" not in fits:
        return []
    used = fits["n_realizations"].max("xi").values
    flagged = fits["flagged"].values.astype(bool)
    if ox.ensemble == "adaptive":
        how = (f"adaptive: per (xi, lambda) from {ox.min_realizations} realizations in batches of {ox.batch} until "
               f"the 95 % half-width of alpha (fast rule, exact for the geometric-mean fit) is within "
               f"{100 * ox.target_half_width:g} %, at most {ox.max_realizations}")
    else:
        how = f"fixed: {ox.n_realizations} realizations per lambda"
    cells = [f"(xi {float(x):g}, lambda {float(l):g})" for x, l in zip(*(
        fits[d].values[i] for d, i in zip(("xi", "lambda"), flagged.nonzero())))]
    hw_a, hw_g = fits["alpha_half_width"], fits["gamma_half_width"]
    rows = [
        [f"{float(lam):g}", int(n), f"{100 * float(hw_a.sel({'lambda': lam}).max()):.2f}",
         f"{float(hw_g.sel({'lambda': lam}).max()):.4f}", f"{float(fits['fit_residual_rms'].sel({'lambda': lam}).max()):.4f}",
         int(fits["flagged"].sel({"lambda": lam}).sum())]
        for lam, n in zip(fits["lambda"].values, used)
    ]
    return [
        Block("h2", "Ensemble: realizations used and reached confidence"),
        Block("p", f"Ensemble {how}; field period '{ox.period}'"
                   + (f" (k1 spans {ox.spectral_resolution:g} lattice steps)" if ox.period == "spectral" else "")
                   + f". {int(used.sum())} fields in all (the most any xi needed, summed over lambda); "
                   f"worst lambda {int(used.max())}. "
                   f"Flagged cells (stopped at the cap short of the target): {int(flagged.sum())}"
                   + (f": {', '.join(cells)}." if cells else ".")),
        Block("p", f"Largest bootstrap half-width over xi per lambda (alpha relative, gamma absolute); RMS log "
                   f"residual of the power law (largest over xi): overall max alpha half-width "
                   f"{100 * float(hw_a.max()):.2f} % (unflagged cells {100 * float(hw_a.where(~fits['flagged'].astype(bool)).max()):.2f} %)."),
        _table(["lambda", "realizations", "max alpha half-width %", "max gamma half-width",
                "max RMS log residual", "flagged"], rows),
        Block("p", _smoothness(fits)),
    ]


def _smoothness(fits: xr.Dataset) -> str:
    """Kinks of alpha in lambda: second differences of log alpha against their 95 % bound."""
    if fits.sizes["lambda"] < 3:
        return "Smoothness in lambda: fewer than three lambdas."
    log_alpha = np.log(fits["alpha"].transpose("xi", "lambda").values)
    se = fits["alpha_half_width"].transpose("xi", "lambda").values / 1.96  # ~ standard error of log alpha
    second = np.abs(log_alpha[:, 2:] - 2 * log_alpha[:, 1:-1] + log_alpha[:, :-2])
    bound = 1.96 * np.sqrt(se[:, 2:] ** 2 + 4 * se[:, 1:-1] ** 2 + se[:, :-2] ** 2)
    ratio = second / bound
    return (f"Smoothness in lambda at fixed xi: the largest |second difference of log alpha| is "
            f"{np.nanmax(second):.3f}; over its 95 % noise bound it reaches {np.nanmax(ratio):.2f}, and "
            f"{int(np.sum(ratio > 1))} of {ratio.size} interior points exceed 1 (about 5 % expected from noise "
            f"alone; the physical curvature of alpha(lambda) counts too where intervals are below 0.5 %).")


def _surrogate_blocks(sur: xr.Dataset) -> list[Block]:
    blocks = [Block("h2", "Table 3: fitted and surrogate alpha, gamma")]
    header = ["xi", "lambda"] + [f"{p} {c}" for p in PARAMETERS for c in ("fit", "SVD", "err %")]
    rows = [[r["xi"], r["lambda"]] + [f"{r[f'{p}_{c}']:.4f}" if c != "error_percent" else f"{r[f'{p}_{c}']:+.2f}"
                                      for p in PARAMETERS for c in ("fit", "surrogate", "error_percent")]
            for r in table3_rows(sur)]
    blocks.append(_table(header, rows))
    blocks.append(Block("h2", "Table 4: surrogate coefficients (ascending powers)"))
    for p in PARAMETERS:
        for axis, var in (("w = log lambda", "w"), ("z = -log(1 - xi)", "z")):
            coef = sur[f"{p}_coef_{var}"].values
            blocks.append(Block("p", f"{p}, modes in {axis}:"))
            blocks.append(_table(["mode"] + [f"c{i}" for i in range(coef.shape[1])],
                                 [[k + 1] + [float(c) for c in row] for k, row in enumerate(coef)]))
    blocks.append(Block("h2", "Leave-one-out cross-validation of the surrogate orders"))
    blocks.append(Block("p", "Each lambda row and each xi column is left out in turn and predicted by a surrogate "
                             "fitted to the rest; the score is the RMS relative error (NaN: not enough lines)."))
    for p in PARAMETERS:
        loo = sur[f"{p}_loo"]
        blocks.append(Block("p", f"{p}: {loo.attrs.get('verdict', '')}"))
        blocks.append(_table(["order w \\ z"] + [str(int(z)) for z in loo.order_z.values],
                             [[int(w)] + [float(v) for v in loo.sel(order_w=w).values] for w in loo.order_w.values]))
    return blocks


def _json_blocks(title: str, data: Any) -> list[Block]:
    if isinstance(data, dict) and all(not isinstance(v, (dict, list)) for v in data.values()):
        return [Block("p", title), _table(["key", "value"], [[k, v] for k, v in data.items()])]
    if isinstance(data, list) and data and all(isinstance(r, dict) for r in data):
        keys = list(dict.fromkeys(k for r in data for k in r))
        return [Block("p", title), _table(keys, [[r.get(k, "") for k in keys] for r in data])]
    return [Block("p", title), Block("pre", json.dumps(data, indent=1, sort_keys=True))]


def _run_blocks(scenario: Scenario, data_dir: Path) -> list[Block]:
    blocks = [Block("h2", "Timings")]
    timings = data_dir / "timings.json"
    if timings.is_file():
        t = json.loads(timings.read_text())
        blocks.append(_table(["stage", "wall time (s)"], [[k, float(v)] for k, v in t.items()]))
    else:
        blocks.append(Block("p", "No timings.json (stages were not run through the g2tom command)."))
    bench = sorted((data_dir / "bench").glob("*.json"))
    if bench:
        blocks.append(Block("h2", "Benchmarks"))
        for path in bench:
            blocks += _json_blocks(path.name, json.loads(path.read_text()))
    blocks.append(Block("h2", "Parameters"))
    values = scenario.flat()
    blocks.append(_table(
        ["parameter", "value", "unit", "meaning"],
        [[key, values[key], unit, doc] for key, _default, unit, _allowed, doc in parameter_table()],
    ))
    return blocks


def build_blocks(scenario: Scenario, data_dir: str | Path) -> list[Block]:
    """The whole report as blocks (figures linked relative to ``data_dir``)."""
    data_dir = Path(data_dir)
    blocks = [
        Block("h1", f"g2tom report: scenario '{scenario.name}'"),
        Block("p", f"{scenario.description} (g2tom {__version__}, configuration hash {scenario.config_hash()})."),
    ]
    fits, missing = _load(data_dir, "fits", scenario)
    blocks += missing if fits is None else _fit_blocks(fits, scenario) + _ensemble_blocks(fits, scenario)
    sur, missing = _load(data_dir, "surrogate", scenario)
    blocks += missing if sur is None else _surrogate_blocks(sur)
    blocks.append(Block("h2", "Figures"))
    figures = sorted((data_dir / "figures").glob("*.png"), key=_figure_order)
    blocks += [Block("img", CAPTIONS.get(p.stem, p.stem), src=p.relative_to(data_dir).as_posix()) for p in figures]
    if not figures:
        blocks.append(Block("p", "No figures: run `g2tom figures` first."))
    return blocks + _run_blocks(scenario, data_dir)


def _md_cell(text: str) -> str:
    return text.replace("|", "\\|")


def to_markdown(blocks: list[Block]) -> str:
    """Render blocks as Markdown."""
    out: list[str] = []
    for b in blocks:
        if b.kind in ("h1", "h2"):
            out.append(("#" if b.kind == "h1" else "##") + " " + b.text)
        elif b.kind == "p":
            out.append(b.text)
        elif b.kind == "pre":
            out.append("```\n" + b.text + "\n```")
        elif b.kind == "img":
            out.append(f"![{b.text}]({b.src})\n\n*{b.text}*")
        elif b.kind == "table":
            header, *rows = b.rows
            lines = ["| " + " | ".join(_md_cell(c) for c in header) + " |", "|" + "---|" * len(header)]
            lines += ["| " + " | ".join(_md_cell(c) for c in row) + " |" for row in rows]
            out.append("\n".join(lines))
        else:
            raise ValueError(f"unknown block kind {b.kind!r}")
    return "\n\n".join(out) + "\n"


def to_html(blocks: list[Block], title: str) -> str:
    """Render blocks as a standalone HTML page."""
    e = html.escape
    body: list[str] = []
    for b in blocks:
        if b.kind in ("h1", "h2", "p"):
            body.append(f"<{b.kind}>{e(b.text)}</{b.kind}>")
        elif b.kind == "pre":
            body.append(f"<pre>{e(b.text)}</pre>")
        elif b.kind == "img":
            body.append(f'<figure><img src="{e(b.src)}" alt="{e(b.text)}"><figcaption>{e(b.text)}</figcaption></figure>')
        elif b.kind == "table":
            header, *rows = b.rows
            head = "".join(f"<th>{e(c)}</th>" for c in header)
            cells = "".join("<tr>" + "".join(f"<td>{e(c)}</td>" for c in row) + "</tr>" for row in rows)
            body.append(f"<table><thead><tr>{head}</tr></thead><tbody>{cells}</tbody></table>")
        else:
            raise ValueError(f"unknown block kind {b.kind!r}")
    style = ("body{font-family:sans-serif;max-width:70em;margin:2em auto}"
             "table{border-collapse:collapse;margin:1em 0}td,th{border:1px solid #ccc;padding:2px 6px;text-align:right}"
             "img{max-width:100%}")
    return (f"<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"><title>{e(title)}</title>"
            f"<style>{style}</style></head><body>\n" + "\n".join(body) + "\n</body></html>\n")


def write_report(scenario: Scenario, data_dir: str | Path) -> list[Path]:
    """Write ``report.md`` and ``report.html`` under ``data_dir`` atomically; returns both paths."""
    data_dir = Path(data_dir)
    blocks = build_blocks(scenario, data_dir)
    outputs = {
        data_dir / "report.md": to_markdown(blocks),
        data_dir / "report.html": to_html(blocks, f"g2tom report: {scenario.name}"),
    }
    for path, text in outputs.items():
        with atomic_path(path) as tmp:
            tmp.write_text(text, encoding="utf-8")
    return list(outputs)
