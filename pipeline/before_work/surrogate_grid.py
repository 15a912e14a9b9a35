"""The surrogate stage's limits on the oxide grid, checked before any stage runs (``run``, ``surrogate``)."""

from __future__ import annotations

from g2tom.config import ConfigError, Scenario

__all__ = ["JOINT_MIN_VALUES", "check_surrogate_grid", "small_grid_note"]


#: Values per axis of the (xi, lambda) grid the joint surrogate needs (leave-one-line-out).
JOINT_MIN_VALUES = 3


def small_grid_note(s: Scenario) -> str | None:
    """Why the surrogate stage fits the paper method instead of the configured joint one, or None.

    A grid with fewer than :data:`JOINT_MIN_VALUES` values of oxide.xi or oxide.lambda (one cell,
    one row, one column) cannot be cross-validated line by line: the surrogate stage then fits the
    paper method with its rank and orders reduced to what the grid determines, which reproduces
    each fitted cell (one cell: that cell's alpha, gamma and curve), and ``g2tom predict`` answers
    only within the grid's ranges.

    Returns
    -------
    str or None
        One line naming the grid and what the surrogate is instead, or None when
        ``surrogate.method`` is not ``joint`` or the grid is large enough for it.
    """
    n_xi, n_lam = len(s.oxide.xi), len(s.oxide.lambda_)
    if s.surrogate.method != "joint" or min(n_xi, n_lam) >= JOINT_MIN_VALUES:
        return None
    return (f"the oxide grid holds {n_xi} value(s) of oxide.xi and {n_lam} of oxide.lambda: too few for "
            f"surrogate.method = 'joint' (>= {JOINT_MIN_VALUES} of each, for leave-one-line-out cross-validation); "
            "the surrogate is fitted trivially instead (the paper method reduced to the grid: it reproduces each "
            "fitted cell, is not cross-validated, and predict answers only within the grid's ranges)")


def check_surrogate_grid(s: Scenario) -> str | None:
    """Cross-stage limits of the surrogate stage on the oxide grid, checked before any stage runs.

    Called for the commands that reach the surrogate stage (``run``, ``surrogate``): a grid
    that other stages accept may still be too small for the configured surrogate.

    Returns
    -------
    str or None
        :func:`small_grid_note`: the line to tell the user when the grid is too small for the
        joint surrogate (the stage then fits a trivial one), else None.

    Raises
    ------
    ConfigError
        If ``surrogate.rank`` exceeds min(len(oxide.xi), len(oxide.lambda)) (an SVD of that
        grid has no more modes).
    """
    n_xi, n_lam = len(s.oxide.xi), len(s.oxide.lambda_)
    top = min(n_xi, n_lam)
    if s.surrogate.rank > top:
        raise ConfigError(
            f"surrogate.rank = {s.surrogate.rank} is out of range: must be >= 1 and <= {top} = "
            f"min(len(oxide.xi) = {n_xi}, len(oxide.lambda) = {n_lam}) (an SVD of the grid has no more modes)"
        )
    return small_grid_note(s)
