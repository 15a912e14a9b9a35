"""The contact stage: dataset contract, physics checks on it, and validation through the CLI."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
import xarray as xr

from g2tom.bench import contact as bench_contact
from g2tom.cli.main import main
from g2tom.compute import ComputeOptions
from g2tom.config import ConfigError, Scenario
from g2tom.before_work import load_scenario
from g2tom.before_work.domains import resolve
from g2tom.physics import spot_models
from g2tom.physics.asperity import area_fraction
from g2tom.physics.grid import cell_centres
from g2tom.stages import contact
from tests.conftest import SMALL_OVERRIDES

FIELDS = ("pressure", "displacement", "separation", "area_fraction")
SCALARS = ("force", "force_normalized", "hertz_radius", "holm_radius", "roughness_parameter",
           "iterations", "residual")


@pytest.fixture(scope="module")
def ds(small):
    return contact.build(small)


def test_dataset_contract(ds, small):
    assert set(ds.dims) == {"delta", "r", "y", "x"}
    for name in FIELDS:
        assert ds[name].dims == ("delta", "r")
    for name in SCALARS:
        assert ds[name].dims == ("delta",)
    for name in ("spot_area", "spot_radius", "spot_separation"):
        assert ds[name].dims == ("delta", "y", "x")
    for name in list(ds.data_vars) + list(ds.coords):
        assert ds[name].attrs["units"] and ds[name].attrs["long_name"], name
    np.testing.assert_array_equal(ds.x, cell_centres(small.n_cells, small.cell_size))
    np.testing.assert_array_equal(ds.y, ds.x)
    np.testing.assert_allclose(ds.delta, small.deltas)
    np.testing.assert_allclose(ds.delta_sigma, np.asarray(small.deltas) / small.roughness.sigma)
    rough = small.roughness
    assert small.contact.spots == "expected" and ds.attrs["spots"] == "expected"
    np.testing.assert_allclose(ds.spot_radius, spot_models.expected_radius(ds.spot_separation, rough.sigma, rough.beta),
                               rtol=1e-14)
    np.testing.assert_allclose(ds.spot_area, area_fraction(ds.spot_separation, rough.sigma, rough.eta, rough.beta)
                               * small.cell_size**2, rtol=1e-14)
    assert np.all(ds.residual <= small.contact.tolerance)


def test_force_increases_with_load(ds):
    assert np.all(np.diff(ds.force) > 0) and np.all(ds.force > 0)
    assert np.all(np.diff(ds.force_normalized) > 0)
    assert np.all(np.diff(ds.hertz_radius) > 0)


def test_holm_radius_exceeds_and_approaches_hertz(ds):
    ratio = ds.holm_radius / ds.hertz_radius
    assert np.all(ratio > 1) and np.all(np.diff(ratio) < 0)


def test_area_conservation_spots_vs_continuous(ds):
    """sum of spot areas over the window = 2 pi integral A*(r) r dr (A* ~ 0 at the window edge)."""
    continuous = (ds.area_fraction * 2 * np.pi * ds.r).integrate("r")
    np.testing.assert_allclose(ds.spot_area.sum(("y", "x")), continuous, rtol=2e-3)


def test_published_conventions():
    sc = resolve(load_scenario("published", {"loading.n_delta": 4}))
    out = contact.build(sc)
    assert out.sizes["r"] == 20 and out.r.values[-1] == pytest.approx(0.3 * sc.indenter.radius)
    np.testing.assert_allclose(np.diff(out.r), out.r.values[1])
    assert np.all((out.iterations > 5) & (out.iterations < 30))
    # A* interpolated linearly from the nodes: the axis cell carries the node-0 value exactly
    centre = sc.n_cells // 2
    np.testing.assert_allclose(out.spot_area[:, centre, centre] / sc.cell_size**2,
                               out.area_fraction[:, 0], rtol=1e-12)
    # ... and an off-axis cell the chord between its two nodes, not A* of the interpolated gap
    cell = out.spot_area[:, centre, centre + 5].values / sc.cell_size**2
    chord = [np.interp(5 * sc.cell_size, out.r, row) for row in out.area_fraction.values]
    np.testing.assert_allclose(cell, chord, rtol=1e-12)
    other = contact.build(load_scenario("published", {"loading.n_delta": 4,
                                                      "contact.area_interpolation": "separation"}))
    assert np.max(np.abs(other.spot_area[:, centre, centre + 5].values / sc.cell_size**2 / cell - 1)) > 3e-3


@pytest.mark.parametrize("shape", ["cone", "flat_punch"])
def test_other_profiles(shape):
    sc = load_scenario("paper_gt", {**SMALL_OVERRIDES, "loading.n_delta": 3, "indenter.shape": shape,
                                 "indenter.cone_angle": 0.02, "indenter.punch_radius": 3e-4})
    out = contact.build(sc)
    assert np.all(np.diff(out.force) > 0) and np.all(out.converged == 1)
    assert np.all(np.isnan(out.hertz_radius))


def test_run_writes_with_provenance(tmp_path, small):
    sc = load_scenario("paper_gt", {**SMALL_OVERRIDES, "loading.n_delta": 2})
    path = contact.run(sc, tmp_path, ComputeOptions(progress=False))
    with xr.open_dataset(path) as out:
        assert out.attrs["config_hash"] == sc.config_hash("contact")
        assert out.attrs["scenario"] == "paper_gt" and "g2tom_version" in out.attrs
        assert out.force.attrs["units"] == "N"
    assert not list(tmp_path.glob(".*.tmp"))


def test_window_corner_outside_radial_domain(tmp_path, capsys):
    target = tmp_path / "contact.nc"
    target.write_text("previous")
    code = main(["contact", "--set", "contact.r_max=0.25", "--set", "contact.n_radial=40",
                 "--data-dir", str(tmp_path), "--no-progress"])
    assert code == 2
    err = capsys.readouterr().err
    assert "contact.r_max = 0.25 truncates the contact" in err and "need r_max >= 0.2542 (R*)" in err
    assert target.read_text() == "previous"


def test_window_check_of_the_stage_itself(small):
    """A scenario built around the validation still gets a ConfigError naming the radial domain."""
    sc = Scenario.of(small, contact=dataclasses.replace(small.contact, r_max=0.25))
    with pytest.raises(ConfigError, match="contact.r_max = 0.25 truncates the contact"):
        contact.build(sc)


@pytest.mark.parametrize(
    ("override", "message"),
    [
        ("roughness.sigma=0", "roughness.sigma = 0 is out of range: must be > 0 and <= 1 (m)"),
        ("roughness.sigma=-2e-5", "roughness.sigma = -2e-05 is out of range"),
        ("material.nu=0.5", "material.nu = 0.5 is out of range: must be > -1 and < 0.5"),
        ("material.nu=-1.2", "material.nu = -1.2 is out of range"),
        ("roughness.eta=inf", "roughness.eta = inf is not finite"),
        ("contact.n_radial=4", "contact.n_radial = 4 is out of range: must be >= 8"),
        ("contact.solver=gauss", "contact.solver = 'gauss' is not allowed: must be one of 'newton', 'fixed_point'"),
        ("contact.radial_grid=log", "contact.radial_grid = 'log' is not allowed"),
        ("contact.relaxation=1.5", "contact.relaxation = 1.5 is out of range: must be > 0 and <= 1"),
        ("contact.window=0.1", "contact.window = 0.1 truncates the contact: the spots outside it can "
         "change R by up to 37.1 > cube.crop_tolerance = 1e-06; it must be >= 0.3465 (R*, 49 cells)"),
        ("contact.spots=disc", "contact.spots = 'disc' is not allowed: must be one of 'mean_area', 'expected', 'asperities'"),
        ("indenter.shape=torus", "indenter.shape = 'torus' is not allowed"),
        ("contact.tolerance=nan", "contact.tolerance = nan is not finite"),
        ("contact.nradial=40", "unknown parameter 'contact.nradial'; did you mean 'contact.n_radial'?"),
        ("roughnes.sigma=1e-5", "did you mean 'roughness.sigma'?"),
    ],
)
def test_validation_errors_leave_data_untouched(tmp_path, capsys, override, message):
    target = tmp_path / "contact.nc"
    target.write_text("previous")
    assert main(["contact", "--set", override, "--data-dir", str(tmp_path), "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert message in err, err
    assert target.read_text() == "previous"


def test_bench_reports_times_and_force_errors(small, monkeypatch):
    monkeypatch.setattr(bench_contact, "_REPEATS", 1)
    sc = load_scenario("paper_gt", {**SMALL_OVERRIDES, "loading.n_delta": 3, "contact.n_radial": 60})
    result = bench_contact.run(sc)
    assert result["reference"]["n_radial"] == 240 and len(result["reference"]["force_N"]) == 3
    cases = {(c["solver"], c["n_radial"], c["radial_grid"]): c for c in result["cases"]}
    assert set(cases) == {("newton", 60, "graded"), ("fixed_point", 60, "graded"), ("newton", 60, "uniform"),
                          ("newton", 20, "uniform"), ("fixed_point", 20, "uniform")}
    assert all(c["all_converged"] and c["solve_seconds"] > 0 for c in cases.values())
    # the 20-node published grid is far coarser than the scenario's graded grid
    assert cases[("newton", 60, "graded")]["force_max_rel_error"] < 0.2 * cases[("newton", 20, "uniform")][
        "force_max_rel_error"]
