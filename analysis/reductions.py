"""Reductions of the resistance cube over realizations (see :mod:`pipeline.reductions`)."""

from pipeline.reductions import (
    DIM,
    QUANTILES,
    arithmetic_mean,
    geometric_mean,
    median,
    open_probability,
    quantiles,
    reduce_realizations,
)

__all__ = [
    "DIM",
    "QUANTILES",
    "open_probability",
    "geometric_mean",
    "arithmetic_mean",
    "quantiles",
    "median",
    "reduce_realizations",
]
