"""One style for every figure: paper column widths, fonts, lines, a grey-safe colour cycle, axis labels.

Every figure module draws inside :func:`context`, sizes its figure with :func:`size` and takes
its axis labels from :data:`LABELS`, so a symbol or a unit is written once, in mathtext.
"""

from __future__ import annotations

import contextlib
from collections.abc import Iterator
from pathlib import Path

import matplotlib
import matplotlib.pyplot as plt
import numpy as np
from cycler import cycler
from matplotlib.axis import Axis
from matplotlib.ticker import Formatter, FuncFormatter, LogLocator

from g2tom.store import atomic_path

__all__ = ["ONE_COLUMN", "TWO_COLUMNS", "COLORS", "RC", "LABELS", "context", "equals", "size", "save", "plain_log_ticks", "grey_level"]

#: Widths of one and of two paper columns, in inches.
ONE_COLUMN = 3.4
TWO_COLUMNS = 7.0
#: The colour cycle: viridis samples whose grey levels rise from dark to light, so curves stay
#: apart when printed in grey (black is kept for clean and reference curves).
COLORS: tuple[str, ...] = ("#440154", "#3b528b", "#21918c", "#5ec962", "#bddf26")
#: Matplotlib settings of every figure: 8 pt text read at a column's width, thin lines, 300 dpi.
RC: dict[str, object] = {
    "font.size": 8.0,
    "axes.titlesize": 8.0,
    "axes.labelsize": 8.0,
    "xtick.labelsize": 7.0,
    "ytick.labelsize": 7.0,
    "legend.fontsize": 6.5,
    "legend.frameon": False,
    "figure.titlesize": 8.0,
    "mathtext.fontset": "dejavusans",
    "lines.linewidth": 1.0,
    "lines.markersize": 3.5,
    "axes.linewidth": 0.6,
    "grid.linewidth": 0.4,
    "xtick.major.width": 0.6,
    "ytick.major.width": 0.6,
    "axes.prop_cycle": cycler(color=COLORS),
    "savefig.dpi": 300,
    "savefig.bbox": "tight",
    "savefig.pad_inches": 0.02,
}
#: Axis (and colour-bar) labels of every figure, in mathtext with units.
LABELS: dict[str, str] = {
    "force": r"$F$ (N)",
    "force_normalized": r"$F' = 2F/(E^*\sqrt{R^*\sigma^3})$",
    "force_normalized_s": r"$F' = 2F/(E^*\sqrt{R^*s^3})$",
    "resistance": r"$R$ ($\Omega$)",
    "resistance_normalized": r"$R' = R\sqrt{R^*\sigma}/(2\rho^*)$",
    "conductance_normalized": r"$\kappa' = 1/R' = 2\rho^*/(R\sqrt{R^*\sigma})$",
    "conductance_normalized_s": r"$\kappa' = 2\rho^*\kappa/\sqrt{R^*s}$",
    "conductance_short": r"$\kappa' = 1/R'$",
    "kappa_barber": r"$\kappa/\kappa_\mathrm{Barber}$",
    "xi": r"$\xi$",
    "lambda": r"$\lambda = l_O\sqrt{\eta}$",
    "alpha": r"$\alpha$",
    "gamma": r"$\gamma$",
    "delta_sigma": r"$\delta/\sigma$",
    "radius_normalized": r"$r/\sqrt{R^*\sigma}$",
    "pressure_normalized": r"$p/(E^*\sqrt{\sigma/R^*})$",
    "gap_normalized": r"$h/\sigma$",
    "displacement_normalized": r"$u/\sigma$",
    "area_fraction": r"$A^*$",
    "x": r"$x$ (mm)",
    "y": r"$y$ (mm)",
    "x_cells": r"$x\sqrt{\eta}$",
    "y_cells": r"$y\sqrt{\eta}$",
    "field": r"$\psi$",
    "spot_radius": r"$a_i\sqrt{\eta}$",
    "alpha_ratio": r"$\alpha_\mathrm{point}/\alpha_\mathrm{Greenwood}$",
    "gamma_shift": r"$\gamma_\mathrm{point} - \gamma_\mathrm{Greenwood}$",
    "film": r"$r_f$ ($\Omega\,\mathrm{m}^2$)",
    "resistance_heaviest": r"$\bar{R}$ at the heaviest load ($\Omega$)",
    "realizations": r"realizations used",
    "half_width": r"$\alpha$: 95 % half-width (%)",
    "relative_error": r"relative error (%)",
}


@contextlib.contextmanager
def context() -> Iterator[None]:
    """Draw and save under :data:`RC` (matplotlib's rc_context), the Agg backend selected."""
    matplotlib.use("Agg")
    with matplotlib.rc_context(RC):
        yield


def equals(key: str, value: float, spec: str = "g") -> str:
    """The mathtext label ``key`` of :data:`LABELS` set equal to ``value``, e.g. ``$\\xi = 0.5$``.

    Raises
    ------
    ValueError
        If the label is not a single mathtext expression (it carries a unit or words).
    """
    label = LABELS[key]
    if not (label.startswith("$") and label.endswith("$") and label.count("$") == 2):
        raise ValueError(f"{key!r} is not a single mathtext expression: {label!r}")
    return f"{label[:-1]} = {value:{spec}}$"


def size(columns: int, height: float) -> tuple[float, float]:
    """Figure size (inches) ``columns`` paper columns wide (1 or 2) and ``height`` inches high.

    Raises
    ------
    ValueError
        If ``columns`` is neither 1 nor 2.
    """
    if columns not in (1, 2):
        raise ValueError(f"a figure spans 1 or 2 columns, not {columns}")
    return (ONE_COLUMN if columns == 1 else TWO_COLUMNS, height)


def save(fig: plt.Figure, path: Path) -> Path:
    """Write ``fig`` to ``path`` with the style's resolution and margins, close it, return ``path``.

    Written atomically (:func:`g2tom.store.atomic_path`): a failed write raises
    :class:`~g2tom.errors.WriteError`, the previous figure kept.
    """
    path = Path(path)
    try:
        with atomic_path(path) as tmp:
            fig.savefig(tmp, format=path.suffix.lstrip(".") or None)
    finally:
        plt.close(fig)
    return path


class _MinorLogLabels(Formatter):
    """Plain labels of a log axis' minor ticks, only where the view spans less than a decade.

    There, the ticks at mantissas 2, 3 and 5 are labelled; every minor tick is when that leaves
    fewer than two labels in view (with the decades), or when matplotlib has fallen back to
    linear minor ticks (1.2, 1.4, ...). Nothing is labelled on a longer view.
    """

    labelled: tuple[float, ...] = ()

    def set_locs(self, locs) -> None:
        """Choose the labelled ticks among ``locs`` for the current view."""
        super().set_locs(locs)
        low, high = sorted(self.axis.get_view_interval())
        if low <= 0 or high / low >= 10.0:
            self.labelled = ()
            return
        shown = np.asarray([v for v in locs if low <= v <= high], float)
        mantissa = np.round(shown / 10.0 ** np.floor(np.log10(shown) + 1e-9), 6)
        decades = np.floor(np.log10(high) + 1e-9) - np.ceil(np.log10(low) - 1e-9) + 1
        chosen = shown[np.isin(mantissa, (2.0, 3.0, 5.0))]
        linear = np.any(mantissa != np.round(mantissa))
        self.labelled = tuple(shown if linear or chosen.size + decades < 2 else chosen)

    def __call__(self, x: float, pos: int | None = None) -> str:
        return f"{x:g}" if np.any(np.isclose(x, self.labelled, rtol=1e-9, atol=0.0)) else ""


def plain_log_ticks(axis: Axis, subs: tuple[float, ...] = (1.0,)) -> None:
    """Plain numbers (0.5, 20) on a log ``axis``: major ticks at ``subs`` x 10^k, minor labels
    only where the view spans less than a decade (:class:`_MinorLogLabels`).

    Matplotlib otherwise labels the minor ticks of a short log axis in scientific notation
    (``4 x 10^-1``, ``6 x 10^-1``), and at a paper's column width those labels run into each other.
    """
    axis.set_major_locator(LogLocator(subs=subs))
    axis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
    axis.set_minor_formatter(_MinorLogLabels())


def grey_level(color: str) -> float:
    """Luminance (0 black, 1 white) of ``color`` printed in grey (ITU-R BT.709 weights)."""
    r, g, b = matplotlib.colors.to_rgb(color)
    return 0.2126 * r + 0.7152 * g + 0.0722 * b
