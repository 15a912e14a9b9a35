"""The atlas's design over (mu, Pi): scenes, held-out draws, scene scenarios and the plan."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from g2tom.atlas.design import AtlasDesign, design_scenes, format_atlas_plan, plan_atlas, scene_scenario, scene_seed
from g2tom.config import AUTO, ConfigError
from g2tom.before_work import load_scenario
from g2tom.physics.groups import groups
from tests.conftest import SMALL_OVERRIDES


def test_the_atlas_scenario_has_36_design_and_8_heldout_scenes() -> None:
    scenes = design_scenes(AtlasDesign.of(load_scenario("atlas")))
    assert sum(not s.heldout for s in scenes) == 36 and sum(s.heldout for s in scenes) == 8
    design = [s for s in scenes if not s.heldout]
    assert sorted({s.mu for s in design}) == pytest.approx(np.geomspace(1.0, 50.0, 6), rel=1e-12)
    assert sorted({s.Pi for s in design}) == pytest.approx(np.geomspace(5.0, 320.0, 6), rel=1e-12)


def test_default_design_covers_engineering_surfaces() -> None:
    scenes = design_scenes(AtlasDesign())
    design = [s for s in scenes if not s.heldout]
    held = [s for s in scenes if s.heldout]
    assert len(design) == 25 and len(held) == 6
    assert sorted({s.mu for s in design}) == pytest.approx(np.geomspace(1.0, 50.0, 5), rel=1e-12)
    assert sorted({s.Pi for s in design}) == pytest.approx(np.geomspace(5.0, 320.0, 5), rel=1e-12)
    step = np.log([50.0, 320.0 / 5.0]) / 4
    for h in held:
        assert 1.0 <= h.mu <= 50.0 and 5.0 <= h.Pi <= 320.0
        gaps = np.abs(np.log([[h.mu / d.mu, h.Pi / d.Pi] for d in design])) / step
        assert np.all(np.any(gaps >= 0.25 - 1e-12, axis=1)), h  # no design node within a quarter step


def test_heldout_draws_follow_the_seed() -> None:
    a, b = design_scenes(AtlasDesign()), design_scenes(AtlasDesign())
    c = design_scenes(AtlasDesign(seed=1))
    assert a == b
    assert [s for s in a if s.heldout] != [s for s in c if s.heldout]
    assert [s for s in a if not s.heldout] == [s for s in c if not s.heldout]


@pytest.mark.parametrize("kwargs, message", [
    ({"n_mu": 0}, "atlas n_mu = 0 is out of range: must be an integer >= 2"),
    ({"n_pi": 1}, "atlas n_pi = 1 is out of range"),
    ({"n_heldout": 0}, "atlas n_heldout = 0 is out of range"),
    ({"mu": (5.0, 1.0)}, "atlas mu = (5.0, 1.0) is out of range"),
    ({"Pi": (0.0, 10.0)}, "atlas Pi = (0.0, 10.0) is out of range"),
    ({"mu": (1.0, math.inf)}, "atlas mu"),
])
def test_bad_designs_are_refused(kwargs, message) -> None:
    with pytest.raises(ConfigError, match=message.replace("(", r"\(").replace(")", r"\)")):
        AtlasDesign(**kwargs)


def test_scene_scenario_has_the_scene_groups() -> None:
    base = load_scenario("paper_gt")
    for scene in design_scenes(AtlasDesign())[::5]:
        s = scene_scenario(base, scene)
        g = groups(s.roughness.sigma, s.roughness.eta, s.roughness.beta, s.indenter.radius)
        assert (g.mu, g.Pi) == pytest.approx((scene.mu, scene.Pi), rel=1e-12)
        assert s.roughness.sigma == base.roughness.sigma and s.indenter.radius == base.indenter.radius
        assert s.contact.window == AUTO and s.material == base.material


def test_every_scene_draws_its_own_streams() -> None:
    """Scenes of other groups get other root seeds (independent fields and asperity pools, so the
    design's sampling errors average out across scenes instead of being one shared error); the same
    groups the same seed, whatever the scene's name or role; the base's seed moves them all."""
    base = load_scenario("atlas")
    scenes = design_scenes(AtlasDesign.of(base))
    seeds = [scene_seed(base.oxide.seed, s) for s in scenes]
    assert len(set(seeds)) == len(scenes) and all(0 <= s < 2**32 for s in seeds)
    # the scene's scenario takes that seed: a design scene, a held-out one and the last (the seed does not
    # depend on the approaches, so the base's stand in for the scene's own F' search, ~1 s a scene;
    # every scene with its own approaches: test_every_scene_scenario_takes_its_own_seed, `make stress`)
    some = [0, next(i for i, s in enumerate(scenes) if s.heldout), len(scenes) - 1]
    assert [scene_scenario(base, scenes[i], base.loading).oxide.seed for i in some] == [seeds[i] for i in some]
    first = scenes[0]
    assert scene_seed(base.oxide.seed, dataclasses.replace(first, name="other", heldout=True)) == seeds[0]
    assert scene_seed(base.oxide.seed + 1, first) != seeds[0]
    assert scene_seed(base.oxide.seed, dataclasses.replace(first, mu=first.mu * (1 + 1e-5))) != seeds[0]
    # the streams themselves differ: the first field of two scenes at lambda 23
    from g2tom.physics.oxide_band import field_stream
    draws = [field_stream(s, 23.0, 0).random(4) for s in seeds[:2]]
    assert not np.allclose(*draws)


@pytest.mark.stress
def test_every_scene_scenario_takes_its_own_seed() -> None:
    """The sweep behind test_every_scene_draws_its_own_streams: all 44 scenes of the bundled atlas, each
    with its own approaches (~1 s a scene)."""
    base = load_scenario("atlas")
    scenes = design_scenes(AtlasDesign.of(base))
    seeds = [scene_scenario(base, s).oxide.seed for s in scenes]
    assert len(set(seeds)) == len(scenes) and seeds == [scene_seed(base.oxide.seed, s) for s in scenes]


def test_heldout_scenes_are_measured_to_the_tighter_target() -> None:
    """A held-out scene's ensemble stops at atlas.heldout_half_width where that is tighter than the
    base's target; a design scene keeps the base's (and so its configuration hash)."""
    base = load_scenario("atlas")
    assert (base.oxide.target_half_width, base.atlas.heldout_half_width) == (0.025, 0.0125)
    scenes = design_scenes(AtlasDesign.of(base))
    design, held = scenes[0], next(s for s in scenes if s.heldout)
    own = lambda scene: dataclasses.replace(base.oxide, seed=scene_seed(base.oxide.seed, scene))  # noqa: E731
    assert scene_scenario(base, design).oxide == own(design)
    tight = scene_scenario(base, held).oxide
    assert tight.target_half_width == 0.0125 and tight == dataclasses.replace(own(held), target_half_width=0.0125,
                                                                              step_half_width=0.025)
    looser = load_scenario("atlas", {"atlas.heldout_half_width": 0.1})
    assert scene_scenario(looser, held).oxide.target_half_width == 0.025  # never looser than the design


def test_heldout_scenes_grow_their_pools_to_the_tighter_target() -> None:
    """The bundled atlas grows every scene's discrete pool to 2 % (contact.pool_half_width);
    atlas.heldout_pool_half_width grows a held-out scene's further, a design scene keeps the base's
    contact section, and so its configuration hash."""
    bundled = load_scenario("atlas")
    assert (bundled.contact.pool_half_width, bundled.atlas.heldout_pool_half_width) == (0.02, 0.02)
    assert (bundled.oxide.step_half_width, bundled.atlas.heldout_step_half_width) == (0.04, 0.025)
    base = load_scenario("atlas", {"contact.pool_half_width": 0.0})
    scenes = design_scenes(AtlasDesign.of(base))
    design, held = scenes[0], next(s for s in scenes if s.heldout)
    assert scene_scenario(bundled, design).contact.pool_half_width == 0.02
    assert scene_scenario(base, held).contact.pool_half_width == 0.02
    assert scene_scenario(base, design).contact.pool_half_width == 0.0
    without = load_scenario("atlas", {"contact.pool_half_width": 0.0, "atlas.heldout_pool_half_width": 0.0})
    assert scene_scenario(without, design).config_hash("fits") == scene_scenario(base, design).config_hash("fits")
    assert scene_scenario(without, held).contact.pool_half_width == 0.0
    from g2tom.atlas.cost import scene_cost

    held_cost, design_cost = scene_cost(scene_scenario(base, held)), scene_cost(scene_scenario(base, design))
    assert held_cost.surfaces_lightest > held_cost.surfaces and design_cost.surfaces_lightest == design_cost.surfaces
    for own, wanted in ((0.01, 0.01), (0.05, 0.02)):  # the tighter of the two where both are set
        both = load_scenario("atlas", {"contact.pool_half_width": own})
        assert scene_scenario(both, held).contact.pool_half_width == wanted
        assert scene_scenario(both, design).contact.pool_half_width == own


def test_plan_grows_with_pi_and_reports_refusals() -> None:
    base = load_scenario("paper_gt", SMALL_OVERRIDES)
    design = AtlasDesign(mu=(2.0, 20.0), Pi=(10.0, 40.0), n_mu=2, n_pi=2, n_heldout=1)
    est = {e.scene.name: e for e in plan_atlas(base, design)}
    assert all(e.problem is None for e in est.values())
    assert est["d02"].n_cells > est["d00"].n_cells and est["d02"].seconds > est["d00"].seconds
    lines = format_atlas_plan(list(est.values()), parallel=2)
    assert lines[-1].startswith("5 of 5 scenes runnable")
    refused = plan_atlas(load_scenario("paper_gt", {**SMALL_OVERRIDES, "oxide.n_realizations": 10**9}), design)
    assert all(e.problem and "oxide.n_realizations" in e.problem for e in refused)
    assert "refused: oxide.n_realizations" in format_atlas_plan(refused)[1]


def test_cli_plans_the_atlas(capsys) -> None:
    from g2tom.cli.main import main

    small = {**SMALL_OVERRIDES, "atlas.n_mu": 2, "atlas.n_pi": 3, "atlas.n_heldout": 2}
    assert main(["plan", "--atlas", "--workers", "2", "--config", "paper_gt",
                 *[a for k, v in small.items() for a in ("--set", f"{k}={v}")]]) == 0
    out = capsys.readouterr().out.splitlines()
    assert len(out) == 1 + 8 + 1 and out[-1].startswith("8 of 8 scenes runnable") and "on 2 concurrent" in out[-1]


def test_the_design_is_the_scenarios_atlas_section() -> None:
    assert AtlasDesign.of(load_scenario("paper_gt")) == AtlasDesign()
    scenario = load_scenario("paper_gt", {"atlas.mu_max": 80.0, "atlas.pi_max": 640.0, "atlas.n_pi": 6, "atlas.seed": 7})
    design = AtlasDesign.of(scenario)
    assert design == AtlasDesign(mu=(1.0, 80.0), Pi=(5.0, 640.0), n_pi=6, seed=7)
    assert max(s.Pi for s in design_scenes(design)) == pytest.approx(640.0)
    with pytest.raises(ConfigError, match=r"atlas.mu_max = 0.5 is out of range: must be > atlas.mu_min = 1.0"):
        load_scenario("paper_gt", {"atlas.mu_max": 0.5})


def test_atlas_commands_default_to_the_atlas_scenario() -> None:
    """Without --config, `g2tom atlas` and `g2tom plan --atlas` take the bundled `atlas` (what
    `make atlas` passes: its 5 x 6 oxide grid and 5 % target), every other command `paper`."""
    from g2tom.cli.arguments import build_parser, default_config

    parser = build_parser()
    assert default_config(parser.parse_args(["plan", "--atlas"])) == "atlas"
    assert default_config(parser.parse_args(["atlas"])) == "atlas"
    assert default_config(parser.parse_args(["plan"])) == "paper"
    assert default_config(parser.parse_args(["run"])) == "paper"
    assert default_config(parser.parse_args(["plan", "--atlas", "--config", "paper_gt"])) == "paper_gt"
