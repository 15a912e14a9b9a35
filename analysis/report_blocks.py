"""The report's building blocks: one element of the report and a table of formatted values."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

__all__ = ["Block", "fmt", "table", "markdown_blocks"]


@dataclass(frozen=True)
class Block:
    """One report element.

    ``kind`` is ``h1`` to ``h4``, ``p`` (Markdown spans allowed: ``**bold**``, backtick
    code, links; a single ``*`` is text), ``table`` (``rows[0]`` is the header), ``list`` (``rows`` = (level, text) items,
    level 0 outermost), ``img`` (``text`` = caption, ``src`` = relative path) or ``pre``.
    """

    kind: str
    text: str = ""
    rows: tuple[tuple[str, ...], ...] = ()
    src: str = ""


def fmt(value: Any) -> str:
    """A table cell: floats to 6 significant digits, anything else as its string."""
    if isinstance(value, float):
        return f"{value:.6g}"
    return str(value)


def table(header: list[str], rows: list[list[Any]]) -> Block:
    """A table block (``rows[0]`` of the block is ``header``)."""
    return Block("table", rows=(tuple(header),) + tuple(tuple(fmt(v) for v in row) for row in rows))


def markdown_blocks(text: str, title: str) -> list[Block]:
    """Blocks of a Markdown section written by a stage (e.g. ``validate.md``): its ``## `` title
    becomes an ``h3`` of ``title``, ``### `` headings ``h3``, pipe tables ``table`` and every
    other line a paragraph."""
    blocks: list[Block] = []
    rows: list[tuple[str, ...]] = []
    for line in text.splitlines() + [""]:
        if line.startswith("|"):
            cells = tuple(c.strip() for c in line.strip().strip("|").split("|"))
            if not all(set(c) <= set("-:") and c for c in cells):  # the header's separator row
                rows.append(cells)
            continue
        if rows:
            blocks.append(Block("table", rows=tuple(rows)))
            rows = []
        if line.startswith("## "):
            blocks.append(Block("h3", title))
        elif line.startswith("### "):
            blocks.append(Block("h3", line[4:]))
        elif line.strip():
            blocks.append(Block("p", line.strip()))
    return blocks
