"""The Python API's arguments checked at its entry: each refusal a :class:`~g2tom.config.ConfigError`
naming the argument, its value and what is allowed (the CLI prints it as its one ``g2tom: error:``
line)."""

from __future__ import annotations

import numbers
import os
from typing import Any

import numpy as np
import xarray as xr

from g2tom.config.declare import ConfigError

__all__ = ["refuse_argument", "is_path", "holds_numbers", "is_number", "is_whole"]


def refuse_argument(name: str, value: Any, allowed: str) -> ConfigError:
    """The refusal of argument ``name``: its value (cut to 60 characters) and what is ``allowed``."""
    shown = repr(value) if len(repr(value)) <= 60 else f"{repr(value)[:57]}..."
    return ConfigError(f"{name} = {shown} is not allowed: must be {allowed}")


def is_path(value: Any) -> bool:
    """Whether ``value`` names a file or folder (a str or an os.PathLike)."""
    return isinstance(value, (str, os.PathLike))


def holds_numbers(value: Any) -> bool:
    """A number, or an array or DataArray of numbers (not text, not booleans)."""
    data = value.values if isinstance(value, xr.DataArray) else value
    try:
        kind = np.asarray(data).dtype.kind
    except (TypeError, ValueError):  # ragged nested lists
        return False
    return kind in "iuf"


def is_number(value: Any) -> bool:
    """A real number (not a bool, not text)."""
    return isinstance(value, numbers.Real) and not isinstance(value, bool)


def is_whole(value: Any) -> bool:
    """A whole number (an int or a NumPy integer, not a bool)."""
    return isinstance(value, numbers.Integral) and not isinstance(value, bool)
