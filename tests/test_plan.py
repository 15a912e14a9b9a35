"""Resources known before work: estimates, refusals naming the parameter, `g2tom plan`."""

from __future__ import annotations

import subprocess
import sys
import warnings

import pytest

from g2tom.before_work import plan, resources
from g2tom.cli.main import main
from g2tom.config import ConfigError
from g2tom.before_work import load_scenario
from g2tom.before_work.domains import resolve

MEMORY = 16.0 * 2**30  # a fixed machine, so the refusals do not depend on the one running the test


@pytest.mark.parametrize(
    ("overrides", "parameter"),
    [
        ({"oxide.ks_ratio": 1000}, "oxide.ks_ratio = 1000 "),
        ({"oxide.lambda": [1e-6]}, "oxide.lambda = [1e-06]"),
        ({"oxide.n_realizations": 1_000_000}, "oxide.n_realizations = 1000000"),
        ({"roughness.eta": 1e14}, "roughness.eta = 1e+14"),
        ({"roughness.eta": 1e11}, "roughness.eta = 1e+11"),
        ({"contact.n_radial": 100_000}, "contact.n_radial = 100000"),
        ({"oxide.xi": [i / 1000 for i in range(1, 1000)], "oxide.n_realizations": 20_000}, "oxide."),
    ],
)
def test_exhausting_parameters_are_refused_naming_them(overrides, parameter):
    with pytest.raises(ConfigError) as err:
        resources.check_resources(load_scenario("paper_gt", overrides), memory=MEMORY)
    assert str(err.value).startswith(parameter), str(err.value)


def test_refused_before_work_by_the_cli(tmp_path, capsys):
    code = main(["cube", "--set", "oxide.n_realizations=1000000", "--data-dir", str(tmp_path), "--no-progress"])
    assert code == 2
    assert "oxide.n_realizations = 1000000 is out of range for this machine" in capsys.readouterr().err
    assert not any(tmp_path.iterdir())


def test_paper_scene_fits_and_plan_prints_every_stage(capsys):
    estimates = resources.check_resources(resolve(load_scenario("paper_gt")), memory=MEMORY)
    assert [e.stage for e in estimates] == ["contact", "oxide", "cube", "fits", "surrogate"]
    assert main(["plan", "--config", "paper_gt"]) == 0
    out = capsys.readouterr().out
    assert "49 x 49 cells" in out
    for stage in ("contact", "oxide", "cube", "fits", "surrogate"):
        assert f"\n{stage}" in out


def test_estimates_grow_with_the_cell_count():
    fixed = {"oxide.ensemble": "fixed"}  # an adaptive cube's memory is dominated by its cap, not the cells
    small = plan.estimate(resolve(load_scenario("paper_gt", fixed)))
    large = plan.estimate(resolve(load_scenario("paper_gt", {**fixed, "roughness.eta": 3.2e9})))
    for a, b in zip(small, large):
        if a.stage in ("oxide", "cube"):
            assert b.peak_bytes > 5 * (a.peak_bytes - plan.BASE_BYTES)
            assert b.seconds > 10 * a.seconds


# VmHWM, the peak RSS of this process image (ru_maxrss would carry the forking parent's peak).
_RSS = """
import sys
from g2tom.cli.main import main
code = main(sys.argv[1:])
with open("/proc/self/status") as fh:
    print(next(int(line.split()[1]) * 1024 for line in fh if line.startswith("VmHWM:")))
sys.exit(code)
"""


@pytest.mark.parametrize("eta", [2e8, pytest.param(8e8, marks=pytest.mark.stress),  # 15 s each beyond the first
                                 pytest.param(3.2e9, marks=pytest.mark.stress)])
def test_memory_estimate_within_a_factor_2_of_measured_peak(tmp_path, eta):
    sets = {"roughness.eta": eta, "oxide.xi": [0.3, 0.7], "oxide.lambda": [3.0, 9.0],
            "oxide.n_realizations": 20, "oxide.chunk": 10, "cube.chunk": 10, "loading.n_delta": 8,
            "contact.n_radial": 240}
    args = ["--config", "paper_gt", *[a for k, v in sets.items() for a in ("--set", f"{k}={v}")], "--data-dir", str(tmp_path),
            "--no-progress"]
    estimates = {e.stage: e.peak_bytes for e in plan.estimate(resolve(load_scenario("paper_gt", sets)))}
    for stage in ("contact", "oxide", "cube"):
        run = subprocess.run([sys.executable, "-c", _RSS, stage, *args], capture_output=True, text=True, check=True)
        measured = float(run.stdout.split()[-1])
        ratio = estimates[stage] / measured
        print(f"eta {eta:g} {stage}: estimate {estimates[stage] / 2**20:.0f} MiB, measured {measured / 2**20:.0f} MiB")
        assert 0.5 <= ratio <= 2.0, (stage, estimates[stage] / 2**20, measured / 2**20)


# The default scenario's adaptive cube measured on a quiet 2-core machine (`g2tom cube`, default
# threaded scheduler, 2026-11-24, expected spots, F' >= 0.4, 49^2 cells): 361,115 realizations kept
# over the 108 (xi, lambda) cells (cube.nc n_realizations), 386,200 computed in whole batches,
# 171,200 fields, 164.5 s (the plan said 125 s with the counts of the previous fit range, 87 s
# before it counted whole batches and the regenerated fields).
MEASURED_REALIZATIONS = 361_115
MEASURED_CUBE_SECONDS = 164.5
# The same scene with a fixed ensemble of 400: 18.7 s on one thread, 12.1 s on two.
MEASURED_FIXED_400 = {1: 18.7, None: 12.1}


def test_adaptive_plan_prints_a_range_containing_the_measured_run(capsys):
    scenario = resolve(load_scenario("paper_gt"))
    counts = plan.realizations(scenario)
    assert counts.adaptive and (counts.low, counts.high) == (400, 30_000)
    assert counts.low * 108 <= MEASURED_REALIZATIONS <= counts.high * 108
    assert counts.typical * 108 == pytest.approx(MEASURED_REALIZATIONS)
    assert counts.computed * 108 == pytest.approx(386_200)
    cube = next(e for e in plan.estimate(scenario) if e.stage == "cube")
    low, high = cube.seconds_range
    assert low < cube.seconds < high and high / low == pytest.approx(30_000 / 400)
    assert low <= MEASURED_CUBE_SECONDS <= high
    assert main(["plan", "--config", "paper_gt"]) == 0
    out = capsys.readouterr().out
    assert "400 .. 30000 realizations per (xi, lambda) (adaptive)" in out
    assert "43200 .. 3240000 realizations in all, typical 361115" in out
    assert "computed in whole batches: typical 386200" in out
    assert f"({low:.3g} .. {high:.3g} s)" in out


@pytest.mark.parametrize("workers", [1, None])
def test_cube_plan_within_1_5x_of_measured(workers):
    """The typical estimate against the measured runs (adaptive default, fixed 400 on 1 and 2 threads)."""
    fixed = resolve(load_scenario("paper_gt", {"oxide.ensemble": "fixed", "oxide.n_realizations": 400}))
    cube = next(e for e in plan.estimate(fixed, workers) if e.stage == "cube")
    assert 1 / 1.5 <= cube.seconds / MEASURED_FIXED_400[workers] <= 1.5, cube.seconds
    if workers is None:
        adaptive = next(e for e in plan.estimate(resolve(load_scenario("paper_gt"))) if e.stage == "cube")
        assert 1 / 1.5 <= adaptive.seconds / MEASURED_CUBE_SECONDS <= 1.5, adaptive.seconds


def test_adaptive_memory_is_typical_with_the_cap_beside():
    scenario = resolve(load_scenario("paper_gt"))
    fixed = resolve(load_scenario("paper_gt", {"oxide.ensemble": "fixed"}))  # same fields in oxide.nc (500)
    adaptive = {e.stage: e for e in plan.estimate(scenario)}
    base = {e.stage: e.peak_bytes for e in plan.estimate(fixed)}
    # the cube's and fits' results are held on the padded realization axis: typically the largest
    # count of the measured run, 30,000 at the cap, instead of 500
    cells = 8.0 * 5 * 9 * 12 * 20
    typical = plan.realizations(scenario).largest
    copies = plan.CUBE_RESULT_COPIES
    assert adaptive["cube"].peak_bytes - base["cube"] == pytest.approx(copies * cells * (typical - 500))
    assert adaptive["cube"].peak_bytes_cap - base["cube"] == pytest.approx(copies * cells * (30_000 - 500))
    assert adaptive["fits"].peak_bytes_cap >= adaptive["fits"].peak_bytes > base["fits"]
    for stage in ("contact", "oxide", "surrogate"):
        assert adaptive[stage].peak_bytes == base[stage] and adaptive[stage].peak_bytes_cap is None
    resources.check_resources(scenario, memory=MEMORY)  # the default scenario is not refused
    # a cap that would not fit only warns: typical runs stop far below it
    with pytest.warns(ResourceWarning, match="oxide.max_realizations = 3000000"):
        resources.check_resources(resolve(load_scenario("paper_gt", {"oxide.max_realizations": 3_000_000})), memory=MEMORY)
    # typical counts that would not fit are refused, naming the parameter
    with pytest.raises(ConfigError) as err:
        resources.check_resources(resolve(load_scenario("paper_gt", {"oxide.min_realizations": 300_000,
                                                             "oxide.max_realizations": 300_000})), memory=MEMORY)
    assert "is out of range for this machine" in str(err.value) and "_realizations = 300000" in str(err.value)


def test_an_8_gb_laptop_runs_the_default():
    """6 GiB available: the default run fits (refused before the fits' memory was calibrated)."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        resources.check_resources(resolve(load_scenario("paper_gt")), memory=6.0 * 2**30)


def test_a_typical_run_that_cannot_fit_is_refused_before_work_by_the_cli(tmp_path, capsys):
    code = main(["cube", "--set", "oxide.min_realizations=300000", "--set", "oxide.max_realizations=300000",
                 "--data-dir", str(tmp_path), "--no-progress"])
    assert code == 2
    assert "_realizations = 300000 is out of range" in capsys.readouterr().err
    assert not any(tmp_path.iterdir())


def test_plan_of_the_discrete_model_counts_its_pool_and_maps() -> None:
    from g2tom.before_work import plan
    from g2tom.before_work import load_scenario

    grid = {e.stage: e for e in plan.estimate(load_scenario("paper_gt"), workers=2)}
    discrete = {e.stage: e for e in plan.estimate(load_scenario("paper"), workers=2)}
    plain = {e.stage: e for e in plan.estimate(load_scenario("paper", {"fits.control_variate": "none"}), workers=2)}
    # 256 surfaces x 20 steps x 3.85 ms on two workers beside the Greenwood-Tripp solve
    assert discrete["contact"].seconds - grid["contact"].seconds == pytest.approx(256 * 20 * 3.85e-3 / 2, rel=1e-9)
    # 188,200 computed (xi, field) pairs on two workers without the control variate: a measured 92.05 s;
    # the default's control variate computes its typical share of them
    assert plain["cube"].seconds == pytest.approx(92.05, rel=1e-9)
    assert discrete["cube"].seconds == pytest.approx(92.05 * plan.CONTROL_VARIATE_REALIZATIONS, rel=1e-9)
    # a pool grown at the light steps adds its modelled surfaces' seconds, shared by the workers
    from g2tom.models.discrete_cost import expected_counts, grown_pool

    grown_scene = load_scenario("paper", {"contact.pool_half_width": 0.01})
    grown = {e.stage: e for e in plan.estimate(grown_scene, workers=2)}
    added = grown_pool(grown_scene, *expected_counts(grown_scene))[1]
    assert added > 0
    assert grown["contact"].seconds - discrete["contact"].seconds == pytest.approx(added / 2, rel=1e-9)


#: Both default studies measured on 2 cores (paper_gt on 2026-11-27; paper, with its control variate,
#: on 2026-11-29, the cube and fits the medians of three): each stage run by `g2tom STAGE
#: --no-progress [--config paper_gt]` in a fresh data directory, the seconds it reports, and the peak
#: resident memory of its process tree (workers included) sampled every 0.1 s, MiB.
MEASURED_DEFAULT_RUN = {
    "paper": {"contact": 10.47, "oxide": 1.11, "cube": 35.15, "fits": 2.83, "surrogate": 4.64},
    "paper_gt": {"contact": 0.95, "oxide": 1.30, "cube": 160.14, "fits": 9.89, "surrogate": 3.31},
}
MEASURED_DEFAULT_PEAK_MIB = {
    "paper": {"contact": 306, "oxide": 342, "cube": 1003, "fits": 586, "surrogate": 262},
    "paper_gt": {"contact": 239, "oxide": 275, "cube": 3507, "fits": 2774, "surrogate": 197},
}


@pytest.mark.parametrize("name", sorted(MEASURED_DEFAULT_RUN))
def test_every_stage_memory_within_1_5x_of_the_measured_default_run(name):
    for estimate in plan.estimate(resolve(load_scenario(name))):
        ratio = estimate.peak_bytes / 2**20 / MEASURED_DEFAULT_PEAK_MIB[name][estimate.stage]
        assert 1 / 1.5 <= ratio <= 1.5, (estimate.stage, estimate.peak_bytes / 2**20)


@pytest.mark.parametrize("name", sorted(MEASURED_DEFAULT_RUN))
def test_every_stage_time_within_1_5x_of_the_measured_default_run(name):
    for estimate in plan.estimate(resolve(load_scenario(name))):
        measured = MEASURED_DEFAULT_RUN[name][estimate.stage]
        assert 1 / 1.5 <= estimate.seconds / measured <= 1.5, (estimate.stage, estimate.seconds, measured)


def test_the_default_scene_s_discrete_models_are_the_recorded_ones() -> None:
    """plan scales the default's measured discrete costs by the cost models' ratio; the ratio is 1 on
    the default scene only if the recorded model values are the models' own there."""
    from g2tom.models import discrete_cost
    from g2tom.models.discrete_cost import expected_counts, field_seconds, surface_seconds

    touching, candidates = expected_counts(load_scenario("paper"))
    assert surface_seconds(touching, candidates) == pytest.approx(discrete_cost.DEFAULT_SURFACE_MODEL_S, rel=1e-12)
    assert field_seconds(touching, candidates) == pytest.approx(discrete_cost.DEFAULT_FIELD_MODEL_S, rel=1e-12)
    assert touching.size == discrete_cost.DEFAULT_STEPS


def test_a_scene_with_more_touching_asperities_is_planned_dearer_by_the_models_ratio() -> None:
    """sigma 100 um instead of 20 um: ~2x the touching asperities and 5x the candidates at the
    heaviest step; the pool's and the cube's estimates grow by the discrete cost models' ratios (the
    previous plan kept the default's 10.8 s and 92 s whatever the scene)."""
    from g2tom.models import discrete_cost
    from g2tom.models.discrete_cost import expected_counts, field_seconds, surface_seconds

    default, rough = load_scenario("paper"), load_scenario("paper", {"roughness.sigma": 1e-4})
    grid = {e.stage: e.seconds for e in plan.estimate(load_scenario("paper_gt", {"roughness.sigma": 1e-4}), workers=2)}
    base = {e.stage: e.seconds for e in plan.estimate(default, workers=2)}
    est = {e.stage: e.seconds for e in plan.estimate(rough, workers=2)}
    touching, candidates = expected_counts(rough)
    assert touching[-1] > 1.5 * expected_counts(default)[0][-1]
    pool = 256 * 20 * discrete_cost.DISCRETE_SOLVE_S / 2 * surface_seconds(touching, candidates) / discrete_cost.DEFAULT_SURFACE_MODEL_S
    assert est["contact"] - grid["contact"] == pytest.approx(pool, rel=1e-9)
    ratio = field_seconds(touching, candidates) / discrete_cost.DEFAULT_FIELD_MODEL_S
    assert ratio > 3
    assert est["cube"] == pytest.approx(base["cube"] * ratio, rel=1e-9)
    lines = plan.format_plan(resolve(rough), workers=2)
    assert any(f"expects {touching[-1]:.0f} touching and {candidates[-1]:.0f} candidates" in line for line in lines)
