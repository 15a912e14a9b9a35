"""g2tom: the Greenwood²–Tripp oxidized model (G²TOM) pipeline.

``pipeline.predict_resistance(surface, force=..., xi=..., lam=...)`` answers as ``g2tom predict``
(:func:`pipeline.predict.answer.predict_resistance`). It is imported on first use: ``import pipeline``
stays free of numpy, so the CLI still sets its BLAS thread counts before numpy loads.
"""

from importlib.metadata import PackageNotFoundError, version
from typing import Any

__all__ = ["__version__", "predict_resistance"]

try:
    __version__ = version("g2tom")
except PackageNotFoundError:  # running from a source tree that is not installed
    __version__ = "0.0.0+unknown"


def __getattr__(name: str) -> Any:
    if name == "predict_resistance":
        from pipeline.predict import predict_resistance

        return predict_resistance
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
