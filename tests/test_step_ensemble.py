"""Per-step ensemble targets (``oxide.step_half_width``): an adaptive cell on discrete spots goes on
past alpha's count at the light steps only, until every fitted step's geometric mean meets the target."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from g2tom.before_work.domains import resolve
from g2tom.compute import ComputeOptions
from g2tom.config import ConfigError
from g2tom.before_work import load_scenario
from g2tom.config.scenario import HASH_NEUTRAL
from g2tom.fitting import ensemble
from g2tom.fitting.control_variate import controlled_mean
from g2tom.stages import contact, cube, fits, oxide
from g2tom.stages.cube_rounds import RULE_MARGIN, stopping_rule
from tests.test_discrete_stages import DISCRETE

QUIET = ComputeOptions(progress=False)
STEP_TARGET = 0.06
ADAPTIVE = {**DISCRETE, "oxide.spot_rule": "disc", "oxide.ensemble": "adaptive", "oxide.min_realizations": 20,
            "compute.oxide_batch": 7, "oxide.max_realizations": 600, "oxide.target_half_width": 0.3,
            "fits.control_variate": "clean_share"}


@pytest.fixture(scope="module")
def scene():
    return resolve(load_scenario("paper", {**ADAPTIVE, "oxide.step_half_width": STEP_TARGET}))


@pytest.fixture(scope="module")
def inputs(scene):
    return contact.build(scene, QUIET), oxide.build(scene, QUIET)


@pytest.fixture(scope="module")
def stepped(scene, inputs):
    return cube.build(scene, *inputs, QUIET)


@pytest.fixture(scope="module")
def plain(scene, inputs):
    """The same scene without the step target (alpha's counts only)."""
    off = dataclasses.replace(scene, oxide=dataclasses.replace(scene.oxide, step_half_width=0.0))
    return off, cube.build(off, *inputs, QUIET)


def test_light_steps_go_on_until_every_fitted_step_meets_the_target(scene, stepped, plain):
    counts = stepped["step_realizations"].transpose("xi", "lambda", "delta").values
    alpha = stepped["n_realizations"].transpose("xi", "lambda").values
    np.testing.assert_array_equal(alpha, plain[1]["n_realizations"].transpose("xi", "lambda").values)
    assert np.all(counts >= alpha[..., None]) and np.all(np.diff(counts, axis=-1) <= 0)
    assert counts.max() > alpha.max()  # the light steps needed more
    assert stepped.sizes["realization"] == counts.max()
    rule = stopping_rule(scene, stepped["force"].values, stepped["force_normalized"].values)
    resistance = stepped["resistance"].transpose("xi", "lambda", "delta", "realization").values
    share = stepped["clean_share"].transpose("xi", "lambda", "delta", "realization").values
    expected = stepped["clean_share_expected"].transpose("xi", "lambda").values
    conducting = stepped["n_conducting"].transpose("xi", "lambda", "delta", "realization").values
    limit = RULE_MARGIN * STEP_TARGET
    for z, a in np.ndindex(alpha.shape):
        for j in range(counts.shape[-1]):
            n = counts[z, a, j]
            assert not np.isnan(resistance[z, a, j, :n]).any() and np.isnan(resistance[z, a, j, n:]).all()
            assert np.all(conducting[z, a, j, n:] == -1)
        own = []
        for j in rule["steps"]:
            n = counts[z, a, j]
            width = np.sinh(ensemble.prefix_controlled_half_width(
                resistance[z, a, j : j + 1, :n], share[z, a, j : j + 1, :n], expected[z, a], np.ones(1), rule["z"]))
            own.append(ensemble.stop_count(np.nan_to_num(width, nan=np.inf)[None], limit, alpha[z, a]))
        assert None not in own  # every fitted step met the target (none reached the cap here)
        # each step keeps its own first count meeting it, or a heavier step's larger one
        np.testing.assert_array_equal(counts[z, a, rule["steps"]], np.maximum.accumulate(own[::-1])[::-1])


def test_the_extra_realizations_are_those_of_a_full_ensemble(scene, inputs, stepped):
    """At each step the kept realizations are the fixed ensemble's first ones, computed at every step."""
    counts = stepped["step_realizations"].transpose("xi", "lambda", "delta").values
    n = int(counts.max())
    fixed = dataclasses.replace(scene, oxide=dataclasses.replace(scene.oxide, ensemble="fixed", n_realizations=n,
                                                                 step_half_width=0.0))
    full = cube.build(fixed, *inputs, QUIET)["resistance"].transpose("xi", "lambda", "delta", "realization").values
    got = stepped["resistance"].transpose("xi", "lambda", "delta", "realization").values
    kept = np.arange(n) < counts[..., None]
    np.testing.assert_allclose(got[kept], full[kept], rtol=1e-9)


def test_the_batch_changes_nothing(scene, inputs, stepped):
    other = dataclasses.replace(scene, compute=dataclasses.replace(scene.compute, oxide_batch=50))
    again = cube.build(other, *inputs, QUIET)
    for name in stepped.data_vars:
        np.testing.assert_array_equal(again[name].values, stepped[name].values, err_msg=name)


def test_the_fits_reduce_each_step_over_its_own_realizations(scene, stepped, plain):
    out = fits.build(scene, stepped)
    counts = stepped["step_realizations"].transpose("xi", "lambda", "delta").values
    np.testing.assert_array_equal(out["step_realizations"].transpose("xi", "lambda", "delta").values, counts)
    resistance = stepped["resistance"].transpose("xi", "lambda", "delta", "realization").values
    share = stepped["clean_share"].transpose("xi", "lambda", "delta", "realization").values
    expected = stepped["clean_share_expected"].transpose("xi", "lambda").values
    expected = stepped["clean_share_expected"].transpose("xi", "lambda").values
    mean = out["geometric_mean"].transpose("xi", "lambda", "delta").values
    for z, a, j in np.ndindex(counts.shape):
        n = counts[z, a, j]
        want = controlled_mean(resistance[z, a, j, :n], share[z, a, j, :n], expected[z, a])
        np.testing.assert_allclose(mean[z, a, j], want, rtol=1e-12)
    # the intervals narrow where a step holds more realizations, about as 1 / sqrt(n)
    before = fits.build(plain[0], plain[1])
    ci, ci0 = (f["geometric_mean_normalized_ci"].transpose("xi", "lambda", "delta", "bound").values
               for f in (out, before))
    width, width0 = (np.log(c[..., 1] / c[..., 0]) for c in (ci, ci0))
    alpha = stepped["n_realizations"].transpose("xi", "lambda").values
    more = (counts >= 2 * alpha[..., None]) & np.isfinite(width) & (out["fitted"].values > 0)
    assert more.any()
    ratio = width[more] / width0[more]
    assert np.all(ratio < 0.95) and np.median(ratio) < 0.85


def test_no_step_target_leaves_the_cube_and_every_hash_as_they_were(plain):
    assert HASH_NEUTRAL["oxide.step_half_width"] == 0.0
    assert "step_realizations" not in plain[1]
    assert load_scenario("paper").oxide.step_half_width == 0.0


@pytest.mark.parametrize("override, named", [
    ({"oxide.ensemble": "fixed"}, "oxide.ensemble"),
    ({"contact.model": "greenwood_tripp", "fits.control_variate": "none", "oxide.spot_rule": "centre"},
     "contact.model"),
])
def test_a_step_target_is_refused_where_it_cannot_work(override, named):
    with pytest.raises(ConfigError, match=rf"{named} = .* is not allowed with oxide.step_half_width = 0.06"):
        load_scenario("paper", {**ADAPTIVE, "oxide.step_half_width": STEP_TARGET, **override})


def test_heldout_atlas_scenes_take_the_tighter_step_target():
    from g2tom.atlas.design import AtlasDesign, design_scenes, scene_scenario

    for own, held, wanted in ((0.0, 0.0, 0.0), (0.04, 0.0, 0.04), (0.0, 0.025, 0.025), (0.04, 0.025, 0.025),
                              (0.02, 0.025, 0.02)):
        base = load_scenario("atlas", {"oxide.step_half_width": own, "atlas.heldout_step_half_width": held})
        scenes = design_scenes(AtlasDesign.of(base))
        design, heldout = scenes[0], next(s for s in scenes if s.heldout)
        assert scene_scenario(base, heldout).oxide.step_half_width == wanted
        assert scene_scenario(base, design).oxide.step_half_width == own
    # an ensemble that cannot take one (a fixed one, or of the median) is left as it is
    for other in ({"oxide.ensemble": "fixed"}, {"fits.reduction": "median", "fits.control_variate": "none"}):
        base = load_scenario("atlas", {**other, "oxide.step_half_width": 0.0, "atlas.heldout_step_half_width": 0.025})
        heldout = next(s for s in design_scenes(AtlasDesign.of(base)) if s.heldout)
        assert scene_scenario(base, heldout).oxide.step_half_width == 0.0


@pytest.mark.parametrize("targets", [(0.1, 0.1), (0.06, 0.08)])
def test_the_plan_models_the_light_steps_realizations_within_a_factor_of_two(targets):
    """``g2tom plan``'s model (g2tom.models.discrete_cost.step_fields) from the stage's own
    alpha counts, against the counts the stage reached at the lightest fitted step; off, it adds nothing."""
    from g2tom.models.discrete_cost import expected_counts, step_fields

    alpha_target, step_target = targets
    scene = resolve(load_scenario("paper", {**ADAPTIVE, "oxide.min_realizations": 10, "oxide.max_realizations": 3000,
                                            "oxide.target_half_width": alpha_target,
                                            "oxide.step_half_width": step_target}))
    built = cube.build(scene, contact.build(scene, QUIET), oxide.build(scene, QUIET), QUIET)
    alpha = built["n_realizations"].transpose("xi", "lambda").values
    measured = built["step_realizations"].transpose("xi", "lambda", "delta").values[..., 0]
    touching, candidates = expected_counts(scene)
    modelled, seconds = step_fields(scene, touching, candidates, alpha)
    assert seconds > 0 and np.all(modelled[..., -1] == alpha)
    ratio = modelled[..., 0] / measured
    assert np.all((ratio >= 0.5) & (ratio <= 2.0)), ratio
    off = dataclasses.replace(scene, oxide=dataclasses.replace(scene.oxide, step_half_width=0.0))
    counts, none = step_fields(off, touching, candidates, alpha)
    assert none == 0.0 and np.all(counts == alpha[..., None])
