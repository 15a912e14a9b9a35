"""The report's blocks as Markdown and as an HTML page rendered from that Markdown (python-markdown),
so the two files always agree."""

from __future__ import annotations

import html
import re

import markdown

from g2tom.analysis.report_blocks import Block

__all__ = ["to_markdown", "to_html", "STYLE"]


def _md_text(text: str) -> str:
    """Inline text as Markdown: a single ``*`` (E*, R*, rho*) escaped outside code spans, so that
    only ``**bold**`` and backtick code spans are markup."""
    parts = re.split(r"(`[^`]*`)", text)
    return "".join(part if k % 2 else re.sub(r"(?<!\*)\*(?!\*)", r"\\*", part) for k, part in enumerate(parts))


def _md_cell(text: str) -> str:
    """A table cell as Markdown: inline text with ``|`` escaped."""
    return _md_text(text).replace("|", "\\|")


def to_markdown(blocks: list[Block]) -> str:
    """Render blocks as Markdown."""
    out: list[str] = []
    for b in blocks:
        if b.kind in ("h1", "h2", "h3", "h4"):
            out.append("#" * int(b.kind[1]) + " " + _md_text(b.text))
        elif b.kind == "p":
            out.append(_md_text(b.text))
        elif b.kind == "pre":
            out.append("```\n" + b.text + "\n```")
        elif b.kind == "list":
            out.append("\n".join("    " * int(level) + "- " + _md_text(text) for level, text in b.rows))
        elif b.kind == "img":
            caption = _md_text(b.text)
            out.append(f"![{caption}]({b.src})\n\n*{caption}*")
        elif b.kind == "table":
            header, *rows = b.rows
            lines = ["| " + " | ".join(_md_cell(c) for c in header) + " |", "|" + "---|" * len(header)]
            lines += ["| " + " | ".join(_md_cell(c) for c in row) + " |" for row in rows]
            out.append("\n".join(lines))
        else:
            raise ValueError(f"unknown block kind {b.kind!r}")
    return "\n\n".join(out) + "\n"


#: The page's style: a readable measure, tables that scroll sideways, figures and formulas that fit.
STYLE = ("body{font-family:sans-serif;max-width:60em;margin:2em auto;padding:0 1em;line-height:1.4}"
         "table{display:block;overflow-x:auto;border-collapse:collapse;margin:1em 0}"
         "td,th{border:1px solid #ccc;padding:2px 6px;text-align:right}"
         "img{max-width:100%}"
         "code,pre{overflow-wrap:anywhere;white-space:pre-wrap}"
         "pre{background:#f6f6f6;padding:0.5em}")


def to_html(blocks: list[Block], title: str) -> str:
    """Render blocks as a standalone HTML page, through their Markdown.

    Parameters
    ----------
    blocks : list of Block
        The report's blocks.
    title : str
        The page's ``<title>``.

    Returns
    -------
    str
        The page: :func:`to_markdown`'s text rendered by python-markdown (``tables``, ``toc``
        for the headings' ids, ``fenced_code``), with :data:`STYLE`.
    """
    body = markdown.markdown(to_markdown(blocks), extensions=["tables", "toc", "fenced_code"])
    return (f"<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"><title>{html.escape(title)}</title>"
            f"<style>{STYLE}</style></head><body>\n{body}\n</body></html>\n")
