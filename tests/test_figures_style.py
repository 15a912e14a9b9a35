"""Every figure in one style (issue 32): mathtext labels, tick labels and legends clear of each other
and of the data, fig10's numbers clear of its flag marks, a colour cycle readable in grey."""

from __future__ import annotations

import itertools
import json
import re
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import matplotlib.figure
import numpy as np
import pytest
import xarray as xr
from matplotlib.backend_bases import RendererBase
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.text import Text
from matplotlib.transforms import Bbox

from g2tom.analysis import figures_results, figures_validate, style
from g2tom.analysis.figures import write_figures
from g2tom.config import ResolvedScenario
from g2tom.store import read_stage

#: ASCII spellings of symbols that belong in mathtext (whole words, outside $...$).
RAW_SYMBOLS = re.compile(r"\b(lambda|kappa|sqrt|sigma|xi|alpha|gamma|eta|rho|delta|psi|ohm)\b|\^|_", re.IGNORECASE)


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory, small_stages: Path) -> Path:
    """The small run's stage files (conftest's ``small_stages``, copied), the spots benchmark's file
    and a synthetic validate.nc."""
    import shutil

    data = tmp_path_factory.mktemp("data") / "data"
    shutil.copytree(small_stages, data)
    force = np.geomspace(1.0, 300.0, 5)
    spots = {name: {"force_N": force.tolist(),
                    "barber_ratio": {"greenwood": (shift * force**0.02).tolist(), "point": np.full(force.size, 0.98 * shift).tolist()}}
             for name, shift in (("mean_area", 1.6), ("expected", 1.01), ("asperities", 0.97))}
    (data / "bench").mkdir()
    (data / "bench" / "spots.json").write_text(json.dumps(spots))
    (data / figures_validate.FOLDER).mkdir()
    synthetic_validation().to_netcdf(data / figures_validate.FOLDER / "validate.nc")
    return data


def synthetic_validation(lightest: float = 0.075, heaviest: float = 18.8) -> xr.Dataset:
    """validate.nc's variables for the figure: two realizations, four loads from ``lightest`` to
    ``heaviest`` F' (the default set's range by default), four oxidized cases."""
    rng = np.random.default_rng(7)
    f = np.geomspace(lightest, heaviest, 4)
    disc, model, xi, lam = ["expected", "asperities"], ["greenwood", "point"], [0.5, 0.7], [1.0, 5.0]
    law = 0.02 * f**-0.7

    def noisy(*shape: int) -> np.ndarray:
        return law * rng.lognormal(0.0, 0.2, size=(*shape, f.size))

    return xr.Dataset(
        {"resistance_reference_clean": (("realization", "load"), noisy(2)),
         "resistance_g2tom_clean": (("discretization", "model", "realization", "load"), noisy(2, 2, 2)),
         "resistance_reference": (("xi", "lambda", "realization", "load"), noisy(2, 2, 2)),
         "resistance_g2tom": (("discretization", "model", "xi", "lambda", "realization", "load"), noisy(2, 2, 2, 2, 2))},
        coords={"force_normalized": ("load", f), "discretization": disc, "model": model, "xi": xi, "lambda": lam},
        attrs={"resistance_scale": 0.01},
    )


@contextmanager
def drawn_not_saved() -> Iterator[dict[str, matplotlib.figure.Figure]]:
    """Inside, ``Figure.savefig`` draws the figure on its canvas and keeps it by file name, writing nothing.

    The layout and the text extents the tests read are the figure's own; encoding a PNG at 300 dpi
    (half of the drawing time) tells them nothing (tests/test_report.py and
    tests/test_pipeline_end_to_end.py check the written files)."""
    figures: dict[str, matplotlib.figure.Figure] = {}

    def keep(self, path, *args, **kwargs):
        name = Path(path).name  # figures are written atomically: ".<name>.<random>.tmp", then renamed
        figures[name[1:].rsplit(".", 2)[0] if name.startswith(".") and name.endswith(".tmp") else name] = self
        self.canvas.draw()

    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(matplotlib.figure.Figure, "savefig", keep)
        yield figures


@pytest.fixture(scope="module")
def drawn(run_dir: Path, small: ResolvedScenario) -> dict[str, matplotlib.figure.Figure]:
    """Every figure of ``write_figures`` on the small run, by file name, drawn (renderer ready)."""
    with drawn_not_saved() as figures:
        written = write_figures(small, run_dir)
    assert sorted(p.name for p in written) == sorted(figures)
    return figures


def test_every_family_draws_on_the_small_run(drawn) -> None:
    assert set(drawn) == {"fig3_bounds.png", "fig4_contact.png", "fig5_spots.png", "fig6_oxide.png",
                          "fig8_resistance.png", "fig9_conductance.png", "fig10_alpha_gamma.png",
                          "fig10_realizations.png", "fig11_barber.png", "barber_spots.png", "validate.png"}
    for name, fig in drawn.items():
        assert fig.get_figwidth() in (style.ONE_COLUMN, style.TWO_COLUMNS), name


def _texts(fig: matplotlib.figure.Figure) -> list[str]:
    """Titles, axis labels, the suptitle and legend entries of ``fig`` (colour bars are axes too)."""
    out = [fig._suptitle.get_text()] if fig._suptitle else []
    for ax in fig.axes:
        out += [ax.get_xlabel(), ax.get_ylabel(), ax.get_title()]
        out += [t.get_text() for t in ax.get_legend().get_texts()] if ax.get_legend() else []
    for legend in fig.legends:
        out += [t.get_text() for t in legend.get_texts()] + [legend.get_title().get_text()]
    return [t for t in out if t]


def outside_math(text: str) -> str:
    """``text`` without its mathtext ($...$) segments; an unpaired $ fails."""
    assert text.count("$") % 2 == 0, f"unpaired $ in {text!r}"
    return "".join(text.split("$")[::2])


def test_no_symbol_is_spelled_in_ascii_outside_mathtext(drawn, small: ResolvedScenario) -> None:
    for name, fig in drawn.items():
        for text in _texts(fig):
            raw = RAW_SYMBOLS.search(outside_math(text).replace(small.name, ""))  # a name, not a symbol
            assert raw is None, f"{name}: {text!r} spells {raw.group(0)!r} outside mathtext"


def test_the_check_catches_the_old_spellings() -> None:
    for old in ("lambda = l_O sqrt(eta) = 5", "kappa / kappa_Barber (clean)", "resistance R (ohm)",
                "F' = 2F / (E* sqrt(R* s^3))"):
        assert RAW_SYMBOLS.search(outside_math(old))
    assert RAW_SYMBOLS.search(outside_math(style.LABELS["lambda"])) is None


def _renderer(fig: matplotlib.figure.Figure) -> RendererBase:
    """Draw ``fig`` (closed once saved) on a fresh Agg canvas in the figures' style; its renderer."""
    canvas = FigureCanvasAgg(fig)
    with style.context():
        canvas.draw()
    return canvas.get_renderer()


def _shown_tick_labels(ax, axis, renderer: RendererBase) -> list[tuple[Text, Bbox]]:
    """Extents of the non-empty major and minor tick labels of ``axis`` inside the axes' span."""
    low, high = (ax.bbox.x0, ax.bbox.x1) if axis is ax.xaxis else (ax.bbox.y0, ax.bbox.y1)
    boxes = []
    for label in axis.get_majorticklabels() + axis.get_minorticklabels():
        if label.get_visible() and label.get_text():
            box = label.get_window_extent(renderer)
            centre = (box.x0 + box.x1) / 2 if axis is ax.xaxis else (box.y0 + box.y1) / 2
            if low - 1 <= centre <= high + 1:
                boxes.append((label, box))
    return boxes


def tick_label_overlaps(fig: matplotlib.figure.Figure) -> list[str]:
    """Pairs of shown tick labels of ``fig`` that overlap, over all its axes (panels and colour bars)."""
    renderer = _renderer(fig)
    shown = [(label, box) for ax in fig.axes for axis in (ax.xaxis, ax.yaxis)
             for label, box in _shown_tick_labels(ax, axis, renderer)]
    return [f"{a.get_text()!r} and {b.get_text()!r}" for (a, box_a), (b, box_b) in itertools.combinations(shown, 2)
            if box_a.overlaps(box_b)]


def test_tick_labels_do_not_overlap(drawn) -> None:
    for name, fig in drawn.items():
        assert tick_label_overlaps(fig) == [], name


def _validate_figure(forces: tuple[float, float], path: Path) -> matplotlib.figure.Figure:
    """validate.png of :func:`synthetic_validation` over ``forces``, drawn and kept open for inspection."""
    with drawn_not_saved() as figures:
        figures_validate.figure(synthetic_validation(*forces), path)
    (figure,) = figures.values()
    return figure


@pytest.mark.parametrize("forces", [(0.075, 18.8), (0.4, 2.0), (0.9, 1.3)], ids=["decades", "one decade", "narrow"])
def test_validate_ticks_are_apart_and_the_legend_is_outside_every_panel(forces, tmp_path: Path) -> None:
    fig = _validate_figure(forces, tmp_path / "validate.png")
    assert tick_label_overlaps(fig) == []
    renderer = _renderer(fig)
    for ax in fig.axes:  # plain labels, and at least two per axis however short the span
        for axis in (ax.xaxis, ax.yaxis) if ax.axison else ():
            labels = [label.get_text() for label, _ in _shown_tick_labels(ax, axis, renderer)]
            assert len(labels) >= 2 and not any("times" in text for text in labels), labels
    assert not any(ax.get_legend() for ax in fig.axes) and len(fig.legends) == 1
    legend = fig.legends[0].get_window_extent(renderer)
    for ax in fig.axes:
        if ax.axison:
            assert not legend.overlaps(ax.get_window_extent(renderer))


def test_default_log_labels_at_paper_width_would_be_caught(tmp_path: Path, monkeypatch) -> None:
    """Matplotlib's own minor labels (4 x 10^-1, 6 x 10^-1) on one decade of F' run into each other."""
    monkeypatch.setattr(figures_validate, "plain_log_ticks", lambda axis: None)
    assert tick_label_overlaps(_validate_figure((0.4, 2.0), tmp_path / "validate.png"))


def _flag_boxes(ax, renderer: RendererBase) -> list[Bbox]:
    """Display-space boxes of each flag marker (marker size plus edge width, in pixels)."""
    boxes = []
    for line in ax.get_lines():
        if line.get_marker() != "x":
            continue
        half = (line.get_markersize() + line.get_markeredgewidth()) * renderer.points_to_pixels(1.0) / 2
        for x, y in ax.transData.transform(line.get_xydata()):
            boxes.append(Bbox.from_extents(x - half, y - half, x + half, y + half))
    return boxes


def _realizations_figure(run_dir: Path, small: ResolvedScenario, tmp_path: Path) -> matplotlib.figure.Figure:
    """fig10_realizations with every cell flagged, drawn and kept open for inspection."""
    fits = read_stage(run_dir, "fits", small)
    fits["flagged"] = xr.ones_like(fits["flagged"])
    with drawn_not_saved() as figures, style.context():
        figures_results.fig10_realizations(tmp_path / "fig10_realizations.png", fits)
    (figure,) = figures.values()
    return figure


def _overlaps(fig: matplotlib.figure.Figure) -> int:
    renderer = _renderer(fig)
    count, panels = 0, [ax for ax in fig.axes if ax.get_images()]
    assert len(panels) == 2
    for ax in panels:
        flags = _flag_boxes(ax, renderer)
        assert len(flags) == len(ax.texts) == 9
        count += sum(text.get_window_extent(renderer).overlaps(flag) for text in ax.texts for flag in flags)
    return count


def test_fig10_numbers_are_clear_of_the_flag_marks(run_dir: Path, small: ResolvedScenario, tmp_path: Path) -> None:
    assert _overlaps(_realizations_figure(run_dir, small, tmp_path)) == 0


def test_flag_marks_at_the_cell_centre_would_be_caught(run_dir: Path, small: ResolvedScenario, tmp_path: Path,
                                                        monkeypatch) -> None:
    monkeypatch.setattr(figures_results, "FLAG_OFFSET", (0.0, 0.0))
    assert _overlaps(_realizations_figure(run_dir, small, tmp_path)) >= 18  # each number under its own mark


def test_alpha_is_drawn_on_a_log_axis(drawn) -> None:
    fig = drawn["fig10_alpha_gamma.png"]
    scales = {ax.get_ylabel(): ax.get_yscale() for ax in fig.axes if ax.get_xlabel() == style.LABELS["xi"]
              and not ax.get_images()}
    assert scales == {style.LABELS["alpha"]: "log", style.LABELS["gamma"]: "linear"}


def test_colour_cycle_darkens_to_lightens_in_grey() -> None:
    levels = [style.grey_level(c) for c in style.COLORS]
    assert all(b - a >= 0.1 for a, b in zip(levels, levels[1:]))
    assert style.grey_level("k") < levels[0]


def test_labels_are_mathtext_and_equals_refuses_a_unit() -> None:
    for key, label in style.LABELS.items():
        assert RAW_SYMBOLS.search(outside_math(label)) is None, key
    assert style.equals("xi", 0.5) == r"$\xi = 0.5$"
    with pytest.raises(ValueError, match="mathtext"):
        style.equals("force", 1.0)
    with pytest.raises(ValueError, match="1 or 2"):
        style.size(3, 2.0)
