"""The predictor (Eq. 27) from a written surrogate: ``predictor`` (R_el and its band), ``queries``
(the grid of queries and their ranges), ``domain`` (which surface a query is on), ``atlas`` (the
shipped atlas surrogate over mu and Pi) and ``answer`` (the surrogate ``g2tom predict`` chooses
for a surface, and its answer); ``chain`` runs a measured surface's height map through the
roughness and the answer against its full field. ``surrogate.json`` is read as the surrogate stage
writes it (:mod:`g2tom.stages.surrogate_file`).

:func:`predict_resistance` is the one call for Python users (also ``g2tom.predict_resistance``).
It is imported on first use, so that importing a submodule stays as light as it was.
"""

from typing import Any

__all__ = ["predict_resistance"]


def __getattr__(name: str) -> Any:
    if name == "predict_resistance":
        from g2tom.predict.answer import predict_resistance

        return predict_resistance
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
