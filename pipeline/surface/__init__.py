"""The resistance of a measured surface: the full field on windows of a height map (``g2tom surface``).

A sphere (or another indenter of the scenario) is pressed at given forces on a window of the
measured topography around each contact position; the full-field contact (elastic, or with the
pressure capped at the hardness) is solved on the window's pixels, the clean conductance by
Barber's analogy (the flat punch on the contact set), and the conductance with oxide by removing
each oxide field's islands from the contact set. The positions over the map are the ensemble.

Modules: ``study`` (what is computed: forces, oxide cases, positions, the pair's materials),
``maps`` (the map or the composite of two, its measured area and plane), ``windows`` (the window
the contact needs, the refusals before work, the positions), ``oxide`` (oxide fields on a window's
pixels, correlation lengths in m), ``solve`` (one position's forces and conductances),
``dataset`` (surface.nc), ``statistical`` (the predictor on the map's summits, beside the full
field), ``run`` (the driver: :func:`surface_resistance`).
"""

from __future__ import annotations

from g2tom.surface.run import surface_resistance

__all__ = ["surface_resistance"]
