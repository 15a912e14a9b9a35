"""Option values the command line gives as text: comma-separated lists of numbers."""

from __future__ import annotations

import numpy as np

from g2tom.config import ConfigError

__all__ = ["number_list"]


def number_list(option: str, text: str) -> np.ndarray:
    """The numbers of ``text`` (one, or a comma-separated list) given to ``option``, float64.

    Raises
    ------
    ConfigError
        Naming the option and its text when an item is not a number.
    """
    items = [t.strip() for t in text.split(",")]
    try:
        return np.array([float(t) for t in items])
    except ValueError:
        raise ConfigError(f"{option} = {text!r} is not a number or a comma-separated list of numbers") from None
