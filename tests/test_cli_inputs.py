"""Bad inputs of issue 32 and the predictor's input and output formats.

Each refusal is checked as the bad-input catalog (tests/test_bad_inputs.py) checks its cases:
exit status 2, stderr exactly one ``g2tom: error:`` line naming what was wrong, no traceback,
nothing written under the working folder.
"""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from g2tom.cli.main import main
from g2tom.config import ResolvedScenario
from g2tom.before_work import load_scenario
from tests.test_bad_inputs import _snapshot
from tests.test_fits_stage import cli_overrides
from tests.test_predict import data_dir  # noqa: F401 - the module's fixture: fits.nc and the surrogate files

QUERY = "force,xi,lambda\n1500,0.4,4\n"


def _refused(capsys: pytest.CaptureFixture, root: Path, argv: list[str], *expect: str, status: int = 2) -> str:
    """Run ``g2tom argv``; assert one error line holding every ``expect`` and no change under ``root``."""
    before = _snapshot(root)
    capsys.readouterr()
    assert main(argv) == status
    out = capsys.readouterr()
    lines = [line for line in out.err.splitlines() if line.strip()]
    assert len(lines) == 1 and lines[0].startswith("g2tom: error: "), out.err
    assert all(e in lines[0] for e in expect), lines[0]
    assert "Traceback" not in out.err + out.out
    assert _snapshot(root) == before
    return lines[0]


def _predict(data: Path, small: ResolvedScenario, *args: str) -> list[str]:
    return ["predict", "--data-dir", str(data), *cli_overrides(small), *args]


# ------------------------------------------------------------------ 1: an unreadable --csv
def test_csv_that_is_a_directory(tmp_path, capsys, small, data_dir) -> None:  # noqa: F811
    _refused(capsys, tmp_path, _predict(data_dir, small, "--csv", str(tmp_path)), f"--csv {str(tmp_path)!r}",
             "is a directory")


def test_csv_without_read_permission(tmp_path, capsys, small, data_dir, monkeypatch) -> None:  # noqa: F811
    """As root chmod 000 does not block reading, so the refusal of the file system is simulated."""
    path = tmp_path / "q.csv"
    path.write_text(QUERY)

    read_text = Path.read_text

    def refuse(self: Path, *args, **kwargs) -> str:
        if self == path:
            raise PermissionError(13, "Permission denied", str(self))
        return read_text(self, *args, **kwargs)

    monkeypatch.setattr(Path, "read_text", refuse)
    _refused(capsys, tmp_path, _predict(data_dir, small, "--csv", str(path)), f"--csv {str(path)!r}",
             "unreadable (Permission denied)")


@pytest.mark.skipif(os.geteuid() == 0, reason="root reads a file whatever its mode: the monkeypatched test covers it")
def test_csv_chmod_000(tmp_path, capsys, small, data_dir) -> None:  # noqa: F811
    path = tmp_path / "q.csv"
    path.write_text(QUERY)
    path.chmod(0)
    _refused(capsys, tmp_path, _predict(data_dir, small, "--csv", str(path)), "--csv", "Permission denied")


# ------------------------------------------------------------------ 2: --output that cannot be written
@pytest.mark.parametrize("where, expect", [("folder", "is a directory"), ("a_file/out.csv", "which is a file")])
def test_output_refused_before_work(tmp_path, capsys, small, data_dir, where: str, expect: str) -> None:  # noqa: F811
    (tmp_path / "folder").mkdir()
    (tmp_path / "a_file").write_text("not a folder")
    target = tmp_path / where
    _refused(capsys, tmp_path, _predict(data_dir, small, "--force", "1500", "--xi", "0.4", "--lambda", "4",
                                        "--output", str(target)), f"--output {str(target)!r}", expect)


def test_output_in_a_new_folder(tmp_path, capsys, small, data_dir) -> None:  # noqa: F811
    target = tmp_path / "new" / "out.csv"
    assert main(_predict(data_dir, small, "--force", "1500", "--xi", "0.4", "--lambda", "4", "--output", str(target))) == 0
    assert target.read_text().startswith("force_N,")


# ------------------------------------------------------------------ 3: --surrogate files that are not one
def _future(data: Path, folder: Path) -> Path:
    path = folder / "future.json"
    path.write_text((data / "surrogate.json").read_text().replace('"version": 1,', '"version": 2,', 1))
    return path


def _binary(data: Path, folder: Path) -> Path:
    path = folder / "binary.json"
    path.write_bytes(b'{"format": "\xff\xfe\x00\x01' * 8)
    return path


@pytest.mark.parametrize("make, expect", [
    (_binary, ("is not UTF-8 text",)),
    (_future, ("format version 2", "reads version 1..1", "update g2tom")),
    (lambda data, folder: data / "fits.nc", ("fits.nc'", "output of the fits stage, not a surrogate")),
])
def test_surrogate_that_is_not_one(tmp_path, capsys, small, data_dir, make, expect) -> None:  # noqa: F811
    path = make(data_dir, tmp_path)
    _refused(capsys, tmp_path, _predict(data_dir, small, "--force", "1500", "--xi", "0.4", "--lambda", "4",
                                        "--surrogate", str(path)), f"--surrogate {str(path)!r}", *expect)


# ------------------------------------------------------------------ 4: a run on a 1 x 1 grid
def test_one_cell_run_answers_with_its_cell(tmp_path, capsys, small) -> None:
    """No interpolation on one cell: the cell's own curve, its band without a surrogate error, said so."""
    import warnings

    from g2tom.before_work.domains import resolve
    from g2tom.stages import fits, surrogate
    from g2tom.store import write_dataset
    from tests.conftest import SMALL_OVERRIDES
    from tests.test_fits_stage import synthetic_cube

    one = resolve(load_scenario("paper_gt", {**SMALL_OVERRIDES, "oxide.xi": [0.5], "oxide.lambda": [5.0],
                                          "surrogate.method": "paper", "surrogate.rank": 1}))
    write_dataset(fits.build(one, synthetic_cube(one, noise=0.2)), tmp_path, "fits", one)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        surrogate.run(one, tmp_path, None)
    capsys.readouterr()
    assert main(_predict(tmp_path, one, "--force", "1500,2500", "--xi", "0.5", "--lambda", "5")) == 0
    out = capsys.readouterr()
    assert "the surrogate holds one cell (xi = 0.5, lambda = 5)" in out.err and "without interpolation" in out.err
    header, *rows = [line.split(",") for line in out.out.strip().splitlines()]
    values = [{k: float(v) for k, v in zip(header, row) if k != "outside_domain"} for row in rows]
    assert len(values) == 2 and all(v["surrogate_error"] == 0 for v in values)
    assert all(v["resistance_mean_lower_ohm"] < v["resistance_ohm"] < v["resistance_mean_upper_ohm"] for v in values)
    assert values[0]["resistance_ohm"] > values[1]["resistance_ohm"]  # the cell's curve, falling with the load


# ------------------------------------------------------------------ 5: a pixel size no map can have
@pytest.mark.parametrize("pixel", ["1e300", "1e-12"])
def test_pixel_size_beyond_a_physical_map(tmp_path, capsys, pixel: str) -> None:
    import numpy as np

    path = tmp_path / "map.npy"
    np.save(path, np.random.default_rng(1).normal(scale=1e-6, size=(16, 16)))
    _refused(capsys, tmp_path, ["roughness", "--pixel-size", pixel, str(path)],
             f"--pixel-size = {float(pixel)!r} is out of range", "16 x 16 map", "[6.25e-11, 0.0625] m")


# ------------------------------------------------------------------ 6: validate's checks before work
@pytest.mark.parametrize("where, expect", [("a_file", "is not a directory"), ("a_file/data", "is not writable")])
def test_validate_data_dir_refused_before_work(tmp_path, capsys, monkeypatch, where: str, expect: str) -> None:
    import g2tom.reference.validate as validate

    def never(*args, **kwargs) -> None:
        raise AssertionError("validate started work on an unusable --data-dir")

    monkeypatch.setattr(validate, "run_validation", never)
    (tmp_path / "a_file").write_text("not a folder")
    _refused(capsys, tmp_path, ["validate", "--quick", "--data-dir", str(tmp_path / where)],
             f"--data-dir {str(tmp_path / where)!r}", expect)


# ------------------------------------------------------------------ 7: Ctrl-C during validate or atlas
@pytest.mark.parametrize("command, module, function, kept", [
    ("validate", "g2tom.reference.validate", "run_validation", "validate/cases"),
    ("atlas", "g2tom.atlas.run", "run_atlas", "atlas"),
])
def test_ctrl_c_says_what_was_kept(tmp_path, capsys, monkeypatch, command, module, function, kept) -> None:
    import importlib

    def interrupted(*args, **kwargs) -> None:
        raise KeyboardInterrupt

    monkeypatch.setattr(importlib.import_module(module), function, interrupted)
    capsys.readouterr()
    assert main([command, "--data-dir", str(tmp_path)]) == 130
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("g2tom: interrupted: "), lines
    assert f"kept in {tmp_path / kept}" in lines[0] and f"run the same `g2tom {command}` command again" in lines[0]


# ------------------------------------------------------------------ 8: a CSV with a byte-order mark
def test_csv_with_a_byte_order_mark(tmp_path, capsys, small, data_dir) -> None:  # noqa: F811
    plain, marked = tmp_path / "plain.csv", tmp_path / "excel.csv"
    plain.write_text(QUERY)
    marked.write_bytes(b"\xef\xbb\xbf" + QUERY.encode())
    answers = []
    for path in (plain, marked):
        assert main(_predict(data_dir, small, "--csv", str(path))) == 0
        answers.append(capsys.readouterr().out)
    assert answers[0] == answers[1] and answers[0].count("\n") == 2


# ------------------------------------------------------------------ 9: a setting another one overrides
@pytest.mark.parametrize("overrides, warned", [
    (["fits.min_force=1e12"], "fits.min_force = 1e+12 has no effect: fits.fit_range = 'force_normalized'"),
    (["fits.fit_range=force", "fits.min_force_normalized=3"],
     "fits.min_force_normalized = 3 has no effect: fits.fit_range = 'force'"),
])
def test_setting_without_effect_is_warned(capsys, overrides: list[str], warned: str) -> None:
    """One warning naming the setting that overrides it (the CLI prints it as one ``g2tom: warning:`` line)."""
    import re

    with pytest.warns(UserWarning, match=re.escape(warned)) as record:
        assert main(["params", *(a for o in overrides for a in ("--set", o))]) == 0
    assert len(record) == 1


def test_settings_of_the_bundled_scenario_are_not_warned() -> None:
    """paper.toml carries min_force beside fit_range = force_normalized: not the user's choice."""
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        load_scenario("paper_gt", ["fits.min_force_normalized=0.5"])


# ------------------------------------------------------------------ 10: the default rank follows the grid
_ONE_CELL = ["--set", "oxide.xi=[0.5]", "--set", "oxide.lambda=[5]", "--set", "surrogate.method=paper"]


def test_default_rank_follows_a_one_cell_grid(tmp_path, capsys) -> None:
    assert load_scenario("paper_gt", {"oxide.xi": [0.5], "oxide.lambda": [5.0]}).surrogate.rank == 1
    assert load_scenario("paper_gt", {"oxide.xi": [0.3, 0.5, 0.7]}).surrogate.rank == 2  # the default, within the grid
    assert main(["run", "--check", "--data-dir", str(tmp_path), *_ONE_CELL]) == 0
    assert "every check before work passed" in capsys.readouterr().err


def test_chosen_rank_beyond_the_grid_stays_refused(tmp_path, capsys) -> None:
    _refused(capsys, tmp_path, ["run", "--check", "--data-dir", str(tmp_path / "data"), *_ONE_CELL,
                                "--set", "surrogate.rank=2"], "surrogate.rank = 2 is out of range", "<= 1")
    toml = tmp_path / "mine.toml"
    toml.write_text('base = "paper"\n[surrogate]\nmethod = "paper"\nrank = 2\n[oxide]\nxi = [0.5]\nlambda = [5.0]\n')
    _refused(capsys, tmp_path, ["run", "--check", "--config", str(toml), "--data-dir", str(tmp_path / "data")],
             "surrogate.rank = 2 is out of range")


# ------------------------------------------------------------------ 11: predict's output as its input, and its formats
def test_output_feeds_back_as_input(tmp_path, capsys, small, data_dir) -> None:  # noqa: F811
    first = tmp_path / "first.csv"
    assert main(_predict(data_dir, small, "--force", "1500,2500", "--xi", "0.4", "--lambda", "4,6",
                         "--output", str(first))) == 0
    assert first.read_text().startswith("force_N,")
    assert main(_predict(data_dir, small, "--csv", str(first))) == 0
    assert capsys.readouterr().out == first.read_text()
    both = tmp_path / "both.csv"
    both.write_text("force,force_N,xi,lambda\n1500,1500,0.4,4\n")
    _refused(capsys, tmp_path, _predict(data_dir, small, "--csv", str(both)), "both force and force_n", "keep one")


def test_json_and_the_terminal_table(capsys, small, data_dir, monkeypatch) -> None:  # noqa: F811
    import json

    query = ("--force", "1500,2500", "--xi", "0.4", "--lambda", "4,6")
    assert main(_predict(data_dir, small, *query)) == 0
    csv_rows = capsys.readouterr().out.strip().splitlines()
    assert main(_predict(data_dir, small, *query, "--json")) == 0
    doc = json.loads(capsys.readouterr().out)
    assert [list(row) for row in doc["queries"]] == [csv_rows[0].split(",")] * 2
    assert doc["queries"][1]["force_N"] == 2500 and doc["columns"]["resistance_ohm"]["units"] == "ohm"
    assert doc["answered_by"].startswith("the run's own")
    monkeypatch.setattr("sys.stdout.isatty", lambda: True)
    assert main(_predict(data_dir, small, *query)) == 0
    out = capsys.readouterr()
    table = out.out.splitlines()
    assert table[0].split() == ["force_N", "xi", "lambda", "resistance_ohm", "resistance_mean_lower_ohm",
                                "resistance_mean_upper_ohm", "resistance_spread_p16_ohm", "resistance_spread_p84_ohm"]
    assert len({len(line) for line in table[:3]}) == 1 and len(table) == 4  # aligned, one line per query, the bands
    assert all(len(cell.replace(".", "").replace("e-0", "").lstrip("0")) <= 4 for cell in table[1].split())
    assert "g2tom: note: the main columns" in out.err


def test_atlas_answer_leaves_out_what_the_atlas_lacks(capsys, small, data_dir) -> None:  # noqa: F811
    from g2tom.predict.atlas import NOT_IN_ATLAS, shipped_path

    shipped = shipped_path()
    if shipped is None:
        pytest.skip("this installation ships no atlas surrogate")
    assert main(_predict(data_dir, small, "--force", "1500", "--xi", "0.5", "--lambda", "3",
                         "--surrogate", str(shipped))) == 0
    out = capsys.readouterr()
    header = out.out.splitlines()[0].split(",")
    assert not [c for c in header if c.startswith(NOT_IN_ATLAS)]
    assert "resistance_ohm" in header and "resistance_mean_upper_ohm" in header
    assert out.out.splitlines()[1].split(",")[header.index("resistance_spread_p84_ohm")] == "nan"
    assert "g2tom: note: the atlas surrogate holds no realization spread" in out.err
