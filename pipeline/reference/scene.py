"""The validation scene: its parameters, its rough spheres on the grid, and g2tom on the same scene.

A :class:`ValidationSet` fixes the scene (the paper's materials, sigma and eta; by default R*/2 and
2 beta, which keep the paper's mu = (8/3) eta sigma sqrt(2 R* beta) = 8.26 with a contact that
fits a 1024^2 grid at 16 pixels per asperity spacing), the loads (g2tom's approaches delta/sigma:
the reference is solved at the force g2tom gives at each, so both are compared at equal F), the
oxide cases (xi x lambda, g2tom's fields by seed and realization index), the realizations of
part 1 and the sizes of part 2's ensembles.

g2tom's side runs its stages in memory (contact, oxide, cube): in part 1 for every spot
discretization of Greenwood-Tripp's model and every ``cube.model`` (:func:`g2tom_scenario`), in part
2 the validated scenario's own model (:func:`scene_overrides` on top of it).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np
import xarray as xr

from g2tom.config import ConfigError, ResolvedScenario
from g2tom.before_work import load_scenario
from g2tom.before_work.domains import resolve
from g2tom.reference import surfaces
from g2tom.stages import contact as contact_stage
from g2tom.stages import cube as cube_stage
from g2tom.stages import oxide as oxide_stage
from g2tom.variables import entry

__all__ = ["case_variable", "ValidationSet", "DEFAULT", "QUICK", "RANDOM", "random_process_set", "capped_contact",
           "with_hardness_of", "surface_stream", "rough_sphere", "g2tom_scenario",
           "g2tom_resistances", "contact_extent", "scene_overrides", "scenario_of", "FLOOR_SIGMAS", "DEFAULT_LOADS"]

#: The GW surface's floor between asperities, in sigma below the reference plane: far below any
#: contact of the loads used (the deepest touching tip lies near delta >= -3 sigma).
FLOOR_SIGMAS = 8.0
#: The default set's approaches delta/sigma: 8 evenly spaced from 2 to -3 (g2tom's load steps), i.e.
#: F' = 0.075, 0.45, 1.55, 3.54, 6.35, 9.88, 14.1, 18.8 on the GW surface.
DEFAULT_LOADS = tuple(float(d) for d in np.linspace(2.0, -3.0, 8))


@dataclass(frozen=True)
class ValidationSet:
    """One validation study: scene, loads, oxide cases, realizations and grids.

    Attributes
    ----------
    sigma, eta, beta
        GW asperity heights' standard deviation (m), density (m^-2), tip radius (m).
    radius, E, nu, rho
        Sphere radius R* (m), Young's modulus (Pa) and Poisson ratio of both bodies, rho* (ohm m).
    deltas
        g2tom's approaches delta / sigma, lightest load first.
    xi, lambdas
        Oxide fractions and normalized correlation lengths: every pair is a case.
    realizations
        Surface and oxide realization indices of part 1 (0 .. P-1).
    n_grid, pixels_per_cell
        Reference grid side (pixels) and pixels per asperity spacing 1/sqrt(eta).
    convergence_grid
        A second, coarser grid (same window) run on the first realization, clean, for the grid
        convergence (halving the grid step), or 0 for none.
    surface_seed, oxide_seed
        Root seeds of the surfaces and of g2tom's oxide fields.
    models, discretizations
        g2tom's ``cube.model`` values and spot discretizations to compare.
    spot_rule
        The oxide rule of the ``discrete`` discretization (``disc`` or ``segment``: the validated
        scenario's, :func:`g2tom.reference.discrete_spots.with_rule_of`).
    surface
        ``gw`` (asperities of the GW model with sigma, eta, beta) or ``random_process`` (a Gaussian
        self-affine surface, :func:`random_process_set`: sigma, eta, beta are then its summits').
    hurst, rms, short_wavelength, bandwidth_ratio
        The random process: Hurst exponent, height std (m), shortest wavelength (m) and the ratio
        of the longest to the shortest.
    ensemble_grid, max_ensemble, max_pairs, model_realizations
        Part 2: the grid of the full field's proxies (pixels), the most realizations of a load's
        full-field ensemble and of its pairs (the full field on the main grid beside its proxy:
        part 1's realizations, then added ones), and the validated scenario's oxide realizations.
    clean_error, oxide_error
        Part 2's goal for the standard error of ln ratio, clean and oxidized.
    device, solver
        Where the reference's cases compute (``cpu`` or ``gpu``) and with which solver (``tamaas``,
        CPU only, or ``g2tom``'s own: :mod:`g2tom.reference.devices`); they do not shape a
        case's result beyond the solvers' tolerances, so they are not in the cases' keys.
    hardness
        The full field's hardness H, Pa: its contact pressure is capped at H (the perfectly plastic
        surface: an elastic half-space whose pressure cannot exceed H, not an elasto-plastic volume),
        the validated scenario's ``material.hardness`` (:func:`with_hardness_of`); None: elastic.
    """

    sigma: float = 20e-6
    eta: float = 2e8
    beta: float = 60e-6
    radius: float = 5e-3
    E: float = 2.1e11
    nu: float = 0.3
    rho: float = 7.2e-7
    deltas: tuple[float, ...] = DEFAULT_LOADS
    xi: tuple[float, ...] = (0.5, 0.7)
    lambdas: tuple[float, ...] = (1.0, 5.0)
    realizations: tuple[int, ...] = tuple(range(8))
    n_grid: int = 1024
    pixels_per_cell: float = 16.0
    convergence_grid: int = 512
    surface_seed: int = 20261124
    oxide_seed: int = 20240531
    models: tuple[str, ...] = ("greenwood", "point")
    discretizations: tuple[str, ...] = ("mean_area", "expected", "asperities")
    surface: str = "gw"
    hurst: float = 0.8
    rms: float = 0.0
    short_wavelength: float = 0.0
    bandwidth_ratio: float = 8.0
    ensemble_grid: int = 256
    max_ensemble: int = 512
    max_pairs: int = 24
    model_realizations: int = 1024
    clean_error: float = 0.03
    oxide_error: float = 0.05
    spot_rule: str = "disc"
    device: str = "cpu"
    solver: str = "g2tom"
    hardness: float | None = None

    @property
    def pairs_cap(self) -> int:
        """Part 2's most pairs a load: ``max_pairs``, at most ``max_ensemble`` (each pair has its proxy)."""
        return min(self.max_pairs, self.max_ensemble)

    @property
    def pixel(self) -> float:
        """Pixel side of the main grid, m."""
        return 1.0 / math.sqrt(self.eta) / self.pixels_per_cell

    @property
    def side(self) -> float:
        """Side of the grid's window, m (the same for every grid)."""
        return self.n_grid * self.pixel

    @property
    def e_star(self) -> float:
        """Contact modulus E* = E / (2 (1 - nu^2)) of two equal bodies, Pa."""
        return self.E / (2.0 * (1.0 - self.nu**2))

    @property
    def force_scale(self) -> float:
        """E* sqrt(R* sigma^3) / 2, N: F' = F / force_scale (Eq. 25)."""
        return self.e_star * math.sqrt(self.radius * self.sigma**3) / 2.0

    @property
    def mu(self) -> float:
        """(8/3) eta sigma sqrt(2 R* beta): the Greenwood-Tripp group (:mod:`g2tom.physics.groups`)."""
        return 8.0 / 3.0 * self.eta * self.sigma * math.sqrt(2.0 * self.radius * self.beta)


def random_process_set(base: ValidationSet, rms: float, hurst: float = 0.8, bandwidth_ratio: float = 8.0) -> ValidationSet:
    """``base`` on a Gaussian self-affine surface instead of GW asperities, with g2tom's parameters
    from its spectrum: the closed-form moments m0, m2, m4 of the band and Nayak's summit statistics
    (:func:`g2tom.physics.surface_spectrum.summit_parameters`: summit sigma, eta, and beta by the
    paper's 0.737 / sqrt(m4)). The shortest wavelength is chosen so that the summit density is
    ``base.eta`` (the grid keeps its pixels per asperity spacing)."""
    from g2tom.physics.surface_spectrum import summit_parameters

    def summits(short: float):
        q_high = 2.0 * np.pi / short
        return summit_parameters(*surfaces.spectral_moments_closed_form(hurst, q_high / bandwidth_ratio, q_high, rms))

    short = math.sqrt(summits(1.0).eta / base.eta)  # eta scales as 1 / short^2
    s = summits(short)
    return dataclasses.replace(base, surface="random_process", sigma=s.sigma, eta=s.eta, beta=s.beta, hurst=hurst,
                               rms=rms, short_wavelength=short, bandwidth_ratio=bandwidth_ratio)


DEFAULT = ValidationSet()
#: ``--quick``: 256^2 at 8 pixels per asperity spacing (a window of 2.3 mm, which holds the
#: contact of both loads), two realizations, two loads, clean plus one oxidized case; part 2 on
#: 128^2 with at most 6 full-field realizations per load (3 of them pairs) and 64 of g2tom's.
QUICK = dataclasses.replace(DEFAULT, deltas=(1.0, -0.5), xi=(0.5,), lambdas=(5.0,), realizations=(0, 1),
                            n_grid=256, pixels_per_cell=8.0, convergence_grid=128, ensemble_grid=128,
                            max_ensemble=6, max_pairs=3, model_realizations=64)
#: The random-process surface's approaches: 8 evenly spaced from 1.75 to -3.5 sigma (its summits'),
#: the GW set's span of F' (0.067 .. 18.7; the GW set's approaches give F' 0.033 .. 15.4 there).
RANDOM_LOADS = tuple(float(d) for d in np.linspace(1.75, -3.5, 8))
#: The random-process surface (``--surface random_process``): the default set's oxide cases,
#: realizations and grids on a Gaussian self-affine surface (H 0.8, rms 20 um, a band of 8), its
#: summits as dense as the GW set's asperities (mu = 3.5: the summits are sharper), at
#: :data:`RANDOM_LOADS`.
RANDOM = dataclasses.replace(random_process_set(DEFAULT, rms=20e-6), deltas=RANDOM_LOADS)



def capped_contact(hardness: float) -> str:
    """The full field's contact capped at ``hardness`` (Pa), in words (the plan, validate.nc, the report)."""
    return (f"contact pressure capped at H = {hardness:.4g} Pa (a perfectly plastic surface on the elastic "
            "half-space, not an elasto-plastic volume)")


def with_hardness_of(vset: ValidationSet, config: str) -> ValidationSet:
    """``vset`` with the hardness (Pa) of the validated scenario ``config`` (its ``material.hardness``,
    None where it has none: the elastic full field).

    Raises
    ------
    ConfigError
        If the scenario has a hardness and the set's solver is tamaas' (only g2tom's solver caps the
        pressure).
    """
    hardness = load_scenario(config).material.hardness
    if hardness is not None and vset.solver == "tamaas":
        raise ConfigError(f"--config {config!r} sets material.hardness = {hardness:g} Pa: the hardness-capped full "
                          "field runs on g2tom's solver only; leave out --solver tamaas")
    return dataclasses.replace(vset, hardness=hardness)


def surface_stream(vset: ValidationSet, realization: int) -> np.random.Generator:
    """The random stream of one surface: ``SeedSequence(surface_seed, spawn_key=(realization,))``."""
    seq = np.random.SeedSequence(vset.surface_seed, spawn_key=(int(realization),))
    return np.random.Generator(np.random.PCG64(seq))


def rough_sphere(vset: ValidationSet, realization: int, n: int, side: float | None = None) -> np.ndarray:
    """Heights (m, (n, n)) of the sphere plus the realization's rough surface on an n x n grid of
    a centred window of ``side`` (m, at most and by default the set's window ``vset.side``).

    The surface is one per realization over the set's window (GW asperities drawn once over it,
    the random process periodic over it), independent of ``n`` and ``side``, so every grid and
    window samples the same surface.
    """
    side = vset.side if side is None else side
    if not 0 < side <= vset.side * (1 + 1e-12):
        raise ValueError(f"side = {side:g} m is out of range: must be in (0, {vset.side:g}] (the set's window)")
    pixel = side / n
    if vset.surface == "random_process":
        from g2tom.physics.surface_spectrum import summit_parameters

        q_high = 2.0 * np.pi / vset.short_wavelength
        q_low = q_high / vset.bandwidth_ratio
        rough = surfaces.random_process(n, pixel, vset.hurst, q_low, q_high, vset.rms,
                                        surface_stream(vset, realization), period=vset.side)
        # heights from the summits' mean plane, g2tom's reference (Nayak: 4 sqrt(m0 / (pi alpha)) above the surface's)
        moments = surfaces.spectral_moments_closed_form(vset.hurst, q_low, q_high, vset.rms)
        return rough - summit_parameters(*moments).summit_mean_height + surfaces.sphere(n, pixel, vset.radius)
    asperities = surfaces.gw_asperities(vset.side, vset.eta, vset.sigma, vset.beta, surface_stream(vset, realization))
    rough = surfaces.gw_heights(asperities, n, pixel, floor=-FLOOR_SIGMAS * vset.sigma)
    return rough + surfaces.sphere(n, pixel, vset.radius)


def scene_overrides(vset: ValidationSet, realizations: int) -> dict[str, object]:
    """The settings that make a g2tom scenario the validation scene: materials, roughness, sphere,
    loads, oxide cases and seed, and a fixed ensemble of ``realizations`` oxide fields."""
    return {
        "material.E": vset.E, "material.nu": vset.nu, "material.rho": vset.rho,
        "roughness.sigma": vset.sigma, "roughness.eta": vset.eta, "roughness.beta": vset.beta,
        "indenter.radius": vset.radius,
        "loading.delta_max": max(vset.deltas), "loading.delta_min": min(vset.deltas),
        "loading.n_delta": len(vset.deltas),
        "oxide.xi": list(vset.xi), "oxide.lambda": list(vset.lambdas), "oxide.seed": vset.oxide_seed,
        "oxide.ensemble": "fixed", "oxide.n_realizations": max(2, int(realizations)),
    }


def scenario_of(vset: ValidationSet, config: str, overrides: dict[str, object]) -> ResolvedScenario:
    """``config`` (a bundled scenario or a TOML file) with ``overrides``, its domains resolved; its
    load steps checked to be the set's approaches."""
    scenario = resolve(load_scenario(config, overrides))
    expected = np.asarray(vset.deltas) * vset.sigma
    if not np.allclose(scenario.deltas, expected, rtol=1e-12, atol=0):
        raise ValueError(f"deltas = {vset.deltas} must be evenly spaced, lightest load first (g2tom's load steps)")
    return scenario


def g2tom_scenario(vset: ValidationSet, model: str, spots: str) -> ResolvedScenario:
    """Part 1's g2tom scenario of the validation scene: Greenwood-Tripp's contact model (whatever
    the default's), one spot discretization, the spots' centre rule and one ``cube.model``."""
    overrides = {**scene_overrides(vset, max(vset.realizations) + 1), "contact.model": "greenwood_tripp",
                 "oxide.spot_rule": "centre", "cube.model": model, "contact.spots": spots}
    return scenario_of(vset, "paper", overrides)


#: The contact's extent: the largest radius where GT's area fraction is at least this fraction of
#: its peak; the reference grid's half side must reach it at every load.
EXTENT_FRACTION = 1e-4


def case_variable(name: str, data: np.ndarray) -> tuple[tuple[str, ...], np.ndarray, dict[str, str]]:
    """``(dims, data, attrs)`` of g2tom's resistances on a validation scene (``resistance_clean``,
    ``resistance``), as the metadata registry declares them (``reference.cases``)."""
    declared = entry(f"reference.cases.{name}")
    return declared.dims, data, declared.attrs()


def contact_extent(contact: xr.Dataset) -> xr.DataArray:
    """The Greenwood–Tripp contact's extent per load step (delta), m (see :data:`EXTENT_FRACTION`)."""
    fraction = contact["area_fraction"].transpose("delta", "r").values
    r = contact["r"].values
    extent = [r[np.flatnonzero(a >= EXTENT_FRACTION * a.max())[-1]] for a in fraction]
    declared = entry("reference.cases.contact_extent")
    return xr.DataArray(np.asarray(extent), dims=declared.dims, attrs=declared.attrs(fraction=f"{EXTENT_FRACTION:g}"))


def g2tom_resistances(vset: ValidationSet, model: str, spots: str) -> xr.Dataset:
    """g2tom's cube of the scene: ``force`` (delta), ``resistance_clean`` (delta) and
    ``resistance`` (xi, lambda, delta, realization) with the set's realizations, and
    ``contact_extent`` (delta, m, :func:`contact_extent`)."""
    scenario = g2tom_scenario(vset, model, spots)
    contact = contact_stage.build(scenario)
    oxide = oxide_stage.build(scenario)
    cube = cube_stage.build(scenario, contact, oxide).isel(realization=list(vset.realizations))
    cube["contact_extent"] = contact_extent(contact)
    return cube
