"""Any surface inside the atlas: R' from the atlas surrogate over (xi, lambda, mu, Pi, F').

The atlas surrogate (``<data>/atlas/surrogate.json``, :mod:`g2tom.atlas.fit`) gives ln R' at
the query's (xi, lambda, F') and the surface's groups (mu, Pi) (:mod:`g2tom.physics.groups`)
by its curve model (the default, ``resistance``), and alpha and gamma of Eq. 27
(``resistance_power_law`` = alpha 2 rho*/sqrt(R* sigma) F'^-gamma). Its band is where the query is:
one standard deviation of ln R', the surrogate's leave-one-scene-out error in the query's region
of (F', xi, the (mu, Pi) box's inside or edge) and its interpolation error between oxide nodes
(:mod:`g2tom.fitting.atlas_band`), so the 95 % interval of the predicted mean,
``resistance_mean_lower`` / ``_upper`` = R exp(-/+ 1.96 that). A surrogate of format 1 (the first
atlas's one polynomial, e.g. an older shipped file) is still read and answers with its one global
held-out error. The spread over contacts (``resistance_spread_p16`` / ``_p84``) is not in the
atlas: NaN, and the answer says so; the single-scene band's components (realization spread, fit
interval, open-circuit share) are NaN too. A surface whose mu or Pi lies outside the atlas's
domain is refused, naming the inputs that set them; a query outside it (xi, lambda, or F' beyond
the steps fitted in every scene) is NaN and the others answered; unless ``extrapolate`` (then an
ExtrapolationWarning).
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr

from g2tom.atlas.fit import CURVE, FORMAT, FORMAT_VERSION, curve_model
from g2tom.config import ConfigError, Scenario
from g2tom.fitting.atlas_band import RegionalBand
from g2tom.fitting.atlas_surrogate import AtlasModel
from g2tom.predict.domain import group_problems
from g2tom.predict.queries import OUTPUT_COLUMNS, Z95, check_values, outside_ranges, queries, settle_domain
from g2tom.scene import scene_groups

__all__ = ["NOT_IN_ATLAS", "SPREAD_UNKNOWN", "AtlasSurrogate", "is_atlas_document", "load_atlas_surrogate", "predict_atlas", "shipped_path", "SHIPPED"]

#: The atlas surrogate shipped inside the package (``make atlas`` regenerates it), so that
#: ``g2tom predict`` answers other surfaces on a fresh install.
SHIPPED = "atlas_surrogate.json"
_DOMAIN = ("mu", "Pi", "xi", "lambda", "force_normalized")
#: The single-scene band's components the atlas does not hold: NaN in its answers.
NOT_IN_ATLAS = ("spread_lower", "spread_upper", "fit_error", "open_probability")
#: What the atlas's answer says of the spread over contacts (its NaN columns resistance_spread_p16, _p84).
SPREAD_UNKNOWN = ("spread over contacts: not known to the atlas surrogate (it holds the mean R of each scene, not the "
                  "realizations' spread); `g2tom run` on this surface computes it")


def is_atlas_document(text: str) -> bool:
    """Whether a JSON text is an atlas surrogate."""
    try:
        return json.loads(text).get("format") == FORMAT
    except (ValueError, AttributeError):
        return False


@dataclass(frozen=True)
class AtlasSurrogate:
    """The atlas surrogate's models, domain and band.

    Attributes
    ----------
    models
        ``alpha``, ``gamma`` (Eq. 27) and :data:`CURVE` (ln R'): the grid surrogate
        (:class:`~g2tom.fitting.atlas_grid.GridTensorModel`, formats 2-4), the scene series
        (:class:`~g2tom.fitting.atlas_scene_series.SceneSeriesModel`, formats 3 and 4; format 4 names
        the frame of the groups either is built in) or one polynomial in five logs (format 1, the
        first atlas's).
    domain
        (low, high) of mu, Pi, xi, lambda and F'.
    error
        The held-out RMS error of ln R' (the band of format 1; reported beside the regional band).
    source
        Where it was read from.
    band
        The regional band (:class:`~g2tom.fitting.atlas_band.RegionalBand`), None for format 1.
    """

    models: dict[str, Any]
    domain: dict[str, tuple[float, float]]
    error: float
    source: str
    band: RegionalBand | None = None

    @classmethod
    def from_json(cls, text: str, source: str) -> "AtlasSurrogate":
        """Parse ``surrogate.json`` of the atlas; ConfigError if it is not one (or of a later format)."""
        try:
            doc = json.loads(text)
            if doc.get("format") != FORMAT:
                raise ValueError(f"format is {doc.get('format')!r}, not {FORMAT!r}")
            version = int(doc.get("format_version", 1))
            if version > FORMAT_VERSION:
                raise ValueError(f"format_version {version} is newer than this g2tom's {FORMAT_VERSION}: upgrade g2tom")
            models: dict[str, Any] = {p: _polynomial(doc[p]) for p in ("alpha", "gamma")}
            models[CURVE] = curve_model(doc[CURVE]) if version >= 2 else _polynomial(doc[CURVE])
            band = RegionalBand.from_dict(doc["band"]) if version >= 2 else None
            domain = {k: (float(doc["domain"][k][0]), float(doc["domain"][k][1])) for k in _DOMAIN}
            return cls(models, domain, float(doc["heldout"]["rms_ln_error"]), source, band)
        except (ValueError, KeyError, TypeError, AttributeError) as exc:
            raise ConfigError(f"--surrogate {source!r} is not a g2tom atlas surrogate.json ({exc})") from None

    def describe(self) -> str:
        """Which surrogate answers, for the user."""
        mu, pi = self.domain["mu"], self.domain["Pi"]
        band = "regional held-out band" if self.band is not None else f"held-out error {self.error:.3g} in ln R"
        return (f"the atlas surrogate {self.source} (mu {mu[0]:.4g}..{mu[1]:.4g}, Pi {pi[0]:.4g}..{pi[1]:.4g}, "
                f"{band})")

    def log_resistance(self, xi: np.ndarray, lam: np.ndarray, mu: np.ndarray, pi: np.ndarray,
                       force_n: np.ndarray) -> np.ndarray:
        """ln R' of the curve model at the queries."""
        model = self.models[CURVE]
        if isinstance(model, AtlasModel):
            return model.transformed(xi, lam, mu, pi, force_n)
        return model.log_resistance(xi, lam, mu, pi, force_n)

    def error_at(self, xi: np.ndarray, lam: np.ndarray, mu: np.ndarray, pi: np.ndarray,
                 force_n: np.ndarray) -> np.ndarray:
        """One standard deviation of ln R' at each query: the regional band, or format 1's global error."""
        if self.band is None:
            return np.full(np.shape(xi), self.error)
        return self.band(xi, lam, mu, pi, force_n)


def _polynomial(doc: dict[str, Any]) -> AtlasModel:
    return AtlasModel(doc["transform"], np.array(doc["low"], float), np.array(doc["high"], float),
                      np.array(doc["powers"], int), np.array(doc["coef"], float))


def shipped_path() -> Path | None:
    """The package's atlas surrogate, or None when this installation ships none."""
    from importlib import resources

    path = Path(str(resources.files("g2tom").joinpath(SHIPPED)))
    return path if path.is_file() else None


def load_atlas_surrogate(path: str | Path) -> AtlasSurrogate:
    """Load the atlas's ``surrogate.json``; ConfigError if missing or not one."""
    path = Path(path)
    if not path.is_file():
        raise ConfigError(f"--surrogate {str(path)!r} does not exist: run `g2tom atlas` (or `make atlas`) first")
    return AtlasSurrogate.from_json(path.read_text(), str(path))


def predict_atlas(surrogate: AtlasSurrogate, scenario: Scenario, force: Any, xi: Any, lam: Any,
                  extrapolate: bool = False) -> xr.Dataset:
    """R_el from the atlas surrogate, with the 95 % interval of its mean; columns of :data:`g2tom.predict.queries.OUTPUT_COLUMNS`.

    Queries outside the atlas's ranges of xi, lambda or F' are NaN (``outside_domain`` says why)
    and the others answered; the spread over contacts is not in the atlas: NaN, and
    ``attrs["spread"]`` says so.

    Raises
    ------
    ConfigError
        If an input is out of range.
    OutsideDomainError
        Unless ``extrapolate``: if the surface's mu or Pi lies outside the atlas's domain, or
        every query does, naming every group and query variable outside, the inputs that set
        each group and the forces answered (N).
    """

    (f, x, lm), label = queries(force, xi, lam)
    check_values(f, x, lm)
    groups = scene_groups(scenario)
    mu, pi = np.full(f.size, groups.mu), np.full(f.size, groups.Pi)
    force_n = f / scenario.force_scale
    span = "the domain"
    problems, why = outside_ranges(surrogate.domain, {"xi": x, "lambda": lm, "force_normalized": force_n}, span,
                                   scenario.force_scale)
    surface = group_problems(scenario, surrogate.domain, span)
    if surface:
        why = np.full(f.size, "; ".join(text for text, _ in surface))
    answered = settle_domain(surface + problems, why, extrapolate, f" of {surrogate.describe()}")
    alpha = surrogate.models["alpha"](x, lm, mu, pi)
    gamma = surrogate.models["gamma"](x, lm, mu, pi)
    power_law = alpha * scenario.resistance_scale * np.exp(-gamma * np.log(force_n))
    resistance = np.exp(surrogate.log_resistance(x, lm, mu, pi, force_n)) * scenario.resistance_scale
    error = surrogate.error_at(x, lm, mu, pi, force_n)
    unknown = np.full(f.size, np.nan)
    columns = {
        "force": f, "xi": x, "lambda": lm, "force_normalized": force_n, "alpha": alpha, "gamma": gamma,
        "resistance": resistance, "resistance_mean_lower": resistance * np.exp(-Z95 * error),
        "resistance_mean_upper": resistance * np.exp(Z95 * error), "resistance_spread_p16": unknown,
        "resistance_spread_p84": unknown, **{name: unknown for name in NOT_IN_ATLAS}, "surrogate_error": error,
        "resistance_curve": resistance, "resistance_power_law": power_law,
    }
    columns = {name: np.where(answered, values, np.nan) for name, values in columns.items()}
    columns.update(force=f, xi=x, **{"lambda": lm}, force_normalized=force_n, mu=mu, Pi=pi,
                   outside_domain=np.where(answered, "", why))
    ds = xr.Dataset({name: label(values) for name, values in columns.items()})
    for name, (units, long_name) in OUTPUT_COLUMNS.items():
        ds[name].attrs = {"units": units, "long_name": long_name}
    for name in ("resistance_spread_p16", "resistance_spread_p84"):
        ds[name].attrs["comment"] = SPREAD_UNKNOWN
    ds.attrs["band"] = ("resistance_mean_lower, resistance_mean_upper = R exp(-/+ 1.96 e), the 95 % interval of the "
                        "predicted mean R: e the atlas surrogate's cross-validated error of ln R' in the query's region of "
                        "(F', xi, mu-Pi box) and between oxide nodes (g2tom.fitting.atlas_band)"
                        if surrogate.band is not None else
                        "resistance_mean_lower, resistance_mean_upper = R exp(-/+ 1.96 e), the 95 % interval of the "
                        "predicted mean R: e the held-out rms |ln R'_surrogate - ln R'_scene| of the atlas surrogate")
    ds.attrs["spread"] = SPREAD_UNKNOWN
    ds.attrs["surrogate_method"] = "atlas"
    ds.attrs["model"] = "curve"  # ln R' over (xi, lambda, mu, Pi, F'); the power law beside it
    ds.attrs["answered_by"] = surrogate.describe()
    return ds
