"""The whole pipeline through the CLI on a small scenario: labelled outputs, figures, report."""

from __future__ import annotations

import json
import re

import numpy as np
import xarray as xr
import pytest

from g2tom import __version__
from g2tom.cli.commands import STAGES
from g2tom.cli.main import main
from g2tom.before_work import load_scenario
from g2tom.store import read_stage
from tests.conftest import SMALL_ARGS, SMALL_OVERRIDES
from tests.test_schema import written_against_schema


def _set_args() -> list[str]:
    """The ``small`` scenario (Greenwood-Tripp, paper_gt) on the command line."""
    return list(SMALL_ARGS)


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory, small_stages):
    """A copy of conftest's ``small_stages``: ``g2tom run --no-bench`` with :func:`_set_args`, exit 0
    (the physics benchmarks, about a minute, are tested apart: test_a_second_run_computes_nothing)."""
    import shutil

    warned = (small_stages.parent / "warnings.txt").read_text()
    assert re.search(r"^UserWarning: surrogate for alpha: rank/orders .* reduced to", warned, re.MULTILINE), warned
    data = tmp_path_factory.mktemp("run") / "data"
    shutil.copytree(small_stages, data)
    return data


def test_every_stage_output_is_labelled_and_traceable(run_dir, small) -> None:
    for stage in STAGES:
        ds = read_stage(run_dir, stage, small)
        assert ds.attrs["g2tom_version"] == __version__
        assert ds.attrs["config_hash"] == small.config_hash(stage)
        params = json.loads(ds.attrs["parameters"])  # the parameters that shaped the file
        assert params.items() >= small.stage_parameters(stage).items()
        for name, var in ds.variables.items():
            if var.dtype.kind in "OSU":  # string labels need no unit
                continue
            assert var.attrs.get("units") is not None, f"{stage}.nc: {name} has no units"
            assert var.attrs.get("long_name"), f"{stage}.nc: {name} has no long_name"
    timed = json.loads((run_dir / "timings.json").read_text()).keys()
    assert timed >= set(STAGES) | {"figures: contact", "figures: oxide", "figures: results"}  # a family each


def test_cube_is_consistent_with_its_inputs(run_dir, small) -> None:
    contact = read_stage(run_dir, "contact", small)
    cube = read_stage(run_dir, "cube", small)
    np.testing.assert_array_equal(cube["force"].values, contact["force"].values)
    assert cube["resistance"].sizes == {"xi": 3, "lambda": 3, "delta": 6, "realization": 8}
    assert not np.isnan(cube["resistance"].values).any()
    # oxide only removes conducting spots, so the exact resistance never drops below the clean one;
    # Greenwood's formula (a Rayleigh-quotient bound) is not monotone under removing spots: one that
    # dominated the interaction term can take more of it away than it adds to the self term
    # (4e-4 at worst on this case with spectral-period fields, none with the window's lattice)
    assert (cube["resistance"] >= cube["resistance_clean"] * (1 - 1e-3)).all()
    assert (cube["resistance"].mean("realization") > cube["resistance_clean"]).all()


def test_figures_and_report_are_written(run_dir) -> None:
    figures = sorted((run_dir / "figures").glob("*.png"))
    assert len(figures) >= 8
    assert all(p.stat().st_size > 10_000 for p in figures)
    report = (run_dir / "report.md").read_text()
    for p in figures:
        assert f"figures/{p.name}" in report
    assert (run_dir / "report.html").stat().st_size > 1000


def test_figures_only_draws_the_named_families_and_the_report_sums_their_times(run_dir, small, capsys) -> None:
    """``g2tom figures --only`` (make draws two sets side by side): those families only, each one's wall
    time recorded apart and summed into the report's one row; an unknown family exits 2 before drawing."""
    from g2tom.analysis.report_summary import recorded_timings

    def stamps() -> dict[str, int]:
        return {p.name: p.stat().st_mtime_ns for p in (run_dir / "figures").glob("*.png")}

    before = stamps()
    capsys.readouterr()
    assert main(["figures", "--only", "oxide", "--only", "contact", "--data-dir", str(run_dir), *_set_args()]) == 0
    drawn = [line.rsplit("/", 1)[-1] for line in capsys.readouterr().err.splitlines() if line.startswith("figure: ")]
    assert drawn == ["fig6_oxide.png", "fig4_contact.png", "fig5_spots.png"]
    assert sorted(name for name, stamp in stamps().items() if stamp != before[name]) == sorted(drawn)
    families = {step: entry["seconds"] for step, entry in json.loads((run_dir / "timings.json").read_text()).items()
                if step.startswith("figures: ")}
    assert families.keys() >= {"figures: oxide", "figures: contact", "figures: results"}
    rows = {step: seconds for step, seconds, _ in recorded_timings(small, run_dir)}
    assert list(rows) == [*STAGES, "figures"] and rows["figures"] == pytest.approx(sum(families.values()))

    before = stamps()
    assert main(["figures", "--only", "oxide", "--only", "nope", "--data-dir", str(run_dir), *_set_args()]) == 2
    assert capsys.readouterr().err == ("g2tom: error: --only 'nope' is not a figure family: must be one of contact, "
                                       "oxide, results, point, barber, validate\n")
    assert stamps() == before


def test_a_family_needs_only_the_stage_files_it_draws_and_is_out_of_date_only_after_them(run_dir, small, tmp_path,
                                                                                         capsys) -> None:
    """The contact and oxide figures are drawn from those two stage files alone (make draws them beside
    the cube); the results' family is refused without the cube. The report refuses a figure older
    than a stage file its family draws, and only then."""
    import os
    import shutil

    from g2tom.analysis.figures import FAMILIES
    from g2tom.cli.commands import _report_problems

    early = tmp_path / "early"
    early.mkdir()
    for name in ("contact.nc", "oxide.nc"):
        shutil.copy2(run_dir / name, early / name)
    assert main(["figures", "--only", "contact", "--only", "oxide", "--data-dir", str(early), *_set_args()]) == 0
    assert sorted(p.name for p in (early / "figures").glob("*.png")) == sorted(
        FAMILIES["contact"].files + FAMILIES["oxide"].files)
    capsys.readouterr()
    assert main(["figures", "--only", "results", "--data-dir", str(early), *_set_args()]) == 1
    assert f"figures not written: {early / 'cube.nc'}" in capsys.readouterr().err

    assert _report_problems(run_dir, small) == []
    figure = run_dir / "figures" / "fig4_contact.png"
    stamp = figure.stat().st_mtime_ns
    try:
        contact, cube = ((run_dir / name).stat().st_mtime_ns for name in ("contact.nc", "cube.nc"))
        assert contact < cube
        os.utime(figure, ns=(stamp, (contact + cube) // 2))  # older than the cube, newer than the contact: fine
        assert _report_problems(run_dir, small) == []
        os.utime(figure, ns=(stamp, (run_dir / "contact.nc").stat().st_mtime_ns - 10**9))
        assert _report_problems(run_dir, small) == [
            f"{figure} is older than {run_dir / 'contact.nc'}: run `g2tom figures` (or `make figures`)"]
    finally:
        os.utime(figure, ns=(stamp, stamp))


def _add_steps(data_dir: str, worker: int) -> None:
    from g2tom.cli.commands import _record_timing

    for k in range(20):
        _record_timing(data_dir, f"step {worker}.{k}", 1.0, "hash")


def test_commands_finishing_together_keep_each_others_times(tmp_path) -> None:
    """Four processes adding 20 steps each to one timings.json, as make's jobs do side by side: all 80 kept."""
    import multiprocessing

    context = multiprocessing.get_context("fork")
    workers = [context.Process(target=_add_steps, args=(str(tmp_path), w)) for w in range(4)]
    for w in workers:
        w.start()
    for w in workers:
        w.join(timeout=60)
    assert [w.exitcode for w in workers] == [0] * 4
    assert len(json.loads((tmp_path / "timings.json").read_text())) == 80


def test_rerun_of_a_stage_with_stale_input_is_refused(run_dir, capsys) -> None:
    status = main(["cube", "--data-dir", str(run_dir), "--no-progress", *_set_args(), "--set", "oxide.hurst=0.6"])
    assert status == 1
    assert "oxide.nc was built from a different configuration" in capsys.readouterr().err


def test_every_output_variable_is_declared_in_the_schema(run_dir) -> None:
    assert written_against_schema(run_dir) == []


def test_a_second_run_computes_nothing(run_dir, monkeypatch, capsys) -> None:
    """``g2tom run`` keeps stage files built from its configuration (as make does), runs the physics
    benchmarks make run adds before the figures, and asks for the figures and the report again."""
    import importlib

    import g2tom.bench as bench

    def refuse(*args, **kwargs):  # noqa: ANN002, ANN003, ANN202
        raise AssertionError("a stage computed on a second run")

    for stage in STAGES:
        module = importlib.import_module(f"g2tom.stages.{stage}")
        monkeypatch.setattr(module, "build", refuse)
        monkeypatch.setattr(module, "run", refuse)
    order: list[str] = []
    monkeypatch.setattr(bench, "physics_benchmarks", lambda scenario, data_dir: order.append("bench") or ["bench: ok"])
    import g2tom.analysis.figures

    # the call is recorded, not drawn again: run_dir's run drew these figures from the same files (5 s)
    drawn = sorted((run_dir / "figures").glob("*.png"))
    monkeypatch.setattr(g2tom.analysis.figures, "write_figures", lambda *a, **k: order.append("figures") or drawn)
    report = (run_dir / "report.md").stat().st_mtime_ns
    assert main(["run", "--data-dir", str(run_dir), "--no-progress", *_set_args()]) == 0
    err = capsys.readouterr().err
    for stage in STAGES:
        assert f"{stage}: up to date, kept {run_dir / stage}.nc" in err
    assert order == ["bench", "figures"]
    assert (run_dir / "report.md").stat().st_mtime_ns > report
    # another fits parameter: fits runs again (here refused), the stages upstream of it are kept
    with pytest.raises(AssertionError, match="a stage computed"):
        main(["run", "--data-dir", str(run_dir), "--no-progress", "--no-bench", *_set_args(), "--set", "fits.n_bootstrap=60"])
    err = capsys.readouterr().err
    assert "cube: up to date" in err and "fits: up to date" not in err


def test_physics_benchmarks_run_once_per_configuration(tmp_path, monkeypatch, small) -> None:
    import importlib

    import g2tom.bench as bench

    calls: list[str] = []
    for name in bench.PHYSICS_BENCH:
        monkeypatch.setattr(importlib.import_module(f"g2tom.bench.{name}"), "run",
                            lambda scenario, name=name: calls.append(name) or {"value": 1.0})
    lines = bench.physics_benchmarks(small, tmp_path)
    assert calls == list(bench.PHYSICS_BENCH)
    assert lines == [f"bench {n}: wrote {tmp_path / 'bench' / n}.json" for n in bench.PHYSICS_BENCH]
    assert json.loads((tmp_path / "bench" / "spots.json").read_text())["config_hash"] == small.config_hash()
    assert bench.physics_benchmarks(small, tmp_path) == [
        f"bench {n}: up to date, kept {tmp_path / 'bench' / n}.json" for n in bench.PHYSICS_BENCH]
    assert calls == list(bench.PHYSICS_BENCH)  # nothing ran again
    (tmp_path / "bench" / "biases.json").write_text("{truncated")
    bench.physics_benchmarks(small, tmp_path)
    assert calls == [*bench.PHYSICS_BENCH, "biases"]  # an unreadable one runs again
    other = load_scenario("paper_gt", {**SMALL_OVERRIDES, "fits.n_bootstrap": 60})
    bench.physics_benchmarks(other, tmp_path)
    assert calls[-2:] == list(bench.PHYSICS_BENCH)  # another configuration: both


def test_the_default_discrete_study_runs_end_to_end(tmp_path) -> None:
    """``g2tom run`` on the default scenario (discrete asperities, disc rule, point model), shrunk:
    every stage, the figures and the report, with the discrete model's pool in contact.nc."""
    data = tmp_path / "default"
    sets = {**SMALL_OVERRIDES, "contact.surfaces": 8}
    args = [a for k, v in sets.items() for a in ("--set", f"{k}={v}")]
    assert main(["run", "--data-dir", str(data), "--no-progress", "--no-bench", *args]) == 0
    with xr.open_dataset(data / "contact.nc") as contact_ds:
        assert contact_ds.sizes["surface"] == 8 and contact_ds.attrs["scenario"] == "paper"
        conductance = contact_ds["discrete_barber_conductance"].values
    with xr.open_dataset(data / "cube.nc") as cube_ds:
        assert np.isfinite(cube_ds["resistance"].values[..., :8]).mean() > 0.5
        # Barber per surface, averaged over the pool: the clean point model's conductance is K / (E* rho*)
        np.testing.assert_allclose(cube_ds["conductance_clean_point"].values, conductance.mean(axis=0), rtol=1e-8)
    report = (data / "report.md").read_text()
    assert "contact model discrete" in report and (data / "figures" / "fig5_spots.png").exists()
    # Barber's section checks each surface's own K (not Greenwood-Tripp's): the point model is exact
    assert "With this run's spots (discrete)" in report and re.search(r"point 1\.0000 \([+-]0\.00 %\)", report)
