"""How a parameter is declared: its unit, meaning and allowed range, and the error a bad value raises.

Every field of a section (:mod:`g2tom.config.scene_sections`, :mod:`g2tom.config.study_sections`)
is made by :func:`param`, so validation (:mod:`g2tom.config.validation`), documentation
(:func:`g2tom.config.loading.parameter_table`) and provenance all read one declaration.
"""

from __future__ import annotations

import dataclasses
from dataclasses import field
from typing import Any, Mapping

__all__ = ["AUTO", "UNSET", "ConfigError", "param", "parameter_key", "format_range"]


#: The value of ``contact.r_max`` and ``contact.window`` resolved from the solution
#: (:func:`g2tom.before_work.domains.resolve`) before any stage runs.
AUTO = "auto"
#: The word a parameter declared with ``unset=True`` takes for "not given" (held as ``None``), e.g.
#: ``material.hardness = "none"``: elastic asperities.
UNSET = "none"


class ConfigError(ValueError):
    """A parameter is unknown, malformed or outside its allowed range."""


def _spec(
    unit: str,
    doc: str,
    *,
    gt: float | None = None,
    ge: float | None = None,
    lt: float | None = None,
    le: float | None = None,
    choices: tuple[str, ...] | None = None,
    key: str | None = None,
    each: bool = False,
    auto: bool = False,
    unset: bool = False,
    ordered: bool = True,
) -> dict[str, Any]:
    """Field metadata: unit, description and allowed range (``each`` applies it per element;
    ``auto`` also accepts the word ``"auto"``, resolved from the solution before any stage runs;
    ``unset`` accepts the word ``"none"``, held as ``None``; ``ordered`` False lets a list's
    elements come in any order)."""
    return {
        "auto": auto,
        "unset": unset,
        "ordered": ordered,
        "unit": unit,
        "doc": doc,
        "gt": gt,
        "ge": ge,
        "lt": lt,
        "le": le,
        "choices": choices,
        "key": key,
        "each": each,
    }


def param(default: Any, unit: str, doc: str, **limits: Any) -> Any:
    """A dataclass field with ``default`` and its metadata (:func:`_spec`; lists are copied per instance)."""
    if isinstance(default, list):
        return field(default_factory=lambda: list(default), metadata=_spec(unit, doc, **limits))
    return field(default=default, metadata=_spec(unit, doc, **limits))


def parameter_key(f: dataclasses.Field) -> str:
    """The key of a field in TOML, ``--set`` and the outputs (``lambda`` for ``lambda_``)."""
    return f.metadata.get("key") or f.name


def format_range(meta: Mapping[str, Any]) -> str:
    """The allowed range of a field's metadata, as the messages and ``g2tom params`` print it."""
    parts = []
    if meta["choices"]:
        return "one of " + ", ".join(repr(c) for c in meta["choices"])
    if meta["gt"] is not None:
        parts.append(f"> {meta['gt']:g}")
    if meta["ge"] is not None:
        parts.append(f">= {meta['ge']:g}")
    if meta["lt"] is not None:
        parts.append(f"< {meta['lt']:g}")
    if meta["le"] is not None:
        parts.append(f"<= {meta['le']:g}")
    text = " and ".join(parts) if parts else "any finite value"
    if meta.get("auto"):
        return f"{text}, or 'auto'"
    return f"{text}, or {UNSET!r}" if meta.get("unset") else text
