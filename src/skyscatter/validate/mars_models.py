"""What the Mars validation cases share: the four dust models of Meyran 2022, loaded with a note
for those that are missing, their dusty variants, their solvers, and the geometry and curve
helpers of the comparisons.

The models are the four that Meyran (2022, M.Sc. thesis, Hochschule Hannover; §3, §5) compares
with Mars Pathfinder and the Mars Exploration Rovers: Collienne et al. (2013), Costa et al.
(2020), "Blue Moon's" (Mie dust after Ehlers et al. 2014) and the hybrid of the last two. Each
is a preset whose dust constituent is called "dust"; a preset that does not exist (yet) is
skipped, and the cases say so in their notes instead of failing.

Geometry: an observer on the ground at the north pole of the planet, whose east-north-up frame
is the world frame (`transport.single_scattering.observer_position`); directions are given by
elevation above the horizon and azimuth, the sun at azimuth 0.

    cos(gamma) = sin(e_v) sin(e_s) + cos(e_v) cos(e_s) cos(a_v - a_s)

is the angular distance gamma between a view (e_v, a_v) and the sun (e_s, a_s) (spherical law
of cosines); on the sun's almucantar (e_v = e_s = e) it inverts to
cos(a) = (cos(gamma) - sin^2 e) / cos^2 e.

Radiance: the cases use the Monte Carlo solver (`monte_carlo_solver`) for the sky, and the
precomputed tables (`mars_solver`) only to report how far they are from it: the forward peak
of Mie dust is narrower than the tables' angular cells (docs/validation.md, Mars).

Public names: `DUST`, `MARS_MODELS`, `MODEL_COLOURS`, `MODEL_LABELS`, `SCAN_MODEL`,
`MarsModels`, `load_models`, `dust_scaled`, `vertical_optical_depths`, `dust_optical_depth`,
`orders_for`, `framework_reading`, `monte_carlo_solver`, `mars_solver`, `sky_direction`,
`angle_from_sun_deg`, `almucantar_azimuth_deg`, `sky_chromaticity`, `half_radius_deg`,
`dust_factor_for_transmittance`.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field, replace

import numpy as np
from numpy.typing import ArrayLike

from skyscatter.atmosphere.config import PRESETS_DIR, load_atmosphere
from skyscatter.atmosphere.model import Atmosphere
from skyscatter.atmosphere.variants import scaled_constituent
from skyscatter.errors import SkyscatterError
from skyscatter.spectrum.colour import spectral_to_xyz, xy_chromaticity
from skyscatter.spectrum.tabulated import SpectralParameter
from skyscatter.transport.geometry import local_frame_directions
from skyscatter.transport.lut_solver import LutSolver
from skyscatter.transport.monte_carlo import MonteCarloSolver
from skyscatter.validate.common import table_solver
from skyscatter.validate.optical_depth import vertical_optical_depth
from skyscatter.validate.report import ValidationSettings

__all__ = [
    "DUST",
    "MARS_MODELS",
    "MODEL_COLOURS",
    "MODEL_LABELS",
    "SCAN_MODEL",
    "MarsModels",
    "almucantar_azimuth_deg",
    "angle_from_sun_deg",
    "dust_factor_for_transmittance",
    "dust_optical_depth",
    "dust_scaled",
    "framework_reading",
    "half_radius_deg",
    "load_models",
    "mars_solver",
    "monte_carlo_solver",
    "orders_for",
    "sky_chromaticity",
    "sky_direction",
    "vertical_optical_depths",
]

# The four models of Meyran 2022, in the thesis's order.
MARS_MODELS = ("mars-collienne", "mars-costa", "mars-bluemoon", "mars-hybrid")
MODEL_LABELS = {"mars-collienne": "Collienne", "mars-costa": "Costa",
                "mars-bluemoon": "Blue Moon's", "mars-hybrid": "hybrid"}
MODEL_COLOURS = {"mars-collienne": "tab:blue", "mars-costa": "tab:green",
                 "mars-bluemoon": "tab:purple", "mars-hybrid": "tab:red"}  # the same in every plot
# The model whose dust amount the cases scan: the thesis's best (Meyran 2022 §5.1.2, Fig. 5.9).
SCAN_MODEL = "mars-hybrid"
DUST = "dust"  # the dust constituent's name in all four presets

# Scattering orders of a dusty variant: the smallest n whose truncation error is < 0.5 % was
# measured as 6 at vertical optical depth 0.20 at 550 nm (mars-costa) and 13 at 0.90 (mars-costa,
# dust x 5) (docs/physics/orders.md); n = round(4 + 10 tau_550) runs through both and is
# extrapolated above them.
ORDERS_AT_ZERO_DEPTH = 4.0
ORDERS_PER_OPTICAL_DEPTH = 10.0
MAX_ORDERS = 40


@dataclass
class MarsModels:
    """The models that could be loaded (name -> Atmosphere, in MARS_MODELS order) and those
    skipped (name -> why)."""

    atmospheres: dict[str, Atmosphere] = field(default_factory=dict)
    missing: dict[str, str] = field(default_factory=dict)

    @property
    def names(self) -> list[str]:
        return list(self.atmospheres)

    def notes(self) -> list[str]:
        """One note per skipped model, for `CaseResult.notes`."""
        return [f"{name} skipped: {why}." for name, why in self.missing.items()]


def load_models(names: Sequence[str] = MARS_MODELS) -> MarsModels:
    """Load the presets `names`; one that does not exist or does not load is recorded in
    `missing` with the reason (the cases report it in a note, not as a failure)."""
    models = MarsModels()
    for name in names:
        if not (PRESETS_DIR / f"{name}.toml").exists():
            models.missing[name] = "no such preset yet (src/skyscatter/atmosphere/presets/)"
            continue
        try:
            models.atmospheres[name] = load_atmosphere(name)
        except SkyscatterError as error:
            models.missing[name] = f"the preset does not load ({error})"
    return models


def dust_scaled(atmosphere: Atmosphere, factor: float) -> Atmosphere:
    """`atmosphere` with `factor` times its dust density, named 'NAME, dust x FACTOR' and with
    the scattering orders its optical depth needs (`orders_for`)."""
    if factor == 1.0:
        return atmosphere
    scaled = scaled_constituent(atmosphere, DUST, factor,
                                label=f"{atmosphere.name}, dust x{factor:g}")
    # the variant keeps the preset's orders; a dustier one needs more
    return replace(scaled, scattering_orders=max(atmosphere.scattering_orders,
                                                 orders_for(scaled)))


def vertical_optical_depths(atmosphere: Atmosphere, wavelengths_nm: ArrayLike
                            ) -> dict[str, np.ndarray]:
    """Vertical extinction optical depth of each constituent, ground to top, at
    `wavelengths_nm` treated monochromatically (`validate.optical_depth.vertical_optical_depth`).

    Returns
    -------
    dict
        Constituent name -> ndarray, shape (n_wl,). [-]
    """
    wavelengths = np.atleast_1d(np.asarray(wavelengths_nm, dtype=np.float64))
    profile = atmosphere.optical_profile(wavelengths, monochromatic=True)
    depths = vertical_optical_depth(profile)
    return {name: depths[c] for c, name in enumerate(profile.names)}


def dust_optical_depth(atmosphere: Atmosphere, wavelength_nm: float) -> float:
    """Vertical extinction optical depth of the dust alone at `wavelength_nm` [nm]. [-]"""
    return float(vertical_optical_depths(atmosphere, [wavelength_nm])[DUST][0])


def orders_for(atmosphere: Atmosphere) -> int:
    """Scattering orders for a (dusty) Mars: round(4 + 10 tau), tau the total vertical optical
    depth at 550 nm, capped at `MAX_ORDERS` (see `ORDERS_PER_OPTICAL_DEPTH`)."""
    tau = float(sum(vertical_optical_depths(atmosphere, [550.0]).values())[0])
    return int(min(MAX_ORDERS, round(ORDERS_AT_ZERO_DEPTH + ORDERS_PER_OPTICAL_DEPTH * tau)))


def framework_reading(atmosphere: Atmosphere, constituent: str = "gas") -> Atmosphere | None:
    """`atmosphere` with the scattering table of `constituent` in reverse wavelength order,
    named 'NAME, CONSTITUENT reversed'; None when it has no tabulated scattering.

    For Collienne's preset: its "inverted Rayleigh" (5.75, 13.57, 19.918) 1e-6 m^-1 at (440,
    550, 680) nm read as (680, 550, 440) nm, the order in which the thesis's framework config
    lists Costa's coefficients on the same `RayleighScattering: Constant` line (Meyran 2022
    App. A.1.2): a test of whether the thesis computed Collienne's sky with that reading.
    """
    for k, c in enumerate(atmosphere.constituents):
        scattering = getattr(c.optics, "scattering", None)
        if c.name != constituent or not isinstance(scattering, SpectralParameter) \
                or scattering.wavelengths_nm is None:
            continue
        reversed_table = SpectralParameter(tuple(reversed(scattering.values)),
                                           scattering.wavelengths_nm)
        changed = replace(c, optics=replace(c.optics, scattering=reversed_table))
        constituents = atmosphere.constituents[:k] + (changed,) + atmosphere.constituents[k + 1:]
        return replace(atmosphere, constituents=constituents,
                       name=f"{atmosphere.name}, {constituent} reversed")
    return None


def mars_solver(atmosphere: Atmosphere, wavelengths_nm: ArrayLike,
                settings: ValidationSettings, monochromatic: bool = False,
                orders: int | None = None) -> LutSolver:
    """The table solver of `atmosphere` on `wavelengths_nm` [nm] (cell averages, or each
    wavelength alone when `monochromatic`) with the atmosphere's orders (or `orders`), tables
    from the run's cache (`validate.common.table_solver`)."""
    wavelengths = np.atleast_1d(np.asarray(wavelengths_nm, dtype=np.float64))
    n = atmosphere.scattering_orders if orders is None else int(orders)
    settings.log(f"{atmosphere.name}: tables ({n} orders, {wavelengths.size} wavelengths)")
    profile = atmosphere.optical_profile(wavelengths, monochromatic=monochromatic)
    return table_solver(atmosphere, profile, settings, orders=n)


def monte_carlo_solver(atmosphere: Atmosphere, wavelengths_nm: ArrayLike,
                       settings: ValidationSettings, n_samples: int,
                       monochromatic: bool = False) -> MonteCarloSolver:
    """The Monte Carlo solver of `atmosphere` on `wavelengths_nm` [nm] with `n_samples` paths
    per view ray and wavelength and the run's seed: the cases' reference for the sky radiance.

    For a few view directions it is cheaper than precomputing tables, and it has no angular
    cells to smear the forward peak of Mie dust (the Pathfinder case reports the tables'
    difference)."""
    profile = atmosphere.optical_profile(np.atleast_1d(np.asarray(wavelengths_nm, float)),
                                         monochromatic=monochromatic)
    return MonteCarloSolver(profile, n_samples=n_samples, seed=settings.seed)


def sky_direction(elevation_deg: ArrayLike, azimuth_deg: ArrayLike = 0.0) -> np.ndarray:
    """Unit vectors (..., 3) in the observer's east-north-up frame from elevation above the
    horizon and azimuth (from north towards east) [deg]; inputs broadcast."""
    elevation = np.asarray(elevation_deg, dtype=np.float64)
    azimuth = np.asarray(azimuth_deg, dtype=np.float64)
    return local_frame_directions(np.radians(90.0 - elevation), np.radians(azimuth))


def angle_from_sun_deg(view_elevation_deg: ArrayLike, view_azimuth_deg: ArrayLike,
                       sun_elevation_deg: ArrayLike, sun_azimuth_deg: ArrayLike = 0.0
                       ) -> np.ndarray:
    """Angular distance gamma [deg] between a view and the sun, both given by elevation and
    azimuth [deg] (spherical law of cosines, module docstring); inputs broadcast."""
    ev, av, es, az = (np.radians(np.asarray(v, dtype=np.float64)) for v in
                      (view_elevation_deg, view_azimuth_deg, sun_elevation_deg, sun_azimuth_deg))
    cos_gamma = np.sin(ev) * np.sin(es) + np.cos(ev) * np.cos(es) * np.cos(av - az)
    return np.degrees(np.arccos(np.clip(cos_gamma, -1.0, 1.0)))


def almucantar_azimuth_deg(angle_from_sun_deg: ArrayLike, elevation_deg: float) -> np.ndarray:
    """Azimuth from the sun [deg] of the point on the sun's almucantar (elevation
    `elevation_deg` [deg], that of the sun) at angular distance `angle_from_sun_deg` [deg]:
    cos(a) = (cos(gamma) - sin^2 e) / cos^2 e, defined for gamma <= 180 - 2 e."""
    gamma = np.radians(np.asarray(angle_from_sun_deg, dtype=np.float64))
    e = math.radians(elevation_deg)
    if np.any(np.degrees(gamma) > 180.0 - 2.0 * elevation_deg + 1e-9):
        raise ValueError(f"angles from the sun above {180.0 - 2.0 * elevation_deg:g} deg are "
                         f"not on the almucantar at elevation {elevation_deg:g} deg")
    cos_a = (np.cos(gamma) - math.sin(e) ** 2) / math.cos(e) ** 2
    return np.degrees(np.arccos(np.clip(cos_a, -1.0, 1.0)))


def sky_chromaticity(solver: LutSolver | MonteCarloSolver, views: ArrayLike, sun: ArrayLike,
                     altitude_m: float = 0.0) -> np.ndarray:
    """CIE 1931 x, y (..., 2) of the sky radiance seen from the ground (or `altitude_m` [m])
    along unit `views` (..., 3) with the sun along unit `sun` (3,)
    (`spectrum.colour.spectral_to_xyz` of the solver's spectral radiance)."""
    profile = solver.profile
    origin = np.array([0.0, 0.0, profile.bottom_radius_m + altitude_m])
    radiance = solver.sky_radiance(origin, np.asarray(views, dtype=np.float64), sun)
    return xy_chromaticity(spectral_to_xyz(radiance, profile.wavelengths_nm))


def half_radius_deg(angles_deg: ArrayLike, values: ArrayLike, near_deg: float,
                    far_deg: float) -> float:
    """The angle [deg] where `values` (sampled at ascending `angles_deg`, e.g. a chromaticity
    x against the angle from the sun) first reaches halfway between its values at `near_deg`
    and `far_deg` (linear interpolation), searching outwards from `near_deg`; NaN when the
    values at the two ends are equal or the curve never gets there before `far_deg`."""
    angles = np.asarray(angles_deg, dtype=np.float64)
    v = np.asarray(values, dtype=np.float64)
    v_near, v_far = float(np.interp(near_deg, angles, v)), float(np.interp(far_deg, angles, v))
    if v_near == v_far:
        return math.nan
    # progress towards the far value, 0 at near and 1 at far; the first crossing of 0.5
    inside = (angles > near_deg) & (angles <= far_deg)
    xs = np.concatenate([[near_deg], angles[inside]])
    ps = (np.concatenate([[v_near], v[inside]]) - v_near) / (v_far - v_near)
    for i in range(1, xs.size):
        if ps[i] >= 0.5:
            t = (0.5 - ps[i - 1]) / (ps[i] - ps[i - 1])
            return float(xs[i - 1] + t * (xs[i] - xs[i - 1]))
    return math.nan


def dust_factor_for_transmittance(transmittance: ArrayLike, other_optical_depth: float,
                                  dust_optical_depth_: float) -> np.ndarray:
    """The factor f on the dust density that gives the vertical transmittance
    T = exp(-(tau_other + f tau_dust)), i.e. f = (-ln T - tau_other) / tau_dust [-]; negative
    when the gas alone is already more opaque than T (Beer-Lambert, exact for the zenith)."""
    t = np.asarray(transmittance, dtype=np.float64)
    return (-np.log(t) - other_optical_depth) / dust_optical_depth_
