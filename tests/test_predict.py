"""The predictor of Eq. 27: API, band components, surrogate.json and `g2tom predict`."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest
import xarray as xr
from numpy.polynomial import polynomial as P

from g2tom.cli.main import main
from g2tom.config import ConfigError, ResolvedScenario
from g2tom.before_work import load_scenario
from g2tom.before_work.domains import resolve
from g2tom.fitting.surrogate import evaluate
from g2tom.predict.predictor import ExtrapolationWarning, SurrogateErrorWarning, load_surrogate, predict
from g2tom.stages import fits, surrogate
from g2tom.store import write_dataset
from tests.conftest import SMALL_OVERRIDES
from tests.test_fits_stage import cli_overrides, synthetic_cube


def _build(small: ResolvedScenario, **kwargs) -> xr.Dataset:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)  # orders reduced on the 3 x 3 grid
        return surrogate.build(small, fits.build(small, synthetic_cube(small, **kwargs)))


@pytest.fixture(scope="module")
def surrogate_ds(small: ResolvedScenario) -> xr.Dataset:
    return _build(small, noise=0.2)


@pytest.fixture(scope="module")
def data_dir(tmp_path_factory, small: ResolvedScenario):
    """fits.nc written, then the surrogate stage run: surrogate.nc and surrogate.json."""
    path = tmp_path_factory.mktemp("predict")
    write_dataset(fits.build(small, synthetic_cube(small, noise=0.2)), path, "fits", small)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        surrogate.run(small, path, None)
    return path


def _quiet(*args, **kwargs) -> xr.Dataset:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", SurrogateErrorWarning)
        return predict(*args, **kwargs)


def test_equals_eq27_by_hand(small: ResolvedScenario, surrogate_ds: xr.Dataset) -> None:
    force, xi, lam = 1500.0, 0.4, 4.0
    m, r, s = small.material, small.indenter.radius, small.roughness.sigma
    e_star = m.E / (2 * (1 - m.nu**2))
    coef = {p: (surrogate_ds[f"{p}_coef_w"].values, surrogate_ds[f"{p}_coef_z"].values,
                surrogate_ds[f"{p}_coef_w"].attrs["transform"]) for p in ("alpha", "gamma")}
    assert coef["alpha"][2] == "log"
    alpha = float(np.exp(evaluate(coef["alpha"][0], coef["alpha"][1], lam, xi)))
    gamma = float(evaluate(*coef["gamma"][:2], lam, xi, coef["gamma"][2]))
    by_hand = alpha * 2 * m.rho / math.sqrt(r * s) * (2 * force / (e_star * math.sqrt(r * s**3))) ** -gamma
    with warnings.catch_warnings():
        warnings.simplefilter("error", ExtrapolationWarning)
        result = _quiet(surrogate_ds, small, force, xi, lam, model="power_law")
    assert float(result["resistance"]) == pytest.approx(by_hand, rel=1e-12)
    assert float(result["resistance_power_law"]) == pytest.approx(by_hand, rel=1e-12)
    assert float(result["alpha"]) == pytest.approx(alpha, rel=1e-14)
    assert result["resistance_mean_lower"] < result["resistance"] < result["resistance_mean_upper"]
    assert result["resistance"].attrs["units"] == "ohm"


def test_band_components_add_up(small: ResolvedScenario, surrogate_ds: xr.Dataset) -> None:
    rng = np.random.default_rng(0)
    f_range = surrogate_ds["force"].values
    force = rng.uniform(f_range.min(), f_range.max(), 200)
    xi = rng.uniform(0.2, 0.8, 200)
    lam = rng.uniform(1.0, 13.0, 200)
    r = _quiet(surrogate_ds, small, force, xi, lam)
    assert r["resistance"].dims == ("query",)
    mean = 1.959963984540054 * np.sqrt(r["fit_error"] ** 2 + r["surrogate_error"] ** 2)
    np.testing.assert_allclose(r["resistance_mean_lower"], r["resistance"] * np.exp(-mean), rtol=1e-13)
    np.testing.assert_allclose(r["resistance_mean_upper"], r["resistance"] * np.exp(mean), rtol=1e-13)
    np.testing.assert_allclose(r["resistance_spread_p16"], r["resistance"] * np.exp(-r["spread_lower"]), rtol=1e-13)
    np.testing.assert_allclose(r["resistance_spread_p84"], r["resistance"] * np.exp(r["spread_upper"]), rtol=1e-13)
    for name in ("spread_lower", "spread_upper", "fit_error", "surrogate_error"):
        assert (r[name] > 0).all(), name


def test_band_components_match_the_tables_on_the_grid(small: ResolvedScenario, surrogate_ds: xr.Dataset) -> None:
    xi, lam, step = small.oxide.xi[1], small.oxide.lambda_[1], 1
    cell = {"xi": xi, "lambda": lam}
    f = float(surrogate_ds["force"][step])
    ln_f = math.log(float(surrogate_ds["force_normalized"][step]))
    r = _quiet(surrogate_ds, small, f, xi, lam, model="power_law")
    ratio = float(surrogate_ds["band_ratio_lower"].sel(cell)[step])
    assert float(r["resistance_spread_p16"] / r["resistance"]) == pytest.approx(ratio, rel=1e-9)
    s_a, s_g = (float(surrogate_ds[f"{p}_fit_sigma"].sel(cell)) for p in ("alpha", "gamma"))
    e_a, e_g = (float(surrogate_ds[f"{p}_cv_error"].sel(cell)) for p in ("alpha", "gamma"))
    assert float(r["fit_error"]) == pytest.approx(math.hypot(s_a, ln_f * s_g), rel=1e-9)
    assert float(r["surrogate_error"]) == pytest.approx(math.hypot(e_a, ln_f * e_g), rel=1e-9)
    # the fit's sigma is its 95 % interval over 2 x 1.96
    ci = fits.build(small, synthetic_cube(small, noise=0.2))["alpha_ci"].sel(cell)
    assert s_a == pytest.approx(float(np.log(ci[1] / ci[0])) / (2 * 1.959963984540054), rel=1e-9)


def test_vectorized_xarray_queries(small: ResolvedScenario, surrogate_ds: xr.Dataset) -> None:
    force = xr.DataArray([1000.0, 2000.0, 3000.0], dims="force", coords={"force": [1000.0, 2000.0, 3000.0]})
    xi = xr.DataArray([0.3, 0.5], dims="xi")
    r = _quiet(surrogate_ds, small, force, xi, 5.0)
    assert r["resistance"].dims == ("force", "xi") and r["resistance"].shape == (3, 2)
    one = _quiet(surrogate_ds, small, 2000.0, 0.5, 5.0)
    assert float(r["resistance"].sel(force=2000.0)[1]) == pytest.approx(float(one["resistance"]), rel=1e-14)
    assert float(r["resistance_mean_upper"][1, 1]) == pytest.approx(float(one["resistance_mean_upper"]), rel=1e-12)
    grid = _quiet(surrogate_ds, small, np.array([[1000.0], [2000.0]]), np.array([0.3, 0.5, 0.7]), 5.0)
    assert grid["resistance"].shape == (2, 3)


def test_extrapolation_is_refused_unless_asked(small: ResolvedScenario, surrogate_ds: xr.Dataset) -> None:
    for kwargs, name in (({"xi": 0.95}, "xi"), ({"lam": 40.0}, "lambda"), ({"force": 1.0}, "F'")):
        args = {"force": 1500.0, "xi": 0.4, "lam": 4.0, **kwargs}
        with pytest.raises(ConfigError, match=f"{name} = .* outside the fitted range .* pass --extrapolate"):
            predict(surrogate_ds, small, **args)
        with pytest.warns(ExtrapolationWarning, match=f"{name} = .* outside the fitted range"):
            _quiet(surrogate_ds, small, **args, extrapolate=True)


def test_warns_where_the_surrogate_error_is_large(small: ResolvedScenario, surrogate_ds: xr.Dataset) -> None:
    r = _quiet(surrogate_ds, small, 1500.0, 0.4, 4.0)
    below, above = 2 * float(r["surrogate_error"]), 0.5 * float(r["surrogate_error"])
    with warnings.catch_warnings():
        warnings.simplefilter("error", SurrogateErrorWarning)
        predict(surrogate_ds, small, 1500.0, 0.4, 4.0, warn_error=below)
    with pytest.warns(SurrogateErrorWarning, match="exceeds surrogate.warn_error"):
        predict(surrogate_ds, small, 1500.0, 0.4, 4.0, warn_error=above)


@pytest.mark.parametrize("kwargs, message", [
    ({"force": 0.0}, "force = 0.0 is out of range"),
    ({"force": math.nan}, "force = nan is out of range"),
    ({"xi": 1.0}, "xi = 1.0 is out of range"),
    ({"lam": -2.0}, "lambda = -2.0 is out of range"),
    ({"lam": [1.0, 2.0, -1.0]}, r"lambda = -1.0 \(query 3 of 3\) is out of range"),
    ({"force": [1000.0, 2000.0], "xi": [0.3, 0.4, 0.5]}, "must be numbers or arrays that broadcast"),
])
def test_bad_input_raises(small: ResolvedScenario, surrogate_ds: xr.Dataset, kwargs: dict, message: str) -> None:
    args = {"force": 1500.0, "xi": 0.4, "lam": 4.0, **kwargs}
    with pytest.raises(ConfigError, match=message):
        predict(surrogate_ds, small, **args)


def test_json_gives_the_same_predictions_as_netcdf(small: ResolvedScenario, data_dir) -> None:
    from_json = load_surrogate(data_dir / "surrogate.json")
    from_nc = load_surrogate(data_dir / "surrogate.nc")
    rng = np.random.default_rng(1)
    f = rng.uniform(800.0, 4000.0, 300)
    args = (f, rng.uniform(0.2, 0.8, 300), rng.uniform(1.0, 13.0, 300))
    xr.testing.assert_identical(_quiet(from_json, small, *args), _quiet(from_nc, small, *args))
    assert from_json.info["alpha_formula"].startswith("alpha = EXP(")


def test_band_is_unbounded_with_many_open_circuits(small: ResolvedScenario) -> None:
    ds = _build(small, noise=0.2, open_share=0.25)
    result = _quiet(ds, small, 1500.0, 0.4, 4.0)
    assert float(result["resistance_spread_p84"]) == math.inf
    assert 0 < float(result["resistance_spread_p16"]) < float(result["resistance"])
    assert float(result["open_probability"]) == pytest.approx(0.25)


# ------------------------------------------------------------------ CLI
def _rows(text: str) -> list[dict[str, float]]:
    header, *lines = text.strip().splitlines()
    keys = header.split(",")
    return [{k: float(v) for k, v in zip(keys, line.split(",")) if k != "outside_domain"} for line in lines]


def test_cli_lists_csv_and_output(tmp_path, capsys, small: ResolvedScenario, data_dir) -> None:
    base = ["predict", "--data-dir", str(data_dir), *cli_overrides(small)]
    assert main(base + ["--force", "1500,2500", "--xi", "0.4", "--lambda", "4,6"]) == 0
    rows = _rows(capsys.readouterr().out)
    assert len(rows) == 2 and rows[1]["force_N"] == 2500 and rows[1]["lambda"] == 6
    expected = _quiet(load_surrogate(data_dir / "surrogate.json"), small, [1500.0, 2500.0], 0.4, [4.0, 6.0])
    np.testing.assert_allclose([r["resistance_ohm"] for r in rows], expected["resistance"], rtol=1e-9)
    np.testing.assert_allclose([r["resistance_mean_upper_ohm"] for r in rows], expected["resistance_mean_upper"], rtol=1e-9)
    # material from the scenario, overridable with --set
    assert main(base + ["--set", "material.rho=1.44e-6", "--force", "1500", "--xi", "0.4", "--lambda", "4"]) == 0
    doubled = _rows(capsys.readouterr().out)[0]["resistance_ohm"]
    assert doubled == pytest.approx(2 * rows[0]["resistance_ohm"], rel=1e-9)
    queries = tmp_path / "q.csv"
    queries.write_text("xi,lambda,force,note\n0.4,4,1500,a\n0.4,6,2500,b\n")
    out = tmp_path / "out.csv"
    assert main(base + ["--csv", str(queries), "--output", str(out)]) == 0
    assert _rows(out.read_text()) == rows
    # from surrogate.nc explicitly: the same numbers
    assert main(base + ["--csv", str(queries), "--surrogate", str(data_dir / "surrogate.nc")]) == 0
    assert _rows(capsys.readouterr().out) == rows
    assert main(base + ["--force", "1500", "--xi", "0.95", "--lambda", "4", "--extrapolate"]) == 0
    assert "warning: xi = 0.95 lies outside the fitted range" in capsys.readouterr().err


@pytest.mark.parametrize("args, message", [
    (["--force=-5", "--xi", "0.4", "--lambda", "4"], "force = -5.0 is out of range: must be finite and > 0"),
    (["--force", "nan", "--xi", "0.4", "--lambda", "4"], "force = nan is out of range"),
    (["--force", "5", "--xi", "0", "--lambda", "4"], "xi = 0.0 is out of range: must be in (0, 1)"),
    (["--force", "5", "--xi", "0.4", "--lambda", "inf"], "lambda = inf is out of range"),
    (["--force", "5,6", "--xi", "0.4,0.5,0.6", "--lambda", "4"], "lists of different lengths (--force 2, --xi 3, --lambda 1)"),
    (["--force", "5,abc", "--xi", "0.4", "--lambda", "4"], "--force = '5,abc' is not a number"),
    (["--force", "5", "--xi", "0.4"], "--lambda missing"),
    (["--force", "1500", "--xi", "0.95", "--lambda", "4"], "xi = 0.95 lies outside the fitted range"),
    (["--force", "5", "--xi", "0.4", "--lambda", "4", "--surrogate", "/nonexistent/s.nc"], "does not exist"),
])
def test_cli_bad_input(capsys, small: ResolvedScenario, data_dir, args: list[str], message: str) -> None:
    assert main(["predict", "--data-dir", str(data_dir), *cli_overrides(small), *args]) == 2
    captured = capsys.readouterr()
    assert message in captured.err and captured.err.count("\n") == 1 and captured.out == ""


@pytest.mark.parametrize("text, message", [
    ("force,xi\n1500,0.4\n", "lacks column(s) lambda"),
    ("force,xi,lambda\n1500,0.4,abc\n", "line 2: lambda = 'abc' is not a number"),
    ("force,xi,lambda\n1500,0.4\n", "line 2: 2 fields, the header has 3"),
    ("force,xi,lambda\n", "at least one query"),
    ("force,xi,lambda\n1500,0.4,4\n-3,0.4,4\n", "force = -3.0 (query 2 of 2) is out of range"),
])
def test_cli_malformed_csv(tmp_path, capsys, small: ResolvedScenario, data_dir, text: str, message: str) -> None:
    path = tmp_path / "q.csv"
    path.write_text(text)
    assert main(["predict", "--data-dir", str(data_dir), *cli_overrides(small), "--csv", str(path)]) == 2
    captured = capsys.readouterr()
    assert message in captured.err and captured.err.count("\n") == 1


def test_bench_vectorized_agrees_with_one_at_a_time(small: ResolvedScenario, monkeypatch: pytest.MonkeyPatch) -> None:
    from g2tom.bench import predict as bench_predict

    for name, value in (("_REPEATS", 1), ("_QUERIES", 2000), ("_LOOP_QUERIES", 20)):
        monkeypatch.setattr(bench_predict, name, value)
    result = bench_predict.run(small)
    assert result["queries"] == 2000 and result["max_rel_difference_upper"] < 1e-12
    assert result["atlas_queries"] == 2000 and result["atlas_surfaces"] == 10 and result["atlas_seconds"] > 0


def test_json_round_trips_every_table_value(data_dir) -> None:
    tables = load_surrogate(data_dir / "surrogate.nc")
    tables.tables["band_ratio_lower"][0, 0, 0] = np.nan
    tables.tables["band_ratio_upper"][0, 0, 1] = np.inf
    back = type(tables).from_json(tables.to_json())
    for name, values in tables.tables.items():
        np.testing.assert_array_equal(back.tables[name], values)
    for p, (cw, cz, t) in tables.coef.items():
        np.testing.assert_array_equal(back.coef[p][0], cw)
        np.testing.assert_array_equal(back.coef[p][1], cz)
        assert back.coef[p][2] == t
    assert back.ranges == tables.ranges


def test_json_carries_the_lambda_map(tmp_path, small: ResolvedScenario) -> None:
    scenario = resolve(load_scenario("paper_gt", {**SMALL_OVERRIDES, "surrogate.lambda_map": "lambda"}))
    write_dataset(fits.build(scenario, synthetic_cube(scenario, noise=0.2)), tmp_path, "fits", scenario)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        surrogate.run(scenario, tmp_path, None)
    from_json = load_surrogate(tmp_path / "surrogate.json")
    from_nc = load_surrogate(tmp_path / "surrogate.nc")
    lam, xi = np.array([2.0, 6.0, 12.0]), np.array([0.3, 0.5, 0.7])
    for p in ("alpha", "gamma"):
        coef_w, coef_z, spec = from_json.coef[p]
        assert spec.endswith(";w=lambda")
        np.testing.assert_array_equal(from_json.parameter(p, lam, xi), from_nc.parameter(p, lam, xi))
        # the predictor evaluates polynomials in lambda itself, not in log(lambda)
        direct = sum(P.polyval(lam, cw) * P.polyval(-np.log1p(-xi), cz) for cw, cz in zip(coef_w, coef_z))
        direct = np.exp(direct) if spec.startswith("log") else direct
        np.testing.assert_allclose(from_json.parameter(p, lam, xi), direct, rtol=1e-12)
    args = (np.array([900.0, 2000.0]), np.array([0.3, 0.6]), np.array([2.0, 11.0]))
    xr.testing.assert_identical(_quiet(from_json, scenario, *args), _quiet(from_nc, scenario, *args))


def test_curve_model_reproduces_every_cell_at_every_fitted_step(small: ResolvedScenario) -> None:
    """The default predictor (the curve model) at a grid cell's (xi, lambda) and a fitted step is
    that cell's curve, within max(3 %, the step's interval) of the cell's mean (issue 21's target)."""
    fits_ds = fits.build(small, synthetic_cube(small, noise=0.2))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        sur = surrogate.build(small, fits_ds)
    steps = np.flatnonzero(fits_ds["fitted"].values)
    reduction = fits_ds.attrs["reduction"]
    for xi in small.oxide.xi:
        for lam in small.oxide.lambda_:
            cell = {"xi": xi, "lambda": lam}
            force = fits_ds["force"].values[steps]
            r = _quiet(sur, small, force, np.full(force.size, xi), np.full(force.size, lam))
            assert r.attrs["model"] == "curve"
            got = r["resistance"].values / small.resistance_scale
            coef = fits_ds["curve_coefficients"].sel(cell).values
            by_hand = np.exp(np.polynomial.polynomial.polyval(np.log(fits_ds["force_normalized"].values[steps]), coef))
            np.testing.assert_allclose(got, by_hand, rtol=1e-12)
            mean = fits_ds[f"{reduction}_normalized"].sel(cell).values[steps]
            ci = fits_ds[f"{reduction}_normalized_ci"].sel(cell).values[steps]
            lo = np.minimum(0.97, ci[:, 0] / mean)
            hi = np.maximum(1.03, ci[:, 1] / mean)
            assert np.all((got / mean >= lo * (1 - 1e-12)) & (got / mean <= hi * (1 + 1e-12)))
            assert np.all(r["fit_error"].values > 0) and np.all(np.isfinite(r["surrogate_error"].values))


def test_curve_between_cells_is_the_linear_interpolation_of_the_cells(small: ResolvedScenario, surrogate_ds: xr.Dataset) -> None:
    lam = np.asarray(small.oxide.lambda_)
    xi = small.oxide.xi[1]
    mid = float(np.exp(0.5 * (np.log(lam[0]) + np.log(lam[1]))))  # halfway in w = ln lambda
    force = float(surrogate_ds["force"][2])
    ends = [float(_quiet(surrogate_ds, small, force, xi, v)["resistance"]) for v in (lam[0], lam[1])]
    got = float(_quiet(surrogate_ds, small, force, xi, mid)["resistance"])
    assert math.log(got) == pytest.approx(0.5 * (math.log(ends[0]) + math.log(ends[1])), rel=1e-12)
