"""Stage 4: reductions over realizations and power-law fits on synthetic cubes."""

from __future__ import annotations

import json

import numpy as np
import pytest
import xarray as xr
from scipy import stats

from g2tom.reductions import (
    geometric_mean,
    open_probability,
    quantiles,
    reduce_realizations,
)
from g2tom.cli.main import main
from g2tom.config import ConfigError, ResolvedScenario, Scenario
from g2tom.before_work import load_scenario
from g2tom.stages import fits
from g2tom.store import read_stage, write_dataset
from tests.conftest import SMALL_OVERRIDES


def cli_overrides(scenario: Scenario) -> list[str]:
    """``--set`` arguments that turn the CLI's default scenario (``paper``) into ``scenario``."""
    base = load_scenario("paper").flat()
    args: list[str] = []
    for key, value in scenario.flat().items():
        if value != base[key]:
            args += ["--set", f"{key}={json.dumps(value)}"]
    return args


def true_alpha(lam: np.ndarray, xi: np.ndarray) -> np.ndarray:
    """A separable rank-2 alpha(lambda, xi), polynomial in w = log lambda and z = -log(1-xi)."""
    w, z = np.log(lam)[:, None], -np.log1p(-xi)[None, :]
    return 1.0 + 0.3 * z + 0.1 * z**2 + 0.05 * w * z


def true_gamma(lam: np.ndarray, xi: np.ndarray) -> np.ndarray:
    w, z = np.log(lam)[:, None], -np.log1p(-xi)[None, :]
    return 0.23 + 0.1 * z + 0.02 * w * z


def synthetic_cube(
    scenario: Scenario, noise: float = 0.3, open_share: float = 0.0, seed: int = 1
) -> xr.Dataset:
    """A cube with R' = alpha F'^-gamma times log-normal noise per realization and step.

    ``open_share`` of the realizations (the same ones at every step) are open circuits.
    """
    rng = np.random.default_rng(seed)
    xi = np.asarray(scenario.oxide.xi)
    lam = np.asarray(scenario.oxide.lambda_)
    n_real = scenario.oxide.n_realizations
    force = np.geomspace(20.0, 5000.0, scenario.loading.n_delta)
    force_n = force / scenario.force_scale
    alpha = true_alpha(lam, xi).T  # (xi, lambda)
    gamma = true_gamma(lam, xi).T
    clean = 0.8 * force_n**-0.23
    log_noise = noise * rng.standard_normal((xi.size, lam.size, force.size, n_real))
    r_norm = alpha[..., None, None] * force_n[:, None] ** -gamma[..., None, None] * np.exp(log_noise)
    resistance = r_norm * scenario.resistance_scale
    n_open = int(round(open_share * n_real))
    resistance[..., :n_open] = np.inf
    dims = ("xi", "lambda", "delta", "realization")
    ds = xr.Dataset(
        {
            "resistance": (dims, resistance),
            "n_open": (dims[:3], np.full(resistance.shape[:3], n_open)),
            "resistance_clean": ("delta", clean * scenario.resistance_scale),
        },
        coords={
            "xi": xi,
            "lambda": lam,
            "delta": np.asarray(scenario.deltas),
            "realization": np.arange(n_real),
            "force": ("delta", force),
            "force_normalized": ("delta", force_n),
        },
    )
    return ds


def test_known_power_law_within_intervals(small: ResolvedScenario) -> None:
    cube = synthetic_cube(small, noise=0.15)
    ds = fits.build(small, cube)
    lam, xi = np.asarray(small.oxide.lambda_), np.asarray(small.oxide.xi)
    a_true = true_alpha(lam, xi).T
    g_true = true_gamma(lam, xi).T
    a_ci, g_ci = ds["alpha_ci"].values, ds["gamma_ci"].values
    inside_a = (a_ci[..., 0] <= a_true) & (a_true <= a_ci[..., 1])
    inside_g = (g_ci[..., 0] <= g_true) & (g_true <= g_ci[..., 1])
    # 95 % intervals: nearly all of the 9 cells must cover the truth
    assert inside_a.mean() >= 0.75 and inside_g.mean() >= 0.75
    np.testing.assert_allclose(ds["alpha"], a_true, rtol=0.15)
    np.testing.assert_allclose(ds["gamma"], g_true, atol=0.05)
    assert float(ds["gamma_clean"]) == pytest.approx(0.23, abs=1e-9)
    assert float(ds["alpha_clean"]) == pytest.approx(0.8, rel=1e-9)


def test_noise_free_fit_is_exact(small: ResolvedScenario) -> None:
    ds = fits.build(small, synthetic_cube(small, noise=0.0))
    lam, xi = np.asarray(small.oxide.lambda_), np.asarray(small.oxide.xi)
    np.testing.assert_allclose(ds["alpha"], true_alpha(lam, xi).T, rtol=1e-9)
    np.testing.assert_allclose(ds["gamma"], true_gamma(lam, xi).T, rtol=1e-9)
    assert float(ds["fit_residual_rms"].max()) < 1e-9
    assert ds["fitted"].values.tolist() == (ds["force"] >= 200.0).values.astype(int).tolist()


def test_geometric_mean_ignores_open_circuits() -> None:
    r = xr.DataArray([[1.0, 4.0, np.inf, 16.0]], dims=("delta", "realization"))
    assert float(geometric_mean(r)[0]) == pytest.approx(4.0)
    assert float(open_probability(r)[0]) == pytest.approx(0.25)
    all_open = xr.DataArray([[np.inf, np.inf]], dims=("delta", "realization"))
    assert np.isnan(float(geometric_mean(all_open)[0]))
    assert float(open_probability(all_open)[0]) == 1.0


def test_quantiles_treat_open_circuits_as_infinite() -> None:
    values = np.array([1.0, 2.0, 3.0, 4.0, np.inf])
    r = xr.DataArray(values[None, :], dims=("delta", "realization"))
    q = quantiles(r, (0.16, 0.5, 0.84, 0.75)).values[0]
    np.testing.assert_allclose(q[:2], np.quantile(values[:4].tolist() + [1e300], [0.16, 0.5]))
    assert q[2] == np.inf and q[3] == 4.0


def test_reductions_over_each_points_own_count_equal_those_of_its_slice() -> None:
    """An adaptive ensemble's cells each reduce over their own first realizations (one kernel call per
    distinct count): every point equals the reductions of its own slice, open circuits and all-open included."""
    rng = np.random.default_rng(3)
    values = rng.lognormal(0.0, 1.0, size=(3, 4, 5, 40))
    values[rng.random(values.shape) < 0.2] = np.inf
    values[0, 0, 0, :7] = np.inf
    r = xr.DataArray(values, dims=("xi", "lambda", "delta", "realization"),
                     coords={"xi": [0.1, 0.5, 0.9], "force": ("delta", np.arange(5.0))})
    counts = rng.integers(1, 41, size=(3, 4, 5))
    counts[0, 0, 0] = 7
    fast = reduce_realizations(r, 2.0, counts=counts)
    assert set(fast.coords) == {"xi", "force", "quantile"} and fast["resistance_quantile"].dims[-1] == "quantile"
    for index in np.ndindex(counts.shape):
        one = reduce_realizations(r[index].isel(realization=slice(0, int(counts[index]))), 2.0)
        for name in one.data_vars:
            np.testing.assert_allclose(fast[name].values[index], one[name].values, rtol=1e-15, err_msg=name)
    assert np.isnan(fast["geometric_mean"].values[0, 0, 0]) and fast["open_probability"].values[0, 0, 0] == 1.0


def test_reductions_are_dask_friendly(small: ResolvedScenario) -> None:
    cube = synthetic_cube(small, open_share=0.25)
    eager = reduce_realizations(cube["resistance"], 2.0)
    lazy = reduce_realizations(cube["resistance"].chunk({"realization": 3, "xi": 1}), 2.0)
    assert lazy["resistance_quantile"].chunks is not None
    xr.testing.assert_allclose(eager, lazy.compute())
    np.testing.assert_allclose(eager["open_probability"], 0.25)


def test_open_share_reported_and_mean_unbiased(small: ResolvedScenario) -> None:
    ds = fits.build(small, synthetic_cube(small, noise=0.0, open_share=0.25))
    np.testing.assert_allclose(ds["open_probability"], 0.25)
    lam, xi = np.asarray(small.oxide.lambda_), np.asarray(small.oxide.xi)
    np.testing.assert_allclose(ds["alpha"], true_alpha(lam, xi).T, rtol=1e-9)


@pytest.mark.parametrize("reduction", ["arithmetic_mean", "median"])
def test_other_reductions(small: ResolvedScenario, reduction: str) -> None:
    scenario = load_scenario("paper_gt", {**SMALL_OVERRIDES, "fits.reduction": reduction})
    ds = fits.build(scenario, synthetic_cube(scenario, noise=0.05))
    lam, xi = np.asarray(scenario.oxide.lambda_), np.asarray(scenario.oxide.xi)
    np.testing.assert_allclose(ds["gamma"], true_gamma(lam, xi).T, atol=0.03)
    assert np.all(ds["alpha_ci"].sel(bound="lower") <= ds["alpha_ci"].sel(bound="upper"))


def test_too_few_fitted_steps_is_a_config_error(small: ResolvedScenario) -> None:
    scenario = load_scenario("paper_gt", {**SMALL_OVERRIDES, "fits.fit_range": "force", "fits.min_force": 1e6})
    with pytest.raises(ConfigError, match="fits.min_force"):
        fits.build(scenario, synthetic_cube(scenario))


def test_stage_run_writes_fits(tmp_path, small: ResolvedScenario) -> None:
    write_dataset(synthetic_cube(small), tmp_path, "cube", small)
    args = ["fits", "--data-dir", str(tmp_path), "--no-progress"]
    assert main(args + cli_overrides(small)) == 0
    ds = read_stage(tmp_path, "fits", small)
    for name in ("alpha", "gamma", "alpha_ci", "gamma_ci", "geometric_mean", "resistance_quantile",
                 "open_probability", "alpha_clean", "gamma_clean", "fitted", "fit_residual_rms"):
        assert name in ds
    assert ds["alpha_ci"].dims == ("xi", "lambda", "bound")
    assert "force_normalized" in ds.coords


def assert_labelled(ds: xr.Dataset) -> None:
    """Every numeric variable and coordinate carries units and a long name."""
    for name, var in ds.variables.items():
        if var.dtype.kind in "OSU":
            continue
        assert var.attrs.get("units") is not None, f"{name} has no units"
        assert var.attrs.get("long_name"), f"{name} has no long_name"


def test_outputs_are_labelled(small: ResolvedScenario) -> None:
    assert_labelled(fits.build(small, synthetic_cube(small)))


def test_bootstrap_redraws_realizations_jointly_across_steps(small: ResolvedScenario) -> None:
    # Each realization is the exact power law times its own factor, the same at every step:
    # a resample that keeps whole realizations changes alpha but never gamma. Redrawing the
    # realizations independently at each step would scatter gamma.
    cube = synthetic_cube(small, noise=0.0)
    factor = np.exp(0.5 * np.random.default_rng(5).standard_normal(cube.sizes["realization"]))
    cube["resistance"] = cube["resistance"] * xr.DataArray(factor, dims="realization")
    ds = fits.build(small, cube)
    g_ci, a_ci = ds["gamma_ci"].values, ds["alpha_ci"].values
    np.testing.assert_allclose(g_ci[..., 0], g_ci[..., 1], rtol=1e-9)
    assert np.all(a_ci[..., 1] > 1.05 * a_ci[..., 0])


@pytest.mark.parametrize("open_step", [False, True])
def test_clean_interval_is_the_least_squares_one(open_step: bool) -> None:
    scenario = load_scenario("paper_gt", {**SMALL_OVERRIDES, "loading.n_delta": 10})
    cube = synthetic_cube(scenario, noise=0.0)
    wiggle = np.exp(0.05 * np.random.default_rng(2).standard_normal(cube.sizes["delta"]))
    if open_step:  # a non-finite clean value on a fitted step must not count as a point
        wiggle[-1] = np.inf
    cube["resistance_clean"] = cube["resistance_clean"] * xr.DataArray(wiggle, dims="delta")
    ds = fits.build(scenario, cube)
    use = ds["fitted"].values.astype(bool) & np.isfinite(ds["resistance_clean"].values)
    lx = np.log(ds["force_normalized"].values[use])
    ly = np.log(ds["resistance_clean_normalized"].values[use])
    ref = stats.linregress(lx, ly)
    t = stats.t.ppf(0.975, lx.size - 2)
    np.testing.assert_allclose(ds["gamma_clean"], -ref.slope, rtol=1e-12)
    np.testing.assert_allclose(ds["gamma_clean_ci"], [-ref.slope - t * ref.stderr, -ref.slope + t * ref.stderr], rtol=1e-9)
    np.testing.assert_allclose(
        np.log(ds["alpha_clean_ci"]), [ref.intercept - t * ref.intercept_stderr, ref.intercept + t * ref.intercept_stderr],
        rtol=1e-9,
    )


def test_clean_interval_undefined_on_two_steps() -> None:
    scenario = load_scenario("paper_gt", {**SMALL_OVERRIDES, "fits.fit_range": "force", "fits.min_force": 1000.0})
    ds = fits.build(scenario, synthetic_cube(scenario, noise=0.0))
    assert int(ds["fitted"].sum()) == 2
    assert np.all(np.isnan(ds["gamma_clean_ci"])) and np.all(np.isnan(ds["alpha_clean_ci"]))
