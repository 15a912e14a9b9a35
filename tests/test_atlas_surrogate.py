"""The atlas surrogate over (xi, lambda, mu, Pi): recovers a smooth function from noisy scenes."""

from __future__ import annotations

import numpy as np
import pytest

from g2tom.fitting.atlas_surrogate import exponents, fit_atlas_model, select_degree


def truth(xi, lam, mu, pi):
    """A smooth ln alpha of the log coordinates (cubic in ln mu, with cross terms)."""
    z, w, m, q = -np.log1p(-xi), np.log(lam), np.log(mu), np.log(pi)
    return -1.4 + 0.6 * z + 0.08 * z**2 + 0.03 * w - 0.25 * m + 0.04 * m**2 - 0.015 * m**3 + 0.05 * q + 0.02 * z * m


def _scenes(rng, n_scenes: int):
    xi = np.linspace(0.1, 0.9, 5)
    lam = np.array([1.0, 3.0, 7.0, 11.0, 17.0, 23.0])
    mu = np.exp(rng.uniform(np.log(1), np.log(50), n_scenes))
    pi = np.exp(rng.uniform(np.log(5), np.log(320), n_scenes))
    grid = np.array([(a, b, s) for s in range(n_scenes) for a in xi for b in lam])
    s = grid[:, 2].astype(int)
    return grid[:, 0], grid[:, 1], mu[s], pi[s], s


def test_exponents_count_the_monomials() -> None:
    assert [len(exponents(d)) for d in range(5)] == [1, 5, 15, 35, 70]
    assert exponents(1).tolist()[0] == [0, 0, 0, 0]


def test_recovers_a_smooth_function_from_noisy_scenes() -> None:
    rng = np.random.default_rng(np.random.SeedSequence(23))
    xi, lam, mu, pi, scene = _scenes(rng, 25)
    noise = 0.02
    alpha = np.exp(truth(xi, lam, mu, pi) + rng.normal(0.0, noise, xi.size))
    sigma = np.full(xi.size, noise)
    degree, scores = select_degree(xi, lam, mu, pi, alpha, sigma, scene, range(1, 5))
    assert degree == 3, scores  # the truth's degree: lower underfits, higher adds nothing
    assert scores[3] < 1.5 * noise and scores[1] > 2 * noise
    model = fit_atlas_model(xi, lam, mu, pi, alpha, sigma, degree)
    # held-out scenes, drawn inside the box, never fitted: within 2 % of the truth everywhere
    hxi, hlam, hmu, hpi, _ = _scenes(np.random.default_rng(7), 6)
    error = np.log(model(hxi, hlam, hmu, hpi)) - truth(hxi, hlam, hmu, hpi)
    assert np.max(np.abs(error)) < 0.02


def test_identity_transform_and_refusals() -> None:
    rng = np.random.default_rng(1)
    xi, lam, mu, pi, scene = _scenes(rng, 4)
    gamma = 0.3 + 0.1 * np.log(mu)
    model = fit_atlas_model(xi, lam, mu, pi, gamma, np.full(xi.size, 0.01), 1, "identity")
    np.testing.assert_allclose(model(xi, lam, mu, pi), gamma, rtol=1e-10)
    with pytest.raises(ValueError, match="positive"):
        fit_atlas_model(xi, lam, mu, pi, gamma - 1.0, np.full(xi.size, 0.01), 1, "log")
    with pytest.raises(ValueError, match="cannot fit degree 4"):
        fit_atlas_model(xi[:40], lam[:40], mu[:40], pi[:40], gamma[:40], np.full(40, 0.01), 4, "identity")


def test_design_by_parents_equals_the_products_of_powers():
    """The monomial table built term by term from a parent equals prod_i u_i^p_i (5 coordinates)."""
    from g2tom.fitting.atlas_surrogate import AtlasModel

    rng = np.random.default_rng(3)
    powers = exponents(4, 5)
    model = AtlasModel("log", np.zeros(5), np.ones(5), powers, rng.standard_normal(powers.shape[0]))
    x = rng.uniform(0.0, 1.0, (50, 5))
    u = 2.0 * x - 1.0
    direct = np.prod(u[:, None, :] ** powers[None, :, :], axis=-1)
    np.testing.assert_allclose(model._design(x), direct, rtol=1e-13, atol=1e-15)


def test_curve_over_the_load_recovers_a_bending_law():
    """ln R' with a quadratic term in ln F' (a Barber-like bend) over (xi, lambda, mu, Pi, F')."""
    rng = np.random.default_rng(5)
    n = 3000
    xi, lam = rng.uniform(0.1, 0.9, n), rng.uniform(1.0, 23.0, n)
    mu, pi, f = np.exp(rng.uniform(0, 4, n)), np.exp(rng.uniform(1.6, 5.8, n)), np.exp(rng.uniform(-1, 3, n))
    ln_r = -0.5 - 0.6 * np.log(f) + 0.04 * np.log(f) ** 2 + 0.3 * -np.log1p(-xi) - 0.1 * np.log(mu) + 0.02 * np.log(lam)
    model = fit_atlas_model(xi, lam, mu, pi, np.exp(ln_r), np.full(n, 0.01), 2, "log", force_n=f)
    np.testing.assert_allclose(model.transformed(xi, lam, mu, pi, f), ln_r, atol=1e-10)
