"""g2tom: the Greenwood²–Tripp oxidized model (G²TOM) pipeline.

``pipeline.predict_resistance(surface, force=..., xi=..., lam=...)`` answers as ``g2tom predict``
(:func:`pipeline.predict.answer.predict_resistance`). It is imported on first use: ``import pipeline``
stays free of numpy, so the CLI still sets its BLAS thread counts before numpy loads.

Importing the package sets the checks across parameters that every loaded scenario passes
(:func:`pipeline.before_work.scenario_checks.check_scenario`, through
:func:`pipeline.config.use_cross_checks`): they stand before work, above config, which imports
nothing from the package.
"""

from importlib.metadata import PackageNotFoundError, version
from typing import Any

__all__ = ["__version__", "predict_resistance"]

try:
    __version__ = version("g2tom")
except PackageNotFoundError:  # running from a source tree that is not installed
    __version__ = "0.0.0+unknown"

from pipeline.before_work.scenario_checks import check_scenario as _check_scenario  # noqa: E402
from pipeline.config import use_cross_checks as _use_cross_checks  # noqa: E402

_use_cross_checks(_check_scenario)


def __getattr__(name: str) -> Any:
    if name == "predict_resistance":
        from pipeline.predict import predict_resistance

        return predict_resistance
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
