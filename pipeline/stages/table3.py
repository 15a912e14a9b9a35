"""The paper's Table 3 from ``surrogate.nc``: per (xi, lambda) the fitted alpha and gamma, the
surrogate's values and their relative errors, as rows, CSV and Markdown."""

from __future__ import annotations

import xarray as xr

__all__ = ["PARAMETERS", "table3_rows", "table3_csv", "table3_markdown"]

#: The power law's parameters, in the table's order.
PARAMETERS = ("alpha", "gamma")


def table3_rows(ds: xr.Dataset) -> list[dict[str, float]]:
    """One row per (xi, lambda): fitted value, surrogate value and relative error (%)."""
    rows = []
    for xi in ds["xi"].values:
        for lam in ds["lambda"].values:
            row: dict[str, float] = {"xi": float(xi), "lambda": float(lam)}
            for p in PARAMETERS:
                cell = {"lambda": lam, "xi": xi}
                row[f"{p}_fit"] = float(ds[f"{p}_fit"].sel(cell))
                row[f"{p}_surrogate"] = float(ds[f"{p}_surrogate"].sel(cell))
                row[f"{p}_error_percent"] = 100.0 * float(ds[f"{p}_relative_error"].sel(cell))
            rows.append(row)
    return rows


def table3_csv(ds: xr.Dataset) -> str:
    """Table 3 as CSV text (header line first)."""
    rows = table3_rows(ds)
    lines = [",".join(rows[0])]
    lines += [",".join(f"{v:.6g}" for v in row.values()) for row in rows]
    return "\n".join(lines) + "\n"


def table3_markdown(ds: xr.Dataset) -> str:
    """Table 3 as a Markdown table."""
    header = ["xi", "lambda", "alpha fit", "alpha surrogate", "err %", "gamma fit", "gamma surrogate", "err %"]
    lines = ["| " + " | ".join(header) + " |", "|" + "---:|" * len(header)]
    for row in table3_rows(ds):
        cells = [f"{row['xi']:g}", f"{row['lambda']:g}"]
        for p in PARAMETERS:
            cells += [f"{row[f'{p}_fit']:.4f}", f"{row[f'{p}_surrogate']:.4f}", f"{row[f'{p}_error_percent']:+.2f}"]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"
