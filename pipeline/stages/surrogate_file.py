"""The fitted surrogate as the predictor reads it: :class:`SurrogateTables`, ``surrogate.json``.

Everything :func:`g2tom.predict.predict` needs, as plain numpy arrays: the coefficients of
alpha(xi, lambda) and gamma(xi, lambda), each cell's curve model, the fitted ranges and the band's
tables, read from ``surrogate.nc`` or written to and read from ``surrogate.json`` (NaN as null,
infinities as "inf"; floats round-trip exactly), so that a prediction needs no netCDF. The
surrogate stage (:mod:`g2tom.stages.surrogate`) writes the file, the predictor
(:mod:`g2tom.predict`) reads it.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr
from scipy.interpolate import RegularGridInterpolator

from g2tom import __version__
from g2tom.config import ConfigError, read_input_text
from g2tom.fitting.curve_model import evaluate_curve
from g2tom.fitting.surrogate import evaluate, to_w, to_z

__all__ = ["FORMAT", "VERSION", "PARAMETERS", "GRID_TABLES", "STEP_TABLES", "CURVE_TABLE", "RANGES",
           "SurrogateTables", "load_surrogate"]

FORMAT = "g2tom-surrogate"
VERSION = 1
PARAMETERS = ("alpha", "gamma")
#: Per-cell (lambda, xi) tables and per-step (lambda, xi, step) tables the band needs.
GRID_TABLES = ("alpha_fit_sigma", "gamma_fit_sigma", "alpha_cv_error", "gamma_cv_error", "curve_interpolation_error")
STEP_TABLES = ("band_ratio_lower", "band_ratio_upper", "open_probability", "curve_fit_error")
#: The curve model's coefficients, (lambda, xi, power).
CURVE_TABLE = "curve_coefficients"
RANGES = ("xi", "lambda", "force_normalized")


@dataclass(frozen=True)
class SurrogateTables:
    """Everything the predictor needs, as plain numpy arrays.

    Attributes
    ----------
    coef
        Parameter name -> (coef_w (rank, p), coef_z (rank, q), transform).
    lam, xi
        The fitted grid (dimensionless).
    force_normalized
        F' of the fitted load steps (dimensionless).
    ranges
        ``xi``, ``lambda``, ``force_normalized`` -> (min, max) fitted.
    tables
        :data:`GRID_TABLES` (lambda, xi) and :data:`STEP_TABLES` (lambda, xi, step), dimensionless.
    info
        Provenance and model description (method, formulas, free parameters, CV errors).
    """

    coef: dict[str, tuple[np.ndarray, np.ndarray, str]]
    lam: np.ndarray
    xi: np.ndarray
    force_normalized: np.ndarray
    ranges: dict[str, tuple[float, float]]
    tables: dict[str, np.ndarray]
    info: dict[str, Any]

    # ------------------------------------------------------------------ construction
    @classmethod
    def from_dataset(cls, ds: xr.Dataset, source: str = "the surrogate dataset") -> "SurrogateTables":
        """From ``surrogate.nc`` (or the surrogate stage's dataset); ``source`` names it in errors."""
        missing = [n for n in (*(f"{p}_coef_w" for p in PARAMETERS), *GRID_TABLES, *STEP_TABLES, CURVE_TABLE) if n not in ds]
        if missing:
            title = str(ds.attrs.get("title", ""))
            if title.startswith("g2tom ") and "surrogate" not in title:
                raise ConfigError(f"{source} is the output of the {title.removeprefix('g2tom ')}, not a surrogate: "
                                  "give surrogate.json or surrogate.nc (written by `g2tom surrogate`)")
            raise ConfigError(f"{source} lacks {', '.join(missing)}: re-run `g2tom surrogate`")
        coef = {p: (ds[f"{p}_coef_w"].values, ds[f"{p}_coef_z"].values, str(ds[f"{p}_coef_w"].attrs.get("transform", "identity")))
                for p in PARAMETERS}
        tables = {n: ds[n].transpose("lambda", "xi").values for n in GRID_TABLES}
        tables.update({n: ds[n].transpose("lambda", "xi", "step").values for n in STEP_TABLES})
        tables[CURVE_TABLE] = ds[CURVE_TABLE].transpose("lambda", "xi", "power").values
        info = {k: _plain(ds.attrs[k]) for k in _INFO_KEYS if k in ds.attrs}
        return cls(
            coef=coef,
            lam=ds["lambda"].values,
            xi=ds["xi"].values,
            force_normalized=ds["force_normalized"].values,
            ranges={r: (float(ds[f"{r}_range"][0]), float(ds[f"{r}_range"][1])) for r in RANGES},
            tables=tables,
            info=info,
        )

    def to_json(self) -> str:
        """The ``surrogate.json`` text (NaN written as null, infinities as "inf"; floats round-trip exactly)."""
        doc = {
            "format": FORMAT,
            "version": VERSION,
            "model": {
                "predictor": "curve (default): R_el = 2 rho* / sqrt(R* sigma) * exp(sum_k c_k (ln F')^k), c_k = "
                             "tables.curve_coefficients[lambda][xi][k] interpolated linearly in (w, z); "
                             "power_law: R_el = alpha * 2 rho* / sqrt(R* sigma) * F'^(-gamma)  (Eq. 27)",
                "surrogate": "T(p) = sum_k P_k(w) Q_k(z), P_k(w) = sum_i coef_w[k][i] w^i, "
                             "Q_k(z) = sum_j coef_z[k][j] z^j; T = log (p = exp(...)) or identity",
                "coordinates": {"w": "ln(lambda), lambda = l_O sqrt(eta)", "z": "-ln(1 - xi)"},
                "scales": {
                    "F'": "2 F / (E* sqrt(R* sigma^3)), F in N",
                    "R'": "R_el sqrt(R* sigma) / (2 rho*), R_el in ohm",
                    "E*": "E / (2 (1 - nu^2)), Pa",
                },
                "band": "two bands in ohm, from ln-R half-widths (one standard deviation each): the 95 % interval "
                        "of the predicted mean, R exp(-/+ 1.96 sqrt(fit_error^2 + surrogate_error^2)) "
                        "(resistance_mean_lower, resistance_mean_upper), and the spread over contacts, 16-84 % of R "
                        "over realizations, R exp(-spread_lower), R exp(spread_upper) (resistance_spread_p16, "
                        "resistance_spread_p84); see g2tom.predict",
            },
            "parameters": {
                p: {"transform": t, "coef_w": cw.tolist(), "coef_z": cz.tolist()} for p, (cw, cz, t) in self.coef.items()
            },
            "ranges": {k: list(v) for k, v in self.ranges.items()},
            "grid": {"lambda": self.lam.tolist(), "xi": self.xi.tolist(), "force_normalized": self.force_normalized.tolist()},
            "tables": {k: _encode(v) for k, v in self.tables.items()},
            "info": self.info,
        }
        return json.dumps(doc, indent=1, allow_nan=False) + "\n"

    @classmethod
    def from_json(cls, text: str, source: str = "surrogate.json") -> "SurrogateTables":
        """Parse :meth:`to_json` output; ConfigError if it is not a surrogate file."""
        try:
            doc = json.loads(text)
            if doc.get("format") != FORMAT:
                raise ValueError(f"format is {doc.get('format')!r}, not {FORMAT!r}")
            _check_version(doc.get("version"), source)
            coef = {p: (np.array(doc["parameters"][p]["coef_w"], dtype=float), np.array(doc["parameters"][p]["coef_z"], dtype=float),
                        str(doc["parameters"][p]["transform"])) for p in PARAMETERS}
            tables = {k: np.array(_decode(doc["tables"][k]), dtype=float) for k in (*GRID_TABLES, *STEP_TABLES, CURVE_TABLE)}
            grid = doc["grid"]
            return cls(
                coef=coef,
                lam=np.array(grid["lambda"], dtype=float),
                xi=np.array(grid["xi"], dtype=float),
                force_normalized=np.array(grid["force_normalized"], dtype=float),
                ranges={k: (float(doc["ranges"][k][0]), float(doc["ranges"][k][1])) for k in RANGES},
                tables=tables,
                info=doc.get("info", {}),
            )
        except ConfigError:
            raise
        except (ValueError, KeyError, TypeError, AttributeError) as exc:
            raise ConfigError(f"--surrogate {source!r} is not a g2tom surrogate.json ({exc})") from None

    # ------------------------------------------------------------------ evaluation
    def parameter(self, name: str, lam: np.ndarray, xi: np.ndarray) -> np.ndarray:
        """Surrogate alpha or gamma at (lambda, xi)."""
        coef_w, coef_z, transform = self.coef[name]
        return evaluate(coef_w, coef_z, lam, xi, transform)

    def curve(self, lam: np.ndarray, xi: np.ndarray, force_n: np.ndarray) -> np.ndarray:
        """ln R' of the curve model: each cell's coefficients interpolated linearly in (w, z),
        clamped to the grid (exact at the grid's cells), evaluated at ``force_n``."""
        coef = self.interpolate((CURVE_TABLE,), lam, xi)[..., 0]  # (n, power)
        return evaluate_curve(coef, force_n[:, None])[:, 0]

    def interpolate(self, names: tuple[str, ...], lam: np.ndarray, xi: np.ndarray, force_n: np.ndarray | None = None) -> np.ndarray:
        """Tables linearly interpolated in (w, z[, ln F']), clamped to the grid; shape (n, len(names))
        (tables with trailing axes beyond (lambda, xi[, step]) keep them after the query axis)."""
        axes = [to_w(self.lam), to_z(self.xi)]
        points = [to_w(lam), to_z(xi)]
        if force_n is not None:
            axes.append(np.log(self.force_normalized))
            points.append(np.log(force_n))
        values = np.stack([self.tables[n] for n in names], axis=-1)
        keep = [a.size > 1 for a in axes]
        values = values[tuple(slice(None) if k else 0 for k in keep)]
        points = [np.clip(p, a.min(), a.max()) for p, a, k in zip(points, axes, keep) if k]
        axes = [a for a, k in zip(axes, keep) if k]
        if not axes:  # a single cell and no load axis: its values, whatever the query
            return np.broadcast_to(values, (lam.size, *values.shape)).copy()
        return RegularGridInterpolator(tuple(axes), values)(np.stack(points, axis=-1))


_INFO_KEYS = (
    "scenario", "config_hash", "method", "trivial", "reduction", "fit_confidence", "mu", "Pi", "indenter_shape",
    "hardness",
    *(f"{p}_{k}" for p in PARAMETERS for k in ("transform", "rank", "order_w", "order_z", "free_parameters", "cv_rms", "formula")),
)


def _plain(value: Any) -> Any:
    """A netCDF attribute as a JSON-ready Python value."""
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def _encode(a: np.ndarray) -> list:
    """Nested lists for JSON: NaN as null, +-inf as the strings "inf" / "-inf"."""
    out = a.astype(object)
    out[np.isnan(a)] = None
    out[np.isposinf(a)] = "inf"
    out[np.isneginf(a)] = "-inf"
    return out.tolist()


def _decode(values: Any) -> Any:
    """Inverse of :func:`_encode`."""
    if isinstance(values, list):
        return [_decode(v) for v in values]
    if values is None:
        return math.nan
    return float(values) if isinstance(values, str) and values in ("inf", "-inf") else values


def _check_version(version: Any, source: str) -> None:
    """Refuse a surrogate.json of a format version this g2tom does not read (a newer g2tom's)."""
    if isinstance(version, bool) or not isinstance(version, int) or not 1 <= version <= VERSION:
        raise ConfigError(f"--surrogate {source!r} has format version {version!r}: this g2tom ({__version__}) reads "
                          f"version 1..{VERSION}; update g2tom, or rewrite the file with this one (`g2tom surrogate`)")


def load_surrogate(path: str | Path) -> SurrogateTables:
    """Load ``surrogate.json`` (no netCDF needed) or ``surrogate.nc``.

    Raises
    ------
    ConfigError
        If the file is missing, unreadable, not a surrogate file (naming it), or of a newer
        format version.
    """
    path = Path(path)
    if not path.is_file():
        raise ConfigError(f"--surrogate {str(path)!r} does not exist: run `g2tom surrogate` (or `make surrogate`) first")
    if path.suffix == ".json":
        return SurrogateTables.from_json(read_input_text("--surrogate", path), str(path))
    try:
        with xr.open_dataset(path, engine="netcdf4") as ds:
            ds = ds.load()
    except (OSError, ValueError) as exc:
        raise ConfigError(f"--surrogate {str(path)!r} is not a readable netCDF file ({exc})") from None
    return SurrogateTables.from_dataset(ds, f"--surrogate {str(path)!r}")
