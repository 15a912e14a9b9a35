"""``g2tom params`` prints every parameter; ``--resolved`` the values a run uses (``auto`` domains resolved)."""

from __future__ import annotations

from g2tom.before_work import load_scenario
from g2tom.before_work.domains import resolve
from g2tom.cli.main import main
from g2tom.config import parameter_table


def _lines(capsys, *args: str) -> dict[str, str]:
    assert main(["params", "--config", "paper", *args]) in (0, None)
    return {line.split()[0]: line.split()[1] for line in capsys.readouterr().out.splitlines()}


def test_params_lists_every_parameter_as_configured(capsys) -> None:
    values = _lines(capsys)
    assert set(values) == {row[0] for row in parameter_table()}
    assert values["contact.window"] == "auto" and values["contact.r_max"] == "auto"


def test_params_resolved_prints_the_domains_and_grid_a_run_uses(capsys) -> None:
    resolved = resolve(load_scenario("paper"))
    values = _lines(capsys, "--resolved")
    assert float(values["contact.window"]) == resolved.contact.window
    assert float(values["contact.r_max"]) == resolved.contact.r_max
    assert values["cells"] == str(resolved.n_cells)
