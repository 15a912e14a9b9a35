"""Bundled scenarios, chosen by name (``--config paper``)."""
