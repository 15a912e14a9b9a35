"""The discrete-asperity contact: Hertz, point-load superposition, equilibrium, Barber, invariances."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import quad
from scipy.special import ndtr

from g2tom.physics import discrete_contact as dc
from g2tom.physics.discrete_resistance import resistances
from g2tom.physics.cap_law import CappedCap, HertzCap
from g2tom.physics.cap_overlap import owned_areas
from g2tom.physics.hertz import hertz_radius

E_STAR = 2.1e11 / (2 * (1 - 0.3**2))
SIGMA, ETA, BETA, RADIUS = 20e-6, 2e8, 30e-6, 10e-3
RHO = 7.2e-7
FLOOR = dc.coupling_floor(BETA, SIGMA)
FORCE_SCALE = E_STAR * np.sqrt(RADIUS * SIGMA**3) / 2.0  # F = F' x this


def sphere(r: np.ndarray) -> np.ndarray:
    return r * r / (2.0 * RADIUS)


def flat(r: np.ndarray) -> np.ndarray:
    return np.zeros_like(r)


def surface(k: int) -> dc.Asperities:
    return dc.draw_asperities(7, k, dc.domain_radius(sphere, -3.5 * SIGMA, SIGMA, ETA), ETA, SIGMA)


FORCES = np.geomspace(0.05, 20.0, 8) * FORCE_SCALE


def test_one_asperity_is_hertz_exactly():
    cap = dc.Asperities(np.array([0.0]), np.array([0.0]), np.array([1e-6]))
    forces = np.array([0.1, 1.0, 10.0])
    sol = dc.solve_forces(cap, sphere, forces, E_STAR, BETA, FLOOR)
    a = hertz_radius(forces, BETA, E_STAR)  # a cap of radius beta on a flat
    np.testing.assert_allclose(sol.radii[:, 0], a, rtol=1e-12)
    np.testing.assert_allclose(sol.delta, 1e-6 - a**2 / BETA, rtol=1e-12)
    np.testing.assert_allclose(sol.stiffness, 2.0 * E_STAR * a, rtol=1e-12)


def test_two_distant_asperities_are_uncoupled():
    pair = dc.Asperities(np.array([0.0, 1e3]), np.array([0.0, 0.0]), np.array([2e-6, 1e-6]))
    sol = dc.solve_forces(pair, flat, np.array([5.0]), E_STAR, BETA, FLOOR)
    k = 4.0 / 3.0 * E_STAR * np.sqrt(BETA)
    w = sol.interference[0]
    # uncoupled: both at the same delta, so the interferences differ by the height difference
    np.testing.assert_allclose(w[0] - w[1], 1e-6, rtol=1e-6)
    np.testing.assert_allclose(k * (w**1.5).sum(), 5.0, rtol=1e-10)


@pytest.mark.parametrize("distance", [2e-4, 5e-5, 0.3 * FLOOR])
def test_two_close_asperities_match_the_superposition_by_hand(distance):
    pair = dc.Asperities(np.array([0.0, distance]), np.array([0.0, 0.0]), np.array([3e-6, 3e-6]))
    force = 2.0
    sol = dc.solve_forces(pair, flat, np.array([force]), E_STAR, BETA, FLOOR)
    k = 4.0 / 3.0 * E_STAR * np.sqrt(BETA)
    w = (force / 2.0 / k) ** (2.0 / 3.0)  # each carries half
    coupling = 1.0 / (np.pi * E_STAR * max(distance, FLOOR))
    np.testing.assert_allclose(sol.interference[0], [w, w], rtol=1e-9)
    np.testing.assert_allclose(sol.delta[0], 3e-6 - w - coupling * force / 2.0, rtol=1e-9)
    # K: 1^T (D^-1 + C)^-1 1 with D = 2 E* a on both: 2 / (1/(2 E* a) + coupling)
    a = np.sqrt(BETA * w)
    np.testing.assert_allclose(sol.stiffness[0], 2.0 / (1.0 / (2.0 * E_STAR * a) + coupling), rtol=1e-9)


@pytest.mark.parametrize("k", [0, 1, 2])
def test_equilibrium_and_complementarity_on_rough_spheres(k):
    asp = surface(k)
    sol = dc.solve_forces(asp, sphere, FORCES, E_STAR, BETA, FLOOR)
    assert np.all(sol.residual <= dc.TOLERANCE)
    np.testing.assert_allclose(sol.load.sum(axis=1), FORCES, rtol=1e-9)
    g = asp.z - sphere(np.hypot(asp.x, asp.y))
    kernel = dc.interaction_kernel(asp.x, asp.y, FLOOR)
    for f in range(FORCES.size):
        w = g - sol.delta[f] - kernel @ sol.load[f] / E_STAR  # over every asperity, candidates or not
        touching = sol.load[f] > 0
        np.testing.assert_allclose(w[touching], sol.interference[f, touching], rtol=1e-8, atol=1e-9 * SIGMA)
        assert np.all(w[~touching] <= 1e-9 * SIGMA)
        np.testing.assert_allclose(sol.load[f], 4 / 3 * E_STAR * np.sqrt(BETA) * sol.interference[f] ** 1.5, rtol=1e-12)
    # heavier loads, more approach and more contacts
    assert np.all(np.diff(sol.delta) < 0)
    assert (sol.load[-1] > 0).sum() > 100 and (sol.load[0] > 0).sum() <= 10


def test_solution_is_independent_of_the_order_of_the_asperities_and_of_the_load_steps():
    asp = surface(3)
    sol = dc.solve_forces(asp, sphere, FORCES, E_STAR, BETA, FLOOR)
    perm = np.random.default_rng(0).permutation(asp.size)
    shuffled = dc.Asperities(asp.x[perm], asp.y[perm], asp.z[perm])
    other = dc.solve_forces(shuffled, sphere, FORCES, E_STAR, BETA, FLOOR)
    np.testing.assert_allclose(other.delta, sol.delta, rtol=1e-9)
    np.testing.assert_allclose(other.load, sol.load[:, perm], rtol=1e-7, atol=1e-9 * FORCES[-1])
    alone = dc.solve_forces(asp, sphere, FORCES[-2:], E_STAR, BETA, FLOOR)  # no warm start from light loads
    np.testing.assert_allclose(alone.delta, sol.delta[-2:], rtol=1e-9)
    np.testing.assert_allclose(alone.stiffness, sol.stiffness[-2:], rtol=1e-8)


def test_stiffness_is_the_derivative_of_the_force():
    asp = surface(4)
    forces = np.array([1.0, 1.0 + 1e-5]) * FORCE_SCALE
    sol = dc.solve_forces(asp, sphere, forces, E_STAR, BETA, FLOOR)
    fd = -(forces[1] - forces[0]) / (sol.delta[1] - sol.delta[0])
    np.testing.assert_allclose(sol.stiffness[0], fd, rtol=1e-4)


@pytest.mark.parametrize("k", [5, 6])
def test_barber_holds_per_realization_with_the_point_model(k):
    asp = surface(k)
    sol = dc.solve_forces(asp, sphere, FORCES, E_STAR, BETA, FLOOR)
    kernel = dc.interaction_kernel(asp.x, asp.y, FLOOR)
    r_point = resistances(kernel, sol.radii, RHO, "point")
    np.testing.assert_allclose(1.0 / r_point, sol.stiffness / (E_STAR * RHO), rtol=1e-8)
    r_greenwood = resistances(kernel, sol.radii, RHO, "greenwood")
    assert np.all(r_greenwood >= r_point * (1 - 1e-12))


def test_resistance_of_one_spot_and_open_circuit():
    kernel = dc.interaction_kernel(np.array([0.0, 1e-4]), np.array([0.0, 0.0]), FLOOR)
    radius = np.array([[1e-5, 0.0], [0.0, 0.0]])
    for model in ("point", "greenwood"):
        np.testing.assert_allclose(resistances(kernel, radius, RHO, model), [RHO / 2e-5, np.inf], rtol=1e-14)


def test_domain_radius_leaves_the_stated_expected_count_outside():
    delta = -3.0 * SIGMA
    radius = dc.domain_radius(sphere, delta, SIGMA, ETA, outside=1e-6)
    # closed form for the sphere: eta 2 pi R* sigma int_{t0}^inf Q(t + delta/sigma) dt, t0 = R^2/(2 R* sigma)
    def outside(r: float) -> float:
        t0 = r * r / (2.0 * RADIUS * SIGMA)
        return ETA * 2 * np.pi * RADIUS * SIGMA * quad(lambda t: ndtr(-(t + delta / SIGMA)), t0, np.inf)[0]
    assert outside(radius) < 1e-6 < outside(0.99 * radius)


def test_asperities_are_reproducible_poisson_with_gaussian_heights():
    a, b = dc.draw_asperities(3, 9, 2e-3, ETA, SIGMA), dc.draw_asperities(3, 9, 2e-3, ETA, SIGMA)
    np.testing.assert_array_equal(a.z, b.z)
    counts = np.array([dc.draw_asperities(3, k, 1e-3, ETA, SIGMA).size for k in range(200)])
    mean = ETA * np.pi * 1e-6
    assert abs(counts.mean() - mean) < 4 * np.sqrt(mean / counts.size)
    z = np.concatenate([dc.draw_asperities(3, k, 1e-3, ETA, SIGMA).z for k in range(20)])
    assert abs(z.std() / SIGMA - 1) < 4 / np.sqrt(2 * z.size)
    assert np.hypot(a.x, a.y).max() <= 2e-3


def test_bad_forces_are_refused():
    asp = surface(0)
    for forces in ([1.0, 0.5], [0.0, 1.0], [-1.0]):
        with pytest.raises(ValueError, match="forces"):
            dc.solve_forces(asp, sphere, np.array(forces), E_STAR, BETA, FLOOR)


def test_rigid_approach_when_only_the_highest_cap_touches():
    """The bracket's lower end is where the highest cap alone carries the force: with no other cap
    touching there the excess is zero up to rounding, of either sign, and that end is the root."""
    from g2tom.physics.discrete_contact import _rigid_delta

    rng = np.random.default_rng(4)
    e_star, beta = 1.154e11, 3e-5
    for _ in range(300):
        top = rng.uniform(-5e-5, 5e-5)
        g = np.concatenate([[top], top - rng.uniform(2e-5, 1e-4, 20)])  # the rest far below
        force = 10.0 ** rng.uniform(-3, 1)
        d = _rigid_delta(g, force, HertzCap(e_star, beta))
        assert HertzCap(e_star, beta).load(g - d).sum() == pytest.approx(force, rel=1e-12)


@pytest.mark.parametrize("forces", [FORCES[[0, -1]], FORCES[[1, 4, 7]], FORCES[-1:]])
def test_far_apart_forces_are_climbed_to_the_same_solution(forces):
    """Forces more than MAX_STEP_RATIO apart are reached through intermediate forces: the solution
    at each given force is the fine ladder's (a cold heavy start too), and no step takes far more
    candidates than the ladder (the linear extrapolation over a 400x jump took every asperity of
    the domain, ~35x the time)."""
    asp = surface(5)
    ladder = np.unique(np.concatenate([np.geomspace(FORCES[0] / 8, forces[-1], 40), forces]))
    fine = dc.solve_forces(asp, sphere, ladder, E_STAR, BETA, FLOOR)
    at = np.searchsorted(ladder, forces)
    got = dc.solve_forces(asp, sphere, forces, E_STAR, BETA, FLOOR)
    np.testing.assert_allclose(got.delta, fine.delta[at], rtol=1e-9)
    np.testing.assert_allclose(got.load, fine.load[at], rtol=1e-7, atol=1e-9 * forces[-1])
    np.testing.assert_allclose(got.load.sum(axis=1), forces, rtol=1e-9)
    assert np.all(got.candidates <= 2 * fine.candidates[at] + 10)


def _top_level_forces(monkeypatch) -> list[float]:
    """The forces the walk is asked for from :meth:`_Walker.climb` (refinements of a failing step excluded)."""
    asked: list[float] = []
    reach = dc._Walker.reach

    def spy(self, force, depth=0):
        if depth == 0:
            asked.append(force)
        return reach(self, force, depth)

    monkeypatch.setattr(dc._Walker, "reach", spy)
    return asked


def test_close_forces_are_not_climbed_far_ones_are(monkeypatch):
    """Steps within MAX_STEP_RATIO go straight to Newton, as before the ladder (the paper's 20 steps and the atlas's scenes keep their solves bit for bit); a far step
    is split into steps of at most MAX_STEP_RATIO."""
    asp = surface(6)
    forces = np.geomspace(0.05, 20.0, 20) * FORCE_SCALE  # 1.37x a step
    asked = _top_level_forces(monkeypatch)
    dc.solve_forces(asp, sphere, forces, E_STAR, BETA, FLOOR)
    assert asked == list(forces)
    asked.clear()
    dc.solve_forces(asp, sphere, forces[[0, -1]], E_STAR, BETA, FLOOR)
    ratios = np.diff(np.log(asked))
    assert asked[0] == forces[0] and asked[-1] == forces[-1] and len(asked) > 2
    assert np.all(ratios > 0) and np.all(ratios <= np.log(dc.MAX_STEP_RATIO) + 1e-12)


def test_continuation_halves_a_failing_step_however_short(monkeypatch):
    """Where Newton fails on a step shorter than sqrt(2), the walk must still refine it (before,
    a step of 1.4x was retried unchanged until the depth limit)."""
    advance = dc._Walker._advance

    def fussy(self, force):  # fails on any step above 1.1x, like a Newton that stagnates
        if self.force and force / self.force > 1.1:
            raise dc.NotConverged("step too long")
        return advance(self, force)

    monkeypatch.setattr(dc._Walker, "_advance", fussy)
    rng = np.random.default_rng(2)
    asperities = dc.Asperities(rng.uniform(-4e-4, 4e-4, 60), rng.uniform(-4e-4, 4e-4, 60),
                               rng.normal(0.0, 2e-5, 60))
    profile = lambda r: r ** 2 / (2 * 1e-2)  # noqa: E731
    got = dc.solve_forces(asperities, profile, np.array([10.0, 14.0]), 1.154e11, 3e-5, 1e-5)
    assert got.load[1].sum() == pytest.approx(14.0, rel=1e-9)


def test_the_default_scene_solves_every_surface_at_coarse_steps():
    """Surface 12 of the default scene with six load steps (38.8 N, then 406.9 N) stalled Newton
    from 290.9 N on a step of 1.4x; the walk refines it now."""
    from g2tom.before_work.domains import resolve
    from g2tom.before_work import load_scenario
    from g2tom.compute import ComputeOptions
    from g2tom.stages import contact
    from tests.conftest import SMALL_OVERRIDES

    scene = resolve(load_scenario("paper", {**SMALL_OVERRIDES, "contact.surfaces": 13}))
    pool = contact.build(scene, ComputeOptions(progress=False, workers=1))
    assert np.all(pool["discrete_residual"].values <= dc.TOLERANCE)


def test_a_solve_stalled_at_its_rounding_floor_is_accepted_a_larger_stall_is_not(monkeypatch):
    """A solve whose line search cannot lower the residual any more returns as stalled and is accepted
    below STALL_TOLERANCE; a tolerance no float reaches makes every solve stall here."""
    asp = surface(4)
    sol = dc.solve_forces(asp, sphere, FORCES, E_STAR, BETA, FLOOR)
    stalled = dc.solve_forces(asp, sphere, FORCES, E_STAR, BETA, FLOOR, tolerance=1e-30)
    assert np.all(stalled.residual <= dc.STALL_TOLERANCE)
    np.testing.assert_allclose(stalled.delta, sol.delta, rtol=1e-9)
    np.testing.assert_allclose(stalled.load, sol.load, rtol=1e-7, atol=1e-9 * FORCES[-1])
    monkeypatch.setattr(dc, "STALL_TOLERANCE", 1e-40)  # a stall above the accepted floor is not converged
    with pytest.raises(dc.NotConverged, match="stalled"):
        dc.solve_forces(asp, sphere, FORCES[:1], E_STAR, BETA, FLOOR, tolerance=1e-30)


def test_caps_wider_than_their_spacing_pass_a_fold_of_the_load_path(monkeypatch):
    """The atlas's scene h07 (mu 26, Pi 7.5: caps of radius 8.8 mm, 0.16 mm apart) made D^-1 + C
    indefinite; Newton stalled at a fold of the load path and the atlas stopped. The solve now
    passes the fold by proximal rounds (and only there) to an equilibrium that is a minimum of the
    energy: balanced, complementary, with a positive definite Hessian."""
    eta, beta = 3.7313379116594106e7, 8.80323154925433e-3
    floor = dc.coupling_floor(beta, SIGMA)
    asp = dc.draw_asperities(20240531, 9, 1.88e-3, eta, SIGMA)
    folds = []
    proximal = dc._proximal

    def spy(*args, **kwargs):
        folds.append(args[2])
        return proximal(*args, **kwargs)

    monkeypatch.setattr(dc, "_proximal", spy)
    sol = dc.solve_forces(asp, sphere, FORCES, E_STAR, beta, floor)
    assert folds == [FORCES[-1]]  # one fold, on the way to F' 20
    assert np.all(sol.residual <= dc.TOLERANCE)
    np.testing.assert_allclose(sol.load.sum(axis=1), FORCES, rtol=1e-9)
    g = asp.z - sphere(np.hypot(asp.x, asp.y))
    coupling = dc.interaction_kernel(asp.x, asp.y, floor) / E_STAR
    for i in range(FORCES.size):
        w = g - sol.delta[i] - coupling @ sol.load[i]  # every asperity's interference, touching or not
        touching = sol.load[i] > 0
        np.testing.assert_allclose(w[touching], sol.interference[i, touching], rtol=0, atol=1e-9 * SIGMA)
        assert np.all(w[~touching] <= 1e-9 * SIGMA)
        hessian = coupling[np.ix_(touching, touching)] + np.diag(1.0 / (2.0 * E_STAR * sol.radii[i, touching]))
        assert np.linalg.eigvalsh(hessian).min() > 0  # a minimum of the energy, not a saddle
    monkeypatch.setattr(dc, "_proximal", lambda *args, **kwargs: (args[5], 0.0, 0, 1.0, True))
    with pytest.raises(dc.NotConverged):  # Newton alone, as before, does not get through
        dc.solve_forces(asp, sphere, FORCES, E_STAR, beta, floor)


def test_proximal_rounds_solve_a_convex_problem_like_newton():
    """On a convex problem (the default's caps) the proximal rounds reach Newton's solution."""
    asp = surface(4)
    g = np.sort(asp.z - sphere(np.hypot(asp.x, asp.y)))[::-1][:300]
    order = np.argsort(-(asp.z - sphere(np.hypot(asp.x, asp.y))), kind="stable")[:300]
    kernel = dc.interaction_kernel(asp.x[order], asp.y[order], FLOOR)
    force = FORCES[5]
    cap = HertzCap(E_STAR, BETA)
    start = dc._State(g - dc._rigid_delta(g, force, cap), dc._rigid_delta(g, force, cap))
    newton = dc._newton(g, kernel, force, E_STAR, cap, start, 1e-11, 100)
    rounds = dc._proximal(g, kernel, force, E_STAR, cap, start, 1e-11, 100)
    assert not newton[4] and not rounds[4] and rounds[3] <= 1e-11
    assert rounds[0].delta == pytest.approx(newton[0].delta, abs=1e-9 * SIGMA)
    np.testing.assert_allclose(rounds[0].s, newton[0].s, rtol=0, atol=1e-9 * SIGMA)
    assert rounds[1] == pytest.approx(newton[1], rel=1e-6)  # the stiffness of the original equations


def test_a_cap_under_a_sphere_touches_where_the_two_paraboloids_meet() -> None:
    """The cap's first contact against a brute-force minimum of the gap along its radial line, and
    its Hertz radius against the gap's curvature there (both within 1e-6)."""
    radius, beta = 5e-3, 60e-6
    profile_radius, cap = dc.sphere_cap_geometry(radius, beta)
    for r in (0.0, 2e-4, 6.3e-4, 1.5e-3):
        t = np.linspace(-2e-3, 3e-3, 2_000_001)
        gap = (t - r) ** 2 / (2 * beta) + t**2 / (2 * radius)
        least = int(np.argmin(gap))
        assert gap[least] == pytest.approx(r * r / (2 * profile_radius), rel=1e-6, abs=1e-15)
        h = t[1] - t[0]
        curvature = (gap[least + 1] - 2 * gap[least] + gap[least - 1]) / h**2
        assert 1.0 / curvature == pytest.approx(cap, rel=1e-6)
    # the tip-evaluated sphere understates the interference by r^2 beta / (2 R (R + beta))
    r = 6.3e-4
    assert r * r / (2 * radius) - r * r / (2 * profile_radius) == pytest.approx(4.7e-7, rel=0.01)


def test_one_cap_under_a_sphere_is_hertz_of_the_two_curvatures() -> None:
    """One cap off the axis, solved by the stage's geometry: force and radius are Hertz's with
    radius beta R / (beta + R) at the interference z - r^2 / (2 (R + beta)) - delta."""
    radius, beta, e_star = 5e-3, 60e-6, 1.154e11
    profile_radius, cap = dc.sphere_cap_geometry(radius, beta)
    x, z = 6.3e-4, 30e-6
    sol = dc.solve_forces(dc.Asperities(np.array([x]), np.array([0.0]), np.array([z])),
                          lambda r: r * r / (2 * profile_radius), np.array([10.0, 100.0]), e_star, cap,
                          dc.coupling_floor(beta, 20e-6))
    w = (np.array([10.0, 100.0]) / (4 / 3 * e_star * np.sqrt(cap))) ** (2 / 3)
    np.testing.assert_allclose(sol.interference[:, 0], w, rtol=1e-8)
    np.testing.assert_allclose(sol.delta, z - x * x / (2 * profile_radius) - w, rtol=1e-8)
    np.testing.assert_allclose(sol.radii[:, 0], np.sqrt(cap * w), rtol=1e-8)


@pytest.mark.parametrize("shape, params", [
    ("sphere", {"radius": 5e-3}),
    ("cone", {"cone_angle": 0.3}),
    ("cone", {"cone_angle": 0.01}),
    ("flat_punch", {"punch_radius": 1e-3, "edge_radius": 2e-3}),
])
def test_a_caps_gap_is_the_least_over_the_line_through_both_axes(shape, params) -> None:
    """`cap_gap` against a brute-force minimum of (t - r)^2 / (2 beta) + z(|t|) over t, the indenter's
    own profile, at caps on the apex or face, near it and far out (within 1e-9 of the largest gap)."""
    from g2tom.physics.indenter import profile

    beta = 60e-6
    t = np.linspace(-4e-3, 4e-3, 4_000_001)
    z = profile(np.abs(t), shape, **params)
    for r in (0.0, 5e-6, 2e-5, 3e-4, 1.2e-3, 2.5e-3):
        brute = float(np.min((t - r) ** 2 / (2 * beta) + z))
        assert float(dc.cap_gap(np.array([r]), shape, beta, **params)[0]) == pytest.approx(brute, rel=1e-6, abs=1e-13)
    # never above the tip-evaluated profile; equal to it only where the indenter is flat under the cap
    r = np.linspace(0.0, 2.5e-3, 11)
    assert np.all(dc.cap_gap(r, shape, beta, **params) <= profile(r, shape, **params) + 1e-18)


def test_the_stage_places_caps_by_their_first_contact_with_every_indenter() -> None:
    """The stage's gap and Hertz radius are the physics' closed forms for the scenario's indenter:
    a cone of slope s lowers every flank cap's gap by s^2 beta / 2, a sphere's radius is beta R / (beta + R)."""
    from g2tom.before_work import load_scenario
    from g2tom.models.discrete_pool import cap_contact

    cone = load_scenario("paper", {"indenter.shape": "cone", "indenter.cone_angle": 0.2})
    gap, radius = cap_contact(cone)
    s, beta = np.tan(0.2), cone.roughness.beta
    assert radius == beta
    assert gap(np.array([1e-3]))[0] == pytest.approx(s * 1e-3 - s * s * beta / 2, rel=1e-12)
    sphere = load_scenario("paper")
    gap, radius = cap_contact(sphere)
    big_r = sphere.indenter.radius
    assert radius == pytest.approx(beta * big_r / (beta + big_r), rel=1e-12)
    assert gap(np.array([6e-4]))[0] == pytest.approx(6e-4**2 / (2 * (big_r + beta)), rel=1e-12)


# ---------------------------------------------------------------- caps capped at a hardness
@pytest.mark.parametrize("hardness", [5e9, 2e9])
def test_capped_caps_balance_the_force_and_obey_barber_through_their_unloading_stiffness(hardness):
    """Capped caps (psi 20-50): each cap carries its law's force at its interference times the share of
    its disc it owns (its power cell, from the discs of every touching cap), the forces sum to F, the
    interference closes the coupled gap; each spot has the owned area; the conductance of the spots is
    the unloading stiffness over E* rho* (Barber), and the loading stiffness is lower once caps yield."""
    asp = surface(5)
    cap = CappedCap(E_STAR, BETA, hardness)
    sol = dc.solve_forces(asp, sphere, FORCES, E_STAR, BETA, FLOOR, cap=cap)
    g = asp.z - sphere(np.hypot(asp.x, asp.y))
    kernel = dc.interaction_kernel(asp.x, asp.y, FLOOR)
    np.testing.assert_allclose(sol.load.sum(axis=1), FORCES, rtol=1e-9)
    for f in range(FORCES.size):
        w = g - sol.delta[f] - kernel @ sol.load[f] / E_STAR
        touching = sol.load[f] > 0
        np.testing.assert_allclose(w[touching], sol.interference[f, touching], rtol=0, atol=1e-9 * SIGMA)
        disc = cap.radius(sol.interference[f])
        share = np.ones_like(disc)
        share[disc > 0] = np.clip(owned_areas(asp.x, asp.y, disc)[disc > 0] / (np.pi * disc[disc > 0] ** 2), 0, 1)
        np.testing.assert_allclose(sol.load[f], share * cap.load(sol.interference[f]), rtol=1e-12,
                                   atol=1e-12 * FORCES[f])
        np.testing.assert_allclose(sol.radii[f], np.sqrt(share) * disc, rtol=1e-12, atol=1e-15)
    assert share.min() < 0.9  # the heaviest force's discs overlap: the test holds the sharing
    r_point = resistances(kernel, sol.radii, RHO, "point")
    np.testing.assert_allclose(1.0 / r_point, sol.unloading_stiffness / (E_STAR * RHO), rtol=1e-8)
    yielded = (sol.interference > cap.omega_c).any(axis=1)
    assert yielded[-1] and np.all(sol.stiffness[yielded] < sol.unloading_stiffness[yielded])


def discs_meet(asp: dc.Asperities, radii: np.ndarray) -> bool:
    """Whether any two contact discs of radii ``radii`` (m) at the asperities overlap."""
    on = radii > 0
    d = np.hypot(asp.x[on, None] - asp.x[None, on], asp.y[on, None] - asp.y[None, on])
    reach = radii[on, None] + radii[None, on]
    np.fill_diagonal(d, np.inf)
    return bool((d < reach).any())


class _ApartCap(CappedCap):
    """The capped law whose discs never share their overlaps: the isolated caps' solve."""

    shares_overlap = False


def test_capped_caps_that_overlap_none_are_the_isolated_caps_solution():
    """On a sparse surface (no two discs meet) the shared solve (Newton on the full Jacobian) gives the
    isolated caps' solve (the symmetric Newton) to the solver's tolerance; on a dense one it sinks deeper."""
    rng = np.random.default_rng(11)
    sparse = dc.Asperities(*(rng.uniform(-2e-3, 2e-3, (2, 40))), SIGMA * rng.standard_normal(40))
    forces = FORCES[:3]
    shared = dc.solve_forces(sparse, sphere, forces, E_STAR, BETA, FLOOR, cap=CappedCap(E_STAR, BETA, 2e9))
    apart = dc.solve_forces(sparse, sphere, forces, E_STAR, BETA, FLOOR, cap=_ApartCap(E_STAR, BETA, 2e9))
    np.testing.assert_allclose(shared.delta, apart.delta, rtol=0, atol=1e-9 * SIGMA)
    np.testing.assert_allclose(shared.radii, apart.radii, rtol=1e-8, atol=1e-15)
    np.testing.assert_allclose(shared.stiffness, apart.stiffness, rtol=1e-7)
    assert not any(discs_meet(sparse, radii) for radii in apart.radii)
    dense = surface(5)
    shared = dc.solve_forces(dense, sphere, FORCES, E_STAR, BETA, FLOOR, cap=CappedCap(E_STAR, BETA, 2e9))
    apart = dc.solve_forces(dense, sphere, FORCES, E_STAR, BETA, FLOOR, cap=_ApartCap(E_STAR, BETA, 2e9))
    assert shared.delta[-1] < apart.delta[-1] - 0.1 * SIGMA


def test_shared_caps_jacobian_is_the_derivative_of_their_loads():
    """The shared caps' dP/dw (diagonal and neighbours') equals central differences of their loads."""
    rng = np.random.default_rng(5)
    n = 60
    x, y = rng.uniform(-6e-5, 6e-5, (2, n))
    cap = CappedCap(E_STAR, BETA, 2e9)
    caps = dc._SharedCaps(cap, x, y)
    w = cap.omega_c * rng.uniform(0.5, 60.0, n)
    active = np.flatnonzero(caps.load(w) > 0)
    diagonal, (rows, cols, values) = caps.jacobian(w, active)
    rest = np.zeros((active.size, active.size))
    np.add.at(rest, (rows, cols), values)
    exact = np.diag(diagonal) + rest
    numeric = np.empty((active.size, active.size))
    for k, j in enumerate(active):
        step = np.zeros(n)
        step[j] = 1e-6 * w[j]
        numeric[:, k] = ((caps.load(w + step) - caps.load(w - step)) / (2 * step[j]))[active]
    np.testing.assert_allclose(exact, numeric, rtol=0, atol=1e-6 * np.abs(exact).max())
    assert np.count_nonzero(rest) > n // 2


def test_capped_caps_far_above_any_yield_are_the_elastic_solution():
    """A hardness no cap reaches (H -> infinity) gives the elastic caps' answer wherever no two Hertz discs
    overlap; where some do (the heavier forces here) the capped caps still share them, which moves the
    approach by a few parts in 10^4."""
    asp = surface(6)
    elastic = dc.solve_forces(asp, sphere, FORCES, E_STAR, BETA, FLOOR)
    capped = dc.solve_forces(asp, sphere, FORCES, E_STAR, BETA, FLOOR, cap=CappedCap(E_STAR, BETA, 1e15))
    apart = np.array([not discs_meet(asp, radii) for radii in elastic.radii])
    assert apart[:5].all() and not apart.all()
    np.testing.assert_allclose(capped.delta[apart], elastic.delta[apart], rtol=1e-12)
    np.testing.assert_allclose(capped.radii[apart], elastic.radii[apart], rtol=1e-12, atol=0)
    np.testing.assert_allclose(capped.stiffness[apart], elastic.stiffness[apart], rtol=1e-12)
    np.testing.assert_allclose(capped.delta, elastic.delta, rtol=1e-3)


def test_yielding_caps_widen_the_spots_and_lower_the_resistance_at_a_force():
    """At the same force yielding caps sink deeper and touch over more area: R falls below the elastic R."""
    asp = surface(7)
    kernel = dc.interaction_kernel(asp.x, asp.y, FLOOR)
    elastic = dc.solve_forces(asp, sphere, FORCES, E_STAR, BETA, FLOOR)
    capped = dc.solve_forces(asp, sphere, FORCES, E_STAR, BETA, FLOOR, cap=CappedCap(E_STAR, BETA, 2e9))
    assert np.all(capped.delta <= elastic.delta + 1e-15)
    assert np.all(resistances(kernel, capped.radii, RHO, "point") < resistances(kernel, elastic.radii, RHO, "point"))
