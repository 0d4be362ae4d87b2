r"""The Moon's disk in absolute spectral radiance: photometric function, colour, maria, earthshine.

Each point x of the visible lunar surface has the spectral radiance

    L(x, λ) = A(x, λ) [ E_⊙(λ) C(x, λ) F(μ_0, μ, φ) + E_⊕(λ) F(μ, μ, 0) ]              (1)

- F: the Hapke (1966) Lommel–Seeliger photometric function as written in the seed's eqs. 4.5-4.8
  (Hapke 1963, J. Geophys. Res. 68, 4571, doi:10.1029/JZ068i015p04571, for the retrodirective
  function B; Hapke 1966, Astron. J. 71, 333, doi:10.1086/109924, for S):

      F = (2 / 3π) B(φ, g) S(φ) / (1 + μ/μ_0)                                         [sr⁻¹]
      B = 2 - tan φ / (2g) (1 - e^{-g/tan φ}) (3 - e^{-g/tan φ})  (φ < π/2),  1 otherwise
      S = ½ (1 - sin(φ/2) tan(φ/2) ln cot(φ/4) + t (1 - cos φ)²)

  μ_0, μ: cosines of the incidence and emission angles, φ: phase angle at the point,
  g = 0.6 (the seed's value), t = 0.05 (the seed has 0.1: see the calibration below); F = 0
  where μ_0 <= 0 or μ <= 0.
- A(x, λ) = a_550 r(λ) m(x): a_550 = `MOON_ALBEDO_550` calibrated below; r(λ) = k_r(λ)/k_r(550)
  with k_r(λ) = -0.27063 + 2.6175e-3 λ - 1.2673e-6 λ² (λ in nm; the seed's eq. 4.11, a fit to the
  mean lunar reflectance of Pieters 1999 and Yapo & Cutler 2009), held constant outside
  300-1032.7 nm (below: outside the fit; above: past its maximum); m(x) = `albedo_map`.
- E_⊙: solar spectral irradiance at the Moon; C: the eclipse factor (1 outside eclipses; see
  `render.lunar_eclipse`).
- E_⊕ = E_⊙ p_⊕ β(λ) Φ_L(α_⊕) (R_⊕/d)²: earthshine, the sunlit Earth seen from the Moon as a
  Lambert sphere of geometric albedo p_⊕ = 0.367 (Allen's Astrophysical Quantities, 4th ed.,
  Cox 2000, ch. 12, planets and satellites: Earth p = 0.367), Lambert phase law
  Φ_L(α) = (sin α + (π - α) cos α) / π (Russell 1916, ApJ 43, 173, doi:10.1086/142244),
  α_⊕ = the Earth's phase angle seen from the Moon (= the Sun-Earth-Moon angle), tinted by the
  seed's earthshine colour β_e = (0.88, 0.96, 1.00) at (680, 550, 440) nm, interpolated linearly
  in λ, normalised to 1 at 550 nm and held constant outside 440-680 nm. The Earth is seen from
  the Moon at the observer's direction (< 1° from its centre), so the earthshine is reflected at
  phase angle 0 and μ_0 = μ: F(μ, μ, 0) = 1/(3π).

Calibration (what a_550 is fitted to): the disk-integrated V magnitude of the sunlit Moon at the
mean distance (384 400 km, Sun at 1 AU) against the phase curve of Allen's Astrophysical
Quantities (Cox 2000, ch. 12, planets and satellites: the Moon),
V(α) = -12.73 + 0.026 |α| + 4.0e-9 α⁴ (α in degrees), least squares in magnitude over
5° <= α <= 120° for the waxing and the waning Moon, V computed with the Bessell (1990) V band
(`spectrum.magnitudes.v_magnitude_of_spectrum`) from the ASTM G173 solar spectrum.
`fit_albedo_to_allen_phase_curve` repeats the fit (a test checks the constant). With the seed's
t = 0.1 the model is 0.38 mag too bright at α = 120° (forward scattering too strong), so we use
t = 0.05 (`HAPKE_T`, a deliberate departure from the seed), which fits within 0.11 mag over
5°-120° (rms 0.04 mag). The fitted a_550 = 0.395 gives the disk-mean normal albedo
π F(1, 1, 0) a_550 = a_550/3 = 0.13 at 550 nm (highlands 0.16, maria 0.086), against the Moon's
geometric albedo p_V = 0.12 (Allen) and normal albedos 0.07-0.10 (maria) and 0.11-0.18
(highlands) (Lunar Sourcebook, Heiken et al. 1991).

Albedo map m(x): no lunar image ships with skyscatter, so the near side is a highland surface
with the large maria as soft-edged discs at their IAU Gazetteer of Planetary Nomenclature centres
and diameters (USGS/IAU WGPSN, planetarynames.wr.usgs.gov, "Moon: mare, oceanus"). The two
elongated ones, Oceanus Procellarum (2568 km) and Mare Frigoris (1596 km long, ~200 km wide),
are chains of discs along their outlines (our approximation from a lunar map, not Gazetteer
data). Maria have normal albedo ≈ 0.07 and highlands ≈ 0.11-0.18 (Heiken, Vaniman & French
1991, *Lunar Sourcebook*, Cambridge Univ. Press, §2.2); the map uses the ratio
`MARE_TO_HIGHLAND_ALBEDO` = 0.07/0.13 and is normalised so that its full-moon disk mean (weight
μ, the projected area) is 1 — the calibration above holds for the mean. The discs cover 30 % of
the near side's area (published: maria cover ~31 % of the near side, Lunar Sourcebook §2.2).

Orientation: the selenographic frame has x towards the observer (the sub-observer point is
latitude 0, longitude 0: optical, physical and diurnal librations are ignored — up to 7-8° of
real shift, which moves the maria on the disk by up to 0.13 of its radius), z along the Moon's
north pole given by the caller (the rotation axis is 1.54° from the ecliptic north pole, Cassini's
laws; passing the ecliptic pole is a fine approximation), y = z × x (east, towards Crisium).

Geometry per pixel: the view ray is intersected with the lunar sphere (exact), giving the surface
point and its normal; the Sun's direction is taken from the Moon's centre (it changes by
< 1e-5 rad across the Moon).

Public names: `HAPKE_G`, `HAPKE_T`, `MOON_ALBEDO_550`, `MARE_TO_HIGHLAND_ALBEDO`,
`EARTH_GEOMETRIC_ALBEDO`, `EARTH_MEAN_RADIUS_M`, `MEAN_MOON_DISTANCE_M`, `MARIA`,
`MoonGeometry`, `hapke_lommel_seeliger_1966`, `lunar_reflectance_ratio`,
`earthshine_colour_ratio`, `lambert_phase_function`, `maria_fraction`, `albedo_map`,
`earthshine_irradiance`, `moon_disk_radiance`, `moon_irradiance`, `add_moon_disk`,
`allen_phase_curve_v`, `fit_albedo_to_allen_phase_curve`.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from functools import cache

import numpy as np
from numpy.typing import ArrayLike

from skyscatter.astro.moon_phase import MOON_RADIUS_M
from skyscatter.errors import InputError
from skyscatter.render.scene import deposit_small_disk
from skyscatter.spectrum.grid import checked_grid
from skyscatter.spectrum.star import AU_M

__all__ = [
    "EARTH_GEOMETRIC_ALBEDO",
    "EARTH_MEAN_RADIUS_M",
    "HAPKE_G",
    "HAPKE_T",
    "MARE_TO_HIGHLAND_ALBEDO",
    "MARIA",
    "MEAN_MOON_DISTANCE_M",
    "MOON_ALBEDO_550",
    "MoonGeometry",
    "add_moon_disk",
    "albedo_map",
    "allen_phase_curve_v",
    "earthshine_colour_ratio",
    "earthshine_irradiance",
    "fit_albedo_to_allen_phase_curve",
    "hapke_lommel_seeliger_1966",
    "lambert_phase_function",
    "lunar_reflectance_ratio",
    "maria_fraction",
    "moon_disk_radiance",
    "moon_irradiance",
]

HAPKE_G = 0.6  # -, "surface density" parameter of B (seed §2.5; Hapke 1963's h)
# -, forward-scattering term of S (Hapke 1966). The seed's t = 0.1 makes the disk-integrated Moon
# 0.38 mag too bright at α = 120° against Allen's V(α); t = 0.05 fits within 0.11 mag (5°-120°).
HAPKE_T = 0.05
# -, a_550 of eq. (1), fitted to Allen's V(α) by `fit_albedo_to_allen_phase_curve` (5°-120°)
MOON_ALBEDO_550 = 0.3946
MARE_TO_HIGHLAND_ALBEDO = 0.07 / 0.13  # normal albedos, Lunar Sourcebook (Heiken et al. 1991)
EARTH_GEOMETRIC_ALBEDO = 0.367  # -, Allen's Astrophysical Quantities (Cox 2000)
EARTH_MEAN_RADIUS_M = 6_371_000.0  # m, IUGG mean radius R_1 (Moritz 2000, J. Geod. 74, 128)
MEAN_MOON_DISTANCE_M = 384_400_000.0  # m, the distance Allen's V(α) refers to

# Maria: (name, centre latitude [deg N], centre longitude [deg E], diameter [km]). Single discs:
# IAU Gazetteer of Planetary Nomenclature centres and diameters. Chains (Procellarum, Frigoris):
# our discs along the outline of the elongated maria (Gazetteer lengths 2568 km and 1596 km).
MARIA = (
    ("Mare Imbrium", 32.8, -15.6, 1123.0),
    ("Mare Serenitatis", 28.0, 17.5, 707.0),
    ("Mare Tranquillitatis", 8.5, 31.4, 873.0),
    ("Mare Crisium", 17.0, 59.1, 418.0),
    ("Mare Fecunditatis", -7.8, 51.3, 909.0),
    ("Mare Nectaris", -15.2, 35.5, 333.0),
    ("Mare Nubium", -21.3, -16.6, 715.0),
    ("Mare Humorum", -24.4, -38.6, 389.0),
    ("Mare Vaporum", 13.3, 3.6, 245.0),
    ("Mare Cognitum", -10.0, -23.1, 376.0),
    ("Mare Insularum", 7.5, -30.9, 513.0),
    ("Mare Smythii", 1.3, 87.5, 373.0),
    ("Mare Marginis", 13.3, 86.1, 420.0),
    ("Mare Undarum", 6.8, 68.4, 243.0),
    ("Mare Anguis", 22.6, 67.7, 150.0),
    ("Mare Spumans", 1.1, 65.1, 139.0),
    ("Mare Humboldtianum", 56.8, 81.5, 273.0),
    ("Mare Australe", -38.9, 93.0, 603.0),
    ("Mare Orientale", -19.4, -92.8, 327.0),
    ("Oceanus Procellarum (north)", 45.0, -50.0, 550.0),
    ("Oceanus Procellarum (north-west)", 30.0, -60.0, 650.0),
    ("Oceanus Procellarum (centre)", 15.0, -57.0, 700.0),
    ("Oceanus Procellarum (south)", 0.0, -52.0, 600.0),
    ("Oceanus Procellarum (south-west)", -10.0, -60.0, 400.0),
    *((f"Mare Frigoris ({lon:+.0f})", 57.0 - 0.05 * lon, lon, 220.0)
      for lon in np.arange(-40.0, 45.0, 10.0)),
)
_EDGE_FRACTION = 0.15  # soft edge: albedo ramps over ±15 % of each disc's radius (smoothstep)
_ALLEN_PHASE_FIT_DEG = np.linspace(5.0, 120.0, 24)  # phase angles of the calibration fit


def hapke_lommel_seeliger_1966(cos_incidence: ArrayLike, cos_emission: ArrayLike,
                               phase_angle_rad: ArrayLike, g: float = HAPKE_G,
                               t: float = HAPKE_T) -> np.ndarray:
    r"""Hapke (1966) Lommel–Seeliger photometric function, the seed's eqs. 4.5-4.8.

        F = (2 / 3π) B(φ, g) S(φ) μ_0 / (μ_0 + μ)
        B = 2 - tan φ / (2g) (1 - e^{-g/tan φ}) (3 - e^{-g/tan φ})   (φ < π/2),   1 otherwise
        S = ½ (1 - sin(φ/2) tan(φ/2) ln cot(φ/4) + t (1 - cos φ)²)

    Hapke (1963), J. Geophys. Res. 68, 4571, doi:10.1029/JZ068i015p04571 (B, the shadow-hiding
    opposition effect: B(0) = 2); Hapke (1966), Astron. J. 71, 333, doi:10.1086/109924 (S, with
    the forward-scattering term t). L = E × albedo × F for a surface under normal irradiance E:
    F has units sr⁻¹. F(1, 1, 0) = 1/(3π). φ is clipped to [1e-9, π - 1e-6] (both limits of
    S are finite: S(0) = ½, S(π) = 2t).

    Parameters
    ----------
    cos_incidence, cos_emission : array_like, broadcast to S
        μ_0 and μ: cosines of the angles between the surface normal and the directions to the
        light and to the observer; F = 0 where either is <= 0. [-]
    phase_angle_rad : array_like, broadcast to S
        φ: angle at the surface between the directions to the light and to the observer. [rad]
    g, t : float
        Compaction ("surface density") and forward-scattering parameters. [-]

    Returns
    -------
    ndarray, shape S
        F. [sr⁻¹]
    """
    mu0 = np.asarray(cos_incidence, dtype=np.float64)
    mu = np.asarray(cos_emission, dtype=np.float64)
    phi = np.clip(np.asarray(phase_angle_rad, dtype=np.float64), 1e-9, math.pi - 1e-6)
    tan_phi = np.tan(np.minimum(phi, 0.5 * math.pi - 1e-9))
    e = np.exp(-g / tan_phi)
    b = np.where(phi < 0.5 * math.pi, 2.0 - tan_phi / (2.0 * g) * (1.0 - e) * (3.0 - e), 1.0)
    half = 0.5 * phi
    s = 0.5 * (1.0 - np.sin(half) * np.tan(half) * np.log(1.0 / np.tan(0.5 * half))
               + t * (1.0 - np.cos(phi)) ** 2)
    lit = (mu0 > 0.0) & (mu > 0.0)
    with np.errstate(invalid="ignore", divide="ignore"):
        ratio = np.where(lit, mu0 / (mu0 + mu), 0.0)
    return 2.0 / (3.0 * math.pi) * b * s * ratio


def lunar_reflectance_ratio(wavelengths_nm: ArrayLike) -> np.ndarray:
    """Spectral shape of the lunar albedo, r(λ) = k_r(λ) / k_r(550 nm).

        k_r(λ) = -0.27063 + 2.6175e-3 λ - 1.2673e-6 λ²,   λ in nm

    The seed's eq. 4.11: a quadratic fit to the Moon's mean reflectance spectrum (Pieters 1999,
    in *New Views of the Moon* / Lunar Sample Compendium; Yapo & Cutler 2009, Comput. Graph.
    Forum 28, 1185, doi:10.1111/j.1467-8659.2009.01495.x): reddish, rising from 0.81 (440 nm) to
    1.18 (680 nm) relative to 550 nm. λ is clamped to [300, 1032.7] nm (below: outside the data;
    above: past the parabola's maximum).

    Parameters
    ----------
    wavelengths_nm : array_like, shape W
        Wavelengths. [nm]

    Returns
    -------
    ndarray, shape W
        r(λ), 1 at 550 nm. [-]
    """
    lam = np.clip(np.asarray(wavelengths_nm, dtype=np.float64), 300.0, 2.6175e-3 / 2.5346e-6)

    def k_r(x):
        return -0.27063 + 2.6175e-3 * x - 1.2673e-6 * x * x

    return k_r(lam) / k_r(550.0)


def earthshine_colour_ratio(wavelengths_nm: ArrayLike) -> np.ndarray:
    """Spectral tint β(λ) of earthshine relative to sunlight, 1 at 550 nm.

    The seed's colour coefficient β_e = (0.88, 0.96, 1.00) for (R, G, B) (Müller 2012 §4.1.2,
    after the bluish ashen light), placed at (680, 550, 440) nm (the seed's representative
    wavelengths, Riley et al. 2004), interpolated linearly in λ, divided by 0.96 and held
    constant outside 440-680 nm. A coarse stand-in for the Earth's reflectance spectrum.

    Parameters
    ----------
    wavelengths_nm : array_like, shape W
        Wavelengths. [nm]

    Returns
    -------
    ndarray, shape W
        β(λ); 1.042 at <= 440 nm, 0.917 at >= 680 nm. [-]
    """
    lam = np.asarray(wavelengths_nm, dtype=np.float64)
    return np.interp(lam, [440.0, 550.0, 680.0], [1.00 / 0.96, 1.0, 0.88 / 0.96])


def lambert_phase_function(phase_angle_rad: ArrayLike) -> np.ndarray:
    """Phase law of a Lambert sphere, Φ(α) = (sin α + (π - α) cos α) / π (Russell 1916).

    Russell (1916), ApJ 43, 173, doi:10.1086/142244. Φ(0) = 1, Φ(π/2) = 1/π, Φ(π) = 0; the
    irradiance from a sphere of geometric albedo p and radius R at distance d is
    E = E_⊙ p Φ(α) (R/d)².

    Parameters
    ----------
    phase_angle_rad : array_like, shape S
        α in [0, π]. [rad]

    Returns
    -------
    ndarray, shape S
        Φ(α). [-]
    """
    a = np.clip(np.asarray(phase_angle_rad, dtype=np.float64), 0.0, math.pi)
    return (np.sin(a) + (math.pi - a) * np.cos(a)) / math.pi


def _unit_vectors(value: ArrayLike, name: str) -> np.ndarray:
    v = np.asarray(value, dtype=np.float64)
    if v.ndim == 0 or v.shape[-1] != 3 or not np.all(np.isfinite(v)):
        raise InputError(f"{name} must be finite vectors of shape (..., 3); got {value!r}",
                         key=name, value=value, allowed="finite (..., 3)")
    norm = np.linalg.norm(v, axis=-1, keepdims=True)
    if np.any(norm <= 0.0):
        raise InputError(f"{name} must not be a zero vector", key=name, value=value,
                         allowed="non-zero (..., 3)")
    return v / norm


def _smoothstep(x: np.ndarray) -> np.ndarray:
    x = np.clip(x, 0.0, 1.0)
    return x * x * (3.0 - 2.0 * x)


@cache
def _maria_arrays() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Unit centre vectors (n, 3) in the selenographic frame, cos of the inner and outer edge
    radii (n,) of the soft discs."""
    lat = np.radians([m[1] for m in MARIA])
    lon = np.radians([m[2] for m in MARIA])
    centres = np.stack([np.cos(lat) * np.cos(lon), np.cos(lat) * np.sin(lon), np.sin(lat)], -1)
    radius = np.array([m[3] for m in MARIA]) * 1e3 / 2.0 / MOON_RADIUS_M  # rad of arc
    return (centres, np.cos(radius * (1.0 - _EDGE_FRACTION)),
            np.cos(radius * (1.0 + _EDGE_FRACTION)))


def maria_fraction(normals_selenographic: ArrayLike) -> np.ndarray:
    """How much of a surface point is mare: 1 inside a mare disc, 0 in the highlands.

    Each entry of `MARIA` is a spherical cap of the Gazetteer diameter; the fraction ramps by a
    smoothstep from the cap's radius × 0.85 to × 1.15 (soft edge), and overlapping caps take
    the maximum.

    Parameters
    ----------
    normals_selenographic : array_like, shape S + (3,)
        Unit vectors from the Moon's centre in the selenographic frame (x: 0° N 0° E,
        y: 0° N 90° E, z: north pole). [-]

    Returns
    -------
    ndarray, shape S
        Mare fraction in [0, 1]. [-]
    """
    n = _unit_vectors(normals_selenographic, "normals_selenographic")
    centres, cos_inner, cos_outer = _maria_arrays()
    cos_d = n @ centres.T  # S + (n_maria,)
    # linear ramp in cos of the distance between the outer (0) and inner (1) edge
    fraction = _smoothstep((cos_d - cos_outer) / (cos_inner - cos_outer))
    return fraction.max(axis=-1)


@cache
def _albedo_map_mean() -> float:
    """Full-moon disk mean of the unnormalised map: ∫ m μ dA / ∫ μ dA over the near side."""
    nodes, weights = np.polynomial.legendre.leggauss(96)
    mu = 0.5 * (nodes + 1.0)  # cos of the angle from the sub-observer point, (0, 1]
    w_mu = 0.5 * weights * mu  # weight μ dμ (dA = dμ dψ on the unit sphere)
    psi = (np.arange(192) + 0.5) * 2.0 * math.pi / 192
    sin_t = np.sqrt(1.0 - mu * mu)
    n = np.stack([np.broadcast_to(mu[:, None], (96, 192)), sin_t[:, None] * np.cos(psi),
                  sin_t[:, None] * np.sin(psi)], -1)
    raw = 1.0 - (1.0 - MARE_TO_HIGHLAND_ALBEDO) * maria_fraction(n)
    return float(np.sum(raw * w_mu[:, None]) / (np.sum(w_mu) * 192))


def albedo_map(normals_selenographic: ArrayLike) -> np.ndarray:
    """Relative albedo m(x) of the lunar surface: highlands vs maria, full-moon disk mean 1.

        m = (1 - (1 - q) f(x)) / ⟨1 - (1 - q) f⟩,   q = `MARE_TO_HIGHLAND_ALBEDO` = 0.07/0.13

    f = `maria_fraction`; ⟨·⟩ = mean over the near side weighted by μ (the full Moon's projected
    area; 96 × 192 Gauss–Legendre/midpoint nodes). The same everywhere in λ.

    Parameters
    ----------
    normals_selenographic : array_like, shape S + (3,)
        Unit vectors from the Moon's centre, selenographic frame (see `maria_fraction`). [-]

    Returns
    -------
    ndarray, shape S
        m; highlands 1.215, maria 0.654. [-]
    """
    raw = 1.0 - (1.0 - MARE_TO_HIGHLAND_ALBEDO) * maria_fraction(normals_selenographic)
    return raw / _albedo_map_mean()


@dataclass(frozen=True)
class MoonGeometry:
    """Where the Moon and the Sun are, seen from the observer, and how the Moon is turned.

    All vectors in one frame (e.g. the camera's east-north-up frame); directions need not be
    normalised (they are normalised here).

    Attributes
    ----------
    moon_direction : ndarray, shape (3,)
        From the observer towards the Moon's centre. [-]
    moon_distance_m : float
        Observer to the Moon's centre. [m]
    sun_direction : ndarray, shape (3,)
        From the observer towards the Sun's centre. [-]
    moon_north : ndarray, shape (3,)
        The Moon's north pole direction (≈ the ecliptic north pole, 1.54° away). [-]
    sun_distance_m : float
        Observer to the Sun's centre (1 AU by default). [m]
    """

    moon_direction: np.ndarray
    moon_distance_m: float
    sun_direction: np.ndarray
    moon_north: np.ndarray
    sun_distance_m: float = AU_M

    def __post_init__(self) -> None:
        for key in ("moon_direction", "sun_direction", "moon_north"):
            v = _unit_vectors(getattr(self, key), key)
            if v.shape != (3,):
                raise InputError(f"{key} must be one vector (3,); got shape {v.shape}", key=key,
                                 value=v.shape, allowed="(3,)")
            object.__setattr__(self, key, v)
        for key in ("moon_distance_m", "sun_distance_m"):
            value = float(getattr(self, key))
            if not (math.isfinite(value) and value > MOON_RADIUS_M):
                raise InputError(f"{key} = {value!r} must exceed the Moon's radius "
                                 f"{MOON_RADIUS_M:g} m", key=key, value=value,
                                 allowed=f"> {MOON_RADIUS_M:g} [m]")
            object.__setattr__(self, key, value)
        if abs(float(self.moon_north @ self.moon_direction)) > 1.0 - 1e-9:
            raise InputError("moon_north is along the line of sight; the Moon's pole must not "
                             "point at the observer", key="moon_north", value=self.moon_north)

    @classmethod
    def from_positions(cls, moon_position_m: ArrayLike, sun_position_m: ArrayLike,
                       moon_north: ArrayLike) -> MoonGeometry:
        """From the Moon's and the Sun's positions relative to the observer (3,) [m]."""
        moon = np.asarray(moon_position_m, dtype=np.float64)
        sun = np.asarray(sun_position_m, dtype=np.float64)
        return cls(moon, float(np.linalg.norm(moon)), sun, np.asarray(moon_north, float),
                   float(np.linalg.norm(sun)))

    @property
    def angular_radius_rad(self) -> float:
        """asin(R_moon / d). [rad]"""
        return math.asin(MOON_RADIUS_M / self.moon_distance_m)

    @property
    def solid_angle_sr(self) -> float:
        """2π (1 - cos s_m). [sr]"""
        return 2.0 * math.pi * (1.0 - math.cos(self.angular_radius_rad))

    @property
    def moon_centre_m(self) -> np.ndarray:
        return self.moon_distance_m * self.moon_direction

    @property
    def sun_from_moon(self) -> np.ndarray:
        """Unit vector from the Moon's centre to the Sun's centre. [-]"""
        v = self.sun_distance_m * self.sun_direction - self.moon_centre_m
        return v / np.linalg.norm(v)

    def selenographic_axes(self) -> np.ndarray:
        """Rows x, y, z of the selenographic frame in the input frame (3, 3): x towards the
        observer (librations ignored), z the pole's part perpendicular to x, y = z × x."""
        x = -self.moon_direction
        z = self.moon_north - (self.moon_north @ x) * x
        z = z / np.linalg.norm(z)
        return np.stack([x, np.cross(z, x), z])


def earthshine_irradiance(geometry: MoonGeometry, wavelengths_nm: ArrayLike,
                          solar_irradiance_at_moon: ArrayLike) -> np.ndarray:
    """Spectral irradiance of earthshine at the Moon, normal to the Earth's direction.

        E_⊕(λ) = E_⊙(λ) p_⊕ β(λ) Φ_L(α_⊕) (R_⊕ / d)²

    p_⊕ = 0.367 (`EARTH_GEOMETRIC_ALBEDO`, Allen / Cox 2000), β = `earthshine_colour_ratio`,
    Φ_L = `lambert_phase_function`, α_⊕ = angle between the Sun and the Moon seen from the
    observer (the Earth's phase angle seen from the Moon; the observer stands in for the Earth's
    centre), R_⊕ = 6371 km, d = Moon distance. ≈ 1e-4 E_⊙ at new moon.

    Parameters
    ----------
    geometry : MoonGeometry
        Moon and Sun seen from the observer.
    wavelengths_nm : array_like, shape (n_wl,)
        Wavelength grid. [nm]
    solar_irradiance_at_moon : array_like, shape (n_wl,)
        E_⊙ at the Moon (no atmosphere). [W m⁻² nm⁻¹]

    Returns
    -------
    ndarray, shape (n_wl,)
        E_⊕. [W m⁻² nm⁻¹]
    """
    wl = checked_grid(wavelengths_nm)
    e_sun = np.asarray(solar_irradiance_at_moon, dtype=np.float64)
    alpha = math.acos(float(np.clip(geometry.sun_direction @ geometry.moon_direction, -1, 1)))
    dilution = (EARTH_MEAN_RADIUS_M / geometry.moon_distance_m) ** 2
    return (e_sun * EARTH_GEOMETRIC_ALBEDO * earthshine_colour_ratio(wl)
            * float(lambert_phase_function(alpha)) * dilution)


def moon_disk_radiance(view_directions: ArrayLike, geometry: MoonGeometry,
                       wavelengths_nm: ArrayLike, solar_irradiance_at_moon: ArrayLike, *,
                       earthshine: bool = True,
                       eclipse: Callable[[np.ndarray], np.ndarray] | None = None) -> np.ndarray:
    """Spectral radiance of the Moon along view rays, eq. (1) of the module docstring.

    Each ray from the observer is intersected with the lunar sphere (radius 1737.4 km); rays
    that miss it get 0. The hit point's normal gives μ (towards the observer), μ_0 (towards the
    Sun, from the Moon's centre), the phase angle φ, and the selenographic position for the
    albedo map.

    Parameters
    ----------
    view_directions : array_like, shape S + (3,)
        Unit vectors from the observer, frame of `geometry`. [-]
    geometry : MoonGeometry
        Moon and Sun seen from the observer; the Moon's pole.
    wavelengths_nm : array_like, shape (n_wl,)
        Wavelength grid. [nm]
    solar_irradiance_at_moon : array_like, shape (n_wl,)
        Solar spectral irradiance at the Moon (no Earth atmosphere), e.g.
        `Star.sun(distance_au).irradiance_toa(wl)`. [W m⁻² nm⁻¹]
    earthshine : bool
        Add the Earth-lit term (the ashen light on the night side).
    eclipse : callable or None
        `eclipse(points_m (n, 3)) -> (n, n_wl)`: the fraction of sunlight reaching surface
        points given relative to the observer in `geometry`'s frame [m] (e.g. a wrapper of
        `lunar_eclipse.eclipse_factor` that adds the observer's geocentric position). None: 1.

    Returns
    -------
    ndarray, shape S + (n_wl,)
        Spectral radiance at the Moon (before the Earth's atmosphere). [W m⁻² sr⁻¹ nm⁻¹]
    """
    wl = checked_grid(wavelengths_nm)
    e_sun = np.asarray(solar_irradiance_at_moon, dtype=np.float64)
    if e_sun.shape != wl.shape:
        raise InputError(f"solar_irradiance_at_moon must have shape {wl.shape}; got "
                         f"{e_sun.shape}", key="solar_irradiance_at_moon", value=e_sun.shape,
                         allowed=str(wl.shape))
    v = _unit_vectors(view_directions, "view_directions")
    shape = v.shape[:-1]
    v = v.reshape(-1, 3)
    out = np.zeros((v.shape[0], wl.size))
    d, r = geometry.moon_distance_m, MOON_RADIUS_M
    along = v @ geometry.moon_direction  # cos of the angle from the disk centre
    disc = r * r - d * d * (1.0 - along * along)
    hit = np.flatnonzero((disc >= 0.0) & (along > 0.0))
    if hit.size == 0:
        return out.reshape(shape + wl.shape)
    vh = v[hit]
    t = d * along[hit] - np.sqrt(disc[hit])  # distance to the near-side hit point
    points = t[:, None] * vh
    normals = (points - geometry.moon_centre_m) / r
    normals /= np.linalg.norm(normals, axis=-1, keepdims=True)
    mu = np.clip(-np.einsum("ij,ij->i", normals, vh), 0.0, 1.0)
    sun = geometry.sun_from_moon
    mu0 = normals @ sun
    phase = np.arccos(np.clip(-(vh @ sun), -1.0, 1.0))
    albedo = MOON_ALBEDO_550 * albedo_map(normals @ geometry.selenographic_axes().T)
    reflectance = lunar_reflectance_ratio(wl)
    f_sun = hapke_lommel_seeliger_1966(mu0, mu, phase)
    sunlit = f_sun[:, None] * e_sun
    if eclipse is not None:
        sunlit = sunlit * np.asarray(eclipse(points), dtype=np.float64)
    radiance = sunlit
    if earthshine:
        f_earth = hapke_lommel_seeliger_1966(mu, mu, 0.0)  # = 1/(3π) where μ > 0
        radiance = radiance + f_earth[:, None] * earthshine_irradiance(geometry, wl, e_sun)
    out[hit] = albedo[:, None] * reflectance * radiance
    return out.reshape(shape + wl.shape)


def _disk_quadrature(geometry: MoonGeometry, n_radial: int,
                     n_azimuth: int) -> tuple[np.ndarray, np.ndarray]:
    """Directions (n, 3) and solid-angle weights (n,) covering the lunar disk: Gauss–Legendre
    in cos θ over [cos s_m, 1] × midpoint rule in azimuth (Σ weights = 2π (1 - cos s_m))."""
    m = geometry.moon_direction
    helper = np.array([1.0, 0.0, 0.0]) if abs(m[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    e1 = np.cross(m, helper)
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(m, e1)
    cos_s = math.cos(geometry.angular_radius_rad)
    nodes, weights = np.polynomial.legendre.leggauss(n_radial)
    cos_t = cos_s + (1.0 - cos_s) * 0.5 * (nodes + 1.0)
    w_t = (1.0 - cos_s) * 0.5 * weights
    psi = (np.arange(n_azimuth) + 0.5) * 2.0 * math.pi / n_azimuth
    sin_t = np.sqrt(1.0 - cos_t * cos_t)
    dirs = (cos_t[:, None, None] * m + sin_t[:, None, None]
            * (np.cos(psi)[None, :, None] * e1 + np.sin(psi)[None, :, None] * e2))
    w = np.broadcast_to(w_t[:, None] * (2.0 * math.pi / n_azimuth), dirs.shape[:2])
    return dirs.reshape(-1, 3), w.reshape(-1)


def moon_irradiance(geometry: MoonGeometry, wavelengths_nm: ArrayLike,
                    solar_irradiance_at_moon: ArrayLike, *, earthshine: bool = True,
                    eclipse: Callable[[np.ndarray], np.ndarray] | None = None,
                    n_radial: int = 48, n_azimuth: int = 96) -> np.ndarray:
    """Disk-integrated spectral irradiance of the Moon at the observer (no atmosphere).

        E_moon(λ) = ∫_disk L(λ) dΩ

    L = `moon_disk_radiance` (same arguments), integrated with `n_radial` Gauss–Legendre nodes
    in cos θ (θ: angle from the disk centre) × `n_azimuth` azimuths; the terminator and the
    maria edges are continuous, so 48 × 96 nodes agree with 192 × 384 to 0.1 %. Use it as the
    Moon's light for the night-sky atmosphere, and to check the image (Σ L Ω over the disk).

    Parameters
    ----------
    geometry, wavelengths_nm, solar_irradiance_at_moon, earthshine, eclipse
        As `moon_disk_radiance`.
    n_radial, n_azimuth : int
        Quadrature nodes across and around the disk.

    Returns
    -------
    ndarray, shape (n_wl,)
        Spectral irradiance normal to the Moon's direction. [W m⁻² nm⁻¹]
    """
    dirs, weights = _disk_quadrature(geometry, int(n_radial), int(n_azimuth))
    radiance = moon_disk_radiance(dirs, geometry, wavelengths_nm, solar_irradiance_at_moon,
                                  earthshine=earthshine, eclipse=eclipse)
    return weights @ radiance


def add_moon_disk(spectral: np.ndarray, camera, directions: np.ndarray, valid: np.ndarray,
                  geometry: MoonGeometry, *, wavelengths_nm: ArrayLike,
                  solar_irradiance_at_moon: ArrayLike, transmittance: ArrayLike,
                  earthshine: bool = True,
                  eclipse: Callable[[np.ndarray], np.ndarray] | None = None,
                  irradiance: np.ndarray | None = None) -> None:
    """Add the transmitted lunar disk to `spectral` (h, w, n_wl) in place.

    Like `scene.add_sun_disk`: when the disk's solid angle is below `scene.SPLAT_PIXELS` (4) times
    that of the pixel containing its centre, the whole `moon_irradiance` × `transmittance`
    goes into that pixel (divided by its solid angle), so the image carries the Moon's flux at
    any resolution; otherwise each pixel whose centre ray hits the Moon gets
    `moon_disk_radiance` × `transmittance` (one transmittance for the whole disk: it changes by
    < 1 % across 0.5° except within ~2° of the horizon).

    Parameters
    ----------
    spectral : ndarray, shape (h, w, n_wl)
        Image to add to. [W m⁻² sr⁻¹ nm⁻¹]
    camera : Camera
        Gives `direction_to_pixel` and `pixel_solid_angles`.
    directions : ndarray, shape (h, w, 3)
        The camera's pixel directions, frame of `geometry`. [-]
    valid : ndarray, shape (h, w)
        Pixels inside the lens.
    geometry, wavelengths_nm, solar_irradiance_at_moon, earthshine, eclipse
        As `moon_disk_radiance`.
    transmittance : array_like, shape (n_wl,)
        Atmospheric transmittance from the observer towards the Moon. [-]
    irradiance : ndarray, shape (n_wl,), optional
        `moon_irradiance` of the same arguments when the caller has it already (it is the
        moonlight of the sky too); computed here otherwise. [W m⁻² nm⁻¹]
    """
    trans = np.asarray(transmittance, dtype=np.float64)
    if not np.any(trans > 0.0) or deposit_small_disk(
            spectral, camera, valid, geometry.moon_direction, geometry.solid_angle_sr,
            irradiance=lambda: (
                moon_irradiance(geometry, wavelengths_nm, solar_irradiance_at_moon,
                                earthshine=earthshine, eclipse=eclipse)
                if irradiance is None else irradiance) * trans):
        return
    cos_angle = directions @ geometry.moon_direction
    inside = valid & (cos_angle > math.cos(geometry.angular_radius_rad))
    if not np.any(inside):
        return
    spectral[inside] += moon_disk_radiance(directions[inside], geometry, wavelengths_nm,
                                           solar_irradiance_at_moon, earthshine=earthshine,
                                           eclipse=eclipse) * trans


def allen_phase_curve_v(phase_angle_deg: ArrayLike) -> np.ndarray:
    """The Moon's V magnitude vs phase angle, mean distance: Allen's Astrophysical Quantities.

        V(α) = -12.73 + 0.026 |α| + 4.0e-9 α⁴,   α in degrees

    Cox (2000), *Allen's Astrophysical Quantities*, 4th ed., Springer, §12 (the Moon), for the
    Moon at 384 400 km from the observer and 1 AU from the Sun; valid to α ≈ 150°.

    Parameters
    ----------
    phase_angle_deg : array_like, shape S
        α. [deg]

    Returns
    -------
    ndarray, shape S
        V. [mag]
    """
    a = np.abs(np.asarray(phase_angle_deg, dtype=np.float64))
    return -12.73 + 0.026 * a + 4.0e-9 * a**4


def _phase_geometry(phase_angle_deg: float, waxing: bool) -> MoonGeometry:
    """Moon at the mean distance along +x, Sun at 1 AU such that the geocentric phase angle is
    α (Sun-Moon parallax included), ecliptic pole +z; waxing: Sun at +y side."""
    alpha = math.radians(phase_angle_deg)
    d = MEAN_MOON_DISTANCE_M
    # Sun direction at elongation ε from the Moon: solve the triangle for the phase angle α:
    # ε = π - α - asin(d sin α / AU) (exact for the Moon-observer-Sun triangle)
    elongation = math.pi - alpha - math.asin(d * math.sin(alpha) / AU_M)
    side = 1.0 if waxing else -1.0
    sun = np.array([math.cos(elongation), side * math.sin(elongation), 0.0])
    return MoonGeometry(np.array([1.0, 0.0, 0.0]), d, sun, np.array([0.0, 0.0, 1.0]), AU_M)


def fit_albedo_to_allen_phase_curve(phase_angles_deg: ArrayLike = _ALLEN_PHASE_FIT_DEG,
                                    ) -> tuple[float, np.ndarray]:
    """Re-derive `MOON_ALBEDO_550`: the a_550 that fits `allen_phase_curve_v` best.

    For each α, the waxing and the waning Moon (earthshine off) are integrated by
    `moon_irradiance` with the ASTM G173 Sun at 1 AU on a 380-780 nm grid (5 nm cells) and
    turned into V by `spectrum.magnitudes.v_magnitude_of_spectrum` (Bessell 1990 V band,
    Bessell et al. 1998 zero point). V - V_Allen is a constant offset in log a_550, so the least
    squares a_550 is closed form: a_550 = MOON_ALBEDO_550 × 10^{0.4 mean(V - V_Allen)}.

    Parameters
    ----------
    phase_angles_deg : array_like, shape (n,)
        Phase angles of the fit; default 24 angles, 5°-120°. [deg]

    Returns
    -------
    (float, ndarray)
        The fitted a_550 [-], and the residuals V_model - V_Allen (n, 2) after the fit
        (columns: waxing, waning). [mag]
    """
    from skyscatter.spectrum.magnitudes import v_magnitude_of_spectrum
    from skyscatter.spectrum.star import Star

    wl = np.arange(382.5, 780.0, 5.0)
    e_sun = Star.sun(1.0).irradiance_toa(wl)
    angles = np.asarray(phase_angles_deg, dtype=np.float64)
    v = np.array([[float(v_magnitude_of_spectrum(wl, moon_irradiance(
        _phase_geometry(a, waxing), wl, e_sun, earthshine=False))) for waxing in (True, False)]
        for a in angles])
    diff = v - allen_phase_curve_v(angles)[:, None]
    offset = float(np.mean(diff))
    return MOON_ALBEDO_550 * 10.0 ** (0.4 * offset), diff - offset
