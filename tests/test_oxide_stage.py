"""Stage 2 (g2tom.stages.oxide): layout, reproducibility, realized fractions, CLI errors."""

from __future__ import annotations

import dataclasses
import os
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from g2tom.analysis import figures_oxide
from g2tom import store
from g2tom.cli import main as cli
from g2tom.bench import oxide as bench_oxide
from g2tom.compute import ComputeOptions
from g2tom.config import ConfigError, ResolvedScenario
from g2tom.before_work import load_scenario
from g2tom.before_work.domains import resolve
from g2tom.physics import oxide_band, oxide_field
from g2tom.physics.grid import cell_centres
from g2tom.scene import FieldSource, bands
from g2tom.stages import oxide


def _with(scenario: ResolvedScenario, **changes) -> ResolvedScenario:
    compute = {k: changes.pop(k) for k in ("oxide_chunk",) if k in changes}
    return dataclasses.replace(scenario, oxide=dataclasses.replace(scenario.oxide, **changes),
                               compute=dataclasses.replace(scenario.compute, **compute))


@pytest.fixture(scope="module")
def built(small: ResolvedScenario) -> xr.Dataset:
    return oxide.build(small)


def test_layout_units_and_grid(small: ResolvedScenario, built: xr.Dataset) -> None:
    ox, n = small.oxide, small.n_cells
    assert built["psi"].dims == ("lambda", "realization", "y", "x")
    assert built["psi"].dtype == np.float32
    assert built["psi"].shape == (len(ox.lambda_), ox.n_realizations, n, n)
    for name in ("threshold", "oxide_fraction"):
        assert built[name].dims == ("xi", "lambda", "realization")
    assert built["threshold"].dtype == np.float32
    np.testing.assert_array_equal(built["x"], cell_centres(n, small.cell_size))
    np.testing.assert_array_equal(built["y"], built["x"])
    np.testing.assert_array_equal(built["lambda"], ox.lambda_)
    np.testing.assert_array_equal(built["realization"], np.arange(ox.n_realizations))
    assert built["lambda"].attrs == {
        "units": "1", "long_name": "normalized oxide correlation length l_O sqrt(eta)"
    }
    assert built["xi"].attrs["units"] == "1" and built["x"].attrs["units"] == "m"
    assert np.all(np.isfinite(built["psi"]))


def test_theoretical_thresholds_and_fractions_follow_the_rule(built: xr.Dataset) -> None:
    expected = np.float32(oxide_field.theoretical_threshold(built["xi"].values))
    np.testing.assert_array_equal(built["threshold"].values, np.broadcast_to(
        expected[:, None, None], built["threshold"].shape))
    covered = (built["psi"] >= built["threshold"]).mean(("y", "x"))
    np.testing.assert_array_equal(built["oxide_fraction"], covered.transpose(*built["oxide_fraction"].dims))


def test_stage_fields_are_the_physics_fields(small: ResolvedScenario, built: xr.Dataset) -> None:
    ox = small.oxide
    lam, r = ox.lambda_[0], 5
    modes = oxide_band.band(small.n_cells, small.cell_size, lam, ox.ks_ratio, ox.hurst)
    coeffs = oxide_band.coefficients(modes, oxide_band.field_stream(ox.seed, lam, r), ox.amplitudes)
    direct = oxide_field.field_at_points(modes, coeffs, built["x"].values[None, :], built["y"].values[:, None])
    np.testing.assert_allclose(built["psi"].sel({"lambda": lam, "realization": r}), direct, atol=2e-6, rtol=0)


@pytest.mark.parametrize("chunk", [1, 8])
def test_psi_does_not_depend_on_chunking(small: ResolvedScenario, built: xr.Dataset, chunk: int) -> None:
    other = oxide.build(_with(small, oxide_chunk=chunk))
    assert small.compute.oxide_chunk == 3
    np.testing.assert_array_equal(other["psi"], built["psi"])
    np.testing.assert_array_equal(other["oxide_fraction"], built["oxide_fraction"])


@pytest.mark.parametrize("processes", [False, True], ids=["1-thread", "2-distributed-workers"])
def test_psi_does_not_depend_on_workers(small: ResolvedScenario, built: xr.Dataset, processes: bool,
                                        request: pytest.FixtureRequest) -> None:
    # `built` used the threaded scheduler with one thread per core; the other: one thread, or
    # conftest's cluster of two worker processes
    options = (ComputeOptions(scheduler=request.getfixturevalue("cluster_address"), progress=False) if processes
               else ComputeOptions(workers=1, progress=False))
    np.testing.assert_array_equal(oxide.build(small, options)["psi"], built["psi"])


def test_adding_a_lambda_leaves_the_other_fields_unchanged(small: ResolvedScenario, built: xr.Dataset) -> None:
    other = oxide.build(_with(small, lambda_=[2.0, 5.0]))
    np.testing.assert_array_equal(other["psi"].sel({"lambda": 5.0}), built["psi"].sel({"lambda": 5.0}))


def test_mean_realized_fraction_is_xi_within_its_standard_error(small: ResolvedScenario) -> None:
    scenario = _with(small, lambda_=[1.0, 3.0, 7.0], xi=[0.1, 0.3, 0.5, 0.9], n_realizations=150, oxide_chunk=50)
    fraction = oxide.build(scenario)["oxide_fraction"]
    mean = fraction.mean("realization")
    standard_error = fraction.std("realization", ddof=1) / np.sqrt(fraction.sizes["realization"])
    z = (mean - fraction["xi"]) / standard_error
    assert float(np.abs(z).max()) < 4.0, z.values


@pytest.mark.parametrize("amplitudes", ["ideal", "rayleigh"])
def test_empirical_rule_hits_xi_exactly(small: ResolvedScenario, amplitudes: str) -> None:
    scenario = _with(small, threshold="empirical", amplitudes=amplitudes, xi=[0.1, 0.25, 0.5, 0.8])
    ds = oxide.build(scenario)
    cells = small.n_cells**2
    target = np.rint(ds["xi"].values * cells) / cells
    np.testing.assert_array_equal(ds["oxide_fraction"], np.broadcast_to(target[:, None, None], ds["oxide_fraction"].shape))
    covered = (ds["psi"] >= ds["threshold"]).mean(("y", "x")).transpose(*ds["oxide_fraction"].dims)
    np.testing.assert_array_equal(covered, ds["oxide_fraction"])
    assert float(ds["threshold"].std("realization").min()) > 0  # each field has its own threshold


def test_run_writes_oxide_nc_with_provenance(small: ResolvedScenario, built: xr.Dataset, tmp_path: Path) -> None:
    path = oxide.run(small, tmp_path, ComputeOptions(progress=False))
    assert path == tmp_path / "oxide.nc"
    ds = store.read_stage(tmp_path, "oxide", small)
    assert ds["psi"].dtype == np.float32 and ds["threshold"].dtype == np.float32
    np.testing.assert_array_equal(ds["psi"], built["psi"])
    masks = ds["psi"] >= ds["threshold"]
    np.testing.assert_array_equal(masks.mean(("y", "x")).transpose(*ds["oxide_fraction"].dims), ds["oxide_fraction"])
    assert ds.attrs["config_hash"] == small.config_hash("oxide")
    assert ds["lambda"].attrs["units"] == "1"


@pytest.mark.parametrize(
    ("override", "name"),
    [
        ("oxide.hurst=1.5", "oxide.hurst"),
        ("oxide.hurst=0.0", "oxide.hurst"),
        ("oxide.xi=[0.5, 1.0]", "oxide.xi"),
        ("oxide.xi=[0.0, 0.5]", "oxide.xi"),
        ("oxide.lambda=[-1.0, 2.0]", "oxide.lambda"),
        ("oxide.lambda=[0.0]", "oxide.lambda"),
        ("oxide.ks_ratio=1.0", "oxide.ks_ratio"),
        ("oxide.n_realizations=1", "oxide.n_realizations"),
        ("oxide.amplitudes=gaussian", "oxide.amplitudes"),
        ("oxide.threshold=median", "oxide.threshold"),
        ("oxide.period=window;oxide.lambda=[500.0]", "oxide.lambda"),
        ("oxide.target_half_width=0.0", "oxide.target_half_width"),
        ("oxide.target_half_width=1.0", "oxide.target_half_width"),
        ("oxide.min_realizations=300;oxide.max_realizations=200", "oxide.max_realizations"),
        ("oxide.spectral_resolution=1e5", "oxide.spectral_resolution"),
    ],
)
def test_cli_rejects_bad_oxide_parameters(
    override: str, name: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    existing = tmp_path / "oxide.nc"
    existing.write_bytes(b"previous oxide.nc")
    os.utime(existing, (1_000_000_000, 1_000_000_000))
    sets = [a for o in override.split(";") for a in ("--set", o)]
    assert cli.main(["oxide", *sets, "--data-dir", str(tmp_path), "--no-progress"]) == 2
    assert name in capsys.readouterr().err
    assert existing.read_bytes() == b"previous oxide.nc"
    assert existing.stat().st_mtime == 1_000_000_000
    assert sorted(p.name for p in tmp_path.iterdir()) == ["oxide.nc"]


def test_window_smaller_than_correlation_length_warns_with_mode_count() -> None:
    lam = 60.0  # l_O = 60 cells > the 57-cell window
    with pytest.warns(UserWarning, match=r"oxide.lambda = 60.*only (\d+) independent Fourier modes") as record:
        scenario = resolve(load_scenario("paper_gt", {"oxide.lambda": [5.0, lam], "oxide.period": "window"}))
    modes = oxide_band.band(scenario.n_cells, scenario.cell_size, lam, 3.0, 0.5)
    assert f"only {modes.size} independent" in str(record[0].message)


def test_window_without_modes_is_an_error() -> None:
    with pytest.raises(ConfigError, match="oxide.lambda"):
        resolve(load_scenario("paper_gt", {"oxide.lambda": [500.0], "oxide.period": "window"}))


def test_spectral_period_has_modes_at_any_lambda() -> None:
    scenario = resolve(load_scenario("paper_gt", {"oxide.lambda": [500.0], "oxide.spectral_resolution": 4.0}))
    assert bands(scenario)[0].size > 100


def test_adaptive_record_is_the_first_batch_and_cube_regenerates_it(small: ResolvedScenario) -> None:
    scenario = dataclasses.replace(
        small, compute=dataclasses.replace(small.compute, oxide_chunk=2),
        oxide=dataclasses.replace(small.oxide, ensemble="adaptive", min_realizations=5,
                                         period="spectral", threshold="empirical")
    )
    record = oxide.build(scenario)
    assert record.sizes["realization"] == 5
    source = FieldSource.of(scenario)
    for a in range(len(scenario.oxide.lambda_)):
        psi, threshold = source.fields(a, np.arange(2, 5))
        np.testing.assert_array_equal(psi, record["psi"].values[a, 2:5])
        np.testing.assert_array_equal(threshold, record["threshold"].values[:, a, 2:5])
    assert record["period_cells"].values.tolist() == [
        oxide_band.spectral_period(scenario.n_cells, lam, 16.0) for lam in scenario.oxide.lambda_
    ]


def test_figure_is_written(small: ResolvedScenario, tmp_path: Path) -> None:
    paths = figures_oxide.write(small, tmp_path, tmp_path)
    assert [p.name for p in paths] == ["fig6_oxide.png"]
    assert paths[0].stat().st_size > 10_000


def test_bench_reports_ratio_and_error(small: ResolvedScenario, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(bench_oxide, "REPEATS", 1)
    monkeypatch.setattr(bench_oxide, "PER_LAMBDA_FIELDS", 3)
    for period in ("window", "spectral"):
        result = bench_oxide.run(_with(small, lambda_=[1.0, 5.0], n_realizations=4, period=period))
        assert result["direct_subset_max_abs_error"] < 1e-5  # float32 rounding of unit-variance values
        # a ratio, not a timed claim: on this tiny scene the stage's fixed costs may outweigh the sums
        assert result["speedup_per_field"] == pytest.approx(result["direct_per_field_seconds"] / result["per_field_seconds"])
        assert np.isfinite(result["speedup_per_field"]) and result["speedup_per_field"] > 0
        assert [row["lambda"] for row in result["per_lambda"]] == [1.0, 5.0]
