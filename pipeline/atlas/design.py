"""The atlas's design over the dimensionless groups (mu, Pi), its scenes, and their plan.

The atlas (issue 23) runs the whole chain contact -> oxide -> cube -> fits on many scenes that
differ only in mu = (8/3) eta sigma sqrt(2 R* beta) and Pi = eta R* sigma
(:mod:`pipeline.physics.groups`): everything else, E*, rho* and the reference lengths sigma and
R*, only scales F and R. This module holds what is known before any scene runs:

* :class:`AtlasDesign`: a log-spaced grid of ``n_mu x n_pi`` design scenes over the box
  ``mu x Pi`` and ``n_heldout`` held-out scenes drawn uniformly in (log mu, log Pi) inside it
  from one seed (numpy SeedSequence), each at least a quarter grid step from every design node
  in both coordinates, so none duplicates a design scene;
* :func:`scene_scenario`: the scenario of one scene: the base scenario with eta and beta from
  (mu, Pi) at the base's sigma and R*, and the domains back to ``auto``;
* :func:`plan_atlas`: each scene's window, memory and time (:func:`pipeline.before_work.plan.estimate`), or
  why it cannot run (a refusal of the plan or the preflight), before any work.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from pipeline.config import AUTO, ConfigError, Scenario
from pipeline.physics.groups import surface_from_groups

__all__ = ["AtlasDesign", "Scene", "SceneEstimate", "design_scenes", "scene_scenario", "plan_atlas",
           "format_atlas_plan"]

#: Smallest distance of a held-out scene from a design node, in grid steps of each log coordinate.
MIN_HELDOUT_GAP = 0.25
#: Draws tried per held-out scene before the design is refused as too dense.
_MAX_DRAWS = 10_000


@dataclass(frozen=True)
class AtlasDesign:
    """Where the atlas's scenes lie in (mu, Pi); a scenario's from its ``[atlas]`` section (:meth:`of`).

    Attributes
    ----------
    mu, Pi
        (low, high) of each group, dimensionless, 0 < low < high.
    n_mu, n_pi
        Design values per group (log-spaced, ends included), >= 2 each.
    n_heldout
        Held-out scenes, >= 1, never used in a fit.
    seed
        Root seed of the held-out draws.
    """

    mu: tuple[float, float] = (1.0, 50.0)
    Pi: tuple[float, float] = (5.0, 320.0)
    n_mu: int = 5
    n_pi: int = 5
    n_heldout: int = 6
    seed: int = 20261124

    @classmethod
    def of(cls, scenario: Scenario) -> "AtlasDesign":
        """The design of ``scenario``'s ``[atlas]`` section."""
        a = scenario.atlas
        return cls(mu=(a.mu_min, a.mu_max), Pi=(a.pi_min, a.pi_max), n_mu=a.n_mu, n_pi=a.n_pi,
                   n_heldout=a.n_heldout, seed=a.seed)

    def __post_init__(self) -> None:
        for name in ("mu", "Pi"):
            lo, hi = (float(v) for v in getattr(self, name))
            if not (math.isfinite(lo) and math.isfinite(hi) and 0 < lo < hi):
                raise ConfigError(f"atlas {name} = {getattr(self, name)!r} is out of range: must be (low, high) "
                                  "with 0 < low < high")
        for name, least in (("n_mu", 2), ("n_pi", 2), ("n_heldout", 1)):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int) or value < least:
                raise ConfigError(f"atlas {name} = {value!r} is out of range: must be an integer >= {least}")


@dataclass(frozen=True)
class Scene:
    """One scene: its name, groups and role."""

    name: str
    mu: float
    Pi: float
    heldout: bool


def _log_grid(bounds: tuple[float, float], n: int) -> np.ndarray:
    return np.geomspace(bounds[0], bounds[1], n)


def design_scenes(design: AtlasDesign) -> list[Scene]:
    """The design scenes (grid, mu fastest) and then the held-out ones, named ``d00..`` and ``h00..``.

    Raises
    ------
    ConfigError
        If no held-out scene can keep :data:`MIN_HELDOUT_GAP` from the design nodes.
    """
    mus, pis = _log_grid(design.mu, design.n_mu), _log_grid(design.Pi, design.n_pi)
    scenes = [Scene(f"d{k:02d}", float(m), float(p), False)
              for k, (p, m) in enumerate((p, m) for p in pis for m in mus)]
    step = np.array([math.log(design.mu[1] / design.mu[0]) / (design.n_mu - 1),
                     math.log(design.Pi[1] / design.Pi[0]) / (design.n_pi - 1)])
    lows = np.log([design.mu[0], design.Pi[0]])
    nodes = (np.log(np.array([[s.mu, s.Pi] for s in scenes])) - lows) / step  # in grid steps
    rng = np.random.default_rng(np.random.SeedSequence(design.seed))
    for k in range(design.n_heldout):
        for _ in range(_MAX_DRAWS):
            point = rng.uniform(0.0, 1.0, 2) * (np.array([design.n_mu, design.n_pi]) - 1)
            if np.all(np.any(np.abs(nodes - point) >= MIN_HELDOUT_GAP, axis=1)):
                break
        else:
            raise ConfigError(f"atlas n_heldout = {design.n_heldout}: no held-out scene keeps {MIN_HELDOUT_GAP} grid "
                              "steps from the design scenes")
        mu, pi = np.exp(lows + point * step)
        scenes.append(Scene(f"h{k:02d}", float(mu), float(pi), True))
    return scenes


def scene_scenario(base: Scenario, scene: Scene) -> Scenario:
    """``base`` with the scene's eta and beta (at the base's sigma and R*) and ``auto`` domains."""
    surface = surface_from_groups(scene.mu, scene.Pi, base.roughness.sigma, base.indenter.radius)
    roughness = dataclasses.replace(base.roughness, eta=surface.eta, beta=surface.beta)
    contact = dataclasses.replace(base.contact, window=AUTO, r_max=AUTO)
    return dataclasses.replace(base, name=f"{base.name}/{scene.name}", roughness=roughness, contact=contact)


@dataclass(frozen=True)
class SceneEstimate:
    """A scene's plan: cells per window side, peak memory (bytes) and time (s), or why it cannot run."""

    scene: Scene
    n_cells: int | None
    peak_bytes: float
    seconds: float
    problem: str | None


def plan_atlas(base: Scenario, design: AtlasDesign, workers: int | None = 1) -> list[SceneEstimate]:
    """Every scene's resolved window and its stages' estimates, before any work.

    ``workers`` is the per-scene worker count (1: one scene per single-threaded task). A scene
    the plan or the preflight refuses carries the refusal as ``problem`` instead of raising, so
    the whole design is seen at once.
    """
    from pipeline.before_work import plan
    from pipeline.before_work.domains import resolve
    from pipeline.before_work.preflight import check_scene

    out = []
    for scene in design_scenes(design):
        scenario = scene_scenario(base, scene)
        try:
            plan.check_resources(scenario, workers)
            resolved = resolve(scenario)
            check_scene(resolved)
            estimates = plan.check_resources(resolved, workers)
        except ConfigError as exc:
            out.append(SceneEstimate(scene, None, math.nan, math.nan, str(exc)))
            continue
        out.append(SceneEstimate(scene, resolved.n_cells, max(e.peak_bytes for e in estimates),
                                 sum(e.seconds for e in estimates), None))
    return out


def format_atlas_plan(estimates: list[SceneEstimate], parallel: int = 1) -> list[str]:
    """One line per scene and the total, time divided over ``parallel`` concurrent scenes."""
    lines = [f"{'scene':6s} {'mu':>8s} {'Pi':>8s} {'cells':>6s} {'memory':>10s} {'time':>10s}"]
    for e in estimates:
        head = f"{e.scene.name:6s} {e.scene.mu:8.4g} {e.scene.Pi:8.4g}"
        if e.problem:
            lines.append(f"{head}  refused: {e.problem}")
        else:
            lines.append(f"{head} {e.n_cells:6d} {e.peak_bytes / 2**20:7.0f} MiB {e.seconds:8.3g} s")
    runnable = [e for e in estimates if not e.problem]
    total = sum(e.seconds for e in runnable)
    lines.append(f"{len(runnable)} of {len(estimates)} scenes runnable, {total:.3g} s in all, about "
                 f"{total / parallel / 3600:.3g} h on {parallel} concurrent scene(s)")
    return lines
