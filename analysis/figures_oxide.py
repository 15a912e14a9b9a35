"""Fig. 6: random fields for lambda = 2, 5, 10 and the oxides thresholded at xi = 50, 20, 10 %.

The fields are those the oxide stage draws for these lambda values (realization 0 of the
scenario's seed), evaluated exactly by :func:`g2tom.physics.oxide_field.field_at_points` on a
display grid finer than the cells; the lower row marks the oxide-covered cell centres.
"""

from __future__ import annotations

from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from g2tom.analysis.style import LABELS, context, equals, save, size
from g2tom.config import ResolvedScenario, Scenario
from g2tom.physics import oxide_band, oxide_field
from g2tom.physics.grid import cell_centres

__all__ = ["write", "LAMBDAS", "FRACTIONS"]

#: Correlation lengths (columns) and oxide fractions (one per column) of the paper's Fig. 6.
LAMBDAS: tuple[float, ...] = (2.0, 5.0, 10.0)
FRACTIONS: tuple[float, ...] = (0.5, 0.2, 0.1)
#: Display pixels per cell.
SUPERSAMPLING = 4


def _field(scenario: ResolvedScenario, lam: float) -> tuple[oxide_band.Band, np.ndarray]:
    """Band and coefficients of realization 0 at ``lam``, as the stage draws them."""
    ox = scenario.oxide
    modes = oxide_band.band(scenario.n_cells, scenario.cell_size, lam, ox.ks_ratio, ox.hurst)
    coeffs = oxide_band.coefficients(modes, oxide_band.field_stream(ox.seed, lam, 0), ox.amplitudes)
    return modes, coeffs


def _threshold(scenario: Scenario, cells: np.ndarray, xi: float) -> float:
    """The stage's threshold rule applied to one field's float32 cell values."""
    if scenario.oxide.threshold == "theoretical":
        return float(np.float32(oxide_field.theoretical_threshold(xi)))
    return float(oxide_field.empirical_threshold(cells.ravel(), np.array([xi]))[0])


def write(scenario: ResolvedScenario, data_dir: Path, out_dir: Path) -> list[Path]:
    """Draw Fig. 6 to ``<out_dir>/fig6_oxide.png`` and return ``[path]``.

    Parameters
    ----------
    scenario
        Supplies the cell grid, the spectrum, the seed and the threshold rule.
    data_dir
        Unused: the figure re-evaluates the fields from the scenario.
    out_dir
        Where the PNG is written.
    """
    n, h = scenario.n_cells, scenario.cell_size
    centres = cell_centres(n, h)
    half = n * h / 2.0
    display = (np.arange(n * SUPERSAMPLING) + 0.5) * (2.0 * half / (n * SUPERSAMPLING)) - half
    extent = np.array([-half, half, -half, half]) / h
    with context():
        fig, axes = plt.subplots(2, 3, figsize=size(2, 4.9), layout="constrained")
        _draw(scenario, fig, axes, centres, display, extent)
        return [save(fig, Path(out_dir) / "fig6_oxide.png")]


def _draw(scenario: ResolvedScenario, fig: plt.Figure, axes: np.ndarray, centres: np.ndarray, display: np.ndarray,
          extent: np.ndarray) -> None:
    """The fields (upper row) and their oxides with the oxidized cell centres (lower row)."""
    n, h = scenario.n_cells, scenario.cell_size
    for col, (lam, xi) in enumerate(zip(LAMBDAS, FRACTIONS)):
        modes, coeffs = _field(scenario, lam)
        image = oxide_field.field_at_points(modes, coeffs, display[None, :], display[:, None])
        cells = oxide_field.cell_values(modes, coeffs, n).astype(np.float32)
        psi0 = _threshold(scenario, cells, xi)
        top = axes[0, col].imshow(image, origin="lower", extent=extent, cmap="RdBu_r", vmin=-3, vmax=3)
        axes[0, col].set_title(equals("lambda", lam))
        axes[1, col].imshow(image >= psi0, origin="lower", extent=extent, cmap="Greys", vmin=0, vmax=1.6)
        yy, xx = np.nonzero(cells >= psi0)
        axes[1, col].plot(centres[xx] / h, centres[yy] / h, ".", color="tab:red", markersize=0.6)
        axes[1, col].set_title(f"{equals('xi', xi)}, cells covered {np.mean(cells >= psi0):.1%}")
    for ax in axes.flat:
        ax.set_xlabel(LABELS["x_cells"])
        ax.set_ylabel(LABELS["y_cells"])
    fig.colorbar(top, ax=axes[0, :], label=LABELS["field"], shrink=0.8)
    fig.suptitle(
        f"Oxide fields ($H$ = {scenario.oxide.hurst:g}, $k_s/k_1$ = {scenario.oxide.ks_ratio:g}, "
        f"{scenario.oxide.amplitudes} amplitudes); grey: oxide, red dots: oxidized cell centres"
    )
