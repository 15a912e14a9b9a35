"""The whole pipeline through the CLI on a small scenario: labelled outputs, figures, report."""

from __future__ import annotations

import json

import numpy as np
import pytest

from pipeline import __version__
from pipeline.cli.main import STAGES, main
from pipeline.store import read_stage
from tests.conftest import SMALL_OVERRIDES
from tests.test_schema import written_against_schema


def _set_args() -> list[str]:
    args: list[str] = []
    for key, value in SMALL_OVERRIDES.items():
        args += ["--set", f"{key}={value}"]
    return args


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory):
    data = tmp_path_factory.mktemp("run")
    with pytest.warns(UserWarning, match=r"surrogate for alpha: rank/orders .* reduced to"):
        status = main(["run", "--data-dir", str(data), "--no-progress", *_set_args()])
    assert status == 0
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
    assert json.loads((run_dir / "timings.json").read_text()).keys() >= set(STAGES) | {"figures"}


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


def test_rerun_of_a_stage_with_stale_input_is_refused(run_dir, capsys) -> None:
    status = main(["cube", "--data-dir", str(run_dir), "--no-progress", *_set_args(), "--set", "oxide.seed=3"])
    assert status == 1
    assert "oxide.nc was built from a different configuration" in capsys.readouterr().err


def test_every_output_variable_is_declared_in_the_schema(run_dir) -> None:
    assert written_against_schema(run_dir) == []
