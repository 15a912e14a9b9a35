"""`g2tom validate`: the plan, the outputs, resuming, and the refusal without the extra."""

from __future__ import annotations

import dataclasses
import io
import json
import sys

import numpy as np
import pytest
import xarray as xr

from pipeline.cli.main import main
from pipeline.config import ConfigError
from pipeline.reference import cases, scene
from analysis.figures_validate import figure
from pipeline.reference.validate import chosen_set, run_validation

TINY = dataclasses.replace(scene.QUICK, radius=1e-3, deltas=(1.0, 0.0), realizations=(0, 1), n_grid=96,
                           pixels_per_cell=4.0, convergence_grid=48,
                           discretizations=("expected", "asperities", "surface_asperities", "discrete"))


def test_without_the_extra_validate_names_the_install_command_and_exits_2(tmp_path, monkeypatch, capsys) -> None:
    monkeypatch.setitem(sys.modules, "tamaas", None)  # import tamaas raises ImportError
    assert main(["validate", "--quick", "--data-dir", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert f"{sys.executable} -m pip install tamaas (g2tom's optional extra 'reference')" in err
    assert "Traceback" not in err and "-e '.[reference]'" not in err  # no path that exists only in the repository
    assert not (tmp_path / "validate").exists()  # refused before any work


def test_validate_refuses_scenario_options_it_would_ignore(tmp_path, capsys) -> None:
    assert main(["validate", "--quick", "--data-dir", str(tmp_path), "--set", "roughness.sigma=1e-5"]) == 2
    assert "--config and --set are not used" in capsys.readouterr().err
    assert not (tmp_path / "validate").exists()


def test_default_and_quick_sets_meet_the_issue() -> None:
    default, quick = chosen_set(False), chosen_set(True)
    assert default.mu == pytest.approx(8.262, abs=0.01)  # the paper's mu
    assert default.n_grid == 1024 and default.pixels_per_cell >= 16
    assert len(default.deltas) >= 3 and max(default.deltas) >= 2.0 and min(default.deltas) <= -3.0  # F' 0.075..18.8
    assert set(default.xi) == {0.5, 0.7} and set(default.lambdas) == {1.0, 5.0} and len(default.realizations) >= 4
    assert cases.estimate_seconds(default, cases.plan_cases(default)) <= 45 * 60
    assert quick.n_grid == 256 and len(quick.realizations) == 1 and len(quick.deltas) == 2
    assert len(quick.xi) * len(quick.lambdas) == 1
    assert cases.estimate_seconds(quick, cases.plan_cases(quick)) <= 180


@pytest.fixture(scope="module")
def tiny_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("validate")
    log = io.StringIO()
    run_validation(TINY, out, stream=log, draw=figure)
    return out, log.getvalue()


def test_outputs_are_labelled_and_consistent(tiny_run) -> None:
    out, log = tiny_run
    assert log.index("validate: 6 cases; estimated") < log.index("g2tom done; 0 of 6 cases already stored")
    assert log.index("already stored") < log.index("case 1/6")  # the plan comes first, then g2tom, then the cases
    ds = xr.open_dataset(out / "validate.nc")
    for name, var in ds.variables.items():
        assert var.attrs.get("units") is not None and var.attrs.get("long_name"), name
    ref = ds["resistance_reference_clean"].values
    assert np.all(np.isfinite(ref)) and np.all(ref > 0)
    np.testing.assert_allclose(ds["force_reference"].values, np.broadcast_to(ds["force"].values, ref.shape), rtol=1e-9)
    np.testing.assert_allclose(ds["ratio_clean"].values, ds["resistance_g2tom_clean"].values / ref[None, None])
    sides = ds["window_side"].values  # fitted per case, at most the set's window; one window for both grids
    assert np.all(sides <= TINY.side * (1 + 1e-12)) and sides[0, 0] < TINY.side
    np.testing.assert_array_equal(ds["window_side_convergence"].values, sides[0])
    g2_clean = ds["resistance_g2tom_clean"]
    shared = g2_clean.sel(discretization="expected").values
    np.testing.assert_array_equal(shared[:, 0], shared[:, 1])  # one value over the realizations
    own = g2_clean.sel(discretization="surface_asperities").values  # each surface its own
    assert np.all(np.isfinite(own)) and np.all(own[:, 0] != own[:, 1]) and np.all(own[:, :, 1] < own[:, :, 0])
    assert np.all(ref[:, 1] < ref[:, 0])  # heavier load, lower resistance
    # oxide only removes conducting area: never a lower resistance than the clean contact's
    assert np.all(ds["resistance_reference"].values >= ref[None, None] * (1 - 1e-9))
    assert np.all(np.abs(ds["convergence_change"].values) < 0.5)
    barber = ds["barber_ratio"].values  # the coarse grid's light load may fail (one-pixel contact): NaN
    assert np.isfinite(barber).any() and np.nanmax(np.abs(barber - 1.0)) < 0.02
    text = (out / "validate.md").read_text()
    assert text.startswith("## How right is the model?")
    first = text.splitlines()[2]
    assert "g2tom's default discretization (expected" in first
    assert ds.attrs["skipped_g2tom"] == "none" and "### asperities, point" in text
    assert "### surface_asperities, greenwood" in text
    assert not np.isnan(ds["resistance_g2tom"].values).any()  # +inf where g2tom's own asperities all miss
    assert (out / "validate.png").stat().st_size > 10_000


def test_the_discrete_model_on_each_surfaces_own_caps_tracks_the_full_field(tiny_run) -> None:
    out, _ = tiny_run
    ds = xr.open_dataset(out / "validate.nc")
    clean = ds["ratio_clean"].sel(discretization="discrete").values  # (model, realization, load)
    assert np.all(clean[:, 0] != clean[:, 1])  # each surface its own
    # a coarse tiny grid (4 pixels per asperity spacing): within 10 % per surface, clean
    assert np.all(np.abs(clean[ds["model"].values == "point"] - 1.0) < 0.10)
    se = ds["ratio_clean_standard_error"].sel(discretization="discrete").values  # (model, load)
    logs = np.log(clean)
    np.testing.assert_allclose(se, logs.std(axis=1, ddof=1) / np.sqrt(2), rtol=1e-12)
    assert "### discrete, point" in (out / "validate.md").read_text()


def test_log_standard_error_against_a_bootstrap() -> None:
    from pipeline.fitting.ensemble import log_standard_error

    rng = np.random.default_rng(5)
    ratios = np.exp(rng.normal(0.05, 0.3, size=40))
    means = [np.mean(np.log(rng.choice(ratios, ratios.size))) for _ in range(4000)]
    assert log_standard_error(ratios) == pytest.approx(np.std(means), rel=0.08)
    # open circuits (inf), NaN and zero are left out; fewer than two values: NaN
    padded = np.concatenate([ratios, [np.inf, np.nan, 0.0]])
    assert log_standard_error(padded) == log_standard_error(ratios)
    assert np.isnan(log_standard_error(np.array([1.2, np.inf])))


def test_a_rerun_resumes_from_the_stored_cases(tiny_run) -> None:
    out, _ = tiny_run
    before = xr.open_dataset(out / "validate.nc").load()
    damaged = out / "cases" / f"{cases.Case(1, 0, TINY.n_grid, True).name}.json"
    damaged.write_text("{ truncated")
    log = io.StringIO()
    run_validation(TINY, out, stream=log, draw=figure)
    text = log.getvalue()
    assert "5 of 6 cases already stored, 1 to run" in text and "case 1/1 r1_load0_n96" in text
    after = xr.open_dataset(out / "validate.nc").load()
    np.testing.assert_allclose(after["resistance_reference"].values, before["resistance_reference"].values, rtol=1e-12)
    assert json.loads(damaged.read_text())["key"]  # rewritten whole
    # another force (another set) does not reuse the stored case
    case = cases.Case(0, 0, TINY.n_grid, True)
    source_key = json.loads((out / "cases" / f"{case.name}.json").read_text())["key"]
    assert cases.load_case(out / "cases" / f"{case.name}.json", source_key) is not None
    assert cases.load_case(out / "cases" / f"{case.name}.json", "0" * 16) is None


def test_a_combination_g2tom_refuses_is_nan_and_named(monkeypatch) -> None:
    from pipeline.config import ConfigError
    from pipeline.reference import validate

    real = scene.g2tom_resistances

    def refusing(vset, model, spots):
        if (spots, model) == ("asperities", "point"):
            raise ConfigError("contact.spots = 'asperities' is not allowed with cube.model = 'point'")
        return real(vset, model, spots)

    monkeypatch.setattr(scene, "g2tom_resistances", refusing)
    side = validate._g2tom_side(dataclasses.replace(TINY, realizations=(0,)))
    assert np.isnan(side["resistance"][1, 1]).all() and np.isnan(side["clean"][1, 1]).all()
    assert not np.isnan(side["clean"][0]).any() and not np.isnan(side["resistance"][1, 0]).any()
    assert side["skipped"] == ["asperities/point: contact.spots = 'asperities' is not allowed with cube.model = 'point'"]


def test_random_process_set_feeds_g2tom_its_summit_statistics() -> None:
    from pipeline.physics.surface_spectrum import summit_parameters
    from pipeline.reference import surfaces

    vset = chosen_set(False, "random_process")
    q_high = 2 * np.pi / vset.short_wavelength
    summits = summit_parameters(*surfaces.spectral_moments_closed_form(vset.hurst, q_high / vset.bandwidth_ratio,
                                                                       q_high, vset.rms))
    assert (vset.sigma, vset.eta, vset.beta) == pytest.approx((summits.sigma, summits.eta, summits.beta), rel=1e-12)
    assert vset.eta == pytest.approx(chosen_set(False).eta, rel=1e-9)  # as dense as the GW set's asperities
    assert 2 * np.pi / q_high >= 2 * vset.side / vset.convergence_grid  # the band is resolved on both grids
    with pytest.raises(ConfigError, match="--surface 'fractal'"):
        chosen_set(False, "fractal")


def test_a_tiny_random_process_run(tmp_path) -> None:
    from pipeline.reference.scene import random_process_set

    vset = dataclasses.replace(random_process_set(TINY, rms=20e-6), convergence_grid=0,  # 48^2 cannot hold the band
                               discretizations=("expected", "asperities"))  # its asperities are not known
    paths = run_validation(vset, tmp_path, stream=io.StringIO())
    text = paths[1].read_text()
    assert "self-affine" in text and "summit statistics" in text
    with xr.open_dataset(paths[0]) as ds:
        assert ds.attrs["scene_surface"] == "random_process"
        assert np.isfinite(ds["resistance_reference_clean"].values).any()


def test_surface_asperities_are_the_reference_surfaces_own_tips() -> None:
    from pipeline.reference import surface_spots, surfaces

    vset = dataclasses.replace(TINY, realizations=(1,))
    tips = surfaces.gw_asperities(vset.side, vset.eta, vset.sigma, vset.beta, scene.surface_stream(vset, 1))
    # the reference's rough sphere peaks at those tips: the pixel under the highest tip holds its height
    n = 4 * vset.n_grid
    rough = scene.rough_sphere(vset, 1, n) - surfaces.sphere(n, vset.side / n, vset.radius)
    top = int(np.argmax(tips.z))
    centres = (np.arange(n) - (n - 1) / 2) * vset.side / n
    iy, ix = np.argmin(np.abs(centres - tips.y[top])), np.argmin(np.abs(centres - tips.x[top]))
    assert rough[iy, ix] == pytest.approx(tips.z[top], abs=(vset.side / n) ** 2 / vset.beta)
    # g2tom's spots of that surface: with every tip touching, each cell carries its tips' summed radii
    cells = (np.arange(9) - 4) / np.sqrt(vset.eta)
    deep = np.full((1, 9, 9), -10 * vset.sigma)
    radii = surface_spots.spot_radii(vset, 1, cells, deep)
    inside = (np.abs(tips.x) < 4.5 / np.sqrt(vset.eta)) & (np.abs(tips.y) < 4.5 / np.sqrt(vset.eta))
    assert radii.sum() == pytest.approx(np.sqrt(vset.beta * (tips.z[inside] + 10 * vset.sigma)).sum(), rel=1e-12)
    with pytest.raises(ValueError, match="needs the GW surface"):
        surface_spots.spot_radii(dataclasses.replace(vset, surface="random_process"), 1, cells, deep)


@pytest.mark.parametrize("surface", ["gw", "random_process"])
def test_a_smaller_window_samples_the_same_surface(surface) -> None:
    from pipeline.reference.scene import random_process_set

    vset = TINY if surface == "gw" else random_process_set(TINY, rms=20e-6)
    n = vset.n_grid
    whole = scene.rough_sphere(vset, 1, n)
    half = scene.rough_sphere(vset, 1, n // 2, vset.side / 2)  # the same pixels, the centre of the window
    np.testing.assert_allclose(half, whole[n // 4: 3 * n // 4, n // 4: 3 * n // 4], rtol=0, atol=1e-12 * vset.sigma)
    with pytest.raises(ValueError, match="side = .* is out of range"):
        scene.rough_sphere(vset, 1, n, 1.01 * vset.side)


def test_a_case_window_holds_its_contact_and_grows_when_too_small() -> None:
    from pipeline.reference import window

    force = float(scene.g2tom_resistances(TINY, "greenwood", "expected")["force"].values[0])
    side, reach = window.fitted_side(TINY, 0, force)
    assert side == pytest.approx(min(TINY.side, 2 * (window.MARGIN * reach + window.PAD_SPACINGS / np.sqrt(TINY.eta))))
    assert side < TINY.side  # the light load's contact is small: finer pixels than the set's window
    _, _, state, used = window.solve_in_window(TINY, 0, TINY.n_grid, force, side)
    assert used == side and not state.contact[0].any() and state.force == pytest.approx(force, rel=1e-6)
    # a window the contact overflows grows by GROWTH until it holds it
    tight = reach  # half the probe's reach on each side
    _, _, state, grown = window.solve_in_window(TINY, 0, TINY.n_grid, force, tight)
    steps = np.log(grown / tight) / np.log(window.GROWTH)  # a whole number of growths, or capped at the set's window
    assert grown > tight and (steps == pytest.approx(round(steps), abs=1e-9) or grown == TINY.side)
    assert not (state.contact[0].any() or state.contact[-1].any() or state.contact[:, 0].any() or state.contact[:, -1].any())


def test_realizations_and_loads_override_the_set_and_bad_values_exit_2(tmp_path, monkeypatch, capsys) -> None:
    vset = chosen_set(False, realizations=40, loads=8)
    assert vset.realizations == tuple(range(40))
    np.testing.assert_allclose(vset.deltas, np.linspace(2.0, -3.0, 8))
    for argv, expect in ((["--realizations", "0"], "--realizations = 0"), (["--loads", "1"], "--loads = 1")):
        assert main(["validate", "--data-dir", str(tmp_path), *argv]) == 2
        err = capsys.readouterr().err
        assert expect in err and err.count("\n") == 1 and "Traceback" not in err
    assert not (tmp_path / "validate").exists()
    seen = {}

    def record(vset, out, progress=True, **_):
        seen.update(vset=vset, progress=progress)
        return []

    import pipeline.reference.validate as validate

    monkeypatch.setattr(validate, "run_validation", record)
    assert main(["validate", "--quick", "--no-progress", "--realizations", "2", "--data-dir", str(tmp_path)]) == 0
    assert seen["progress"] is False and seen["vset"].realizations == (0, 1) and seen["vset"].n_grid == 256
