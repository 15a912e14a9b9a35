"""Scenario loading, overrides, validation messages and configuration hashes."""

from __future__ import annotations

import math
import warnings

import pytest

from g2tom.config import ConfigError, bundled_scenarios, odd_cells, parameter_table
from g2tom.before_work import load_scenario
from g2tom.before_work.domains import resolve


def test_bundled_scenarios_are_listed() -> None:
    assert {"paper", "published"} <= set(bundled_scenarios())


def test_paper_scenario_embeds_tables_1_and_2(paper) -> None:
    assert paper.material.E == 2.1e11 and paper.material.nu == 0.3
    assert paper.material.E_star == pytest.approx(1.1538e11, rel=1e-4)
    assert paper.roughness.sigma == 20e-6 and paper.roughness.eta == 2e8
    assert paper.roughness.beta == 30e-6 and paper.indenter.radius == 10e-3
    assert len(paper.oxide.xi) == 9 and len(paper.oxide.lambda_) == 12
    assert paper.oxide.n_realizations == 500
    deltas = paper.deltas
    assert len(deltas) == 20
    assert deltas[0] == pytest.approx(2 * 20e-6) and deltas[-1] == pytest.approx(-3 * 20e-6)
    # auto window: the spots outside 55 cells change R by < cube.crop_tolerance at -3 sigma
    assert paper.n_cells == 49  # the auto window of expected spots (mean_area spots need 55)
    assert resolve(load_scenario("published")).n_cells == 57  # explicit 0.4 R* sqrt(eta) = 56.6 -> nearest odd


def test_published_differs_only_in_its_conventions(paper_gt) -> None:
    published = load_scenario("published")
    diff = {k for k, v in published.flat().items() if paper_gt.flat()[k] != v}
    assert diff == {
        "contact.solver",
        "contact.n_radial",
        "contact.radial_grid",
        "contact.area_interpolation",
        "contact.spots",  # the paper's mean-area spots, as published
        "fits.fit_range",  # F >= 200 N, as published (the paper fits F' >= 0.4: the same steps)
        "contact.r_max",  # explicit 0.3 and 0.4 R*, as published; the paper's are resolved (auto)
        "contact.window",
        "cube.weights",
        "surrogate.method",  # the paper's SVD-then-polyfit surrogate, as published
        "oxide.period",  # the window's lattice, as published
        "oxide.ensemble",  # 500 fixed realizations, as published
    }


def test_override_strings_and_mappings_agree() -> None:
    a = load_scenario("paper", ["roughness.sigma=1.5e-5", "contact.solver=fixed_point"])
    b = load_scenario("paper", {"roughness.sigma": 1.5e-5, "contact.solver": "fixed_point"})
    assert a == b and a.roughness.sigma == 1.5e-5


def test_toml_file_with_base(tmp_path) -> None:
    path = tmp_path / "mine.toml"
    path.write_text('base = "paper"\n[roughness]\nsigma = 1e-5\n')
    s = load_scenario(path)
    assert s.name == "mine" and s.roughness.sigma == 1e-5 and s.roughness.eta == 2e8


@pytest.mark.parametrize(
    ("override", "message"),
    [
        ("roughness.sigma=-1e-6", "roughness.sigma = -1e-06 is out of range: must be > 0 and <= 1 (m)"),
        ("roughness.eta=0", "roughness.eta = 0 is out of range: must be > 0"),
        ("roughness.beta=-3", "roughness.beta"),
        ("indenter.radius=0", "indenter.radius"),
        ("material.E=-2e11", "material.E"),
        ("material.rho=0", "material.rho"),
        ("material.nu=0.5", "material.nu = 0.5 is out of range: must be > -1 and < 0.5"),
        ("material.nu=-1", "material.nu"),
        ("material.E=nan", "material.E = nan is not finite"),
        ("roughness.sigma=inf", "roughness.sigma = inf is not finite"),
        ("oxide.xi=[0.0, 0.5]", "oxide.xi[0] = 0.0 is out of range: must be > 0 and < 1"),
        ("oxide.lambda=[-1.0]", "oxide.lambda[0] = -1.0 is out of range: must be > 0"),
        ("oxide.n_realizations=1", "oxide.n_realizations = 1 is out of range: must be >= 2"),
        ("oxide.hurst=1.0", "oxide.hurst"),
        ("oxide.ks_ratio=1", "oxide.ks_ratio"),
        ("contact.solver=magic", "contact.solver = 'magic' is not allowed: must be one of 'newton', 'fixed_point'"),
        ("loading.n_delta=2.5", "loading.n_delta = 2.5 is not an integer"),
        ("loading.delta_min=3", "loading.delta_min = 3.0 is out of range: must be <= loading.delta_max"),
        ("oxide.xi=[0.5, 0.2]", "must be strictly increasing"),
        ("oxide.xi=0.5", "oxide.xi = 0.5 is not allowed: must be a non-empty list of numbers, each > 0 and < 1"),
        ("loading.delta_min=2", "loading.delta_min = 2.0 must differ from loading.delta_max = 2.0"),
        # the corner cells (r = 0.28 R*) must lie inside the radial domain, not just the half-side
    ],
)
def test_bad_values_name_parameter_value_and_range(override: str, message: str) -> None:
    with pytest.raises(ConfigError) as err:
        load_scenario("paper", [override])
    assert message in str(err.value)


@pytest.mark.parametrize(
    ("override", "suggestion"),
    [
        ("roughness.sigam=1", "roughness.sigma"),
        ("sigma=1", "roughness.sigma"),
        ("oxide.n_realisations=3", "oxide.n_realizations"),
        ("materials.E=1", "material.E"),
    ],
)
def test_unknown_key_suggests_nearest(override: str, suggestion: str) -> None:
    with pytest.raises(ConfigError, match=f"did you mean '{suggestion}'"):
        load_scenario("paper", [override])


def test_window_fits_the_radial_domain_exactly() -> None:
    """sqrt(2) * 28 cells * 1/sqrt(eta) = 0.28 R*: r_max = 0.28 is enough, 0.279 is not."""
    s = load_scenario("paper", ["contact.window=0.4", "contact.r_max=0.28"])
    assert odd_cells(0.4 * s.indenter.radius, s.cell_size) == 57
    with pytest.raises(ConfigError, match="contact.window = 0.4 is out of range"):
        load_scenario("paper", ["contact.window=0.4", "contact.r_max=0.279"])
    with pytest.raises(ConfigError) as err:
        load_scenario("paper", ["contact.window=0.4", "contact.r_max=0.25"])
    assert "contact.window = 0.4 is out of range: its corner cell centres lie at r = 0.0028 m" in str(err.value)


def test_section_that_is_not_a_table(tmp_path) -> None:
    path = tmp_path / "bad.toml"
    path.write_text("material = 3\n")
    with pytest.raises(ConfigError, match=r"material = 3 is not allowed: must be a \[material\] table"):
        load_scenario(path)


def test_malformed_override_and_missing_file() -> None:
    with pytest.raises(ConfigError, match="expected key=value"):
        load_scenario("paper", ["roughness.sigma"])
    with pytest.raises(ConfigError, match="neither a bundled scenario"):
        load_scenario("no/such/file.toml")


def test_large_correlation_length_warns_with_mode_count() -> None:
    with pytest.warns(UserWarning, match=r"oxide.lambda = 60.*independent Fourier modes"):
        resolve(load_scenario("paper", ["oxide.lambda=[60.0]", "oxide.period=window"]))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        resolve(load_scenario("paper"))


def test_stage_hashes_follow_only_their_inputs(paper) -> None:
    oxide_change = resolve(load_scenario("paper", ["oxide.hurst=0.6"]))
    assert oxide_change.config_hash("contact") == paper.config_hash("contact")
    # the seed also draws the discrete pool's surfaces
    assert resolve(load_scenario("paper", ["oxide.seed=1"])).config_hash("contact") != paper.config_hash("contact")
    assert oxide_change.config_hash("oxide") != paper.config_hash("oxide")
    # downstream stages inherit their inputs' hashes
    assert oxide_change.config_hash("cube") != paper.config_hash("cube")
    assert oxide_change.config_hash("fits") != paper.config_hash("fits")
    fit_change = resolve(load_scenario("paper", ["fits.n_bootstrap=100"]))
    assert fit_change.config_hash("cube") == paper.config_hash("cube")
    assert fit_change.config_hash("fits") != paper.config_hash("fits")
    # the adaptive ensemble's stopping rule fits the steps the fits stage fits (F' >= fits.min_force_normalized)
    assert resolve(load_scenario("paper", ["fits.min_force_normalized=0.2"])).config_hash("cube") != paper.config_hash("cube")


def test_parameter_table_documents_every_parameter(paper) -> None:
    rows = parameter_table()
    assert {r[0] for r in rows} == set(paper.flat())
    for key, _default, unit, allowed, doc in rows:
        assert unit and allowed and doc, key
    assert not any(isinstance(v, float) and not math.isfinite(v) for v in paper.flat().values())


def test_eq25_scales_by_hand(paper) -> None:
    # R' = R sqrt(R* sigma) / (2 rho*),  F' = 2F / (E* sqrt(R* sigma^3))
    assert paper.resistance_scale == pytest.approx(2 * 7.2e-7 / math.sqrt(1e-2 * 20e-6), rel=1e-14)
    e_star = 2.1e11 / (2 * (1 - 0.3**2))
    assert paper.force_scale == pytest.approx(e_star * math.sqrt(1e-2 * (20e-6) ** 3) / 2, rel=1e-14)


def test_integers_must_fit_the_64_bit_attributes_they_are_stored_in() -> None:
    assert load_scenario("paper", {"oxide.seed": 2**63 - 1}).oxide.seed == 2**63 - 1
    for value in (2**63, 1e30):
        with pytest.raises(ConfigError, match=r"oxide.seed = \d+ is out of range: must be <= 2\*\*63 - 1"):
            load_scenario("paper", {"oxide.seed": value})


def test_list_split_at_spaces_by_make_is_glued_back(capsys) -> None:
    from g2tom.cli.main import _rejoin, main

    assert _rejoin(["oxide.xi=[0.3,", "0.5]", "cube.weights=area"]) == ["oxide.xi=[0.3, 0.5]", "cube.weights=area"]
    assert _rejoin(["oxide.lambda=[1.0,", "5.0,", "13.0]"]) == ["oxide.lambda=[1.0, 5.0, 13.0]"]
    assert _rejoin(["fits.reduction='median'"]) == ["fits.reduction='median'"]
    assert main(["params", "--config", "paper_gt", "--set", "oxide.xi=[0.3,", "--set", "0.5]", "--set",
                 "contact.spots=mean_area", "--set", "cube.weights=area"]) == 0
    out = capsys.readouterr().out
    assert "oxide.xi" in out and "[0.3, 0.5]" in out and "area" in out


def test_version_names_package_and_commit(capsys) -> None:
    from g2tom import __version__
    from g2tom.cli.main import main

    with pytest.raises(SystemExit) as exit_:
        main(["--version"])
    assert exit_.value.code == 0
    assert capsys.readouterr().out.startswith(f"g2tom {__version__}")
