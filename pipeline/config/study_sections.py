"""The study's parameters: the sections ``oxide`` (Table 2 and the ensemble), ``cube``, ``fits``,
``surrogate`` and ``atlas``; and ``compute``, how the work is cut up, which changes no result and so
enters no configuration hash.

Each field declares its unit, meaning and allowed range (:func:`g2tom.config.declare.param`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from g2tom.config.declare import param

__all__ = ["Oxide", "Cube", "Fits", "Surrogate", "Atlas", "Compute", "CHUNK_BYTES", "KERNEL_CACHE_BYTES"]

#: Largest float32 fields of one oxide chunk (all lambdas), bytes: ``compute.oxide_chunk`` realizations a
#: chunk, fewer where their fields would pass it; bounds the oxide stage's peak on large grids (and
#: its estimate before work).
CHUNK_BYTES = 64 * 2**20
#: Bytes of coupling kernels the discrete cube's pool keeps (one per surface, 8 n^2 bytes each:
#: 0.3 MB at the default's ~200 spots, 300 MB at the atlas's largest scene's ~6,100); beyond it a
#: surface's kernel is made again for every oxide realization that meets it, one O(n^2) pass against
#: the realization's point solves over every load step (a few % of them). The plan counts it.
KERNEL_CACHE_BYTES = 2 * 2**30


@dataclass(frozen=True)
class Oxide:
    """Thresholded Gaussian random fields (Sect. 2.6, Table 2)."""

    xi: list[float] = param(
        [0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9], "1", "oxide fractions", gt=0, lt=1, each=True
    )
    lambda_: list[float] = param(
        [1.0, 3.0, 5.0, 7.0, 9.0, 11.0, 13.0, 15.0, 17.0, 19.0, 21.0, 23.0],
        "1",
        "normalized correlation lengths l_O sqrt(eta)",
        gt=0,
        each=True,
        key="lambda",
    )
    n_realizations: int = param(
        500, "1", "fixed ensemble: random fields per correlation length (adaptive: fields recorded in oxide.nc)", ge=2
    )
    ensemble: str = param(
        "adaptive",
        "1",
        "realizations: a fixed count per lambda (n_realizations), or per (xi, lambda) batches until "
        "alpha's 95 % half-width reaches target_half_width or the cap max_realizations",
        choices=("fixed", "adaptive"),
    )
    min_realizations: int = param(
        400, "1", "adaptive: first batch, the fewest realizations any (xi, lambda) uses", ge=2
    )
    max_realizations: int = param(30000, "1", "adaptive: cap on the realizations per (xi, lambda)", ge=2)
    target_half_width: float = param(
        0.025, "1", "adaptive: target relative 95 % half-width of alpha in every cell", ge=1e-4, lt=1
    )
    step_half_width: float = param(
        0.0, "1", "adaptive, discrete: target relative 95 % half-width of the geometric mean of R at every "
        "fitted step as well (0: alpha's target only); the realizations past alpha's count are computed "
        "only at the lightest steps still wider", ge=0, lt=1
    )
    period: str = param(
        "spectral",
        "1",
        "period of the random field: the spot window (the published lattice), or a period of "
        "P >= n_cells cells with k1 = P / (2 lambda) >= spectral_resolution lattice steps",
        choices=("window", "spectral"),
    )
    spectral_resolution: float = param(
        16.0, "1", "period = spectral: k1 in lattice steps 2 pi / P (annulus ~ 4 pi res^2 modes)", gt=0
    )
    seed: int = param(20240531, "1", "root seed of every random stream", ge=0)
    hurst: float = param(0.5, "1", "Hurst exponent H of the spectrum k^-2(1+H)", gt=0, lt=1)
    ks_ratio: float = param(3.0, "1", "upper to lower cut-off wavenumber ks/k1", gt=1, le=1e3)
    amplitudes: str = param(
        "ideal", "1", "spectral amplitudes", choices=("ideal", "rayleigh")
    )
    threshold: str = param(
        "theoretical",
        "1",
        "threshold rule: Gaussian quantile sqrt(2) erfcinv(2 xi), or each realization's own quantile",
        choices=("theoretical", "empirical"),
    )
    film: str = param(
        "insulating",
        "1",
        "oxide film on a spot: insulating (the spot carries no current) or resistive "
        "(the film's specific resistance oxide.film_resistance in series with the spot)",
        choices=("insulating", "resistive"),
    )
    film_resistance: float = param(
        1e-11, "ohm m2", "specific resistance r_f of a resistive oxide film (used when oxide.film = resistive)",
        ge=0,
    )
    spot_rule: str = param(
        "centre",
        "1",
        "which share of a spot conducts: centre (all of it where its centre is clean, the paper's "
        "rule), disc (its clean share f of the contact disc, at quadrature points, conducting "
        "with radius a sqrt(f)) or segment (the same f, conducting as the circular segment of that "
        "share: radius a h(f) >= a sqrt(f)); disc and segment: contact.model = discrete only",
        choices=("centre", "disc", "segment"),
    )


@dataclass(frozen=True)
class Cube:
    """Greenwood multi-spot resistance over xi x lambda x delta x realization."""

    weights: str = param(
        "radius",
        "1",
        "interaction weights: spot radii (Eq. 13) or cell contact areas (the published code)",
        choices=("radius", "area"),
    )
    crop_tolerance: float = param(
        1e-6, "1", "spots are cropped while their bounded effect on R stays below this", ge=0, lt=1
    )
    model: str = param(
        "greenwood",
        "1",
        "resistance model: greenwood (closed form, Eqs. 11-13) or point (the exact "
        "point-interaction solve: by preconditioned conjugate gradients on grid spots, by a dense "
        "Cholesky solve on discrete spots)",
        choices=("greenwood", "point"),
    )
    solver_tolerance: float = param(
        1e-10, "1", "point model: where the solver stops, in the measure cube.solver_criterion names", gt=0, lt=1
    )
    solver_criterion: str = param(
        "error",
        "1",
        "point model: what solver_tolerance bounds: error (the estimated relative error of the "
        "conductance, from CG's energy-norm record) or residual (the relative residual, Jacobi norm)",
        choices=("error", "residual"),
    )
    max_iterations: int = param(100, "1", "point model: conjugate-gradient iterations per solve at most", ge=1)
    lattice_constant: float = param(
        0.0, "1", "point model: C of the lattice self term C / (pi dx) added to every spot's own "
        "resistance: the interaction with its own cell that the sum over the other cells misses; "
        "3.90026 for the square lattice (g2tom.physics.lattice), 0: none", ge=0,
    )


@dataclass(frozen=True)
class Fits:
    """Reductions over realizations and power-law fits R' = alpha F'^-gamma."""

    reduction: str = param(
        "geometric_mean",
        "1",
        "reduction over realizations that is fitted",
        choices=("geometric_mean", "arithmetic_mean", "median"),
    )
    min_force: float = param(200.0, "N", "fit only load steps with F >= min_force (fit_range = force)", ge=0)
    fit_range: str = param(
        "force",
        "1",
        "what selects the fitted load steps: force (F >= min_force, in N) or force_normalized "
        "(F' >= min_force_normalized, the same steps for every scene of equal F')",
        choices=("force", "force_normalized"),
    )
    min_force_normalized: float = param(
        0.4, "1", "fit only load steps with F' >= min_force_normalized (fit_range = force_normalized)", ge=0
    )
    curve_max_order: int = param(
        3, "1", "curve model ln R'(ln F'): highest polynomial order tried (the lowest order within "
        "tolerance is kept)", ge=1, le=6
    )
    curve_tolerance: float = param(
        0.03, "1", "curve model: relative error of R' allowed at every fitted step (or the step's "
        "confidence interval where wider)", gt=0, lt=1
    )
    control_variate: str = param(
        "none", "1", "control variate of the geometric mean: none, or clean_share (ln R of each step regressed on "
        "the realization's radius-weighted clean share of its spots, whose expectation is known exactly; needs "
        "discrete asperities, the theoretical threshold, ideal amplitudes and the geometric mean), or auto: "
        "clean_share where those hold, else none (g2tom params shows the value used)",
        choices=("none", "clean_share", "auto"),
    )
    n_bootstrap: int = param(400, "1", "bootstrap resamples over realizations", ge=10)
    confidence: float = param(0.95, "1", "confidence level of the intervals", gt=0, lt=1)
    seed: int = param(7, "1", "seed of the bootstrap", ge=0)

    def fitted_loads(self, force: Any, force_normalized: Any) -> tuple[str, float, Any, str]:
        """What selects the fitted load steps: the parameter's key, its threshold, the loads it is
        compared with (``force`` in N or ``force_normalized``, as given) and their unit."""
        if self.fit_range == "force":
            return "min_force", self.min_force, force, " N"
        return "min_force_normalized", self.min_force_normalized, force_normalized, ""


@dataclass(frozen=True)
class Surrogate:
    """Surrogate of alpha(xi, lambda) and gamma(xi, lambda) (Eq. 26) and the predictor's warning.

    ``method = "paper"`` is the paper's SVD-then-polyfit with the fixed rank and orders below;
    ``method = "joint"`` fits all coefficients of the rank-r model at once in the chosen
    transform, weighted by each cell's interval, with transform, rank and orders chosen by
    leave-one-line-out cross-validation within the ``max_*`` limits.
    """

    method: str = param(
        "joint", "1", "paper: SVD modes fitted one by one (Sect. 3.1); joint: weighted joint fit, "
        "rank/orders by cross-validation", choices=("paper", "joint"),
    )
    rank: int = param(2, "1", "paper method: SVD rank r", ge=1)
    alpha_order_w: int = param(3, "1", "paper method: alpha polynomial order in w = log(lambda)", ge=0)
    alpha_order_z: int = param(2, "1", "paper method: alpha polynomial order in z = -log(1 - xi)", ge=0)
    gamma_order_w: int = param(2, "1", "paper method: gamma polynomial order in w = log(lambda)", ge=0)
    gamma_order_z: int = param(1, "1", "paper method: gamma polynomial order in z = -log(1 - xi)", ge=0)
    alpha_transform: str = param(
        "log", "1", "joint method: alpha fitted as log(alpha), as alpha, or the better by cross-validation",
        choices=("log", "identity", "auto"),
    )
    gamma_transform: str = param(
        "auto", "1", "joint method: gamma fitted as log(gamma), as gamma, or the better by cross-validation",
        choices=("log", "identity", "auto"),
    )
    lambda_map: str = param(
        "auto", "1", "joint method: coordinate w of lambda: log (the paper's), lambda, sqrt, or the best by "
        "cross-validation", choices=("log", "lambda", "sqrt", "auto"),
    )
    max_rank: int = param(3, "1", "joint method: highest rank tried by cross-validation", ge=1)
    max_order_w: int = param(4, "1", "joint method: highest order in w tried by cross-validation", ge=0)
    max_order_z: int = param(3, "1", "joint method: highest order in z tried by cross-validation", ge=0)
    weight_floor: float = param(
        0.01, "1", "joint method: lower bound on a cell's relative 95 % half-width in its weight", gt=0, lt=1
    )
    cv_tolerance: float = param(
        0.05, "1", "joint method: the simplest model within (1 + this) x the best cross-validated error wins",
        ge=0, le=1,
    )
    warn_error: float = param(
        0.05, "1", "predict: warn where the local cross-validated surrogate error of ln R exceeds this", gt=0
    )


@dataclass(frozen=True)
class Atlas:
    """The atlas's design over the groups mu and Pi (``g2tom atlas``, :mod:`g2tom.atlas.design`):
    a log-spaced ``n_mu x n_pi`` grid over the box, plus held-out scenes drawn inside it."""

    mu_min: float = param(1.0, "1", "lowest mu = (8/3) eta sigma sqrt(2 R* beta) of the design", gt=0)
    mu_max: float = param(50.0, "1", "highest mu of the design (> atlas.mu_min)", gt=0)
    pi_min: float = param(5.0, "1", "lowest Pi = eta R* sigma of the design", gt=0)
    pi_max: float = param(320.0, "1", "highest Pi of the design (> atlas.pi_min)", gt=0)
    n_mu: int = param(5, "1", "design values of mu (log-spaced, ends included)", ge=2)
    n_pi: int = param(5, "1", "design values of Pi (log-spaced, ends included)", ge=2)
    n_heldout: int = param(6, "1", "held-out scenes drawn inside the box, never fitted", ge=1)
    seed: int = param(20261124, "1", "root seed of the held-out scenes' draws", ge=0)
    heldout_half_width: float = param(
        0.025, "1", "target relative 95 % half-width of alpha in the held-out scenes (the smaller of this and "
        "oxide.target_half_width): their own noise should not decide the held-out verdict", gt=0, lt=1
    )
    heldout_step_half_width: float = param(
        0.0, "1", "oxide.step_half_width of the held-out scenes where their ensemble can take one (adaptive, "
        "discrete, the geometric mean; the smaller of the two where both are set; 0: as the design's): their "
        "light steps' intervals, not only alpha's", ge=0, lt=1
    )
    heldout_pool_half_width: float = param(
        0.0, "1", "discrete: contact.pool_half_width of the held-out scenes (the smaller of the two where both "
        "are set; 0: as the design's): a pool grown at the light steps, whose error no interval shows", ge=0, lt=1
    )


@dataclass(frozen=True)
class Compute:
    """How the work is cut up and which exact algorithm runs: no setting here changes a result, so
    none enters a configuration hash, and changing one re-runs no stage.

    The workers, a cluster's address and the device are the command line's (``--workers``,
    ``--scheduler``, ``--device``).
    """

    interaction_sum: str = param(
        "auto",
        "1",
        "interaction sum algorithm (equal results): auto (the fastest, folded), folded (dft_gemm on the four "
        "mirror-parity quarters), dft_gemm (real DFT along x as a GEMM, "
        "then Toeplitz GEMM along y), fft (2-D real FFT, Parseval), gemm (dense 1/d), "
        "direct (double sum)",
        choices=("auto", "folded", "dft_gemm", "fft", "gemm", "direct"),
    )
    cube_chunk: int = param(25, "1", "cube: realizations per dask task", ge=1)
    oxide_chunk: int = param(50, "1", "oxide: realizations per dask chunk", ge=1)
    oxide_batch: int = param(
        1000, "1", "adaptive ensemble: realizations added per round to a cell still short of its target "
        "(an xi's count is the first prefix meeting it, whatever the batch)", ge=1
    )
