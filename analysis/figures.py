"""All figures of ``make figures``, written under ``<data_dir>/figures``.

Each figure family lives in its own module exposing
``write(scenario, data_dir, out_dir) -> list[Path]``; a family whose input file is missing
is an error (run the stages first).
"""

from __future__ import annotations

import importlib
from pathlib import Path

import matplotlib

from g2tom.config import Scenario
from g2tom.store import check_writable

matplotlib.use("Agg")

__all__ = ["FAMILIES", "write_figures"]

FAMILIES: tuple[str, ...] = (
    "g2tom.analysis.figures_contact",
    "g2tom.analysis.figures_oxide",
    "g2tom.analysis.figures_results",
    "g2tom.analysis.figures_point",
    "g2tom.analysis.figures_barber",
    "g2tom.analysis.figures_validate",
)


def write_figures(scenario: Scenario, data_dir: str | Path) -> list[Path]:
    """Write every figure family and return the files written.

    Raises
    ------
    WriteError
        Before any figure is drawn, if ``<data_dir>/figures`` cannot be written (every figure
        there kept); while drawing, if one figure cannot (that one kept).
    """
    out_dir = Path(data_dir) / "figures"
    check_writable(out_dir, "no figure was drawn; those already there are kept")
    written: list[Path] = []
    for name in FAMILIES:
        written += importlib.import_module(name).write(scenario, Path(data_dir), out_dir)
    return written
