"""Stars in an image: point sources splatted flux-exactly, scintillation, and the faint-star glow.

- `add_stars`: each star's transmitted irradiance E T [W m⁻² nm⁻¹] is shared among the four
  pixel centres around its image point with bilinear (tent) weights w_p, Σ w_p = 1, and
  deposited as radiance L_p += w_p E T / Ω_p, Ω_p = `camera.pixel_solid_angles()`. Then

      Σ_p L_p Ω_p = E T                                                             (1)

  exactly, at any resolution and for any projection: the image carries each star's flux, and a
  star moving across pixels does not flicker. Weights of neighbours outside the image or the
  lens are given to the others (renormalised); a star whose own pixel is outside is skipped.
- `scintillation_factors`: log-normal intensity factors of mean 1 and relative standard
  deviation from Young (1967), AJ 72, 747, doi:10.1086/110303:

      σ_I = 0.09 D^(-2/3) X^1.75 exp(-h / 8000 m) (2 t)^(-1/2)                        (2)

  D aperture [cm], X airmass, h altitude [m], t exposure [s] (Young's eq. 7 as restated by
  Dravins et al. 1998, PASP 110, 610, eq. 10, doi:10.1086/316161). Eq. (2) holds for
  apertures larger than the Fresnel zone (~5 cm) and weak scintillation; for the eye's 7 mm
  pupil it is an extrapolation, so σ_I is capped at 1 (saturated scintillation: the
  scintillation index of small apertures levels off near unity, Dravins et al. 1997, PASP 109,
  173, doi:10.1086/133872).
- `airmass_kasten_young_1989`: relative optical air mass,

      X = 1 / (cos z + 0.50572 (96.07995° - z)^-1.6364),   z in degrees              (3)

  Kasten & Young (1989), Appl. Opt. 28, 4735, doi:10.1364/AO.28.004735; 1.000 at the zenith,
  37.92 at the horizon.
- `ICRS_TO_GALACTIC`, `integrated_starlight_radiance`: a smooth all-sky map of the light of the
  stars fainter than a rendered limit (the diffuse Milky Way); see that function.
  `add_star_background` adds it to an image, times the view transmittance.

Public names: `add_stars`, `add_star_background`, `scintillation_factors`,
`airmass_kasten_young_1989`, `ICRS_TO_GALACTIC`, `S10_RADIANCE_V`, `integrated_starlight_radiance`,
`INTEGRATED_STARLIGHT_POLE_S10`, `INTEGRATED_STARLIGHT_PLANE_S10`.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable

import numpy as np
from numpy.typing import ArrayLike

from skyscatter.astro.star_catalogue import load_star_catalogue
from skyscatter.errors import InputError
from skyscatter.render.camera import Camera, EquirectangularCamera
from skyscatter.render.scene import cached_pixel_solid_angles
from skyscatter.spectrum.magnitudes import (
    V_ZERO_POINT_FLUX,
    colour_temperature_from_b_minus_v,
    stellar_irradiance,
)

__all__ = [
    "ICRS_TO_GALACTIC",
    "INTEGRATED_STARLIGHT_PLANE_S10",
    "INTEGRATED_STARLIGHT_POLE_S10",
    "S10_RADIANCE_V",
    "add_star_background",
    "add_stars",
    "airmass_kasten_young_1989",
    "integrated_starlight_radiance",
    "scintillation_factors",
]

SCINTILLATION_SIGMA_CAP = 1.0  # relative σ_I; saturated scintillation (Dravins et al. 1997)
_SCALE_HEIGHT_M = 8000.0  # m, Young (1967)

# Rows: the galactic x (to the centre), y (l = 90°) and z (north galactic pole) axes in ICRS.
# ESA (1997), The Hipparcos and Tycho Catalogues, Vol. 1, §1.5.3, eq. 1.5.11 (matrix A_G,
# transposed here so that r_gal = ICRS_TO_GALACTIC @ r_icrs).
ICRS_TO_GALACTIC = np.array([
    [-0.0548755604, -0.8734370902, -0.4838350155],
    [+0.4941094279, -0.4448296300, +0.7469822445],
    [-0.8676661490, -0.1980763734, +0.4559837762],
])
ICRS_TO_GALACTIC.flags.writeable = False

_SQUARE_DEGREE_SR = (math.pi / 180.0) ** 2  # sr
# 1 S10 = the flux of one V = 10 star per square degree; its V-band mean radiance:
S10_RADIANCE_V = V_ZERO_POINT_FLUX * 1e-4 / _SQUARE_DEGREE_SR  # W m⁻² sr⁻¹ nm⁻¹

# Integrated light of the stars fainter than V = 6, in S10(V): about 25 at the galactic poles
# and 250 averaged over |b| < 5° (Leinert et al. 1998, A&AS 127, 1, §10 and Fig. 36, after
# Roach & Megill 1961, ApJ 133, 228; Roach & Gordon 1973, "The Light of the Night Sky").
INTEGRATED_STARLIGHT_POLE_S10 = 25.0
INTEGRATED_STARLIGHT_PLANE_S10 = 250.0
_ANCHOR_LIMIT_V = 6.0  # the anchors count stars fainter than this
_INTEGRATED_STARLIGHT_B_MINUS_V = 0.8  # mag; colour given to the glow (G8-K0-like, ~5000 K)
_MAP_BANDS, _MAP_COLUMNS = 90, 180  # equal-area map: bands in sin b, columns in l
_DENSITY_MAGNITUDES = (7.0, 9.0)  # V range whose star density shapes the map


def airmass_kasten_young_1989(zenith_deg: ArrayLike) -> np.ndarray:
    """Relative optical air mass X(z), eq. (3) of the module docstring.

    Kasten & Young (1989), Appl. Opt. 28, 4735, doi:10.1364/AO.28.004735, fitted to ISO 1972
    standard-atmosphere air masses with a maximum error of 0.5 % up to z = 90°. The formula
    is for the apparent (refracted) zenith angle.

    Parameters
    ----------
    zenith_deg : array_like, shape S
        Zenith angle, 0 <= z <= 90. [deg]

    Returns
    -------
    ndarray, shape S
        Air mass relative to the zenith. [-]
    """
    z = np.asarray(zenith_deg, dtype=np.float64)
    if not np.all((z >= 0.0) & (z <= 90.0)):
        bad = float(z[~((z >= 0.0) & (z <= 90.0))].flat[0])
        raise InputError(f"zenith_deg = {bad!r} must lie in [0, 90] degrees", key="zenith_deg",
                         value=bad, allowed="0 <= zenith_deg <= 90")
    return 1.0 / (np.cos(np.radians(z)) + 0.50572 * (96.07995 - z) ** -1.6364)


def scintillation_factors(airmass: ArrayLike, rng: np.random.Generator,
                          aperture_m: float = 0.007, exposure_s: float = 0.1,
                          altitude_m: float = 0.0) -> np.ndarray:
    """Random multiplicative intensity factors for twinkling stars, mean 1.

        σ_I = min(0.09 D^(-2/3) X^1.75 exp(-h / 8000 m) (2 t)^(-1/2), 1),   D in cm
        factor = exp(s N(0, 1) - s²/2),   s² = ln(1 + σ_I²)

    Eq. (2) of the module docstring (Young 1967) for the relative standard deviation σ_I of the
    intensity; the log-normal distribution of weak scintillation (Dravins et al. 1997) with
    mean exactly 1 and standard deviation σ_I. The defaults are a dark-adapted eye: 7 mm pupil
    and ~0.1 s integration; at the zenith at sea level σ_I = 0.26.

    Parameters
    ----------
    airmass : array_like, shape S
        Air mass along each star's line of sight, >= 1 (e.g. `airmass_kasten_young_1989`). [-]
    rng : numpy.random.Generator
        Source of randomness (pass a seeded one for reproducible images).
    aperture_m : float
        Entrance pupil diameter, > 0. [m]
    exposure_s : float
        Integration time, > 0. [s]
    altitude_m : float
        Observer altitude above sea level. [m]

    Returns
    -------
    ndarray, shape S
        Intensity factors, > 0, mean 1. [-]
    """
    x = np.asarray(airmass, dtype=np.float64)
    # Kasten & Young's fit gives 0.99988 at the zenith: values just below 1 count as 1
    if not np.all(np.isfinite(x) & (x >= 0.999)):
        bad = float(x[~(np.isfinite(x) & (x >= 0.999))].flat[0])
        raise InputError(f"airmass = {bad!r} must be finite and >= 1", key="airmass", value=bad,
                         allowed=">= 1")
    for name, value in (("aperture_m", aperture_m), ("exposure_s", exposure_s)):
        if not (math.isfinite(value) and value > 0.0):
            raise InputError(f"{name} = {value!r} must be > 0", key=name, value=value,
                             allowed="> 0")
    sigma = (0.09 * (100.0 * aperture_m) ** (-2.0 / 3.0) * x**1.75
             * math.exp(-altitude_m / _SCALE_HEIGHT_M) / math.sqrt(2.0 * exposure_s))
    sigma = np.minimum(sigma, SCINTILLATION_SIGMA_CAP)
    s2 = np.log1p(sigma * sigma)
    return np.exp(np.sqrt(s2) * rng.standard_normal(x.shape) - 0.5 * s2)


def _splat_weights(camera: Camera, valid: np.ndarray, directions: np.ndarray
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Flat pixel indices (m, 4), weights (m, 4) summing to 1 per star, and the star rows (m,)."""
    height, width = valid.shape
    up = directions[:, 2] > 0.0
    rows_in = np.flatnonzero(up)
    row, col = camera.direction_to_pixel(directions[rows_in])
    row, col = np.asarray(row, dtype=np.float64), np.asarray(col, dtype=np.float64)
    wraps = isinstance(camera, EquirectangularCamera)  # columns wrap around in azimuth
    finite = np.isfinite(row) & np.isfinite(col)
    i, j = np.floor(row[finite]).astype(np.int64), np.floor(col[finite]).astype(np.int64)
    if wraps:
        j = np.mod(j, width)
    own = (i >= 0) & (i < height) & (j >= 0) & (j < width)
    own[own] = valid[i[own], j[own]]
    keep = np.flatnonzero(finite)[own]
    r, c = row[keep] - 0.5, col[keep] - 0.5  # coordinates relative to pixel centres
    i0, j0 = np.floor(r).astype(np.int64), np.floor(c).astype(np.int64)
    fr, fc = r - i0, c - j0
    ii = np.stack([i0, i0, i0 + 1, i0 + 1], axis=1)
    jj = np.stack([j0, j0 + 1, j0, j0 + 1], axis=1)
    weights = np.stack([(1 - fr) * (1 - fc), (1 - fr) * fc, fr * (1 - fc), fr * fc], axis=1)
    if wraps:
        jj = np.mod(jj, width)
    inside = (ii >= 0) & (ii < height) & (jj >= 0) & (jj < width)
    inside[inside] = valid[ii[inside], jj[inside]]
    weights = np.where(inside, weights, 0.0)
    # The star's own pixel is one of the four, valid, with weight >= 1/4: total >= 1/4.
    total = weights.sum(axis=1, keepdims=True)
    weights /= total
    flat = np.where(inside, ii * width + jj, 0)
    return flat, weights, rows_in[keep]


def add_stars(spectral: np.ndarray, camera: Camera, valid: np.ndarray,
              star_directions_enu: ArrayLike, star_irradiance: ArrayLike, *,
              transmittance: ArrayLike, scintillation: ArrayLike | None = None) -> int:
    """Deposit point-like stars into a spectral image, in place, conserving each star's flux.

        L_p += w_p E T f / Ω_p,   Σ_p w_p = 1   =>   Σ_p L_p Ω_p = E T f   (eq. 1)

    w_p: bilinear weights of the four pixel centres around the star's continuous image
    position (`camera.direction_to_pixel`); Ω_p: `camera.pixel_solid_angles()`; E: irradiance
    above the air; T: transmittance along the star's line of sight; f: scintillation factor.
    Stars at or below the horizon (z <= 0), behind a perspective camera, or whose own pixel
    is outside the image or lens are skipped. Vectorised (contributions sorted by pixel and
    summed with np.add.reduceat): no loop over stars.

    Parameters
    ----------
    spectral : ndarray, shape (h, w, n_wl)
        Spectral radiance image, modified in place. [W m⁻² sr⁻¹ nm⁻¹]
    camera : Camera
        The camera that made the image (needs `direction_to_pixel`, `pixel_solid_angles`).
    valid : ndarray, shape (h, w) bool
        Pixels inside the lens.
    star_directions_enu : array_like, shape (n, 3)
        Unit vectors to the stars in the observer's east-north-up frame, already refracted.
    star_irradiance : array_like, shape (n, n_wl)
        Spectral irradiance normal to the beam at the top of the atmosphere. [W m⁻² nm⁻¹]
    transmittance : array_like, shape (n, n_wl) or broadcastable
        Direct transmittance from the top of the atmosphere to the observer. [-]
    scintillation : array_like, shape (n,), optional
        Intensity factors (`scintillation_factors`); None = no twinkling. [-]

    Returns
    -------
    int
        Number of stars deposited.
    """
    directions = np.asarray(star_directions_enu, dtype=np.float64)
    if directions.ndim != 2 or directions.shape[1] != 3:
        raise InputError(f"star_directions_enu must have shape (n, 3); got {directions.shape}",
                         key="star_directions_enu", value=directions.shape,
                         allowed="(n, 3)")
    n, n_wl = directions.shape[0], spectral.shape[-1]
    flux = np.asarray(star_irradiance, dtype=np.float64)
    if flux.shape != (n, n_wl):
        raise InputError(f"star_irradiance must have shape ({n}, {n_wl}); got {flux.shape}",
                         key="star_irradiance", value=flux.shape, allowed=f"({n}, {n_wl})")
    if not spectral.flags.c_contiguous:
        raise InputError("spectral must be a C-contiguous (h, w, n_wl) array (it is filled in "
                         "place)", key="spectral", value=spectral.shape)
    flat, weights, stars = _splat_weights(camera, np.asarray(valid, dtype=bool), directions)
    if stars.size == 0:
        return 0
    # Only the deposited stars: E T f, (m, n_wl).
    flux = flux[stars] * np.broadcast_to(np.asarray(transmittance, dtype=np.float64),
                                         (n, n_wl))[stars]
    if scintillation is not None:
        flux *= np.broadcast_to(np.asarray(scintillation, dtype=np.float64), (n,))[stars, None]
    omega = cached_pixel_solid_angles(camera).ravel()
    flat = flat.ravel()
    share = weights.ravel() / np.where(weights.ravel() > 0.0, omega[flat], 1.0)
    # Sum the (4m, n_wl) contributions per pixel: sort by pixel, add runs, scatter once.
    order = np.argsort(flat, kind="stable")
    flat = flat[order]
    contributions = flux[order // 4] * share[order, None]
    starts = np.flatnonzero(np.r_[True, flat[1:] != flat[:-1]])
    image = spectral.reshape(-1, n_wl)  # a view: spectral is C-contiguous
    image[flat[starts]] += np.add.reduceat(contributions, starts, axis=0)
    return int(stars.size)


@functools.cache
def _starlight_map(rendered_limit_v: float) -> np.ndarray:
    """Equal-area (sin b, l) map of the integrated light of stars fainter than the limit [S10]."""
    catalogue = load_star_catalogue()
    galactic = catalogue.unit_vectors @ ICRS_TO_GALACTIC.T
    band = np.clip(((galactic[:, 2] + 1.0) * 0.5 * _MAP_BANDS).astype(np.int64), 0,
                   _MAP_BANDS - 1)
    longitude = np.mod(np.arctan2(galactic[:, 1], galactic[:, 0]), 2.0 * np.pi)
    column = np.minimum((longitude / (2.0 * np.pi) * _MAP_COLUMNS).astype(np.int64),
                        _MAP_COLUMNS - 1)
    cell = band * _MAP_COLUMNS + column
    cell_sr = 4.0 * np.pi / (_MAP_BANDS * _MAP_COLUMNS)
    v = catalogue.v_magnitude
    low, high = _DENSITY_MAGNITUDES
    density = _smooth(np.bincount(cell[(v >= low) & (v < high)], minlength=cell.max() + 1)
                      .astype(np.float64).reshape(_MAP_BANDS, _MAP_COLUMNS) + 0.5)
    # Shape from the density, contrast from the anchors: I = k ρ^γ, with k and γ such that the
    # area means over |b| > 80° and |b| < 5° are the anchors (γ by bisection: the plane/pole
    # ratio of the means grows with γ).
    edges = np.linspace(-1.0, 1.0, _MAP_BANDS + 1)  # sin b of the band edges
    pole = _band_overlap(edges, math.sin(math.radians(80.0)), 1.0)
    pole += _band_overlap(edges, -1.0, -math.sin(math.radians(80.0)))
    plane = _band_overlap(edges, -math.sin(math.radians(5.0)), math.sin(math.radians(5.0)))
    relative = density / density.mean()

    def band_mean(values: np.ndarray, bands: np.ndarray) -> float:
        return float(bands @ values.mean(axis=1) / bands.sum())

    wanted = INTEGRATED_STARLIGHT_PLANE_S10 / INTEGRATED_STARLIGHT_POLE_S10
    low_gamma, high_gamma = 0.0, 20.0
    for _ in range(60):
        gamma = 0.5 * (low_gamma + high_gamma)
        shaped = relative**gamma
        if band_mean(shaped, plane) / band_mean(shaped, pole) < wanted:
            low_gamma = gamma
        else:
            high_gamma = gamma
    shaped = relative**gamma
    total = shaped * (INTEGRATED_STARLIGHT_POLE_S10 / band_mean(shaped, pole))
    # Stars between V = 6 and the rendered limit are drawn as points: take their light out.
    if rendered_limit_v > _ANCHOR_LIMIT_V:
        drawn = (v > _ANCHOR_LIMIT_V) & (v <= rendered_limit_v)
        flux_s10 = 10.0 ** (-0.4 * (v[drawn] - 10.0))  # in V = 10 stars
        per_cell = np.bincount(cell[drawn], weights=flux_s10, minlength=_MAP_BANDS * _MAP_COLUMNS)
        per_deg2 = _smooth(per_cell.reshape(_MAP_BANDS, _MAP_COLUMNS)) / (cell_sr
                                                                          / _SQUARE_DEGREE_SR)
        total = np.maximum(total - per_deg2, 0.0)
    return total


def _band_overlap(edges: np.ndarray, low: float, high: float) -> np.ndarray:
    """Fraction of each band [edges[k], edges[k+1]] that lies inside [low, high]."""
    inside = np.clip(np.minimum(edges[1:], high) - np.maximum(edges[:-1], low), 0.0, None)
    return inside / np.diff(edges)


def _smooth(grid: np.ndarray, passes: int = 6) -> np.ndarray:
    """Repeated 1-2-1 filter (≈ Gaussian of σ ≈ 1.7 cells ≈ 3.5°), wrapping in longitude."""
    out = grid.astype(np.float64)
    for _ in range(passes):
        out = 0.25 * (np.roll(out, 1, axis=1) + 2.0 * out + np.roll(out, -1, axis=1))
        padded = np.concatenate([out[:1], out, out[-1:]], axis=0)
        out = 0.25 * (padded[:-2] + 2.0 * padded[1:-1] + padded[2:])
    return out


def integrated_starlight_radiance(directions_icrs: ArrayLike, wavelengths_nm: ArrayLike,
                                  rendered_limit_v: float = 6.0) -> np.ndarray:
    """Spectral radiance of the unresolved stars (the diffuse Milky Way) above the atmosphere.

        I(l, b) = I_pole (ρ(l, b) / ρ_pole)^γ - I_drawn(l, b)   [S10]
        L_λ = I × S10_RADIANCE_V × spectrum normalised to V-band mean 1

    ρ: smoothed (≈ 3.5°) density of Hipparcos stars of 7 <= V < 9 on an equal-area galactic
    map (the angular structure: plane, Gould belt, Orion/Cygnus/Carina clouds); k and γ are
    set so that the mean over |b| > 80° is `INTEGRATED_STARLIGHT_POLE_S10` = 25 S10 and the
    mean over |b| < 5° is `INTEGRATED_STARLIGHT_PLANE_S10` = 250 S10 (Leinert et al. 1998,
    A&AS 127, 1, §10; stars fainter than V = 6). I_drawn: the smoothed light of catalogue
    stars with 6 < V <= `rendered_limit_v`, which the caller draws as points, so nothing is
    counted twice. 1 S10 = one V = 10 star per square degree =
    3.631e-15 / 3.0462e-4 = 1.192e-11 W m⁻² sr⁻¹ nm⁻¹ (V-band mean; F_0 of Bessell, Castelli
    & Plez 1998). Spectrum: a black body of B-V = 0.8 (5200 K, Ballesteros 2012), the colour
    of integrated starlight being close to solar (Leinert et al. 1998 §10). Galactic
    coordinates: `ICRS_TO_GALACTIC` (ESA 1997 Vol. 1 §1.5.3). No dark lanes beyond what the
    star counts show, no diffuse galactic light (scattered starlight, ~20-30 % more).

    Parameters
    ----------
    directions_icrs : array_like, shape (..., 3)
        Unit view directions in the ICRS / J2000 equatorial frame. [-]
    wavelengths_nm : array_like, shape (n_wl,)
        Wavelength grid. [nm]
    rendered_limit_v : float
        Faintest V magnitude the caller draws as point stars; values below 6 act as 6, inf
        means the whole catalogue (to V ≈ 12.5). [mag]

    Returns
    -------
    ndarray, shape (..., n_wl)
        Spectral radiance above the atmosphere; multiply by the view transmittance. [W m⁻²
        sr⁻¹ nm⁻¹]
    """
    d = np.asarray(directions_icrs, dtype=np.float64)
    if d.shape[-1:] != (3,):
        raise InputError(f"directions_icrs must have shape (..., 3); got {d.shape}",
                         key="directions_icrs", value=d.shape, allowed="(..., 3)")
    limit = min(float(rendered_limit_v), 99.0)  # inf: every catalogue star is drawn
    starlight = _starlight_map(max(limit, _ANCHOR_LIMIT_V)).ravel()
    x_icrs, y_icrs, z_icrs = d[..., 0], d[..., 1], d[..., 2]
    m = ICRS_TO_GALACTIC  # r_gal = m @ r_icrs, written out (faster than matmul for (n, 3))
    gx = m[0, 0] * x_icrs + m[0, 1] * y_icrs + m[0, 2] * z_icrs
    gy = m[1, 0] * x_icrs + m[1, 1] * y_icrs + m[1, 2] * z_icrs
    gz = m[2, 0] * x_icrs + m[2, 1] * y_icrs + m[2, 2] * z_icrs
    norm = np.sqrt(x_icrs * x_icrs + y_icrs * y_icrs + z_icrs * z_icrs)
    sin_b = np.clip(gz / np.where(norm > 0.0, norm, 1.0), -1.0, 1.0)
    turns = np.arctan2(gy, gx) * (0.5 / np.pi)
    # Bilinear interpolation between cell centres; clamp in b, wrap in l.
    y = np.clip((sin_b + 1.0) * 0.5 * _MAP_BANDS - 0.5, 0.0, _MAP_BANDS - 1.0)
    x = np.mod(turns, 1.0) * _MAP_COLUMNS - 0.5
    y0 = np.minimum(y.astype(np.int64), _MAP_BANDS - 2)
    x0 = np.floor(x).astype(np.int64)
    fy, fx = y - y0, x - x0
    x0 %= _MAP_COLUMNS
    x1 = (x0 + 1) % _MAP_COLUMNS
    row0, row1 = y0 * _MAP_COLUMNS, (y0 + 1) * _MAP_COLUMNS
    s10 = ((1 - fy) * ((1 - fx) * starlight[row0 + x0] + fx * starlight[row0 + x1])
           + fy * ((1 - fx) * starlight[row1 + x0] + fx * starlight[row1 + x1]))
    spectrum = _s10_spectrum(tuple(np.asarray(wavelengths_nm, dtype=np.float64).ravel()))
    return s10[..., None] * spectrum


def add_star_background(spectral: np.ndarray, valid: np.ndarray, directions_enu: ArrayLike,
                        to_horizon: ArrayLike, wavelengths_nm: ArrayLike, *,
                        transmittance_of: Callable[[np.ndarray], np.ndarray],
                        magnitude_limit: float | None = None) -> None:
    """Add the unresolved-star glow, seen through the air, to a spectral image in place.

        L_p += T(d_p) L_glow(R^T d_p)

    R = `to_horizon` (ICRS -> east-north-up, so ICRS = R^T ENU for a rotation), L_glow =
    `integrated_starlight_radiance` with the catalogue's stars down to `magnitude_limit` taken
    out (they are drawn as points by `add_stars`), T = `transmittance_of(directions)`.

    Parameters
    ----------
    spectral : ndarray, shape (h, w, n_wl)
        Spectral radiance image, modified in place. [W m⁻² sr⁻¹ nm⁻¹]
    valid : ndarray, shape (h, w) bool
        Pixels inside the lens.
    directions_enu : array_like, shape (h, w, 3)
        Unit view directions of the pixels, east-north-up. [-]
    to_horizon : array_like, shape (3, 3)
        Rotation from ICRS/J2000 to the observer's east-north-up frame. [-]
    wavelengths_nm : array_like, shape (n_wl,)
        Wavelength grid. [nm]
    transmittance_of : callable
        (m, 3) ENU directions -> (m, n_wl) transmittance to the top of the atmosphere, 0 where
        the ground is in the way. [-]
    magnitude_limit : float or None
        The limit the caller's point stars were loaded with (`load_star_catalogue`); None =
        all catalogue stars are drawn. [mag]
    """
    valid = np.asarray(valid, dtype=bool)
    if not np.any(valid):
        return
    rays = np.asarray(directions_enu, dtype=np.float64)[valid]
    icrs = rays @ np.asarray(to_horizon, dtype=np.float64)  # R^T d, row vectors
    limit = np.inf if magnitude_limit is None else float(magnitude_limit)
    glow = integrated_starlight_radiance(icrs, wavelengths_nm, rendered_limit_v=limit)
    spectral[valid] += glow * transmittance_of(rays)


@functools.cache
def _s10_spectrum(wavelengths: tuple[float, ...]) -> np.ndarray:
    """Radiance of 1 S10 on the grid [W m⁻² sr⁻¹ nm⁻¹]: V = 10 black body per square degree."""
    temperature = colour_temperature_from_b_minus_v(_INTEGRATED_STARLIGHT_B_MINUS_V)
    return stellar_irradiance(10.0, temperature, np.array(wavelengths)) / _SQUARE_DEGREE_SR
