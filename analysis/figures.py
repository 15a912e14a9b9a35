"""All figures of ``make figures``, written under ``<data_dir>/figures``.

Each figure family lives in its own module exposing
``write(scenario, data_dir, out_dir) -> list[Path]``; a family whose input file is missing
is an error (run the stages first). The families are drawn side by side in processes of their own
(:func:`write_figures`); each figure is the same file as when drawn alone.
"""

from __future__ import annotations

import importlib
import multiprocessing
import os
from concurrent.futures import ProcessPoolExecutor
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


def _write_family(name: str, scenario: Scenario, data_dir: Path, out_dir: Path) -> list[Path]:
    """The figures of family ``name`` (a module of :data:`FAMILIES`), written under ``out_dir``."""
    return importlib.import_module(name).write(scenario, data_dir, out_dir)


def write_figures(scenario: Scenario, data_dir: str | Path, jobs: int | None = None) -> list[Path]:
    """Write every figure family and return the files written, in the order of :data:`FAMILIES`.

    Parameters
    ----------
    scenario
        The scenario the stage files under ``data_dir`` were built from.
    data_dir
        The folder of the stage files; the figures go to its ``figures`` folder.
    jobs
        Processes drawing at once: this one and ``jobs - 1`` workers (started fresh, about a second
        each), at most one per family; default one per core. This process draws the families no
        worker has taken yet, from the last, so the work balances whatever each family costs.
        1 draws every family here, in order.

    Raises
    ------
    WriteError
        Before any figure is drawn, if ``<data_dir>/figures`` cannot be written (every figure
        there kept); while drawing, if one figure cannot (that one kept).
    """
    data_dir = Path(data_dir)
    out_dir = data_dir / "figures"
    check_writable(out_dir, "no figure was drawn; those already there are kept")
    jobs = min(len(FAMILIES), jobs or os.cpu_count() or 1)
    if jobs == 1:
        return [path for name in FAMILIES for path in _write_family(name, scenario, data_dir, out_dir)]
    pool = ProcessPoolExecutor(jobs - 1, mp_context=multiprocessing.get_context("spawn"))
    try:
        futures = [pool.submit(_write_family, name, scenario, data_dir, out_dir) for name in FAMILIES]
        here = {i: _write_family(FAMILIES[i], scenario, data_dir, out_dir)
                for i in reversed(range(len(FAMILIES))) if futures[i].cancel()}
        return [path for i, future in enumerate(futures) for path in (here[i] if i in here else future.result())]
    finally:
        pool.shutdown(cancel_futures=True)
