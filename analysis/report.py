"""``make report``: ``<data_dir>/report.md`` and ``report.html`` from one block structure.

The report is a list of blocks (heading, paragraph, table, image, preformatted text);
:func:`to_markdown` writes them as Markdown and :func:`to_html` renders that Markdown with
python-markdown, so the two files always agree. Sections whose input file is missing or stale say so
instead of failing, so a partial run still gets a report.
"""


from __future__ import annotations

import re
import time
from pathlib import Path
from typing import Any

from markdown.extensions.toc import slugify, unique
import xarray as xr

from g2tom.analysis.report_appendix import (
    FRONTIER_FIGURES, benchmark_blocks, frontier_blocks, parameter_blocks, stability_blocks, timing_blocks)
from g2tom.analysis.report_blocks import Block
from g2tom.analysis.report_physics import (
    atlas_blocks, barber_blocks, bias_blocks, curve_blocks, point_blocks, validation_blocks)
from g2tom.analysis.report_render import to_html, to_markdown
from g2tom.analysis.report_summary import summary_blocks as _summary_blocks
from g2tom.analysis.report_surface import surface_blocks
from g2tom.analysis.report_results import ensemble_blocks, fit_blocks, surrogate_model_blocks, surrogate_table_blocks
from g2tom.config import Scenario
from g2tom.store import StaleInputError, atomic_path, read_stage

__all__ = ["Block", "build_blocks", "to_markdown", "to_html", "write_report"]


#: Captions of the known figures, keyed by file stem; other figures are captioned by their stem.
CAPTIONS = {
    "fig3_bounds": "Fig. 3: Barber's clean and oxide-extended conductance bounds (Eqs. 8-9) and their geometric mean",
    "fig4_contact": "Fig. 4: Greenwood-Tripp solution of the rough Hertzian contact",
    "fig5_spots": "Fig. 5: discrete contact spots",
    "fig6_oxide": "Fig. 6: random oxide fields and thresholded oxides",
    "fig8_resistance": "Fig. 8: resistance R against force F: 16-84 % band, the fitted reduction (markers) and its power-law fit",
    "fig9_conductance": "Fig. 9: normalized conductance kappa' = 1/R' against F'",
    "fig10_alpha_gamma": "Fig. 10: fitted alpha and gamma (95 % bootstrap intervals) with their surrogate (Eq. 26) and its relative error",
    "fig10_realizations": "Fig. 10 (beside): realizations used per (xi, lambda) and alpha's reached 95 % half-width; x marks flagged cells",
    "fig11_barber": "Fig. 11: G2TOM against the p-average of the oxide-extended Barber bounds (Eq. 10)",
    "point_alpha_gamma": "Point-interaction model against Greenwood's closed form: alpha ratio and gamma shift",
    "barber_spots": "Barber's check: clean conductance over K / (E* rho*) against F for every grid spot discretization "
                    "of Greenwood-Tripp's contact (colours) and model (lines), from `g2tom bench --only spots`",
    "point_film": "Resistance against the oxide film's specific resistance r_f: clean to insulating",
}


def _figure_order(path: Path) -> tuple[Any, ...]:
    """Sort key that puts fig3 before fig10 (numbers compared as numbers)."""
    return tuple(int(part) if part.isdigit() else part for part in re.split(r"(\d+)", path.stem))


def _load(data_dir: Path, stage: str, scenario: Scenario) -> tuple[xr.Dataset | None, list[Block]]:
    try:
        return read_stage(data_dir, stage, scenario), []
    except StaleInputError as exc:
        return None, [Block("p", f"Not available: {exc}")]


def _contents_blocks(before: list[Block], after: list[Block]) -> list[Block]:
    """Section "Contents": links to the sections in ``after`` (and the Appendix's subsections).

    Parameters
    ----------
    before, after : list of Block
        The report's blocks before and after the contents; the anchors count every heading in
        order, as python-markdown's ``toc`` extension (and GitHub) number repeated titles.

    Returns
    -------
    list of Block
        The heading and a nested list of ``[title](#anchor)`` links.
    """
    contents = Block("h2", "Contents")
    ids: set[str] = set()
    items, section = [], ""
    for b in [*before, contents, *after]:
        if b.kind not in ("h1", "h2", "h3", "h4"):
            continue
        anchor = unique(slugify(b.text, "-"), ids)
        if b.kind == "h2":
            section = b.text
        if b.kind == "h2" and b is not contents:
            items.append((0, f"[{b.text}](#{anchor})"))
        elif b.kind == "h3" and section == "Appendix":
            items.append((1, f"[{b.text}](#{anchor})"))
    return [contents, Block("list", rows=tuple(items))]


def _demote(blocks: list[Block]) -> list[Block]:
    """The blocks with every heading one level lower (h2 to h3, h3 to h4), to nest them in a section."""
    lower = {"h2": "h3", "h3": "h4"}
    return [Block(lower.get(b.kind, b.kind), b.text, b.rows, b.src) for b in blocks]


def build_blocks(scenario: Scenario, data_dir: str | Path, started: float | None = None) -> list[Block]:
    """The whole report as blocks, in reading order (figures linked relative to ``data_dir``).

    Title, Summary (the answer in ohm, how right, how long, the predict command), Contents, Figures,
    the physics sections, then an Appendix with the long tables and the list of raw benchmark
    records.

    Parameters
    ----------
    scenario : Scenario
        The run's configuration.
    data_dir : str or Path
        The folder of the stage outputs, where the report is written.
    started : float, optional
        A :func:`time.perf_counter` value: when the report began, for its own row in the
        timings table; default: now.

    Returns
    -------
    list of Block
        The report's blocks.
    """
    started = time.perf_counter() if started is None else started
    data_dir = Path(data_dir)
    fits, missing_fits = _load(data_dir, "fits", scenario)
    sur, missing_sur = _load(data_dir, "surrogate", scenario)
    validation = validation_blocks(data_dir)
    physics = missing_fits if fits is None else (
        fit_blocks(fits, scenario) + ensemble_blocks(fits, scenario) + curve_blocks(fits))
    physics += missing_sur if sur is None else surrogate_model_blocks(sur)
    physics += bias_blocks(data_dir) + barber_blocks(data_dir, scenario) + validation
    physics += atlas_blocks(data_dir) + point_blocks(data_dir) + surface_blocks(data_dir)
    figures = sorted((p for p in (data_dir / "figures").glob("*.png") if p.stem not in FRONTIER_FIGURES),
                     key=_figure_order)
    body = [Block("h2", "Figures")]
    body += [Block("img", CAPTIONS.get(p.stem, p.stem), src=p.relative_to(data_dir).as_posix()) for p in figures]
    if not figures:
        body.append(Block("p", "No figures: run `g2tom figures` first."))
    appendix = [] if sur is None else surrogate_table_blocks(sur)
    appendix += frontier_blocks(data_dir) + stability_blocks(data_dir) + parameter_blocks(scenario)
    appendix += benchmark_blocks(data_dir)
    appendix += timing_blocks(scenario, data_dir, time.perf_counter() - started)  # last: it times the rest
    body += physics + [Block("h2", "Appendix"), Block("p", "The long tables and the raw records.")]
    body += _demote(appendix)
    head = [Block("h1", f"g2tom report: scenario '{scenario.name}'")]
    head += _summary_blocks(scenario, fits, sur, validation, data_dir)
    return head + _contents_blocks(head, body) + body


def write_report(scenario: Scenario, data_dir: str | Path) -> list[Path]:
    """Write ``report.md`` and ``report.html`` under ``data_dir`` atomically; returns both paths."""
    started = time.perf_counter()
    data_dir = Path(data_dir)
    blocks = build_blocks(scenario, data_dir, started)
    outputs = {
        data_dir / "report.md": to_markdown(blocks),
        data_dir / "report.html": to_html(blocks, f"g2tom report: {scenario.name}"),
    }
    for path, text in outputs.items():
        with atomic_path(path) as tmp:
            tmp.write_text(text, encoding="utf-8")
    return list(outputs)
