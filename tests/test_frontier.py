"""The accuracy–time frontier benchmark: its sweeps, its recommendation and its file."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

from g2tom.bench import frontier, frontier_plot, frontier_sweeps
from g2tom.before_work.domains import resolve
from g2tom.before_work import load_scenario


def _ensemble(widths: list[float]) -> xr.Dataset:
    n = np.array([25, 50, 100, 200])[: len(widths)]
    w = np.array(widths)[:, None, None] * np.ones((1, 2, 1))
    dims = ("n_realizations", "xi", "lambda")
    return xr.Dataset(
        {"alpha_halfwidth": (dims, w, {"units": "1", "long_name": "a"}),
         "gamma_halfwidth": (dims, w / 2, {"units": "1", "long_name": "g"}),
         "ensemble_seconds": (("n_realizations",), n * 0.01, {"units": "s", "long_name": "t"})},
        coords={"n_realizations": ("n_realizations", n, {"units": "1", "long_name": "n"}),
                "xi": ("xi", [0.2, 0.5], {"units": "1", "long_name": "xi"}),
                "lambda": ("lambda", [3.0], {"units": "1", "long_name": "lambda"})},
    )


CONTACT = [
    {"solver": "newton", "n_radial": 20, "radial_grid": "graded", "tolerance": 1e-4, "seconds": 0.01,
     "force_error": 2e-3, "area_error": 5e-3, "converged": True},
    {"solver": "newton", "n_radial": 120, "radial_grid": "graded", "tolerance": 1e-7, "seconds": 0.05,
     "force_error": 4e-4, "area_error": 6e-4, "converged": True},
    {"solver": "newton", "n_radial": 720, "radial_grid": "graded", "tolerance": 1e-10, "seconds": 0.5,
     "force_error": 3e-6, "area_error": 1e-5, "converged": True},
    {"solver": "fixed_point", "n_radial": 20, "radial_grid": "uniform", "tolerance": 1e-3, "seconds": 0.001,
     "force_error": 1e-1, "area_error": 2e-1, "converged": True},
]
CUBE = [
    {"method": "folded", "crop_tolerance": 1e-2, "precision": "float64", "seconds": 0.1, "simulations": 10,
     "resistance_error": 5e-4, "alpha_error": 1e-4, "gamma_error": 1e-4},
    {"method": "folded", "crop_tolerance": 1e-6, "precision": "float64", "seconds": 0.3, "simulations": 10,
     "resistance_error": 1e-7, "alpha_error": 1e-8, "gamma_error": 1e-8},
    {"method": "folded", "crop_tolerance": 0.0, "precision": "float32", "seconds": 0.01, "simulations": 10,
     "resistance_error": 1e-9, "alpha_error": 1e-9, "gamma_error": 1e-9},
]


def test_recommendation_is_the_fastest_setting_meeting_each_target() -> None:
    rec = frontier.recommend(CONTACT, CUBE, _ensemble([0.2, 0.09, 0.04, 0.02]))
    quick, paper, publication = (rec[u] for u in frontier.USES)
    assert quick["contact"] == "n_radial=120 tolerance=1e-07"  # the fixed point is fast but too far off
    assert quick["cube"] == "interaction_sum=folded crop_tolerance=0.01" and quick["n_realizations"] == 50
    assert paper["contact"] == "n_radial=720 tolerance=1e-10" and paper["force_error"] == 3e-6
    assert paper["cube"] == "interaction_sum=folded crop_tolerance=1e-06"  # float32 is not a stage setting
    assert paper["n_realizations"] == 100 and paper["interval_halfwidth"] == pytest.approx(0.04)
    assert quick["targets_met"] and paper["targets_met"]
    # nothing meets 1e-7 in force: the most accurate setting is shown and flagged
    assert publication["contact"] == "n_radial=720 tolerance=1e-10" and not publication["targets_met"]


def test_frontier_file_and_figures(tmp_path) -> None:
    path = frontier.write(CONTACT, CUBE, _ensemble([0.2, 0.1]), tmp_path / "bench" / "frontier.nc")
    with xr.open_dataset(path, decode_timedelta=False) as ds:
        assert ds.sizes["contact"] == 4 and ds.sizes["cube"] == 3
        np.testing.assert_array_equal(ds["contact_n_radial"].values, [20, 120, 720, 20])
        assert ds["contact_seconds"].attrs["units"] == "s"
        for name, var in ds.variables.items():
            assert "units" in var.attrs and "long_name" in var.attrs, name
        paths = frontier_plot.plot(ds.load(), tmp_path / "figures")
    assert [p.name for p in paths] == ["frontier_contact.png", "frontier_cube.png", "frontier_ensemble.png"]
    assert all(p.stat().st_size > 10_000 for p in paths)


def test_contact_sweep_errors_fall_with_nodes_and_tolerance(monkeypatch) -> None:
    monkeypatch.setattr(frontier_sweeps, "NODES", (20, 160))
    monkeypatch.setattr(frontier_sweeps, "TOLERANCES", (1e-3, 1e-10))
    monkeypatch.setattr(frontier_sweeps, "REPEATS", 1)
    scenario = load_scenario("paper_gt", {"contact.n_radial": 160, "loading.n_delta": 6})
    rows = {(r["solver"], r["n_radial"], r["tolerance"]): r for r in frontier_sweeps.contact_frontier(scenario)}
    fine, coarse = rows["newton", 160, 1e-10], rows["newton", 20, 1e-10]
    assert fine["force_error"] < coarse["force_error"] and fine["area_error"] < coarse["area_error"]
    assert fine["force_error"] < 1e-3  # 4x refinement of the same graded grid: close already
    assert rows["newton", 160, 1e-3]["force_error"] >= fine["force_error"]
    assert ("fixed_point", 20, 1e-3) in rows and ("fixed_point", 160, 1e-3) in rows
    assert all(r["seconds"] > 0 for r in rows.values())


def test_report_sections_show_the_frontier_and_the_stability_map(tmp_path) -> None:
    import json

    from g2tom.analysis.report_appendix import frontier_blocks, stability_blocks
    from g2tom.analysis.report_render import to_markdown
    from g2tom.bench import stability

    assert "Not available" in to_markdown(frontier_blocks(tmp_path) + stability_blocks(tmp_path))
    rec = frontier.recommend(CONTACT, CUBE, _ensemble([0.2, 0.09, 0.04, 0.02]))
    (tmp_path / "bench").mkdir()
    (tmp_path / "bench" / "frontier.json").write_text(json.dumps({"recommended": rec}))
    with xr.open_dataset(frontier.write(CONTACT, CUBE, _ensemble([0.2, 0.1]), tmp_path / "bench" / "frontier.nc"),
                         decode_timedelta=False) as ds:
        frontier_plot.plot(ds.load(), tmp_path / "figures")
    base = {"status": "converged", "message": "", "iterations": 7, "residual": 3e-11, "seconds": 0.1,
            "finite_nonnegative": True, "force_monotone": True, "resistance_falls": True,
            "hertz_ratio": 0.9, "roughness_parameter": 0.01, "open_circuits": 2}
    results = [
        (stability.Case("roughness.sigma", 1e-9, {}), base),
        (stability.Case("roughness.sigma", 1e-3, {}), {**base, "iterations": 12, "residual": 8e-11}),
        (stability.Case("oxide.lambda", "[200]", {}), {**base, "status": "refused", "residual": float("nan"),
                                                       "message": "oxide.lambda = 200 is out of range"}),
    ]
    stability.write_map(results, tmp_path / "bench" / "stability.nc")
    md = to_markdown(frontier_blocks(tmp_path) + stability_blocks(tmp_path))
    assert "## How fast, how accurate" in md and "## Stability map" in md
    for use in frontier.USES:
        assert f"| {use} |" in md
    assert "| quick look | n_radial=120 tolerance=1e-07 | 0.05 | 0.0004 | 0.0006 | interaction_sum=folded crop_tolerance=0.01 |" in md
    for stem in ("frontier_contact", "frontier_cube", "frontier_ensemble"):
        assert f"(figures/{stem}.png)" in md
    assert "3 parameter sets" in md and "2 converged" in md and "1 refused" in md and "4 open circuits" in md
    assert "| roughness.sigma | 1e-09, 0.001 | 2 | 0 | 12 | 8e-11 |" in md
    assert "oxide.lambda=[200]: oxide.lambda = 200 is out of range" in md
    assert "Hertz limit" not in md  # no hertz_limit case in this map


def test_cube_and_ensemble_sweeps_measure_real_errors(monkeypatch) -> None:
    monkeypatch.setattr(frontier_sweeps, "CUBE_REALIZATIONS", 6)
    monkeypatch.setattr(frontier_sweeps, "METHODS", ("folded",))
    monkeypatch.setattr(frontier_sweeps, "CROPS", (0.0, 1e-2))
    monkeypatch.setattr(frontier_sweeps, "REPEATS", 1)
    monkeypatch.setattr(frontier_sweeps, "ENSEMBLE_REALIZATIONS", 24)
    monkeypatch.setattr(frontier_sweeps, "ENSEMBLE_COUNTS", (6, 24, 400))
    scenario = resolve(load_scenario("paper_gt", {"contact.n_radial": 160, "loading.n_delta": 6}))
    rows = {(r["crop_tolerance"], r["precision"]): r for r in frontier_sweeps.cube_frontier(scenario)}
    assert rows[0.0, "float64"]["resistance_error"] < 1e-12  # exact algorithm against the dense sum
    assert 1e-8 < rows[1e-2, "float64"]["resistance_error"] <= 1e-2  # cropping error within its tolerance
    assert 0 < rows[0.0, "float32"]["resistance_error"] < 1e-6  # float32 spot maps: rounding only
    ens = frontier_sweeps.ensemble_frontier(scenario)
    assert list(ens["n_realizations"].values) == [6, 24]  # counts beyond the ensemble are dropped
    for name in ("alpha", "gamma"):
        width = ens[f"{name}_halfwidth"]
        assert (width > 0).all() and float(width.isel(n_realizations=1).mean()) < float(width.isel(n_realizations=0).mean())
    assert ens["ensemble_seconds"].values[1] > ens["ensemble_seconds"].values[0]
