"""The validation's figure: R' against F' per case, the full-field reference and g2tom's curves.

Draws ``validate.png`` from ``<data_dir>/validate/validate.nc`` (``g2tom validate``) in the
shared style: one panel per case (clean, then each xi and lambda), one colour per spot
discretization and one line style per resistance model (part 1, per realization), and where the
dataset has part 2, the full field's ensemble geometric mean with its standard error and the
validated scenario's; the legend below the panels. Writes nothing when the validation has not run.
"""

from __future__ import annotations

from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
import xarray as xr

from g2tom.analysis.style import LABELS, context, equals, plain_log_ticks, save, size
from g2tom.config import Scenario
from g2tom.reference.summary import ratios

__all__ = ["FOLDER", "figure", "write"]

#: The validation's folder under the data directory.
FOLDER = "validate"
#: Line style of each resistance model.
MODEL_STYLES = {"greenwood": "-", "point": "--"}
#: Height of one row of panels, in inches.
ROW_HEIGHT = 2.2


def _panels(ds: xr.Dataset) -> list[tuple[str, xr.DataArray, xr.DataArray, dict]]:
    """(title, reference R (realization, load), g2tom R (discretization, model, realization?, load),
    the selection of part 2's variables) per case."""
    out = [("clean", ds["resistance_reference_clean"], ds["resistance_g2tom_clean"], {})]
    for xi in ds["xi"].values:
        for lam in ds["lambda"].values:
            sel = {"xi": xi, "lambda": lam}
            out.append((f"{equals('xi', xi)}, {equals('lambda', lam)}", ds["resistance_reference"].sel(sel),
                        ds["resistance_g2tom"].sel(sel), sel))
    return out


def _ensembles(ax: plt.Axes, ds: xr.Dataset, sel: dict, f: np.ndarray, scale: float) -> None:
    """Part 2 on one panel: the full field's ensemble geometric mean (error bars: its standard error)
    and the validated scenario's."""
    suffix = "" if sel else "_clean"
    if f"ensemble_reference{suffix}" not in ds:
        return
    ref = ds[f"ensemble_reference{suffix}"].sel(sel).values / scale
    err = ds[f"ensemble_reference{suffix}_standard_error"].sel(sel).values
    ax.errorbar(f, ref, yerr=(ref * (1 - np.exp(-err)), ref * (np.exp(err) - 1)), fmt="s", mfc="none", color="k",
                ms=5, capsize=2, label="full field, ensemble (part 2)")
    ax.loglog(f, ds[f"ensemble_model{suffix}"].sel(sel).values / scale, "-", color="0.35", lw=2.5, alpha=0.6,
              label=f"{ds.attrs.get('validated_scenario', 'the default')}, ensemble (part 2)")


def figure(ds: xr.Dataset, path: Path) -> Path:
    """Draw the validation dataset ``ds`` (the variables of validate.nc) to ``path``.

    Parameters
    ----------
    ds
        ``force_normalized`` (load), the reference ``resistance_reference_clean`` (realization,
        load) and ``resistance_reference`` (xi, lambda, realization, load), g2tom's
        ``resistance_g2tom_clean`` and ``resistance_g2tom`` (discretization, model, [xi, lambda,]
        realization, load) in ohm, and the attribute ``resistance_scale`` (ohm) that makes R' of R.
    path
        The PNG written.

    Returns
    -------
    Path
        ``path``.
    """
    panels = _panels(ds)
    cols = min(3, len(panels))
    rows = -(-len(panels) // cols)
    f = ds["force_normalized"].values
    scale = ds.attrs["resistance_scale"]
    with context():
        fig, axes = plt.subplots(rows, cols, figsize=size(2, ROW_HEIGHT * rows + 0.6), squeeze=False,
                                 layout="constrained")
        for ax, (title, ref, g2, sel) in zip(axes.ravel(), panels):
            ax.loglog(np.broadcast_to(f, ref.shape).ravel(), ref.values.ravel() / scale, "ko", ms=3,
                      label="full field (each realization)")
            for colour, d in enumerate(ds["discretization"].values):
                for m in ds["model"].values:
                    curve = g2.sel(discretization=d, model=m)
                    if not np.isfinite(curve.values).any():  # a combination g2tom refuses
                        continue
                    if "realization" in curve.dims:  # geometric mean over conducting realizations
                        curve = ratios(curve.transpose("realization", "load").values)[0]
                    ax.loglog(f, np.asarray(curve) / scale, MODEL_STYLES.get(str(m), ":"), color=f"C{colour}",
                              marker=".", label=f"g2tom: {str(d).replace('_', ' ')}, {m}")
            _ensembles(ax, ds, sel, f, scale)
            ax.set(title=title, xlabel=LABELS["force_normalized"])
            if np.ptp(f) == 0:  # one load step (--steps): a factor of 2 either side, not an empty axis
                ax.set_xlim(f[0] / 2.0, f[0] * 2.0)
            plain_log_ticks(ax.xaxis)
            plain_log_ticks(ax.yaxis)
            ax.grid(True, which="major", alpha=0.3)
        for ax in axes[:, 0]:
            ax.set_ylabel(LABELS["resistance_normalized"])
        for ax in axes.ravel()[len(panels):]:
            ax.axis("off")
        fig.legend(*axes[0, 0].get_legend_handles_labels(), loc="outside lower center", ncols=2)
        return save(fig, path)


def write(scenario: Scenario, data_dir: Path, out_dir: Path) -> list[Path]:
    """``validate.png`` under ``out_dir`` from ``<data_dir>/validate/validate.nc``, or nothing without it."""
    source = Path(data_dir) / FOLDER / "validate.nc"
    if not source.is_file():
        return []
    with xr.open_dataset(source, engine="netcdf4") as ds:
        return [figure(ds.load(), Path(out_dir) / "validate.png")]
