"""All figures of ``make figures``, written under ``<data_dir>/figures``.

Each figure family lives in its own module exposing
``write(scenario, data_dir, out_dir) -> list[Path]``; a family whose input file is missing
is an error (run the stages first).
"""

from __future__ import annotations

import importlib
import time
from collections.abc import Callable, Iterable
from pathlib import Path

import matplotlib

from g2tom.config import ConfigError, Scenario
from g2tom.store import check_writable

matplotlib.use("Agg")

__all__ = ["FAMILIES", "write_figures"]

#: Family name -> module drawing it (each in its own module: ``g2tom figures --only NAME`` draws one).
FAMILIES: dict[str, str] = {
    "contact": "g2tom.analysis.figures_contact",
    "oxide": "g2tom.analysis.figures_oxide",
    "results": "g2tom.analysis.figures_results",
    "point": "g2tom.analysis.figures_point",
    "barber": "g2tom.analysis.figures_barber",
    "validate": "g2tom.analysis.figures_validate",
}


def write_figures(scenario: Scenario, data_dir: str | Path, families: Iterable[str] | None = None,
                  on_family: Callable[[str, list[Path], float], None] | None = None) -> list[Path]:
    """Write every figure family (or those of ``families``, names of :data:`FAMILIES`, in that
    order) and return the files written.

    ``on_family(name, files, seconds)``, if given, is called after each family with the files it
    wrote (none where its input is absent: the comparison, the validation) and its wall time (s).

    Raises
    ------
    ConfigError
        Before any figure is drawn, if ``families`` names an unknown family.
    WriteError
        Before any figure is drawn, if ``<data_dir>/figures`` cannot be written (every figure
        there kept); while drawing, if one figure cannot (that one kept).
    """
    names = list(FAMILIES) if families is None else list(families)
    unknown = [name for name in names if name not in FAMILIES]
    if unknown:
        raise ConfigError(f"--only {unknown[0]!r} is not a figure family: must be one of {', '.join(FAMILIES)}")
    out_dir = Path(data_dir) / "figures"
    check_writable(out_dir, "no figure was drawn; those already there are kept")
    written: list[Path] = []
    for name in names:
        start = time.perf_counter()
        files = importlib.import_module(FAMILIES[name]).write(scenario, Path(data_dir), out_dir)
        if on_family is not None:
            on_family(name, files, time.perf_counter() - start)
        written += files
    return written
