"""The full-field reference: elastic contact of the actual rough sphere on a grid.

Only this package imports the optional extra ``tamaas`` (``pip install -e '.[reference]'``),
and only :mod:`g2tom.reference.elastic` touches it: everything else calls that module's
free-surface operator and contact solver, so another array backend can replace them there.

Modules: ``elastic`` (the non-periodic Boussinesq operator and the library's contact solver),
``contact`` (load steps of a rough sphere), ``punch`` (conductance of a conducting set by
Barber's analogy), ``surfaces`` (sphere, GW and random-process surfaces), ``oxide`` (g2tom's
oxide field on the grid), ``scene`` (the validation scene and its g2tom counterpart),
``surface_spots`` and ``discrete_spots`` (g2tom on the GW surface's own asperities), ``window``
(each case's window, fitted to its contact), ``cases`` (one stored case), ``statistics`` (part 2's
ensemble means and standard errors), ``ensemble`` (part 2: the validated scenario's ensemble
against the full field's), ``cost`` (the plan's estimate), ``validate`` (the ``g2tom validate``
driver), ``variables`` and ``summary`` (validate.nc) and ``section`` (its report section).
"""

from __future__ import annotations

from g2tom.errors import install_hint

__all__ = ["INSTALL_HINT", "missing_extra"]

#: The command that installs the reference's optional dependency into the Python running g2tom.
INSTALL_HINT = install_hint("reference", "tamaas")


def missing_extra() -> str | None:
    """Why the reference cannot run (the extra is not installed), or None when it can."""
    try:
        import tamaas  # noqa: F401
    except ImportError as exc:
        return (f"the full-field reference needs the optional extra 'reference' (tamaas), "
                f"which is not installed ({exc}): install it with {INSTALL_HINT}")
    return None
