"""The surrogate's limits on the oxide grid are refused before any stage writes (a grid too small for
the joint method is not refused: tests/test_small_grids.py)."""

from __future__ import annotations

import pytest

from g2tom.cli.main import main
from g2tom.before_work.surrogate_grid import check_surrogate_grid
from g2tom.config import ConfigError
from g2tom.before_work import load_scenario
from tests.conftest import SMALL_ARGS

_SMALL = list(SMALL_ARGS)
_GRID_2x2 = ["--set", "oxide.xi=[0.3, 0.7]", "--set", "oxide.lambda=[3.0, 9.0]"]


def test_run_refuses_before_writing(tmp_path, capsys) -> None:
    data = tmp_path / "data"
    status = main(["run", "--data-dir", str(data), "--no-progress", *_SMALL, "--set", "surrogate.rank=1000"])
    err = capsys.readouterr().err
    assert status == 2
    assert err.count("\n") == 1 and err.startswith("g2tom: error: ")
    assert not data.exists() or not any(data.rglob("*"))


def test_rank_range_follows_the_grid() -> None:
    check_surrogate_grid(load_scenario("paper_gt", {"surrogate.rank": 9}))  # 9 x 12 grid: 9 modes
    with pytest.raises(ConfigError, match=r"surrogate.rank = 10 is out of range: must be >= 1 and <= 9"):
        check_surrogate_grid(load_scenario("paper_gt", {"surrogate.rank": 10}))


def test_paper_method_allows_a_2x2_grid_and_other_stages_any_grid() -> None:
    two = {"oxide.xi": [0.3, 0.7], "oxide.lambda": [3.0, 9.0]}
    check_surrogate_grid(load_scenario("paper_gt", {**two, "surrogate.method": "paper"}))
    assert check_surrogate_grid(load_scenario("paper_gt", two)).startswith("the oxide grid holds 2 value(s)")
    assert main(["params", "--set", "oxide.xi=[0.3, 0.7]", "--set", "surrogate.rank=1000"]) == 0


def test_run_check_does_no_work(tmp_path, capsys) -> None:
    data = tmp_path / "data"
    assert main(["run", "--check", "--data-dir", str(data), "--no-progress", *_SMALL]) == 0
    assert "every check before work passed" in capsys.readouterr().err
    assert not any(p.suffix == ".nc" for p in data.rglob("*"))
    assert main(["run", "--check", "--data-dir", str(data), *_SMALL, *_GRID_2x2]) == 0
    assert "g2tom: note: the oxide grid holds 2 value(s)" in capsys.readouterr().err
