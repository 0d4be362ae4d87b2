"""The solvers by name, so that the CLI and `validate` can pick one: `make_solver("lut", ...)`.

Every solver answers `sky_radiance(position, view_directions, sun_direction)`,
`transmittance(position, directions, distance_m)`, `ground_irradiance(position,
sun_direction)` and `aerial_perspective(position, points, sun_direction)` for one
`OpticalProfile`. `transmittance` with the default infinite distance is the light of a source
(the sun, the moon, a star) along the directions: 0 where the ray meets the planet.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from skyscatter.atmosphere.model import DEFAULT_SCATTERING_ORDERS, OpticalProfile
from skyscatter.errors import InputError
from skyscatter.transport.cache import TableCache
from skyscatter.transport.lut_solver import LutSolver
from skyscatter.transport.monte_carlo import MonteCarloSolver
from skyscatter.transport.single_scattering import SingleScatteringSolver
from skyscatter.transport.table_store import cached_tables
from skyscatter.transport.tables import TableResolution

__all__ = ["SOLVERS", "SolverOptions", "make_solver"]

SOLVERS = {
    "lut": "precomputed tables with multiple scattering (Bruneton & Neyret), orders from the "
           "config (4 for Earth), cached on disk",
    "single": "single scattering + one Lambertian ground bounce, ray marched (no tables): the "
              "independent check",
    "montecarlo": "backward Monte Carlo path tracing, all orders, exact up to noise (slow; "
                  "n_samples paths per ray and wavelength): the reference",
}


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
    """

    n_samples: int = 64
    orders: int = DEFAULT_SCATTERING_ORDERS
    resolution: TableResolution | None = None
    cache: TableCache | None = None
    force: bool = False
    progress: Callable[[int, int, str], None] | None = None
    log: Callable[[str], None] | None = None
    seed: int = 0


def make_solver(name: str, profile: OpticalProfile, options: SolverOptions | None = None
                ) -> SingleScatteringSolver | LutSolver | MonteCarloSolver:
    """A solver of `profile` by name (`SOLVERS`)."""
    options = options or SolverOptions()
    if name == "single":
        return SingleScatteringSolver(profile, n_samples=options.n_samples)
    if name == "lut":
        tables = cached_tables(profile, options.resolution, options.orders,
                               cache=options.cache, force=options.force,
                               progress=options.progress, log=options.log)
        return LutSolver(profile, tables=tables)
    if name == "montecarlo":
        return MonteCarloSolver(profile, n_samples=options.n_samples, seed=options.seed)
    raise InputError(f"unknown solver {name!r}; available: {', '.join(SOLVERS)}",
                     key="solver", value=name, allowed=", ".join(SOLVERS))
