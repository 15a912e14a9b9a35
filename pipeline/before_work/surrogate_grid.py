"""The surrogate stage's limits on the oxide grid, checked before any stage runs (``run``, ``surrogate``)."""

from __future__ import annotations

from g2tom.config import ConfigError, Scenario

__all__ = ["JOINT_MIN_VALUES", "check_surrogate_grid"]


#: Values per axis of the (xi, lambda) grid the joint surrogate needs (leave-one-line-out).
JOINT_MIN_VALUES = 3


def check_surrogate_grid(s: Scenario) -> None:
    """Cross-stage limits of the surrogate stage on the oxide grid, checked before any stage runs.

    Called for the commands that reach the surrogate stage (``run``, ``surrogate``): a grid
    that other stages accept may still be too small for the surrogate.

    Raises
    ------
    ConfigError
        If ``surrogate.rank`` exceeds min(len(oxide.xi), len(oxide.lambda)) (an SVD of that
        grid has no more modes), or ``surrogate.method = 'joint'`` has fewer than
        :data:`JOINT_MIN_VALUES` values of oxide.xi or oxide.lambda.
    """
    n_xi, n_lam = len(s.oxide.xi), len(s.oxide.lambda_)
    top = min(n_xi, n_lam)
    if s.surrogate.rank > top:
        raise ConfigError(
            f"surrogate.rank = {s.surrogate.rank} is out of range: must be >= 1 and <= {top} = "
            f"min(len(oxide.xi) = {n_xi}, len(oxide.lambda) = {n_lam}) (an SVD of the grid has no more modes)"
        )
    if s.surrogate.method == "joint" and min(n_xi, n_lam) < JOINT_MIN_VALUES:
        short = "oxide.xi" if n_xi < JOINT_MIN_VALUES else "oxide.lambda"
        raise ConfigError(
            f"{short} holds {n_xi if short == 'oxide.xi' else n_lam} value(s): surrogate.method = 'joint' needs "
            f">= {JOINT_MIN_VALUES} values of oxide.xi and of oxide.lambda (leave-one-line-out "
            "cross-validation); add values or set surrogate.method = 'paper'"
        )
