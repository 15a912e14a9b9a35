"""The metadata registry: every variable g2tom writes, declared once in ``variables.toml``.

Each entry of the registry names a variable's dims, CF units and long name (possibly with
``{field}`` slots the writer fills); an entry written as a dotted path (``"stages.coordinates.xi"``)
is the declaration it names. Namespaces group the entries by file: ``stages.<stage>``,
``validate``, ``bench.frontier``, ``bench.stability``, ``atlas``, ``predict``; ``texts.*`` hold
long-name choices and unit exceptions. The schema modules (:mod:`g2tom.stages.schema`,
:mod:`g2tom.reference.variables`, :mod:`g2tom.bench.schema`, :mod:`g2tom.atlas.schema`), the
reductions and the predictor read their attributes from here.
"""

from __future__ import annotations

import re
import tomllib
from dataclasses import dataclass
from functools import cache
from importlib.resources import files
from typing import Any

__all__ = ["Variable", "registry", "namespace", "entry", "texts"]


@dataclass(frozen=True)
class Variable:
    """An output variable: its dimensions, CF units and long name (possibly with ``{field}`` slots)."""

    dims: tuple[str, ...]
    units: str
    long_name: str

    def attrs(self, **fields: Any) -> dict[str, str]:
        """``units`` and ``long_name``, the long name's slots filled from ``fields``."""
        return {"units": self.units, "long_name": self.long_name.format(**fields)}

    @classmethod
    def of(cls, dims: str, units: str, long_name: str) -> "Variable":
        """A variable whose dimensions are written as one space-separated string (``""``: a scalar)."""
        return cls(tuple(dims.split()), units, long_name)

    def pattern(self) -> re.Pattern[str]:
        """A regular expression of the long name, any text in place of each slot."""
        parts = re.split(r"\{\w+\}", self.long_name)
        return re.compile(".+".join(re.escape(p) for p in parts) + r"\Z")


@cache
def registry() -> dict[str, Any]:
    """The parsed ``variables.toml`` shipped in the package, tables nested by namespace."""
    return tomllib.loads(files("g2tom").joinpath("variables.toml").read_text(encoding="utf-8"))


def _table(path: str) -> dict[str, Any]:
    """The registry's table at the dotted ``path`` (``"stages.fits"``)."""
    table = registry()
    for part in path.split("."):
        table = table[part]
    return table


def _variable(declared: dict[str, Any] | str) -> Variable:
    """A registry entry as a :class:`Variable` (no ``dims``: the shape of the inputs, ``()``)."""
    if isinstance(declared, str):
        return entry(declared)
    return Variable(tuple(declared.get("dims", ())), declared["units"], declared["long_name"])


def entry(path: str) -> Variable:
    """The variable declared at the dotted ``path`` (``"stages.fits.alpha"``)."""
    table, name = path.rsplit(".", 1)
    return _variable(_table(table)[name])


def namespace(path: str) -> dict[str, Variable]:
    """Every variable of the namespace at the dotted ``path`` (``"stages.fits"``), in the order declared."""
    return {name: _variable(declared) for name, declared in _table(path).items()}


def texts(path: str) -> dict[str, str]:
    """The text table at the dotted ``path`` under ``texts`` (``"spot_radius"``: long names by choice)."""
    return dict(_table(f"texts.{path}"))
