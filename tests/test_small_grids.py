"""Studies of any size run: a one-cell or one-row oxide grid gets a trivial surrogate, said so."""

from __future__ import annotations

import numpy as np
import pytest

from g2tom.before_work import load_scenario
from g2tom.before_work.surrogate_grid import check_surrogate_grid
from g2tom.cli.main import main
from g2tom.config import ConfigError
from g2tom.predict.predictor import predict
from g2tom.stages import fits, surrogate
from g2tom.stages.surrogate_file import SurrogateTables
from tests.conftest import SMALL_ARGS, SMALL_OVERRIDES
from tests.test_fits_stage import synthetic_cube

#: (oxide.xi, oxide.lambda): one cell, one row, one column.
GRIDS = [([0.5], [5.0]), ([0.2, 0.5, 0.8], [5.0]), ([0.5], [1.0, 5.0, 13.0])]


def _small(xi: list[float], lam: list[float], **extra: object):
    return load_scenario("paper_gt", {**SMALL_OVERRIDES, "oxide.xi": xi, "oxide.lambda": lam, **extra})


@pytest.mark.parametrize(("xi", "lam"), GRIDS)
def test_small_grid_is_noted_not_refused(xi, lam) -> None:
    note = check_surrogate_grid(_small(xi, lam))
    assert note.startswith(f"the oxide grid holds {len(xi)} value(s) of oxide.xi and {len(lam)} of oxide.lambda")
    assert "fitted trivially" in note
    assert check_surrogate_grid(_small(xi, lam, **{"surrogate.method": "paper"})) is None
    assert check_surrogate_grid(load_scenario("paper_gt", SMALL_OVERRIDES)) is None  # 3 x 3: joint


@pytest.mark.parametrize(("xi", "lam"), GRIDS)
def test_trivial_surrogate_passes_through_every_cell(xi, lam, recwarn) -> None:
    scenario = _small(xi, lam)
    ds = surrogate.build(scenario, fits.build(scenario, synthetic_cube(scenario, noise=0.0)))
    assert not [w for w in recwarn if "reduced to" in str(w.message)]  # said once before the run, not per parameter
    assert ds.attrs["method"] == "paper" and ds.attrs["trivial"] == check_surrogate_grid(scenario)
    for p in ("alpha", "gamma"):
        np.testing.assert_allclose(ds[f"{p}_relative_error"].values, 0.0, atol=1e-9)
    assert SurrogateTables.from_dataset(ds).info["trivial"] == ds.attrs["trivial"]


def test_one_cell_predict_answers_its_cell_and_refuses_others() -> None:
    scenario = _small([0.5], [5.0])
    ds = surrogate.build(scenario, fits.build(scenario, synthetic_cube(scenario, noise=0.0)))
    tables = SurrogateTables.from_dataset(ds)
    force = float(ds["force"][1])
    with pytest.warns(UserWarning, match="the surrogate holds one cell"):
        out = predict(tables, scenario, force, 0.5, 5.0, model="power_law")
    expected = float(ds["alpha_fit"][0, 0]) * float(ds["force_normalized"][1]) ** -float(ds["gamma_fit"][0, 0])
    assert float(out["resistance"]) / scenario.resistance_scale == pytest.approx(expected, rel=1e-9)
    with pytest.raises(ConfigError, match=r"xi = 0.4 lies outside the fitted range \[0.5, 0.5\]"):
        predict(tables, scenario, force, 0.4, 5.0)


def test_one_cell_run_end_to_end(tmp_path, capsys) -> None:
    data = tmp_path / "data"
    grid = ["--set", "oxide.xi=[0.5]", "--set", "oxide.lambda=[5]"]
    assert main(["run", "--data-dir", str(data), "--no-progress", "--no-bench", *SMALL_ARGS, *grid]) == 0
    err = capsys.readouterr().err
    assert err.count("g2tom: note: the oxide grid holds 1 value(s)") == 1
    for name in ("contact.nc", "oxide.nc", "cube.nc", "fits.nc", "surrogate.nc", "surrogate.json", "report.md"):
        assert (data / name).is_file(), name
    report = (data / "report.md").read_text()
    assert "Trivial: the oxide grid holds 1 value(s) of oxide.xi" in report
