"""Errors the CLI turns into exit statuses (kept free of heavy imports)."""

from __future__ import annotations

__all__ = ["StaleInputError"]


class StaleInputError(RuntimeError):
    """A stage input is missing or was built from a different configuration."""
