"""Result figures and the report on a synthetic cube run through stages 4-5."""

from __future__ import annotations

import json
import re
import warnings
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
import pytest

from g2tom.analysis import figures_results
from g2tom.analysis.report import write_report
from g2tom.analysis.report_blocks import Block
from g2tom.analysis.report_render import to_html, to_markdown
from g2tom.cli.main import main
from g2tom.config import ResolvedScenario
from g2tom.before_work import load_scenario
from g2tom.stages import fits as fits_stage
from g2tom.store import write_dataset
from tests.conftest import SMALL_OVERRIDES
from tests.test_fits_stage import cli_overrides, synthetic_cube

FIGURES = ["fig3_bounds.png", "fig8_resistance.png", "fig9_conductance.png", "fig10_alpha_gamma.png", "fig10_realizations.png", "fig11_barber.png"]


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory, small: ResolvedScenario) -> Path:
    """fits and surrogate stages run by the CLI on a synthetic cube with some open circuits."""
    data = tmp_path_factory.mktemp("data")
    write_dataset(synthetic_cube(small, open_share=0.25), data, "cube", small)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)  # surrogate orders reduced on a 3 x 3 grid
        for stage in ("fits", "surrogate"):
            assert main([stage, "--data-dir", str(data), "--no-progress", *cli_overrides(small)]) == 0
    (data / "bench").mkdir()
    (data / "bench" / "cube.json").write_text(json.dumps([{"method": "fft", "seconds": 1.5}]))
    # a nested record, as `g2tom bench` writes them: the report lists it, it does not print it
    record = {"spots": {name: {"per_step_seconds": [0.1 * k for k in range(12)], "ratio": [1 + 0.01 * k for k in range(12)]}
                        for name in ("expected", "asperities", "grid")}}
    (data / "bench" / "spots.json").write_text(json.dumps(record))
    return data


def test_stage_files(run_dir: Path) -> None:
    for name in ("fits.nc", "surrogate.nc", "table3.csv", "table3.md", "timings.json"):
        assert (run_dir / name).stat().st_size > 0
    assert len((run_dir / "table3.csv").read_text().splitlines()) == 10


def test_figures_written_and_non_empty(run_dir: Path, small: ResolvedScenario) -> None:
    out = run_dir / "figures"
    out.mkdir(exist_ok=True)
    paths = figures_results.write(small, run_dir, out)
    assert [p.name for p in paths] == FIGURES
    for p in paths:
        assert p.stat().st_size > 10_000, p


def test_report_has_everything(run_dir: Path, small: ResolvedScenario) -> None:
    out = run_dir / "figures"
    out.mkdir(exist_ok=True)
    (out / "extra_stage_figure.png").write_bytes(b"\x89PNG")
    assert main(["report", "--data-dir", str(run_dir), *cli_overrides(small)]) == 0
    md = (run_dir / "report.md").read_text()
    page = (run_dir / "report.html").read_text()
    for text in ("Clean-surface fit", "Table 3", "Table 4", "cross-validation", "Timings", "Benchmarks",
                 "fits.min_force", "figures/extra_stage_figure.png", "bench/cube.json", "bench/spots.json"):
        assert text in md and text in page, text
    assert md.count("![") == page.count("<img") == len(list(out.glob("*.png")))
    # figures in numeric order, captioned; the bootstrap intervals are described
    order = [md.index(f"figures/{name}") for name in FIGURES]  # FIGURES is in numeric order
    assert order == sorted(order)
    assert "Fig. 11: G2TOM against the p-average" in md and "Fig. 11: G2TOM against the p-average" in page
    assert "95 % percentile intervals of alpha and gamma" in md
    # the ensemble section: a fixed ensemble of 8, nothing flagged, half-widths in the table
    assert "Ensemble: realizations used and reached confidence" in md and "fixed: 8 realizations" in md
    assert "Flagged cells (stopped at the cap short of the target): 0." in md


def test_report_without_stage_files(tmp_path, small: ResolvedScenario) -> None:
    paths = write_report(small, tmp_path)
    assert "Not available" in paths[0].read_text()


def test_renderers_escape() -> None:
    blocks = [Block("h1", "a <b>"), Block("table", rows=(("x|y", "z"), ("1", "<2>")))]
    assert "x\\|y" in to_markdown(blocks)
    assert "&lt;2&gt;" in to_html(blocks, "t")
    # a single * is a star (E*, R*), not emphasis; **bold** and `code` stay markup
    page = to_html([Block("p", "K / (E* rho*) with **bold** and `A*`"), Block("table", rows=(("R*",), ("*",)))], "t")
    assert "K / (E* rho*) with <strong>bold</strong> and <code>A*</code>" in page and "<em>" not in page
    assert "<th>R*</th>" in page and "<td>*</td>" in page
    with pytest.raises(ValueError, match="unknown block"):
        to_markdown([Block("video")])


def test_load_figure_markers_are_the_fitted_reduction() -> None:
    scenario = load_scenario("paper_gt", {**SMALL_OVERRIDES, "fits.reduction": "median"})
    cube = synthetic_cube(scenario, noise=0.5)
    ds = fits_stage.build(scenario, cube)
    xi, lam = float(ds.xi[1]), float(ds["lambda"][1])
    fig, ax = plt.subplots()
    figures_results._load_panel(ax, cube, ds, lam, [xi], normalized=False)
    markers = [line for line in ax.get_lines() if line.get_marker() == "o"]
    plt.close(fig)
    cell = {"xi": xi, "lambda": lam}
    np.testing.assert_allclose(markers[0].get_ydata(), ds["median"].sel(cell).values)
    assert not np.allclose(ds["median"].sel(cell), ds["geometric_mean"].sel(cell))


def test_report_parameters_carry_units(run_dir: Path, small: ResolvedScenario) -> None:
    assert main(["report", "--data-dir", str(run_dir), *cli_overrides(small)]) == 0
    md = (run_dir / "report.md").read_text()
    assert "| roughness.sigma | 2e-05 | m | standard deviation of asperity heights |" in md
    assert "| material.rho | 7.2e-07 | ohm m |" in md


def test_curve_section_counts_the_cells(small) -> None:
    from g2tom.analysis.report_physics import curve_blocks
    from g2tom.stages import fits
    from tests.test_fits_stage import synthetic_cube

    ds = fits.build(small, synthetic_cube(small, noise=0.0))
    text = curve_blocks(ds)[1].text
    n = ds["curve_order"].size
    assert f"Within 3 %: {int((ds['curve_within'] == 1).sum())} of {n}" in text
    assert "F' >= 0.4" in text and "--model power_law" in text


def test_a_stage_markdown_section_becomes_headings_paragraphs_and_tables(tmp_path) -> None:
    from g2tom.analysis.report_blocks import markdown_blocks
    from g2tom.analysis.report_physics import validation_blocks

    text = ("## How right is the model?\n\n**Clean: off by +40 %.**\nScene: mu = 8.26.\n\n### expected, greenwood\n\n"
            "| F (N) | clean |\n|---|---|\n| 27.45 | 1.397 [1.2-1.9] |\n| 1768 | 1.024 |\n\nGrid convergence: -1.4 %.\n")
    blocks = markdown_blocks(text, "GW surface")
    assert [b.kind for b in blocks] == ["h3", "p", "p", "h3", "table", "p"]
    assert blocks[0].text == "GW surface" and blocks[3].text == "expected, greenwood"
    assert blocks[4].rows == (("F (N)", "clean"), ("27.45", "1.397 [1.2-1.9]"), ("1768", "1.024"))
    html = to_html(blocks, "t")
    assert "<strong>Clean: off by +40 %.</strong>" in html and "<td>1.397 [1.2-1.9]</td>" in html
    assert to_markdown(blocks).count("| 27.45 | 1.397 [1.2-1.9] |") == 1
    (tmp_path / "validate").mkdir()
    (tmp_path / "validate" / "validate.md").write_text(text)
    kinds = [b.kind for b in validation_blocks(tmp_path)]
    assert kinds[:2] == ["h2", "h3"] and "pre" not in kinds and "table" in kinds


def _report(run_dir: Path, small: ResolvedScenario) -> tuple[str, str]:
    """report.md and report.html of the small run, written by the CLI."""
    assert main(["report", "--data-dir", str(run_dir), *cli_overrides(small)]) == 0
    return (run_dir / "report.md").read_text(), (run_dir / "report.html").read_text()


def test_report_reads_top_to_bottom(run_dir: Path, small: ResolvedScenario) -> None:
    md, _ = _report(run_dir, small)
    lines = md.splitlines()
    first_table = next(i for i, line in enumerate(lines) if line.startswith("|"))
    at = {title: lines.index(title) for title in ("## Summary", "## Contents", "## Figures", "## Appendix",
                                                   "### Table 3: fitted and surrogate alpha, gamma")}
    assert lines[0].startswith("# g2tom report")
    assert at["## Summary"] < at["## Contents"] < at["## Figures"] < first_table
    assert at["## Appendix"] < at["### Table 3: fitted and surrogate alpha, gamma"]
    assert not [line for line in lines[at["## Appendix"] + 1:] if line.startswith("## ")]  # the appendix is last
    summary = md[md.index("## Summary"):md.index("## Contents")]
    for text in ("scenario 'paper'", "3 xi", "3 lambda", "F = 20-5000 N", "F' = ", "realizations used per cell 8",
                 "alpha = 0.8", "gamma = 0.23", "worst relative error on the grid", "0 of 9", "greenwood_tripp"):
        assert text in summary, text


def test_report_contents_links_resolve(run_dir: Path, small: ResolvedScenario) -> None:
    md, page = _report(run_dir, small)
    contents = md[md.index("## Contents"):md.index("## Figures")]
    anchors = re.findall(r"\]\(#([^)]+)\)", contents)
    assert len(anchors) == contents.count("\n- ") + contents.count("\n    - ") > 10
    assert "table-3-fitted-and-surrogate-alpha-gamma" in anchors
    ids = set(re.findall(r'<h[1-4] id="([^"]+)"', page))
    assert set(anchors) <= ids, set(anchors) - ids


def test_report_lists_benchmarks_and_renders_code(run_dir: Path, small: ResolvedScenario) -> None:
    md, page = _report(run_dir, small)
    # the nested record is listed, not printed: no raw JSON lines, and the report is shorter than the
    # 393 lines the same run gave when records were dumped (issue 32)
    assert '{"' not in md and "{" not in md.splitlines() and "per_step_seconds" not in md
    size = (run_dir / "bench" / "spots.json").stat().st_size
    assert size < 1000 and f"- spots: [bench/spots.json](bench/spots.json), {size} B" in md
    assert len(md.splitlines()) < 393
    # Markdown rendered: backticks become <code>, tables and ids are HTML
    assert "<code>make validate</code>" in page and "`" not in page
    assert "<table>" in page and 'id="summary"' in page and "overflow-wrap:anywhere" in page


def test_summary_quotes_the_validation_flags(tmp_path, small: ResolvedScenario) -> None:
    from g2tom.analysis.report import _summary_blocks
    from g2tom.analysis.report_physics import validation_blocks

    (tmp_path / "validate").mkdir()
    (tmp_path / "validate" / "validate.md").write_text("## How right?\n\n**Clean: off by +40 %.**\nScene: mu = 8.\n")
    heading, items = _summary_blocks(small, None, None, validation_blocks(tmp_path))
    texts = [text for _level, text in items.rows]
    assert heading.text == "Summary" and "Against the full elastic contact (GW surface): **Clean: off by +40 %.**" in texts
    assert not any("Scene: mu" in t for t in texts) and any("fits stage" in t for t in texts)


def test_surrogate_cells_outside_the_target_are_named() -> None:
    import xarray as xr

    from g2tom.analysis.report_results import surrogate_misses

    lam, xi = [1.0, 5.0], [0.3, 0.5, 0.9]
    sigma = np.full((2, 3), 0.01)  # 2 % half-width at z = 2: the bound is the 3 % floor
    error = np.array([[0.01, -0.029, 0.02], [0.0, 0.055, -0.031]])
    sur = xr.Dataset({"alpha_relative_error": (("lambda", "xi"), error),
                      "alpha_fit_sigma": (("lambda", "xi"), sigma),
                      "alpha_fit": (("lambda", "xi"), np.ones((2, 3)))}, coords={"lambda": lam, "xi": xi})
    assert surrogate_misses(sur, "alpha", 2.0) == ["alpha at xi 0.5, lambda 5: 5.50 % against 3.00 %",
                                                   "alpha at xi 0.9, lambda 5: 3.10 % against 3.00 %"]
    sur["alpha_fit_sigma"][1, 1] = 0.03  # a wide interval (6.2 %) covers the 5.5 % miss
    assert surrogate_misses(sur, "alpha", 2.0) == ["alpha at xi 0.9, lambda 5: 3.10 % against 3.00 %"]
