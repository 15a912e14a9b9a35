"""The predictor of Eq. 27: API and `g2tom predict`."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest
import xarray as xr

from pipeline.cli import main
from pipeline.config import ConfigError, Scenario
from pipeline.physics.surrogate import evaluate
from pipeline.predict import ExtrapolationWarning, load_surrogate, predict
from pipeline.stages import fits, surrogate
from pipeline.store import write_dataset
from tests.test_fits_stage import cli_overrides, synthetic_cube


@pytest.fixture(scope="module")
def surrogate_ds(small: Scenario) -> xr.Dataset:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)  # orders reduced on the 3 x 3 grid
        return surrogate.build(small, fits.build(small, synthetic_cube(small, noise=0.2)))


def test_equals_eq27_by_hand(small: Scenario, surrogate_ds: xr.Dataset) -> None:
    force, xi, lam = 1500.0, 0.4, 4.0
    m, r, s = small.material, small.indenter.radius, small.roughness.sigma
    e_star = m.E / (2 * (1 - m.nu**2))
    alpha = evaluate(surrogate_ds["alpha_coef_w"].values, surrogate_ds["alpha_coef_z"].values, lam, xi)
    gamma = evaluate(surrogate_ds["gamma_coef_w"].values, surrogate_ds["gamma_coef_z"].values, lam, xi)
    by_hand = alpha * 2 * m.rho / math.sqrt(r * s) * (2 * force / (e_star * math.sqrt(r * s**3))) ** -gamma
    with warnings.catch_warnings():
        warnings.simplefilter("error", ExtrapolationWarning)
        result = predict(surrogate_ds, small, force, xi, lam)
    assert result.resistance == pytest.approx(float(by_hand), rel=1e-12)
    assert result.lower < result.resistance < result.upper


def test_band_matches_the_data_on_the_grid(small: Scenario, surrogate_ds: xr.Dataset) -> None:
    xi, lam = small.oxide.xi[1], small.oxide.lambda_[1]
    step = 1
    f = float(surrogate_ds["force"][step])
    result = predict(surrogate_ds, small, f, xi, lam)
    ratio = surrogate_ds["band_ratio_lower"].sel(xi=xi, **{"lambda": lam})[step]
    assert result.lower / result.resistance == pytest.approx(float(ratio), rel=1e-9)


@pytest.mark.parametrize("kwargs, name", [
    ({"xi": 0.95}, "xi"), ({"lam": 40.0}, "lambda"), ({"force": 1.0}, "F'"),
])
def test_warns_outside_fitted_range(small: Scenario, surrogate_ds: xr.Dataset, kwargs: dict, name: str) -> None:
    args = {"force": 1500.0, "xi": 0.4, "lam": 4.0, **kwargs}
    with pytest.warns(ExtrapolationWarning, match=f"{name} = .* outside the fitted range"):
        predict(surrogate_ds, small, **args)


@pytest.mark.parametrize("kwargs, message", [
    ({"force": 0.0}, "--force = 0.0 is out of range"),
    ({"xi": 1.0}, "--xi = 1.0 is out of range"),
    ({"lam": -2.0}, "--lambda = -2.0 is out of range"),
])
def test_bad_input_raises(small: Scenario, surrogate_ds: xr.Dataset, kwargs: dict, message: str) -> None:
    args = {"force": 1500.0, "xi": 0.4, "lam": 4.0, **kwargs}
    with pytest.raises(ConfigError, match=message):
        predict(surrogate_ds, small, **args)


def test_cli(tmp_path, capsys, small: Scenario, surrogate_ds: xr.Dataset) -> None:
    path = write_dataset(surrogate_ds, tmp_path, "surrogate", small)
    base = ["predict", "--data-dir", str(tmp_path), *cli_overrides(small)]
    assert main(base + ["--force", "1500", "--xi", "0.4", "--lambda", "4"]) == 0
    out = capsys.readouterr()
    assert "R_el =" in out.out and "ohm" in out.out and "warning" not in out.err
    expected = predict(load_surrogate(path), small, 1500.0, 0.4, 4.0).resistance
    assert float(out.out.split("R_el =")[1].split()[0]) == pytest.approx(expected, rel=1e-5)
    # material from the scenario, overridable with --set
    assert main(base + ["--set", "material.rho=1.44e-6", "--force", "1500", "--xi", "0.4", "--lambda", "4"]) == 0
    doubled = float(capsys.readouterr().out.split("R_el =")[1].split()[0])
    assert doubled == pytest.approx(2 * expected, rel=1e-5)
    assert main(base + ["--force", "1500", "--xi", "0.95", "--lambda", "4"]) == 0
    assert "warning: xi = 0.95 lies outside the fitted range" in capsys.readouterr().err


@pytest.mark.parametrize("args, message", [
    (["--force", "-5", "--xi", "0.4", "--lambda", "4"], "--force = -5.0 is out of range: must be > 0"),
    (["--force", "5", "--xi", "0", "--lambda", "4"], "--xi = 0.0 is out of range: must be in (0, 1)"),
    (["--force", "5", "--xi", "0.4", "--lambda", "0"], "--lambda = 0.0 is out of range: must be > 0"),
    (["--force", "5", "--xi", "0.4", "--lambda", "4", "--surrogate", "/nonexistent/s.nc"], "does not exist"),
])
def test_cli_bad_input(tmp_path, capsys, args: list[str], message: str) -> None:
    assert main(["predict", "--data-dir", str(tmp_path), *args]) == 2
    assert message in capsys.readouterr().err


def test_band_is_unbounded_with_many_open_circuits(small: Scenario) -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        ds = surrogate.build(small, fits.build(small, synthetic_cube(small, noise=0.2, open_share=0.25)))
    result = predict(ds, small, 1500.0, 0.4, 4.0)
    assert result.upper == math.inf and 0 < result.lower < result.resistance
    assert result.open_probability == pytest.approx(0.25)
