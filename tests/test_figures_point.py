"""``make compare``: both models through every stage on one ensemble, their figures and report section."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest

from g2tom.analysis import figures_point
from g2tom.analysis.report import build_blocks
from g2tom.cli.main import main
from g2tom.config import ResolvedScenario
from tests.test_fits_stage import cli_overrides


@pytest.fixture(scope="module")
def compare_dir(tmp_path_factory, small: ResolvedScenario, small_stages: Path) -> Path:
    """The stages run by the CLI once per model under <data>/compare/<model>, as `make compare` does
    (greenwood, small's own cube.model: conftest's ``small_stages``, the same scenario, copied)."""
    import shutil

    assert small.cube.model == "greenwood"
    data = tmp_path_factory.mktemp("data")
    shutil.copytree(small_stages, data / figures_point.COMPARE / "greenwood")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)  # surrogate orders reduced on a 3 x 3 grid
        for model in figures_point.MODELS:
            if model == "greenwood":
                continue
            target = data / figures_point.COMPARE / model
            for stage in ("contact", "oxide", "cube", "fits", "surrogate"):
                args = [stage, "--data-dir", str(target), "--no-progress", *cli_overrides(small),
                        "--set", f"cube.model={model}"]
                assert main(args) == 0
    return data


def test_point_alpha_is_below_greenwood_and_the_report_shows_both(compare_dir: Path, small: ResolvedScenario) -> None:
    fits = figures_point.load_comparison(compare_dir)
    assert fits is not None
    assert float(fits["point"]["alpha_clean"]) < float(fits["greenwood"]["alpha_clean"])
    r_g = fits["greenwood"]["geometric_mean"].values
    r_p = fits["point"]["geometric_mean"].values
    assert np.all(r_p[np.isfinite(r_g)] <= r_g[np.isfinite(r_g)] * (1 + 1e-6))
    blocks = build_blocks(small, compare_dir)
    titles = [b.text for b in blocks if b.kind == "h2"]
    assert "Greenwood's closed form against the point-interaction model" in titles
    table = next(b for b in blocks[blocks.index(next(b for b in blocks if b.text == titles[titles.index(
        "Greenwood's closed form against the point-interaction model")])):] if b.kind == "table")
    assert len(table.rows) == 1 + 1 + 9  # header, clean, 3 x 3 grid
    # alpha is an extrapolated intercept, so its ratio is not bounded by 1 as every R is; with
    # expected spots Greenwood's form is within 1 % of the exact one (clean: 0.995)
    for row in table.rows[1:]:
        assert float(row[4]) == pytest.approx(float(row[3]) / float(row[2]), rel=1e-4)
        assert 0.9 < float(row[4]) < 1.01


def test_film_sweep_runs_from_clean_to_insulating(compare_dir: Path) -> None:
    sweep = figures_point.film_sweep(compare_dir, np.logspace(-15, -6, 4))
    point, greenwood = sweep["point"], sweep["greenwood"]
    assert np.all(np.diff(point, axis=1) >= -1e-9 * point[:, 1:])  # R grows with r_f
    np.testing.assert_allclose(point[:, 0], sweep["point_clean"], rtol=1e-3)  # r_f = 1e-15: nearly clean
    finite = np.isfinite(sweep["point_insulating"])
    np.testing.assert_allclose(point[finite, -1], sweep["point_insulating"][finite], rtol=1e-2)
    assert np.all(greenwood >= point * (1 - 1e-9))


def test_figures_written_only_with_a_comparison(compare_dir: Path, small: ResolvedScenario, tmp_path: Path) -> None:
    out = compare_dir / "figures"
    out.mkdir(exist_ok=True)
    paths = figures_point.write(small, compare_dir, out, films=np.logspace(-13, -9, 3))
    assert [p.name for p in paths] == ["point_alpha_gamma.png", "point_film.png"]
    assert all(p.stat().st_size > 10_000 for p in paths)
    assert figures_point.write(small, tmp_path, tmp_path) == []
