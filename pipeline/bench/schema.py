"""The variable schema of the benchmarks' netCDF files: each variable's dims, units and long name, once.

``bench/frontier.nc`` (:mod:`g2tom.bench.frontier`: :data:`FRONTIER`, the sweep tables'
columns by :func:`sweep_column`) and ``bench/stability.nc`` (:mod:`g2tom.bench.stability`:
:data:`STABILITY`), in the form of the stage files' schema (:mod:`g2tom.stages.schema`).
Their attributes are written long name first (:func:`g2tom.stages.schema.labelled`), as
they always were.
"""

from __future__ import annotations

from g2tom.stages.schema import Variable

__all__ = ["FRONTIER", "STABILITY", "SWEEP_UNITS", "sweep_column", "sweep_index"]


_v = Variable.of


_ENSEMBLE = "n_realizations xi lambda"
_PREFIX = "cube_xi cube_lambda prefix_step"

#: frontier.nc: the ensemble sweep and the adaptive cube's prefix curve (the sweep tables: :func:`sweep_column`).
FRONTIER: dict[str, Variable] = {
    "alpha_halfwidth": _v(_ENSEMBLE, "1", "relative half-width of the alpha interval"),
    "gamma_halfwidth": _v(_ENSEMBLE, "1", "relative half-width of the gamma interval"),
    "alpha": _v(_ENSEMBLE, "1", "fitted alpha"),
    "gamma": _v(_ENSEMBLE, "1", "fitted gamma"),
    "ensemble_seconds": _v("n_realizations", "s", "oxide + cube time prorated to n, plus the fits time"),
    "n_realizations": _v("n_realizations", "1", "realizations fitted"),
    "xi": _v("xi", "1", "oxide fraction"),
    "lambda": _v("lambda", "1", "normalized correlation length"),
    "prefix_n": _v(_PREFIX, "1", "realizations in the prefix of the adaptive cube's cell"),
    "prefix_alpha_halfwidth": _v(_PREFIX, "1",
                                 "fast-rule relative half-width of alpha with the first prefix_n realizations"),
    "prefix_gamma_halfwidth": _v(_PREFIX, "1",
                                 "fast-rule absolute half-width of gamma with the first prefix_n realizations"),
    "prefix_seconds": _v(_PREFIX, "s", "cube stage time prorated to prefix_n realizations of the cell"),
    "prefix_count": _v("cube_xi cube_lambda", "1", "realizations of the adaptive cube's cell"),
    "cube_xi": _v("cube_xi", "1", "oxide fraction (adaptive cube)"),
    "cube_lambda": _v("cube_lambda", "1", "normalized correlation length (adaptive cube)"),
    "prefix_step": _v("prefix_step", "1", "prefix index"),
}

#: Units of the sweep tables' columns that have one; every other column is dimensionless.
SWEEP_UNITS = {"seconds": "s", "n_radial": "1"}


def sweep_column(table: str, key: str) -> Variable:
    """Column ``key`` of the sweep ``table`` (``contact`` or ``cube``) of frontier.nc: ``<table>_<key>``."""
    return Variable((table,), SWEEP_UNITS.get(key, "1"), f"{table} sweep: {key.replace('_', ' ')}")


def sweep_index(table: str) -> Variable:
    """The coordinate of the sweep ``table``: one index per setting."""
    return Variable((table,), "1", f"{table} setting")


#: stability.nc: one entry per case of the stability map.
STABILITY: dict[str, Variable] = {
    "status": _v("case", "1", "converged, unconverged, refused (by validation) or failed"),
    "message": _v("case", "1", "why a case was refused, failed or did not converge"),
    "converged": _v("case", "1", "1 if every approach converged"),
    "iterations": _v("case", "1", "largest solver iteration count over the approaches"),
    "residual": _v("case", "1", "worst final relative residual over the approaches"),
    "seconds": _v("case", "s", "wall time of the contact build and clean resistance"),
    "finite_nonnegative": _v("case", "1", "1 if no NaN or negative value anywhere"),
    "force_monotone": _v("case", "1", "1 if the force grows with every approach step"),
    "resistance_falls": _v("case", "1", "1 if the clean resistance falls with load"),
    "open_circuits": _v("case", "1", "approaches with no touching spot (R = +inf)"),
    "hertz_ratio": _v("case", "1",
                      "central pressure / Hertz central pressure at the heaviest load (sphere; 1 in the smooth limit)"),
    "roughness_parameter": _v("case", "1", "sigma R* / a_Hertz^2 at the heaviest load (sphere)"),
    "case": _v("case", "1", "case number"),
    "parameter": _v("case", "1", "parameter pushed to an extreme"),
    "value": _v("case", "1", "its value"),
}
