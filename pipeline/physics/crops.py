"""Cropping the interaction sum: the centred square of cells kept per load step, and its error bound.

Dropping conducting weight ``eps`` outside a centred crop changes the interaction sum by at
most ``eps (2 s_w - eps) / h`` (every pair is at least one pitch apart) and never increases
``R``, so the relative error of ``R`` from cropping is bounded by the weight outside the crop
(:func:`choose_crops` sizes the crops from that bound, :func:`truncation_bounds` gives it for
every square at once, :func:`crop_error_bound` for each computed entry).
"""

from __future__ import annotations

import numpy as np

__all__ = ["CROP_MARGIN", "crop_slice", "choose_crops", "truncation_bounds", "crop_error_bound"]

#: Safety factor on the oxide-free ratio sum(a)/sum(w) when sizing crops for non-radius weights.
CROP_MARGIN = 10.0


def crop_slice(n_cells: int, size: int) -> slice:
    """Centred slice of ``size`` cells out of ``n_cells`` (same parity, ``size <= n_cells``)."""
    if size > n_cells or (n_cells - size) % 2:
        raise ValueError(f"crop size {size} must be <= {n_cells} with the same parity")
    start = (n_cells - size) // 2
    return slice(start, start + size)


def choose_crops(radius: np.ndarray, weights: np.ndarray, pitch: float, tolerance: float) -> np.ndarray:
    """Smallest centred square crop per load step whose cropping bound stays within tolerance.

    Dropping conducting weight ``eps`` outside the crop changes the interaction sum by at most
    ``eps (2 s_w - eps) / h`` (every pair is at least one pitch apart), so the relative change
    of ``R >= R_self`` is at most ``4 eps s_a / (pi s_w h)``, and ``eps`` is at most the
    unmasked weight outside the crop. For radius weights ``s_a / s_w = 1`` for every oxide
    mask, so the crop is safe for all of them. For other weights the ratio depends on the
    mask; the crop is sized with :data:`CROP_MARGIN` times the oxide-free ratio, and entries
    that still exceed the tolerance are recomputed uncropped by
    :func:`g2tom.physics.constriction.resistance`.

    Parameters
    ----------
    radius, weights
        Spot radii (m) and interaction weights, shape (n_delta, n, n).
    pitch
        Cell pitch, in m.
    tolerance
        Allowed relative change of ``R``; 0 keeps the whole window.

    Returns
    -------
    numpy.ndarray
        Crop sizes in cells, shape (n_delta,), same parity as ``n``.
    """
    n = radius.shape[-1]
    sizes = np.full(radius.shape[0], n, dtype=int)
    if tolerance <= 0:
        return sizes
    margin = 1.0 if np.array_equal(radius, weights) else CROP_MARGIN
    for k, (a, w) in enumerate(zip(radius, weights)):
        if not w.sum() > 0:
            continue
        ratio = margin * a.sum() / w.sum()
        for size in range(1 + (n + 1) % 2, n, 2):
            c = crop_slice(n, size)
            outside = w.sum() - w[c, c].sum()
            if 4.0 * outside * ratio / (np.pi * pitch) <= tolerance:
                sizes[k] = size
                break
    return sizes


def truncation_bounds(radius: np.ndarray, weights: np.ndarray, pitch: float, margin: float) -> np.ndarray:
    """Bound on the relative change of ``R`` from keeping only a centred square of each odd size.

    The bound of :func:`choose_crops`, ``4 eps margin s_a / (pi s_w h)`` with ``eps`` the
    weight outside the square, for every odd square side at once: the weights are summed over
    the square rings of equal Chebyshev distance from the centre cell.

    Parameters
    ----------
    radius, weights
        Spot radii (m) and interaction weights of one map, shape (n, n), ``n`` odd.
    pitch
        Cell pitch, in m.
    margin
        Safety factor on ``s_a / s_w`` (1 for radius weights, :data:`CROP_MARGIN` otherwise).

    Returns
    -------
    numpy.ndarray
        Shape ((n + 1) // 2,): entry ``k`` bounds the square of side ``2 k + 1``; 0 for an
        empty map.
    """
    n = radius.shape[-1]
    if n % 2 == 0 or radius.shape != (n, n):
        raise ValueError(f"the map must be square with an odd side, got {radius.shape}")
    offset = np.abs(np.arange(n) - n // 2)
    ring = np.maximum(offset[:, None], offset[None, :])
    inside = np.cumsum(np.bincount(ring.ravel(), weights=weights.ravel(), minlength=n // 2 + 1))
    total = inside[-1]
    if not total > 0:
        return np.zeros(n // 2 + 1)
    outside = np.maximum(total - inside, 0.0)
    outside[-1] = 0.0
    return 4.0 * outside * margin * radius.sum() / (total * np.pi * pitch)


def crop_error_bound(
    radius_sum: np.ndarray,
    weight_sum: np.ndarray,
    outside_sum: np.ndarray,
    resistance_cropped: np.ndarray,
    pitch: float,
    rho: float,
) -> np.ndarray:
    """Upper bound on the relative error of ``R`` from dropping the spots outside a crop.

    The dropped conducting weight ``eps`` changes the interaction sum by at most
    ``eps (2 s_w - eps) / h`` and never increases ``R``, so the cropped value ``R'`` is a
    lower bound of ``R`` and ``(R - R') / R <= rho eps (2 s_w - eps) / (pi s_w^2 h R')``.

    Parameters
    ----------
    radius_sum
        ``s_a = sum phi a`` over all spots, in m (0 marks an open circuit).
    weight_sum
        ``s_w = sum phi w`` over all spots.
    outside_sum
        ``eps = sum phi w`` over the spots outside the crop.
    resistance_cropped
        ``R'`` computed with the cropped interaction sum, in ohm.
    pitch
        Cell pitch, in m.
    rho
        Effective resistivity, in ohm m.

    Returns
    -------
    numpy.ndarray
        The bound, 0 where nothing was dropped or the circuit is open.
    """
    eps = np.asarray(outside_sum, float)
    with np.errstate(divide="ignore", invalid="ignore"):
        delta_r = rho * eps * (2.0 * weight_sum - eps) / (np.pi * weight_sum**2 * pitch)
        bound = delta_r / resistance_cropped
    keep = (eps > 0) & (np.asarray(radius_sum) > 0) & np.isfinite(resistance_cropped)
    return np.where(keep, bound, 0.0)
