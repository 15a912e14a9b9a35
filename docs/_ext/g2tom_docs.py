"""Reference pages generated from the code at build time: parameters, file variables, the CLI.

Each ``*_markdown`` function returns a MyST Markdown text; :func:`write_generated` writes them under
``docs/_generated/`` (not committed), where the pages include them. As a Sphinx extension
(``extensions = ["g2tom_docs"]``) the files are written when the builder starts, so the reference
cannot drift from the code. ``tests/test_docs.py`` imports the same functions.
"""

from __future__ import annotations

import argparse
import os
from pathlib import Path
from typing import Any, Iterable

GENERATED = Path(__file__).resolve().parents[1] / "_generated"


def _cell(value: Any) -> str:
    """A value as the text of one Markdown table cell (pipes and newlines escaped)."""
    text = str(value).replace("\n", " ").replace("|", "\\|")
    if not text.startswith("`"):
        text = text.replace("*", "\\*").replace("<", "\\<").replace("_", "\\_")
    return text if text else " "


def _table(header: Iterable[str], rows: Iterable[Iterable[Any]]) -> str:
    header = list(header)
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(_cell(v) for v in row) + " |" for row in rows]
    return "\n".join(lines) + "\n"


def _code(value: Any) -> str:
    return f"`{value}`" if str(value) != "" else "`\"\"`"


# --- parameters -------------------------------------------------------------------------------

def parameter_rows() -> list[tuple]:
    """The registry's rows ``(key, default, unit, allowed range, description)``."""
    from g2tom.config import parameter_table

    return list(parameter_table())


def parameters_markdown() -> str:
    """Every parameter of a scenario, one table per section, from :func:`g2tom.config.parameter_table`."""
    sections: dict[str, list[tuple]] = {}
    for key, default, unit, allowed, doc in parameter_rows():
        sections.setdefault(key.split(".", 1)[0], []).append((key, default, unit, allowed, doc))
    out = []
    for section, rows in sections.items():
        out.append(f"### `[{section}]`\n")
        out.append(_table(("key", "default", "unit", "allowed", "description"),
                          ((_code(k), _code(d), u, a, doc) for k, d, u, a, doc in rows)))
    return "\n".join(out)


# --- variables of the output files ------------------------------------------------------------

def variable_registries() -> list[tuple[str, str, dict]]:
    """``(file, what, {name: Variable})`` for every file g2tom writes with declared variables.

    The one place that knows where the variable declarations live: repoint it if they move.
    """
    from g2tom.atlas.schema import ATLAS
    from g2tom.bench.schema import FRONTIER, STABILITY
    from g2tom.reference.variables import VARIABLES
    from g2tom.stages.schema import SCHEMA

    registries = [(f"{stage}.nc", f"the {stage} stage", variables) for stage, variables in SCHEMA.items()]
    registries += [
        ("atlas/atlas.nc", "`g2tom atlas`", ATLAS),
        ("validate/validate.nc", "`g2tom validate`", VARIABLES),
        ("bench/frontier.nc", "`g2tom bench` (the accuracy-time frontier)", FRONTIER),
        ("bench/stability.nc", "`g2tom bench` (the stability map)", STABILITY),
    ]
    return registries


def variables_markdown() -> str:
    """One table per output file: each variable's dimensions, units and long name."""
    out = []
    for path, what, variables in variable_registries():
        out.append(f"### `{path}`\n\nWritten by {what}.\n")
        rows = []
        for name, var in variables.items():
            dims = ", ".join(var.dims) if var.dims else "(scalar)"
            rows.append((_code(name), dims, _code(var.units), var.long_name.replace("{", "⟨").replace("}", "⟩")))
        out.append(_table(("variable", "dimensions", "units", "long name"), rows))
    return "\n".join(out)


# --- command line -----------------------------------------------------------------------------

def cli_parser() -> argparse.ArgumentParser:
    """The ``g2tom`` command's argparse parser."""
    from g2tom.cli.arguments import build_parser

    return build_parser()


def subcommands(parser: argparse.ArgumentParser | None = None) -> dict[str, argparse.ArgumentParser]:
    """Every subcommand's parser, in the order of ``g2tom --help``."""
    parser = parser or cli_parser()
    for action in parser._actions:  # argparse keeps subparsers only here
        if isinstance(action, argparse._SubParsersAction):
            return dict(action.choices)
    return {}


def cli_markdown(width: int = 90) -> str:
    """``g2tom --help`` and every subcommand's ``--help``, as printed."""
    previous = os.environ.get("COLUMNS")
    os.environ["COLUMNS"] = str(width)
    try:
        parser = cli_parser()
        out = ["## `g2tom`\n", "```text\n" + parser.format_help().rstrip() + "\n```\n"]
        for name, sub in subcommands(parser).items():
            out += [f"## `g2tom {name}`\n", "```text\n" + sub.format_help().rstrip() + "\n```\n"]
    finally:
        if previous is None:
            del os.environ["COLUMNS"]
        else:
            os.environ["COLUMNS"] = previous
    return "\n".join(out)


# --- the files and the Sphinx hook ------------------------------------------------------------

PAGES = {"parameters.md": parameters_markdown, "variables.md": variables_markdown, "cli.md": cli_markdown}


def write_generated(folder: Path = GENERATED) -> list[Path]:
    """Write every generated page under ``folder``; a file is rewritten only when its text changed."""
    folder.mkdir(parents=True, exist_ok=True)
    written = []
    for name, make in PAGES.items():
        path = folder / name
        text = make()
        if not path.is_file() or path.read_text() != text:
            path.write_text(text)
        written.append(path)
    return written


def _on_builder_inited(app: Any) -> None:
    write_generated(Path(app.srcdir) / "_generated")


def setup(app: Any) -> dict[str, Any]:
    app.connect("builder-inited", _on_builder_inited)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
