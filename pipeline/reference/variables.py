"""validate.nc's variables: each one's dims, units and long name, declared once (as :mod:`g2tom.stages.schema`).

Part 1 (*exactness per surface*, paired): the full field and g2tom per realization and load.
Part 2 (*the default's ensemble*, unpaired): the validated scenario's ensemble geometric mean of R
against the full field's, per load, with standard errors (variables ``ensemble_*``).
"""

from __future__ import annotations

from typing import Any

from g2tom.stages.schema import COORDINATES, Variable

__all__ = ["VARIABLES", "variable"]


def _v(dims: str, units: str, long_name: str) -> Variable:
    return Variable(tuple(dims.split()), units, long_name)


_RL = "realization load"
_OX = "xi lambda realization load"
_DM = "discretization model"
_EX = "xi lambda load"

#: Every variable and labelled coordinate of validate.nc.
VARIABLES: dict[str, Variable] = {
    # coordinates
    "load": _v("load", "1", "load step index, lightest first"),
    "realization": _v("realization", "1", "surface and oxide realization index"),
    "xi": COORDINATES["xi"],
    "lambda": COORDINATES["lambda"],
    "discretization": _v("discretization", "1", "g2tom spot discretization (contact.spots)"),
    "model": _v("model", "1", "g2tom resistance model (cube.model)"),
    "grid": _v("grid", "1", "pixels along one side of the reference grid (same window)"),
    "force": _v("load", "N", "normal force F (g2tom's at its approach; the reference is solved at it)"),
    "force_normalized": _v("load", "1", "normalized force F' = 2F / (E* sqrt(R* sigma^3))"),
    "delta_g2tom": _v("load", "m", "g2tom's approach delta at the force"),
    # part 1: the reference
    "force_reference": _v(_RL, "N", "normal force of the full-field solution"),
    "delta_reference": _v(_RL, "m", "approach delta of the full-field solution (g2tom's convention)"),
    "contact_area": _v(_RL, "m2", "contact area of the full-field solution"),
    "window_side": _v(_RL, "m", "side of the case's window (fitted to its contact)"),
    "window_side_convergence": _v("load", "m", "side of the convergence case's window"),
    "resistance_reference_clean": _v(_RL, "ohm", "full-field clean resistance (Barber's analogy)"),
    "resistance_reference": _v(_OX, "ohm", "full-field resistance with the oxide removed from the contact set"),
    # part 1: g2tom and the ratios
    "resistance_g2tom_clean": _v(f"{_DM} {_RL}", "ohm", "g2tom's clean resistance (one value over the "
                                 "realizations unless the spots are the surface's own)"),
    "resistance_g2tom": _v(f"{_DM} {_OX}", "ohm", "g2tom's resistance on the same oxide field"),
    "ratio_clean": _v(f"{_DM} {_RL}", "1", "g2tom / full-field clean resistance at equal force"),
    "ratio": _v(f"{_DM} {_OX}", "1", "g2tom / full-field oxidized resistance at equal force"),
    "ratio_clean_standard_error": _v(f"{_DM} load", "1", "standard error of ln of the geometric-mean clean "
                                     "ratio over the realizations (paired)"),
    "ratio_standard_error": _v(f"{_DM} {_EX}", "1", "standard error of ln of the geometric-mean oxidized "
                               "ratio over the realizations (paired)"),
    # part 1: the reference's own checks and costs
    "resistance_convergence": _v("grid load", "ohm", "clean full-field resistance of the first realization on "
                                 "each grid"),
    "convergence_change": _v("load", "1", "relative change of the clean R when the grid step doubles"),
    "barber_ratio": _v("load", "1", "punch conductance / (K / (E* rho*)), K = dF/d(-delta) from loads "
                       "F (1 +- 1 %), convergence grid"),
    "seconds_contact": _v(_RL, "s", "wall time of the full-field contact solve"),
    "seconds_case": _v(_RL, "s", "wall time of the case (contact and every conductance)"),
    "seconds_convergence": _v("load", "s", "wall time of the convergence-grid case"),
    "seconds_cpu_case": _v(_RL, "s", "CPU time of the case (its time on a core of its own)"),
    "ensemble_seconds": _v("load", "s", "summed wall time of part 2's full-field cases at the load"),
    "ensemble_seconds_cpu": _v("load", "s", "summed CPU time of part 2's full-field cases at the load"),
    # part 2: the default's ensemble against the full field's
    "ensemble_realization": _v("ensemble_realization", "1", "realization index of part 2's full-field ensemble"),
    "ensemble_count_clean": _v("load", "1", "realizations in the full field's clean ensemble (part 2)"),
    "ensemble_count": _v(_EX, "1", "realizations in the full field's oxidized ensemble (part 2)"),
    "ensemble_grid_cases": _v("load", "1", "full-field cases solved on the ensemble grid at the load (part 2)"),
    "ensemble_stand_in_clean": _v("load", "1", "1: the discrete solve of each surface's own caps stands in for the "
                                  "full field beyond part 1's realizations (part 1 within the tolerance); "
                                  "0: the full field on the ensemble grid, or part 1's alone"),
    "ensemble_stand_in": _v(_EX, "1", "1: the discrete solve of each surface's own caps stands in for the full "
                            "field beyond part 1's realizations; 0: the full field"),
    "ensemble_pairs": _v("load", "1", "realizations of the full field on the main grid paired with their proxy at "
                         "the load (part 1's, then part 2's added ones: realizations 0 .. P-1)"),
    "resistance_pairs_clean": _v("ensemble_realization load", "ohm", "the full field's clean resistance on the "
                                 "main grid per paired realization (part 1's and part 2's; NaN: not solved)"),
    "resistance_pairs": _v("xi lambda ensemble_realization load", "ohm", "the full field's oxidized resistance on "
                           "the main grid per paired realization (part 1's and part 2's; NaN: not solved)"),
    "resistance_ensemble_clean": _v("ensemble_realization load", "ohm", "part 2's proxy of the full field's clean "
                                    "resistance per realization (ensemble grid or stand-in; NaN: not solved)"),
    "resistance_ensemble": _v("xi lambda ensemble_realization load", "ohm", "part 2's proxy of the full field's "
                              "oxidized resistance per realization (ensemble grid or stand-in; NaN: not solved)"),
    "ensemble_reference_clean": _v("load", "ohm", "the full field's clean ensemble geometric mean of R "
                                   "(two-phase: proxy mean plus the main-grid pairs' correction)"),
    "ensemble_reference_clean_standard_error": _v("load", "1", "standard error of ln of the full field's clean "
                                                  "ensemble geometric mean"),
    "ensemble_reference": _v(_EX, "ohm", "the full field's oxidized ensemble geometric mean of R over conducting "
                             "realizations (two-phase)"),
    "ensemble_reference_standard_error": _v(_EX, "1", "standard error of ln of the full field's oxidized "
                                            "ensemble geometric mean"),
    "ensemble_reference_clean_pairs_standard_error": _v("load", "1", "the pairs' share of the full field's clean "
                                                        "standard error, sd(ln main grid / proxy) / sqrt(P) "
                                                        "(NaN: part 1 alone, no proxy)"),
    "ensemble_reference_pairs_standard_error": _v(_EX, "1", "the pairs' share of the full field's oxidized standard "
                                                  "error, sd(ln main grid / proxy) / sqrt(P) (NaN: part 1 alone, "
                                                  "no proxy)"),
    "ensemble_reference_open_fraction": _v(_EX, "1", "fraction of the full field's ensemble that is an open "
                                           "circuit"),
    "ensemble_model_clean": _v("load", "ohm", "the validated scenario's clean ensemble geometric mean of R"),
    "ensemble_model_clean_standard_error": _v("load", "1", "standard error of ln of the validated scenario's "
                                              "clean ensemble geometric mean (0: one exact value)"),
    "ensemble_model": _v(_EX, "ohm", "the validated scenario's oxidized ensemble geometric mean of R over "
                         "conducting realizations"),
    "ensemble_model_standard_error": _v(_EX, "1", "standard error of ln of the validated scenario's oxidized "
                                        "ensemble geometric mean"),
    "ensemble_model_open_fraction": _v(_EX, "1", "fraction of the validated scenario's ensemble that is an "
                                       "open circuit"),
    "ensemble_model_count": _v("", "1", "realizations in the validated scenario's oxidized ensemble"),
    "ensemble_model_count_clean": _v("", "1", "values in the validated scenario's clean ensemble (its pool's "
                                     "surfaces; 1: one exact answer)"),
    "ensemble_ratio_clean": _v("load", "1", "the validated scenario's / the full field's clean ensemble "
                               "geometric mean of R at equal force"),
    "ensemble_ratio_clean_standard_error": _v("load", "1", "standard error of ln of the clean ensemble ratio "
                                              "(both ensembles' in squares)"),
    "ensemble_ratio": _v(_EX, "1", "the validated scenario's / the full field's oxidized ensemble geometric "
                         "mean of R at equal force"),
    "ensemble_ratio_standard_error": _v(_EX, "1", "standard error of ln of the oxidized ensemble ratio (both "
                                        "ensembles' in squares)"),
    "ensemble_target_clean": _v("load", "1", "allowed |clean ratio - 1| at the load's F' (accuracy target)"),
    "ensemble_target": _v(_EX, "1", "allowed |oxidized ratio - 1| at the load's F' (accuracy target; NaN: none)"),
    "ensemble_grid_check_clean": _v("load", "1", "geometric mean over the pairs' realizations of the ensemble "
                                    "grid's clean R over the main grid's (NaN: no ensemble case)"),
}


def variable(name: str, data: Any, **extra: Any) -> tuple[tuple[str, ...], Any, dict[str, Any]]:
    """``(dims, data, attrs)`` of validate.nc's variable ``name`` for :class:`xarray.Dataset`
    (``extra`` attributes, e.g. a ``comment``, after ``units`` and ``long_name``)."""
    var = VARIABLES[name]
    return var.dims, data, {**var.attrs(), **extra}
