"""The adaptive ensemble: the fast stopping rule against slow references, and a deterministic cube."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
import xarray as xr

from g2tom.compute import ComputeOptions
from g2tom.config import ResolvedScenario
from g2tom.fitting import ensemble
from g2tom.fitting.powerlaw import fit_power_law
from g2tom.scene import FieldSource
from g2tom.stages import contact as contact_stage
from g2tom.stages import cube, cube_rounds, fits
from g2tom.stages import oxide as oxide_stage

OPTIONS = ComputeOptions(progress=False)


def test_log_alpha_and_gamma_are_means_of_the_per_realization_statistic() -> None:
    rng = np.random.default_rng(3)
    x = np.geomspace(2.0, 90.0, 7)
    log_r = np.log(1.7 * x[:, None] ** -0.4) + 0.5 * rng.standard_normal((7, 300))
    c_alpha, c_gamma = ensemble.fit_weights(np.log(x))
    fit = fit_power_law(x, np.exp(log_r.mean(axis=1)))  # the geometric-mean fit
    assert np.mean(ensemble.statistic(log_r, c_alpha)) == pytest.approx(np.log(fit.alpha), abs=1e-12)
    assert np.mean(ensemble.statistic(log_r, c_gamma)) == pytest.approx(fit.gamma, abs=1e-12)


def test_prefix_half_width_is_the_standard_error_of_every_prefix() -> None:
    rng = np.random.default_rng(4)
    t = 5.0 + rng.standard_normal((2, 60))
    t[1, [3, 17]] = np.nan  # open circuits are skipped
    out = ensemble.prefix_half_width(t, 1.96)
    for n in (2, 5, 18, 60):
        for row in range(2):
            sample = t[row, :n][np.isfinite(t[row, :n])]
            expected = 1.96 * sample.std(ddof=1) / np.sqrt(sample.size)
            assert out[row, n - 1] == pytest.approx(expected, rel=1e-10)
    assert np.isnan(out[:, 0]).all()


def test_stop_count_is_the_first_prefix_where_every_row_meets_the_target() -> None:
    hw = np.array([[0.5, 0.3, 0.1, 0.05, 0.2, 0.01], [0.5, 0.04, 0.3, 0.04, 0.01, 0.01]])
    assert ensemble.stop_count(hw, 0.06, 1) == 4
    assert ensemble.stop_count(hw, 0.06, 5) == 6
    assert ensemble.stop_count(hw, 0.001, 1) is None


def test_z_value_is_1_96_at_95_percent() -> None:
    assert ensemble.z_value(0.95) == pytest.approx(1.959964, abs=1e-6)


# ------------------------------------------------------------------ the adaptive cube
def _adaptive(small: ResolvedScenario, **changes) -> ResolvedScenario:
    ox = dict(ensemble="adaptive", min_realizations=12, max_realizations=60,
              target_half_width=0.03, lambda_=[1.0, 13.0], xi=[0.3, 0.8], period="spectral",
              spectral_resolution=6.0)
    ox.update(changes)
    return dataclasses.replace(small, oxide=dataclasses.replace(small.oxide, **ox),
                               compute=dataclasses.replace(small.compute, oxide_batch=7))


@pytest.fixture(scope="module")
def adaptive_inputs(small: ResolvedScenario) -> tuple[ResolvedScenario, xr.Dataset, xr.Dataset]:
    scenario = _adaptive(small)
    return scenario, contact_stage.build(scenario), oxide_stage.build(scenario)


@pytest.fixture(scope="module")
def adaptive_cube(adaptive_inputs) -> xr.Dataset:
    scenario, contact, oxide = adaptive_inputs
    return cube.build(scenario, contact, oxide, OPTIONS)


def test_adaptive_counts_stop_where_the_interval_is_reached(adaptive_inputs, adaptive_cube) -> None:
    scenario, _, _ = adaptive_inputs
    ox = scenario.oxide
    counts = adaptive_cube["n_realizations"].transpose("xi", "lambda").values
    assert counts.min() >= ox.min_realizations and counts.max() <= ox.max_realizations
    assert len(set(counts.ravel().tolist())) > 2  # cells really differ in how many fields they need
    rule = cube_rounds.stopping_rule(scenario, adaptive_cube["force"].values, adaptive_cube["force_normalized"].values)
    for (z, a), n in np.ndenumerate(counts):
        resistance = adaptive_cube["resistance"].isel(xi=[z], **{"lambda": a}).values
        assert np.isnan(resistance[..., n:]).all() and not np.isnan(resistance[..., :n]).any()
        alpha, _ = cube_rounds.half_widths(resistance[..., :n], rule)
        if n < ox.max_realizations:
            assert alpha[0, n - 1] <= cube_rounds.RULE_MARGIN * ox.target_half_width
        if n > ox.min_realizations:  # no earlier prefix reached it
            assert np.all(alpha[0, ox.min_realizations - 1 : n - 1] > cube_rounds.RULE_MARGIN * ox.target_half_width)


@pytest.mark.parametrize(
    ("batch", "chunk", "workers"),
    # the two-worker cluster (12 s) under make stress: tests/test_compute.py's cluster cube stays in make test
    [(1, 25, None), (13, 5, None), pytest.param(40, 3, 2, marks=pytest.mark.stress)]
)
def test_adaptive_cube_does_not_depend_on_batch_chunk_or_workers(
    adaptive_inputs, adaptive_cube, batch: int, chunk: int, workers: int | None
) -> None:
    scenario, contact, oxide = adaptive_inputs
    if workers:
        pytest.importorskip("distributed")
    other = dataclasses.replace(
        scenario,
        compute=dataclasses.replace(scenario.compute, oxide_batch=batch, cube_chunk=chunk),
    )
    ds = cube.build(other, contact, oxide, ComputeOptions(workers=workers, progress=False))
    np.testing.assert_array_equal(ds["n_realizations"], adaptive_cube["n_realizations"])
    if workers:  # worker processes may round a multi-threaded GEMM differently (see test_cube_stage)
        np.testing.assert_allclose(ds["resistance"], adaptive_cube["resistance"], rtol=1e-14)
    else:
        np.testing.assert_array_equal(ds["resistance"], adaptive_cube["resistance"])


def test_regenerated_fields_are_the_recorded_ones(adaptive_inputs) -> None:
    scenario, _, oxide = adaptive_inputs
    source = FieldSource.of(scenario)
    for a in range(len(scenario.oxide.lambda_)):
        psi, threshold = source.fields(a, np.arange(scenario.oxide.min_realizations))
        np.testing.assert_array_equal(psi, oxide["psi"].values[a])
        np.testing.assert_array_equal(threshold, oxide["threshold"].values[:, a])


def test_fits_use_each_lambdas_realizations_and_flag_the_cap(adaptive_inputs, adaptive_cube) -> None:
    scenario, _, _ = adaptive_inputs
    ds = fits.build(scenario, adaptive_cube)
    counts = adaptive_cube["n_realizations"].transpose("xi", "lambda").values
    np.testing.assert_array_equal(ds["n_realizations"].transpose("xi", "lambda").values, counts)
    compared = 0
    for (z, a), n in np.ndenumerate(counts):  # each cell's reduction equals that of its slice alone
        cell = {"xi": [z], "lambda": [a]}
        alone = fits.build(scenario, adaptive_cube.isel({**cell, "realization": slice(0, int(n))}).drop_vars("n_realizations"))
        np.testing.assert_allclose(ds["alpha"].isel(cell), alone["alpha"], rtol=1e-12)
        np.testing.assert_allclose(ds["resistance_quantile"].isel(cell), alone["resistance_quantile"], rtol=1e-12)
        if ds["curve_within"].isel(cell).item() == 1 == alone["curve_within"].item():  # no interval used
            np.testing.assert_allclose(ds["curve_coefficients"].isel(cell), alone["curve_coefficients"], atol=1e-12)
            compared += 1
    assert compared >= 1
    fitted = ds["fitted"].values.astype(bool)
    band = ds["geometric_mean_normalized_ci"].transpose("xi", "lambda", "delta", "bound").values[:, :, fitted]
    mean = ds["geometric_mean_normalized"].transpose("xi", "lambda", "delta").values[:, :, fitted]
    assert np.all(band[..., 0] < mean) and np.all(mean < band[..., 1])  # each cell's own resamples
    at_cap = counts >= scenario.oxide.max_realizations
    short = (adaptive_cube["rule_alpha_half_width"].transpose("xi", "lambda").values
             > cube_rounds.RULE_MARGIN * scenario.oxide.target_half_width)
    np.testing.assert_array_equal(ds["flagged"].transpose("xi", "lambda").values, (at_cap & short).astype(np.int8))
    assert np.all(ds["alpha_half_width"] > 0) and np.all(ds["gamma_half_width"] > 0)
    # the bootstrap confirms the fast rule's half-widths (both estimate the same standard error)
    ratio = ds["alpha_half_width"] / ds["rule_alpha_half_width"]
    assert float(ratio.min()) > 0.6 and float(ratio.max()) < 1.6


def test_doubling_the_spectral_resolution_stays_within_the_intervals(small: ResolvedScenario) -> None:
    """A small case: resolution 6 against 12 at lambda 3 and 13 (the bench does the full grid)."""
    from g2tom.bench import convergence

    scenario = _adaptive(small, lambda_=[3.0, 13.0], xi=[0.5], min_realizations=150, max_realizations=150,
                         target_half_width=0.5)
    con = contact_stage.build(scenario)
    runs = []
    for resolution in (6.0, 12.0):
        variant = dataclasses.replace(scenario, oxide=dataclasses.replace(scenario.oxide, spectral_resolution=resolution))
        runs.append(convergence.fit_at(variant, con, OPTIONS)[0])
    result = convergence.compare(*runs)
    assert result["cells"] == 2
    assert result["alpha_cells_over_combined"] == 0 and result["gamma_cells_over_combined"] == 0
    assert all(r["alpha_change"] > 0 for r in result["rows"])  # really different fields
