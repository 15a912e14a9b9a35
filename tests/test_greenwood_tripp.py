"""Influence matrix, solvers and limits of the axisymmetric Greenwood–Tripp solve."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import quad
from scipy.special import ellipkm1, i0e

from g2tom.before_work import load_scenario
from g2tom.physics import greenwood_tripp as gt
from g2tom.physics import radial_grid as rg
from g2tom.physics.asperity import asperity_pressure
from g2tom.physics.hertz import (
    hertz_approach,
    hertz_displacement,
    hertz_force,
    hertz_pressure,
    hertz_radius,
    roughness_parameter,
)
from g2tom.physics.indenter import profile
from g2tom.contact_solution import indenter_profile, layer as _layer, radial_grid
from g2tom.before_work.domains import solve_scenario


def _quad_displacement(r_nodes, p_nodes, r, e_star):
    """Eq. 18 for the piecewise-linear pressure by adaptive quadrature, element by element."""
    def integrand(rho):
        return rho / (rho + r) * np.interp(rho, r_nodes, p_nodes) * ellipkm1(((rho - r) / (rho + r)) ** 2)
    total = sum(quad(integrand, a, b, epsabs=0, epsrel=1e-12, limit=200)[0]
                for a, b in zip(r_nodes[:-1], r_nodes[1:]))
    return 4.0 / (math.pi * e_star) * total


def test_influence_matrix_matches_quadrature_of_linear_pressure():
    r = rg.radial_nodes(41, 4.0)
    p = np.exp(-r**2) * (1 + r)
    u = rg.influence_matrix(r, 2.0) @ p
    for i in (0, 1, 2, 7, 25, 40):
        assert u[i] == pytest.approx(_quad_displacement(r, p, r[i], 2.0), rel=1e-8)


def test_influence_matrix_gaussian_pressure_converges_second_order():
    """p = exp(-r^2/s^2) gives u = sqrt(pi) s e^{-r^2/2s^2} I0(r^2/2s^2) / E*."""
    errors = []
    for n in (100, 200, 400):
        r = rg.radial_nodes(n, 6.0)
        exact = math.sqrt(math.pi) * i0e(r**2 / 2)
        errors.append(np.max(np.abs(rg.influence_matrix(r, 1.0) @ np.exp(-r**2) - exact)) / exact.max())
    assert errors[-1] < 3e-5
    assert 3.5 < errors[0] / errors[1] < 4.5 and 3.5 < errors[1] / errors[2] < 4.5


def test_influence_matrix_hertz_displacement():
    a, p0, e_star = 2.0, 1.0, 1.0
    r = rg.radial_nodes(400, 6.0)
    u = rg.influence_matrix(r, e_star) @ (p0 * np.sqrt(np.clip(1 - r**2 / a**2, 0, None)))
    inside = r <= a
    exact = math.pi * p0 * (2 * a**2 - r[inside] ** 2) / (4 * a * e_star)
    np.testing.assert_allclose(u[inside], exact, rtol=2e-3)  # sqrt edge: O(h^1.5)


def test_force_weights_exact_for_linear_pressure():
    r = rg.graded_nodes(50, 3.0, 1.0)
    assert rg.force_weights(r) @ (1 - r / 3.0) == pytest.approx(math.pi * 9 / 3, rel=1e-13)


def test_graded_nodes():
    r = rg.graded_nodes(100, 3.0, 2.0)
    steps = np.diff(r)
    assert len(r) == 100 and r[0] == 0 and r[-1] == 3.0 and np.all(steps > 0)
    assert steps[-1] / steps[0] == pytest.approx(4.0, rel=0.1)
    np.testing.assert_array_equal(rg.graded_nodes(10, 3.0, 5.0), rg.radial_nodes(10, 3.0))


@pytest.mark.parametrize("bad", [{"n": 1}, {"r_max": 0.0}, {"r_max": float("nan")}])
def test_radial_nodes_validation(bad):
    args = {"n": 10, "r_max": 1.0, **bad}
    with pytest.raises(ValueError, match="out of range"):
        rg.radial_nodes(args["n"], args["r_max"])


def test_solver_validation():
    with pytest.raises(ValueError, match="solver = 'gauss'"):
        gt.solve(np.eye(2), np.zeros(2), [0.0], gt.Layer(1, 1, 1, 1), solver="gauss")


def _check_residual(scenario, r, sols):
    """Recompute max|u - M p(u)| / max|M p(u)| independently of the solver."""
    rough = scenario.roughness
    m = rg.influence_matrix(r, scenario.material.E_star)
    z = profile(r, radius=scenario.indenter.radius)
    for delta, sol in zip(scenario.deltas, sols):
        image = m @ asperity_pressure(delta + z + sol.displacement, rough.sigma, rough.eta,
                                      rough.beta, scenario.material.E_star)
        yield np.max(np.abs(sol.displacement - image)) / np.max(np.abs(image))


def test_newton_residual_and_fixed_point_agreement(small):
    r, newton = solve_scenario(small)
    residuals = list(_check_residual(small, r, newton))
    assert max(residuals) <= 1e-10
    assert all(s.converged and s.residual <= 1e-10 for s in newton)
    # a true Newton step: a wrong Jacobian or a chord never refreshed needs 16-21 steps here
    assert max(s.iterations for s in newton) <= 12
    _, fixed = solve_scenario(small, solver="fixed_point")
    assert all(s.converged for s in fixed)
    for a, b in zip(newton, fixed):
        np.testing.assert_allclose(b.displacement, a.displacement, rtol=0,
                                   atol=5e-3 * np.max(a.displacement))


def test_fixed_point_not_converged_is_reported():
    sc = load_scenario("paper_gt", {"loading.n_delta": 2, "contact.n_radial": 40, "contact.max_iterations": 2})
    _, fixed = solve_scenario(sc, solver="fixed_point")
    assert not any(s.converged for s in fixed) and all(s.iterations == 2 for s in fixed)


def test_fixed_point_stops_at_the_papers_criterion():
    """Stop at the first k with ||u'_{k+1} - u_k|| <= zeta eps ||u_k|| (Sect. 2.5.1), not before."""
    sc = load_scenario("published", {"loading.n_delta": 1, "loading.delta_max": -2.0})
    r = rg.radial_nodes(sc.contact.n_radial, sc.contact.r_max * sc.indenter.radius)
    rough = sc.roughness
    layer = gt.Layer(rough.sigma, rough.eta, rough.beta, sc.material.E_star)
    args = (rg.influence_matrix(r, layer.e_star), profile(r, radius=sc.indenter.radius), [-2 * rough.sigma], layer)
    zeta, eps = 0.3, 1e-3
    (done,) = gt.solve(*args, solver="fixed_point", relaxation=zeta, fixed_point_tolerance=eps)
    n = done.iterations
    assert done.converged and 5 < n < 30
    u = [gt.solve(*args, solver="fixed_point", relaxation=zeta, fixed_point_tolerance=eps,
                  max_iterations=k)[0].displacement for k in (n - 2, n - 1)] + [done.displacement]
    ratio = [np.max(np.abs(b - a)) / np.max(np.abs(a)) for a, b in zip(u[:-1], u[1:])]
    assert ratio[0] > zeta * eps >= ratio[1]


def test_fixed_point_without_load_converges_at_once():
    """Zero pressure everywhere (far apart): u = 0 is the solution, not a failure to converge."""
    v, it, res, ok = gt.solve_fixed_point(np.zeros((3, 3)), np.full(3, 50.0), 0.3, 1e-3, 50)
    assert ok and it == 1 and res == 0.0 and not v.any()


def test_hertz_fields_against_the_influence_matrix():
    """Hertz displacement (inside and outside a) = M p_Hertz; the deformed gap closes inside a."""
    radius, e_star, force = 1.0, 1.0, 1e-3
    a = float(hertz_radius(force, radius, e_star))
    r = rg.radial_nodes(801, 4 * a)
    p = hertz_pressure(r, a, force)
    assert rg.force_weights(r) @ p == pytest.approx(force, rel=1e-3)
    u = hertz_displacement(r, a, force, e_star)
    np.testing.assert_allclose(u, rg.influence_matrix(r, e_star) @ p, rtol=1e-3)
    gap = profile(r, radius=radius) - hertz_approach(a, radius) + u
    np.testing.assert_allclose(gap[r <= a], 0.0, atol=1e-12 * a)
    assert np.all(gap[r > a] > 0)
    assert float(hertz_force(hertz_approach(a, radius), radius, e_star)) == pytest.approx(force, rel=1e-12)


def test_hertz_fields_vanish_without_load():
    r = np.linspace(0, 1, 5)
    assert not hertz_pressure(r, 0.0, 0.0).any() and not hertz_displacement(r, 0.0, 0.0, 1.0).any()
    assert roughness_parameter(1.0, 1.0, 0.0) == np.inf
    with pytest.raises(ValueError, match=r"force = -1 is out of range: must be >= 0 \(N\)"):
        hertz_radius(np.array([-1.0, 2.0]), 1.0, 1.0)


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"shape": "torus"}, "shape = 'torus' is not allowed: must be one of sphere, cone, flat_punch"),
        ({"radius": 0.0}, "radius = 0.0 is out of range: must be > 0 (m)"),
        ({"shape": "cone", "cone_angle": np.float64(2.0)}, "cone_angle = 2.0 is out of range"),
        ({"shape": "flat_punch", "edge_radius": -1.0}, "edge_radius = -1.0 is out of range"),
    ],
)
def test_profile_validation(kwargs, message):
    with pytest.raises(ValueError) as err:
        profile([0.0, 1.0], **kwargs)
    assert message in str(err.value)


def test_profiles():
    r = np.array([0.0, 1.0, 3.0])
    np.testing.assert_allclose(profile(r, "cone", cone_angle=0.1), r * math.tan(0.1))
    np.testing.assert_allclose(profile(r, "flat_punch", punch_radius=1.0, edge_radius=2.0), [0, 0, 1.0])


def test_roughness_parameter_at_minus_two_sigma():
    """Table 1 at delta = -2 sigma: sigma R*/a^2 ~= 0.361 (Sect. 2.5.1)."""
    sc = load_scenario("paper_gt", {"loading.n_delta": 1, "loading.delta_max": -2.0})
    r, (sol,) = solve_scenario(sc)
    rough, e_star, radius = sc.roughness, sc.material.E_star, sc.indenter.radius
    p = asperity_pressure(-2 * rough.sigma + profile(r, radius=radius) + sol.displacement,
                          rough.sigma, rough.eta, rough.beta, e_star)
    a = hertz_radius(rg.force_weights(r) @ p, radius, e_star)
    assert roughness_parameter(rough.sigma, radius, a) == pytest.approx(0.361, rel=0.01)


def _limit_force(stiffening: float) -> tuple[float, float]:
    """Force of a smooth (sigma = 1 nm), stiffened layer and Hertz's at the same interpenetration."""
    radius, e_star, delta = 10e-3, 1.15e11, -20e-6
    layer = gt.Layer(sigma=1e-9, eta=2e8 * stiffening, beta=30e-6, e_star=e_star)
    r = rg.radial_nodes(400, 1e-3)
    (sol,) = gt.solve(rg.influence_matrix(r, e_star), profile(r, radius=radius), [delta], layer)
    assert sol.converged
    p = asperity_pressure(delta + profile(r, radius=radius) + sol.displacement,
                          layer.sigma, layer.eta, layer.beta, e_star)
    return float(rg.force_weights(r) @ p), float(hertz_force(-delta, radius, e_star))


def test_hertz_limit():
    """As sigma -> 0 delta is the interpenetration of smooth bodies; a stiff layer gives Hertz."""
    soft, hertz = _limit_force(1e2)
    stiff, _ = _limit_force(1e6)
    assert abs(stiff / hertz - 1) < 2e-4
    assert abs(stiff / hertz - 1) < abs(soft / hertz - 1)


def _scene(scenario):
    """Nodes, influence matrix, profile and layer of a scenario's solve."""
    r = radial_grid(scenario)
    layer = _layer(scenario)
    return r, rg.influence_matrix(r, layer.e_star), indenter_profile(scenario, r), layer


def test_stiffness_against_a_central_difference_of_fine_steps(small):
    """K = -dF/d delta from the linearised system equals (F(delta - e) - F(delta + e)) / 2e."""
    r, m, z, layer = _scene(small)
    deltas = np.asarray(small.deltas)
    stiffness = gt.stiffness(m, z, deltas, layer, gt.solve(m, z, deltas, layer), r)
    e = 1e-4 * layer.sigma

    def force(delta):
        (sol,) = gt.solve(m, z, [delta], layer, tolerance=1e-14)
        assert sol.converged
        return rg.force_weights(r) @ asperity_pressure(delta + z + sol.displacement, layer.sigma,
                                                       layer.eta, layer.beta, layer.e_star)

    difference = np.array([(force(d - e) - force(d + e)) / (2 * e) for d in deltas])
    assert np.all(stiffness > 0)
    np.testing.assert_allclose(stiffness, difference, rtol=1e-6)


def test_stiffness_of_a_stiff_smooth_layer_is_hertz():
    """As the layer stiffens K -> dF_Hertz/d delta = 2 E* a, a = sqrt(R |delta|)."""
    radius, e_star, delta = 10e-3, 1.15e11, -20e-6
    r = rg.radial_nodes(400, 1e-3)
    m, z = rg.influence_matrix(r, e_star), profile(r, radius=radius)
    errors = []
    for stiffening in (1e2, 1e6):
        layer = gt.Layer(sigma=1e-9, eta=2e8 * stiffening, beta=30e-6, e_star=e_star)
        (k,) = gt.stiffness(m, z, [delta], layer, gt.solve(m, z, [delta], layer), r)
        errors.append(abs(k / (2 * e_star * math.sqrt(-radius * delta)) - 1))
    assert errors[1] < 1e-3 < errors[0]


def test_stiffness_needs_one_solution_per_approach():
    layer = gt.Layer(1, 1, 1, 1)
    with pytest.raises(ValueError, match="1 solutions for 2 approaches"):
        gt.stiffness(np.eye(2), np.zeros(2), [0.0, 1.0], layer,
                     gt.solve(np.eye(2), np.zeros(2), [0.0], layer), np.array([0.0, 1.0]))


def test_influence_matrix_of_repeated_nodes_is_a_fresh_copy_of_the_same_bits():
    """The matrix kept for a node set is the one computed afresh, bit for bit (tolerance 0), and
    each call gets its own writable array: changing one leaves the next call's intact."""
    r = rg.graded_nodes(97, 3.0e-3, 1.0e-3)
    first = rg.influence_matrix(r, 7.0e10)
    fresh = 4.0 / (np.pi * 7.0e10) * rg._unscaled_matrix(r)
    assert np.array_equal(first.view(np.int64), fresh.view(np.int64))
    first[:] = 0.0
    again = rg.influence_matrix(r.copy(), 7.0e10)
    assert again.flags.writeable and np.array_equal(again.view(np.int64), fresh.view(np.int64))
    other = rg.influence_matrix(r, 1.4e11)  # the same nodes, another modulus: the factor alone changes
    assert np.array_equal(other.view(np.int64), (4.0 / (np.pi * 1.4e11) * rg._unscaled_matrix(r)).view(np.int64))
