"""The atlas's design over the dimensionless groups (mu, Pi), its scenes, and their plan.

The atlas runs the whole chain contact -> oxide -> cube -> fits on many scenes that
differ only in mu = (8/3) eta sigma sqrt(2 R* beta) and Pi = eta R* sigma
(:mod:`g2tom.physics.groups`): everything else, E*, rho* and the reference lengths sigma and
R*, only scales F and R. This module holds what is known before any scene runs:

* :class:`AtlasDesign`: a log-spaced grid of ``n_mu x n_pi`` design scenes over the box
  ``mu x Pi`` and ``n_heldout`` held-out scenes drawn uniformly in (log mu, log Pi) inside it
  from one seed (numpy SeedSequence), each at least a quarter grid step from every design node
  in both coordinates, so none duplicates a design scene;
* :func:`scene_scenario`: the scenario of one scene: the base scenario with eta and beta from
  (mu, Pi) at the base's sigma and R*, its own random streams (:func:`scene_seed`), load steps
  spanning F' 0.05-20 (:mod:`g2tom.atlas.loads`), every step fitted, on discrete asperities a
  pool sized by its touching count, and the domains back to ``auto``;
* :func:`plan_atlas`: each scene's window, memory and time (:mod:`g2tom.atlas.cost`: on
  discrete asperities the time grows with the touching asperities), or why it cannot run (a
  refusal of the plan or the preflight), before any work; :func:`format_atlas_plan` adds the wall
  time on the workers against the 3 h budget.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from g2tom.atlas.cost import SceneCost
from g2tom.config import AUTO, ConfigError, Loading, Scenario
from g2tom.models import contact_model, step_target_conflicts
from g2tom.physics.groups import surface_from_groups

__all__ = ["AtlasDesign", "Scene", "SceneEstimate", "design_scenes", "scene_seed", "scene_scenario", "plan_atlas",
           "format_atlas_plan", "SCENE_TAG", "GROUP_KEY_SCALE", "wall_seconds", "schedule", "ALONE_EFFICIENCY", "BUDGET_SECONDS", "POOL_TOUCHING", "MIN_POOL"]

#: Smallest distance of a held-out scene from a design node, in grid steps of each log coordinate.
MIN_HELDOUT_GAP = 0.25
#: Touching asperities the discrete pool holds at its heaviest step over all its surfaces: the
#: paper's, 256 surfaces of ~200. A scene with more per surface gets fewer surfaces (the surface-to-
#: surface scatter of ln R falls as the touching count grows), at least MIN_POOL and at most the
#: base's ``contact.surfaces``.
POOL_TOUCHING = 256 * 200
MIN_POOL = 32
#: Draws tried per held-out scene before the design is refused as too dense.
_MAX_DRAWS = 10_000
#: Second entropy word of a scene's root seed: ``SeedSequence([seed, SCENE_TAG, mu_key, Pi_key])``.
SCENE_TAG = 0x7363656E  # "scen"
#: Resolution of the groups in a scene's seed key: scenes closer than 1 / GROUP_KEY_SCALE in both
#: mu and Pi draw the same streams.
GROUP_KEY_SCALE = 1_000_000


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


def scene_seed(seed: int, scene: Scene) -> int:
    """The root seed of a scene's random streams (its oxide fields and asperity pool), from the base's
    ``oxide.seed`` and the scene's groups.

    Every scene draws its own fields, so the design scenes' sampling errors are independent: the
    surrogate, smoothing across scenes, averages them down instead of inheriting the one error that
    common streams would give every scene (at lambda 23, where a 5 % ensemble stops after 100-200
    fields, that shared error was 3-5 % in ln R'), and a held-out scene's error is not shared with
    the design that is judged against it. Two scenes of equal groups (the invariance twin and its
    original) draw the same streams, so their comparison is the invariance alone.

    Returns
    -------
    int
        A seed in [0, 2^32).
    """
    key = [round(scene.mu * GROUP_KEY_SCALE), round(scene.Pi * GROUP_KEY_SCALE)]
    return int(np.random.SeedSequence([int(seed), SCENE_TAG, *key]).generate_state(1)[0])


def _tighter(own: float, heldout: float) -> float:
    """The smaller positive of a design target and its held-out counterpart (0: none set)."""
    wanted = [w for w in (own, heldout) if w > 0]
    return min(wanted) if wanted else 0.0


def scene_scenario(base: Scenario, scene: Scene, loading: Loading | None = None) -> Scenario:
    """``base`` with the scene's eta and beta (at the base's sigma and R*), its own random streams
    (``oxide.seed`` from :func:`scene_seed`), a held-out scene's ensemble to
    ``atlas.heldout_half_width`` where that is tighter than the base's (its light steps' to
    ``atlas.heldout_step_half_width`` where its ensemble takes a step target, and its discrete pool
    grown to ``atlas.heldout_pool_half_width``, likewise), approaches whose forces span
    :data:`g2tom.atlas.loads.FORCE_RANGE` in F' (:func:`g2tom.atlas.loads.loading_for_range`,
    ``loading.n_delta`` kept), every step fitted, and ``auto`` domains.

    Raises
    ------
    ConfigError
        If the scene's approaches cannot be found (naming the scene).
    """
    from g2tom.atlas.loads import END_MARGIN, FORCE_RANGE, loading_for_range

    surface = surface_from_groups(scene.mu, scene.Pi, base.roughness.sigma, base.indenter.radius)
    roughness = dataclasses.replace(base.roughness, eta=surface.eta, beta=surface.beta)
    oxide = dataclasses.replace(base.oxide, seed=scene_seed(base.oxide.seed, scene))
    if scene.heldout:  # measured closer than the design, so the verdict judges the surrogate
        oxide = dataclasses.replace(oxide, target_half_width=min(oxide.target_half_width,
                                                                 base.atlas.heldout_half_width))
        if not step_target_conflicts(base):
            oxide = dataclasses.replace(oxide, step_half_width=_tighter(oxide.step_half_width,
                                                                        base.atlas.heldout_step_half_width))
    contact = dataclasses.replace(base.contact, window=AUTO, r_max=AUTO)
    if scene.heldout:  # its pool's error, too, below the design's
        contact = dataclasses.replace(contact, pool_half_width=_tighter(contact.pool_half_width,
                                                                        base.atlas.heldout_pool_half_width))
    # every step is fitted: the lightest lies at FORCE_RANGE[0] / (1 + END_MARGIN)
    fits = dataclasses.replace(base.fits, fit_range="force_normalized",
                               min_force_normalized=round(FORCE_RANGE[0] / (1.0 + 2.0 * END_MARGIN), 6))
    scenario = Scenario.of(base, name=f"{base.name}/{scene.name}", roughness=roughness, contact=contact,
                           oxide=oxide, fits=fits)
    try:
        scenario = loading_for_range(scenario) if loading is None else dataclasses.replace(scenario, loading=loading)
        # a pool (the discrete model's) as many touching caps as the paper's
        return contact_model(scenario).atlas_scenario(scenario, base.contact.surfaces, MIN_POOL, POOL_TOUCHING)
    except ValueError as exc:
        raise ConfigError(f"atlas scene {scene.name} (mu {scene.mu:.4g}, Pi {scene.Pi:.4g}): {exc}") from None


@dataclass(frozen=True)
class SceneEstimate:
    """A scene's plan: cells per window side, peak memory (bytes), time (s, one thread) and what
    drives it (:class:`g2tom.atlas.cost.SceneCost`), or why it cannot run."""

    scene: Scene
    n_cells: int | None
    peak_bytes: float
    seconds: float
    problem: str | None
    cost: SceneCost | None = None


def plan_atlas(base: Scenario, design: AtlasDesign, workers: int | None = 1) -> list[SceneEstimate]:
    """Every scene's resolved window, peak memory and modelled time, before any work.

    Memory comes from :func:`g2tom.before_work.resources.check_resources` (a scene that does not fit
    is refused there), time from :func:`g2tom.atlas.cost.scene_cost` (on discrete asperities it
    grows with the touching asperities, not with a grid). ``workers`` is the per-scene worker
    count (1: one scene per single-threaded task). A scene the plan or the preflight refuses
    carries the refusal as ``problem`` instead of raising, so the whole design is seen at once.
    """
    from g2tom.atlas.cost import scene_cost
    from g2tom.before_work.domains import resolve
    from g2tom.before_work.preflight import check_scene
    from g2tom.before_work.resources import check_resources

    out = []
    for scene in design_scenes(design):
        try:
            scenario = scene_scenario(base, scene)
            check_resources(scenario, workers)
            resolved = resolve(scenario)
            check_scene(resolved)
            estimates = check_resources(resolved, workers)
        except ConfigError as exc:
            out.append(SceneEstimate(scene, None, math.nan, math.nan, str(exc)))
            continue
        cost = scene_cost(resolved)
        out.append(SceneEstimate(scene, resolved.n_cells, max(e.peak_bytes for e in estimates), cost.seconds, None,
                                 cost))
    return out


#: The wall time an atlas may take (`make atlas` within 3 h on a 2-core machine).
BUDGET_SECONDS = 3 * 3600.0


#: A scene's speed-up per worker when it runs alone on every worker (its surfaces and fields spread
#: over them) against one thread: d20 of the full atlas, ~7,955 s on one thread, ~4,160 s on two.
ALONE_EFFICIENCY = 0.95


def wall_seconds(seconds: list[float], parallel: int) -> float:
    """Wall time of scenes of these CPU times, one per task on ``parallel`` workers, longest first
    (each worker takes the next scene when free)."""
    loads = [0.0] * max(1, parallel)
    for s in sorted(seconds, reverse=True):
        loads[loads.index(min(loads))] += s
    return max(loads)


def schedule(seconds: list[float], parallel: int) -> tuple[int, float]:
    """How many of the longest scenes run alone first, each on all ``parallel`` workers, and the
    wall time (s) of that schedule: the count that gives the least wall time, the rest then one
    per task, longest first (:func:`wall_seconds`).

    One scene longer than the others' share keeps one worker busy while the rest idle (the full
    atlas's d20 ran ~2 h on one core, the other 32 scenes ~70 min on the other); alone on every
    worker it takes ``seconds / (parallel * ALONE_EFFICIENCY)``. On one worker none runs alone.
    """
    order = sorted(seconds, reverse=True)
    best = (0, wall_seconds(order, parallel))
    if parallel <= 1:
        return best
    first = 0.0
    for k in range(1, len(order)):
        first += order[k - 1] / (parallel * ALONE_EFFICIENCY)
        wall = first + wall_seconds(order[k:], parallel)
        if wall < best[1]:
            best = (k, wall)
    return best


def format_atlas_plan(estimates: list[SceneEstimate], parallel: int = 1) -> list[str]:
    """One line per scene, the total and the wall time on ``parallel`` concurrent scenes
    (:func:`schedule`) against :data:`BUDGET_SECONDS`."""
    lines = [f"{'scene':6s} {'mu':>8s} {'Pi':>8s} {'cells':>6s} {'touching':>9s} {'pool':>10s} {'fields':>7s} "
             f"{'memory':>10s} {'time':>10s}"]
    for e in estimates:
        head = f"{e.scene.name:6s} {e.scene.mu:8.4g} {e.scene.Pi:8.4g}"
        if e.problem:
            lines.append(f"{head}  refused: {e.problem}")
            continue
        c = e.cost
        touching = f"{c.touching[-1]:9.0f}" if c is not None and c.touching is not None else f"{'-':>9s}"
        pool = f"{'-':>10s}"
        if c is not None and c.surfaces:
            grown = f"{c.surfaces}/{c.surfaces_lightest}" if c.surfaces_lightest > c.surfaces else f"{c.surfaces}"
            pool = f"{grown:>10s}"
        fields = f"{c.fields:7.0f}" if c is not None else f"{'-':>7s}"
        lines.append(f"{head} {e.n_cells:6d} {touching} {pool} {fields} {e.peak_bytes / 2**20:7.0f} MiB "
                     f"{e.seconds:8.3g} s")
    runnable = [e for e in estimates if not e.problem]
    total = sum(e.seconds for e in runnable)
    alone, wall = schedule([e.seconds for e in runnable], parallel)
    first = f", the longest {alone} alone on all of them first" if alone else ""
    lines.append(f"{len(runnable)} of {len(estimates)} scenes runnable, {total:.3g} s of one thread in all, about "
                 f"{wall / 3600:.3g} h on {parallel} concurrent scene(s){first} (touching: expected asperities in "
                 f"contact at the heaviest step; pool: surfaces at every step, / at the lightest where the pool "
                 f"grows there, expected; fields: oxide realizations x lambda)")
    if wall > BUDGET_SECONDS:
        worst = sorted(runnable, key=lambda e: -e.seconds)[:3]
        lines.append(f"over the {BUDGET_SECONDS / 3600:g} h budget by {wall / BUDGET_SECONDS:.3g} x; the costliest scenes: "
                     + ", ".join(f"{e.scene.name} (mu {e.scene.mu:.3g}, Pi {e.scene.Pi:.3g}) {e.seconds / 3600:.3g} h"
                                 for e in worst))
    return lines
