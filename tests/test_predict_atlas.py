"""Eq. 27 for any surface inside the atlas: the atlas surrogate answers, knows its domain, says so."""

from __future__ import annotations

import dataclasses
import json
import math
import shutil
import warnings

import numpy as np
import pytest

from g2tom.atlas import run as atlas
from g2tom.atlas.fit import CURVE, FORMAT_VERSION, curve_doc, write_atlas_surrogate
from g2tom.cli.main import main
from g2tom.config import ConfigError
from g2tom.before_work import load_scenario
from g2tom.predict.atlas import NOT_IN_ATLAS, load_atlas_surrogate, predict_atlas
from g2tom.predict.predictor import ExtrapolationWarning
from g2tom.stages import fits, surrogate
from g2tom.scene import scene_groups
from g2tom.store import write_dataset
from tests.conftest import SMALL_OVERRIDES
from tests.test_atlas import BASE
from tests.test_fits_stage import cli_overrides, synthetic_cube
from tests.test_predict import _rows


@pytest.fixture(scope="module")
def atlas_json(tmp_path_factory, small_atlas):
    """The surrogate of conftest's small atlas (run_atlas on paper_gt with test_atlas's ``BASE`` and
    ``DESIGN``, computed once for the whole run), fitted on a copy of its atlas.nc."""
    folder = tmp_path_factory.mktemp("atlas") / "atlas"
    folder.mkdir()
    target, _ = write_atlas_surrogate(shutil.copy(small_atlas, folder / atlas.ATLAS_FILE))
    return target


def _surface(eta: float):
    """The paper surface with another eta: mu and Pi both scale with eta."""
    paper = load_scenario("paper_gt", BASE)
    return dataclasses.replace(paper, roughness=dataclasses.replace(paper.roughness, eta=eta))


def _force(sur, scenario) -> float:
    lo, hi = sur.domain["force_normalized"]
    return math.sqrt(lo * hi) * scenario.force_scale


def test_answers_inside_the_domain_by_the_formula(atlas_json) -> None:
    sur = load_atlas_surrogate(atlas_json)
    scenario = _surface(1.5e8)  # mu 6.2, Pi 30: inside (4..16, 20..40)
    g = scene_groups(scenario)
    force = _force(sur, scenario)
    result = predict_atlas(sur, scenario, force, 0.5, 3.0)
    args = (np.array([0.5]), np.array([3.0]), np.array([g.mu]), np.array([g.Pi]))
    alpha, gamma = sur.models["alpha"](*args)[0], sur.models["gamma"](*args)[0]
    by_hand = alpha * scenario.resistance_scale * (force / scenario.force_scale) ** -gamma
    assert float(result["resistance_power_law"]) == pytest.approx(by_hand, rel=1e-12)
    f_n = np.array([force / scenario.force_scale])
    curve = float(np.exp(sur.models[CURVE].log_resistance(*args, f_n)[0]))
    assert result.attrs["model"] == "curve"
    assert float(result["resistance"]) == pytest.approx(curve * scenario.resistance_scale, rel=1e-12)
    band = float(sur.band(*args, f_n)[0])  # the regional band where the query is
    assert float(result["surrogate_error"]) == pytest.approx(band, rel=1e-12) and band > 0
    assert float(result["resistance_mean_upper"]) == pytest.approx(float(result["resistance"]) * math.exp(1.959963984540054 * band), rel=1e-12)
    assert float(result["mu"]) == pytest.approx(g.mu) and "atlas surrogate" in result.attrs["answered_by"]
    # another surface inside the domain gets other coefficients
    other = predict_atlas(sur, _surface(1.9e8), _force(sur, _surface(1.9e8)), 0.5, 3.0)
    assert float(other["alpha"]) != pytest.approx(float(result["alpha"]), rel=1e-3)


def test_refuses_outside_the_domain_naming_the_group(atlas_json) -> None:
    sur = load_atlas_surrogate(atlas_json)
    scenario = _surface(6e8)  # mu 24.8, Pi 120
    with pytest.raises(ConfigError, match=r"mu = 24.78\d* lies outside the domain \[4, 16\] of the atlas surrogate"):
        predict_atlas(sur, scenario, _force(sur, scenario), 0.5, 3.0)
    with pytest.warns(ExtrapolationWarning, match="mu = "):
        predict_atlas(sur, scenario, _force(sur, scenario), 0.5, 3.0, extrapolate=True)


def test_cli_the_run_own_for_its_surface_the_atlas_for_others(tmp_path, capsys, atlas_json) -> None:
    from g2tom.before_work.domains import resolve
    from g2tom.predict.predictor import load_surrogate

    small = resolve(load_scenario("paper_gt", SMALL_OVERRIDES))  # the run's own: a 3 x 3 grid
    write_dataset(fits.build(small, synthetic_cube(small, noise=0.2)), tmp_path, "fits", small)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        surrogate.run(small, tmp_path, None)
    (tmp_path / "atlas").mkdir()
    shutil.copy(atlas_json, tmp_path / "atlas" / "surrogate.json")
    sur = load_atlas_surrogate(atlas_json)
    own_range = load_surrogate(tmp_path / "surrogate.json").ranges["force_normalized"]
    lo, hi = max(own_range[0], sur.domain["force_normalized"][0]), min(own_range[1], sur.domain["force_normalized"][1])
    assert lo < hi
    query = ["--force", f"{math.sqrt(lo * hi) * small.force_scale:.6g}", "--xi", "0.5", "--lambda", "3"]
    base = ["predict", "--data-dir", str(tmp_path), *cli_overrides(small), *query]
    assert main(base) == 0
    own = capsys.readouterr()
    assert "answered by the run's own single-scene surrogate" in own.err
    assert main(base + ["--set", "roughness.eta=1.5e8"]) == 0
    other = capsys.readouterr()
    assert "answered by the atlas surrogate" in other.err
    # the same columns, less the single-scene band's components the atlas does not hold
    assert other.out.splitlines()[0].split(",") == [c for c in own.out.splitlines()[0].split(",")
                                                    if not c.startswith(NOT_IN_ATLAS)]
    assert _rows(other.out)[0]["mu"] == pytest.approx(scene_groups(_surface(1.5e8)).mu, rel=1e-9)
    # outside both: refused, naming the atlas's range
    assert main(base + ["--set", "roughness.eta=6e8"]) == 2
    assert "lies outside the domain [4, 16] of the atlas surrogate" in capsys.readouterr().err
    # --surrogate picks the atlas explicitly, by its format
    assert main(base + ["--surrogate", str(atlas_json)]) == 0
    assert "answered by the atlas surrogate" in capsys.readouterr().err
    assert json.loads(atlas_json.read_text())["format"] == "g2tom-atlas-surrogate"


def test_fresh_install_answers_from_the_shipped_atlas(tmp_path, capsys, atlas_json, monkeypatch) -> None:
    import g2tom.predict.atlas as pa

    sur = load_atlas_surrogate(atlas_json)
    scenario = _surface(1.5e8)
    query = ["--force", f"{_force(sur, scenario):.6g}", "--xi", "0.5", "--lambda", "3"]
    argv = ["predict", "--data-dir", str(tmp_path / "empty"), "--set", "roughness.eta=1.5e8",
            *[a for k, v in BASE.items() for a in ("--set", f"{k}={v}")], *query]
    monkeypatch.setattr(pa, "shipped_path", lambda: None)
    assert main(argv) == 2 and "does not exist" in capsys.readouterr().err  # nothing to answer with
    monkeypatch.setattr(pa, "shipped_path", lambda: atlas_json)
    assert main(argv) == 0
    assert f"answered by the atlas surrogate {atlas_json}" in capsys.readouterr().err
    doc = json.loads(atlas_json.read_text())
    assert doc["provenance"]["config_hash"] and "g2tom_commit" in doc["provenance"]


def test_the_band_is_regional(atlas_json) -> None:
    """Light loads and much oxide get their own error; on an oxide node the grid adds nothing,
    between nodes it does."""
    sur = load_atlas_surrogate(atlas_json)
    scenario = _surface(1.5e8)
    lo, hi = sur.domain["force_normalized"]
    light = predict_atlas(sur, scenario, 1.1 * lo * scenario.force_scale, 0.5, 1.0)
    heavy = predict_atlas(sur, scenario, 0.9 * hi * scenario.force_scale, 0.5, 1.0)
    assert float(light["surrogate_error"]) != pytest.approx(float(heavy["surrogate_error"]), rel=1e-6)
    between = predict_atlas(sur, scenario, 0.9 * hi * scenario.force_scale, 0.5, 2.2)
    assert float(between["surrogate_error"]) >= float(heavy["surrogate_error"])
    assert "region" in between.attrs["band"]


def test_a_format_one_surrogate_is_still_read(tmp_path) -> None:
    """The first atlas's surrogate (one polynomial in five logs, one global error; the file shipped
    before issue 31's full run) still answers, with its global band."""
    from g2tom.predict.atlas import shipped_path

    path = shipped_path()
    if path is None or json.loads(path.read_text()).get("format_version", 1) != 1:
        pytest.skip("the shipped atlas surrogate is not of format 1: nothing old to read")
    sur = load_atlas_surrogate(path)
    assert sur.band is None
    paper = load_scenario("paper")
    lo, hi = sur.domain["force_normalized"]
    out = predict_atlas(sur, paper, math.sqrt(lo * hi) * paper.force_scale, 0.5, 5.0)
    assert float(out["surrogate_error"]) == pytest.approx(sur.error) and np.isfinite(float(out["resistance"]))
    newer = json.loads(path.read_text())
    newer["format_version"] = 99
    (tmp_path / "new.json").write_text(json.dumps(newer))
    with pytest.raises(ConfigError, match=f"format_version 99 is newer than this g2tom's {FORMAT_VERSION}: upgrade g2tom"):
        load_atlas_surrogate(tmp_path / "new.json")


def test_a_format_two_surrogate_is_still_read(tmp_path, atlas_json) -> None:
    """A format-2 file (the grid surrogate; shipped before the scene series) answers by its grid."""
    from g2tom.fitting.atlas_grid import fit_grid_tensor, node_coordinates

    doc = json.loads(atlas_json.read_text())
    sur = load_atlas_surrogate(atlas_json)
    z, w = node_coordinates(np.array([0.0, 0.5]), np.array([1.0, 5.0]))
    force = np.tile(np.geomspace(0.05, 20, 6), 4)
    mu, pi = np.repeat([4.0, 16.0, 4.0, 16.0], 6), np.repeat([20.0, 20.0, 80.0, 80.0], 6)
    log_r = (np.log(mu) - 0.5 * np.log(force) + 0.1 * np.log(pi))[:, None, None] + z[None, :, None] + w[None, None, :]
    grid = fit_grid_tensor(z, w, mu, pi, force, log_r, np.full(log_r.shape, 0.01), 1, 1)
    old = {**doc, "format_version": 2, CURVE: curve_doc(grid)}
    (tmp_path / "old.json").write_text(json.dumps(old))
    paper = load_scenario("paper_gt", BASE)
    out = predict_atlas(load_atlas_surrogate(tmp_path / "old.json"), paper, _force(sur, paper), 0.5, 5.0)
    g = scene_groups(paper)
    f_n = _force(sur, paper) / paper.force_scale
    assert float(out["resistance"]) == pytest.approx(
        paper.resistance_scale * np.exp(np.log(g.mu) - 0.5 * np.log(f_n) + 0.1 * np.log(g.Pi) + z[1] + w[1]), rel=1e-9)


def test_1e5_queries_over_10_surfaces_are_answered_each_as_alone(atlas_json) -> None:
    """10^4 queries on each of 10 surfaces in one call per surface (`g2tom bench --only predict` times
    this on the shipped atlas): every answer finite, and equal to the same query asked alone."""
    sur = load_atlas_surrogate(atlas_json)
    rng = np.random.default_rng(0)
    lo, hi = sur.domain["force_normalized"]
    for scenario in [_surface(eta) for eta in np.linspace(1.1e8, 1.9e8, 10)]:
        n = 10_000
        force = np.exp(rng.uniform(np.log(lo), np.log(hi), n)) * scenario.force_scale
        xi, lam = rng.uniform(0.05, 0.5, n), rng.uniform(1.0, 5.0, n)
        out = predict_atlas(sur, scenario, force, xi, lam)["resistance"].values
        assert np.all(np.isfinite(out))
        for i in rng.choice(n, 3, replace=False):
            alone = float(predict_atlas(sur, scenario, force[i], xi[i], lam[i])["resistance"])
            assert out[i] == pytest.approx(alone, rel=1e-12)
