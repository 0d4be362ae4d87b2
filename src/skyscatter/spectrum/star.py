"""Stars as light sources: Planck radiance, solar limb darkening, and the `Star` a planet sees.

- `planck_spectral_radiance`: black-body spectral radiance, Planck (1901), with CODATA 2018 exact
  SI constants.
- `limb_darkening_neckel_labs_1994`: the Sun's centre-to-limb intensity ratio I(μ)/I(1), fifth-
  degree polynomials in μ from Neckel & Labs (1994), with wavelength-dependent coefficients in the
  analytic form of Neckel (2005).
- `Star`: a spherical star of radius R at distance d: its irradiance at the top of a planet's
  atmosphere (measured solar spectrum, or π B sin²α for a black body) and the radiance of each
  point of its disk, limb-darkened and normalised so that the disk integrates to that irradiance.

Solar constants: IAU 2015 Resolution B3 nominal values (Prša et al. 2016, AJ 152, 41,
doi:10.3847/0004-6256/152/2/41); astronomical unit: IAU 2012 Resolution B2 (exact).

Public names: `AU_M`, `SOLAR_RADIUS_M`, `SOLAR_EFFECTIVE_TEMPERATURE_K`, `PLANCK`,
`SPEED_OF_LIGHT`, `BOLTZMANN`, `STAR_SPECTRA`, `planck_spectral_radiance`,
`limb_darkening_neckel_labs_1994`, `limb_darkening_disk_mean`, `Star`.
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from skyscatter.checks import checked_finite_array
from skyscatter.errors import InputError
from skyscatter.spectrum.grid import cell_edges, checked_grid, checked_wavelengths
from skyscatter.spectrum.solar import solar_irradiance_1au

__all__ = [
    "AU_M",
    "BOLTZMANN",
    "PLANCK",
    "SOLAR_EFFECTIVE_TEMPERATURE_K",
    "SOLAR_RADIUS_M",
    "SPEED_OF_LIGHT",
    "STAR_SPECTRA",
    "Star",
    "limb_darkening_disk_mean",
    "limb_darkening_neckel_labs_1994",
    "planck_spectral_radiance",
]

PLANCK = 6.62607015e-34  # J s, exact (SI 2019; CODATA 2018)
SPEED_OF_LIGHT = 299_792_458.0  # m s⁻¹, exact (SI)
BOLTZMANN = 1.380649e-23  # J K⁻¹, exact (SI 2019; CODATA 2018)
AU_M = 149_597_870_700.0  # m, astronomical unit, exact (IAU 2012 Resolution B2)
SOLAR_RADIUS_M = 6.957e8  # m, nominal solar radius (IAU 2015 Resolution B3)
SOLAR_EFFECTIVE_TEMPERATURE_K = 5772.0  # K, nominal solar T_eff (IAU 2015 Resolution B3)

STAR_SPECTRA = ("astm-g173", "blackbody")  # allowed values of Star.spectrum
_NM = 1e-9  # m per nm
_GAUSS_NODES = 8  # Gauss–Legendre nodes per cell for black-body cell averages
_NECKEL_SHORTEST_NM = 300.0  # nm; short end of Neckel's fits; coefficients held below it


def planck_spectral_radiance(wavelengths_nm: ArrayLike, temperature_k: ArrayLike) -> np.ndarray:
    """Black-body spectral radiance per unit wavelength.

        B_λ(T) = 2 h c² / λ⁵ / (exp(h c / (λ k T)) - 1)

    Planck (1901), Ann. Phys. 309, 553, doi:10.1002/andp.19013090310; h, c, k exact SI (CODATA
    2018). Evaluated with expm1, so the Rayleigh–Jeans end keeps full precision; where the
    exponent overflows (λT ≲ 0.2 µm K) the result is 0.

    Parameters
    ----------
    wavelengths_nm : array_like, shape W
        Wavelengths, > 0; usually a grid (n_wl,). [nm]
    temperature_k : array_like, shape S
        Temperatures, > 0. [K]

    Returns
    -------
    ndarray, shape S + W
        Spectral radiance; every temperature with every wavelength. [W m⁻² sr⁻¹ nm⁻¹]
    """
    wl = checked_wavelengths(wavelengths_nm) * _NM
    t = checked_finite_array("temperature_k", temperature_k, "K", positive=True)
    t = t.reshape(t.shape + (1,) * wl.ndim)
    with np.errstate(over="ignore"):
        x = (PLANCK * SPEED_OF_LIGHT) / (wl * BOLTZMANN * t)
        b = 2.0 * PLANCK * SPEED_OF_LIGHT**2 / wl**5 / np.expm1(x)
    return b * _NM


# Neckel (2005) analytic coefficients, λ in µm: a_k(λ) = a_k0 + a_k1/λ + a_k5/λ⁵, with a_1 fixed by
# Σ a_k = 1 (I(1)/I(1) = 1). Columns: (upper edge of the range [µm], a00, a01, a20, a30, a40, a50,
# a25, a35, a45, a55). Each row's fit reproduces the Neckel & Labs (1994) polynomial coefficients
# measured in its range to <= 0.01 in I(μ)/I(1) (tests/spectrum/test_spectrum_star.py).
_NECKEL_RANGES = np.array([
    # 300.00–372.98 nm
    [0.37298, 0.35601, -0.085217, -0.67237, 0.18696, 0.00038, 0.01373,
     0.003589, -0.002415, 0.000897, -0.000200],
    # 385.00–422.57 nm (also used across the unfitted 372.98–385 nm gap)
    [0.42257, 0.09900, 0.010643, -2.80511, 3.32780, -2.17878, 0.58825,
     0.024873, -0.029317, 0.018273, -0.004663],
    # 422.57–1100 nm (used beyond 1100 nm as an extrapolation)
    [np.inf, 0.75267, -0.265577, -1.89287, 2.42234, -1.71150, 0.49062,
     0.012582, -0.017117, 0.011977, -0.003347],
])


def _neckel_coefficients(wavelengths_nm: np.ndarray) -> np.ndarray:
    """Polynomial coefficients a_0..a_5 at each wavelength, shape W + (6,); see the caller."""
    lam = np.maximum(wavelengths_nm, _NECKEL_SHORTEST_NM) * 1e-3  # µm; held below 300 nm
    row = _NECKEL_RANGES[np.searchsorted(_NECKEL_RANGES[:, 0], lam, side="right")]
    a00, a01, a20, a30, a40, a50, a25, a35, a45, a55 = np.moveaxis(row[..., 1:], -1, 0)
    inv1, inv5 = 1.0 / lam, lam**-5.0
    a10 = 1.0 - (a00 + a20 + a30 + a40 + a50)
    a15 = -(a25 + a35 + a45 + a55)
    return np.stack([a00 + a01 * inv1,
                     a10 - a01 * inv1 + a15 * inv5,
                     a20 + a25 * inv5,
                     a30 + a35 * inv5,
                     a40 + a45 * inv5,
                     a50 + a55 * inv5], axis=-1)


def limb_darkening_neckel_labs_1994(cos_limb: ArrayLike, wavelengths_nm: ArrayLike) -> np.ndarray:
    r"""Solar centre-to-limb intensity ratio I(μ, λ)/I(1, λ).

        I(μ)/I(1) = Σ_{k=0..5} a_k(λ) μ^k,   Σ_k a_k = 1

    Polynomials fitted to the limb-darkening measurements of Neckel & Labs (1994), Solar Phys.
    153, 91 (1994SoPh..153...91N), "Solar limb darkening 1986–1990 (λλ 303 to 1099 nm)", with
    a_k(λ) in the analytic form of Neckel (2005), Solar Phys. 229, 13 (2005SoPh..229...13N),
    λ in µm, for 422.57–1100 nm:

        a0 = 0.75267 - 0.265577/λ           a3 =  2.42234 - 0.017117/λ⁵
        a1 = 0.93874 + 0.265577/λ - 0.004095/λ⁵   a4 = -1.71150 + 0.011977/λ⁵
        a2 = -1.89287 + 0.012582/λ⁵          a5 =  0.49062 - 0.003347/λ⁵

    and Neckel's separate fits for 300–372.98 nm and 385–422.57 nm (a_1 from Σ a_k = 1). Outside
    the fitted ranges: the 385–422.57 nm fit is extrapolated across the 372.98–385 nm gap
    (Balmer-line region; the disk mean jumps 5 % at 372.98 nm), the coefficients at 300 nm are
    held constant below 300 nm (extrapolating the fit would make the limb negative below
    ≈ 250 nm), and the 422.57–1100 nm fit is extrapolated beyond 1100 nm (monotonic, a0 -> 0.75
    as λ -> ∞). These are fits for the Sun; `Star` also applies them to other stars as a generic
    limb darkening.

    Parameters
    ----------
    cos_limb : array_like, shape S
        μ = cos of the angle between the line of sight and the stellar surface normal; 1 at disk
        centre, 0 at the limb; 0 <= μ <= 1. [-]
    wavelengths_nm : array_like, shape W
        Wavelengths, > 0; usually a grid (n_wl,). [nm]

    Returns
    -------
    ndarray, shape S + W
        I(μ)/I(1); 1 at μ = 1, about 0.27 at the limb at 550 nm. [-]
    """
    wl = checked_wavelengths(wavelengths_nm)
    mu = _checked_cos_limb(cos_limb)
    a = _neckel_coefficients(wl)  # W + (6,)
    mu = mu.reshape(mu.shape + (1,) * wl.ndim)
    result = a[..., 5]
    for k in range(4, -1, -1):  # Horner
        result = result * mu + a[..., k]
    return result


def limb_darkening_disk_mean(wavelengths_nm: ArrayLike) -> np.ndarray:
    """Flux-weighted disk mean of the limb-darkening law, ∫_0^1 (I(μ)/I(1)) 2μ dμ.

        ∫_0^1 Σ_k a_k μ^k 2μ dμ = Σ_k 2 a_k / (k + 2)

    Exact for the polynomial of `limb_darkening_neckel_labs_1994` (same sources). For a sphere of
    angular radius α the irradiance it gives is E = π sin²α I(1) × this mean (see
    `Star.disk_radiance`).

    Parameters
    ----------
    wavelengths_nm : array_like, shape W
        Wavelengths, > 0. [nm]

    Returns
    -------
    ndarray, shape W
        Disk mean relative to disk centre; about 0.80 at 550 nm. [-]
    """
    a = _neckel_coefficients(checked_wavelengths(wavelengths_nm))
    return a @ (2.0 / (np.arange(6) + 2.0))


@dataclass(frozen=True)
class Star:
    """A spherical star seen from a planet: spectrum, size and distance.

    Attributes
    ----------
    name : str
        Label, e.g. "Sun".
    spectrum : str
        "astm-g173" (measured solar spectrum, ASTM G173-03 ETR, scaled to `distance_m`) or
        "blackbody" (Planck at `temperature_k`).
    temperature_k : float
        Effective temperature; used for "blackbody"; the Sun's is 5772 K (IAU 2015 B3). [K]
    radius_m : float
        Stellar radius; the Sun's is 6.957e8 m (IAU 2015 B3). [m]
    distance_m : float
        Distance from the star's centre to the planet, > radius_m. [m]
    limb_darkening : bool
        Limb-darkened disk (Neckel & Labs 1994 law, for any star) if True, uniform if False.
    """

    name: str
    spectrum: str
    temperature_k: float
    radius_m: float
    distance_m: float
    limb_darkening: bool = True

    def __post_init__(self) -> None:
        if self.spectrum not in STAR_SPECTRA:
            raise InputError(
                f"star {self.name!r}: unknown spectrum {self.spectrum!r}; allowed: "
                f"{', '.join(STAR_SPECTRA)}", key="spectrum", value=self.spectrum,
                allowed=", ".join(STAR_SPECTRA))
        for key, unit in (("temperature_k", "K"), ("radius_m", "m"), ("distance_m", "m")):
            value = _positive_number(getattr(self, key), key, unit, f"star {self.name!r}: ")
            object.__setattr__(self, key, value)  # frozen: store the checked float
        object.__setattr__(self, "limb_darkening", bool(self.limb_darkening))
        if self.distance_m <= self.radius_m:
            raise InputError(
                f"star {self.name!r}: distance_m = {self.distance_m!r} must exceed radius_m = "
                f"{self.radius_m!r} (the observer is outside the star)", key="distance_m",
                value=self.distance_m, allowed=f"> {self.radius_m!r} m")

    @classmethod
    def sun(cls, distance_au: float = 1.0) -> Star:
        """The Sun at `distance_au` [AU]: measured ASTM G173-03 spectrum, 5772 K, R = 6.957e8 m
        (IAU 2015 B3 nominal values), limb-darkened. Mars' mean distance is 1.524 AU."""
        distance = _positive_number(distance_au, "distance_au", "AU")
        return cls("Sun", "astm-g173", SOLAR_EFFECTIVE_TEMPERATURE_K, SOLAR_RADIUS_M,
                   distance * AU_M)

    @classmethod
    def blackbody(cls, name: str, temperature_k: float, radius_m: float,
                  distance_m: float) -> Star:
        """A black-body star of `temperature_k` [K], `radius_m` [m] at `distance_m` [m]."""
        return cls(name, "blackbody", temperature_k, radius_m, distance_m)

    @property
    def angular_radius_rad(self) -> float:
        """Angular radius of the disk, α = asin(R/d) (exact for a sphere). [rad]"""
        return math.asin(self.radius_m / self.distance_m)

    @property
    def solid_angle_sr(self) -> float:
        """Solid angle of the disk, Ω = 2π (1 - cos α). [sr]"""
        return 2.0 * math.pi * (1.0 - math.cos(self.angular_radius_rad))

    def irradiance_scale_at(self, distance_m: float) -> float:
        """(d / distance_m)^2: how much more the star lights a planet `distance_m` [m] away (a
        date's, from the ephemeris) than one at its own distance d (inverse-square law)."""
        return (self.distance_m / distance_m) ** 2

    def irradiance_toa(self, wavelengths_nm: ArrayLike) -> np.ndarray:
        """Spectral irradiance from the whole disk, normal to the beam, at the planet (no air).

        - "astm-g173": E_j = E_G173,j (AU / d)², the cell average of the measured spectrum at
          1 AU (`solar.solar_irradiance_1au`) moved to distance d by the inverse-square law
          (exact for a sphere: E ∝ sin²α = (R/d)²).
        - "blackbody": E_j = cell average over [e_j, e_{j+1}] of π B_λ(T) sin²α, the irradiance
          of a uniform Lambertian sphere (Planck 1901; geometry: E = ∫ I cos θ dΩ over the disk),
          averaged like the solar spectrum (8-point Gauss–Legendre per cell), so
          Σ_j E_j (e_{j+1} - e_j) is the irradiance in the grid's range for any grid.

        Parameters
        ----------
        wavelengths_nm : array_like, shape (n_wl,)
            Wavelength grid, strictly ascending. [nm]

        Returns
        -------
        ndarray, shape (n_wl,)
            Spectral irradiance. [W m⁻² nm⁻¹]
        """
        wl = checked_grid(wavelengths_nm)
        if self.spectrum == "astm-g173":
            return solar_irradiance_1au(wl) * (AU_M / self.distance_m) ** 2
        edges = cell_edges(wl)
        nodes, weights = np.polynomial.legendre.leggauss(_GAUSS_NODES)
        half = 0.5 * np.diff(edges)
        samples = (0.5 * (edges[1:] + edges[:-1]))[:, None] + half[:, None] * nodes
        mean_b = planck_spectral_radiance(samples, self.temperature_k) @ weights * 0.5
        sin_alpha = self.radius_m / self.distance_m
        return math.pi * sin_alpha**2 * mean_b

    def disk_radiance(self, wavelengths_nm: ArrayLike, cos_limb: ArrayLike) -> np.ndarray:
        r"""Spectral radiance of a point of the stellar disk, as seen from the planet.

            I(μ, λ) = E(λ) / (π sin²α) × D(μ, λ) / ∫_0^1 D(μ', λ) 2μ' dμ'

        E = `irradiance_toa`, D = `limb_darkening_neckel_labs_1994` (or 1 if `limb_darkening`
        is False). Normalisation: a point at angular distance θ from the disk centre sees the
        surface at μ with sin θ = sin α √(1 - μ²) (exact for a sphere), so
        ∫_disk I cos θ dΩ = 2π ∫_0^α I sin θ cos θ dθ = π sin²α ∫_0^1 I(μ) 2μ dμ = E: the disk
        integrates to `irradiance_toa` exactly. For a uniform black body I = cell-mean B_λ(T).

        Parameters
        ----------
        wavelengths_nm : array_like, shape (n_wl,)
            Wavelength grid, strictly ascending. [nm]
        cos_limb : array_like, shape S
            μ at the point of the disk, 0 (limb) <= μ <= 1 (centre). [-]

        Returns
        -------
        ndarray, shape S + (n_wl,)
            Spectral radiance. [W m⁻² sr⁻¹ nm⁻¹]
        """
        wl = checked_grid(wavelengths_nm)
        mu = _checked_cos_limb(cos_limb)
        sin_alpha = self.radius_m / self.distance_m
        uniform = self.irradiance_toa(wl) / (math.pi * sin_alpha**2)
        if not self.limb_darkening:
            return np.broadcast_to(uniform, mu.shape + wl.shape).copy()
        return limb_darkening_neckel_labs_1994(mu, wl) * (uniform / limb_darkening_disk_mean(wl))


def _positive_number(value: object, key: str, unit: str, prefix: str = "") -> float:
    """`value` as a float, or InputError unless it is a real, finite number > 0."""
    if isinstance(value, numbers.Real) and not isinstance(value, bool):
        number = float(value)
        if math.isfinite(number) and number > 0.0:
            return number
    raise InputError(f"{prefix}{key} = {value!r} must be a finite number > 0 [{unit}]",
                     key=key, value=value, allowed=f"> 0 [{unit}]")


def _checked_cos_limb(cos_limb: ArrayLike) -> np.ndarray:
    try:
        mu = np.asarray(cos_limb, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise InputError(f"cos_limb must be numbers in [0, 1]; got {cos_limb!r}", key="cos_limb",
                         value=cos_limb, allowed="0 <= cos_limb <= 1") from exc
    bad = ~((mu >= 0.0) & (mu <= 1.0))
    if np.any(bad):
        first = float(mu[tuple(np.argwhere(bad)[0])])
        raise InputError(
            f"cos_limb must lie in [0, 1] (0 = limb, 1 = disk centre); got {first!r}",
            key="cos_limb", value=first, allowed="0 <= cos_limb <= 1")
    return mu
