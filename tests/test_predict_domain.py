"""`g2tom predict` knows its domain: the surrogate's scene (mu, Pi), refusals, --extrapolate, --roughness."""

from __future__ import annotations

import json
import warnings

import numpy as np
import pytest

from g2tom.cli.main import main
from g2tom.config import ConfigError, ResolvedScenario
from g2tom.before_work import load_scenario
from g2tom.physics.groups import groups, surface_from_groups
from g2tom.predict.predictor import ExtrapolationWarning, SurrogateErrorWarning, load_surrogate, predict
from g2tom.heightmap import measure
from tests.test_fits_stage import cli_overrides
from tests.test_predict import _quiet, _rows, data_dir  # noqa: F401 (the fixture: fits.nc and the surrogate stage run)
from tests.test_roughness import PIXEL, wave_surface

QUERY = ["--force", "1500", "--xi", "0.4", "--lambda", "4"]


def _predict(data_dir, small, capsys, *extra: str) -> tuple[int, str, str]:
    """The run's own single-scene surrogate answers (``--surrogate``: not the atlas the package ships)."""
    status = main(["predict", "--data-dir", str(data_dir), *cli_overrides(small), *QUERY,
                   "--surrogate", str(data_dir / "surrogate.json"), *extra])
    captured = capsys.readouterr()
    return status, captured.out, captured.err


def test_surrogate_records_its_scene(data_dir, small: ResolvedScenario) -> None:
    g = groups(small.roughness.sigma, small.roughness.eta, small.roughness.beta, small.indenter.radius)
    info = json.loads((data_dir / "surrogate.json").read_text())["info"]
    assert info["mu"] == pytest.approx(8.2624, abs=5e-5) and info["mu"] == g.mu
    assert info["Pi"] == pytest.approx(40.0, rel=1e-12)
    assert load_surrogate(data_dir / "surrogate.nc").info["mu"] == g.mu


def test_another_surface_is_refused_naming_the_group(data_dir, small: ResolvedScenario, capsys) -> None:
    status, out, err = _predict(data_dir, small, capsys, "--set", "roughness.beta=3e-4")
    mu = groups(small.roughness.sigma, small.roughness.eta, 3e-4, small.indenter.radius).mu
    assert status == 2 and out == "" and err.count("\n") == 1
    assert f"mu = {mu:.6g} of this surface lies outside the domain [8.25" in err
    assert "single-scene surrogate" in err and "--extrapolate" in err


def test_extrapolate_accepts_it_with_a_warning(data_dir, small: ResolvedScenario, capsys) -> None:
    status, out, err = _predict(data_dir, small, capsys, "--set", "roughness.eta=1e9", "--extrapolate")
    assert status == 0
    assert "warning: mu = " in err and "another surface's coefficients" in err
    assert f"answered by the run's own single-scene surrogate (scenario '{small.name}', mu = 8.262" in err
    row = _rows(out)[0]
    expected = groups(small.roughness.sigma, 1e9, small.roughness.beta, small.indenter.radius)
    assert row["mu"] == pytest.approx(expected.mu, rel=1e-9) and row["Pi"] == pytest.approx(expected.Pi, rel=1e-9)
    header = out.splitlines()[0].split(",")
    assert header[:2] == ["force_N", "xi"] and header[-3:] == ["mu", "Pi", "outside_domain"]  # new columns last


def test_same_groups_other_dimensions_scale_exactly(data_dir, small: ResolvedScenario, capsys) -> None:
    """Inside the domain but with other dimensions: other numbers, the same R'(F')."""
    other = surface_from_groups(*groups(small.roughness.sigma, small.roughness.eta, small.roughness.beta,
                                        small.indenter.radius).__dict__.values(), sigma=40e-6, radius=5e-3)
    sets = {"roughness.sigma": other.sigma, "roughness.eta": other.eta, "roughness.beta": other.beta,
            "indenter.radius": other.radius, "material.E": 7e10, "material.rho": 2e-8}
    b = load_scenario("paper_gt", {**{k: v for k, v in small.flat().items() if k.startswith(("oxide", "loading"))}, **sets})
    tables = load_surrogate(data_dir / "surrogate.json")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", SurrogateErrorWarning)
        a_res = predict(tables, small, 1500.0, 0.4, 4.0)
        b_res = predict(tables, b, 1500.0 * b.force_scale / small.force_scale, 0.4, 4.0)
    assert float(b_res["resistance"]) != pytest.approx(float(a_res["resistance"]), rel=1e-3)
    assert float(b_res["resistance"]) / b.resistance_scale == pytest.approx(
        float(a_res["resistance"]) / small.resistance_scale, rel=1e-12)


def test_surrogate_without_groups_is_refused(data_dir, small: ResolvedScenario) -> None:
    tables = load_surrogate(data_dir / "surrogate.json")
    tables.info.pop("mu")
    with pytest.raises(ConfigError, match="records no \\(mu, Pi\\)"):
        predict(tables, small, 1500.0, 0.4, 4.0)
    with pytest.warns(ExtrapolationWarning):
        _quiet(tables, small, 1500.0, 0.4, 4.0, extrapolate=True)


def test_measured_roughness_feeds_the_groups(tmp_path, data_dir, small: ResolvedScenario, capsys) -> None:
    z, *_ = wave_surface(128)
    path = tmp_path / "surface.npy"
    np.save(path, z)
    measured = measure(path, PIXEL)
    expected = groups(measured["sigma"], measured["eta"], measured["beta"], small.indenter.radius)
    status, out, err = _predict(data_dir, small, capsys, "--roughness", str(path), "--pixel-size", str(PIXEL))
    assert status == 2 and f"mu = {expected.mu:.6g} of this surface" in err
    status, out, err = _predict(data_dir, small, capsys, "--roughness", str(path), "--pixel-size", str(PIXEL),
                                "--extrapolate")
    assert status == 0
    assert _rows(out)[0]["mu"] == pytest.approx(expected.mu, rel=1e-9)
    status, out, err = _predict(data_dir, small, capsys, "--pixel-size", "1e-6")
    assert status == 2 and "--pixel-size is only used with --roughness" in err


def test_another_surface_in_the_atlas_domain_is_answered_by_the_atlas(data_dir, small: ResolvedScenario, capsys) -> None:
    """Without --surrogate, a surface other than the run's is answered by the atlas surrogate the
    package ships (never by the run's coefficients), and the run's own surface by the run's."""
    query = ["predict", "--data-dir", str(data_dir), *cli_overrides(small), *QUERY]
    assert main(query) == 0
    own = capsys.readouterr()
    assert "answered by the run's own single-scene surrogate" in own.err
    assert main([*query, "--set", "roughness.beta=3e-4"]) == 0
    other = capsys.readouterr()
    assert "answered by the atlas surrogate" in other.err and "atlas_surrogate.json" in other.err
    assert _rows(other.out)[0]["resistance_ohm"] != pytest.approx(_rows(own.out)[0]["resistance_ohm"], rel=1e-3)
