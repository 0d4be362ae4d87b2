"""The solver contract and the solvers by name: `make_solver("lut", profile, options)`.

Every solver answers two questions about the light in one `OpticalProfile` (`Solver`):

    sky_radiance(position, view_directions, sun_direction)  -> S + (n_wl,)  [W m^-2 sr^-1 nm^-1]
    transmittance(position, directions, distance_m=inf)     -> S + (n_wl,)  [-]

on the profile's wavelengths, `solver.profile.wavelengths_nm`: the last axis of every spectral
result. Positions are planet-centred [m] (3,) or broadcast against the directions (..., 3) to
the shape S; observers stand on the ground, in the air or in space (rays that miss the
atmosphere see no sky and lose no light). `transmittance` with the default infinite distance is
the light of a source (the sun, the moon, a star) along the directions: 0 where the ray meets
the planet.

What only some solvers can do is a capability protocol, asked for with `isinstance`:

    solver               SurfaceSolver  SurfaceRadianceSolver  NoisySolver  TableSolver
    lut                  yes            yes                    -            yes
    single               yes            -                      -            -
    montecarlo           -              -                      yes          -
    hillaire             yes            -                      -            -
    schuler              -              -                      -            -
    bruneton-simplified  -              -                      -            -
    cie                  -              -                      -            -
    preetham             -              -                      -            -

    SurfaceSolver          ground_irradiance, aerial_perspective
    SurfaceRadianceSolver  surface_radiance (albedo maps, terrain)
    NoisySolver            sky_radiance_with_error
    TableSolver            tables (eclipse optics, lowest sun)

Where a solver answers at all is its `domain` (`SolverDomain`, read by `solver_domain`): the
analytic skies fitted to Earth's ground ("cie", "preetham") refuse other planets, observers
off the ground and the sun below the horizon with an InputError; the others declare none
(`ANYWHERE`).

`tests/transport/test_solver_conformance.py` runs every registered solver through the same
checks (shapes, units, broadcasting, wavelength last, finite at the horizon) and calls the
members of every protocol it satisfies.

A new solver is one class and one registration: write the class in `transport/<name>.py` (the
`Solver` members and those of the capabilities it has; its module docstring gives the model,
the sources and the accuracy), then register its factory at the end of this module:

    @register_solver("name", "one line for errors and listings")
    def _name(profile: OpticalProfile, options: SolverOptions) -> NameSolver:
        return NameSolver(profile, n_samples=options.n_samples)

`make_solver`, `SOLVERS`, `--solver name` and the conformance test then know it.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Protocol, runtime_checkable

import numpy as np
from numpy.typing import ArrayLike

from skyscatter.atmosphere.model import DEFAULT_SCATTERING_ORDERS, OpticalProfile
from skyscatter.errors import InputError
from skyscatter.transport.bruneton_simplified import BrunetonSimplifiedSolver, SimplifiedTables
from skyscatter.transport.cache import TableCache
from skyscatter.transport.cie_sky import DEFAULT_SKY_TYPE, CieSkySolver
from skyscatter.transport.ground_sky import ANYWHERE, SolverDomain, solver_domain
from skyscatter.transport.hillaire import HillaireSolver
from skyscatter.transport.lut_solver import LutSolver
from skyscatter.transport.monte_carlo import MonteCarloSolver
from skyscatter.transport.preetham import DEFAULT_TURBIDITY, PreethamSolver
from skyscatter.transport.schuler import SchulerSolver
from skyscatter.transport.single_scattering import SingleScatteringSolver
from skyscatter.transport.table_store import cached_tables
from skyscatter.transport.tables import AtmosphereTables, TableResolution

__all__ = [
    "ANYWHERE",
    "SOLVERS",
    "NoisySolver",
    "Solver",
    "SolverFactory",
    "SolverDomain",
    "SolverOptions",
    "SurfaceRadianceSolver",
    "SurfaceSolver",
    "TableSolver",
    "make_solver",
    "register_solver",
    "solver_domain",
]


@runtime_checkable
class Solver(Protocol):
    """What every solver answers, for one atmosphere on its wavelengths.

    name : str
        The name it is registered under (`SOLVERS`).
    profile : OpticalProfile
        The atmosphere; `profile.wavelengths_nm` (n_wl,) [nm] is the spectral grid of every
        result, `profile.n_wavelengths` its length.
    """

    name: str
    profile: OpticalProfile

    def sky_radiance(self, position: ArrayLike, view_directions: ArrayLike,
                     sun_direction: ArrayLike,
                     progress: Callable[[int], None] | None = None) -> np.ndarray:
        """Diffuse spectral radiance [W m^-2 sr^-1 nm^-1], shape S + (n_wl,), seen from
        `position` (planet-centred [m], (3,) or broadcastable to the directions) along unit
        `view_directions` (..., 3) broadcast to S + (3,), with the sun along unit
        `sun_direction` (3,) (any height, below the horizon included); without the sun disk's
        own radiance. `progress(n)`, when given, is called with the number of rays done."""
        ...

    def transmittance(self, position: ArrayLike, directions: ArrayLike,
                      distance_m: ArrayLike = np.inf) -> np.ndarray:
        """Transmittance [-] in [0, 1], shape S + (n_wl,), from `position` along unit
        `directions` (shapes as `sky_radiance`) over `distance_m` [m] (broadcastable to S;
        inf: out of the atmosphere, and 0 when the planet is in the way)."""
        ...


@runtime_checkable
class SurfaceSolver(Protocol):
    """A solver that lights surfaces: the irradiance on the ground and the air between the
    observer and a point (`LutSolver.aerial_perspective` has the full meaning)."""

    def ground_irradiance(self, position: ArrayLike, sun_direction: ArrayLike
                          ) -> tuple[np.ndarray, np.ndarray]:
        """(direct, diffuse) spectral irradiance [W m^-2 nm^-1], each (n_wl,), on a horizontal
        surface at `position` (planet-centred [m], (3,)) with the sun along `sun_direction`
        (3,). Direct: E_sun T_sun max(mu_s, 0) times the visible part of the disk."""
        ...

    def aerial_perspective(self, position: ArrayLike, points: ArrayLike,
                           sun_direction: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
        """(inscattered [W m^-2 sr^-1 nm^-1], transmittance [-]), each S + (n_wl,), between the
        observer at `position` (3,) and `points` (S + (3,)) [m]: an object at p with radiance
        L_p is seen as T L_p + inscattered."""
        ...


@runtime_checkable
class SurfaceRadianceSolver(Protocol):
    """A solver that shades Lambertian surfaces of their own albedo and orientation (albedo
    maps, terrain: `render.surfaces`)."""

    def surface_radiance(self, position: ArrayLike, points: ArrayLike, normals: ArrayLike,
                         albedo: ArrayLike, sun_direction: ArrayLike, *,
                         lit: ArrayLike | None = None) -> np.ndarray:
        """Radiance [W m^-2 sr^-1 nm^-1] (n, n_wl) reaching the observer at `position` (3,)
        from surfaces at `points` (n, 3) facing unit `normals` (n, 3) with `albedo` ((n, n_wl)
        or (n_wl,)), in sunlight where `lit` (n,): L_in + T albedo / pi (E_sun + E_sky)."""
        ...


@runtime_checkable
class NoisySolver(Protocol):
    """A solver whose sky radiance is a statistical estimate (Monte Carlo)."""

    def sky_radiance_with_error(self, position: ArrayLike, view_directions: ArrayLike,
                                sun_direction: ArrayLike,
                                progress: Callable[[int], None] | None = None
                                ) -> tuple[np.ndarray, np.ndarray]:
        """(mean, standard error of the mean) of the sky radiance [W m^-2 sr^-1 nm^-1], each
        S + (n_wl,); arguments as `Solver.sky_radiance`, whose answer is the mean."""
        ...


@runtime_checkable
class TableSolver(Protocol):
    """A solver that answers from precomputed tables (their transmittance serves the eclipse
    optics; below their lowest sun, `tables.min_cos_sun_zenith`, the sunlit sky is left out)."""

    tables: AtmosphereTables


@dataclass(frozen=True)
class SolverOptions:
    """What the solvers may be given; each takes the options that concern it.

    n_samples      ray-marching samples per view ray ("single"); paths per view ray and
                   wavelength ("montecarlo")
    orders         scattering orders of the tables ("lut")
    resolution     table sizes ("lut"; None: Bruneton 2017's)
    cache          where tables are kept between runs ("lut"; None: compute, keep in memory)
    force          recompute the tables even when cached ("lut")
    progress       callable(done, total, stage) during the precomputation ("lut")
    log            callable(message): one line on where the tables came from ("lut")
    seed           seed of the random numbers ("montecarlo")
    sky_type       CIE standard general sky type 1-15 ("cie"; 12: the CIE clear sky)
    turbidity      Linke-style turbidity of the analytic sky ("preetham"; 2.5: clear)
    """

    n_samples: int = 64
    orders: int = DEFAULT_SCATTERING_ORDERS
    resolution: TableResolution | None = None
    cache: TableCache | None = None
    force: bool = False
    progress: Callable[[int, int, str], None] | None = None
    log: Callable[[str], None] | None = None
    seed: int = 0
    sky_type: int = DEFAULT_SKY_TYPE
    turbidity: float = DEFAULT_TURBIDITY


SolverFactory = Callable[[OpticalProfile, SolverOptions], Solver]

# name -> one-line description, in the order of registration (`register_solver`)
SOLVERS: dict[str, str] = {}
_FACTORIES: dict[str, SolverFactory] = {}


def register_solver(name: str, description: str) -> Callable[[SolverFactory], SolverFactory]:
    """Decorator that makes `factory(profile, options) -> Solver` the solver `name` of
    `make_solver`, described by `description` in `SOLVERS`. A name is registered once."""
    def register(factory: SolverFactory) -> SolverFactory:
        if name in _FACTORIES:
            raise ValueError(f"a solver named {name!r} is registered already")
        _FACTORIES[name] = factory
        SOLVERS[name] = description
        return factory
    return register


def make_solver(name: str, profile: OpticalProfile, options: SolverOptions | None = None
                ) -> Solver:
    """A solver of `profile` by name (`SOLVERS`); InputError listing the names otherwise."""
    factory = _FACTORIES.get(name) if isinstance(name, str) else None
    if factory is None:
        raise InputError(f"unknown solver {name!r}; available: {', '.join(SOLVERS)}",
                         key="solver", value=name, allowed=", ".join(SOLVERS))
    return factory(profile, options or SolverOptions())


# The solvers -------------------------------------------------------------------------------

@register_solver("lut", "precomputed tables with multiple scattering (Bruneton & Neyret), "
                        "orders from the config ([tables] orders), cached on disk")
def _lut(profile: OpticalProfile, options: SolverOptions) -> LutSolver:
    tables = cached_tables(profile, options.resolution, options.orders, cache=options.cache,
                           force=options.force, progress=options.progress, log=options.log)
    return LutSolver(profile, tables=tables)


@register_solver("single", "single scattering + one Lambertian ground bounce, ray marched "
                           "(no tables): the independent check")
def _single(profile: OpticalProfile, options: SolverOptions) -> SingleScatteringSolver:
    return SingleScatteringSolver(profile, n_samples=options.n_samples)


@register_solver("montecarlo", "backward Monte Carlo path tracing, all orders, exact up to "
                               "noise (slow; n_samples paths per ray and wavelength): the "
                               "reference")
def _montecarlo(profile: OpticalProfile, options: SolverOptions) -> MonteCarloSolver:
    return MonteCarloSolver(profile, n_samples=options.n_samples, seed=options.seed)


@register_solver("hillaire", "Hillaire 2020: small tables in under a second, orders >= 2 from "
                             "an isotropic approximation, a sky-view table per observer (fast, "
                             "approximate)")
def _hillaire(profile: OpticalProfile, options: SolverOptions) -> HillaireSolver:
    return HillaireSolver(profile, n_samples=options.n_samples)


@register_solver("schuler", "single scattering with Schüler's analytic Chapman-function "
                            "transmittances (GPU Pro 3, 2012): no precomputation")
def _schuler(profile: OpticalProfile, options: SolverOptions) -> SchulerSolver:
    return SchulerSolver(profile, n_samples=options.n_samples)


@register_solver("bruneton-simplified", "single scattering from a transmittance and a 4-D "
                                        "single-scattering table only (Bruneton & Neyret 2008 "
                                        "without the multiple-scattering tables)")
def _bruneton_simplified(profile: OpticalProfile, options: SolverOptions
                         ) -> BrunetonSimplifiedSolver:
    tables = cached_tables(profile, options.resolution, 1, cache=options.cache,
                           force=options.force, progress=options.progress, log=options.log)
    return BrunetonSimplifiedSolver(
        profile, SimplifiedTables.from_tables(tables, profile.sun_angular_radius_rad))


@register_solver("cie", "CIE standard general sky (ISO 15469), sky_type 1-15, scaled to the "
                        "\"lut\" zenith: Earth, ground, sun up")
def _cie(profile: OpticalProfile, options: SolverOptions) -> CieSkySolver:
    return CieSkySolver(profile, lambda: _lut(profile, options), sky_type=options.sky_type)


@register_solver("preetham", "Preetham, Shirley & Smits 1999 analytic daylight of a turbidity: "
                             "Earth, ground, sun up")
def _preetham(profile: OpticalProfile, options: SolverOptions) -> PreethamSolver:
    return PreethamSolver(profile, turbidity=options.turbidity)
