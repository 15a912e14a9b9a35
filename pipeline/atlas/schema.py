"""The variable schema of the atlas's files: the per-scene ``atlas/scenes/<scene>.nc`` and the
gathered ``atlas/atlas.nc`` (over ``scene``), each variable's dims, units and long name, read from
the metadata registry (:mod:`g2tom.variables`, namespace ``atlas``).

The variables a scene file takes over from fits.nc (alpha, gamma, their intervals, the curve
model, ``open_probability``) keep the fits stage's declaration (:mod:`g2tom.stages.schema`)
and its coordinates the surrogate's; the registry declares the rest, in the form of the stage
files' schema. A long name's ``{reduction}`` slot is the scenario's ``fits.reduction``.
"""

from __future__ import annotations

from g2tom.variables import Variable, namespace

__all__ = ["ATLAS", "SCALARS"]


#: The atlas's own variables and labelled coordinates (``scene`` only in atlas.nc).
ATLAS: dict[str, Variable] = namespace("atlas")
#: The scene's scalars, in the order they are written.
SCALARS = ("mu", "Pi", "heldout", "n_cells", "wall_seconds")
