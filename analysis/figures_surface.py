"""The measured surface's figure: R against F with its band over contacts, and one contact's map.

Draws ``surface.png`` from a ``g2tom surface`` dataset (surface.nc): on the left the clean
resistance (and each oxide case's) against the force, the typical value (geometric mean over the
contacts) as a line and the band (the quantiles over positions and fields) shaded, every
position's clean curve thin; on the right the first position's window at the middle force, its
heights in grey, conducting contact in black and oxidized contact in red.
"""

from __future__ import annotations

from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
import xarray as xr
from matplotlib.colors import ListedColormap

from g2tom.analysis.style import context, plain_log_ticks, save, size

__all__ = ["figure"]


def _cases(ds: xr.Dataset) -> list[tuple[str, xr.DataArray, xr.DataArray, xr.DataArray]]:
    """(label, typical, lower, upper) per case: clean, then each xi and correlation length."""
    out = [("clean", ds["resistance_clean_typical"], ds["resistance_clean_lower"], ds["resistance_clean_upper"])]
    if "resistance_typical" in ds:
        for xi in ds["xi"].values:
            for length in ds["correlation_length"].values:
                sel = {"xi": xi, "correlation_length": length}
                out.append((rf"$\xi$ = {xi:g}, $l_O$ = {length * 1e6:.3g} µm", ds["resistance_typical"].sel(sel),
                            ds["resistance_lower"].sel(sel), ds["resistance_upper"].sel(sel)))
    return out


def figure(ds: xr.Dataset, path: Path) -> Path:
    """Draw the surface dataset ``ds`` to ``path`` (PNG) and return ``path``."""
    force = ds["force"].values
    low, high = (float(q) for q in ds.attrs["band_quantiles"])
    with context():
        fig, (left, right) = plt.subplots(1, 2, figsize=size(2, 3.0), layout="constrained",
                                          gridspec_kw={"width_ratios": [1.4, 1.0]})
        for p in range(ds.sizes["position"]):
            left.loglog(force, ds["resistance_clean"].values[p], "-", color="0.75", lw=0.6,
                        label="clean, each position" if p == 0 else None)
        for colour, (label, typical, lower, upper) in enumerate(_cases(ds)):
            left.fill_between(force, lower.values, upper.values, color=f"C{colour}", alpha=0.2, lw=0)
            left.loglog(force, typical.values, "-o", color=f"C{colour}", ms=3,
                        label=f"{label} (band {low:g}-{high:g} %)")
        left.set(xlabel="force F (N)", ylabel=r"resistance R ($\Omega$)",
                 title=f"{ds.sizes['position']} position(s) of {ds.attrs['window_side'] * 1e6:.3g} µm")
        plain_log_ticks(left.xaxis)
        left.grid(True, which="major", alpha=0.3)
        left.legend(fontsize="small")
        extent = np.array([ds["x"].values[[0, -1]], ds["y"].values[[0, -1]]]).ravel() * 1e6
        right.imshow(ds["height"].values * 1e6, cmap="Greys_r", origin="lower", extent=extent)
        state = np.ma.masked_equal(ds["contact_state"].values, 0)
        right.imshow(state, cmap=ListedColormap(["black", "red"]), vmin=1, vmax=2, origin="lower", extent=extent,
                     interpolation="nearest")
        middle = force[len(force) // 2]
        right.set(xlabel="x (µm)", ylabel="y (µm)", title=f"position 0 at {middle:.3g} N: contact (black), oxide (red)")
        return save(fig, path)
