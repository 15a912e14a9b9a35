"""The report's building blocks: one element of the report and a table of formatted values."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

__all__ = ["Block", "fmt", "table"]


@dataclass(frozen=True)
class Block:
    """One report element.

    ``kind`` is ``h1``, ``h2``, ``p``, ``table`` (``rows[0]`` is the header), ``img``
    (``text`` = caption, ``src`` = relative path) or ``pre``.
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
