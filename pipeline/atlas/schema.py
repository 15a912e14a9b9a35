"""The variable schema of the atlas's files: the per-scene ``atlas/scenes/<scene>.nc`` and the
gathered ``atlas/atlas.nc`` (over ``scene``), each variable's dims, units and long name, once.

The variables a scene file takes over from fits.nc (alpha, gamma, their intervals, the curve
model, ``open_probability``) keep the fits stage's declaration (:mod:`g2tom.stages.schema`)
and its coordinates the surrogate's; this declares the rest, in the form of the stage files'
schema. A long name's ``{reduction}`` slot is the scenario's ``fits.reduction``.
"""

from __future__ import annotations

from g2tom.stages.schema import Variable

__all__ = ["ATLAS", "SCALARS"]


_v = Variable.of


#: The atlas's own variables and labelled coordinates (``scene`` only in atlas.nc).
ATLAS: dict[str, Variable] = {
    "resistance_normalized": _v("xi lambda step", "1", "R' of the fitted reduction ({reduction}) over realizations"),
    "resistance_normalized_ci": _v("xi lambda step bound", "1", "bootstrap interval of the {reduction} of R' at each step"),
    "resistance_clean_normalized": _v("step", "1", "R' of the oxide-free surface"),
    "force_normalized": _v("step", "1", "F' = 2F/(E* sqrt(R* sigma^3))"),
    "fitted": _v("step", "1", "1 where the step was fitted"),
    "bound": _v("bound", "1", "end of the interval"),
    "power": _v("power", "1", "power of ln F'"),
    "mu": _v("", "1", "(8/3) eta sigma sqrt(2 R* beta)"),
    "Pi": _v("", "1", "eta R* sigma"),
    "heldout": _v("", "1", "1: held out (never used in a fit)"),
    "n_cells": _v("", "1", "cells along the window's side"),
    "wall_seconds": _v("", "s", "wall time of the scene's chain (s)"),
    "scene": _v("scene", "1", "scene name (d: design, h: held out)"),
}
#: The scene's scalars, in the order they are written.
SCALARS = ("mu", "Pi", "heldout", "n_cells", "wall_seconds")
