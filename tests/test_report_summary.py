"""The report's first screen answers the study's question: the law in ohm, how right, how long, how to
ask for other forces."""

from __future__ import annotations

import json
import re
import shlex
import warnings
from pathlib import Path

import pytest

from g2tom.analysis.report import write_report
from g2tom.analysis.report_summary import law_forces, predict_command
from g2tom.cli.main import main
from g2tom.config import ResolvedScenario
from g2tom.store import read_stage, write_dataset
from tests.test_fits_stage import cli_overrides, synthetic_cube

FIRST_SCREEN = 30


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory, small: ResolvedScenario) -> Path:
    """The fits and surrogate stages run by the CLI on a synthetic cube (no contact or cube solve)."""
    data = tmp_path_factory.mktemp("data")
    write_dataset(synthetic_cube(small), data, "cube", small)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)  # surrogate orders reduced on a 3 x 3 grid
        for stage in ("fits", "surrogate"):
            assert main([stage, "--data-dir", str(data), "--no-progress", *cli_overrides(small)]) == 0
    write_report(small, data)
    return data


def test_first_screen_gives_the_law_in_ohm_at_three_forces(run_dir: Path, small: ResolvedScenario) -> None:
    head = (run_dir / "report.md").read_text().splitlines()[:FIRST_SCREEN]
    text = "\n".join(head)
    fits = read_stage(run_dir, "fits", small)
    forces = law_forces(fits)
    assert forces.size == 3 and forces[0] < forces[1] < forces[2]
    assert "R = alpha F'^-gamma R0" in text and "ohm" in text
    # the table: one row per force, the clean law's value in ohm computed here again
    scale = float(fits["resistance_scale"])
    for force in forces:
        row = next(line for line in head if line.startswith(f"{force:.4g} "))
        clean = float(fits["alpha_clean"]) * (force / small.force_scale) ** -float(fits["gamma_clean"]) * scale
        assert f" {clean:.4g} [" in row, (row, clean)
        low, high = map(float, re.search(r"\[([^,]+), ([^\]]+)\]", row).groups())
        assert low * (1 - 1e-3) <= clean <= high * (1 + 1e-3)  # printed to 4 digits


def test_first_screen_says_how_right_how_long_and_how_to_predict(run_dir: Path, small: ResolvedScenario) -> None:
    head = (run_dir / "report.md").read_text().splitlines()[:FIRST_SCREEN]
    text = "\n".join(head)
    assert "**How right:**" in text and "95 % intervals" in text and "**Surrogate (Eq. 26):**" in text
    assert re.search(r"\*\*How long:\*\* [0-9.e+-]+ s of wall time \(.*fits", text)
    command = re.search(r"`(g2tom predict [^`]+)`", text).group(1)
    args = shlex.split(command)
    assert args[:4] == ["g2tom", "predict", "--config", small.name]
    assert args[args.index("--data-dir") + 1] == str(run_dir)
    assert {"--force", "--xi", "--lambda"} <= set(args)


def test_the_predict_command_answers_the_law(run_dir: Path, small: ResolvedScenario, capsys) -> None:
    """The printed command runs, and answers near the first screen's law at its forces."""
    fits = read_stage(run_dir, "fits", small)
    forces = law_forces(fits)
    command = shlex.split(predict_command(small, run_dir, forces, 0.5, 5.0))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        assert main([*command[1:], "--json"]) == 0
    queries = json.loads(capsys.readouterr().out)["queries"]
    assert [q["force_N"] for q in queries] == [float(f"{f:.4g}") for f in forces]
    cell = fits.sel(xi=0.5, **{"lambda": 5.0})
    for q in queries:  # the first screen's law of this cell lies within the answer's band
        law = float(cell["alpha"]) * q["force_normalized"] ** -float(cell["gamma"]) * float(fits["resistance_scale"])
        assert q["resistance_mean_lower_ohm"] <= law <= q["resistance_mean_upper_ohm"], (q, law)


def test_report_never_mentions_sessions(run_dir: Path) -> None:
    for name in ("report.md", "report.html"):
        lowered = (run_dir / name).read_text().lower()
        assert "session" not in lowered and "one-off" not in lowered
