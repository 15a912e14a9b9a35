"""All figures of ``make figures``, written under ``<data_dir>/figures``.

Each figure family lives in its own module exposing
``write(scenario, data_dir, out_dir) -> list[Path]``; :data:`FAMILIES` says which stage files each
draws and which files it writes. A family whose input file is missing is an error (run the stages
first).
"""

from __future__ import annotations

import importlib
import time
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from pathlib import Path

import matplotlib

from g2tom.config import ConfigError, Scenario
from g2tom.store import check_writable

matplotlib.use("Agg")

__all__ = ["FAMILIES", "Family", "family_names", "write_figures"]


@dataclass(frozen=True)
class Family:
    """A family of figures, drawn by one module's ``write(scenario, data_dir, out_dir)``.

    Attributes
    ----------
    module
        The module that draws it.
    stages
        The stage files it draws (or, for the oxide fields, whose configuration it draws again): it
        is drawn once they are current, and is out of date once one of them is newer.
    files
        Every file it may write under ``figures/`` (some only where their input exists).
    """

    module: str
    stages: tuple[str, ...]
    files: tuple[str, ...]


#: Family name -> :class:`Family` (``g2tom figures --only NAME`` draws one).
FAMILIES: dict[str, Family] = {
    "contact": Family("g2tom.analysis.figures_contact", ("contact",), ("fig4_contact.png", "fig5_spots.png")),
    "oxide": Family("g2tom.analysis.figures_oxide", ("oxide",), ("fig6_oxide.png",)),
    "results": Family("g2tom.analysis.figures_results", ("cube", "fits", "surrogate"),
                      ("fig3_bounds.png", "fig8_resistance.png", "fig9_conductance.png", "fig10_alpha_gamma.png",
                       "fig10_realizations.png", "fig11_barber.png")),
    "point": Family("g2tom.analysis.figures_point", (), ("point_alpha_gamma.png", "point_film.png")),
    "barber": Family("g2tom.analysis.figures_barber", (), ("barber_spots.png",)),
    "validate": Family("g2tom.analysis.figures_validate", (), ("validate.png",)),
}


def family_names(families: Iterable[str] | None) -> list[str]:
    """The names ``families`` gives (every family for None), checked.

    Raises
    ------
    ConfigError
        If one is not a name of :data:`FAMILIES`.
    """
    names = list(FAMILIES) if families is None else list(families)
    unknown = [name for name in names if name not in FAMILIES]
    if unknown:
        raise ConfigError(f"--only {unknown[0]!r} is not a figure family: must be one of {', '.join(FAMILIES)}")
    return names


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
    names = family_names(families)
    out_dir = Path(data_dir) / "figures"
    check_writable(out_dir, "no figure was drawn; those already there are kept")
    written: list[Path] = []
    for name in names:
        start = time.perf_counter()
        files = importlib.import_module(FAMILIES[name].module).write(scenario, Path(data_dir), out_dir)
        if on_family is not None:
            on_family(name, files, time.perf_counter() - start)
        written += files
    return written
