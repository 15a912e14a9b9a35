"""The documentation's generated references and the README, checked without a Sphinx build."""

from __future__ import annotations

import re
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
README = ROOT / "README.md"
sys.path.insert(0, str(ROOT / "docs" / "_ext"))

import g2tom_docs  # noqa: E402  (docs/_ext/g2tom_docs.py: the generators the Sphinx build runs)


def test_parameter_reference_names_every_parameter() -> None:
    from g2tom.config import parameter_table

    text = g2tom_docs.parameters_markdown()
    keys = [row[0] for row in parameter_table()]
    assert keys
    missing = [key for key in keys if f"`{key}`" not in text]
    assert not missing, f"parameters missing from the generated reference: {missing}"


def test_cli_reference_names_every_subcommand() -> None:
    from g2tom.cli.arguments import build_parser

    text = g2tom_docs.cli_markdown()
    names = list(g2tom_docs.subcommands(build_parser()))
    assert {"predict", "run", "validate", "roughness"} <= set(names)
    missing = [name for name in names if f"## `g2tom {name}`" not in text]
    assert not missing, f"subcommands missing from the generated CLI reference: {missing}"
    assert "usage: g2tom predict" in text


def test_variable_reference_names_every_declared_variable() -> None:
    text = g2tom_docs.variables_markdown()
    for path, _, variables in g2tom_docs.variable_registries():
        assert f"### `{path}`" in text
        missing = [name for name in variables if f"`{name}`" not in text]
        assert not missing, f"{path}: variables missing from the generated reference: {missing}"


def test_generated_pages_are_written(tmp_path) -> None:
    written = g2tom_docs.write_generated(tmp_path)
    assert {p.name for p in written} == {"parameters.md", "variables.md", "cli.md"}
    assert all(p.read_text() for p in written)


def test_readme_is_short_and_describes_the_software_as_it_is() -> None:
    text = README.read_text()
    assert len(text.splitlines()) <= 250
    lowered = text.lower()
    for word in ("session", "../shared", "design note", "one-off"):
        assert word not in lowered, f"README.md mentions {word!r}"
    assert not re.search(r"\bissues? #?\d+", lowered), "README.md refers to an issue by number"
    assert not re.search(r"\b20\d\d-\d\d-\d\d\b", text), "README.md holds a date (dates belong in CHANGELOG.md)"
    assert "import pipeline" not in text and "pipeline." not in text.replace("pipeline/", "")


def _shell_commands(text: str) -> list[str]:
    blocks = re.findall(r"^```(?:sh|bash|console|shell)\n(.*?)^```$", text, flags=re.M | re.S)
    return [line.strip() for block in blocks for line in block.splitlines() if line.strip()]


@pytest.mark.parametrize("command", [c for c in _shell_commands(README.read_text()) if c.startswith("g2tom ")])
def test_readme_g2tom_commands_name_existing_subcommands(command: str) -> None:
    names = set(g2tom_docs.subcommands())
    assert command.split()[1] in names, f"README.md runs `{command}`, whose subcommand does not exist"


def test_readme_has_g2tom_commands() -> None:
    assert any(c.startswith("g2tom ") for c in _shell_commands(README.read_text()))


def test_example_pages_hold_code_output_and_figures(tmp_path) -> None:
    """docs/_ext/g2tom_examples.py: a script runs in its own folder; its page shows code, output, figures."""
    import g2tom_examples

    examples = tmp_path / "examples"
    examples.mkdir()
    (examples / "tiny.py").write_text('"""A tiny example\n\nIt prints and draws.\n"""\n\n'
                                      'from pathlib import Path\n\nprint("R_el = 1.5 mOhm")\n'
                                      'Path("plot.png").write_bytes(b"\\x89PNG")\n')
    times = g2tom_examples.write_examples(examples, tmp_path / "out")
    page = (tmp_path / "out" / "tiny.md").read_text()
    assert set(times) == {"tiny.py"}
    assert page.startswith("# A tiny example\n") and "It prints and draws." in page
    assert "```{literalinclude} ../examples/tiny.py" in page and ":lines: 6-" in page
    assert "R_el = 1.5 mOhm" in page and "```{image} tiny/plot.png" in page
    assert (tmp_path / "out" / "tiny" / "plot.png").read_bytes() == b"\x89PNG"
    assert not (examples / "plot.png").exists()  # written in a temporary folder, not beside the script


def test_every_example_has_a_title_and_an_introduction() -> None:
    import g2tom_examples

    scripts = sorted((ROOT / "docs" / "examples").glob("*.py"))
    assert len(scripts) >= 3
    for script in scripts:
        title, intro = g2tom_examples._docstring(script)
        assert title and len(title) < 40 and intro, script.name


def test_ci_builds_the_docs_after_the_tests() -> None:
    lines = [line.strip() for line in (ROOT / ".ci" / "run").read_text().splitlines()]
    assert lines.index("make test") < lines.index("make docs")
    conf = (ROOT / "docs" / "conf.py").read_text()
    assert "nitpicky = True" in conf and "sphinx-mathjax-offline" in conf
