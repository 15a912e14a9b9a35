"""The control variate of the geometric mean: the exact clean probability of the random-phase field,
the estimator against its formula by hand, its bootstrap against expanded resamples, its gain and
its bias on a synthetic ensemble, and the stages with fits.control_variate = clean_share."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.stats import norm

from g2tom.fitting.control_variate import bootstrap_controlled_mean, controllable, controlled_mean
from g2tom.fitting.powerlaw import bootstrap_log_mean, resample_counts
from g2tom.physics.oxide_marginal import MIN_MODES, clean_probability


def test_clean_probability_is_the_normal_one_for_many_equal_modes_and_the_sampled_one_for_few() -> None:
    many = np.full(4000, np.sqrt(2.0 / 4000))
    for t in (-1.28, 0.0, 0.52, 1.28):  # the CLT's error is O(1/N) in the tails: 4000 modes, < 1e-4
        assert clean_probability(many, t) == pytest.approx(norm.cdf(t), abs=1e-4)
    rng = np.random.default_rng(11)
    weight = rng.uniform(0.3, 1.7, 24)
    weight *= np.sqrt(2.0 / np.sum(weight**2))
    psi = np.zeros(400_000)
    for w in weight:  # 24 modes: visibly not normal in the tails, sampled directly
        psi += w * np.cos(rng.uniform(0.0, 2.0 * np.pi, psi.size))
    for t in (-1.6, -0.5, 0.8, 1.6):
        sampled = np.mean(psi < t)
        assert clean_probability(weight, t) == pytest.approx(sampled, abs=4 * np.sqrt(sampled * (1 - sampled) / psi.size))
    assert clean_probability(weight, 0.0) == pytest.approx(0.5, abs=1e-12)  # a symmetric distribution
    with pytest.raises(ValueError, match="at least"):
        clean_probability(weight[: MIN_MODES - 1], 0.0)


def _by_hand(values: np.ndarray, x: np.ndarray, p: float) -> float:
    """The estimator written out: the adjusted mean of y c over the adjusted share of conducting."""
    c = np.isfinite(values).astype(float)
    y = np.where(c > 0, np.log(np.where(c > 0, values, 1.0)), 0.0)
    var = np.var(x)
    b_n = np.mean((x - x.mean()) * (y - y.mean())) / var
    b_d = np.mean((x - x.mean()) * (c - c.mean())) / var
    return float(np.exp((y.mean() - b_n * (x.mean() - p)) / (c.mean() - b_d * (x.mean() - p))))


def _ensemble(rng: np.random.Generator, n: int, opens: bool) -> tuple[np.ndarray, np.ndarray]:
    """A synthetic step: x ~ U(0, 1) (expectation 0.5), ln R = 1 - 2 x + noise; open where x < 0.1."""
    x = rng.uniform(0.0, 1.0, n)
    r = np.exp(1.0 - 2.0 * x + 0.1 * rng.standard_normal(n))
    if opens:
        r[x < 0.1] = np.inf
    return r, x


@pytest.mark.parametrize("opens", [False, True])
def test_the_estimate_is_its_formula_and_the_bootstrap_the_expanded_resamples(opens: bool) -> None:
    rng = np.random.default_rng(5)
    r, x = _ensemble(rng, 60, opens)
    assert controlled_mean(r, x, 0.5) == pytest.approx(_by_hand(r, x, 0.5), rel=1e-12)
    table = resample_counts(60, 7, rng)
    boot = bootstrap_controlled_mean(r, x, np.array(0.5), table)
    for k, counts in enumerate(table):
        pick = np.repeat(np.arange(60), counts)
        assert boot[k] == pytest.approx(_by_hand(r[pick], x[pick], 0.5), rel=1e-10)


def test_without_the_control_the_plain_geometric_mean_is_kept() -> None:
    rng = np.random.default_rng(6)
    r, x = _ensemble(rng, 40, True)
    flat = np.full(40, 0.3)  # no spread: nothing to regress on
    gap = x.copy()
    gap[3] = np.nan  # a step without contact in one realization
    table = resample_counts(40, 5, rng)
    for control in (flat, gap):
        assert not controllable(r, control)
        np.testing.assert_array_equal(bootstrap_controlled_mean(r, control, np.array(0.5), table),
                                      bootstrap_log_mean(r, table, True))


@pytest.mark.parametrize("opens, ratio", [(False, 0.25), (True, 0.7)])
def test_the_control_shrinks_the_error_without_a_bias(opens: bool, ratio: float) -> None:
    """Over 2,000 synthetic ensembles of 100: the estimate's spread is a fraction of the plain mean's
    (x explains most of ln R; with open circuits below x = 0.1 the linear adjustment of the ratio
    gains less: measured 0.57), and its mean lies on the truth within a few of its standard errors."""
    rng = np.random.default_rng(7)
    trials = np.array([[np.log(controlled_mean(r, x, 0.5)), np.log(bootstrap_log_mean(r, np.ones((1, 100), int), True)[0])]
                       for r, x in (_ensemble(rng, 100, opens) for _ in range(2000))])
    # E[ln R | conducting] for ln R = 1 - 2x + noise, x ~ U(0, 1), conducting where x >= 0.1
    truth = 1.0 - 2.0 * (0.55 if opens else 0.5)
    controlled, plain = trials[:, 0], trials[:, 1]
    assert np.std(controlled) < ratio * np.std(plain)
    assert np.mean(controlled) == pytest.approx(truth, abs=4 * np.std(controlled) / np.sqrt(2000) + 1e-3)
    assert np.mean(plain) == pytest.approx(truth, abs=4 * np.std(plain) / np.sqrt(2000))


DISCRETE_CV = {"contact.model": "discrete", "contact.surfaces": 4, "oxide.xi": [0.3, 0.7], "oxide.lambda": [1.0, 9.0],
               "oxide.n_realizations": 12, "cube.model": "point", "oxide.spot_rule": "disc"}


@pytest.fixture(scope="module")
def stages():
    """The small discrete chain with and without the control variate (the same contact and fields)."""
    from g2tom.before_work.domains import resolve
    from g2tom.compute import ComputeOptions
    from g2tom.before_work import load_scenario
    from g2tom.stages import contact, cube, fits, oxide
    from tests.conftest import SMALL_OVERRIDES

    quiet = ComputeOptions(progress=False)
    out = {}
    for name in ("none", "clean_share"):
        scene = resolve(load_scenario("paper", {**SMALL_OVERRIDES, **DISCRETE_CV, "fits.control_variate": name}))
        c = contact.build(scene, quiet)
        k = cube.build(scene, c, oxide.build(scene, quiet), quiet)
        out[name] = (scene, k, fits.build(scene, k))
    return out


def test_the_stages_record_the_control_and_adjust_the_geometric_mean(stages) -> None:
    (plain_scene, plain_cube, plain_fits), (scene, k, f) = stages["none"], stages["clean_share"]
    # the physics is the same; only the control is recorded, its expectation ~ 1 - xi
    np.testing.assert_array_equal(k["resistance"].values, plain_cube["resistance"].values)
    assert "clean_share" not in plain_cube and "control_variate_applied" not in plain_fits
    share = k["clean_share"].values
    assert np.nanmin(share) >= 0.0 and np.nanmax(share) <= 1.0
    np.testing.assert_allclose(k["clean_share_expected"].values, (1.0 - k["xi"].values)[:, None] * np.ones(2), atol=2e-3)
    assert k["clean_share"].attrs["units"] == "1" and k["clean_share_expected"].attrs["long_name"]
    # the fitted geometric mean is the estimator on the cube's own columns, cell by cell
    applied = f["control_variate_applied"].transpose("xi", "lambda", "delta").values.astype(bool)
    assert applied.any()
    r = k["resistance"].transpose("xi", "lambda", "delta", "realization").values
    x = k["clean_share"].transpose("xi", "lambda", "delta", "realization").values
    p = k["clean_share_expected"].transpose("xi", "lambda").values
    mean = f["geometric_mean"].transpose("xi", "lambda", "delta").values
    plain = plain_fits["geometric_mean"].transpose("xi", "lambda", "delta").values
    for z, a, d in zip(*np.nonzero(applied)):
        assert mean[z, a, d] == pytest.approx(controlled_mean(r[z, a, d], x[z, a, d], p[z, a]), rel=1e-12)
    np.testing.assert_array_equal(mean[~applied], plain[~applied])
    assert not np.allclose(mean[applied], plain[applied])
    np.testing.assert_allclose(f["geometric_mean_normalized"].values, f["geometric_mean"].values / scene.resistance_scale,
                               rtol=1e-12)
    # the option is part of the cube's and the fits' configuration, and "none" of neither
    assert scene.config_hash("cube") != plain_scene.config_hash("cube")
    assert "fits.control_variate" not in plain_scene.stage_parameters("fits")


def test_the_control_variate_is_refused_where_its_expectation_is_not_exact() -> None:
    from g2tom.config import ConfigError
    from g2tom.before_work import load_scenario

    for key, value in (("contact.model", "greenwood_tripp"), ("oxide.amplitudes", "rayleigh"),
                       ("fits.reduction", "median"), ("oxide.threshold", "empirical")):
        overrides = {**DISCRETE_CV, "fits.control_variate": "clean_share", key: value}
        if key == "contact.model":
            overrides["oxide.spot_rule"] = "centre"
        with pytest.raises(ConfigError, match=f"{key} = '{value}' is not allowed with fits.control_variate"):
            load_scenario("paper", overrides)


def test_auto_takes_the_control_variate_where_it_applies_and_leaves_it_elsewhere() -> None:
    """The default study's ``auto`` is settled as the scenario loads; published's hashes stay."""
    from g2tom.before_work import load_scenario
    from g2tom.config import read_scenario

    assert read_scenario("paper").fits.control_variate == "auto"
    assert load_scenario("paper").fits.control_variate == "clean_share"
    for name in ("paper_gt", "published"):
        assert load_scenario(name).fits.control_variate == "none"
    for key, value in (("oxide.threshold", "empirical"), ("fits.reduction", "median"), ("oxide.amplitudes", "rayleigh")):
        assert load_scenario("paper", {key: value}).fits.control_variate == "none"  # no refusal
    published = load_scenario("published")
    assert "fits.control_variate" not in published.stage_parameters("cube")
    assert load_scenario("published", {"fits.control_variate": "none"}).config_hash() == published.config_hash()


def _synthetic_steps(rng: np.random.Generator, n: int, p: float = 0.45) -> tuple[np.ndarray, np.ndarray]:
    """Three load steps of R (ohm, +inf where open) tied to a control of expectation ``p``: the
    lightest steps open most often where the control is small."""
    x = np.clip(p + 0.15 * rng.standard_normal(n), 0.01, 0.99)
    x = np.stack([x + 0.02 * rng.standard_normal(n) for _ in range(3)])
    log_r = 1.0 - 2.5 * (x - p) + 0.15 * rng.standard_normal((3, n)) - np.arange(3)[:, None] * 0.7
    opens = rng.uniform(size=(3, n)) < np.array([0.5, 0.2, 0.0])[:, None] * (1.0 - x) ** 2 * 3
    return np.where(opens, np.inf, np.exp(log_r)), x


def test_the_rules_controlled_half_width_is_the_linearized_error_of_the_fits_estimate_at_every_prefix() -> None:
    """Against the linearization written out prefix by prefix: the fits' slopes and adjusted ratio
    (:func:`controlled_mean`), each realization's influence, its sample standard deviation."""
    from g2tom.fitting.ensemble import prefix_controlled_half_width

    rng = np.random.default_rng(8)
    resistance, x = _synthetic_steps(rng, 700)
    w = np.array([[0.5, 0.3, 0.2], [1.0, 0.0, -1.0]])
    width = prefix_controlled_half_width(resistance, x, 0.45, w, 1.96, first=4, block=64)
    assert np.all(np.isnan(width[:, :3]))
    for n in (12, 63, 64, 65, 200, 700):
        r, c = resistance[:, :n], x[:, :n]
        conducts = np.isfinite(r)
        y = np.where(conducts, np.log(np.where(conducts, r, 1.0)), 0.0)
        influence = np.zeros((2, n))
        for s in range(3):
            xc = c[s] - c[s].mean()
            b_n = np.mean(xc * (y[s] - y[s].mean())) / np.mean(xc**2)
            b_d = np.mean(xc * (conducts[s] - conducts[s].mean())) / np.mean(xc**2)
            share = conducts[s].mean() - b_d * (c[s].mean() - 0.45)
            m = float(np.log(controlled_mean(r[s], c[s], np.array(0.45))))
            influence += w[:, s : s + 1] * (y[s] - m * conducts[s] - (b_n - m * b_d) * c[s]) / share
        expected = 1.96 * influence.std(axis=1, ddof=1) / np.sqrt(n)
        assert width[:, n - 1] == pytest.approx(expected, rel=1e-9), n


def test_the_rules_controlled_half_width_measures_the_scatter_of_the_fits_estimate() -> None:
    """Over 400 independent ensembles of 300 realizations (open circuits at the light steps, tied
    to the control): the rule's standard error, averaged, within 8 % of the observed standard
    deviation of the fits' controlled estimate, and well under the plain estimate's scatter."""
    from g2tom.fitting.ensemble import prefix_controlled_half_width

    rng = np.random.default_rng(21)
    w = np.array([0.5, 0.3, 0.2])
    estimates, plain, predicted = [], [], []
    for _ in range(400):
        resistance, x = _synthetic_steps(rng, 300)
        m = np.log(controlled_mean(resistance, x, np.array(0.45)))
        estimates.append(w @ m)
        conducts = np.isfinite(resistance)
        plain.append(w @ (np.where(conducts, np.log(np.where(conducts, resistance, 1.0)), 0.0).sum(1) / conducts.sum(1)))
        predicted.append(prefix_controlled_half_width(resistance, x, 0.45, w, 1.0, first=300)[-1])
    observed = np.std(estimates, ddof=1)
    assert np.mean(predicted) == pytest.approx(observed, rel=0.08)
    assert observed < 0.7 * np.std(plain, ddof=1)
