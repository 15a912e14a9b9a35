"""Each parameter's value against its declaration: type, range, choices (before any cross-check).

The checks across parameters (one setting that rules out another, the window against the domain)
run before work, in :mod:`g2tom.before_work.scenario_checks` and
:mod:`g2tom.before_work.window_checks`.
"""

from __future__ import annotations

import dataclasses
import difflib
import math
from typing import Any, Mapping

from g2tom.config.declare import AUTO, UNSET, ConfigError, format_range, parameter_key
from g2tom.config.scenario import SECTIONS

__all__ = ["check_field", "unknown"]


def _check_scalar(name: str, value: Any, kind: type, meta: Mapping[str, Any]) -> Any:
    unit = meta["unit"]
    allowed = format_range(meta)
    where = f"{name} = {value!r}"
    if kind is str:
        if not isinstance(value, str) or (meta["choices"] and value not in meta["choices"]):
            raise ConfigError(f"{where} is not allowed: must be {allowed}")
        return value
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ConfigError(f"{where} is not a number: must be {allowed} ({unit})")
    if kind is int:
        if isinstance(value, float) and not value.is_integer():
            raise ConfigError(f"{where} is not an integer: must be an integer {allowed}")
        value = int(value)
    else:
        value = float(value)
        if not math.isfinite(value):
            raise ConfigError(f"{where} is not finite: must be {allowed} ({unit})")
    ok = (
        (meta["gt"] is None or value > meta["gt"])
        and (meta["ge"] is None or value >= meta["ge"])
        and (meta["lt"] is None or value < meta["lt"])
        and (meta["le"] is None or value <= meta["le"])
    )
    if not ok:
        raise ConfigError(f"{where} is out of range: must be {allowed} ({unit})")
    return value


def _element_kind(f: dataclasses.Field) -> tuple[type, bool]:
    ann = str(f.type)
    if f.metadata.get("auto") or f.metadata.get("unset"):
        ann = ann.split("|")[0].strip()  # "float | str" or "float | None": a number, or the word
    if ann.startswith("list"):
        return (float if "float" in ann else int if "int" in ann else str), True
    return {"float": float, "int": int, "str": str}[ann], False


def check_field(section: str, f: dataclasses.Field, value: Any) -> Any:
    """``value`` of field ``f`` of ``section`` as its declared type, or a ConfigError naming the parameter,
    its value and the allowed range (lists: non-empty, each element in range, strictly increasing unless declared
    ``ordered=False``; ``"none"`` where declared ``unset``: None)."""
    name = f"{section}.{parameter_key(f)}"
    if f.metadata.get("auto") and value == AUTO:
        return AUTO
    if f.metadata.get("unset") and value in (UNSET, None):
        return None
    kind, is_list = _element_kind(f)
    if not is_list:
        return _check_scalar(name, value, kind, f.metadata)
    if not isinstance(value, (list, tuple)) or len(value) == 0:
        raise ConfigError(
            f"{name} = {value!r} is not allowed: must be a non-empty list of {'names' if kind is str else 'numbers'}, each "
            f"{format_range(f.metadata)} ({f.metadata['unit']})"
        )
    out = [_check_scalar(f"{name}[{i}]", v, kind, f.metadata) for i, v in enumerate(value)]
    if f.metadata.get("ordered", True) and (len(set(out)) != len(out) or out != sorted(out)):
        raise ConfigError(f"{name} = {value!r} must be strictly increasing")
    return out


def _all_keys() -> list[str]:
    return [f"{s}.{parameter_key(f)}" for s, cls in SECTIONS.items() for f in dataclasses.fields(cls)]


def unknown(name: str) -> ConfigError:
    """The error for an unknown parameter ``name``, naming the closest known one."""
    keys = _all_keys()
    leaf = name.rsplit(".", 1)[-1]
    exact_leaf = [k for k in keys if k.rsplit(".", 1)[-1].lower() == leaf.lower()]
    close = exact_leaf or difflib.get_close_matches(name, keys, n=1, cutoff=0.5)
    if not close:
        close = difflib.get_close_matches(
            leaf, [k.rsplit(".", 1)[-1] for k in keys], n=1, cutoff=0.6
        )
        close = [k for k in keys if close and k.endswith("." + close[0])][:1]
    hint = f"; did you mean '{close[0]}'?" if close else ""
    return ConfigError(f"unknown parameter '{name}'{hint}")

