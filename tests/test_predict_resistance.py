"""The one predict call for Python users (issue 32): the surrogate ``g2tom predict`` chooses, from Python."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

import g2tom
from g2tom.config import ConfigError
from g2tom.before_work import load_scenario
from g2tom.predict.atlas import NOT_IN_ATLAS, load_atlas_surrogate, shipped_path
from g2tom.predict.predictor import load_surrogate, predict
from g2tom.scene import scene_groups
from g2tom.stages import fits, surrogate
from g2tom.store import write_dataset
from tests.conftest import SMALL_OVERRIDES
from tests.test_fits_stage import synthetic_cube


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory):
    """A data directory holding a small run's own surrogate (synthetic cube, the paper's surface)."""
    from g2tom.before_work.domains import resolve

    data = tmp_path_factory.mktemp("run")
    small = resolve(load_scenario("paper_gt", SMALL_OVERRIDES))
    write_dataset(fits.build(small, synthetic_cube(small, noise=0.2)), data, "fits", small)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        surrogate.run(small, data, None)
    return data, small


def _shared_force(data, scenario) -> float:
    """A force inside both the run's surrogate's and the shipped atlas's fitted F' ranges, N."""
    own = load_surrogate(data / "surrogate.json").ranges["force_normalized"]
    atlas = load_atlas_surrogate(shipped_path()).domain["force_normalized"]
    lo, hi = max(own[0], atlas[0]), min(own[1], atlas[1])
    assert lo < hi
    return math.sqrt(lo * hi) * scenario.force_scale


def test_readme_case_other_sigma_is_answered_by_the_atlas(run_dir) -> None:
    data, small = run_dir
    scenario = load_scenario("paper_gt", {"roughness.sigma": 15e-6})
    force = _shared_force(data, scenario)
    # the run's own surrogate alone refuses this surface (the README's snippets before issue 32)
    with pytest.raises(ConfigError, match="mu"):
        predict(load_surrogate(data / "surrogate.json"), scenario, force, 0.5, 3.0)
    result = g2tom.predict_resistance(scenario, force=[force, 1.5 * force], xi=0.5, lam=3.0, data_dir=data)
    assert result.attrs["answered_by"].startswith("the atlas surrogate")
    assert str(shipped_path()) in result.attrs["answered_by"]
    assert not set(NOT_IN_ATLAS) & set(result.data_vars)
    assert float(result["mu"][0]) == pytest.approx(scene_groups(scenario).mu, rel=1e-12)
    # heavier load, lower resistance; the band holds the answer
    r = np.asarray(result["resistance"])
    assert r[1] < r[0] and np.all(result["resistance_mean_lower"] < r) and np.all(r < result["resistance_mean_upper"])
    # the same call by the scenario's name and overrides, through g2tom.predict
    from g2tom.predict import predict_resistance

    again = predict_resistance("paper", force, 0.5, 3.0, data_dir=data, overrides={"roughness.sigma": 15e-6})
    np.testing.assert_allclose(np.asarray(again["resistance"]).ravel(), r[:1], rtol=1e-14)


def test_the_run_own_surface_is_answered_by_its_own_surrogate(run_dir) -> None:
    data, small = run_dir
    force = _shared_force(data, small)
    result = g2tom.predict_resistance(small, force, 0.5, 3.0, data_dir=data)
    assert result.attrs["answered_by"].startswith("the run's own single-scene surrogate")
    by_hand = predict(load_surrogate(data / "surrogate.json"), small, force, 0.5, 3.0)
    assert float(result["resistance"]) == pytest.approx(float(by_hand["resistance"]), rel=1e-14)
    assert "open_probability" in result
    # the paper scenario by name has the same surface: also the run's own
    named = g2tom.predict_resistance("paper", force, 0.5, 3.0, data_dir=data, model="power_law")
    assert named.attrs["answered_by"].startswith("the run's own") and named.attrs["model"] == "power_law"


def test_a_height_map_is_measured_like_predict_roughness(run_dir, tmp_path) -> None:
    from g2tom.predict.answer import surface_scenario
    from g2tom.predict.domain import with_measured_roughness

    rng = np.random.default_rng(3)
    heights = np.fft.irfft2(np.fft.rfft2(rng.standard_normal((128, 128))) * 0.05, s=(128, 128)) * 1e-5
    path = tmp_path / "map.npy"
    np.save(path, heights)
    measured = surface_scenario(path, pixel_size=1e-6)
    assert measured == with_measured_roughness(load_scenario("paper"), path, 1e-6)  # the default scene
    with pytest.raises(ConfigError, match="pixel_size"):
        surface_scenario("paper", pixel_size=1e-6)
    with pytest.raises(ConfigError, match="no_such_scenario"):
        g2tom.predict_resistance("no_such_scenario", 500.0, 0.5, 3.0, data_dir=run_dir[0])
