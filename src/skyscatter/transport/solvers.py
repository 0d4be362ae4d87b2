"""The solvers by name, so that the CLI and `validate` can pick one: `make_solver("single", ...)`.

Every solver answers `sky_radiance(position, view_directions, sun_direction)`,
`transmittance(position, directions, distance_m)` and `ground_irradiance(position,
sun_direction)` for one `OpticalProfile`.
"""

from __future__ import annotations

from skyscatter.atmosphere.model import OpticalProfile
from skyscatter.errors import InputError
from skyscatter.transport.lut_solver import LutSolver
from skyscatter.transport.single_scattering import SingleScatteringSolver

__all__ = ["SOLVERS", "make_solver"]

SOLVERS = {
    "single": (SingleScatteringSolver, "single scattering + one Lambertian ground bounce, "
                                       "ray marched (no tables)"),
    "lut": (LutSolver, "precomputed tables with multiple scattering (Bruneton & Neyret), "
                       "4 orders by default"),
}


def make_solver(name: str, profile: OpticalProfile,
                **options) -> SingleScatteringSolver | LutSolver:
    """A solver of `profile` by name (`SOLVERS`); options go to its constructor."""
    if name not in SOLVERS:
        raise InputError(f"unknown solver {name!r}; available: {', '.join(SOLVERS)}",
                         key="solver", value=name, allowed=", ".join(SOLVERS))
    return SOLVERS[name][0](profile, **options)
