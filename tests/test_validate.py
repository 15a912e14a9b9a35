"""`g2tom validate`: the plan, both parts' outputs, part 2's statistics, resuming, the CLI's options and refusals."""

from __future__ import annotations

import dataclasses
import io
import json
import sys

import numpy as np
import pytest
import xarray as xr

from g2tom.cli.main import main
from g2tom.config import ConfigError
from g2tom.reference import cases, cost, ensemble, scene, statistics
from g2tom.analysis.figures_validate import figure
from g2tom.reference.validate import Part2Precision, chosen_set, run_validation

TINY = dataclasses.replace(scene.QUICK, radius=1e-3, deltas=(1.0, 0.0), realizations=(0, 1), n_grid=96,
                           pixels_per_cell=4.0, convergence_grid=48, ensemble_grid=48, max_ensemble=4,
                           model_realizations=16,
                           discretizations=("expected", "asperities", "surface_asperities", "discrete"))
#: The variables that differ between two runs of the same set: wall times.
TIMES = ("seconds_contact", "seconds_case", "seconds_convergence", "seconds_cpu_case", "ensemble_seconds",
         "ensemble_seconds_cpu")


def test_without_the_extra_validate_names_the_install_command_and_exits_2(tmp_path, monkeypatch, capsys) -> None:
    monkeypatch.setitem(sys.modules, "tamaas", None)  # import tamaas raises ImportError
    assert main(["validate", "--quick", "--solver", "tamaas", "--data-dir", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert f"{sys.executable} -m pip install tamaas (g2tom's optional extra 'reference')" in err
    assert "Traceback" not in err and "-e '.[reference]'" not in err  # no path that exists only in the repository
    assert not (tmp_path / "validate").exists()  # refused before any work


@pytest.mark.parametrize("options, message", [
    (["--device", "tpu"], "g2tom: error: --device 'tpu' is not allowed: must be one of cpu, gpu, auto"),
    (["--solver", "fenics"], "g2tom: error: --solver 'fenics' is not allowed: must be one of tamaas, g2tom"),
    (["--device", "gpu"], "g2tom: error: --device gpu cannot be used: CuPy sees no GPU (0 devices)"),
])
def test_bad_device_or_solver_exits_2_with_one_line_before_work(tmp_path, monkeypatch, capsys, options,
                                                                 message) -> None:
    from g2tom.reference import devices

    monkeypatch.setattr(devices, "gpu_missing", lambda: "CuPy sees no GPU (0 devices)")
    assert main(["validate", "--quick", "--data-dir", str(tmp_path), *options]) == 2
    err = capsys.readouterr().err
    assert err.strip() == message
    assert not (tmp_path / "validate").exists()


def test_validate_refuses_scenario_options_it_would_ignore(tmp_path, capsys) -> None:
    assert main(["validate", "--quick", "--data-dir", str(tmp_path), "--set", "roughness.sigma=1e-5"]) == 2
    assert "--set is not used" in capsys.readouterr().err
    assert not (tmp_path / "validate").exists()


def test_validate_plan_prints_the_chosen_sets_estimate_and_does_no_work(tmp_path, capsys) -> None:
    assert main(["validate", "--plan", "--realizations", "3", "--loads", "5", "--surface", "random_process",
                 "--workers", "2", "--data-dir", str(tmp_path / "data")]) == 0
    out = capsys.readouterr().out
    assert "random_process surface" in out and "realizations [0, 1, 2]" in out and "5 loads" in out
    assert "estimated" in out and "on 2 worker(s)" in out
    assert not (tmp_path / "data").exists()  # nothing written
    assert main(["validate", "--plan", "--realizations", "0", "--data-dir", str(tmp_path / "data")]) == 2
    assert "--realizations = 0 is out of range" in capsys.readouterr().err


def _force_normalized(vset: scene.ValidationSet) -> np.ndarray:
    from g2tom.stages import contact as contact_stage

    return contact_stage.build(scene.g2tom_scenario(vset, "greenwood", "expected"))["force_normalized"].values


@pytest.mark.parametrize("surface", ["gw", "random_process"])
def test_default_and_quick_sets_meet_the_issue(surface) -> None:
    default, quick = chosen_set(False, surface), chosen_set(True, surface)
    if surface == "gw":
        assert default.mu == pytest.approx(8.262, abs=0.01)  # the paper's mu
    assert default.n_grid == 1024 and default.pixels_per_cell >= 16
    f = _force_normalized(default)  # >= 8 loads from F' <= 0.075 (the paper's delta = 2 sigma: 0.0752) to >= 18
    assert len(default.deltas) >= 8 and round(f[0], 3) <= 0.075 and f[-1] >= 18.0 and np.all(np.diff(f) > 0)
    assert set(default.xi) == {0.5, 0.7} and set(default.lambdas) == {1.0, 5.0} and len(default.realizations) >= 4
    assert (default.clean_error, default.oxide_error) == (0.03, 0.05)
    N, P = ensemble.prior_allocation(default, f, cost.case_costs(default, f))
    counts, pairs = N.max(axis=0), P.max(axis=0)  # more realizations at light loads, fewer at heavy ones
    assert counts[0] > 100 and np.all(np.diff(counts) <= 0) and counts[-1] == len(default.realizations)
    assert pairs[0] > pairs[-1] == len(default.realizations)  # more pairs where the proxy is coarse against the spots
    assert np.all(pairs <= default.max_pairs) and np.all(counts >= pairs)
    assert cost.estimate(default, f, 2, 60.0).wall <= 45 * 60
    assert quick.n_grid == 256 and len(quick.realizations) == 2 and len(quick.deltas) == 2
    assert len(quick.xi) * len(quick.lambdas) == 1
    est = cost.estimate(quick, _force_normalized(quick), 2, 5.0)
    assert est.ensemble > 0 and est.wall <= 60  # --quick exercises part 2 too


#: g2tom's side of a set (``validate._g2tom_side``) and the validated scenario's ensemble
#: (``ensemble.model_ensemble``), as ``tiny_run`` computed them, by their arguments.
_G2TOM_ANSWERS: dict = {}


def _remembering(monkeypatch, reuse: bool) -> None:
    """Store g2tom's side and the model's ensemble of each set computed from now on in
    :data:`_G2TOM_ANSWERS`; with ``reuse``, answer a set stored there from the store (a deep copy)
    instead of computing it again. Both are deterministic and no full-field case depends on them: the
    tests that read them back are about the cases (resuming, running them on a cluster)."""
    import copy

    from g2tom.reference import validate

    for owner, name in ((validate, "_g2tom_side"), (ensemble, "model_ensemble")):
        real = getattr(owner, name)

        def answer(*args, _real=real, _name=name):
            key = (_name, *args)
            if not (reuse and key in _G2TOM_ANSWERS):
                _G2TOM_ANSWERS[key] = _real(*args)
            return copy.deepcopy(_G2TOM_ANSWERS[key])

        monkeypatch.setattr(owner, name, answer)


@pytest.fixture(scope="module")
def tiny_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("validate")
    log = io.StringIO()
    with pytest.MonkeyPatch.context() as patch:
        _remembering(patch, reuse=False)  # computed here, once
        run_validation(TINY, out, stream=log, draw=figure)
    return out, log.getvalue()


@pytest.fixture
def g2tom_once(tiny_run, monkeypatch) -> None:
    """g2tom's side and the model's ensemble of ``tiny_run``'s set read back, not computed again."""
    _remembering(monkeypatch, reuse=True)


def test_outputs_are_labelled_and_consistent(tiny_run) -> None:
    out, log = tiny_run
    # the plan comes first (cases, grids, estimate), then g2tom, then part 1's cases, then part 2's rounds
    assert log.index("validate: part 1 (exactness per surface, paired)") < log.index("validate: estimated")
    assert log.index("part 2 (the default's ensemble") < log.index("validate: estimated") < log.index("g2tom done")
    assert log.index("g2tom done") < log.index("part 1: 0 of 6 cases already stored") < log.index("case 1/6")
    assert log.index("case 6/6") < log.index("part 2 round 1")
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
    assert f"g2tom's default discretization ({ds.attrs['default_discretization']}" in first
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


def test_part_2_compares_the_ensembles_at_equal_force_with_combined_errors(tiny_run) -> None:
    out, _ = tiny_run
    ds = xr.open_dataset(out / "validate.nc")
    P = ds.sizes["realization"]
    assert np.all(ds["ensemble_count_clean"].values >= P) and np.all(ds["ensemble_count"].values >= P)
    assert ds["ensemble_count_clean"].values.max() <= TINY.max_ensemble
    for name in ("ensemble_ratio_clean", "ensemble_ratio_clean_standard_error", "ensemble_reference_clean",
                 "ensemble_model_clean"):
        assert np.all(np.isfinite(ds[name].values)), name
    np.testing.assert_allclose(ds["ensemble_ratio_clean"].values,
                               ds["ensemble_model_clean"].values / ds["ensemble_reference_clean"].values, rtol=1e-12)
    np.testing.assert_allclose(ds["ensemble_ratio_clean_standard_error"].values,
                               np.hypot(ds["ensemble_model_clean_standard_error"].values,
                                        ds["ensemble_reference_clean_standard_error"].values), rtol=1e-12)
    np.testing.assert_allclose(ds["ensemble_ratio_standard_error"].values,
                               np.hypot(ds["ensemble_model_standard_error"].values,
                                        ds["ensemble_reference_standard_error"].values), rtol=1e-12)
    pairs = ds["ensemble_pairs"].values  # part 1's realizations, then part 2's added ones (at most max_pairs)
    assert np.all(pairs >= P) and np.all(pairs <= TINY.max_pairs)
    np.testing.assert_array_equal(ds["resistance_pairs_clean"].values[:P], ds["resistance_reference_clean"].values)
    for k in range(ds.sizes["load"]):  # the pairs' share: the stored proxies and pairs give it again
        proxy = ds["resistance_ensemble_clean"].isel(load=k).values[:int(ds["ensemble_count_clean"][k])]
        exact = ds["resistance_pairs_clean"].isel(load=k).values[:pairs[k]]
        assert np.all(np.isfinite(exact) | np.isposinf(exact))
        again = statistics.two_phase_log_mean(proxy, exact)
        stored = float(ds["ensemble_reference_clean_pairs_standard_error"][k])
        assert stored == pytest.approx(again.pairs_error, rel=1e-12) or np.isnan(stored) and np.isnan(again.pairs_error)
    f = ds["force_normalized"].values
    np.testing.assert_allclose(ds["ensemble_target_clean"].values, [statistics.target(x, False) for x in f])
    # part 2's full-field cases are solved at g2tom's force, as part 1's: equal force, no interpolation
    records = [json.loads(path.read_text()) for path in (out / "cases").glob("e_*.json")]
    assert records, "part 2 solved no full-field case"
    for rec in records:
        assert rec["ensemble"] and rec["n"] == TINY.ensemble_grid
        assert rec["force"] == pytest.approx(float(ds["force"].values[rec["load"]]), rel=1e-9)
    text = (out / "validate.md").read_text()
    assert "### Part 2: the default's ensemble" in text and "| F (N) | F' | N full field (P pairs) |" in text
    first = text.split("\n\n")[1]  # the first lines, before the first blank one: both parts' flags
    assert "Part 2: the ensemble of" in first


def test_log_standard_error_against_a_bootstrap() -> None:
    from g2tom.fitting.ensemble import log_standard_error

    rng = np.random.default_rng(5)
    ratios = np.exp(rng.normal(0.05, 0.3, size=40))
    means = [np.mean(np.log(rng.choice(ratios, ratios.size))) for _ in range(4000)]
    assert log_standard_error(ratios) == pytest.approx(np.std(means), rel=0.08)
    # open circuits (inf), NaN and zero are left out; fewer than two values: NaN
    padded = np.concatenate([ratios, [np.inf, np.nan, 0.0]])
    assert log_standard_error(padded) == log_standard_error(ratios)
    assert np.isnan(log_standard_error(np.array([1.2, np.inf])))


def test_a_rerun_resumes_from_the_stored_cases(tiny_run, g2tom_once) -> None:
    out, _ = tiny_run
    before = xr.open_dataset(out / "validate.nc").load()
    damaged = out / "cases" / f"{cases.Case(1, 0, TINY.n_grid, True).name}.json"
    damaged.write_text("{ truncated")
    log = io.StringIO()
    run_validation(TINY, out, stream=log, draw=figure)
    text = log.getvalue()
    assert "part 1: 5 of 6 cases already stored, 1 to run" in text and "case 1/1 r1_load0_n96" in text
    after = xr.open_dataset(out / "validate.nc").load()
    np.testing.assert_allclose(after["resistance_reference"].values, before["resistance_reference"].values, rtol=1e-12)
    assert "part 2: 0 of" not in text and "to run (~0 s)" in text  # part 2's cases all read back
    assert json.loads(damaged.read_text())["key"]  # rewritten whole
    # another force (another set) does not reuse the stored case
    case = cases.Case(0, 0, TINY.n_grid, True)
    source_key = json.loads((out / "cases" / f"{case.name}.json").read_text())["key"]
    assert cases.load_case(out / "cases" / f"{case.name}.json", source_key) is not None
    assert cases.load_case(out / "cases" / f"{case.name}.json", "0" * 16) is None


def test_a_combination_g2tom_refuses_is_nan_and_named(monkeypatch) -> None:
    from g2tom.config import ConfigError
    from g2tom.reference import validate

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
    from g2tom.physics.surface_spectrum import summit_parameters
    from g2tom.reference import surfaces

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
    from g2tom.reference.scene import random_process_set

    vset = dataclasses.replace(random_process_set(TINY, rms=20e-6), convergence_grid=0,  # 48^2 cannot hold the band
                               ensemble_grid=96, discretizations=("expected", "asperities"))  # its asperities are not known
    paths = run_validation(vset, tmp_path, stream=io.StringIO())
    text = paths[1].read_text()
    assert "self-affine" in text and "summit statistics" in text
    with xr.open_dataset(paths[0]) as ds:
        assert ds.attrs["scene_surface"] == "random_process"
        assert np.isfinite(ds["resistance_reference_clean"].values).any()


def test_surface_asperities_are_the_reference_surfaces_own_tips() -> None:
    from g2tom.reference import surface_spots, surfaces

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
    from g2tom.reference.scene import random_process_set

    vset = TINY if surface == "gw" else random_process_set(TINY, rms=20e-6)
    n = vset.n_grid
    whole = scene.rough_sphere(vset, 1, n)
    half = scene.rough_sphere(vset, 1, n // 2, vset.side / 2)  # the same pixels, the centre of the window
    np.testing.assert_allclose(half, whole[n // 4: 3 * n // 4, n // 4: 3 * n // 4], rtol=0, atol=1e-12 * vset.sigma)
    with pytest.raises(ValueError, match="side = .* is out of range"):
        scene.rough_sphere(vset, 1, n, 1.01 * vset.side)


def test_a_case_window_holds_its_contact_and_grows_when_too_small() -> None:
    from g2tom.reference import window

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

    import g2tom.reference.validate as validate

    monkeypatch.setattr(validate, "run_validation", record)
    assert main(["validate", "--quick", "--no-progress", "--realizations", "2", "--data-dir", str(tmp_path)]) == 0
    assert seen["progress"] is False and seen["vset"].realizations == (0, 1) and seen["vset"].n_grid == 256


def test_steps_and_part2_precision_reach_the_set_and_bad_values_exit_2(tmp_path, monkeypatch, capsys) -> None:
    full = chosen_set(False, "random_process")
    vset = chosen_set(False, "random_process", steps=(5, 4),
                      precision=Part2Precision(standard_error=(0.01, 0.02), max_ensemble=1024, max_pairs=64,
                                               model_realizations=4096))
    assert vset.deltas == full.deltas[3:5]  # the set's 4th and 5th steps, lightest first, whatever the order given
    assert (vset.clean_error, vset.oxide_error, vset.max_ensemble, vset.max_pairs, vset.model_realizations) == (
        0.01, 0.02, 1024, 64, 4096)
    assert dataclasses.replace(vset, deltas=full.deltas, clean_error=0.03, oxide_error=0.05, max_ensemble=512,
                               max_pairs=24, model_realizations=1024) == full  # nothing else changed
    assert chosen_set(False, loads=3, steps=(3,)).deltas == (-3.0,)  # steps of the --loads set
    bad = ((["--steps", "9"], "--steps = 9 is out of range: must be distinct load steps 1 .. 8"),
           (["--steps", "1,1"], "--steps = 1,1 is out of range"),
           (["--steps", "2.5"], "--steps = '2.5' is not allowed: must be whole load-step numbers"),
           (["--steps", "two"], "--steps = 'two' is not a number"),
           (["--standard-error", "0"], "--standard-error = 0.0 is out of range: must be in [0.0001, 0.5]"),
           (["--standard-error", "nan"], "--standard-error = nan is out of range"),
           (["--standard-error", "0.01,0.6"], "--standard-error = 0.6 is out of range"),
           (["--standard-error", "0.1,0.1,0.1"], "must be CLEAN or CLEAN,OXIDIZED"),
           (["--max-realizations", "1"], "--max-realizations = 1 is out of range: must be 2 .. 10000"),
           (["--max-pairs", "1"], "--max-pairs = 1 is out of range: must be 2 .. 10000"),
           (["--model-realizations", "8"], "--model-realizations = 8 is out of range: must be 16 .. 100000"))
    for argv, expect in bad:
        assert main(["validate", "--data-dir", str(tmp_path), *argv]) == 2
        err = capsys.readouterr().err
        assert expect in err and err.count("\n") == 1 and "Traceback" not in err, argv
    assert not (tmp_path / "validate").exists()
    assert main(["validate", "--plan", "--surface", "random_process", "--steps", "4,5", "--standard-error", "0.01",
                 "--max-realizations", "1024", "--max-pairs", "64", "--model-realizations", "4096",
                 "--data-dir", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    assert "2 loads delta/sigma [-0.5, -1.25], F' 3.32, 6.1" in out and "contact.surfaces 4096" in out
    assert "standard error of ln R <= 0.01 clean, 0.01 oxidized" in out and "(at most 1024)" in out
    assert "at most 64;" in out and not (tmp_path / "validate").exists()


def test_a_run_of_one_load_step_draws_its_figure_without_warnings(tmp_path) -> None:
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error")  # one F' gave a singular log axis: divide by zero in matplotlib
        paths = run_validation(dataclasses.replace(TINY, deltas=TINY.deltas[1:]), tmp_path, stream=io.StringIO(),
                               draw=figure)
    assert paths[-1].name == "validate.png" and paths[-1].stat().st_size > 0
    assert xr.open_dataset(paths[0]).sizes["load"] == 1


def _same(a: xr.Dataset, b: xr.Dataset) -> None:
    """Every variable but the wall times equal, bit for bit (NaN equal to NaN)."""
    assert set(a.data_vars) == set(b.data_vars)
    for name in a.data_vars:
        if name not in TIMES:
            np.testing.assert_array_equal(a[name].values, b[name].values, err_msg=name)


def test_a_killed_run_resumes_to_the_uninterrupted_result_in_both_parts(tiny_run, g2tom_once, tmp_path,
                                                                         monkeypatch) -> None:
    out, _ = tiny_run
    real = cases.run_case
    calls = []

    def killed_at(n):
        def run(*args, **kwargs):
            calls.append(args[1])
            if len(calls) == n:
                raise KeyboardInterrupt
            return real(*args, **kwargs)
        return run

    monkeypatch.setattr(cases, "run_case", killed_at(3))  # killed in part 1
    with pytest.raises(KeyboardInterrupt):
        run_validation(TINY, tmp_path, stream=io.StringIO())
    assert not calls[-1].ensemble and len(list((tmp_path / "cases").glob("*.json"))) == 2
    calls.clear()
    monkeypatch.setattr(cases, "run_case", killed_at(6))  # part 1's last four, then killed in part 2
    with pytest.raises(KeyboardInterrupt):
        run_validation(TINY, tmp_path, stream=io.StringIO())
    assert calls[-1].ensemble and len(list((tmp_path / "cases").glob("e_*.json"))) == 1
    monkeypatch.setattr(cases, "run_case", real)
    log = io.StringIO()
    run_validation(TINY, tmp_path, stream=log)
    assert "part 1: 6 of 6 cases already stored, 0 to run" in log.getvalue()
    assert "part 2: 1 of" in log.getvalue()
    with xr.open_dataset(out / "validate.nc") as whole, xr.open_dataset(tmp_path / "validate.nc") as resumed:
        _same(whole.load(), resumed.load())


def test_the_standard_error_of_a_ratio_against_a_bootstrap() -> None:
    """Part 2's ratio of two ensembles: the model's (plain) over the full field's (two-phase: a proxy on N
    realizations corrected by the paired exact values on the first P), against resampling both."""
    rng = np.random.default_rng(11)
    M, N, P = 100, 200, 40
    model = np.exp(rng.normal(0.1, 0.2, M))
    surface = rng.normal(0.0, 0.3, N)  # each realization's own scatter, which its proxy and its full field share
    proxy = np.exp(surface + 0.04)  # a proxy with an offset (the pairs remove it)
    exact = np.exp(1.5 * surface[:P] + rng.normal(0.0, 0.1, P))  # differences correlated with the proxy
    m, f = statistics.log_mean(model), statistics.two_phase_log_mean(proxy, exact)
    error = statistics.ratio_error(m, f)
    boot = []
    for _ in range(4000):
        im, ip, iq = rng.integers(0, M, M), rng.integers(0, P, P), rng.integers(P, N, N - P)
        d = np.concatenate([proxy[ip], proxy[iq]])  # the pairs resampled as pairs, the rest on their own
        boot.append(statistics.log_mean(model[im]).mean - statistics.two_phase_log_mean(d, exact[ip]).mean)
    # within 5 %: leaving out the pairs' covariance term (11 %) or their own variance (27 %) would fail
    assert error == pytest.approx(np.std(boot), rel=0.05)
    # the pairs remove the proxy's offset: the estimate is the full field's, not the proxy's
    d, e = np.log(proxy), np.log(exact) - np.log(proxy[:P])
    assert f.mean == pytest.approx(np.mean(d) + np.mean(e), rel=1e-12)
    # the pairs' share: sd of the paired log differences over sqrt(P); none for a plain mean
    assert f.pairs_error == pytest.approx(np.std(e, ddof=1) / np.sqrt(P), rel=1e-12)
    assert np.isnan(m.pairs_error)
    # with N = P it is the plain mean and standard error of the exact values
    plain = statistics.two_phase_log_mean(exact, exact)
    assert plain.mean == pytest.approx(np.mean(np.log(exact)), rel=1e-12)
    assert plain.error == pytest.approx(np.std(np.log(exact), ddof=1) / np.sqrt(P), rel=1e-12)
    # open circuits are counted, not averaged; a deterministic answer has no error
    opened = statistics.log_mean(np.array([1.0, 2.0, np.inf, 4.0]))
    assert opened.count == 4 and opened.open_fraction == 0.25 and opened.mean == pytest.approx(np.log(8) / 3)
    assert statistics.log_mean(np.array([3.0]), deterministic=True).error == 0.0


def test_realizations_are_sized_by_the_scatter_and_the_targets_are_the_issues() -> None:
    rng = np.random.default_rng(2)
    wide, narrow = np.exp(rng.normal(0, 0.3, 40)), np.exp(rng.normal(0, 0.03, 40))
    pairs = np.exp(rng.normal(0, 0.005, 4))  # the full field on the first four, close to its proxy

    def count(proxy, exact, error, cap, pairs_cap=4, pair_cost=25.0, prior_sd=None):
        return statistics.allocation(proxy, exact, error, cap, pairs_cap, pair_cost, prior_sd)

    assert 50 < count(wide, wide[:4] * pairs, 0.03, 10_000)[0] < 200  # more where surfaces scatter
    assert count(narrow, narrow[:4] * pairs, 0.03, 10_000) == (4, 4)  # at least part 1's
    # open circuits carry no ln R: with as many open as conducting, twice the realizations
    conducting = count(wide, wide[:4] * pairs, 0.03, 10_000)[0]
    with_open = count(np.concatenate([wide, np.full(40, np.inf)]), wide[:4] * pairs, 0.03, 10_000)[0]
    assert with_open in (2 * conducting - 1, 2 * conducting)
    # at that count (the sample repeated, half of it open) the estimate's error is the target
    grown = np.concatenate([wide, np.full(40, np.inf)] * (with_open // 80 + 1))[:with_open]
    assert statistics.two_phase_log_mean(grown, wide[:4] * pairs).error <= 0.03 * 1.05
    # pairs that scatter more than the error allows, and no more pairs allowed: no count of proxies can help, the cap
    noisy = np.exp(rng.normal(0, 0.3, 4))
    assert count(wide, noisy, 0.03, 77) == (77, 4)
    exact = wide[:4]
    assert count(exact, exact, 0.03, 64)[0] <= 64  # at most the cap
    assert count(np.array([]), np.array([]), 0.03, 1000, prior_sd=0.3) == (100, 1)  # no scatter yet: the prior's
    assert statistics.prior_log_sd(0.075, False) == pytest.approx(0.32)
    assert statistics.prior_log_sd(1.5, True) == pytest.approx(0.42)
    assert statistics.prior_log_sd(100.0, True) == pytest.approx(0.083)  # constant beyond the last point
    assert statistics.prior_pairs_sd(0.01, True) == pytest.approx(0.17)
    assert statistics.prior_pairs_sd(3.0, False) == pytest.approx(0.01)
    for f, clean, oxide in ((0.075, 0.15, np.nan), (0.5, 0.08, np.nan), (1.0, 0.05, 0.10), (2.0, 0.05, 0.10),
                            (5.0, 0.05, 0.07), (18.8, 0.05, 0.07)):
        assert statistics.target(f, False) == pytest.approx(clean)
        assert np.isnan(oxide) and np.isnan(statistics.target(f, True)) or statistics.target(f, True) == pytest.approx(oxide)


def test_proxies_and_pairs_are_allocated_at_least_cost() -> None:
    """Where the proxy and the full field disagree, pairs are added (on the main grid, ``pair_cost``
    times a proxy's cost); the allocation reaches the error and costs no more than the cheapest
    integer (N, P) that does, by brute force."""
    rng = np.random.default_rng(7)
    proxy = np.exp(rng.normal(0, 0.4, 60))
    exact = proxy[:8] * np.exp(rng.normal(0, 0.15, 8))  # the pairs disagree by 0.15 in ln R

    d, e = np.log(proxy), np.log(exact) - np.log(proxy[:8])
    per_proxy, per_pair = np.var(d, ddof=1) + 2 * np.cov(np.log(proxy[:8]), e)[0, 1], np.var(e, ddof=1)

    def variance(n, p):  # the estimate's variance with n proxies and p pairs, from the same moments (arrays too)
        return per_proxy / n + per_pair / p

    # every integer (N, P) with 8 <= P <= 200 and P <= N < 4000, at once (the same sums as one by one)
    a, b = np.arange(4000.0)[None, :], np.arange(8.0, 201.0)[:, None]
    for error, pair_cost in ((0.03, 25.0), (0.03, 4.0), (0.05, 25.0), (0.02, 100.0)):
        n, p = statistics.allocation(proxy, exact, error, 10_000, 200, pair_cost)
        assert 8 <= p <= n and variance(n, p) <= error**2 * (1 + 1e-9)
        with np.errstate(divide="ignore"):
            reaches = (a >= b) & (variance(a, b) <= error**2)
        assert reaches.any()
        best = float(np.min(np.where(reaches, a + pair_cost * b, np.inf)))
        assert n + pair_cost * p <= best * 1.02 + pair_cost  # the continuous optimum rounded up: within a pair
    cheap, dear = (statistics.allocation(proxy, exact, 0.03, 10_000, 200, c) for c in (4.0, 100.0))
    assert cheap[1] > dear[1] > 8 and cheap[0] < dear[0]  # cheaper pairs: more pairs, fewer proxies
    capped = statistics.allocation(proxy, exact, 0.03, 10_000, 30, 4.0)
    assert capped[1] == 30 and variance(*capped) <= 0.03**2 * (1 + 1e-9)  # the pairs' cap, more proxies instead
    capped = statistics.allocation(proxy, exact, 0.03, 300, 200, 25.0)
    assert capped[0] == 300 and variance(*capped) <= 0.03**2 * (1 + 1e-9)  # the proxies' cap, more pairs instead
    assert statistics.allocation(proxy, exact, 0.03, 10_000, 12, 4.0) == (10_000, 12)  # no count can: both caps
    same = proxy[:8].copy()  # the full field equal to its proxy: no pair beyond part 1's
    assert statistics.allocation(proxy, same, 0.03, 10_000, 200, 25.0)[1] == 8


def _bundled_with(model: str) -> str:
    """A bundled scenario of ``contact.model`` (``paper`` first: whichever model the default has, the
    side-by-side scenario has the other)."""
    from g2tom.config import bundled_scenarios
    from g2tom.before_work import load_scenario

    names = ["paper"] + [n for n in ("paper_gt", "paper_discrete") if n in bundled_scenarios()]
    return next(n for n in names if load_scenario(n).contact.model == model)


@pytest.mark.parametrize("model", ["greenwood_tripp", "discrete"])
def test_part_2_validates_the_scenarios_own_model(model) -> None:
    config = _bundled_with(model)
    from g2tom.before_work import load_scenario

    own = load_scenario(config)
    scenario = ensemble.validated_scenario(TINY, config)
    assert (scenario.contact.model, scenario.oxide.spot_rule, scenario.cube.model, scenario.contact.spots) == (
        own.contact.model, own.oxide.spot_rule, own.cube.model, own.contact.spots)
    assert scenario.roughness.sigma == TINY.sigma and scenario.indenter.radius == TINY.radius
    model = ensemble.model_ensemble(TINY, config)
    assert model.resistance.shape[-1] == TINY.model_realizations
    if own.contact.model == "discrete":  # each surface of the pool its own clean resistance
        assert not model.deterministic and model.clean.shape[0] == max(own.contact.surfaces, TINY.model_realizations)
        assert np.unique(model.clean[:, -1]).size > 10
    else:  # Greenwood-Tripp's expected spots: one clean answer
        assert model.deterministic and model.clean.shape[0] == 1
    assert own.contact.model in model.description and own.cube.model in model.description


def test_a_run_on_the_discrete_model_reuses_part_1s_cases(tiny_run, g2tom_once, tmp_path) -> None:
    import shutil

    out, _ = tiny_run
    shutil.copytree(out / "cases", tmp_path / "cases")
    log = io.StringIO()
    config = _bundled_with("discrete")
    paths = run_validation(TINY, tmp_path, stream=log, config=config)
    assert "part 1: 6 of 6 cases already stored, 0 to run" in log.getvalue()  # the full field is the model's own
    with xr.open_dataset(paths[0]) as ds:
        assert ds.attrs["validated_scenario"] == config and "contact.model discrete" in ds.attrs["validated_model"]
        assert ds.attrs["default_discretization"] == "discrete" and ds.attrs["default_model"] == "point"
        assert np.all(ds["ensemble_model_clean_standard_error"].values > 0)  # an ensemble of surfaces
        assert np.all(np.isfinite(ds["ensemble_ratio_clean"].values))


def test_validate_takes_the_global_options_and_refuses_bad_values_before_work(tmp_path, monkeypatch, capsys) -> None:
    import g2tom.reference.validate as validate

    seen = {}

    def record(vset, out, progress=True, config="paper", options=None, **_):
        seen.update(vset=vset, progress=progress, config=config, options=options)
        return []

    monkeypatch.setattr(validate, "run_validation", record)
    other = _bundled_with("discrete" if _bundled_with("greenwood_tripp") == "paper" else "greenwood_tripp")
    assert main(["validate", "--quick", "--no-progress", "--workers", "2", "--config", other,
                 "--data-dir", str(tmp_path)]) == 0
    assert seen["progress"] is False and seen["config"] == other and seen["options"].workers == 2
    assert main(["validate", "--quick", "--data-dir", str(tmp_path)]) == 0  # default: a local cluster on every core
    assert seen["options"].workers == (__import__("os").cpu_count() or 1) and seen["progress"] is True
    capsys.readouterr()
    for argv, expect in ((["--realizations", "0"], "--realizations = 0 is out of range"),
                         (["--realizations", "1"], "--realizations = 1 is out of range"),
                         (["--surface", "fractal"], "invalid choice: 'fractal'"),
                         (["--workers", "0"], "--workers = 0 is out of range"),
                         (["--scheduler", "nowhere"], "--scheduler 'nowhere'")):
        seen.clear()
        try:
            status = main(["validate", "--data-dir", str(tmp_path / "x"), *argv])
        except SystemExit as exc:  # argparse's refusals (an unknown choice)
            status = exc.code
        assert status == 2, argv
        err = capsys.readouterr().err
        assert err.startswith("g2tom: error:") and expect in err and err.count("\n") == 1, err
        assert not seen  # before any work


def test_plan_validate_prints_both_surfaces_cases_grids_and_estimate(capsys) -> None:
    assert main(["plan", "--validate", "--workers", "2"]) == 0
    out = capsys.readouterr().out
    for surface in ("gw surface", "random_process surface"):
        assert f"validate: {surface}" in out
    assert out.count("validate: part 1 (exactness per surface, paired)") == 2 and "1024^2" in out
    assert out.count("validate: part 2 (the default's ensemble") == 2 and "256^2" in out
    assert out.count("validate: estimated") == 2 and "on 2 worker(s)" in out


def test_cases_on_a_local_cluster_give_the_serial_run(tiny_run, g2tom_once, tmp_path, cluster_address) -> None:
    """The cases on conftest's cluster of two worker processes, reached by its address (--scheduler),
    planned for its two workers (the cluster g2tom starts itself: tests/test_atlas.py, test_signals.py)."""
    from g2tom.compute import ComputeOptions

    out, _ = tiny_run
    log = io.StringIO()
    run_validation(TINY, tmp_path, stream=log, options=ComputeOptions(scheduler=cluster_address, workers=2,
                                                                      progress=False))
    assert "estimated" in log.getvalue() and "on 2 worker(s)" in log.getvalue()
    with xr.open_dataset(out / "validate.nc") as serial, xr.open_dataset(tmp_path / "validate.nc") as cluster:
        _same(serial.load(), cluster.load())


def test_part_one_discrete_rows_take_the_validated_scenarios_spot_rule_and_no_case_depends_on_it(tmp_path) -> None:
    """The discrete rows count oxide by the validated scenario's rule (segment for paper; disc
    where the scenario has none of disc and segment), and the rule shapes no full-field case: the
    stored cases serve either rule."""
    from g2tom.reference import discrete_spots
    from g2tom.scene import FieldSource

    assert discrete_spots.with_rule_of(scene.DEFAULT, "paper").spot_rule == "segment"
    assert discrete_spots.with_rule_of(scene.DEFAULT, "paper_gt").spot_rule == "disc"  # centre: disc
    toml = tmp_path / "disc.toml"
    toml.write_text('base = "paper"\nname = "disc"\n[oxide]\nspot_rule = "disc"\n')
    assert discrete_spots.with_rule_of(scene.DEFAULT, str(toml)).spot_rule == "disc"
    vset = scene.QUICK
    source = FieldSource.of(scene.g2tom_scenario(vset, vset.models[0], vset.discretizations[0]))
    case = cases.plan_cases(vset)[0]
    keys = {cases.case_key(dataclasses.replace(vset, spot_rule=rule), case, 1.0, source) for rule in ("disc", "segment")}
    assert len(keys) == 1


def test_a_round_adds_main_grid_pairs_where_the_proxy_and_the_full_field_disagree() -> None:
    """Round 2 on a state whose 256^2-like proxies scatter against the main grid: pairs on the main grid
    (part 1's cases of realizations P ..), proxies covering every pair; none where they agree."""
    vset = dataclasses.replace(scene.DEFAULT, deltas=(2.0, 0.0), xi=(0.7,), lambdas=(5.0,), realizations=tuple(range(4)),
                               max_ensemble=64, max_pairs=16)
    rng = np.random.default_rng(3)
    P, loads = 4, 2
    exact_clean = np.exp(rng.normal(0, 0.3, (P, loads)))
    exact = np.exp(rng.normal(0, 0.3, (1, 1, P, loads)))
    state = ensemble.Part2.empty(vset, exact_clean, exact)
    state.grid_count[:] = 24
    state.grid_clean[:24] = np.exp(rng.normal(0, 0.3, (24, loads)))
    state.grid_clean[:P] = exact_clean  # clean: the proxy equals the full field
    state.grid[0, 0, :24] = np.exp(rng.normal(0, 0.3, (24, loads)))
    state.grid[0, 0, :P, 0] = exact[0, 0, :, 0] * np.exp(rng.normal(0, 0.2, P))  # load 0 oxidized: they disagree
    state.grid[0, 0, :P, 1] = exact[0, 0, :, 1]
    model = ([statistics.LogMean(0.0, 0.005, 100, 0.0)] * loads, [[[statistics.LogMean(0.0, 0.01, 100, 0.0)] * loads]])
    costs = ensemble.CaseCosts(pair=np.full(loads, 25.0), grid=np.ones(loads), stand_in=0.01)
    none = np.zeros(loads, bool), np.zeros((1, 1, loads), bool)
    todo, stand_goal = ensemble.plan_round(vset, state, False, np.array([0.075, 3.5]), model, *none, costs)
    pairs = [c for c in todo if not c.ensemble]
    assert pairs and all(c.load == 0 and c.n == vset.n_grid and c.oxide for c in pairs), [(c.load, c.realization, c.n) for c in pairs]
    assert sorted(c.realization for c in pairs) == list(range(P, P + len(pairs))) and P + len(pairs) <= 16
    top = max(c.realization for c in todo if c.ensemble and c.load == 0)
    assert top + 1 >= P + len(pairs)  # every pair has its proxy
    assert stand_goal == 0
    # the same state with the stand-in at load 0: the stand-in covers the pairs instead
    stand = np.zeros(loads, bool), np.ones((1, 1, loads), bool)
    state.stand_clean[:30], state.stand[:, :, :30] = state.grid_clean[:30], np.nan_to_num(state.grid[:, :, :30], nan=1.0)
    state.stand_in_count = 24
    todo, stand_goal = ensemble.plan_round(vset, state, False, np.array([0.075, 3.5]), model, *stand, costs)
    added = max([c.realization + 1 for c in todo if not c.ensemble and c.load == 0], default=P)
    assert stand_goal >= added


def test_an_open_clean_contact_of_drawn_asperities_is_inf_without_a_warning() -> None:
    """At F' 0.075 no drawn asperity of the quick set touches: the clean R is inf, its interaction part
    NaN, and no RuntimeWarning (inf - inf) reaches the user."""
    import warnings

    vset = dataclasses.replace(scene.QUICK, deltas=(2.0, 0.5))
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        result = scene.g2tom_resistances(vset, "point", "asperities")
    clean = result["resistance_clean"].values
    assert np.isinf(clean[0]) and np.isfinite(clean[1])
