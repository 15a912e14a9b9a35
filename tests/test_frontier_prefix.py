"""The frontier's prefix curve of an adaptive cube: fast-rule half-widths and time per (xi, lambda)."""

from __future__ import annotations

import json

import numpy as np
import pytest
import xarray as xr

from g2tom.bench import frontier, frontier_plot, frontier_prefix
from g2tom.cli.main import main
from g2tom.before_work import load_scenario

SETS = {"oxide.xi": "[0.3, 0.7]", "oxide.lambda": "[3.0, 9.0]", "oxide.min_realizations": 60,
        "compute.oxide_batch": 40, "oxide.max_realizations": 260, "oxide.target_half_width": 0.02,
        "loading.n_delta": 6, "contact.n_radial": 160}


@pytest.fixture(scope="module")
def adaptive_dir(tmp_path_factory):
    data = tmp_path_factory.mktemp("adaptive")
    args = ["--config", "paper_gt", *[a for k, v in SETS.items() for a in ("--set", f"{k}={v}")], "--data-dir", str(data),
            "--no-progress"]
    for stage in ("contact", "oxide", "cube"):
        assert main([stage, *args]) == 0
    return data


def _scenario():
    from g2tom.before_work.domains import resolve

    return resolve(load_scenario("paper_gt", {k: json.loads(v) if isinstance(v, str) else v for k, v in SETS.items()}))


def test_prefix_counts_are_log_spaced_and_end_at_the_count() -> None:
    n = frontier_prefix.prefix_counts(3000)
    assert n[0] == 50 and n[-1] == 3000 and n.size == frontier_prefix.PREFIX_POINTS
    assert np.all(np.diff(n) > 0)
    np.testing.assert_allclose(n[1:] / n[:-1], (3000 / 50) ** (1 / (n.size - 1)), rtol=0.02)
    assert frontier_prefix.prefix_counts(30)[0] == 30 and frontier_prefix.prefix_counts(30)[-1] == 30


def test_prefix_curve_of_an_adaptive_cube(adaptive_dir) -> None:
    scenario = _scenario()
    curve, note = frontier_prefix.adaptive_prefix(scenario, adaptive_dir)
    assert curve is not None, note
    with xr.open_dataset(adaptive_dir / "cube.nc") as cube_ds:
        counts = cube_ds["n_realizations"].transpose("xi", "lambda").values
        rule = {k: cube_ds[f"rule_{k}_half_width"].transpose("xi", "lambda").values for k in ("alpha", "gamma")}
    seconds = json.loads((adaptive_dir / "timings.json").read_text())["cube"]["seconds"]
    assert curve["prefix_n"].shape == (2, 2, frontier_prefix.PREFIX_POINTS)
    assert counts.min() >= 60 and counts.max() > counts.min()  # the rule stopped cells at different counts
    np.testing.assert_array_equal(curve["prefix_n"].isel(prefix_step=0).values, 50)
    np.testing.assert_array_equal(curve["prefix_n"].isel(prefix_step=-1).values, counts)
    for k in ("alpha", "gamma"):
        width = curve[f"prefix_{k}_halfwidth"].values
        # ends at the cube's recorded fast-rule half-width, computed by the cube stage
        np.testing.assert_allclose(width[..., -1], rule[k], rtol=1e-12)
        assert np.all(width > 0) and np.all(width[..., -1] < width[..., 0])
        assert np.mean(np.diff(width, axis=-1) < 0) > 0.7  # monotone-ish: mostly falling
        # the rule's half-width falls like n^-1/2 to within the noise of the std estimate
        scaled = width * np.sqrt(curve["prefix_n"].values)
        assert np.all(scaled.max(-1) / scaled.min(-1) < 3)
    np.testing.assert_allclose(curve["prefix_seconds"].values,
                               curve["prefix_n"].values * seconds / counts.sum(), rtol=1e-12)
    for var in curve.variables.values():
        assert "units" in var.attrs and "long_name" in var.attrs


def test_prefix_curve_written_plotted_and_reported(adaptive_dir, tmp_path) -> None:
    from g2tom.analysis.report_appendix import frontier_blocks
    from g2tom.analysis.report_render import to_markdown
    from tests.test_frontier import CONTACT, CUBE, _ensemble

    curve, note = frontier_prefix.adaptive_prefix(_scenario(), adaptive_dir)
    path = frontier.write(CONTACT, CUBE, _ensemble([0.2, 0.1]), tmp_path / "bench" / "frontier.nc", curve, note)
    with xr.open_dataset(path, decode_timedelta=False) as ds:
        assert ds.sizes["xi"] == 2 and ds.sizes["cube_xi"] == 2 and ds.sizes["prefix_step"] == frontier_prefix.PREFIX_POINTS
        np.testing.assert_array_equal(ds["prefix_n"].values, curve["prefix_n"].values)
        for name, var in ds.variables.items():
            assert "units" in var.attrs and "long_name" in var.attrs, name
        assert ds.attrs["prefix_rule_target"] == pytest.approx(0.9 * 0.02)  # 0.9 x oxide.target_half_width
        paths = frontier_plot.plot(ds.load(), tmp_path / "figures")
    assert paths[-1].name == "frontier_prefix.png" and paths[-1].stat().st_size > 10_000
    summary = frontier_prefix.prefix_summary(curve, note)
    (tmp_path / "bench" / "frontier.json").write_text(json.dumps({"prefix": summary}))
    md = to_markdown(frontier_blocks(tmp_path))
    assert f"over 4 (xi, lambda) cells of {summary['count_min']} .. {summary['count_max']} realizations" in md
    assert "(figures/frontier_prefix.png)" in md


def test_prefix_curve_skipped_with_a_note(tmp_path) -> None:
    curve, note = frontier_prefix.adaptive_prefix(_scenario(), tmp_path)
    assert curve is None and note.startswith("prefix curve skipped:") and "cube.nc is missing" in note
    (tmp_path / "bench").mkdir()
    (tmp_path / "bench" / "frontier.json").write_text(json.dumps({"prefix": frontier_prefix.prefix_summary(None, note)}))
    from g2tom.analysis.report_appendix import frontier_blocks
    from g2tom.analysis.report_render import to_markdown

    assert "prefix curve skipped:" in to_markdown(frontier_blocks(tmp_path))
