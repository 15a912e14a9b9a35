"""g2tom: the electrical contact resistance of rough, partially oxidized sphere-on-flat contacts.

``g2tom.predict_resistance(surface, force=..., xi=..., lam=...)`` answers as ``g2tom predict``
(:func:`g2tom.predict.answer.predict_resistance`), ``g2tom.surface_resistance(map, force=...)`` as
``g2tom surface`` (:func:`g2tom.surface.run.surface_resistance`). Each is imported on first use, so ``import g2tom``
imports nothing else from the package and no numpy: the command line still sets its BLAS thread
counts before numpy loads.

The source tree keeps the package in ``pipeline/`` (the stages, physics and fitting) and its
figures and report in ``analysis/``, installed as :mod:`g2tom` and :mod:`g2tom.analysis`.
"""

from importlib.metadata import PackageNotFoundError, version
from typing import Any

__all__ = ["__version__", "predict_resistance", "surface_resistance"]

try:
    __version__ = version("g2tom")
except PackageNotFoundError:  # running from a source tree that is not installed
    __version__ = "0.0.0+unknown"


def __getattr__(name: str) -> Any:
    if name == "predict_resistance":
        from g2tom.predict import predict_resistance

        return predict_resistance
    if name == "surface_resistance":
        from g2tom.surface import surface_resistance

        return surface_resistance
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
