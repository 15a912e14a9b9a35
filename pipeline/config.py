"""Scenarios: the parameter set of a run, loaded from TOML, overridden and validated.

A scenario is a nested, frozen set of dataclasses, one per section (``material``,
``roughness``, ...). Every field declares its unit, meaning and allowed range in its
metadata, so validation, documentation and provenance all come from one place. All values
are SI unless a field's unit says otherwise (``loading.delta_max`` is in units of sigma).

Bundled scenarios (``paper``, ``published``) live in :mod:`pipeline.scenarios` and are
chosen by name; any other value of ``--config`` is read as a TOML file path.
"""

from __future__ import annotations

import dataclasses
import difflib
import hashlib
import json
import math
import tomllib
import warnings
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import Any, Iterable, Mapping

__all__ = [
    "AUTO",
    "ConfigError",
    "read_input_text",
    "check_domains",
    "Scenario",
    "load_scenario",
    "bundled_scenarios",
    "parameter_table",
    "STAGE_INPUTS",
]


#: The value of ``contact.r_max`` and ``contact.window`` resolved from the solution
#: (:func:`pipeline.before_work.domains.resolve`) before any stage runs.
AUTO = "auto"


class ConfigError(ValueError):
    """A parameter is unknown, malformed or outside its allowed range."""


def read_input_text(option: str, path: str | Path, encoding: str = "utf-8") -> str:
    """The text of an input file given by ``option``, or one ConfigError line naming both.

    Parameters
    ----------
    option
        How the user named the file (``--csv``, ``--surrogate``), for the message.
    path
        The file.
    encoding
        Its text encoding (``utf-8-sig`` also accepts a leading byte-order mark).

    Raises
    ------
    ConfigError
        If ``path`` is a directory, does not exist, cannot be read (permissions) or is not
        text in ``encoding``.
    """
    path = Path(path)
    where = f"{option} {str(path)!r}"
    if path.is_dir():
        raise ConfigError(f"{where} is a directory: give a file")
    if not path.exists():
        raise ConfigError(f"{where} does not exist")
    try:
        return path.read_text(encoding=encoding)
    except UnicodeDecodeError as exc:
        raise ConfigError(f"{where} is not UTF-8 text (byte {exc.start}: {exc.object[exc.start:exc.start + 1]!r})") from None
    except OSError as exc:
        raise ConfigError(f"{where} is unreadable ({exc.strerror or exc}): check its permissions") from None


def _spec(
    unit: str,
    doc: str,
    *,
    gt: float | None = None,
    ge: float | None = None,
    lt: float | None = None,
    le: float | None = None,
    choices: tuple[str, ...] | None = None,
    key: str | None = None,
    each: bool = False,
    auto: bool = False,
) -> dict[str, Any]:
    """Field metadata: unit, description and allowed range (``each`` applies it per element;
    ``auto`` also accepts the word ``"auto"``, resolved from the solution before any stage runs)."""
    return {
        "auto": auto,
        "unit": unit,
        "doc": doc,
        "gt": gt,
        "ge": ge,
        "lt": lt,
        "le": le,
        "choices": choices,
        "key": key,
        "each": each,
    }


def _param(default: Any, unit: str, doc: str, **limits: Any) -> Any:
    if isinstance(default, list):
        return field(default_factory=lambda: list(default), metadata=_spec(unit, doc, **limits))
    return field(default=default, metadata=_spec(unit, doc, **limits))


@dataclass(frozen=True)
class Material:
    """Effective elastic and electrical properties of the contacting pair (Table 1)."""

    E: float = _param(2.1e11, "Pa", "Young's modulus of both bodies", gt=0)
    nu: float = _param(0.3, "1", "Poisson's ratio of both bodies", gt=-1, lt=0.5)
    rho: float = _param(7.2e-7, "ohm m", "effective resistivity rho* = (rho1 + rho2)/2", gt=0)

    @property
    def E_star(self) -> float:
        """Effective modulus E* = E / (2 (1 - nu^2)) of two equal bodies, in Pa."""
        return self.E / (2.0 * (1.0 - self.nu**2))


@dataclass(frozen=True)
class Roughness:
    """Greenwood–Williamson asperity statistics (Table 1)."""

    sigma: float = _param(20e-6, "m", "standard deviation of asperity heights", gt=0)
    eta: float = _param(2e8, "m-2", "asperity density (asperities per unit area)", gt=0)
    beta: float = _param(30e-6, "m", "mean asperity tip radius", gt=0)


@dataclass(frozen=True)
class Indenter:
    """Axisymmetric indenter profile."""

    shape: str = _param(
        "sphere", "1", "indenter profile", choices=("sphere", "cone", "flat_punch")
    )
    radius: float = _param(10e-3, "m", "effective radius R* of the sphere", gt=0)
    cone_angle: float = _param(
        0.01, "rad", "cone: angle between the flank and the flat (profile r tan angle)", gt=0, lt=math.pi / 2
    )
    punch_radius: float = _param(1e-3, "m", "flat punch: radius of the flat face", gt=0)
    edge_radius: float = _param(10e-3, "m", "flat punch: radius of the rounded edge", gt=0)


@dataclass(frozen=True)
class Loading:
    """Approaches delta: evenly spaced from ``delta_max`` down to ``delta_min`` (units of sigma)."""

    delta_max: float = _param(2.0, "sigma", "first (lightest) approach delta/sigma")
    delta_min: float = _param(-3.0, "sigma", "last (heaviest) approach delta/sigma")
    n_delta: int = _param(20, "1", "number of approaches", ge=1)


@dataclass(frozen=True)
class Contact:
    """Numerical settings of the Greenwood–Tripp solve and of the discretisation into spots."""

    solver: str = _param(
        "newton", "1", "Greenwood–Tripp solver", choices=("newton", "fixed_point")
    )
    n_radial: int = _param(720, "1", "number of radial nodes", ge=8)
    r_max: float | str = _param(
        "auto", "R*", "outer radius of the radial domain, in units of R*, or auto: until the "
        "pressure is negligible and beyond the spot window's corners", gt=0, auto=True,
    )
    radial_grid: str = _param(
        "graded",
        "1",
        "radial nodes: uniform, or uniform where asperities can touch (rigid gap < 4 sigma at "
        "the heaviest approach) and 4 times coarser beyond",
        choices=("uniform", "graded"),
    )
    tolerance: float = _param(1e-10, "1", "Newton: relative residual to reach", gt=0, lt=1)
    max_iterations: int = _param(200, "1", "iteration limit of either solver", ge=1)
    relaxation: float = _param(0.3, "1", "fixed point: relaxation zeta", gt=0, le=1)
    fixed_point_tolerance: float = _param(
        1e-3, "1", "fixed point: relative displacement change epsilon", gt=0, lt=1
    )
    area_interpolation: str = _param(
        "separation",
        "1",
        "how A* reaches the cell centres: interpolate the separation and evaluate A* there, "
        "or interpolate A* linearly (the published study)",
        choices=("separation", "area_fraction"),
    )
    window: float | str = _param(
        "auto", "R*", "side of the square spot window, in units of R*, or auto: every cell whose "
        "spot can change R by more than cube.crop_tolerance at the heaviest load", gt=0, auto=True,
    )
    spots: str = _param(
        "expected",
        "1",
        "one spot per cell: expected (radius sqrt(beta) F_1/2(h), the expected sum of asperity "
        "radii; obeys Barber's theorem), mean_area (the paper's radius sqrt(A* dx^2 / pi)) or "
        "asperities (one Gaussian asperity per cell, drawn per realization)",
        choices=("mean_area", "expected", "asperities"),
    )
    model: str = _param(
        "greenwood_tripp",
        "1",
        "contact model: greenwood_tripp (the asperities' mean, Sect. 2.5, discretized by contact.spots) "
        "or discrete (each surface's own Poisson asperities, Hertzian caps coupled through the "
        "half-space, solved at the Greenwood-Tripp forces of the approaches; design note 11)",
        choices=("greenwood_tripp", "discrete"),
    )
    surfaces: int = _param(
        256, "1", "discrete: rough surfaces solved (the pool); oxide realization k meets surface "
        "k mod surfaces", ge=1,
    )


@dataclass(frozen=True)
class Oxide:
    """Thresholded Gaussian random fields (Sect. 2.6, Table 2)."""

    xi: list[float] = _param(
        [0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9], "1", "oxide fractions", gt=0, lt=1, each=True
    )
    lambda_: list[float] = _param(
        [1.0, 3.0, 5.0, 7.0, 9.0, 11.0, 13.0, 15.0, 17.0, 19.0, 21.0, 23.0],
        "1",
        "normalized correlation lengths l_O sqrt(eta)",
        gt=0,
        each=True,
        key="lambda",
    )
    n_realizations: int = _param(
        500, "1", "fixed ensemble: random fields per correlation length (adaptive: fields recorded in oxide.nc)", ge=2
    )
    ensemble: str = _param(
        "adaptive",
        "1",
        "realizations: a fixed count per lambda (n_realizations), or per (xi, lambda) batches until "
        "alpha's 95 % half-width reaches target_half_width or the cap max_realizations",
        choices=("fixed", "adaptive"),
    )
    min_realizations: int = _param(
        400, "1", "adaptive: first batch, the fewest realizations any (xi, lambda) uses", ge=2
    )
    batch: int = _param(
        1000, "1", "adaptive: realizations added per round to a cell still short of the target "
        "(compute granularity only: results do not depend on it)", ge=1
    )
    max_realizations: int = _param(30000, "1", "adaptive: cap on the realizations per (xi, lambda)", ge=2)
    target_half_width: float = _param(
        0.025, "1", "adaptive: target relative 95 % half-width of alpha in every cell", gt=0, lt=1
    )
    period: str = _param(
        "spectral",
        "1",
        "period of the random field: the spot window (the published lattice), or a period of "
        "P >= n_cells cells with k1 = P / (2 lambda) >= spectral_resolution lattice steps",
        choices=("window", "spectral"),
    )
    spectral_resolution: float = _param(
        16.0, "1", "period = spectral: k1 in lattice steps 2 pi / P (annulus ~ 4 pi res^2 modes)", gt=0
    )
    seed: int = _param(20240531, "1", "root seed of every random stream", ge=0)
    hurst: float = _param(0.5, "1", "Hurst exponent H of the spectrum k^-2(1+H)", gt=0, lt=1)
    ks_ratio: float = _param(3.0, "1", "upper to lower cut-off wavenumber ks/k1", gt=1)
    amplitudes: str = _param(
        "ideal", "1", "spectral amplitudes", choices=("ideal", "rayleigh")
    )
    threshold: str = _param(
        "theoretical",
        "1",
        "threshold rule: Gaussian quantile sqrt(2) erfcinv(2 xi), or each realization's own quantile",
        choices=("theoretical", "empirical"),
    )
    chunk: int = _param(50, "1", "realizations per dask chunk", ge=1)
    film: str = _param(
        "insulating",
        "1",
        "oxide film on a spot: insulating (the spot carries no current) or resistive "
        "(the film's specific resistance oxide.film_resistance in series with the spot)",
        choices=("insulating", "resistive"),
    )
    film_resistance: float = _param(
        1e-11, "ohm m2", "specific resistance r_f of a resistive oxide film (used when oxide.film = resistive)",
        ge=0,
    )
    spot_rule: str = _param(
        "centre",
        "1",
        "which share of a spot conducts: centre (all of it where its centre is clean, the paper's "
        "rule) or disc (its clean share f of the contact disc, at quadrature points, conducting "
        "with radius a sqrt(f); contact.model = discrete only)",
        choices=("centre", "disc"),
    )


@dataclass(frozen=True)
class Cube:
    """Greenwood multi-spot resistance over xi x lambda x delta x realization."""

    weights: str = _param(
        "radius",
        "1",
        "interaction weights: spot radii (Eq. 13) or cell contact areas (the published code)",
        choices=("radius", "area"),
    )
    crop_tolerance: float = _param(
        1e-6, "1", "spots are cropped while their bounded effect on R stays below this", ge=0, lt=1
    )
    method: str = _param(
        "auto",
        "1",
        "interaction sum algorithm: auto (the fastest, folded), folded (dft_gemm on the four "
        "mirror-parity quarters), dft_gemm (real DFT along x as a GEMM, "
        "then Toeplitz GEMM along y), fft (2-D real FFT, Parseval), gemm (dense 1/d), "
        "direct (double sum)",
        choices=("auto", "folded", "dft_gemm", "fft", "gemm", "direct"),
    )
    chunk: int = _param(25, "1", "realizations per dask chunk", ge=1)
    model: str = _param(
        "greenwood",
        "1",
        "resistance model: greenwood (closed form, Eqs. 11-13) or point (the exact "
        "point-interaction solve: by preconditioned conjugate gradients on grid spots, by a dense "
        "Cholesky solve on discrete spots)",
        choices=("greenwood", "point"),
    )
    solver_tolerance: float = _param(
        1e-10, "1", "point model: where the solver stops, in the measure cube.solver_criterion names", gt=0, lt=1
    )
    solver_criterion: str = _param(
        "error",
        "1",
        "point model: what solver_tolerance bounds: error (the estimated relative error of the "
        "conductance, from CG's energy-norm record) or residual (the relative residual, Jacobi norm)",
        choices=("error", "residual"),
    )
    max_iterations: int = _param(100, "1", "point model: conjugate-gradient iterations per solve at most", ge=1)
    lattice_constant: float = _param(
        0.0, "1", "point model: C of the lattice self term C / (pi dx) added to every spot's own "
        "resistance: the interaction with its own cell that the sum over the other cells misses; "
        "3.90026 for the square lattice (pipeline.physics.lattice), 0: none", ge=0,
    )


@dataclass(frozen=True)
class Fits:
    """Reductions over realizations and power-law fits R' = alpha F'^-gamma."""

    reduction: str = _param(
        "geometric_mean",
        "1",
        "reduction over realizations that is fitted",
        choices=("geometric_mean", "arithmetic_mean", "median"),
    )
    min_force: float = _param(200.0, "N", "fit only load steps with F >= min_force (fit_range = force)", ge=0)
    fit_range: str = _param(
        "force",
        "1",
        "what selects the fitted load steps: force (F >= min_force, in N) or force_normalized "
        "(F' >= min_force_normalized, the same steps for every scene of equal F')",
        choices=("force", "force_normalized"),
    )
    min_force_normalized: float = _param(
        0.4, "1", "fit only load steps with F' >= min_force_normalized (fit_range = force_normalized)", ge=0
    )
    curve_max_order: int = _param(
        3, "1", "curve model ln R'(ln F'): highest polynomial order tried (the lowest order within "
        "tolerance is kept)", ge=1, le=6
    )
    curve_tolerance: float = _param(
        0.03, "1", "curve model: relative error of R' allowed at every fitted step (or the step's "
        "confidence interval where wider)", gt=0, lt=1
    )
    n_bootstrap: int = _param(400, "1", "bootstrap resamples over realizations", ge=10)
    confidence: float = _param(0.95, "1", "confidence level of the intervals", gt=0, lt=1)
    seed: int = _param(7, "1", "seed of the bootstrap", ge=0)


@dataclass(frozen=True)
class Surrogate:
    """Surrogate of alpha(xi, lambda) and gamma(xi, lambda) (Eq. 26) and the predictor's warning.

    ``method = "paper"`` is the paper's SVD-then-polyfit with the fixed rank and orders below;
    ``method = "joint"`` fits all coefficients of the rank-r model at once in the chosen
    transform, weighted by each cell's interval, with transform, rank and orders chosen by
    leave-one-line-out cross-validation within the ``max_*`` limits.
    """

    method: str = _param(
        "joint", "1", "paper: SVD modes fitted one by one (Sect. 3.1); joint: weighted joint fit, "
        "rank/orders by cross-validation", choices=("paper", "joint"),
    )
    rank: int = _param(2, "1", "paper method: SVD rank r", ge=1)
    alpha_order_w: int = _param(3, "1", "paper method: alpha polynomial order in w = log(lambda)", ge=0)
    alpha_order_z: int = _param(2, "1", "paper method: alpha polynomial order in z = -log(1 - xi)", ge=0)
    gamma_order_w: int = _param(2, "1", "paper method: gamma polynomial order in w = log(lambda)", ge=0)
    gamma_order_z: int = _param(1, "1", "paper method: gamma polynomial order in z = -log(1 - xi)", ge=0)
    alpha_transform: str = _param(
        "log", "1", "joint method: alpha fitted as log(alpha), as alpha, or the better by cross-validation",
        choices=("log", "identity", "auto"),
    )
    gamma_transform: str = _param(
        "auto", "1", "joint method: gamma fitted as log(gamma), as gamma, or the better by cross-validation",
        choices=("log", "identity", "auto"),
    )
    lambda_map: str = _param(
        "auto", "1", "joint method: coordinate w of lambda: log (the paper's), lambda, sqrt, or the best by "
        "cross-validation", choices=("log", "lambda", "sqrt", "auto"),
    )
    max_rank: int = _param(3, "1", "joint method: highest rank tried by cross-validation", ge=1)
    max_order_w: int = _param(4, "1", "joint method: highest order in w tried by cross-validation", ge=0)
    max_order_z: int = _param(3, "1", "joint method: highest order in z tried by cross-validation", ge=0)
    weight_floor: float = _param(
        0.01, "1", "joint method: lower bound on a cell's relative 95 % half-width in its weight", gt=0, lt=1
    )
    cv_tolerance: float = _param(
        0.05, "1", "joint method: the simplest model within (1 + this) x the best cross-validated error wins",
        ge=0, le=1,
    )
    warn_error: float = _param(
        0.05, "1", "predict: warn where the local cross-validated surrogate error of ln R exceeds this", gt=0
    )


@dataclass(frozen=True)
class Atlas:
    """The atlas's design over the groups mu and Pi (``g2tom atlas``, :mod:`pipeline.atlas.design`):
    a log-spaced ``n_mu x n_pi`` grid over the box, plus held-out scenes drawn inside it."""

    mu_min: float = _param(1.0, "1", "lowest mu = (8/3) eta sigma sqrt(2 R* beta) of the design", gt=0)
    mu_max: float = _param(50.0, "1", "highest mu of the design (> atlas.mu_min)", gt=0)
    pi_min: float = _param(5.0, "1", "lowest Pi = eta R* sigma of the design", gt=0)
    pi_max: float = _param(320.0, "1", "highest Pi of the design (> atlas.pi_min)", gt=0)
    n_mu: int = _param(5, "1", "design values of mu (log-spaced, ends included)", ge=2)
    n_pi: int = _param(5, "1", "design values of Pi (log-spaced, ends included)", ge=2)
    n_heldout: int = _param(6, "1", "held-out scenes drawn inside the box, never fitted", ge=1)
    seed: int = _param(20261124, "1", "root seed of the held-out scenes' draws", ge=0)


SECTIONS: dict[str, type] = {
    "material": Material,
    "roughness": Roughness,
    "indenter": Indenter,
    "loading": Loading,
    "contact": Contact,
    "oxide": Oxide,
    "cube": Cube,
    "fits": Fits,
    "surrogate": Surrogate,
    "atlas": Atlas,
}

#: Parameters each stage depends on (whole sections or single ``section.key`` entries);
#: a stage's config hash covers these and the hashes of the stages it reads.
STAGE_INPUTS: dict[str, tuple[str, ...]] = {
    "contact": ("material", "roughness", "indenter", "loading", "contact"),
    "oxide": ("roughness.eta", "indenter.radius", "contact.window", "oxide"),
    # the fitted steps and fits.confidence: the adaptive ensemble's stopping rule
    "cube": ("material.rho", "cube", "oxide.film", "oxide.film_resistance", "oxide.spot_rule", "fits.min_force",
             "fits.fit_range",
             "fits.min_force_normalized", "fits.confidence"),
    "fits": ("fits",),
    "surrogate": (
        "surrogate.method",
        "surrogate.rank",
        "surrogate.alpha_order_w",
        "surrogate.alpha_order_z",
        "surrogate.gamma_order_w",
        "surrogate.gamma_order_z",
        "surrogate.alpha_transform",
        "surrogate.gamma_transform",
        "surrogate.lambda_map",
        "surrogate.max_rank",
        "surrogate.max_order_w",
        "surrogate.max_order_z",
        "surrogate.weight_floor",
        "surrogate.cv_tolerance",
    ),
}
#: Parameters left out of a stage's inputs although STAGE_INPUTS names their section.
STAGE_EXCLUDED: dict[str, tuple[str, ...]] = {
    "oxide": ("oxide.film", "oxide.film_resistance", "oxide.spot_rule"),
}
STAGE_UPSTREAM: dict[str, tuple[str, ...]] = {
    "contact": (),
    "oxide": (),
    "cube": ("contact", "oxide"),
    "fits": ("cube",),
    "surrogate": ("fits",),
}


def _key(f: dataclasses.Field) -> str:
    return f.metadata.get("key") or f.name


@dataclass(frozen=True)
class Scenario:
    """A complete, validated parameter set."""

    name: str = "custom"
    description: str = ""
    material: Material = field(default_factory=Material)
    roughness: Roughness = field(default_factory=Roughness)
    indenter: Indenter = field(default_factory=Indenter)
    loading: Loading = field(default_factory=Loading)
    contact: Contact = field(default_factory=Contact)
    oxide: Oxide = field(default_factory=Oxide)
    cube: Cube = field(default_factory=Cube)
    fits: Fits = field(default_factory=Fits)
    surrogate: Surrogate = field(default_factory=Surrogate)
    atlas: Atlas = field(default_factory=Atlas)

    # ----------------------------------------------------------------- derived values
    @property
    def deltas(self) -> "list[float]":
        """Approaches delta in m, lightest first."""
        n = self.loading.n_delta
        lo, hi = self.loading.delta_min, self.loading.delta_max
        if n == 1:
            return [hi * self.roughness.sigma]
        return [(hi + (lo - hi) * i / (n - 1)) * self.roughness.sigma for i in range(n)]

    @property
    def cell_size(self) -> float:
        """Cell pitch 1/sqrt(eta), in m."""
        return 1.0 / math.sqrt(self.roughness.eta)

    @property
    def resistance_scale(self) -> float:
        """2 rho* / sqrt(R* sigma), in ohm: R' = R / resistance_scale (Eq. 25)."""
        return 2.0 * self.material.rho / math.sqrt(self.indenter.radius * self.roughness.sigma)

    @property
    def force_scale(self) -> float:
        """E* sqrt(R* sigma^3) / 2, in N: F' = F / force_scale (Eq. 25)."""
        return self.material.E_star * math.sqrt(self.indenter.radius * self.roughness.sigma**3) / 2.0

    @property
    def n_cells(self) -> int:
        """Cells along one side of the window: the odd number closest to window/cell size."""
        if self.contact.window == AUTO:
            raise ConfigError(
                "contact.window = 'auto' is not resolved yet: call pipeline.before_work.domains.resolve(scenario)"
            )
        n = self.contact.window * self.indenter.radius / self.cell_size
        k = int(round((n - 1.0) / 2.0))
        return 2 * max(k, 0) + 1

    # ----------------------------------------------------------------- provenance
    def to_dict(self) -> dict[str, Any]:
        """Nested plain dict ``{section: {key: value}}`` plus name and description."""
        out: dict[str, Any] = {"name": self.name, "description": self.description}
        for section in SECTIONS:
            obj = getattr(self, section)
            out[section] = {_key(f): getattr(obj, f.name) for f in dataclasses.fields(obj)}
        return out

    def flat(self) -> dict[str, Any]:
        """``{"section.key": value}`` for every parameter."""
        d = self.to_dict()
        return {f"{s}.{k}": v for s in SECTIONS for k, v in d[s].items()}

    def stage_parameters(self, stage: str) -> dict[str, Any]:
        """The parameters ``stage`` depends on directly, as ``{"section.key": value}``."""
        flat = self.flat()
        wanted = STAGE_INPUTS[stage]
        excluded = STAGE_EXCLUDED.get(stage, ())
        return {
            k: v
            for k, v in flat.items()
            if any(k == w or k.startswith(w + ".") for w in wanted) and k not in excluded
        }

    def config_hash(self, stage: str | None = None) -> str:
        """SHA-256 (16 hex digits) of a stage's parameters and its upstream stages' hashes.

        With ``stage=None`` the hash covers the whole scenario (name and description aside).
        """
        if stage is None:
            payload: Any = self.flat()
        else:
            payload = {
                "stage": stage,
                "parameters": self.stage_parameters(stage),
                "upstream": {u: self.config_hash(u) for u in STAGE_UPSTREAM[stage]},
            }
        text = json.dumps(payload, sort_keys=True, separators=(",", ":"))
        return hashlib.sha256(text.encode()).hexdigest()[:16]


# --------------------------------------------------------------------------- validation
def _fmt_range(meta: Mapping[str, Any]) -> str:
    parts = []
    if meta["choices"]:
        return "one of " + ", ".join(repr(c) for c in meta["choices"])
    if meta["gt"] is not None:
        parts.append(f"> {meta['gt']:g}")
    if meta["ge"] is not None:
        parts.append(f">= {meta['ge']:g}")
    if meta["lt"] is not None:
        parts.append(f"< {meta['lt']:g}")
    if meta["le"] is not None:
        parts.append(f"<= {meta['le']:g}")
    text = " and ".join(parts) if parts else "any finite value"
    return f"{text}, or 'auto'" if meta.get("auto") else text


def _check_scalar(name: str, value: Any, kind: type, meta: Mapping[str, Any]) -> Any:
    unit = meta["unit"]
    allowed = _fmt_range(meta)
    where = f"{name} = {value!r}"
    if kind is str:
        if not isinstance(value, str) or (meta["choices"] and value not in meta["choices"]):
            raise ConfigError(f"{where} is not allowed: must be {allowed}")
        return value
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ConfigError(f"{where} is not a number: must be {allowed} ({unit})")
    if kind is int:
        if isinstance(value, float) and not value.is_integer():
            raise ConfigError(f"{where} is not an integer: must be an integer {allowed}")
        value = int(value)
    else:
        value = float(value)
        if not math.isfinite(value):
            raise ConfigError(f"{where} is not finite: must be {allowed} ({unit})")
    ok = (
        (meta["gt"] is None or value > meta["gt"])
        and (meta["ge"] is None or value >= meta["ge"])
        and (meta["lt"] is None or value < meta["lt"])
        and (meta["le"] is None or value <= meta["le"])
    )
    if not ok:
        raise ConfigError(f"{where} is out of range: must be {allowed} ({unit})")
    return value


def _element_kind(f: dataclasses.Field) -> tuple[type, bool]:
    ann = str(f.type)
    if f.metadata.get("auto"):
        ann = ann.split("|")[0].strip()  # "float | str": a number, or the word "auto"
    if ann.startswith("list"):
        return (float if "float" in ann else int if "int" in ann else str), True
    return {"float": float, "int": int, "str": str}[ann], False


def _check_field(section: str, f: dataclasses.Field, value: Any) -> Any:
    name = f"{section}.{_key(f)}"
    if f.metadata.get("auto") and value == AUTO:
        return AUTO
    kind, is_list = _element_kind(f)
    if not is_list:
        return _check_scalar(name, value, kind, f.metadata)
    if not isinstance(value, (list, tuple)) or len(value) == 0:
        raise ConfigError(
            f"{name} = {value!r} is not allowed: must be a non-empty list of numbers, each "
            f"{_fmt_range(f.metadata)} ({f.metadata['unit']})"
        )
    out = [_check_scalar(f"{name}[{i}]", v, kind, f.metadata) for i, v in enumerate(value)]
    if len(set(out)) != len(out) or out != sorted(out):
        raise ConfigError(f"{name} = {value!r} must be strictly increasing")
    return out


def _all_keys() -> list[str]:
    return [f"{s}.{_key(f)}" for s, cls in SECTIONS.items() for f in dataclasses.fields(cls)]


def _unknown(name: str) -> ConfigError:
    keys = _all_keys()
    leaf = name.rsplit(".", 1)[-1]
    exact_leaf = [k for k in keys if k.rsplit(".", 1)[-1].lower() == leaf.lower()]
    close = exact_leaf or difflib.get_close_matches(name, keys, n=1, cutoff=0.5)
    if not close:
        close = difflib.get_close_matches(
            leaf, [k.rsplit(".", 1)[-1] for k in keys], n=1, cutoff=0.6
        )
        close = [k for k in keys if close and k.endswith("." + close[0])][:1]
    hint = f"; did you mean '{close[0]}'?" if close else ""
    return ConfigError(f"unknown parameter '{name}'{hint}")


#: Largest integer a netCDF attribute (64-bit signed) can record.
_INT_MAX = 2**63 - 1


def _check_point_model(s: Scenario) -> None:
    """The point model and resistive films need radius weights; the point model, an operator it can
    apply; the lattice term belongs to the point model."""
    if s.cube.lattice_constant > 0 and s.cube.model != "point":
        raise ConfigError(
            f"cube.lattice_constant = {s.cube.lattice_constant!r} is not allowed with cube.model = "
            f"{s.cube.model!r}: the lattice self term belongs to cube.model = 'point' (must be 0 otherwise)"
        )
    if s.cube.model == "point" and s.cube.method not in ("auto", "folded", "gemm", "direct"):
        raise ConfigError(
            f"cube.method = {s.cube.method!r} is not allowed with cube.model = 'point': must be one of "
            "'auto', 'folded', 'gemm', 'direct'"
        )
    needs_radius = "cube.model = 'point'" if s.cube.model == "point" else (
        "oxide.film = 'resistive'" if s.oxide.film == "resistive" else None)
    if needs_radius and s.cube.weights != "radius":
        raise ConfigError(
            f"cube.weights = {s.cube.weights!r} is not allowed with {needs_radius}: must be 'radius' "
            "(only radius weights make Greenwood's form the Rayleigh quotient of the point model)"
        )


def _check_spots(s: Scenario) -> None:
    """``expected`` and ``asperities`` spots need the separation at the cells and radius weights."""
    if s.contact.spots == "mean_area":
        return
    if s.contact.area_interpolation != "separation":
        raise ConfigError(
            f"contact.area_interpolation = {s.contact.area_interpolation!r} is not allowed with "
            f"contact.spots = {s.contact.spots!r}: must be 'separation' (these spots are computed from "
            "the separation at each cell centre)"
        )
    if s.cube.weights != "radius":
        raise ConfigError(
            f"cube.weights = {s.cube.weights!r} is not allowed with contact.spots = {s.contact.spots!r}: "
            "must be 'radius' (cell-area weights are the published code's convention for mean_area spots)"
        )


def _check_discrete(s: Scenario) -> None:
    """The disc rule needs discrete spots; discrete spots take radius weights, no lattice term and
    insulating films."""
    if s.oxide.spot_rule == "disc" and s.contact.model != "discrete":
        raise ConfigError(
            f"oxide.spot_rule = 'disc' is not allowed with contact.model = {s.contact.model!r}: must be "
            "'centre' (a grid spot stands for a cell's asperities, not one contact disc; the disc rule "
            "needs contact.model = 'discrete')"
        )
    if s.contact.model != "discrete":
        return
    for name, value, allowed, why in (
        ("cube.weights", s.cube.weights, "radius", "Greenwood's form on discrete spots weights by radii"),
        ("oxide.film", s.oxide.film, "insulating", "resistive films are not implemented on discrete spots"),
    ):
        if value != allowed:
            raise ConfigError(f"{name} = {value!r} is not allowed with contact.model = 'discrete': must be "
                              f"{allowed!r} ({why})")
    if s.cube.lattice_constant != 0:
        raise ConfigError(f"cube.lattice_constant = {s.cube.lattice_constant!r} is not allowed with contact.model "
                          "= 'discrete': must be 0 (discrete spots have no lattice to complete)")


def _cross_checks(s: Scenario) -> None:
    _check_point_model(s)
    _check_spots(s)
    _check_discrete(s)
    for section in SECTIONS:
        obj = getattr(s, section)
        for f in dataclasses.fields(obj):
            value = getattr(obj, f.name)
            if isinstance(value, int) and not isinstance(value, bool) and abs(value) > _INT_MAX:
                raise ConfigError(
                    f"{section}.{_key(f)} = {value!r} is out of range: must be <= 2**63 - 1 = {_INT_MAX} "
                    f"(stored as a 64-bit integer in every output file)")
    if s.loading.delta_min > s.loading.delta_max:
        raise ConfigError(
            f"loading.delta_min = {s.loading.delta_min!r} is out of range: must be <= "
            f"loading.delta_max = {s.loading.delta_max!r} (sigma)"
        )
    if s.loading.n_delta > 1 and s.loading.delta_min == s.loading.delta_max:
        raise ConfigError(
            f"loading.delta_min = {s.loading.delta_min!r} must differ from loading.delta_max = "
            f"{s.loading.delta_max!r} when loading.n_delta = {s.loading.n_delta} > 1 (sigma)"
        )
    for low, high in (("mu_min", "mu_max"), ("pi_min", "pi_max")):
        if not getattr(s.atlas, low) < getattr(s.atlas, high):
            raise ConfigError(f"atlas.{high} = {getattr(s.atlas, high)!r} is out of range: must be > "
                              f"atlas.{low} = {getattr(s.atlas, low)!r}")
    if AUTO not in (s.contact.window, s.contact.r_max):
        check_domains(s)


def check_domains(s: Scenario) -> None:
    """Cross-checks of the spot window, the radial domain and the oxide band once both are numbers.

    Raises
    ------
    ConfigError
        Naming ``contact.window`` (or ``oxide.lambda``) when the window's corners leave the
        radial domain, the window holds fewer than 3 cells, or the band holds no mode.
    """
    window = s.contact.window * s.indenter.radius
    r_max = s.contact.r_max * s.indenter.radius
    corner = math.sqrt(2.0) * (s.n_cells - 1) / 2.0 * s.cell_size  # radius of the corner cell centres
    if corner > r_max:
        raise ConfigError(
            f"contact.window = {s.contact.window!r} is out of range: its corner cell centres lie at "
            f"r = {corner:.6g} m, beyond the radial domain r <= contact.r_max * R* = {r_max:.6g} m; "
            f"the window must be <= about sqrt(2) * contact.r_max = {math.sqrt(2) * s.contact.r_max:.4g} (R*)"
        )
    if s.n_cells < 3:
        raise ConfigError(
            f"contact.window = {s.contact.window!r} is out of range: the window holds fewer than "
            f"3 cells of pitch 1/sqrt(eta) = {s.cell_size:.3g} m"
        )
    _check_ensemble(s)
    longest = max(s.oxide.lambda_) * s.cell_size
    if s.oxide.period == "window" and longest > window:
        n_modes = _modes_in_band(s, max(s.oxide.lambda_))
        if n_modes == 0:
            raise ConfigError(
                f"oxide.lambda = {max(s.oxide.lambda_):g} is out of range: the window "
                f"({window:.3g} m) holds no Fourier mode of the band k1..ks; it must be "
                f"<= {window / s.cell_size:.3g} for this window"
            )
        warnings.warn(
            f"oxide.lambda = {max(s.oxide.lambda_):g}: the correlation length "
            f"({longest:.3g} m) exceeds the window ({window:.3g} m); the band holds only "
            f"{n_modes} independent Fourier modes",
            stacklevel=3,
        )


def _modes_in_band(s: Scenario, lam: float) -> int:
    """Independent (half-plane) wave vectors of the window's lattice in k1 <= |k| <= ks.

    Pure arithmetic, the count of ``pipeline.physics.oxide_field.band`` (a test checks both agree).
    """
    k1 = s.n_cells / (2.0 * lam)
    ks = s.oxide.ks_ratio * k1
    top = math.floor(ks)
    return sum(
        1
        for j in range(top + 1)
        for i in range(-top, top + 1)
        if (j > 0 or i > 0) and k1 <= math.hypot(i, j) <= ks
    )


#: Bytes per realization and coefficient-table entry while fields are evaluated (complex table,
#: its partial DFT and workspace).
FIELD_BYTES_PER_ENTRY = 48


def _available_memory() -> int:
    """Physical memory of the machine, in bytes (psutil: also on Windows, which has no os.sysconf)."""
    import psutil

    return int(psutil.virtual_memory().total)


def _check_ensemble(s: Scenario) -> None:
    """Adaptive-ensemble limits and the memory a spectral resolution needs."""
    ox = s.oxide
    if ox.ensemble == "adaptive" and ox.max_realizations < ox.min_realizations:
        raise ConfigError(
            f"oxide.max_realizations = {ox.max_realizations} is out of range: must be >= "
            f"oxide.min_realizations = {ox.min_realizations} (the first batch)"
        )
    if ox.period != "spectral":
        return
    top = math.floor(ox.ks_ratio * max(ox.spectral_resolution, s.n_cells / (2.0 * min(ox.lambda_))))
    fields = max(ox.chunk, s.cube.chunk)
    need = FIELD_BYTES_PER_ENTRY * fields * (top + 1) * (2 * top + 1)
    have = _available_memory()
    if need > have:
        raise ConfigError(
            f"oxide.spectral_resolution = {ox.spectral_resolution:g} is out of range: a chunk of "
            f"{fields} fields would need {need / 2**30:.3g} GiB, more than the machine's "
            f"{have / 2**30:.3g} GiB; lower it (the band's top index is {top})"
        )


def _build(data: Mapping[str, Any], *, name: str, description: str) -> Scenario:
    sections: dict[str, Any] = {}
    for key in data:
        if key not in SECTIONS:
            raise _unknown(key)
    for section, cls in SECTIONS.items():
        table = data.get(section, {})
        if not isinstance(table, Mapping):
            raise ConfigError(f"{section} = {table!r} is not allowed: must be a [{section}] table of parameters")
        given = dict(table)
        by_key = {_key(f): f for f in dataclasses.fields(cls)}
        for k in given:
            if k not in by_key:
                raise _unknown(f"{section}.{k}")
        kwargs = {
            by_key[k].name: _check_field(section, by_key[k], v) for k, v in given.items()
        }
        sections[section] = cls(**kwargs)
    scenario = Scenario(name=name, description=description, **sections)
    _cross_checks(scenario)
    return scenario


# --------------------------------------------------------------------------- loading
def bundled_scenarios() -> list[str]:
    """Names of the scenarios shipped with the package."""
    files = resources.files("pipeline.scenarios")
    return sorted(p.name[:-5] for p in files.iterdir() if p.name.endswith(".toml"))


def _parse_value(text: str) -> Any:
    try:
        return tomllib.loads(f"v = {text}")["v"]
    except tomllib.TOMLDecodeError:
        return text  # a bare word such as fixed_point


def _read_toml(config: str | Path) -> tuple[dict[str, Any], str]:
    text_name = str(config)
    if text_name in bundled_scenarios():
        text = resources.files("pipeline.scenarios").joinpath(f"{text_name}.toml").read_text()
        return tomllib.loads(text), text_name
    path = Path(config)
    if not path.is_file():
        raise ConfigError(
            f"--config {text_name!r} is neither a bundled scenario "
            f"({', '.join(bundled_scenarios())}) nor a TOML file"
        )
    try:
        return tomllib.loads(path.read_text()), path.stem
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"--config {text_name!r}: not valid TOML ({exc})") from None


def load_scenario(
    config: str | Path = "paper", overrides: Iterable[str] | Mapping[str, Any] = ()
) -> Scenario:
    """Load a bundled scenario by name or a TOML file, apply overrides and validate.

    Parameters
    ----------
    config
        A bundled scenario name (see :func:`bundled_scenarios`) or a path to a TOML file.
        A file may set ``base = "paper"`` to start from a bundled scenario.
    overrides
        ``"section.key=value"`` strings (values in TOML syntax) or a mapping
        ``{"section.key": value}``.

    Raises
    ------
    ConfigError
        Naming the parameter, its value and the allowed range.
    """
    data, name = _read_toml(config)
    # the settings the user chose (a file's own, not those of its base or of a bundled scenario)
    explicit = set() if str(config) in bundled_scenarios() else {
        f"{section}.{key}" for section, table in data.items() if isinstance(table, dict) for key in table}
    name = str(data.pop("name", name))
    description = str(data.pop("description", ""))
    base = data.pop("base", None)
    if base is not None:
        if base not in bundled_scenarios():
            raise ConfigError(f"base = {base!r} is not a bundled scenario ({', '.join(bundled_scenarios())})")
        merged, _ = _read_toml(base)
        merged.pop("name", None)
        base_description = str(merged.pop("description", ""))
        description = description or base_description
        for section, values in data.items():
            if isinstance(values, dict) and isinstance(merged.get(section), dict):
                merged[section].update(values)
            else:
                merged[section] = values
        data = merged
    items = overrides.items() if isinstance(overrides, Mapping) else (
        _split_override(o) for o in overrides
    )
    for dotted, value in items:
        section, _, key = dotted.partition(".")
        if section not in SECTIONS or not key:
            raise _unknown(dotted)
        data.setdefault(section, {})[key] = value
        explicit.add(dotted)
    return _settle(_build(data, name=name, description=description), explicit)


#: Settings used only under another setting's value: key -> (that setting, its value, what is used instead).
USED_ONLY_WITH: dict[str, tuple[str, str, str]] = {
    "fits.min_force": ("fits.fit_range", "force", "fits.min_force_normalized"),
    "fits.min_force_normalized": ("fits.fit_range", "force_normalized", "fits.min_force"),
}


def _settle(s: Scenario, explicit: set[str]) -> Scenario:
    """Defaults that follow the grid, and a warning for each chosen setting that has no effect.

    ``surrogate.rank`` left at its default follows the oxide grid (at most
    min(len(oxide.xi), len(oxide.lambda))); one the user set is kept, and
    :func:`check_surrogate_grid` refuses it when out of range. A setting of
    :data:`USED_ONLY_WITH` the user set while another setting overrides it is warned about,
    naming that setting.

    Parameters
    ----------
    s
        The scenario as built.
    explicit
        ``section.key`` of every setting the user chose (``--set``, or the TOML file's own).
    """
    flat = s.flat()
    for key, (control, needed, instead) in USED_ONLY_WITH.items():
        if key in explicit and flat[control] != needed:
            warnings.warn(f"{key} = {flat[key]:g} has no effect: {control} = {flat[control]!r} selects by {instead} "
                          f"instead; set {control} = {needed!r} for {key} to count", stacklevel=3)
    top = min(len(s.oxide.xi), len(s.oxide.lambda_))
    if "surrogate.rank" not in explicit and s.surrogate.rank > top:
        s = dataclasses.replace(s, surrogate=dataclasses.replace(s.surrogate, rank=top))
    return s


def _split_override(text: str) -> tuple[str, Any]:
    if "=" not in text:
        raise ConfigError(f"--set {text!r}: expected key=value, e.g. roughness.sigma=2e-5")
    key, _, value = text.partition("=")
    return key.strip(), _parse_value(value.strip())


def parameter_table() -> list[tuple[str, Any, str, str, str]]:
    """Every parameter as ``(key, default, unit, allowed range, description)``."""
    rows = []
    for section, cls in SECTIONS.items():
        default = cls()
        for f in dataclasses.fields(cls):
            rows.append(
                (f"{section}.{_key(f)}", getattr(default, f.name), f.metadata["unit"],
                 _fmt_range(f.metadata), f.metadata["doc"])
            )
    return rows
