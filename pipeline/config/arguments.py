"""The Python API's arguments checked at its entry: each refusal a :class:`~g2tom.config.ConfigError`
naming the argument, its value and what is allowed (the CLI prints it as its one ``g2tom: error:``
line)."""

from __future__ import annotations

import numbers
import os
import re
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

import numpy as np
import xarray as xr

from g2tom.config.declare import ConfigError

__all__ = ["refuse_argument", "is_path", "holds_numbers", "is_number", "is_whole", "python_terms", "in_python_terms"]


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


#: A command-line option (``--pixel-size``) not inside a word.
_OPTION = re.compile(r"(?<![\w-])--([a-z][a-z0-9]*(?:-[a-z0-9]+)*)")


def python_terms(message: str) -> str:
    """``message`` with each command-line option (``--pixel-size``) named as the Python API's argument
    (``pixel_size``), except inside `...` (a command to run keeps its options)."""
    parts = message.split("`")
    parts[::2] = [_OPTION.sub(lambda m: m.group(1).replace("-", "_"), part) for part in parts[::2]]
    return "`".join(parts)


@contextmanager
def in_python_terms() -> Iterator[None]:
    """Inside, a :class:`~g2tom.config.ConfigError` (of any subclass) leaves in :func:`python_terms`:
    the checks the command line shares with the Python API name the API's arguments there."""
    try:
        yield
    except ConfigError as exc:
        if exc.args and isinstance(exc.args[0], str):
            exc.args = (python_terms(exc.args[0]), *exc.args[1:])
        raise
