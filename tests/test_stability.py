"""Numerical stability across extreme but valid scenarios, stage 1 to stage 4.

The sweep of :mod:`g2tom.bench.stability` (the stability map of ``make bench``) is checked
case by case under the ``stress`` marker (``make stress``); a fast subset runs in ``make test``.
"""

from __future__ import annotations

import numpy as np
import pytest

from g2tom.bench import stability
from g2tom.compute import ComputeOptions
from g2tom.before_work import load_scenario
from g2tom.before_work.domains import resolve, solve_scenario
from g2tom.contact_solution import fields
from g2tom.stages import contact, cube, fits, oxide

FAST = {"contact.n_radial": 240, "loading.n_delta": 8}

EXTREMES = {
    "tiny roughness": {"roughness.sigma": 1e-7, "oxide.lambda": [1.0]},  # a 3-cell window
    "deep and light loads": {"loading.delta_min": -12.0, "loading.delta_max": 6.0},
    "soft material": {"material.E": 1e8},
    "auxetic": {"material.nu": -0.9},
    "dense stiff asperities": {"roughness.eta": 1e10, "roughness.beta": 1e-4},
    "blunt cone": {"indenter.shape": "cone", "indenter.cone_angle": 0.02},
    "flat punch": {"indenter.shape": "flat_punch", "indenter.punch_radius": 5e-4, "indenter.edge_radius": 5e-3},
}


@pytest.mark.parametrize("overrides", EXTREMES.values(), ids=EXTREMES.keys())
def test_contact_converges_and_stays_physical(overrides) -> None:
    scenario = load_scenario("paper_gt", {**FAST, **overrides})
    ds = contact.build(scenario)
    force = ds["force"].values
    assert np.all(np.isfinite(force)) and np.all(force > 0)
    assert np.all(np.diff(force) > 0), "force must grow with every approach step"
    assert ds["converged"].values.all()
    assert ds["residual"].max() <= 1e-10
    for name in ("pressure", "separation", "area_fraction", "spot_radius"):
        assert np.isfinite(ds[name].values).all(), name
    assert (ds["pressure"] >= 0).all() and (ds["area_fraction"] >= 0).all()
    # A* = pi eta beta F_1(h) and F_1(h) <= sigma/sqrt(2 pi) + |h| for h <= 0
    rough = scenario.roughness
    bound = np.pi * rough.eta * rough.beta * (rough.sigma / np.sqrt(2 * np.pi) + np.abs(ds["separation"]))
    assert (ds["area_fraction"] <= bound * (1 + 1e-12)).all()


def test_nearly_full_oxide_gives_counted_open_circuits_and_finite_fits() -> None:
    scenario = resolve(load_scenario("paper_gt", {
        **FAST, "oxide.xi": [0.5, 0.99], "oxide.lambda": [23.0], "oxide.ensemble": "fixed", "oxide.n_realizations": 40,
        "fits.n_bootstrap": 20,
    }))
    quiet = ComputeOptions(progress=False)
    result = cube.build(scenario, contact.build(scenario), oxide.build(scenario, quiet), quiet)
    r = result["resistance"]
    assert not np.isnan(r.values).any()
    open_circuits = np.isinf(r.values)
    assert open_circuits.any(), "xi = 0.99 at lambda = 23 must leave some contacts fully oxidized"
    np.testing.assert_array_equal(open_circuits.sum(axis=-1), result["n_open"].values)
    np.testing.assert_array_equal(open_circuits, result["n_conducting"].values == 0)
    fitted = fits.build(scenario, result)
    assert (fitted["open_probability"].sel(xi=0.99) > 0).any()
    assert np.isfinite(fitted["alpha"].values).all() and np.isfinite(fitted["gamma"].values).all()
    assert (fitted["alpha"].sel(xi=0.99) > fitted["alpha"].sel(xi=0.5)).all()


# ----------------------------------------------------------------- the stability map's sweep
def _check_case(case: stability.Case) -> None:
    record, arrays = stability.evaluate(case)
    if record["status"] == "refused":  # validation said no: one line naming the parameter and range
        message = record["message"]
        assert "\n" not in message and " = " in message and ("out of range" in message or "must" in message)
        return
    assert record["status"] == "converged", record["message"]
    assert record["residual"] <= load_scenario("paper_gt").contact.tolerance
    for name in ("force", "pressure", "area_fraction"):
        assert np.isfinite(arrays[name]).all() and (arrays[name] >= 0).all(), name
    assert np.isfinite(arrays["separation"]).all()
    force, r_clean = arrays["force"], arrays["resistance_clean"]
    assert (force > 0).all() and np.all(np.diff(force) > 0), "force must grow with every approach step"
    assert not np.isnan(r_clean).any() and (r_clean > 0).all()
    conducting = np.isfinite(r_clean)
    assert record["open_circuits"] == int((~conducting).sum())  # open circuits are +inf and counted
    # once a spot touches it keeps touching: the open circuits are the lightest loads only
    assert not conducting.any() or conducting[np.argmax(conducting):].all()
    assert np.all(np.diff(r_clean[conducting]) < 0), "the clean resistance must fall with load"


SWEEP_FAST = ["indenter.shape=cone", "roughness.sigma=1e-09"]


@pytest.mark.parametrize("case", [c for c in stability.CASES if c.label in SWEEP_FAST], ids=lambda c: c.label)
def test_sweep_fast_subset(case) -> None:
    _check_case(case)


@pytest.mark.stress
@pytest.mark.parametrize("case", stability.CASES, ids=lambda c: c.label)
def test_sweep(case) -> None:
    _check_case(case)


@pytest.mark.stress
def test_hertz_limit_is_approached_as_the_roughness_parameter_vanishes() -> None:
    cases = [c for c in stability.CASES if c.parameter == "hertz_limit"]
    records = [stability.evaluate(c)[0] for c in cases]
    alpha = [r["roughness_parameter"] for r in records]
    gap = [abs(1.0 - r["hertz_ratio"]) for r in records]
    assert alpha == sorted(alpha, reverse=True) and alpha[-1] < 0.005
    assert gap == sorted(gap, reverse=True), "closer to Hertz at every smaller sigma R*/a^2"
    assert gap[-1] < 0.05


def test_clean_resistance_is_linear_in_rho_over_twelve_decades() -> None:
    low, high = (stability.evaluate(stability.Case("material.rho", v, {"material.rho": v}))[1]
                 for v in (1e-12, 1.0))
    np.testing.assert_allclose(high["resistance_clean"], 1e12 * low["resistance_clean"], rtol=1e-12)
    np.testing.assert_array_equal(high["force"], low["force"])


def test_unconverged_solve_is_reported_naming_the_case() -> None:
    case = stability.Case("contact.max_iterations", 1, {"contact.max_iterations": 1, "contact.tolerance": 1e-14})
    record, arrays = stability.evaluate(case)
    assert record["status"] == "unconverged" and not arrays["converged"].all()
    assert "contact.max_iterations=1" in record["message"] and "stopped after 1 iterations" in record["message"]


@pytest.mark.stress
def test_oxide_fraction_at_its_edges() -> None:
    scenario = resolve(load_scenario("paper_gt", {
        **FAST, "oxide.xi": [1e-6, 0.5, 1 - 1e-6], "oxide.lambda": [1.0, 19.0], "oxide.ensemble": "fixed",
        "oxide.n_realizations": 12,
    }))
    quiet = ComputeOptions(progress=False)
    result = cube.build(scenario, contact.build(scenario), oxide.build(scenario, quiet), quiet)
    r = result["resistance"]
    assert not np.isnan(r.values).any() and (r.values > 0).all()
    clean = result["resistance_clean"].values
    # xi = 1e-6: essentially no oxide, so every realization is the clean contact
    np.testing.assert_allclose(r.sel(xi=1e-6).values, np.broadcast_to(clean[..., None] if clean.ndim == 1
                               else clean, r.sel(xi=1e-6).shape), rtol=1e-6)
    # xi = 1 - 1e-6: essentially all oxide: open circuits, +inf and counted
    assert np.isinf(r.sel(xi=1 - 1e-6).values).all()
    np.testing.assert_array_equal(np.isinf(r.values).sum(axis=-1), result["n_open"].values)


@pytest.mark.stress
def test_random_scenes_converge_and_stay_physical() -> None:
    """Property-based: any scene drawn from the swept ranges solves to a physical contact."""
    from hypothesis import HealthCheck, assume, given, settings
    from hypothesis import strategies as st

    from g2tom.config import ConfigError

    @settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
    @given(sigma=st.floats(-9, -3), eta=st.floats(6, 14), beta=st.floats(-7, -3), radius=st.floats(-3, 0),
           top=st.floats(0, 10), depth=st.floats(0.5, 10),
           shape=st.sampled_from(["sphere", "cone", "flat_punch"]))
    def check(sigma, eta, beta, radius, top, depth, shape) -> None:
        try:
            scenario = load_scenario("paper_gt", {
                **stability.FAST, "roughness.sigma": 10**sigma, "roughness.eta": 10**eta,
                "roughness.beta": 10**beta, "indenter.radius": 10**radius, "indenter.shape": shape,
                "indenter.punch_radius": 0.05 * 10**radius, "indenter.edge_radius": 0.5 * 10**radius,
                "loading.delta_max": top, "loading.delta_min": top - depth - 0.5,
            })
        except ConfigError:
            assume(False)  # refused by validation with its own message: not this property
        r, sols = solve_scenario(scenario)
        f = fields(scenario, r, sols)
        assert all(s.converged for s in sols), [s.residual for s in sols]
        assert np.isfinite(f["force"]).all() and (f["force"] > 0).all() and np.all(np.diff(f["force"]) > 0)
        assert np.isfinite(f["p"]).all() and (f["p"] >= 0).all() and (f["area"] >= 0).all()

    check()
