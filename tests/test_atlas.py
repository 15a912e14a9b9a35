"""The atlas over scenes: one scene per task, resumable, the same bits on any cluster."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

from g2tom.atlas import run as atlas
from g2tom.atlas.design import AtlasDesign, design_scenes
from g2tom.atlas.schema import ATLAS
from g2tom.compute import ComputeOptions
from g2tom.config import ConfigError
from g2tom.before_work import load_scenario
from tests.conftest import SMALL_OVERRIDES

BASE = {**SMALL_OVERRIDES, "oxide.xi": [0.5], "oxide.lambda": [1.0, 5.0], "fits.n_bootstrap": 20,
        "oxide.step_half_width": 0.0}  # a fixed ensemble has no per-step target
DESIGN = AtlasDesign(mu=(4.0, 16.0), Pi=(20.0, 40.0), n_mu=2, n_pi=2, n_heldout=1)
#: Everything but the wall time must agree bit for bit.
COMPARED = ("alpha", "gamma", "alpha_ci", "gamma_ci", "n_realizations", "resistance_normalized",
            "force_normalized", "fitted", "mu", "Pi", "heldout", "n_cells", "alpha_clean", "gamma_clean",
            "curve_coefficients", "curve_order")


def _load(path) -> xr.Dataset:
    with xr.open_dataset(path, engine="netcdf4") as ds:
        return ds.load()


def _same(a: xr.Dataset, b: xr.Dataset) -> None:
    for name in COMPARED:
        np.testing.assert_array_equal(a[name].values, b[name].values, err_msg=name)
    assert list(a["scene"].values) == list(b["scene"].values)


@pytest.fixture(scope="module")
def base():
    return load_scenario("paper_gt", BASE)


@pytest.fixture(scope="module")
def uninterrupted(small_atlas):
    """The small atlas run in one go (conftest's ``small_atlas``: run_atlas on ``base`` and ``DESIGN``)."""
    return _load(small_atlas)


def _copy_of(uninterrupted, data_dir) -> "Path":
    """The uninterrupted run's atlas folder (scenes and atlas.nc) copied into ``data_dir``; its atlas.nc."""
    import shutil
    from pathlib import Path

    shutil.copytree(Path(uninterrupted.encoding["source"]).parent, data_dir / "atlas")
    return data_dir / "atlas" / atlas.ATLAS_FILE


def test_atlas_holds_every_scene_labelled(uninterrupted, base) -> None:
    scenes = design_scenes(DESIGN)
    assert list(uninterrupted["scene"].values) == [s.name for s in scenes]
    np.testing.assert_allclose(uninterrupted["mu"].values, [s.mu for s in scenes], rtol=1e-15)
    assert uninterrupted["heldout"].values.tolist() == [0, 0, 0, 0, 1]
    assert np.all(np.isfinite(uninterrupted["alpha"].values)) and np.all(uninterrupted["alpha"].values > 0)
    # more cells per R* sigma, a wider window
    assert uninterrupted["n_cells"].values[2] > uninterrupted["n_cells"].values[0]
    for name, var in uninterrupted.variables.items():
        if var.dtype.kind not in "OSU":
            assert var.attrs.get("units") is not None and var.attrs.get("long_name"), name
    # the atlas's own variables as its schema declares them (atlas.nc adds the scene dimension)
    for name, declared in ATLAS.items():
        var = uninterrupted[name]
        assert var.dims in (declared.dims, ("scene", *declared.dims)), name
        assert var.attrs["units"] == declared.units and declared.pattern().match(var.attrs["long_name"]), name
    # the scene's slice is the chain run on its own
    alone = atlas.scene_dataset(base, scenes[3])
    np.testing.assert_array_equal(uninterrupted["alpha"].values[3], alone["alpha"].values)


def test_a_resumed_atlas_equals_an_uninterrupted_one(tmp_path, base, uninterrupted, monkeypatch) -> None:
    real = atlas._run_scene
    calls = []

    def dies_at_the_third(*args):
        if len(calls) == 2:
            raise KeyboardInterrupt("killed")
        calls.append(args[1].name)
        return real(*args)

    monkeypatch.setattr(atlas, "_run_scene", dies_at_the_third)
    with pytest.raises(KeyboardInterrupt):
        atlas.run_atlas(base, DESIGN, tmp_path)
    monkeypatch.setattr(atlas, "_run_scene", real)
    written = sorted(p.name for p in (tmp_path / "atlas" / "scenes").glob("*.nc"))
    assert written == ["d00.nc", "d01.nc"] and not (tmp_path / "atlas" / "atlas.nc").exists()
    stamps = {p: p.stat().st_mtime_ns for p in (tmp_path / "atlas" / "scenes").glob("*.nc")}
    ran = []
    monkeypatch.setattr(atlas, "_run_scene", lambda *a: (ran.append(a[1].name), real(*a))[1])
    _same(_load(atlas.run_atlas(base, DESIGN, tmp_path)), uninterrupted)
    assert ran == ["d02", "d03", "h00", "td02"]  # only the scenes not written, then the invariance twin
    assert all(p.stat().st_mtime_ns == t for p, t in stamps.items())


def test_a_scene_left_alone_computes_on_every_worker_asked_for(tmp_path, base, uninterrupted, monkeypatch) -> None:
    """A resumed atlas with one scene left ran it single-threaded while the other workers idled
    (d20: ~2 h on one of two cores); a scene that runs alone now computes with the options given,
    to the same bits."""
    import shutil
    from pathlib import Path

    scenes = Path(uninterrupted.encoding["source"]).parent / "scenes"
    (tmp_path / "atlas").mkdir()
    shutil.copytree(scenes, tmp_path / "atlas" / "scenes", ignore=shutil.ignore_patterns("h00.nc", "td02.nc"))
    seen = []

    def copies(base, scene, data_dir, loading, options):  # the scene's result (thread-independent, tested)
        seen.append((scene.name, options.workers, options.scheduler))
        shutil.copy(scenes / f"{scene.name}.nc", atlas.scene_path(data_dir, scene))
        return scene.name, 0.0

    monkeypatch.setattr(atlas, "_run_scene", copies)
    _same(_load(atlas.run_atlas(base, DESIGN, tmp_path, ComputeOptions(workers=2, progress=False))), uninterrupted)
    assert seen == [("h00", 2, None), ("td02", 2, None)]  # in this process, each on both workers


def test_a_scene_longer_than_the_others_share_runs_alone_first(tmp_path, base, uninterrupted, monkeypatch) -> None:
    """The full atlas's d20 ran ~2 h on one of two cores while the other 32 scenes took ~70 min on
    the other: a scene the plan puts beyond the others' share now runs first, in this process on
    both workers, then the rest one per task; the atlas is the same bits."""
    import dataclasses
    import shutil
    from pathlib import Path

    pytest.importorskip("distributed")
    scenes = Path(uninterrupted.encoding["source"]).parent / "scenes"
    real_plan = atlas.plan_atlas
    monkeypatch.setattr(atlas, "plan_atlas", lambda *a: [
        dataclasses.replace(e, seconds=1000.0 if e.scene.name == "d01" else 10.0) for e in real_plan(*a)])
    seen = []

    def copies(base, scene, data_dir, loading=None, options=None):  # on a worker, `seen` is its own copy
        seen.append((scene.name, options.workers if options else 1))
        atlas.scene_path(data_dir, scene).parent.mkdir(parents=True, exist_ok=True)
        shutil.copy(scenes / f"{scene.name}.nc", atlas.scene_path(data_dir, scene))
        return scene.name, 0.0

    monkeypatch.setattr(atlas, "_run_scene", copies)
    _same(_load(atlas.run_atlas(base, DESIGN, tmp_path, ComputeOptions(workers=2, progress=False))), uninterrupted)
    assert seen == [("d01", 2), ("td02", 2)]  # d01 alone on both workers, the others on the cluster, then the twin


def test_the_schedule_runs_a_scene_alone_only_where_it_saves_time() -> None:
    """By hand: [1000, 10 x 4] on two workers takes 1000 s one scene per worker, 1000 / (2 x 0.95)
    + 20 = 546.3 s with the long one alone first; equal scenes, or one worker, never run alone."""
    from g2tom.atlas.design import ALONE_EFFICIENCY, schedule

    assert ALONE_EFFICIENCY == 0.95
    first, wall = schedule([10.0, 1000.0, 10.0, 10.0, 10.0], 2)
    assert first == 1 and wall == pytest.approx(1000.0 / 1.9 + 20.0, rel=1e-12)
    assert schedule([10.0, 10.0, 10.0, 10.0], 2) == (0, 20.0)
    assert schedule([1000.0, 10.0], 1) == (0, 1010.0)
    # two long scenes on two workers: each on its own worker beats either alone
    assert schedule([1000.0, 1000.0, 10.0], 2) == (0, 1010.0)
    # not the first count that helps but the best: by hand, 0 alone 5000 s, 1 alone 5000 / 1.9 + 3000
    # = 5631.6, 2 alone 8000 / 1.9 + 500 = 4710.5, 3 alone 8400 / 1.9 + 300 = 4721.1
    first, wall = schedule([5000.0, 3000.0, 400.0, 300.0, 200.0, 100.0], 2)
    assert first == 2 and wall == pytest.approx(8000.0 / 1.9 + 500.0, rel=1e-12)


def test_another_configuration_reruns_its_scenes(base, uninterrupted) -> None:
    from pathlib import Path

    data_dir = Path(uninterrupted.encoding["source"]).parents[1]  # run_atlas(base, DESIGN, data_dir)
    other = load_scenario("paper_gt", {**BASE, "oxide.seed": 3})
    assert not atlas._done(other, design_scenes(DESIGN)[0], data_dir)
    assert atlas._done(base, design_scenes(DESIGN)[0], data_dir)


@pytest.mark.stress  # 27 s: a two-process cluster; the cube's own (tests/test_compute.py) stays in make test
def test_two_worker_cluster_gives_the_same_bits(tmp_path, base, uninterrupted) -> None:
    pytest.importorskip("distributed")
    path = atlas.run_atlas(base, DESIGN, tmp_path, ComputeOptions(workers=2, progress=False))
    _same(_load(path), uninterrupted)


def test_a_refused_scene_stops_the_atlas_before_work(tmp_path) -> None:
    bad = load_scenario("paper_gt", {**BASE, "oxide.n_realizations": 10**9})  # fields beyond any memory
    with pytest.raises(ConfigError, match=r"atlas scene d00 \(mu 4, Pi 20\): oxide.n_realizations = 1000000000 is out "
                                          r"of range for this machine"):
        atlas.run_atlas(bad, DESIGN, tmp_path)
    assert not (tmp_path / "atlas").exists()


def test_atlas_surrogate_fitted_on_design_judged_on_heldout(tmp_path, base, uninterrupted) -> None:
    from g2tom.atlas.fit import CURVE, FLOOR, curve_model, fit_atlas
    from g2tom.fitting.atlas_surrogate import AtlasModel

    doc, rows = fit_atlas(uninterrupted)
    assert doc["alpha"]["degree"] == 1  # 8 design points: only degree 1 (5 terms) cross-validates
    assert doc["heldout"]["cells"] == 2 and {r["scene"] for r in rows} == {"h00"}
    assert doc["domain"]["mu"] == pytest.approx([4.0, 16.0]) and doc["domain"]["xi"] == [0.0, 0.5]
    chosen = [r for r in doc["cross_validation"] if r.get("chosen")]
    assert len(chosen) == 1 and chosen[0]["model"] == doc[CURVE]["kind"] and chosen[0]["order"] == doc[CURVE]["order"]
    # chosen for the most cells within at every step, then the lower RMS
    best = max(r["cv_cells_within"] for r in doc["cross_validation"] if "cv_cells_within" in r)
    assert chosen[0]["cv_cells_within"] == best
    assert chosen[0]["cv_rms"] == min(r["cv_rms"] for r in doc["cross_validation"]
                                      if r.get("cv_cells_within") == best and r["cv_rms"] is not None)
    # one row by hand: the grid surrogate and ln(alpha F'^-gamma) against the scene's R'
    r = rows[0]
    models = {p: AtlasModel(doc[p]["transform"], np.array(doc[p]["low"]), np.array(doc[p]["high"]),
                            np.array(doc[p]["powers"]), np.array(doc[p]["coef"])) for p in ("alpha", "gamma")}
    args = (np.array([r["xi"]]), np.array([r["lambda"]]), np.array([r["mu"]]), np.array([r["Pi"]]))
    by_hand = abs(np.log(models["alpha"](*args)[0]) - models["gamma"](*args)[0] * np.log(r["force_normalized"])
                  - np.log(r["resistance_normalized"]))
    assert r["power_law_error"] == pytest.approx(by_hand, rel=1e-12)
    curve = curve_model(doc[CURVE]).log_resistance(*args, np.array([r["force_normalized"]]))[0]
    assert r["error"] == pytest.approx(abs(curve - np.log(r["resistance_normalized"])), rel=1e-12)
    h = int(np.flatnonzero(uninterrupted["scene"].values == "h00")[0])
    ci = uninterrupted["resistance_normalized_ci"].values[h, 0, 0, 0]  # xi 0.5, lambda 1, the lightest step
    assert rows[0]["half_width"] == pytest.approx(np.log(ci[1] / ci[0]) / 2, rel=1e-12)
    assert all(x["within"] == (x["error"] <= max(FLOOR, x["half_width"])) for x in rows)
    steps = int(uninterrupted["fitted"].values[h].sum())
    assert doc["heldout"]["steps"] == 2 * steps
    # every scene spans F' 0.05 .. 20 (its steps chosen in F'), and all its steps are fitted
    force = uninterrupted["force_normalized"].values
    assert np.all(force[:, 0] < 0.05) and np.all(force[:, -1] > 20) and uninterrupted["fitted"].values.all()
    assert doc["domain"]["force_normalized"][0] < 0.05 and doc["domain"]["force_normalized"][1] > 20


def test_the_noise_ceiling_is_the_verdict_on_noisy_copies_of_the_fit(uninterrupted) -> None:
    """The ceiling refits the chosen model on its own predictions plus the design's noise and judges
    it on the held-out scenes' predictions plus theirs: without noise every cell passes; with the
    intervals 30 times wider, fewer; the same seed, the same shares."""
    from g2tom.atlas import fit as F

    doc, _ = F.fit_atlas(uninterrupted)
    ceiling = doc["heldout"]["noise_ceiling"]
    assert ceiling["draws"] == F.CEILING_DRAWS
    assert all(0.0 <= ceiling[k] <= 1.0 for k in ("independent_steps", "correlated_steps"))
    held = uninterrupted["heldout"].values.astype(bool)
    xi_nodes, w_nodes = F._nodes(uninterrupted)
    design, heldout = (F.grid_points(uninterrupted, np.flatnonzero(m)) for m in (~held, held))
    chosen = next(r for r in doc["cross_validation"] if r.get("chosen"))
    curve = F.curve_model(doc[F.CURVE])

    def at(scale: float) -> dict:
        return F.noise_ceiling(chosen, curve, dict(design, half_width=design["half_width"] * scale),
                               dict(heldout, half_width=heldout["half_width"] * scale), xi_nodes, w_nodes, 1.96, draws=6)

    quiet, loud = at(0.0), at(30.0)
    assert quiet["independent_steps"] == quiet["correlated_steps"] == 1.0
    assert loud["independent_steps"] < 1.0 and loud["correlated_steps"] < 1.0
    assert at(30.0) == loud


def test_surrogate_json_and_heldout_csv_are_written(tmp_path, uninterrupted) -> None:
    import json

    from g2tom.atlas.fit import CURVE, FORMAT, write_atlas_surrogate

    target, doc = write_atlas_surrogate(_copy_of(uninterrupted, tmp_path))  # run_atlas(base, DESIGN, tmp_path)'s
    def strict(name: str) -> None:
        raise AssertionError(f"{name} is not JSON")

    assert json.loads(target.read_text(), parse_constant=strict)["format"] == FORMAT == doc["format"]
    lines = (tmp_path / "atlas" / "heldout.csv").read_text().splitlines()
    assert lines[0].startswith("scene,mu,Pi,xi,lambda,force_normalized") and len(lines) == 1 + doc["heldout"]["steps"]
    from g2tom.analysis.report_atlas import atlas_blocks, read_heldout
    from g2tom.atlas.fit import verdict
    from g2tom.fitting.atlas_grid import FRAME_COORDINATES

    with xr.open_dataset(tmp_path / "atlas" / atlas.ATLAS_FILE) as ds:  # the twin: equal groups, other sizes
        assert ds.attrs["invariance_pair"].startswith("d") and ds.attrs["invariance_max_ln_error"] <= 2e-6
    assert (tmp_path / "atlas" / "scenes" / f"t{ds.attrs['invariance_pair'].split()[0]}.nc").is_file()
    # the report's verdict is computed by the code that wrote surrogate.json's, from heldout.csv
    held = doc["heldout"]
    again = verdict(read_heldout(tmp_path / "atlas" / "heldout.csv"))
    for key in ("cells", "cells_within", "steps", "steps_within", "met", "power_law_cells_within"):
        assert again[key] == held[key], key
    assert again["max_ln_error"] == pytest.approx(held["max_ln_error"], rel=1e-12)
    texts = [b.text for b in atlas_blocks(tmp_path) if b.kind == "p"]
    assert any(f"{held['cells_within']} of {held['cells']} (scene, xi, lambda) cells" in t for t in texts)
    assert again["perfect_share_independent"] == pytest.approx(held["perfect_share_independent"], rel=1e-12)
    assert any(f"would pass {100 * held['perfect_share_independent']:.0f} % of the cells" in t for t in texts)
    ceiling = held["noise_ceiling"]
    assert any(f"would pass {100 * ceiling['independent_steps']:.0f} % of the cells (noise independent" in t
               for t in texts)
    assert any("Invariance of the groups" in t for t in texts)
    tables = [b for b in atlas_blocks(tmp_path) if b.kind == "table"]
    chosen = [row for row in tables[0].rows[1:] if row[0].endswith("(chosen)")]  # the cross-validation table
    assert len(chosen) == 1 and chosen[0][0] == f"{doc[CURVE]['kind']} (chosen)"
    assert any(row[0] == "grid" for row in tables[0].rows[1:]) and any("RBF" in row[1] for row in tables[0].rows[1:])
    in_frame = [sum(f"in {words}" in row[1] for row in tables[0].rows[1:]) for words in FRAME_COORDINATES.values()]
    assert in_frame[0] == in_frame[1] > 0  # every candidate in both frames of the groups
    assert len(tables[1].rows) == 1 + 18  # the band by region
    assert [row[0] for row in tables[2].rows[1:]] == ["h00"]
    assert tables[2].rows[1][-1] == f"{held['steps_within']} of {held['steps']}"


def test_cli_runs_fits_and_summarizes(tmp_path, capsys, small_discrete_atlas) -> None:
    """`g2tom atlas` on a small design: conftest's ``small_discrete_atlas`` is that command's run
    (``discrete_atlas_args``: paper's discrete model, BASE, a small fixed pool of 8 surfaces, mu 2 .. 8,
    Pi 10 .. 40), its exit status and standard error kept beside it."""
    import json
    import shutil

    from g2tom.cli.main import main
    from tests.conftest import discrete_atlas_args

    folder = small_discrete_atlas.parents[1]
    status, err = (folder / "atlas_cli.txt").read_text().split("\n", 1)
    assert status == "0", err
    assert err.count("atlas: scene ") == 6 and "held out: " in err and "cells within max(5 %, interval)" in err
    ceiling = json.loads((folder / "atlas" / "surrogate.json").read_text())["heldout"]["noise_ceiling"]
    assert (f"the noise ceiling at this precision {100 * ceiling['independent_steps']:.0f}-"
            f"{100 * ceiling['correlated_steps']:.0f} % of the cells") in err
    assert (folder / "atlas" / "atlas.nc").is_file() and (folder / "atlas" / "surrogate.json").is_file()
    # a second run (on a copy) has nothing left to compute
    shutil.copytree(folder / "atlas", tmp_path / "atlas")
    assert main([*discrete_atlas_args(), "--data-dir", str(tmp_path)]) == 0
    assert "atlas: scene " not in capsys.readouterr().err


def test_the_atlas_runs_on_discrete_asperities(small_discrete_atlas) -> None:
    """The atlas on whatever model its base has: discrete coupled asperities with the disc rule and the
    point model (what `paper` is about to become), on a small design (conftest's ``small_discrete_atlas``:
    mu 2 .. 8, Pi 10 .. 40, which tests/test_predict_chain.py answers with)."""
    from g2tom.atlas.fit import fit_atlas

    # mu <= 8: at mu >= ~16 and Pi <= 40, the discrete solve's first bracket (physics/discrete_contact.py,
    # _rigid_delta) fails by rounding at F' 0.05 on many surfaces where one cap carries the load alone
    ds = _load(small_discrete_atlas)
    assert ds.attrs["contact.model"] == "discrete" and ds.attrs["oxide.spot_rule"] == "disc"
    force = ds["force_normalized"].values
    assert np.all(force[:, 0] < 0.05) and np.all(force[:, -1] > 20)
    assert np.all(np.isfinite(ds["resistance_clean_normalized"].values))
    assert ds.attrs["invariance_max_ln_error"] <= 1e-6  # the twin: equal groups, other dimensions
    doc, rows = fit_atlas(ds)
    assert doc["heldout"]["cells"] == 2 and len(rows) == doc["heldout"]["steps"]


def test_a_scene_computes_on_one_thread_as_the_plan_assumes(monkeypatch) -> None:
    """Each worker runs one scene single-threaded: the discrete contact pool too (two threads per scene on two
    workers oversubscribed the cores and the plan's one-thread seconds)."""
    from g2tom.atlas.design import Scene
    from g2tom.models import discrete_pool

    seen = []
    real = discrete_pool.compute

    def spy(*collections, options, **kwargs):
        seen.append(options.workers)
        return real(*collections, options=options, **kwargs)

    monkeypatch.setattr(discrete_pool, "compute", spy)
    discrete = load_scenario("paper", {**BASE, "contact.model": "discrete", "cube.model": "point", "contact.surfaces": 4})
    ds = atlas.scene_dataset(discrete, Scene("s", 2.0, 20.0, False))
    assert seen == [1] and np.all(np.isfinite(ds["resistance_clean_normalized"].values))


def test_scenes_are_submitted_longest_first_as_the_plan_assumes() -> None:
    from g2tom.atlas.design import Scene, SceneEstimate, wall_seconds

    scenes = [Scene(f"d{k:02d}", 1.0, 5.0, False) for k in range(4)]
    seconds = [10.0, 300.0, 20.0, 300.0]
    estimates = [SceneEstimate(s, 17, 0.0, t, None) for s, t in zip(scenes, seconds)]
    ordered = atlas.longest_first(scenes, estimates)
    assert [s.name for s in ordered] == ["d01", "d03", "d02", "d00"]
    # two workers taking the next scene when free: the plan's wall time is this order's
    loads = [0.0, 0.0]
    for s in ordered:
        loads[loads.index(min(loads))] += seconds[scenes.index(s)]
    assert max(loads) == wall_seconds(seconds, 2) == 320.0


def test_the_verdict_says_what_a_perfect_surrogate_would_pass() -> None:
    """Two steps whose intervals (95 %) are wider than 5 %: a perfect surrogate passes each with chance
    0.95, both with 0.9025 if their noise is independent and 0.95 if it is one; a cell of narrow
    intervals (5 % is ~10 sigma) is passed for sure."""
    from scipy.stats import norm

    from g2tom.atlas.fit import FLOOR, verdict

    z = norm.ppf(0.975)

    def row(scene: str, half: float) -> dict:
        return {"scene": scene, "xi": 0.5, "lambda": 1.0, "mu": 2.0, "Pi": 10.0, "force_normalized": 1.0,
                "error": 0.01, "power_law_error": 0.2, "half_width": half, "noise_sigma": half / z,
                "allowed": max(FLOOR, half), "within": True}

    held = verdict([row("h0", 0.10), row("h0", 0.12), row("h1", 0.01), row("h1", 0.01)])
    assert held["perfect_share_independent"] == pytest.approx((0.95**2 + 1.0) / 2, rel=1e-9)
    assert held["perfect_share_correlated"] == pytest.approx((0.95 + 1.0) / 2, rel=1e-9)
    old = [{k: v for k, v in row("h0", 0.1).items() if k != "noise_sigma"}]  # an older heldout.csv
    assert np.isnan(verdict(old)["perfect_share_independent"])


def test_the_twin_is_measured_as_its_original() -> None:
    """The invariance twin has its original's groups, role and ensemble: on the bundled atlas (held-out
    scenes to 1.25 %, design to 2.5 %) its scenario differs only in sigma and R*, so the check measures
    the invariance, not two ensembles' noise."""
    import dataclasses

    from g2tom.atlas.design import scene_scenario

    base = load_scenario("atlas")
    scenes = design_scenes(AtlasDesign.of(base))
    original, twin = atlas._twin(scenes)
    assert (twin.name, twin.mu, twin.Pi, twin.heldout) == (f"t{original.name}", original.mu, original.Pi, False)
    loading = scene_scenario(base, original).loading
    a, b = scene_scenario(base, original), scene_scenario(atlas.twin_base(base), twin, loading)
    assert b.oxide == a.oxide and b.oxide.target_half_width == base.oxide.target_half_width == 0.025
    assert b.roughness.sigma == 2 * a.roughness.sigma and b.indenter.radius == a.indenter.radius / 2
    assert dataclasses.replace(b, name=a.name, roughness=a.roughness, indenter=a.indenter) == a
