"""Units and long names of the coordinates the stages share, for datasets whose input lacks them."""

from __future__ import annotations

import xarray as xr

__all__ = ["COORD_LABELS", "label_coords"]


#: Units and long names of the coordinates, used where the input does not carry them.
COORD_LABELS = {
    "xi": ("1", "oxide fraction"),
    "lambda": ("1", "normalized oxide correlation length l_O sqrt(eta)"),
    "delta": ("m", "approach of the sphere tip to the mean plane"),
    "force": ("N", "normal force"),
    "force_normalized": ("1", "normalized force F' = 2F/(E* sqrt(R* sigma^3))"),
    "quantile": ("1", "quantile over realizations"),
}


def label_coords(ds: xr.Dataset) -> None:
    """Give every known coordinate of ``ds`` units and a long name if it lacks them."""
    for name, (units, long_name) in COORD_LABELS.items():
        if name in ds.coords:
            ds[name].attrs.setdefault("units", units)
            ds[name].attrs.setdefault("long_name", long_name)
